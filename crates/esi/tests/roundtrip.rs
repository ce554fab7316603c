//! Property tests: any dictionary → ESI → read back gives the same
//! description, the checks find nothing, the file is valid and parses
//! with roxmltree; and no input makes the reader or validator panic.

use drivebus_esi::{CheckOptions, DeviceFacts, SlaveDescription, check_dictionary, read, validate, write};
use drivebus_od::{ALL_DATA_TYPES, Access, DataType, Object, ObjectCode, ObjectDictionary, SubObject};
use proptest::prelude::*;

const ACCESS: [Access; 6] = [Access::Ro, Access::Wo, Access::Rw, Access::Rwr, Access::Rww, Access::Const];

/// Names with XML specials, non-ASCII, tabs, newlines and control characters.
fn name() -> impl Strategy<Value = String> {
    "[ -~\\t\\n\u{1}\u{e9}\u{4e2d}<>&\"']{0,12}"
}

fn value_bytes(dt: DataType) -> BoxedStrategy<Vec<u8>> {
    match dt.fixed_size() {
        Some(1) if dt == DataType::Boolean => {
            prop_oneof![4 => 0u8..=1, 1 => any::<u8>()].prop_map(|b| vec![b]).boxed()
        }
        Some(n) => proptest::collection::vec(any::<u8>(), n).boxed(),
        None if dt == DataType::VisibleString => prop_oneof![
            "[ -~]{0,10}".prop_map(String::into_bytes),
            proptest::collection::vec(any::<u8>(), 0..10),
        ]
        .boxed(),
        None => proptest::collection::vec(any::<u8>(), 0..10).boxed(),
    }
}

#[derive(Clone, Debug)]
struct SubSpec {
    name: String,
    dt: DataType,
    access: Access,
    mappable: bool,
    default: Vec<u8>,
    limits: Option<(Vec<u8>, Vec<u8>)>,
    max_len: Option<usize>,
}

fn sub_spec(dt: Option<DataType>) -> impl Strategy<Value = SubSpec> {
    let dt = match dt {
        Some(t) => Just(t).boxed(),
        None => proptest::sample::select(ALL_DATA_TYPES.to_vec()).boxed(),
    };
    dt.prop_flat_map(|dt| {
        let limits = match dt.fixed_size() {
            Some(n) => proptest::option::of((
                proptest::collection::vec(any::<u8>(), n),
                proptest::collection::vec(any::<u8>(), n),
            ))
            .boxed(),
            None => Just(None).boxed(),
        };
        (
            name(),
            proptest::sample::select(ACCESS.to_vec()),
            any::<bool>(),
            value_bytes(dt),
            limits,
            proptest::option::of(0usize..16),
        )
            .prop_map(move |(name, access, mappable, default, limits, max_len)| SubSpec {
                name,
                dt,
                access,
                mappable,
                default,
                limits,
                max_len: if dt.is_variable() { max_len } else { None },
            })
    })
}

fn make_sub(sub: u8, s: &SubSpec) -> SubObject {
    let mut o = SubObject::from_bytes(sub, s.name.clone(), s.dt, s.access, s.default.clone());
    o.pdo_mappable = s.mappable;
    if let Some((lo, hi)) = &s.limits {
        o.low_limit = Some(lo.clone());
        o.high_limit = Some(hi.clone());
    }
    o.max_len = s.max_len;
    o
}

#[derive(Clone, Debug)]
enum ObjSpec {
    Var(SubSpec, bool),
    Array(u8, Vec<SubSpec>),
    Record(Vec<(u8, SubSpec)>),
}

fn obj_spec() -> impl Strategy<Value = ObjSpec> {
    prop_oneof![
        (sub_spec(None), any::<bool>()).prop_map(|(s, domain)| ObjSpec::Var(s, domain)),
        proptest::sample::select(
            ALL_DATA_TYPES.iter().copied().filter(|t| !t.is_variable()).collect::<Vec<_>>()
        )
        .prop_flat_map(|dt| (any::<u8>(), proptest::collection::vec(sub_spec(Some(dt)), 1..6)))
        .prop_map(|(s0, elems)| ObjSpec::Array(s0, elems)),
        proptest::collection::btree_map(0u8..30, sub_spec(None), 0..6)
            .prop_map(|m| ObjSpec::Record(m.into_iter().collect())),
    ]
}

