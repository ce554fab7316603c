//! Write checks for the PDO objects: the CiA 301 configuration procedure
//! (7.5.2.35..7.5.2.38) and the exact abort for each refusal.

use crate::cobid::{COB_ID_BITS, COB_NO_RTR, can_id, is_valid};
use crate::config::PdoConfig;
use crate::mapping::{PdoKind, resolve, validate_entry, validate_mapping};
use crate::objects::{
    SUB_COB_ID, SUB_EVENT_TIMER, SUB_INHIBIT_TIME, SUB_RESERVED, SUB_SYNC_START, SUB_TRANSMISSION_TYPE,
    TT_EVENT_RTR, TT_SYNC_RTR, classify, comm_index, map_index,
};
use alloc::vec::Vec;
use drivebus_od::{DataType, ObjectDictionary, SdoAbort, check_len, le_u64};

/// Transmission types CiA 301 Table 71/73 allows for `kind` on this device:
/// 241..=251 are reserved; 252/253 are TPDO-only and need RTR support.
pub(crate) fn check_transmission_type(cfg: &PdoConfig, kind: PdoKind, t: u8) -> Result<(), SdoAbort> {
    match (kind, t) {
        (_, 241..=251) => Err(SdoAbort::INVALID_VALUE),
        (PdoKind::Rpdo, TT_SYNC_RTR | TT_EVENT_RTR) => Err(SdoAbort::INVALID_VALUE),
        (PdoKind::Tpdo, TT_SYNC_RTR | TT_EVENT_RTR) if !cfg.rtr_supported => Err(SdoAbort::INVALID_VALUE),
        _ => Ok(()),
    }
}

fn value(dt: DataType, data: &[u8]) -> Result<u64, SdoAbort> {
    check_len(dt, data.len())?;
    Ok(le_u64(data))
}

/// The stored mapping entries of a mapping record (sub 1..=sub 0).
pub(crate) fn stored_entries(od: &ObjectDictionary, map_idx: u16) -> Vec<u32> {
    let n = od.get_u64(map_idx, 0).unwrap_or(0) as u8;
    (1..=n).map(|i| od.get_u32(map_idx, i).unwrap_or(0)).collect()
}

/// See [`crate::Pdo::check_write`].
pub(crate) fn check_write(
    cfg: &PdoConfig,
    od: &ObjectDictionary,
    index: u16,
    sub: u8,
    data: &[u8],
) -> Result<(), SdoAbort> {
    let Some((kind, n, is_map)) = classify(cfg, index) else { return Ok(()) };
    let ci = comm_index(kind, n);
    let old_cob = od.get_u32(ci, SUB_COB_ID).ok_or(SdoAbort::NO_OBJECT)?;
    let valid = is_valid(old_cob);
    if is_map {
        return check_mapping_write(cfg, od, kind, index, sub, data, valid);
    }
    match sub {
        SUB_COB_ID => {
            let new = value(DataType::Unsigned32, data)? as u32;
            // CiA 301 7.5.2.35: bits 0..29 may not change while the PDO exists.
            if valid && is_valid(new) && (new ^ old_cob) & COB_ID_BITS != 0 {
                return Err(SdoAbort::INVALID_VALUE);
            }
            if is_valid(new) {
                // Reserved/restricted CAN-IDs and malformed 11-bit ids.
                if can_id(new).is_none() {
                    return Err(SdoAbort::INVALID_VALUE);
                }
                // Creating the PDO: its mapping must still resolve.
                if !valid {
                    let mi = map_index(kind, n);
                    resolve(od, cfg, kind, &stored_entries(od, mi)).map_err(|_| SdoAbort::INVALID_VALUE)?;
                }
            }
            // CiA 301 7.5.2.37: without RTR support, bit 30 = 0 is refused
            // unless the device is known to ignore it (on RPDOs bit 30 is
            // reserved and ignored).
            if kind == PdoKind::Tpdo && !cfg.rtr_supported && !cfg.ignore_rtr_bit && new & COB_NO_RTR == 0 {
                return Err(SdoAbort::INVALID_VALUE);
            }
            Ok(())
        }
        SUB_TRANSMISSION_TYPE => check_transmission_type(cfg, kind, value(DataType::Unsigned8, data)? as u8),
        SUB_INHIBIT_TIME => {
            let new = value(DataType::Unsigned16, data)?;
            // CiA 301 7.5.2.37: inhibit time may not change while the TPDO exists.
            if kind == PdoKind::Tpdo && valid && Some(new) != od.get_u64(ci, SUB_INHIBIT_TIME) {
                return Err(SdoAbort::INVALID_VALUE);
            }
            Ok(())
        }
        SUB_EVENT_TIMER => value(DataType::Unsigned16, data).map(|_| ()),
        // CiA 301 7.5.2.35: TPDO sub 4 is a compatibility entry; where a
        // device implements it (it is in the dictionary), writes are
        // taken and ignored.
        SUB_RESERVED if kind == PdoKind::Tpdo => value(DataType::Unsigned8, data).map(|_| ()),
        SUB_SYNC_START if kind == PdoKind::Tpdo => {
            let new = value(DataType::Unsigned8, data)?;
            if new > 240 {
                return Err(SdoAbort::VALUE_TOO_HIGH);
            }
            if valid && Some(new) != od.get_u64(ci, SUB_SYNC_START) {
                return Err(SdoAbort::INVALID_VALUE);
            }
            Ok(())
        }
        _ => Err(SdoAbort::NO_SUB_INDEX),
    }
}

fn check_mapping_write(
    cfg: &PdoConfig,
    od: &ObjectDictionary,
    kind: PdoKind,
    mi: u16,
    sub: u8,
    data: &[u8],
    valid: bool,
) -> Result<(), SdoAbort> {
    if sub > cfg.max_entries {
        return Err(SdoAbort::NO_SUB_INDEX);
    }
    let dt = if sub == 0 { DataType::Unsigned8 } else { DataType::Unsigned32 };
    let v = value(dt, data)?;
    // Writing the value an entry holds changes no mapping: accepted in
    // any state (the procedure of 7.5.2.36 is about changes).
    if od.get_u64(mi, sub) == Some(v) {
        return Ok(());
    }
    // CiA 301 7.5.2.36 step 1: the PDO must be destroyed (bit 31 = 1) first.
    if valid {
        return Err(SdoAbort::INVALID_VALUE);
    }
    if sub == 0 {
        if v > u64::from(cfg.max_entries) {
            return Err(SdoAbort::VALUE_TOO_HIGH);
        }
        let entries = (1..=v as u8).map(|i| od.get_u32(mi, i).unwrap_or(0));
        return validate_mapping(od, cfg, kind, entries).map(|_| ());
    }
    // Step 2: entries change only while the mapping is disabled (sub 0 = 0).
    if od.get_u64(mi, 0).unwrap_or(0) != 0 {
        return Err(SdoAbort::INVALID_VALUE);
    }
    // Clearing an entry is always fine; it is checked again when sub 0 is set.
    if v == 0 {
        return Ok(());
    }
    validate_entry(od, cfg, kind, v as u32).map(|_| ())
}
