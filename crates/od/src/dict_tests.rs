//! Tests of the dictionary and its write path.

use super::*;
use crate::owner::NoHooks;

fn od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    od.insert(Object::var(0x1000, "Device type", DataType::Unsigned32, Access::Ro, Value::U32(0x0002_0192)));
    od.insert(
        Object::var(0x2000, "Setpoint", DataType::Integer16, Access::Rw, Value::I16(0)).with_sub(
            SubObject::new(0, "Setpoint", DataType::Integer16, Access::Rw, Value::I16(0))
                .limits(Value::I16(-100), Value::I16(100))
                .mappable(),
        ),
    );
    od.insert(Object::var(0x2001, "Secret", DataType::Unsigned8, Access::Wo, Value::U8(0)));
    od.insert(
        Object::record(0x1018, "Identity")
            .with_sub(SubObject::new(1, "Vendor-ID", DataType::Unsigned32, Access::Ro, Value::U32(0x9A)))
            .with_sub(SubObject::new(4, "Serial", DataType::Unsigned32, Access::Ro, Value::U32(7))),
    );
    od
}

#[test]
fn branch_free_search_matches_binary_search() {
    for n in 0..40u16 {
        let keys: Vec<u16> = (0..n).map(|i| i * 3 + 1).collect();
        for k in 0..(n * 3 + 4) {
            assert_eq!(search(&keys, k), keys.binary_search(&k), "n={n} k={k}");
        }
    }
    assert!(same_bytes(&[1, 2, 3], &[1, 2, 3]) && !same_bytes(&[1, 2, 3], &[1, 2, 4]));
    assert!(!same_bytes(&[1], &[1, 0]) && same_bytes(&[7; 12], &[7; 12]));
}

#[test]
fn lookup_aborts() {
    let od = od();
    assert_eq!(od.find(0x1001, 0), Err(SdoAbort::NO_OBJECT));
    assert_eq!(od.find(0x1018, 2), Err(SdoAbort::NO_SUB_INDEX));
    let r = od.find(0x1018, 4).unwrap();
    assert_eq!(od.index_of(r), (0x1018, 4));
    assert_eq!(od.get_u32(0x1018, 0), Some(4), "sub 0 tracks the highest sub-index");
}

#[test]
fn write_checks_in_order() {
    let mut od = od();
    let h = &mut NoHooks;
    assert_eq!(od.write(h, 0x1000, 0, &[0; 4]), Err(SdoAbort::WRITE_READ_ONLY));
    assert_eq!(od.read(h, 0x2001, 0).map(<[u8]>::to_vec), Err(SdoAbort::READ_WRITE_ONLY));
    assert_eq!(od.write(h, 0x2000, 0, &[0; 4]), Err(SdoAbort::DATA_TOO_LONG));
    assert_eq!(od.write(h, 0x2000, 0, &[0]), Err(SdoAbort::DATA_TOO_SHORT));
    assert_eq!(od.write(h, 0x2000, 0, &101i16.to_le_bytes()), Err(SdoAbort::VALUE_TOO_HIGH));
    assert_eq!(od.write(h, 0x2000, 0, &(-101i16).to_le_bytes()), Err(SdoAbort::VALUE_TOO_LOW));
    let g = od.generation();
    od.write(h, 0x2000, 0, &(-100i16).to_le_bytes()).unwrap();
    assert!(od.generation() != g);
    assert_eq!(od.get_i64(0x2000, 0), Some(-100));
}

/// Records every call so the tests can check the order and the count.
#[derive(Default)]
struct Log {
    calls: Vec<&'static str>,
}

impl ObjectHooks for Log {
    fn on_read(&mut self, od: &mut ObjectDictionary, at: &Target) -> Result<(), SdoAbort> {
        self.calls.push("read");
        od.set_raw(at.r, &42i16.to_le_bytes());
        Ok(())
    }
    fn check_write(
        &mut self,
        od: &mut ObjectDictionary,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        self.calls.push(if at.watched { "veto+check" } else { "check" });
        // Nothing is stored before the check.
        assert_ne!(od.bytes(at.r), data);
        match i16::from_le_bytes([data[0], data[1]]) {
            13 => Err(SdoAbort::DEVICE_STATE),
            7 => {
                od.set_raw(at.r, &70i16.to_le_bytes());
                Ok(WriteOutcome::Handled)
            }
            _ => Ok(WriteOutcome::Store),
        }
    }
    fn apply_write(&mut self, od: &mut ObjectDictionary, at: &Target) {
        self.calls.push("apply");
        // Applied after the store.
        assert_eq!(od.target(at.r), *at);
    }
}

#[test]
fn owner_refreshes_checks_and_applies_once() {
    let mut od = od();
    let r = od.find(0x2000, 0).unwrap();
    {
        let e = od.get_mut(0x2000, 0).unwrap();
        e.owner = Owner::app(3);
        e.live = true;
    }
    let mut h = Log::default();
    assert_eq!(od.read(&mut h, 0x2000, 0).unwrap(), 42i16.to_le_bytes());
    assert_eq!(od.write(&mut h, 0x2000, 0, &13i16.to_le_bytes()), Err(SdoAbort::DEVICE_STATE));
    od.write(&mut h, 0x2000, 0, &12i16.to_le_bytes()).unwrap();
    assert_eq!(od.get_i64(0x2000, 0), Some(12));
    // Handled: the owner stored 70 itself, nothing applied.
    od.write(&mut h, 0x2000, 0, &7i16.to_le_bytes()).unwrap();
    assert_eq!(od.get_i64(0x2000, 0), Some(70));
    assert_eq!(h.calls, ["read", "check", "check", "apply", "check"]);
    // Limits come before the owner: it never sees an out-of-range value.
    assert_eq!(od.write(&mut h, 0x2000, 0, &500i16.to_le_bytes()), Err(SdoAbort::VALUE_TOO_HIGH));
    assert_eq!(h.calls.len(), 5);
    assert_eq!(od.target(r).owner, Owner::app(3));
}

