//! The generic CiA 402 servo: every feature of the stack, no quirks.
//!
//! Beyond [`crate::build::node_config`] from its [`ProfileInfo`](crate::ProfileInfo):
//! LSS (CiA 305) on, the EDS served at 1021h/1022h, and the CiA 302-3
//! program download objects for firmware-style block transfers:
//!
//! - 1F50h:1 program data (DOMAIN): written by segmented or block download,
//!   read back by upload;
//! - 1F51h:1 program control: 0 stop, 1 start, 2 reset, 3 clear (clears
//!   1F50h:1); other values `0609 0030`; a download while the program runs
//!   is refused with `0800 0022` (device state);
//! - 1F56h:1 program software identification: the CRC-32 (IEEE) of the
//!   program data, 0 when empty, updated after every download.

mod facts;

pub use facts::INFO;

/// The EDS file (`crates/personality/eds/generic.eds`).
pub const EDS: &str = include_str!("../../eds/generic.eds");

use crate::Profile;
use crate::build::{Behaviour, Context, Verdict};
use drivebus_cia402::drive::DriveConfig;
use drivebus_node::NodeConfig;
use drivebus_od::{ObjectDictionary, SdoAbort};

/// 1F51h program control values (CiA 302-3).
pub mod control {
    /// Stop the program.
    pub const STOP: u8 = 0;
    /// Start the program.
    pub const START: u8 = 1;
    /// Reset (stop and start).
    pub const RESET: u8 = 2;
    /// Clear the program data.
    pub const CLEAR: u8 = 3;
}

/// The generic servo behaviour.
#[derive(Debug, Clone, Default)]
pub struct Generic {
    running: bool,
}

impl Generic {
    /// The generic behaviour.
    pub fn new() -> Self {
        Generic { running: false }
    }
}

/// CRC-32 (IEEE 802.3, reflected, init and final xor FFFF_FFFFh).
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

fn set_ident(od: &mut ObjectDictionary) {
    let id = match od.get(0x1F50, 1) {
        Some(s) if !s.bytes().is_empty() => crc32(s.bytes()),
        _ => 0,
    };
    if let Ok(r) = od.find(0x1F56, 1) {
        od.set_raw(r, &id.to_le_bytes());
    }
}

impl Behaviour for Generic {
    fn profile(&self) -> Profile {
        Profile::Generic
    }

    /// CiA 402-2 digital I/O towards the machine: 60FDh bits 16–31 show
    /// input lines 1–16, 60FEh:1 bits 16–31 drive output lines 1–16 and
    /// bit 0 sets the brake (each as far as 60FEh:2 enables it).
    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        cfg.io.input_lines = true;
        cfg.io.output_lines = true;
        cfg.io.set_brake_bit = true;
    }

    fn adjust_node_config(&self, cfg: &mut NodeConfig) {
        cfg.eds_object = true;
        cfg.sdo.block_transfer = true;
    }

    fn hooked_objects(&self) -> &'static [u16] {
        &[0x1F50, 0x1F51]
    }

    fn on_write(
        &mut self,
        _cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        match (index, sub) {
            (0x1F50, 1) => {
                if self.running {
                    return Err(SdoAbort::DEVICE_STATE);
                }
                Ok(Verdict::Store)
            }
            (0x1F51, 1) => {
                match data.first().copied().unwrap_or(0xFF) {
                    control::STOP => self.running = false,
                    control::START | control::RESET => {
                        self.running = od.get(0x1F50, 1).is_some_and(|s| !s.bytes().is_empty());
                        if !self.running {
                            // Nothing to start.
                            return Err(SdoAbort::DEVICE_STATE);
                        }
                    }
                    control::CLEAR => {
                        if self.running {
                            return Err(SdoAbort::DEVICE_STATE);
                        }
                        if let Ok(r) = od.find(0x1F50, 1) {
                            od.set_raw(r, &[]);
                        }
                        set_ident(od);
                    }
                    _ => return Err(SdoAbort::INVALID_VALUE),
                }
                Ok(Verdict::Store)
            }
            _ => Ok(Verdict::Pass),
        }
    }

    fn after_write(&mut self, _cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, sub: u8) {
        if (index, sub) == (0x1F50, 1) {
            set_ident(od);
        }
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }
}
