//! CANopen master for drivebus: a sans-IO core with two drivers. (Devices
//! are hosted in real time by `drivebus_transport::host`.)
//!
//! The core (frames and `now` in, frames and the next deadline out) keeps
//! the node table, the heartbeat/guarding monitor, the EMCY consumer, the
//! SYNC producer, and runs SDO transfers (`drivebus_sdo::client`), LSS
//! exchanges and fastscan (`drivebus_lss::FastScan`). A [`Master`] is the
//! async API over it; every procedure (SDO, scan, LSS, PDO configuration,
//! the CiA 402 [`RemoteDrive`] sequences) is written once against it and runs
//! on either driver:
//!
//! - **tokio** ([`Master::new`]): one task on a
//!   [`CanBus`](drivebus_transport::CanBus) (socketcand, slcan, SocketCAN,
//!   in-process hub), on the tokio clock;
//! - **simulated time** ([`SimBus`]): the master as a station of the
//!   deterministic virtual bus (`drivebus_bus::Bus`), exact and repeatable
//!   (what `drivebus demo` and the dual-driver tests use).
//!
//! ```no_run
//! # async fn demo() -> Result<(), Box<dyn std::error::Error>> {
//! let bus = drivebus_transport::open("socketcand://localhost:29536/vcan0").await?;
//! let master = drivebus_master::Master::new(bus);
//! let device_type: u32 = master.sdo(5).read(0x1000, 0).await?;
//! # let _ = device_type; Ok(()) }
//! ```
//!
//! Modules: [`driver`] (tokio,
//! simulated time); `master` (events, NMT, heartbeat/guarding, EMCY,
//! SYNC/TIME); [`sdo`]; [`dict`] (objects by name); [`scan`]; [`lss`]; [`pdo`]; [`drive`] (CiA 402).

mod core;
pub mod dcf;
pub mod dict;
pub mod drive;
pub mod driver;
pub mod gateway;
pub mod lss;
mod master;
pub mod pdo;
pub mod scan;
pub mod sdo;

pub use crate::core::Stats;
pub use dcf::DumpReport;
pub use drive::{
    DriveError, DriveFlags, DriveState, ModeNotShown, MotionEnd, MotionLimits, MotionProgress, MotionReport,
    MoveProfile, RemoteDrive, StopAction, StopReport, mode_name,
};
/// Where mapped objects sit in a PDO or process-data image: the PDO crate's one helper.
pub use drivebus_pdo::{MappedObject, find_mapped, layout as pdo_layout, mapped_bits};
pub use driver::sim::{SimBus, Stalled};
pub use lss::{LssError, LssMaster, OnlySlave};
pub use master::{Master, MasterConfig, MasterEvent, NodeStatus, PdoCallback, SyncTick, WaitError};
pub use pdo::{ConfigError, PdoDir, PdoMapEntry, PdoRecord, PdoWriteError};
pub use scan::{ScanOptions, ScannedNode};
pub use sdo::{SdoError, SdoFailure, SdoHandle, SdoValue};

/// Re-exports so users need one dependency.
pub use drivebus_bus::{Bus as VirtualBus, BusConfig as VirtualBusConfig, candump};
pub use drivebus_can::{CanId, Frame, Instant};
pub use drivebus_emcy::describe as emcy_description;
pub use drivebus_lss::codec::LssField;
pub use drivebus_lss::{FastScan, Identity, LssAddressRange, LssMode};
pub use drivebus_nmt::{NmtCommand, RemoteState};
pub use drivebus_od::{DataType, SdoAbort, Value};
pub use drivebus_sdo::client::Protocol;
/// The SDO command byte (CiA 301 §7.2.4.3), for tools that decode frames.
pub use drivebus_sdo::wire as sdo_wire;
