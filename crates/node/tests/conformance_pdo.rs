//! Conformance-style cases, category PDO (CiA 301 §7.2.2, §7.5.2.35–38).

mod common;
use common::*;
use drivebus_can::Duration;
use drivebus_node::Node;
use drivebus_od::{Access, DataType, Object, SubObject, Value};

/// The conformance device plus three application objects to map.
fn rig() -> Rig {
    let mut node = Node::new(device());
    node.insert_object(
        Object::var(0x2000, "Setpoint", DataType::Unsigned16, Access::Rww, Value::U16(0)).with_sub(
            SubObject::new(0, "Setpoint", DataType::Unsigned16, Access::Rww, Value::U16(0)).mappable(),
        ),
    );
    node.insert_object(
        Object::var(0x2001, "Actual", DataType::Unsigned32, Access::Rwr, Value::U32(0)).with_sub(
            SubObject::new(0, "Actual", DataType::Unsigned32, Access::Rwr, Value::U32(0x1122_3344))
                .mappable(),
        ),
    );
    node.insert_object(Object::var(0x2002, "Not mappable", DataType::Unsigned8, Access::Rw, Value::U8(0)));
    Rig::with_node(node)
}

fn w(r: &mut Rig, index: u16, sub: u8, data: &[u8]) {
    Rig::assert_written(r.sdo_write(5, index, sub, data), 5, index, sub);
}

/// The CiA 301 mapping procedure for one PDO: invalidate, clear, map, count, validate.
fn map(r: &mut Rig, comm: u16, mapping: u16, cob: u32, entries: &[u32], ttype: u8) {
    w(r, comm, 1, &(cob | 0x8000_0000).to_le_bytes());
    w(r, mapping, 0, &[0]);
    for (i, e) in entries.iter().enumerate() {
        w(r, mapping, i as u8 + 1, &e.to_le_bytes());
    }
    w(r, mapping, 0, &[entries.len() as u8]);
    w(r, comm, 2, &[ttype]);
    w(r, comm, 1, &cob.to_le_bytes());
}

#[test]
fn pdo_01_sync_tpdo_samples_at_sync() {
    let mut r = rig();
    map(&mut r, 0x1800, 0x1A00, 0x185, &[0x2001_0020], 1);
    // Not operational yet: a SYNC produces nothing.
    r.exchange("080#", &[]);
    r.send("000#0105");
    r.exchange("080#", &["185#44332211"]);
    r.node_mut().od_mut().set_value(0x2001, 0, &Value::U32(7)).unwrap();
    r.exchange("080#", &["185#07000000"]);
}

#[test]
fn pdo_02_every_third_sync() {
    let mut r = rig();
    map(&mut r, 0x1800, 0x1A00, 0x185, &[0x2001_0020], 3);
    r.send("000#0105");
    let got: Vec<usize> = (0..9)
        .map(|_| {
            r.send("080#");
            r.take().len()
        })
        .collect();
    assert_eq!(got, vec![0, 0, 1, 0, 0, 1, 0, 0, 1]);
}

#[test]
fn pdo_03_async_rpdo_and_length_error() {
    let mut r = rig();
    map(&mut r, 0x1400, 0x1600, 0x205, &[0x2000_0010], 255);
    r.send("000#0105");
    r.exchange("205#3412", &[]);
    assert_eq!(r.node().od().get_u64(0x2000, 0), Some(0x1234));
    // Too short: not processed, EMCY 8210h (CiA 301 §7.2.2.2).
    r.exchange("205#56", &["085#1082110000000000"]);
    assert_eq!(r.node().od().get_u64(0x2000, 0), Some(0x1234));
}

#[test]
fn pdo_04_sync_rpdo_takes_effect_at_next_sync() {
    let mut r = rig();
    map(&mut r, 0x1400, 0x1600, 0x205, &[0x2000_0010], 1);
    r.send("000#0105");
    r.exchange("205#CDAB", &[]);
    assert_eq!(r.node().od().get_u64(0x2000, 0), Some(0));
    r.exchange("080#", &[]);
    assert_eq!(r.node().od().get_u64(0x2000, 0), Some(0xABCD));
}

