//! A software EtherCAT slave controller (ESC): the hardware that lets
//! EtherCAT masters (ethercrab, SOEM, TwinCAT…) see drivebus slaves.
//!
//! * [`Esc`] is one slave controller: register space 0x0000–0x0FFF with
//!   the access rights and side effects of the Beckhoff ESC data sheet,
//!   process RAM from 0x1000, 16 [FMMUs](fmmu), 16 sync managers
//!   (mailbox and 3-buffer), the SII EEPROM interface, distributed clocks
//!   with a drifting local clock and SYNC0/SYNC1, and the process-data and
//!   PDI watchdogs. The master side processes frames in place
//!   ([`Esc::process_frame`]); the firmware side reads and writes through
//!   the PDI ([`Esc::pdi_read`], [`Esc::pdi_write`]) and takes
//!   [`EscEvent`]s.
//! * [`segment::Segment`] strings ESCs into a line with port forwarding,
//!   link state and propagation delays.
//! * [`slave`] is the firmware framework that sits on the PDI: the
//!   EtherCAT state machine, mailbox plumbing and process data, generic
//!   over a [`slave::SlaveApp`].
//! * [`sii`] encodes and parses SII EEPROM images; [`frame`] is the
//!   datagram codec.
//!
//! ```
//! use drivebus_base::Instant;
//! use drivebus_esc::frame::{DatagramCommand, FrameBuilder, datagrams, station_address};
//! use drivebus_esc::{Esc, EscConfig};
//!
//! let mut esc = Esc::new(EscConfig::default());
//! let mut buf = [0u8; 64];
//! let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
//! b.push(DatagramCommand::Brd, 1, station_address(0, 0x0000), &[0; 2]).unwrap(); // count slaves
//! let n = b.finish();
//! esc.process_frame(&mut buf[..n], Instant::from_micros(10));
//! let d = datagrams(&buf[14..n]).next().unwrap();
//! assert_eq!((d.data[0], d.wkc), (0x04, 1)); // ESC type, one slave
//! assert_eq!(buf[6], 0x12); // reply source MAC marked
//! ```
//!
//! Sans-IO like the rest of drivebus: no threads, sockets, clocks or
//! printing; the caller passes `now` and drives [`Esc::poll`] at the
//! deadlines it returns. Nothing on the frame path allocates or panics.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod access;
mod datagram;
pub mod dc;
mod eeprom;
mod esc;
mod events;
pub mod fmmu;
pub mod frame;
pub mod registers;
pub mod segment;
pub mod sii;
pub mod slave;
mod sm;

pub use datagram::FrameIndex;
pub use dc::ClockConfig;
pub use eeprom::SiiTiming;
pub use esc::{Esc, EscConfig, EscTraffic, FrameReport, FrameTiming, MAX_JITTER_NS, SmInfo};
pub use events::EscEvent;
pub use sm::{Side, SmMode};

#[cfg(test)]
mod tests;
