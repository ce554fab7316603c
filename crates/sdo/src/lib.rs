//! SDO server and client (CiA 301 §7.2.4): expedited, segmented and block
//! transfer with CRC, sans-IO.
//!
//! `server.rs` and `crc.rs` hold the server side; `client.rs` the client
//! side; `wire.rs` the command byte both read and write.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

pub mod client;
pub mod crc;
pub mod server;
pub mod wire;
