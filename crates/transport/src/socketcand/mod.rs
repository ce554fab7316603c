//! socketcand: a CAN bus over TCP in ASCII (`< … >` messages).
//!
//! [`SocketcandServer`] is a socketcand-compatible hub (python-can's
//! `socketcand` interface connects to it); [`connect`] is the client side
//! (`socketcand://HOST:PORT/CHANNEL`). Only raw mode is implemented, the
//! mode python-can uses. RTR frames cannot cross socketcand: the client
//! refuses to send them and the server does not forward them.

mod client;
pub mod proto;
mod server;

pub use client::{HANDSHAKE_TIMEOUT, connect};
pub use server::{SocketcandConfig, SocketcandServer};
