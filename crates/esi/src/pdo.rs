//! PDOs from the dictionary: mapping objects 1600h–17FFh (RxPDO) and
//! 1A00h–1BFFh (TxPDO), their default mapping, and the default assignment
//! (1C12h/1C13h on EtherCAT, valid COB-IDs on a CAN dictionary).

use crate::description::{EsiPdo, PdoEntry};
use crate::model::EsiObject;
use crate::types::xml_safe;
use drivebus_coe::access_bits;
use drivebus_od::{ObjectDictionary, le_u64};

/// The RxPDO mapping objects.
pub const RX_MAPPING: std::ops::RangeInclusive<u16> = 0x1600..=0x17FF;
/// The TxPDO mapping objects.
pub const TX_MAPPING: std::ops::RangeInclusive<u16> = 0x1A00..=0x1BFF;

/// The default value of `(index, sub)` as an unsigned number.
pub fn default_u64(od: &ObjectDictionary, index: u16, sub: u8) -> Option<u64> {
    od.get(index, sub).map(|s| le_u64(&s.default))
}

/// The default mapping entries of a mapping object: subs 1..=sub 0's
/// default, as `index << 16 | sub << 8 | bits`; entries the object lacks
/// are skipped.
pub fn mapping_values(od: &ObjectDictionary, index: u16) -> Vec<u32> {
    let n = default_u64(od, index, 0).unwrap_or(0).min(255) as u8;
    (1..=n).filter_map(|i| default_u64(od, index, i).map(|v| v as u32)).collect()
}

/// The default assignment of an SM: 1C12h (`rx`) or 1C13h, subs
/// 1..=sub 0's default. Without that object (a CAN dictionary), the PDOs
/// whose communication parameter (1400h+n / 1800h+n sub 1) has bit 31
/// clear, in order. `None` when neither exists.
pub fn default_assignment(od: &ObjectDictionary, rx: bool) -> Option<Vec<u16>> {
    let (assign, comm, map) = if rx { (0x1C12, 0x1400, 0x1600) } else { (0x1C13, 0x1800, 0x1A00) };
    if od.object(assign).is_some() {
        let n = default_u64(od, assign, 0).unwrap_or(0).min(255) as u8;
        return Some((1..=n).filter_map(|i| default_u64(od, assign, i).map(|v| v as u16)).collect());
    }
    let valid: Vec<u16> = (0..0x200u16)
        .filter(|n| od.object(map + n).is_some())
        .filter(|n| default_u64(od, comm + n, 1).is_some_and(|cob| cob & 0x8000_0000 == 0))
        .map(|n| map + n)
        .collect();
    (od.objects().iter().any(|o| (comm..comm + 0x200).contains(&o.index))).then_some(valid)
}

/// One PDO entry from a mapping value. Dummy entries (data type indices
/// 0001h–0007h, CiA 301 §7.4.7.1) become ETG.2000 gaps (index 0).
pub fn entry(od: &ObjectDictionary, value: u32) -> PdoEntry {
    let (index, sub, bit_len) = ((value >> 16) as u16, (value >> 8) as u8, value as u8);
    if (0x0001..=0x0007).contains(&index) {
        return PdoEntry { index: 0, sub: 0, bit_len, name: String::new(), data_type: None };
    }
    let target = od.get(index, sub);
    PdoEntry {
        index,
        sub,
        bit_len,
        name: target.map(|s| xml_safe(&s.name).into_owned()).unwrap_or_default(),
        data_type: target.map(|s| s.data_type),
    }
}

