//! NMT slave, heartbeat producer/consumer, node and life guarding, error behaviour (CiA 301 7.2.8)
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;