#[test]
fn plain_entries_skip_the_hooks_and_watched_ones_do_not() {
    let mut od = od();
    let mut h = Log::default();
    od.write(&mut h, 0x2000, 0, &5i16.to_le_bytes()).unwrap();
    assert!(h.calls.is_empty(), "no owner, not watched: stored without a call");
    od.get_mut(0x2000, 0).unwrap().watched = true;
    assert_eq!(od.write(&mut h, 0x2000, 0, &13i16.to_le_bytes()), Err(SdoAbort::DEVICE_STATE));
    od.write(&mut h, 0x2000, 0, &6i16.to_le_bytes()).unwrap();
    assert_eq!(h.calls, ["veto+check", "veto+check", "apply"]);
}

#[test]
fn generation_counts_changes_of_marked_entries_only() {
    let mut od = od();
    let r = od.find(0x2000, 0).unwrap();
    let g = od.generation();
    od.set_le(r, &1i16.to_le_bytes());
    od.set_le(r, &1i16.to_le_bytes());
    assert_eq!(od.generation(), g + 1, "marked by default; an unchanged value is no change");
    od.set_marked(r, false);
    od.set_le(r, &2i16.to_le_bytes());
    od.set_raw(r, &3i16.to_le_bytes());
    assert_eq!(od.generation(), g + 1, "unmarked: not counted");
    od.mark_all(true);
    od.set_raw(r, &4i16.to_le_bytes());
    assert_eq!(od.generation(), g + 2);
}

#[test]
fn restore_defaults_by_group() {
    let mut od = od();
    od.write(&mut NoHooks, 0x2000, 0, &5i16.to_le_bytes()).unwrap();
    assert_eq!(od.get(0x2000, 0).unwrap().persist, PersistGroup::Manufacturer);
    od.restore_defaults(|_, s| s.persist == PersistGroup::Communication);
    assert_eq!(od.get_i64(0x2000, 0), Some(5));
    od.restore_defaults(|_, s| s.persist == PersistGroup::Manufacturer);
    assert_eq!(od.get_i64(0x2000, 0), Some(0));
}

#[test]
fn clone_from_is_clone() {
    let mut a = ObjectDictionary::new();
    a.insert(Object::var(
        0x1008,
        "Name",
        DataType::VisibleString,
        Access::Const,
        Value::Str("a long device name".into()),
    ));
    a.insert(Object::array(0x2000, "Array", DataType::Unsigned16, Access::Rw, 3, Value::U16(7)));
    let mut b = ObjectDictionary::new();
    b.insert(Object::var(0x1008, "Other", DataType::Unsigned8, Access::Rw, Value::U8(1)));
    b.insert(Object::array(
        0x2000,
        alloc::format!("Owned {}", 1),
        DataType::Unsigned16,
        Access::Rw,
        5,
        Value::U16(9),
    ));
    b.insert(Object::var(0x3000, "Extra", DataType::Unsigned32, Access::Rw, Value::U32(3)));
    let mut c = b.clone();
    c.clone_from(&a);
    assert!(c == a);
    let mut d = a.clone();
    d.clone_from(&b);
    assert!(d == b);
    assert_eq!(d.get(0x2000, 5).map(|s| s.bytes().to_vec()), Some(alloc::vec![9, 0]));
}

#[test]
fn set_low_stores_what_set_raw_stores() {
    let types = [
        (DataType::Unsigned8, Value::U8(0)),
        (DataType::Integer16, Value::I16(0)),
        (DataType::Integer24, Value::Bytes(vec![0; 3])),
        (DataType::Unsigned32, Value::U32(0)),
        (DataType::Integer64, Value::I64(0)),
    ];
    for (t, v) in types {
        for w in [0u64, 1, 0x80, 0xFFFF_FFFF, 0x1234_5678_9ABC_DEF0, u64::MAX] {
            let (mut a, mut b) = (ObjectDictionary::new(), ObjectDictionary::new());
            for od in [&mut a, &mut b] {
                od.insert(Object::var(0x2000, "Live", t, Access::Ro, v.clone()));
                let r = od.find(0x2000, 0).unwrap();
                od.set_marked(r, true);
            }
            let r = a.find(0x2000, 0).unwrap();
            let n = a.bytes(r).len();
            a.set_raw(r, &w.to_le_bytes()[..n]);
            assert!(b.set_low(r, w, 8), "{t:?}");
            assert_eq!(a.bytes(r), b.bytes(r), "{t:?} {w:#X}");
            assert_eq!(a.generation(), b.generation(), "{t:?} {w:#X}: a change counts once");
            assert_eq!(b.set_low(r, w, 4), n <= 4, "{t:?}: longer than max, nothing stored");
        }
    }
}