fn build(index: u16, name: &str, spec: &ObjSpec) -> Object {
    match spec {
        ObjSpec::Var(s, domain) => {
            let code = if *domain { ObjectCode::Domain } else { ObjectCode::Var };
            Object::with_code(index, code, name.to_string()).with_sub(make_sub(0, s))
        }
        ObjSpec::Array(n, elems) => {
            let s0 = SubObject::from_bytes(0, "count", DataType::Unsigned8, Access::Ro, vec![*n]);
            let mut o = Object::with_code(index, ObjectCode::Array, name.to_string()).with_sub(s0);
            for (i, e) in elems.iter().enumerate() {
                o = o.with_sub(make_sub(i as u8 + 1, e));
            }
            o
        }
        ObjSpec::Record(subs) => {
            let mut o = Object::record(index, name.to_string());
            for (k, s) in subs {
                o = o.with_sub(make_sub(*k, s));
            }
            o
        }
    }
}

/// A dictionary of random objects, sometimes with a mapping object that
/// maps some of their fixed-size entries and a 1C12h assigning it.
fn dictionary() -> impl Strategy<Value = ObjectDictionary> {
    (
        proptest::collection::btree_map(0x2000u16..0x6000, (name(), obj_spec()), 1..10),
        any::<bool>(),
        any::<u8>(),
    )
        .prop_map(|(objects, pdo, pick)| {
            let mut od = ObjectDictionary::new();
            for (index, (name, spec)) in &objects {
                od.insert(build(*index, name, spec));
            }
            if pdo {
                let targets: Vec<u32> = od
                    .objects()
                    .iter()
                    .flat_map(|o| o.subs().iter().map(move |s| (o.index, s)))
                    .filter_map(|(i, s)| Some((u32::from(i) << 16) | (u32::from(s.sub) << 8) | s.bit_len()?))
                    .skip(usize::from(pick % 3))
                    .take(3)
                    .collect();
                let mut m = Object::record(0x1600, "RxPDO1 mapping");
                m.subs_mut()[0].access = Access::Rw;
                m = m.with_sub(SubObject::from_bytes(
                    0,
                    "n",
                    DataType::Unsigned8,
                    Access::Rw,
                    vec![targets.len() as u8],
                ));
                for (k, t) in targets.iter().enumerate() {
                    m = m.with_sub(SubObject::from_bytes(
                        k as u8 + 1,
                        "e",
                        DataType::Unsigned32,
                        Access::Rw,
                        t.to_le_bytes().to_vec(),
                    ));
                }
                od.insert(m);
                let a = Object::array(
                    0x1C12,
                    "assign",
                    DataType::Unsigned16,
                    Access::Rw,
                    1,
                    drivebus_od::Value::U16(0x1600),
                );
                od.insert(a);
            }
            od
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn any_dictionary_round_trips(od in dictionary()) {
        let desc = SlaveDescription::new(&od, &DeviceFacts::new(0x1A3, "v <&>", 7, 0x4130_3047, "p \"x\""));
        let xml = write(&desc);
        let errors: Vec<_> = validate(&xml).into_iter().filter(|p| p.is_error()).collect();
        prop_assert!(errors.is_empty(), "{:?}", errors);
        prop_assert!(roxmltree::Document::parse(&xml).is_ok());
        let mut back = read(&xml).map_err(|e| TestCaseError::fail(e.to_string()))?;
        back.serial = desc.serial;
        prop_assert_eq!(&back, &desc);
        let f = check_dictionary(&back, &od, &CheckOptions::default());
        prop_assert!(f.is_empty(), "{:?}", f.iter().map(ToString::to_string).collect::<Vec<_>>());
    }

    #[test]
    fn reading_anything_never_panics(s in "(<[A-Za-z]{1,8}( [A-Za-z]{1,4}=\"[^\"<]{0,6}\")?>|</[A-Za-z]{1,8}>|[ -~]{0,8}|&[a-z#x0-9]{0,5};){0,40}") {
        let _ = read(&s);
        let _ = validate(&s);
    }

    #[test]
    fn damaged_files_never_panic(cut in 0usize..4000, at in 0usize..4000, with in "[ -~]{0,4}") {
        let mut od = ObjectDictionary::new();
        od.insert(Object::array(0x1C12, "assign", DataType::Unsigned16, Access::Rw, 2, drivebus_od::Value::U16(0x1600)));
        od.insert(Object::var(0x6040, "Controlword", DataType::Unsigned16, Access::Rww, drivebus_od::Value::U16(0)));
        let xml = write(&SlaveDescription::new(&od, &DeviceFacts::new(1, "v", 2, 3, "p")));
        let bytes = xml.as_bytes();
        let cut = cut.min(bytes.len());
        let at = at.min(cut);
        let mut damaged = String::from_utf8_lossy(&bytes[..at]).into_owned();
        damaged.push_str(&with);
        damaged.push_str(&String::from_utf8_lossy(&bytes[at..cut]));
        let _ = read(&damaged);
        let _ = validate(&damaged);
    }
}