/// RxPDOs and TxPDOs of `od`: default-assigned ones first in assignment
/// order with `sm` set, then the others by index. `objects` (the ESI view)
/// says whether a mapping can be changed.
pub fn describe(
    od: &ObjectDictionary,
    objects: &[EsiObject],
    out_sm: u8,
    in_sm: u8,
) -> (Vec<EsiPdo>, Vec<EsiPdo>) {
    let build = |range: std::ops::RangeInclusive<u16>, rx: bool, sm: u8| {
        let assigned = default_assignment(od, rx).unwrap_or_default();
        let mut pdos: Vec<EsiPdo> = od
            .objects()
            .iter()
            .filter(|o| range.contains(&o.index))
            .map(|o| {
                let esi = objects.iter().find(|e| e.index == o.index);
                let writable = esi.and_then(|e| e.get(0)).is_some_and(|s| s.access & access_bits::WRITE != 0);
                EsiPdo {
                    index: o.index,
                    name: xml_safe(&o.name).into_owned(),
                    sm: assigned.contains(&o.index).then_some(sm),
                    fixed: !writable,
                    mandatory: false,
                    entries: mapping_values(od, o.index).into_iter().map(|v| entry(od, v)).collect(),
                }
            })
            .collect();
        let rank = |p: &EsiPdo| assigned.iter().position(|a| *a == p.index).unwrap_or(usize::MAX);
        pdos.sort_by_key(|p| (rank(p), p.index));
        pdos
    };
    (build(RX_MAPPING, true, out_sm), build(TX_MAPPING, false, in_sm))
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_od::{Access, DataType, Object, SubObject, Value};

    fn od() -> ObjectDictionary {
        let mut od = ObjectDictionary::new();
        od.insert(Object::var(0x6040, "Controlword", DataType::Unsigned16, Access::Rww, Value::U16(0)));
        od.insert(Object::var(0x607A, "Target position", DataType::Integer32, Access::Rww, Value::I32(0)));
        let map = |i: u16, v: &[u32]| {
            let mut o = Object::with_code(i, drivebus_od::ObjectCode::Record, format!("RxPDO {i:X}"))
                .with_sub(SubObject::new(0, "n", DataType::Unsigned8, Access::Rw, Value::U8(v.len() as u8)));
            for (k, x) in v.iter().enumerate() {
                o = o.with_sub(SubObject::new(
                    k as u8 + 1,
                    "e",
                    DataType::Unsigned32,
                    Access::Rw,
                    Value::U32(*x),
                ));
            }
            o
        };
        od.insert(map(0x1600, &[0x6040_0010, 0x607A_0020]));
        od.insert(map(0x1601, &[0x6040_0010, 0x0005_0008]));
        od
    }

    #[test]
    fn mapping_assignment_and_gaps() {
        let mut od = od();
        assert_eq!(mapping_values(&od, 0x1600), vec![0x6040_0010, 0x607A_0020]);
        assert_eq!(default_assignment(&od, true), None, "neither 1C12h nor CAN COB-IDs");
        od.insert(Object::array(0x1C12, "assign", DataType::Unsigned16, Access::Rw, 2, Value::U16(0)));
        od.get_mut(0x1C12, 1).unwrap().default = 0x1601u16.to_le_bytes().to_vec();
        od.get_mut(0x1C12, 2).unwrap().default = 0x1600u16.to_le_bytes().to_vec();
        assert_eq!(default_assignment(&od, true), Some(vec![0x1601, 0x1600]));
        let objects: Vec<EsiObject> = od
            .objects()
            .iter()
            .map(|o| EsiObject::from_od(o, |_, s| drivebus_coe::default_object_access(s)))
            .collect();
        let (rx, tx) = describe(&od, &objects, 2, 3);
        assert!(tx.is_empty());
        assert_eq!(
            rx.iter().map(|p| (p.index, p.sm)).collect::<Vec<_>>(),
            [(0x1601, Some(2)), (0x1600, Some(2))]
        );
        assert_eq!(
            rx[0].entries[1],
            PdoEntry { index: 0, sub: 0, bit_len: 8, name: String::new(), data_type: None }
        );
        assert_eq!(rx[1].entries[1].data_type, Some(DataType::Integer32));
        assert_eq!(rx[1].bits(), 48);
        assert!(!rx[0].fixed);
    }

    #[test]
    fn can_dictionaries_assign_by_cob_id() {
        let mut od = od();
        for (n, cob) in [(0u16, 0x200u32 + 5), (1, 0x8000_0305)] {
            od.insert(Object::record(0x1400 + n, "comm").with_sub(SubObject::new(
                1,
                "COB-ID",
                DataType::Unsigned32,
                Access::Rw,
                Value::U32(cob),
            )));
        }
        assert_eq!(default_assignment(&od, true), Some(vec![0x1600]));
        assert_eq!(default_assignment(&od, false), None);
    }
}
