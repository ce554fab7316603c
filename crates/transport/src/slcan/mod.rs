//! slcan (Lawicel ASCII over a serial line): the host side
//! ([`open_serial`], [`connect_tcp`]) for real USB adapters (CANable,
//! USBtin, CANUSB), and an adapter emulator on a pseudo-terminal
//! ([`SlcanPty`], Unix) or over TCP ([`SlcanTcpServer`], pyserial
//! `socket://`) that python-can's `slcan` interface can open.

mod client;
pub mod codec;
pub mod device;
#[cfg(unix)]
mod pty;
mod server;

pub use client::{connect_tcp, open_serial};
pub use codec::bitrate_command;
#[cfg(unix)]
pub use pty::SlcanPty;
pub use server::SlcanTcpServer;
