//! Deterministic virtual CAN bus on simulated time.
//!
//! Stations — [`Device`]s (the `drivebus_can` contract) and test probes —
//! share one bus.
//! [`Bus::step`] / [`Bus::run_until`] advance simulated time event by event:
//!
//! - each node is polled at the deadline it returned (and after each frame
//!   it receives);
//! - every station has a FIFO transmit queue of which only the head competes;
//!   when the bus is idle, the head with the lowest arbitration key (identifier,
//!   then IDE, then RTR, as bitwise arbitration resolves them) wins;
//! - the frame reaches every other active station at its end of frame;
//!   with [`BusConfig::bitrate`] set, that time comes from the exact stuffed
//!   bit length ([`timing::frame_bits`]) and the bus is busy for the
//!   intermission too; without it, frames take no time but still go one at a
//!   time in arbitration order;
//! - [`FaultRule`]s drop, corrupt, delay or duplicate transmissions or put
//!   their sender bus-off; stations can be disconnected;
//! - every delivered frame is logged, in candump format on request
//!   ([`candump`]), and counted in [`BusStats`].
//!
//! ```
//! use drivebus_bus::{Bus, BusConfig};
//! use drivebus_can::{Device, Frame, Instant, TxSink};
//!
//! /// Answers every SYNC with a TPDO.
//! struct Echo;
//! impl Device for Echo {
//!     fn start(&mut self, _now: Instant, _out: &mut dyn TxSink) {}
//!     fn handle_frame(&mut self, f: &Frame, _now: Instant, out: &mut dyn TxSink) {
//!         if f.std_id() == Some(0x080) {
//!             out.send(Frame::new(0x181, &[0x2A]));
//!         }
//!     }
//!     fn poll(&mut self, _now: Instant, _out: &mut dyn TxSink) -> Option<Instant> {
//!         None
//!     }
//!     fn as_any(&self) -> &dyn core::any::Any { self }
//!     fn as_any_mut(&mut self) -> &mut dyn core::any::Any { self }
//! }
//!
//! let mut bus = Bus::new(BusConfig { log_epoch_us: 1_700_000_000_000_000, ..BusConfig::with_bitrate(1_000_000) });
//! bus.attach(Echo);
//! let master = bus.attach_probe();
//! bus.send_from(master, Frame::new(0x080, &[]));
//! bus.run_until(Instant::from_millis(1));
//! assert_eq!(bus.take_received(master), [Frame::new(0x181, &[0x2A])]);
//! assert_eq!(
//!     bus.log_lines(),
//!     ["(1700000000.000048) can0 080#", "(1700000000.000105) can0 181#2A"]
//! );
//! ```
//!
//! Everything is deterministic: the same nodes, rules and seed give the same
//! log. The core is `no_std` + `alloc`; the `std` feature adds writing the
//! log to files.
//!
//! The bus holds `Box<dyn Device>` stations and is therefore not `Send`;
//! a driver on another thread should build the bus (and its nodes) there.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod bus;
pub mod candump;
mod node;
mod sim;
mod stats;
/// Bit timing of frames (`drivebus_can::timing`): the bus paces with it.
pub use drivebus_can::timing;

pub use bus::RuleId;
pub use bus::{Bus, BusConfig, LogSink};
pub use candump::{CandumpRecord, LogEntry, ParseError, ParseErrorKind};
pub use drivebus_can::fault::{FaultAction, FaultRule, XorShift64, corrupt_data};
pub use drivebus_can::{Device, LinkState};
pub use node::{NodeId, ProbeId};
pub use stats::BusStats;