#[test]
fn pdo_05_mapping_procedure_aborts() {
    let mut r = rig();
    // Changing the mapping while the PDO is valid is refused; writing the
    // value sub 0 holds changes nothing and is taken.
    let held = r.node().od().get_u64(0x1A00, 0).unwrap() as u8;
    let resp = r.sdo_write(5, 0x1A00, 0, &[held + 1]);
    assert_eq!(resp.data()[0], 0x80, "mapping a valid PDO must abort: {resp}");
    assert_eq!(r.sdo_write(5, 0x1A00, 0, &[held]).data()[0], 0x60);
    w(&mut r, 0x1800, 1, &0x8000_0185u32.to_le_bytes());
    w(&mut r, 0x1A00, 0, &[0]);
    // Object absent, object not mappable, too long.
    Rig::assert_abort(r.sdo_write(5, 0x1A00, 1, &0x3000_0008u32.to_le_bytes()), 5, 0x1A00, 1, 0x0602_0000);
    Rig::assert_abort(r.sdo_write(5, 0x1A00, 1, &0x2002_0008u32.to_le_bytes()), 5, 0x1A00, 1, 0x0604_0041);
    w(&mut r, 0x1A00, 1, &0x2001_0020u32.to_le_bytes());
    w(&mut r, 0x1A00, 2, &0x2001_0020u32.to_le_bytes());
    w(&mut r, 0x1A00, 3, &0x2001_0020u32.to_le_bytes());
    Rig::assert_abort(r.sdo_write(5, 0x1A00, 0, &[3]), 5, 0x1A00, 0, 0x0604_0042);
    w(&mut r, 0x1A00, 0, &[2]);
    // Transmission types 241..251 are reserved.
    Rig::assert_abort(r.sdo_write(5, 0x1800, 2, &[241]), 5, 0x1800, 2, 0x0609_0030);
}

#[test]
fn pdo_06_event_tpdo_on_change_with_inhibit() {
    let mut r = rig();
    map(&mut r, 0x1800, 0x1A00, 0x185, &[0x2001_0020], 254);
    // Inhibit 50 × 100 µs = 5 ms (written while invalid).
    w(&mut r, 0x1800, 1, &0x8000_0185u32.to_le_bytes());
    w(&mut r, 0x1800, 3, &50u16.to_le_bytes());
    w(&mut r, 0x1800, 1, &0x185u32.to_le_bytes());
    r.send("000#0105");
    // Entering operational sends the current value once.
    assert_eq!(r.take(), frs(&["185#44332211"]));
    r.run_for(Duration::from_millis(10));
    let t0 = r.now();
    for v in [1u32, 2, 3] {
        r.node_mut().od_mut().set_value(0x2001, 0, &Value::U32(v)).unwrap();
        let dut = r.dut;
        r.bus.wake(dut);
        r.run_for(Duration::from_millis(1));
    }
    r.run_for(Duration::from_millis(10));
    let got: Vec<(u64, String)> =
        r.take_timed_ms(t0).into_iter().map(|(t, f)| (t.round() as u64, f.to_string())).collect();
    // The first change goes at once; the later ones wait for the inhibit
    // time and only the latest value is sent.
    assert_eq!(got.len(), 2, "{got:?}");
    assert_eq!(got[0].1, "185#01000000");
    assert_eq!(got[1].1, "185#03000000");
    assert!(got[1].0 - got[0].0 >= 5, "{got:?}");
}

#[test]
fn pdo_07_no_pdo_outside_operational() {
    let mut r = rig();
    map(&mut r, 0x1400, 0x1600, 0x205, &[0x2000_0010], 255);
    r.exchange("205#3412", &[]);
    assert_eq!(r.node().od().get_u64(0x2000, 0), Some(0));
    r.send("000#0105");
    r.send("000#0205");
    r.exchange("205#3412", &[]);
    assert_eq!(r.node().od().get_u64(0x2000, 0), Some(0));
}
