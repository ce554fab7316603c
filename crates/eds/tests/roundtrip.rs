//! Property tests: read → write → read is the identity; no input panics.

use drivebus_eds::{from_od, parse, to_od, write};
use drivebus_od::{Access, DataType, Object, ObjectDictionary, SubObject, Value};
use proptest::prelude::*;

fn value_for(dt: DataType) -> BoxedStrategy<Value> {
    use DataType::*;
    match dt {
        Boolean => any::<bool>().prop_map(Value::Bool).boxed(),
        Integer8 => any::<i8>().prop_map(Value::I8).boxed(),
        Integer16 => any::<i16>().prop_map(Value::I16).boxed(),
        Integer32 => any::<i32>().prop_map(Value::I32).boxed(),
        Integer24 => (-(1i64 << 23)..(1i64 << 23)).prop_map(Value::I64).boxed(),
        Integer64 => any::<i64>().prop_map(Value::I64).boxed(),
        Unsigned8 => any::<u8>().prop_map(Value::U8).boxed(),
        Unsigned16 => any::<u16>().prop_map(Value::U16).boxed(),
        Unsigned32 => any::<u32>().prop_map(Value::U32).boxed(),
        Unsigned48 => (0u64..(1 << 48)).prop_map(Value::U64).boxed(),
        Unsigned64 => any::<u64>().prop_map(Value::U64).boxed(),
        Real32 => (-1e6f32..1e6).prop_map(Value::F32).boxed(),
        Real64 => (-1e12f64..1e12).prop_map(Value::F64).boxed(),
        VisibleString => "[A-Za-z0-9_.]([A-Za-z0-9 _.;=]{0,20}[A-Za-z0-9_.])?".prop_map(Value::Str).boxed(),
        _ => proptest::collection::vec(any::<u8>(), 0..12).prop_map(Value::Bytes).boxed(),
    }
}

const TYPES: [DataType; 16] = {
    use DataType::*;
    [
        Boolean,
        Integer8,
        Integer16,
        Integer24,
        Integer32,
        Integer64,
        Unsigned8,
        Unsigned16,
        Unsigned32,
        Unsigned48,
        Unsigned64,
        Real32,
        Real64,
        VisibleString,
        OctetString,
        Domain,
    ]
};

const ACCESS: [Access; 6] = [Access::Ro, Access::Wo, Access::Rw, Access::Rwr, Access::Rww, Access::Const];

fn sub_strategy(sub: u8) -> impl Strategy<Value = SubObject> {
    (0..TYPES.len(), 0..ACCESS.len(), any::<bool>(), "[A-Za-z][A-Za-z0-9 _-]{0,15}[a-z]").prop_flat_map(
        move |(t, a, map, name)| {
            let dt = TYPES[t];
            value_for(dt).prop_map(move |v| {
                let s = SubObject::new(sub, name.clone(), dt, ACCESS[a], v);
                if map && dt.fixed_size().is_some() { s.mappable() } else { s }
            })
        },
    )
}

fn od_strategy() -> impl Strategy<Value = ObjectDictionary> {
    let object = (0x2000u16..0x2100, any::<bool>(), 1u8..5).prop_flat_map(|(index, record, n)| {
        if record {
            proptest::collection::vec(any::<u8>(), n as usize)
                .prop_flat_map(move |_| {
                    let subs: Vec<_> = (1..=n).map(sub_strategy).collect();
                    subs.prop_map(move |subs| {
                        let mut o = Object::record(index, format!("Record {index:04X}"));
                        for s in subs {
                            o = o.with_sub(s);
                        }
                        o
                    })
                })
                .boxed()
        } else {
            sub_strategy(0)
                .prop_map(move |s| {
                    let name = s.name.clone();
                    Object::with_code(index, drivebus_od::ObjectCode::Var, name).with_sub(s)
                })
                .boxed()
        }
    });
    proptest::collection::vec(object, 1..8).prop_map(|objs| {
        let mut od = ObjectDictionary::new();
        for o in objs {
            od.insert(o);
        }
        od
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn dictionary_survives_write_and_read(od in od_strategy(), node in 1u8..=127) {
        let eds = from_od(&od, Default::default(), node, false);
        let text = write(&eds);
        let parsed = parse(&text).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        let back = to_od(&parsed.eds, node).map_err(|e| TestCaseError::fail(format!("{e}")))?;
        prop_assert_eq!(&od, &back);
        // And the file model itself is stable after one more round.
        let mut again = parse(&write(&parsed.eds)).unwrap().eds;
        let mut first = parsed.eds;
        again.strip_lines();
        first.strip_lines();
        prop_assert_eq!(first, again);
    }

    #[test]
    fn arbitrary_text_never_panics(text in "(\\PC|\n|\\[|\\]|=|\\$NODEID|0x){0,300}") {
        if let Ok(p) = parse(&text) {
            let _ = to_od(&p.eds, 1);
            let _ = drivebus_eds::check(&p.eds);
            let _ = write(&p.eds);
        }
    }
}
