//! [`Eds`] ⇄ [`ObjectDictionary`].

use crate::model::{DeviceInfo, Diagnostic, Eds, EdsError, EdsObject, EdsVar};
use crate::value::{eval, format, is_node_relative};
use drivebus_od::{DataType, Object, ObjectCode, ObjectDictionary, SubObject};
use std::borrow::Cow;

fn var_to_sub(
    v: &EdsVar,
    name: Cow<'static, str>,
    sub: u8,
    index: u16,
    node_id: u8,
    use_parameter_value: bool,
) -> Result<SubObject, Diagnostic> {
    let err = |m: String| Diagnostic { line: v.line, message: format!("object {index:04X} sub {sub}: {m}") };
    let dt = DataType::from_index(v.data_type)
        .ok_or_else(|| err(format!("DataType {:#06x} is not a basic type", v.data_type)))?;
    let text = |t: &Option<String>| -> Result<Option<Vec<u8>>, Diagnostic> {
        match t.as_deref().map(str::trim) {
            None | Some("") if dt.num_kind().is_some() => Ok(None),
            None => Ok(None),
            Some(s) => eval(s, dt, node_id).map(Some).map_err(err),
        }
    };
    let default = text(&v.default)?.unwrap_or_else(|| match dt.fixed_size() {
        Some(n) => vec![0; n],
        None => Vec::new(),
    });
    let mut s = SubObject::from_bytes(sub, name.clone(), dt, v.access, default.clone());
    s.pdo_mappable = v.pdo_mapping;
    s.low_limit = text(&v.low_limit)?;
    s.high_limit = text(&v.high_limit)?;
    s.node_id_relative = v.default.as_deref().is_some_and(is_node_relative);
    if use_parameter_value && let Some(pv) = text(&v.parameter_value)? {
        // A DCF's ParameterValue is the configured value; the default stays.
        let mut with_value = SubObject::from_bytes(sub, name, dt, v.access, pv);
        with_value.default = default;
        with_value.pdo_mappable = s.pdo_mappable;
        with_value.low_limit = s.low_limit.take();
        with_value.high_limit = s.high_limit.take();
        with_value.node_id_relative = s.node_id_relative;
        s = with_value;
    }
    Ok(s)
}

/// Build a dictionary for node `node_id`: `$NODEID` expressions evaluated,
/// DCF `ParameterValue`s applied as current values. Type definitions
/// (DEFTYPE/DEFSTRUCT, e.g. the dummy-mapping entries 0002h..0007h) are
/// kept: CiA 301 lets a device expose them.
pub fn to_od(eds: &Eds, node_id: u8) -> Result<ObjectDictionary, EdsError> {
    convert(eds, node_id, |n| Cow::Owned(n.to_owned()))
}

/// [`to_od`] of a file that lives as long as the program (one read once
/// and kept): the dictionary borrows its names instead of copying them,
/// so it and its clones allocate no name. Same dictionary otherwise.
pub fn to_od_static(eds: &'static Eds, node_id: u8) -> Result<ObjectDictionary, EdsError> {
    convert(eds, node_id, Cow::Borrowed)
}

fn convert<'e>(
    eds: &'e Eds,
    node_id: u8,
    name: impl Fn(&'e str) -> Cow<'static, str>,
) -> Result<ObjectDictionary, EdsError> {
    let mut od = ObjectDictionary::new();
    let mut errors = Vec::new();
    for o in eds.objects.values() {
        if o.object_type == ObjectCode::Null {
            continue;
        }
        let mut obj = Object::with_code(o.index, o.object_type, name(&o.name));
        obj.flags = o.obj_flags;
        let subs: Vec<(u8, &EdsVar)> = match &o.var {
            Some(v) if o.compact_sub_obj.is_none() => vec![(0, v)],
            _ => o.subs.iter().map(|(k, v)| (*k, v)).collect(),
        };
        for (sub, v) in subs {
            match var_to_sub(v, name(&v.name), sub, o.index, node_id, true) {
                Ok(s) => obj = obj.with_sub(s),
                Err(d) => errors.push(d),
            }
        }
        od.insert(obj);
    }
    if errors.is_empty() { Ok(od) } else { Err(EdsError { errors }) }
}

fn sub_to_var(s: &SubObject, node_id: u8, with_value: bool) -> EdsVar {
    let dt = s.data_type;
    let mut v = EdsVar::new(s.name.to_string(), dt as u16, s.access);
    v.default = Some(if s.node_id_relative && dt.num_kind().is_some() {
        let base = drivebus_od::le_u64(&s.default).wrapping_sub(node_id as u64);
        // The node-ID itself (100Bh) as a shipped EDS writes it.
        if base == 0 { "$NODEID".into() } else { format!("$NODEID+0x{base:X}") }
    } else {
        format(dt, &s.default)
    });
    if with_value && s.bytes() != s.default.as_slice() {
        v.parameter_value = Some(format(dt, s.bytes()));
    }
    v.low_limit = s.low_limit.as_deref().map(|b| format(dt, b));
    v.high_limit = s.high_limit.as_deref().map(|b| format(dt, b));
    v.pdo_mapping = s.pdo_mappable;
    v
}

/// Describe a running dictionary as an EDS (`as_dcf`: also the current
/// values as `ParameterValue` where they differ from the defaults).
pub fn from_od(od: &ObjectDictionary, device_info: DeviceInfo, node_id: u8, as_dcf: bool) -> Eds {
    let mut eds = Eds { device_info, ..Eds::default() };
    eds.file_info = vec![
        ("FileName".into(), "drivebus.eds".into()),
        ("FileVersion".into(), "1".into()),
        ("FileRevision".into(), "0".into()),
        ("EDSVersion".into(), "4.0".into()),
        ("Description".into(), "Generated by drivebus from a running object dictionary".into()),
        ("CreatedBy".into(), "drivebus".into()),
    ];
    for o in od.objects() {
        let mut e = EdsObject {
            index: o.index,
            name: o.name.to_string(),
            object_type: o.code,
            sub_number: None,
            compact_sub_obj: None,
            obj_flags: o.flags,
            var: None,
            subs: Default::default(),
            compact_names: Default::default(),
            compact_values: Default::default(),
            line: 0,
        };
        match o.code {
            ObjectCode::Var | ObjectCode::Domain | ObjectCode::DefType
                if o.subs().len() == 1 && o.subs()[0].sub == 0 =>
            {
                e.var = Some(sub_to_var(&o.subs()[0], node_id, as_dcf));
            }
            _ => {
                for s in o.subs() {
                    e.subs.insert(s.sub, sub_to_var(s, node_id, as_dcf));
                }
                e.sub_number = Some(e.subs.len() as u8);
            }
        }
        match o.index {
            // CiA 306 §4.5: data type definitions are in no object list.
            0x0000..=0x0FFF => {}
            0x1000 | 0x1001 | 0x1018 => eds.mandatory.push(o.index),
            0x2000..=0x5FFF => eds.manufacturer.push(o.index),
            _ => eds.optional.push(o.index),
        }
        eds.objects.insert(o.index, e);
    }
    if as_dcf {
        eds.commissioning = Some(crate::model::Commissioning { node_id, ..Default::default() });
    }
    eds
}
