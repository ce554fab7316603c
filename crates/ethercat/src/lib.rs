//! Hosting drivebus EtherCAT slaves ([`drivebus_esc`]) for real masters.
//!
//! * [`Host`]: a [`Segment`](drivebus_esc::segment::Segment) of devices on
//!   a [`Clock`] (real or simulated), the single entry point for frames,
//!   with optional pcapng [`capture`].
//! * [`link`]: an in-process link for ethercrab 0.7.1 — its `PduTx`/`PduRx`
//!   served straight from a host, no root, no network (feature
//!   `ethercrab`, on by default).
//! * [`server`]: an AF_PACKET raw-socket server on a named interface
//!   (Linux, root), so masters on a wire or a veth pair see the segment.
//! * [`master`]: an ethercrab master for tools (scan, AL state, CoE,
//!   PDO mapping, a CiA 402 drive over process data), what `drivebus
//!   ethercat scan|sdo|state|pdo|drive` and `drivebus demo --ethercat` run.
//! * [`objects`]: a hosted slave's objects for a local tool (read, write,
//!   sampled per process-data cycle), through its CoE server's path.
//! * [`dio`]: a digital I/O test slave (no mailbox, SII-described PDOs).
//! * [`described`]: slaves made from a real device's SII EEPROM image or
//!   ESI file (`drivebus ethercat serve --device FILE`).
//!
//! * [`drive`]: the CiA 402 drive personalities (`ipos`, `generic`) as
//!   CoE slaves, and [`drive::DriveLine`], the builder of a line of them.

pub mod capture;
pub mod clock;
pub mod described;
pub mod dio;
pub mod drive;
#[cfg(feature = "ethercrab")]
pub mod drive_probe;
pub mod host;
#[cfg(feature = "ethercrab")]
pub mod link;
#[cfg(feature = "ethercrab")]
pub mod master;
pub mod objects;
#[cfg(feature = "ethercrab")]
pub mod probe;
#[cfg(target_os = "linux")]
pub mod server;

pub use clock::Clock;
pub use drivebus_esc::MAX_JITTER_NS;
pub use drivebus_esc::segment::LineFault;
pub use host::{BoxDevice, FrameObserver, Host, HostStats, ObserverId, SlaveState};
