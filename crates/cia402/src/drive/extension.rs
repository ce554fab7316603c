//! The personality hook: manufacturer statusword bits and write vetoes by
//! drive state.
//!
//! CiA 402-2 §6.2.2 leaves statusword bits 8, 14 and 15 to the manufacturer
//! and lets the device decide when bit 9 (*remote*) is set. A personality
//! (crates/personality) implements [`DriveExtension`] and puts it into
//! [`DriveConfig::extension`](super::DriveConfig::extension):
//!
//! ```
//! use core::sync::atomic::{AtomicBool, Ordering};
//! use drivebus_cia402::drive::{DriveConfig, DriveExtension, DriveView, Extension};
//! use drivebus_cia402::state_machine::State;
//! use drivebus_od::SdoAbort;
//! use std::sync::Arc;
//!
//! /// SSD 630 style: *remote* follows an enable input; no 1010h store while
//! /// the drive is enabled or the node operational (DDS6 style).
//! #[derive(Default)]
//! struct Ssd630 {
//!     enable_input: AtomicBool,
//! }
//!
//! impl DriveExtension for Ssd630 {
//!     fn status_bits(&self, view: &DriveView) -> u16 {
//!         let remote = self.enable_input.load(Ordering::Relaxed);
//!         (view.statusword & !(1 << 9)) | u16::from(remote) << 9
//!     }
//!     fn check_write(&self, view: &DriveView, index: u16, _sub: u8, _data: &[u8]) -> Result<(), SdoAbort> {
//!         if index == 0x6040 && !self.enable_input.load(Ordering::Relaxed) {
//!             return Err(SdoAbort::LOCAL_CONTROL); // local: the controlword is not executed
//!         }
//!         if index == 0x1010 && (view.state == State::OperationEnabled || view.operational) {
//!             return Err(SdoAbort::DEVICE_STATE);
//!         }
//!         Ok(())
//!     }
//! }
//!
//! let ext = Arc::new(Ssd630::default());
//! let mut cfg = DriveConfig::default();
//! cfg.extension = Extension::new(ext.clone());
//! // ... later, the personality drives the input:
//! ext.enable_input.store(true, Ordering::Relaxed);
//! ```
//!
//! The hook's methods take `&self` so the personality can keep a clone of
//! the `Arc` and change its own inputs (atomics) while the drive runs; the
//! drive asks for the bits whenever it publishes the statusword (every
//! poll). [`Drive::set_extension`](super::Drive::set_extension) installs
//! one after the drive was built (e.g. by `generic_drive_with`).
//!
//! Write vetoes: the node hands every write of a hooked object to its
//! application (the drive) before acting on it, 1000h–1FFFh included
//! (1010h store, 1011h restore are hooked by the node), so
//! [`DriveExtension::check_write`] sees them all, by SDO and RPDO, with the
//! drive state in [`DriveView`]. A personality that wraps the drive in its
//! own `drivebus_node::Application` could veto in its `on_write` the same
//! way; the extension saves that wrapper.

use crate::state_machine::State;
use alloc::sync::Arc;
use drivebus_od::SdoAbort;

/// What a [`DriveExtension`] sees of the drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriveView {
    /// The device control state (CiA 402-2 §6.2.1).
    pub state: State,
    /// The active mode of operation (6061h).
    pub mode: i8,
    /// The statusword the drive computed (bit 9 from
    /// [`DriveConfig::remote`](super::DriveConfig::remote), bits 8/14/15 clear).
    pub statusword: u16,
    /// The last controlword received (6040h).
    pub controlword: u16,
    /// Digital inputs 60FDh as the drive publishes them.
    pub digital_inputs: u32,
    /// The node is NMT *Operational* (tracked from the node's events).
    pub operational: bool,
}

/// A personality's hook into the drive (see the module docs).
pub trait DriveExtension: Send + Sync {
    /// The statusword bits 8, 9, 14 and 15 ([`STATUS_MASK`]); the other bits
    /// of the result are ignored. The default keeps the drive's own value
    /// (bit 9 from `DriveConfig::remote`, bits 8/14/15 clear).
    fn status_bits(&self, view: &DriveView) -> u16 {
        view.statusword
    }

    /// Called before the drive (or the node, for 1000h–1FFFh such as 1010h
    /// store) acts on a write of a hooked object, by SDO or RPDO; an error is
    /// the SDO abort (an RPDO write is dropped). The default accepts.
    fn check_write(&self, view: &DriveView, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        let _ = (view, index, sub, data);
        Ok(())
    }
}

/// Statusword bits a [`DriveExtension`] controls: 8, 9, 14, 15.
pub const STATUS_MASK: u16 = 0xC300;

/// An optional, shared [`DriveExtension`] (cloneable and comparable by
/// identity so [`DriveConfig`](super::DriveConfig) stays `Clone + PartialEq`).
#[derive(Clone, Default)]
pub struct Extension(pub Option<Arc<dyn DriveExtension>>);

impl Extension {
    /// Wraps an extension.
    pub fn new(ext: Arc<dyn DriveExtension>) -> Extension {
        Extension(Some(ext))
    }
    /// No extension (the default).
    pub const fn none() -> Extension {
        Extension(None)
    }
    /// The extension, if any.
    pub fn get(&self) -> Option<&dyn DriveExtension> {
        self.0.as_deref()
    }
}

impl core::fmt::Debug for Extension {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(if self.0.is_some() { "Extension(Some(..))" } else { "Extension(None)" })
    }
}

impl PartialEq for Extension {
    fn eq(&self, other: &Self) -> bool {
        match (&self.0, &other.0) {
            (None, None) => true,
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}
