//! SYNC producer/consumer (CiA 301 §7.2.5, objects 1005h, 1006h, 1007h,
//! 1019h) and TIME producer/consumer (CiA 301 §7.2.6, object 1012h).
//!
//! * [`SyncService`] receives SYNC frames ([`SyncService::handle_frame`] →
//!   [`SyncEvent`]), produces them when 1005h bit 30 is set
//!   ([`SyncService::poll`], which also reports the node's own SYNC),
//!   tracks the synchronous window 1007h and watches for SYNC loss.
//! * [`TimeService`] sends and receives TIME_OF_DAY stamps
//!   ([`TimeOfDay`], 1984-01-01 epoch, with Unix time conversions).
//!
//! ```
//! use drivebus_can::{Frame, Instant};
//! use drivebus_od::ObjectDictionary;
//! use drivebus_sync::SyncService;
//!
//! let mut od = ObjectDictionary::new();
//! let mut sync = SyncService::install(&mut od, 1);
//! let ev = sync.handle_frame(&Frame::new(0x080, &[]), Instant::from_millis(1)).unwrap();
//! assert_eq!((ev.counter, ev.length_error), (None, None));
//! assert!(sync.window_open(Instant::from_millis(2)));
//! ```
//!
//! Sans-IO like every drivebus service: the caller passes `now`, the
//! object dictionary and a [`drivebus_can::TxSink`]. NMT-state gating is
//! the node's job. Nothing allocates after `install`.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod sync;
mod time;

pub use sync::{SyncEvent, SyncLengthError, SyncPoll, SyncService, SyncTimeout};
pub use time::{CivilTime, TimeOfDay, TimeService, UNIX_DAYS_AT_1984};

use drivebus_can::CanId;
use drivebus_od::SdoAbort;

/// 1005h: COB-ID SYNC message.
pub const OD_COB_ID_SYNC: u16 = 0x1005;
/// 1006h: communication cycle period (µs).
pub const OD_CYCLE_PERIOD: u16 = 0x1006;
/// 1007h: synchronous window length (µs).
pub const OD_SYNC_WINDOW: u16 = 0x1007;
/// 1012h: COB-ID time stamp object.
pub const OD_COB_ID_TIME: u16 = 0x1012;
/// 1019h: synchronous counter overflow value.
pub const OD_SYNC_COUNTER_OVERFLOW: u16 = 0x1019;

/// COB-ID bit 29: 29-bit (extended) CAN identifier.
pub const COB_ID_EXTENDED: u32 = 1 << 29;
/// 1005h bit 30 "gen": this node generates SYNC. 1012h bit 30: this node produces TIME.
pub const COB_ID_PRODUCE: u32 = 1 << 30;
/// 1012h bit 31: this node consumes TIME (1005h: don't care).
pub const COB_ID_CONSUME: u32 = 1 << 31;
/// Bits 0..29: the identifier and its frame format.
const ID_BITS: u32 = 0x3FFF_FFFF;

pub(crate) use drivebus_can::cob::can_id as can_id_of;

pub(crate) use drivebus_can::cob::is_restricted;

/// COB-ID write rules shared by 1005h and 1012h: the identifier must fit its
/// format and not be restricted, and while the service is active
/// (`active_bits` set in the old value) bits 0..29 must not change. Every
/// refusal is `0609 0030` (CiA 301 §7.5.2, 1005h and 1012h).
pub(crate) fn check_cob_id(old: u32, new: u32, active_bits: u32) -> Result<(), SdoAbort> {
    let Some(id) = can_id_of(new) else { return Err(SdoAbort::INVALID_VALUE) };
    if let CanId::Standard(raw) = id
        && is_restricted(raw)
    {
        return Err(SdoAbort::INVALID_VALUE);
    }
    if old & active_bits != 0 && (old ^ new) & ID_BITS != 0 {
        return Err(SdoAbort::INVALID_VALUE);
    }
    Ok(())
}

/// Little-endian value of a fixed-size SDO write, or the length abort.
pub(crate) fn le_of(dt: drivebus_od::DataType, data: &[u8]) -> Result<u32, SdoAbort> {
    drivebus_od::check_len(dt, data.len())?;
    Ok(drivebus_od::le_u64(data) as u32)
}
