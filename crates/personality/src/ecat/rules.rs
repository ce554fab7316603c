//! The CoE object rules a slave enforces on the write path, whoever
//! writes (CoE SDO, complete access, a local tool):
//!
//! * **PDO assignment** 1C12h/1C13h (ETG.1000.6 §5.6.7.4; iPOS §2.3.10,
//!   §2.3.11): written only in PRE-OP (`0800 0022` otherwise); an entry
//!   only while sub 0 is 0 (`0601 0003`); an entry is 0 or a mapping
//!   object of its direction that exists (`0609 0030`); sub 0 counts valid
//!   entries only (`0609 0031` above the slots, `0609 0030` over an empty
//!   or wrong entry).
//! * **PDO mapping** 16xxh/1Axxh (ETG.1000.6; iPOS §2.4): written only in
//!   PRE-OP; an entry only while sub 0 is 0 (`0601 0003`); each entry is
//!   checked as the CAN PDO service checks it (CiA 301 §7.5.2.36:
//!   `0602 0000`, `0604 0041`); the total is checked by
//!   [`check_length`] after the profile's behaviour had its say (the iPOS
//!   takes a mapping over 64 bits, sends EMCY 8220h and ignores it,
//!   §1.6.3.1; other profiles refuse it with `0604 0042`).
//! * **Synchronisation parameters** 1C32h/1C33h (ETG.1020): type, cycle
//!   and shift written only in PRE-OP; the type is one the device
//!   supports (free run, SM event, DC SYNC0; `0609 0030`).

use drivebus_coe::AlState;
use drivebus_coe::coe::abort;
use drivebus_od::{ObjectDictionary, SdoAbort, le_u64};
use drivebus_pdo::{PdoConfig, PdoKind, validate_entry};

/// 1C12h or 1C13h.
pub fn is_assignment(index: u16) -> bool {
    matches!(index, 0x1C12 | 0x1C13)
}

/// A PDO mapping object.
pub fn is_mapping(index: u16) -> bool {
    matches!(index, 0x1600..=0x17FF | 0x1A00..=0x1BFF)
}

/// 1C32h or 1C33h.
pub fn is_sync_parameter(index: u16) -> bool {
    matches!(index, 0x1C32 | 0x1C33)
}

/// An object whose writes these rules check.
pub fn is_ecat_object(index: u16) -> bool {
    is_assignment(index) || is_mapping(index) || is_sync_parameter(index)
}

/// Written only in PRE-OP (what SDO Information and the ESI report as the
/// entry's write access).
pub fn preop_only(index: u16, sub: u8) -> bool {
    is_assignment(index) || is_mapping(index) || (is_sync_parameter(index) && (1..=3).contains(&sub))
}

/// The direction of a mapping object.
pub fn kind_of(index: u16) -> PdoKind {
    if index < 0x1A00 { PdoKind::Rpdo } else { PdoKind::Tpdo }
}

/// The mapping objects 1C12h (RxPDOs) or 1C13h (TxPDOs) may name.
fn assignable(assign: u16, pdo: u16) -> bool {
    match assign {
        0x1C12 => (0x1600..=0x17FF).contains(&pdo),
        _ => (0x1A00..=0x1BFF).contains(&pdo),
    }
}

fn highest_sub(od: &ObjectDictionary, index: u16) -> u8 {
    od.object(index).and_then(|o| o.subs().last()).map_or(0, |s| s.sub)
}

/// Checks a write of `(index, sub)` in ESM state `esm`; `Ok` for objects
/// the rules do not cover.
pub fn check(
    esm: AlState,
    pdo: &PdoConfig,
    od: &ObjectDictionary,
    index: u16,
    sub: u8,
    data: &[u8],
) -> Result<(), SdoAbort> {
    if preop_only(index, sub) && esm != AlState::PreOp {
        return Err(SdoAbort::DEVICE_STATE);
    }
    let value = le_u64(data);
    if is_assignment(index) {
        let valid =
            |pdo: u64| u16::try_from(pdo).is_ok_and(|p| assignable(index, p) && od.object(p).is_some());
        if sub != 0 {
            if od.get_u64(index, 0).unwrap_or(0) != 0 {
                return Err(abort::SI0_MUST_BE_ZERO);
            }
            return if value == 0 || valid(value) { Ok(()) } else { Err(SdoAbort::INVALID_VALUE) };
        }
        if value > u64::from(highest_sub(od, index)) {
            return Err(SdoAbort::VALUE_TOO_HIGH);
        }
        for s in 1..=value as u8 {
            if !valid(od.get_u64(index, s).unwrap_or(0)) {
                return Err(SdoAbort::INVALID_VALUE);
            }
        }
        return Ok(());
    }
    if is_mapping(index) {
        let kind = kind_of(index);
        if sub != 0 {
            if od.get_u64(index, 0).unwrap_or(0) != 0 {
                return Err(abort::SI0_MUST_BE_ZERO);
            }
            // 0 empties an entry; anything else must map.
            return if value == 0 { Ok(()) } else { validate_entry(od, pdo, kind, value as u32).map(|_| ()) };
        }
        if value > u64::from(highest_sub(od, index)) || value > u64::from(pdo.max_entries) {
            return Err(SdoAbort::VALUE_TOO_HIGH);
        }
        for s in 1..=value as u8 {
            validate_entry(od, pdo, kind, od.get_u32(index, s).unwrap_or(0))?;
        }
        return Ok(());
    }
    if is_sync_parameter(index) && sub == crate::ecat::sync::sub::SYNC_TYPE {
        let ok = match index {
            0x1C32 => matches!(value, 0..=2),
            _ => matches!(value, 0 | 2 | 0x22),
        };
        return if ok { Ok(()) } else { Err(SdoAbort::INVALID_VALUE) };
    }
    Ok(())
}

