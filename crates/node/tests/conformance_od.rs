//! Conformance-style cases, category OD (CiA 301 §7.4): data types,
//! access types and value limits as seen through SDO.

mod common;
use common::*;
use drivebus_node::Node;
use drivebus_od::{ALL_DATA_TYPES, Access, DataType, Object, SubObject, Value};

fn rig() -> Rig {
    let mut node = Node::new(device());
    // One object per data type at 3000h + type index, default 0 / empty.
    for dt in ALL_DATA_TYPES {
        let default = match dt.fixed_size() {
            Some(_) => Value::U8(0),
            None => Value::Bytes(vec![]),
        };
        let idx = 0x3000 + dt as u16;
        let s = SubObject::new(0, dt.name(), dt, Access::Rw, default);
        node.insert_object(Object::with_code(idx, drivebus_od::ObjectCode::Var, dt.name()).with_sub(s));
    }
    node.insert_object(
        Object::var(0x2000, "Limited", DataType::Integer16, Access::Rw, Value::I16(0)).with_sub(
            SubObject::new(0, "Limited", DataType::Integer16, Access::Rw, Value::I16(0))
                .limits(Value::I16(-10), Value::I16(10)),
        ),
    );
    node.insert_object(Object::var(0x2001, "Write only", DataType::Unsigned8, Access::Wo, Value::U8(0)));
    node.insert_object(Object::var(0x2002, "Constant", DataType::Unsigned8, Access::Const, Value::U8(7)));
    Rig::with_node(node)
}

#[test]
fn od_01_every_fixed_size_type_round_trips_through_expedited_sdo() {
    let mut r = rig();
    for dt in ALL_DATA_TYPES {
        let Some(n) = dt.fixed_size() else { continue };
        if n > 4 {
            continue; // longer types go segmented: od_02
        }
        let idx = 0x3000 + dt as u16;
        let data: Vec<u8> = (1..=n as u8).map(|b| if dt == DataType::Boolean { 1 } else { b }).collect();
        Rig::assert_written(r.sdo_write(5, idx, 0, &data), 5, idx, 0);
        let resp = r.sdo_read(5, idx, 0);
        let cmd = 0x43 | ((4 - n as u8) << 2);
        assert_eq!(resp.data()[0], cmd, "{dt:?}");
        assert_eq!(&resp.data()[4..4 + n], &data[..], "{dt:?}");
    }
}

#[test]
fn od_02_long_types_go_segmented() {
    let mut r = rig();
    // UNSIGNED48 (0x19): 6 bytes, initiate with size then one last segment.
    r.exchange("605#2119300006000000", &["585#6019300000000000"]);
    r.exchange("605#0301020304050600", &["585#2000000000000000"]);
    r.exchange("605#4019300000000000", &["585#4119300006000000"]);
    r.exchange("605#6000000000000000", &["585#0301020304050600"]);
}

#[test]
fn od_03_limits_and_access() {
    let mut r = rig();
    Rig::assert_abort(r.sdo_write(5, 0x2000, 0, &11i16.to_le_bytes()), 5, 0x2000, 0, 0x0609_0031);
    Rig::assert_abort(r.sdo_write(5, 0x2000, 0, &(-11i16).to_le_bytes()), 5, 0x2000, 0, 0x0609_0032);
    Rig::assert_written(r.sdo_write(5, 0x2000, 0, &(-10i16).to_le_bytes()), 5, 0x2000, 0);
    Rig::assert_abort(r.sdo_read(5, 0x2001, 0), 5, 0x2001, 0, 0x0601_0001);
    Rig::assert_written(r.sdo_write(5, 0x2001, 0, &[1]), 5, 0x2001, 0);
    Rig::assert_abort(r.sdo_write(5, 0x2002, 0, &[1]), 5, 0x2002, 0, 0x0601_0002);
    assert_eq!(r.sdo_read(5, 0x2002, 0), fr("585#4F02200007000000"));
    // BOOLEAN takes 0 or 1 only.
    Rig::assert_abort(r.sdo_write(5, 0x3001, 0, &[2]), 5, 0x3001, 0, 0x0609_0030);
    // Sub-index 1 of a VAR does not exist.
    Rig::assert_abort(r.sdo_read(5, 0x2000, 1), 5, 0x2000, 1, 0x0609_0011);
}

#[test]
fn od_04_strings_take_any_length_up_to_their_limit() {
    let mut r = rig();
    // VISIBLE_STRING (0x09) "ab" expedited with size, then read back.
    r.exchange("605#2B09300061620000", &["585#6009300000000000"]);
    r.exchange("605#4009300000000000", &["585#4B09300061620000"]);
}
