//! A complete CiA 301 device: the communication services (SDO, PDO, NMT
//! and error control, EMCY, SYNC, TIME, LSS) composed over one object
//! dictionary, sans-IO, with 1010h/1011h store and restore.
//!
//! ```
//! use drivebus_can::{Frame, Instant};
//! use drivebus_node::{Node, NodeConfig};
//! use drivebus_od::NoHooks;
//!
//! let mut cfg = NodeConfig::new(5);
//! cfg.device_type = 0x0002_0192;
//! let mut node = Node::new(cfg);
//! let mut out = Vec::new();
//! node.boot(Instant::ZERO, &mut NoHooks, &mut out);
//! assert_eq!(out[0], Frame::new(0x705, &[0x00])); // boot-up
//! node.handle_frame(&Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), Instant::ZERO, &mut NoHooks, &mut out);
//! assert_eq!(out[1], Frame::new(0x585, &[0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00]));
//! ```
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod app;
mod config;
mod device;
mod dictionary;
#[cfg(feature = "std")]
mod eds_device;
#[cfg(feature = "std")]
mod eds_object;
mod foreign;
mod node;
pub mod owners;
mod poll;
mod requests;
pub mod storage;

pub use app::{AppContext, Application, FrameFilter, NodeEvent, Request};
pub use config::NodeConfig;
pub use device::NodeDevice;
pub use dictionary::build_dictionary;
/// 1018h identity (also the LSS address): the one type of `drivebus-can`.
pub use drivebus_can::Identity;
#[cfg(feature = "std")]
pub use eds_device::EdsOptions;
pub use node::{Node, NodeTemplate};
pub use owners::{LOAD_SIGNATURE, SAVE_SIGNATURE};
#[cfg(feature = "std")]
pub use storage::FileStorage;
pub use storage::{MemoryStorage, Slot, Storage, StorageError};

/// Re-exports so users of the node need one dependency.
pub use drivebus_nmt::{NmtCommand, NmtState};
pub use drivebus_od::{Owner, Target, WriteOutcome};