/// The mapped length of a mapping object's sub 0 write of `n` entries:
/// at most `max_bits` (`0604 0042`).
pub fn check_length(od: &ObjectDictionary, index: u16, n: u8, max_bits: u32) -> Result<(), SdoAbort> {
    let bits: u32 = (1..=n).map(|s| od.get_u32(index, s).unwrap_or(0) & 0xFF).sum();
    if bits > max_bits { Err(SdoAbort::PDO_TOO_LONG) } else { Ok(()) }
}

/// The entries of a mapping object as its sub 0 says.
pub fn entries(od: &ObjectDictionary, index: u16) -> alloc::vec::Vec<u32> {
    let n = od.get_u64(index, 0).unwrap_or(0) as u8;
    (1..=n).map(|s| od.get_u32(index, s).unwrap_or(0)).collect()
}

/// The mapping objects an assignment object names, in order.
pub fn assigned(od: &ObjectDictionary, assign: u16) -> alloc::vec::Vec<u16> {
    let n = od.get_u64(assign, 0).unwrap_or(0) as u8;
    (1..=n).filter_map(|s| od.get_u32(assign, s).map(|v| v as u16)).filter(|v| *v != 0).collect()
}

extern crate alloc;

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_od::{Access, DataType, Object, Value};

    fn od() -> ObjectDictionary {
        let mut od = ObjectDictionary::new();
        let mut cw = Object::var(0x6040, "cw", DataType::Unsigned16, Access::Rw, Value::U16(0));
        cw.subs_mut()[0].pdo_mappable = true;
        od.insert(cw);
        let mut m = Object::record(0x1600, "m").with_sub(drivebus_od::SubObject::new(
            0,
            "n",
            DataType::Unsigned8,
            Access::Rw,
            Value::U8(1),
        ));
        for s in 1..=8 {
            let v = if s == 1 { 0x6040_0010 } else { 0 };
            m = m.with_sub(drivebus_od::SubObject::new(
                s,
                "e",
                DataType::Unsigned32,
                Access::Rw,
                Value::U32(v),
            ));
        }
        od.insert(m);
        let mut a = Object::record(0x1C12, "a").with_sub(drivebus_od::SubObject::new(
            0,
            "n",
            DataType::Unsigned8,
            Access::Rw,
            Value::U8(1),
        ));
        for s in 1..=2 {
            let v = if s == 1 { 0x1600 } else { 0 };
            a = a.with_sub(drivebus_od::SubObject::new(
                s,
                "p",
                DataType::Unsigned16,
                Access::Rw,
                Value::U16(v),
            ));
        }
        od.insert(a);
        od
    }

    #[test]
    fn assignment_rules() {
        let od = od();
        let cfg = PdoConfig::default();
        let c = |esm, sub, v: &[u8]| check(esm, &cfg, &od, 0x1C12, sub, v);
        assert_eq!(c(AlState::SafeOp, 0, &[0]), Err(SdoAbort::DEVICE_STATE));
        assert_eq!(c(AlState::PreOp, 1, &[0x00, 0x16]), Err(abort::SI0_MUST_BE_ZERO));
        assert_eq!(c(AlState::PreOp, 0, &[1]), Ok(()));
        assert_eq!(c(AlState::PreOp, 0, &[2]), Err(SdoAbort::INVALID_VALUE), "sub 2 is empty");
        assert_eq!(c(AlState::PreOp, 0, &[3]), Err(SdoAbort::VALUE_TOO_HIGH));
        assert_eq!(assigned(&od, 0x1C12), [0x1600]);
    }

    #[test]
    fn mapping_rules() {
        let od = od();
        let cfg = PdoConfig::default();
        let c = |esm, sub, v: &[u8]| check(esm, &cfg, &od, 0x1600, sub, v);
        assert_eq!(c(AlState::Op, 0, &[0]), Err(SdoAbort::DEVICE_STATE));
        assert_eq!(c(AlState::PreOp, 2, &0x6040_0010u32.to_le_bytes()), Err(abort::SI0_MUST_BE_ZERO));
        assert_eq!(c(AlState::PreOp, 0, &[2]), Err(SdoAbort::NOT_MAPPABLE), "entry 2 is empty");
        assert_eq!(c(AlState::PreOp, 0, &[9]), Err(SdoAbort::VALUE_TOO_HIGH));
        assert_eq!(entries(&od, 0x1600), [0x6040_0010]);
        assert_eq!(check_length(&od, 0x1600, 1, 8), Err(SdoAbort::PDO_TOO_LONG));
        assert!(preop_only(0x1A03, 4) && !preop_only(0x1C32, 5) && preop_only(0x1C33, 2));
    }
}
