//! Async CANopen master for drivebus (tokio). (Devices are hosted in real
//! time by `drivebus_transport::host`.)
//!
//! A [`Master`] sits on one [`CanBus`](drivebus_transport::CanBus). One
//! receive task demultiplexes every frame: SDO responses go to the transfer
//! waiting for them, heartbeats/boot-ups update the node table and become
//! [`MasterEvent`]s, EMCYs are decoded with their texts, LSS answers go to
//! the LSS operation running, and PDOs to their subscribers. The protocol
//! work itself is done by the sans-IO machines of the core crates
//! (`drivebus_sdo::client`, `drivebus_lss::FastScan`), driven in the
//! caller's future with a monotonic clock derived from `tokio::time`.
//!
//! ```no_run
//! # async fn demo() -> Result<(), Box<dyn std::error::Error>> {
//! let bus = drivebus_transport::open("socketcand://localhost:29536/vcan0").await?;
//! let master = drivebus_master::Master::new(bus);
//! let device_type: u32 = master.sdo(5).read(0x1000, 0).await?;
//! # let _ = device_type; Ok(()) }
//! ```
//!
//! Modules: `master` (the core,
//! events, NMT, heartbeat/guarding, EMCY, SYNC/TIME); [`sdo`]; [`scan`];
//! [`lss`]; [`pdo`]; [`drive`] (CiA 402).

mod clock;
pub mod drive;
pub mod lss;
mod master;
pub mod pdo;
pub mod scan;
pub mod sdo;

pub use drive::{Drive, DriveError, DriveState, Profile};
pub use lss::{LssError, LssMaster};
pub use master::{Master, MasterConfig, MasterEvent, NodeStatus, SyncTick, WaitError};
pub use pdo::{ConfigError, PdoDir, PdoMapEntry, PdoRecord};
pub use scan::{ScanOptions, ScannedNode};
pub use sdo::{SdoError, SdoHandle, SdoValue};

/// Re-exports so users need one dependency.
pub use drivebus_lss::codec::LssField;
pub use drivebus_lss::{FastScan, LssAddress, LssAddressRange, LssMode};
pub use drivebus_nmt::{NmtCommand, RemoteState};
pub use drivebus_od::{DataType, SdoAbort, Value};
pub use drivebus_sdo::client::Protocol;
