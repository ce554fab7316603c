//! pcapng capture of every frame in and out, for Wireshark: the shared
//! writer of `drivebus_can::pcap` with the Ethernet link type.

pub use drivebus_can::pcap::{Capture, Direction, LinkType};
