//! EMCY producer and consumer, error register and pre-defined error field
//! (CiA 301 §7.2.7, objects 1001h, 1003h, 1014h, 1015h, 1028h).
//!
//! * [`Emcy`] is the producer: it owns 1001h, 1003h, 1014h and 1015h, keeps
//!   the list of active errors, and queues EMCY frames that [`Emcy::poll`]
//!   sends while respecting the inhibit time.
//! * [`EmcyConsumer`] owns 1028h and turns received EMCY frames of the
//!   configured producers into [`EmcyReceived`] values.
//! * [`decode`] parses any EMCY frame; [`describe`] names the standard
//!   CiA 301 / CiA 402 error codes; [`register_bit_for`] maps a code to its
//!   1001h bit.
//!
//! ```
//! use drivebus_can::{Frame, Instant};
//! use drivebus_emcy::{Emcy, register_bit_for};
//! use drivebus_od::ObjectDictionary;
//!
//! let mut od = ObjectDictionary::new();
//! let mut emcy = Emcy::install(&mut od, 1, 8);
//! let now = Instant::from_millis(1);
//! emcy.raise(&mut od, 0x3210, register_bit_for(0x3210), [0; 5], now);
//! let mut out = Vec::new();
//! emcy.poll(now, &mut out);
//! assert_eq!(out, [Frame::new(0x081, &[0x10, 0x32, 0x05, 0, 0, 0, 0, 0])]);
//! assert_eq!(od.get_u32(0x1001, 0), Some(0x05));
//! assert_eq!(od.get_u32(0x1003, 1), Some(0x3210));
//! ```
//!
//! Like every drivebus service this crate is sans-IO: the caller passes
//! `now`, the object dictionary and a [`drivebus_can::TxSink`]. NMT-state
//! gating (EMCY is only sent in Pre-operational and Operational) is the
//! node's job.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod codes;
mod consumer;
mod producer;

pub use codes::{ErrorRegister, describe, register_bit_for};
pub use consumer::{EmcyConsumer, EmcyMessage, EmcyReceived, decode};
pub use producer::{ActiveError, Emcy, MAX_ACTIVE, MAX_HISTORY, QUEUE_LEN};

use drivebus_can::CanId;
use drivebus_od::SdoAbort;

/// 1001h: error register.
pub const OD_ERROR_REGISTER: u16 = 0x1001;
/// 1003h: pre-defined error field (error history).
pub const OD_ERROR_HISTORY: u16 = 0x1003;
/// 1014h: COB-ID EMCY.
pub const OD_COB_ID_EMCY: u16 = 0x1014;
/// 1015h: inhibit time EMCY (100 µs units).
pub const OD_INHIBIT_TIME_EMCY: u16 = 0x1015;
/// 1028h: emergency consumer object.
pub const OD_EMCY_CONSUMER: u16 = 0x1028;

/// COB-ID bit 31: the object does *not* exist / is not valid (CiA 301 §7.5.2, 1014h and 1028h).
pub const COB_ID_INVALID: u32 = 1 << 31;
/// COB-ID bit 29: 29-bit (extended) CAN identifier.
pub const COB_ID_EXTENDED: u32 = 1 << 29;

pub(crate) use drivebus_can::cob::can_id as can_id_of;

pub(crate) use drivebus_can::cob::is_restricted;

/// Common checks for a COB-ID written to an EMCY object (1014h, 1028h):
/// CiA 301 §7.5.2 (1014h) forbids changing bits 0..29 while the entry is valid
/// (bit 31 = 0), bit 30 is reserved, an 11-bit id must fit, and a valid
/// 11-bit id must not be restricted. Every refusal is `0609 0030`.
pub(crate) fn check_cob_id_write(old: u32, new: u32) -> Result<(), SdoAbort> {
    let id_bits = 0x3FFF_FFFF & !(1 << 30);
    if new & (1 << 30) != 0 {
        return Err(SdoAbort::INVALID_VALUE);
    }
    let old_valid = old & COB_ID_INVALID == 0;
    let new_valid = new & COB_ID_INVALID == 0;
    if old_valid && new_valid && (old & id_bits) != (new & id_bits) {
        return Err(SdoAbort::INVALID_VALUE);
    }
    let Some(id) = can_id_of(new) else { return Err(SdoAbort::INVALID_VALUE) };
    if new_valid
        && let CanId::Standard(raw) = id
        && is_restricted(raw)
    {
        return Err(SdoAbort::INVALID_VALUE);
    }
    Ok(())
}

/// Little-endian u32 of a 4-byte SDO write, or the length abort.
pub(crate) fn u32_of(data: &[u8]) -> Result<u32, SdoAbort> {
    drivebus_od::check_len(drivebus_od::DataType::Unsigned32, data.len())?;
    Ok(u32::from_le_bytes([data[0], data[1], data[2], data[3]]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cob_id_rules() {
        // Valid -> valid with another id: refused (§7.5.2 (1014h)).
        assert_eq!(check_cob_id_write(0x81, 0x82), Err(SdoAbort::INVALID_VALUE));
        // Invalidate, change, revalidate: accepted.
        assert_eq!(check_cob_id_write(0x81, 0x8000_0081), Ok(()));
        assert_eq!(check_cob_id_write(0x8000_0081, 0x8000_0082), Ok(()));
        assert_eq!(check_cob_id_write(0x8000_0082, 0x82), Ok(()));
        // Same value again: accepted.
        assert_eq!(check_cob_id_write(0x81, 0x81), Ok(()));
        // Reserved bit 30, oversize 11-bit id, restricted ids.
        assert_eq!(check_cob_id_write(0x8000_0000, 0x4000_0081), Err(SdoAbort::INVALID_VALUE));
        assert_eq!(check_cob_id_write(0x8000_0000, 0x0000_0881), Err(SdoAbort::INVALID_VALUE));
        assert_eq!(check_cob_id_write(0x8000_0000, 0x0000_0601), Err(SdoAbort::INVALID_VALUE));
        assert_eq!(check_cob_id_write(0x8000_0000, 0x0000_0000), Err(SdoAbort::INVALID_VALUE));
        // A restricted id may be stored while invalid.
        assert_eq!(check_cob_id_write(0x8000_0000, 0x8000_0601), Ok(()));
        // 29-bit ids are supported.
        assert_eq!(check_cob_id_write(0x8000_0000, 0x2012_3456), Ok(()));
        assert_eq!(can_id_of(0x2012_3456), Some(CanId::Extended(0x0012_3456)));
    }
}
