//! Property tests: segmented transfers round-trip for any size across
//! mailbox sizes 32..=1486, complete access agrees with per-sub access,
//! the header codec round-trips.

mod support;

use drivebus_coe::{MailboxConfig, MailboxHeader, MailboxType, NoFiles};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectCode, ObjectDictionary, SubObject, Value};
use proptest::prelude::*;
use support::{Dev, Rig, soem, test_od};

/// Mailbox sizes 32..=1486, small ones (many segments, 7-byte minimum
/// segments) drawn as often as the rest.
fn mailbox() -> impl Strategy<Value = usize> {
    prop_oneof![32usize..=48, 32usize..=1486]
}

fn rig(rx: usize, tx: usize, od: ObjectDictionary) -> Rig<Dev, NoFiles> {
    Rig::new(MailboxConfig::with_sizes(rx, tx), (od, NoHooks), NoFiles)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn segmented_round_trip(
        rx in mailbox(),
        tx in mailbox(),
        data in prop::collection::vec(any::<u8>(), 0..6000),
    ) {
        let mut r = rig(rx, tx, test_od());
        soem::sdo_write(&mut r, 0x2000, 0, false, &data).unwrap();
        prop_assert_eq!(r.dev.0.get(0x2000, 0).unwrap().bytes(), &data[..]);
        prop_assert_eq!(soem::sdo_read(&mut r, 0x2000, 0, false).unwrap(), data);
        prop_assert!(r.server.is_idle());
    }

    #[test]
    fn header_round_trip(
        length: u16, address: u16, channel in 0u8..64, priority in 0u8..4, t in 0u8..16, counter in 0u8..8,
    ) {
        let h = MailboxHeader { length, address, channel, priority, mailbox_type: MailboxType::from_bits(t), counter };
        prop_assert_eq!(MailboxHeader::decode(&h.encode()), Some(h));
        prop_assert_eq!(h.mailbox_type.bits(), t);
    }

    #[test]
    fn header_bytes_round_trip(b: [u8; 6]) {
        let mut want = b;
        want[5] &= 0x7F; // the reserved bit is not kept
        prop_assert_eq!(MailboxHeader::decode(&b).unwrap().encode(), want);
    }
}

/// Entry types a complete access can carry, BOOLEAN included (packed).
const TYPES: [DataType; 9] = [
    DataType::Boolean,
    DataType::Unsigned8,
    DataType::Integer16,
    DataType::Unsigned24,
    DataType::Unsigned32,
    DataType::Real32,
    DataType::Integer48,
    DataType::Unsigned64,
    DataType::Real64,
];

/// A RECORD of the given entry types (sub 0 constant) holding `values`.
fn record(types: &[usize], values: &[u64]) -> ObjectDictionary {
    let mut o = Object::record(0x2500, "Rec");
    for (k, &t) in types.iter().enumerate() {
        let dt = TYPES[t];
        let n = dt.fixed_size().unwrap();
        let v = if dt == DataType::Boolean { values[k] & 1 } else { values[k] };
        let bytes = v.to_le_bytes()[..n].to_vec();
        o = o.with_sub(SubObject::from_bytes(k as u8 + 1, "e", dt, Access::Rw, bytes));
    }
    let mut od = test_od();
    od.insert(o);
    od
}

/// The complete image, built from per-sub values by the packing rule:
/// sub 0 as 16 bits, BOOLEANs one bit each, the rest byte-aligned.
fn image(sub0: Option<u8>, entries: &[(DataType, Vec<u8>)]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut bit = 0;
    if let Some(n) = sub0 {
        out.extend_from_slice(&[n, 0]);
        bit = 16;
    }
    for (dt, v) in entries {
        if *dt == DataType::Boolean {
            if bit % 8 == 0 {
                out.push(0);
            }
            *out.last_mut().unwrap() |= (v[0] & 1) << (bit % 8);
            bit += 1;
        } else {
            out.extend_from_slice(v);
            bit = out.len() * 8;
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn complete_access_read_back_equals_per_sub_reads(
        types in prop::collection::vec(0usize..TYPES.len(), 1..60),
        seed in prop::collection::vec(any::<u64>(), 60),
        size in mailbox(),
    ) {
        let mut r = rig(size, size, record(&types, &seed));
        let n = types.len() as u8;
        let per_sub: Vec<(DataType, Vec<u8>)> = (1..=n)
            .map(|s| (TYPES[types[usize::from(s) - 1]], soem::sdo_read(&mut r, 0x2500, s, false).unwrap()))
            .collect();
        prop_assert_eq!(soem::sdo_read(&mut r, 0x2500, 0, true).unwrap(), image(Some(n), &per_sub));
        prop_assert_eq!(soem::sdo_read(&mut r, 0x2500, 1, true).unwrap(), image(None, &per_sub));
    }

    #[test]
    fn complete_access_write_then_per_sub_reads(
        types in prop::collection::vec(0usize..TYPES.len(), 1..60),
        old in prop::collection::vec(any::<u64>(), 60),
        new in prop::collection::vec(any::<u64>(), 60),
        size in mailbox(),
        from_sub1: bool,
    ) {
        let mut r = rig(size, size, record(&types, &old));
        let n = types.len() as u8;
        let wanted: Vec<(DataType, Vec<u8>)> = types
            .iter()
            .zip(&new)
            .map(|(&t, &v)| {
                let dt = TYPES[t];
                let v = if dt == DataType::Boolean { v & 1 } else { v };
                (dt, v.to_le_bytes()[..dt.fixed_size().unwrap()].to_vec())
            })
            .collect();
        let img = image(if from_sub1 { None } else { Some(n) }, &wanted);
        soem::sdo_write(&mut r, 0x2500, u8::from(from_sub1), true, &img).unwrap();
        for s in 1..=n {
            prop_assert_eq!(&soem::sdo_read(&mut r, 0x2500, s, false).unwrap(), &wanted[usize::from(s) - 1].1);
        }
    }

    #[test]
    fn pdo_assignment_arrays_of_any_length(count in 0u8..=64, size in mailbox()) {
        // An ARRAY with writable sub 0 (a PDO assignment of up to 64 PDOs).
        let mut o = Object::with_code(0x1C12, ObjectCode::Array, "assign")
            .with_sub(SubObject::new(0, "n", DataType::Unsigned8, Access::Rw, Value::U8(0)));
        for i in 1..=64u8 {
            o = o.with_sub(SubObject::new(i, "pdo", DataType::Unsigned16, Access::Rw, Value::U16(0)));
        }
        let mut od = ObjectDictionary::new();
        od.insert(o);
        let mut r = rig(size, size, od);
        let mut img = vec![count, 0];
        for i in 0..u16::from(count) {
            img.extend_from_slice(&(0x1600 + i).to_le_bytes());
        }
        soem::sdo_write(&mut r, 0x1C12, 0, true, &img).unwrap();
        prop_assert_eq!(soem::sdo_read(&mut r, 0x1C12, 0, true).unwrap(), img);
    }
}
