//! `Profile/Dictionary`: `DataTypes` (base types, sized strings, and the
//! `DTxxxx`/`DTxxxxARR` types of arrays and records) and `Objects`
//! (`Info` with defaults and limits, `Flags` with access, state
//! restrictions, PDO mapping, backup and settings).

use crate::model::{EsiObject, EsiSub, ObjectKind, access_flags, pdo_mapping_flag};
use crate::types::{ValueForm, base_name, format_number, hex_bytes, hex_index, value_form, xml_safe};
use crate::xml::XmlWriter;
use drivebus_coe::access_bits;
use drivebus_od::DataType;
use std::collections::BTreeMap;

/// A `DataType` definition, keyed for a stable order: base types by CoE
/// type code, then sized types by name, then per-object types by index.
enum TypeDef {
    Base { bits: u32 },
    Octets { len: usize },
    Array { base: String, bits: u32, elements: usize },
    Struct { object: usize },
}

pub(crate) fn dictionary(w: &mut XmlWriter, objects: &[EsiObject]) {
    let mut types: BTreeMap<(u8, u32, String), TypeDef> = BTreeMap::new();
    let value_type = |types: &mut BTreeMap<_, _>, s: &EsiSub| {
        let name = s.type_name();
        if base_name(s.data_type).is_some() {
            types.insert((0, s.data_type as u32, name), TypeDef::Base { bits: s.bits() });
        } else if s.data_type == DataType::OctetString {
            types.insert((0, 0x100, "BYTE".into()), TypeDef::Base { bits: 8 });
            types.insert((1, 0, name), TypeDef::Octets { len: s.len });
        } else {
            types.insert((1, 0, name), TypeDef::Base { bits: s.bits() });
        }
    };
    for (i, o) in objects.iter().enumerate() {
        for s in &o.subs {
            value_type(&mut types, s);
        }
        match o.kind {
            ObjectKind::Var => {}
            ObjectKind::Array => {
                let e = &o.subs[1];
                let n = o.subs.len() - 1;
                let key = (2, u32::from(o.index) << 1, o.array_type_name());
                types.insert(
                    key,
                    TypeDef::Array { base: e.type_name(), bits: e.bits() * n as u32, elements: n },
                );
                types
                    .insert((2, (u32::from(o.index) << 1) | 1, o.type_name()), TypeDef::Struct { object: i });
            }
            ObjectKind::Record => {
                types
                    .insert((2, (u32::from(o.index) << 1) | 1, o.type_name()), TypeDef::Struct { object: i });
            }
        }
    }
    w.open("Dictionary", &[]);
    w.open("DataTypes", &[]);
    for ((_, _, name), def) in &types {
        w.open("DataType", &[]);
        w.text("Name", name);
        match def {
            TypeDef::Base { bits } => w.text("BitSize", &bits.to_string()),
            TypeDef::Octets { len } => {
                w.text("BaseType", "BYTE");
                w.text("BitSize", &(8 * len).to_string());
                array_info(w, 0, *len);
            }
            TypeDef::Array { base, bits, elements } => {
                w.text("BaseType", base);
                w.text("BitSize", &bits.to_string());
                array_info(w, 1, *elements);
            }
            TypeDef::Struct { object } => struct_type(w, &objects[*object]),
        }
        w.close("DataType");
    }
    w.close("DataTypes");
    w.open("Objects", &[]);
    for o in objects {
        object(w, o);
    }
    w.close("Objects");
    w.close("Dictionary");
}

fn array_info(w: &mut XmlWriter, lbound: u32, elements: usize) {
    w.open("ArrayInfo", &[]);
    w.text("LBound", &lbound.to_string());
    w.text("Elements", &elements.to_string());
    w.close("ArrayInfo");
}

/// The `SubItem`s of a `DTxxxx` type.
fn struct_type(w: &mut XmlWriter, o: &EsiObject) {
    let (offs, bits) = o.layout();
    w.text("BitSize", &bits.to_string());
    match o.kind {
        ObjectKind::Array => {
            let (s0, e) = (&o.subs[0], &o.subs[1]);
            sub_item(w, Some(0), &s0.name, &s0.type_name(), s0.bits(), offs[0], s0.access);
            let n = (o.subs.len() - 1) as u32;
            sub_item(w, None, "Elements", &o.array_type_name(), e.bits() * n, offs[1], e.access);
        }
        _ => {
            for (s, off) in o.subs.iter().zip(offs) {
                sub_item(w, Some(s.sub), &s.name, &s.type_name(), s.bits(), off, s.access);
            }
        }
    }
}

fn sub_item(w: &mut XmlWriter, sub: Option<u8>, name: &str, ty: &str, bits: u32, off: u32, access: u16) {
    w.open("SubItem", &[]);
    if let Some(s) = sub {
        w.text("SubIdx", &s.to_string());
    }
    w.text("Name", &xml_safe(name));
    w.text("Type", ty);
    w.text("BitSize", &bits.to_string());
    w.text("BitOffs", &off.to_string());
    flags(w, access, true);
    w.close("SubItem");
}

/// `Flags`: `Access` with its restrictions, then (for values) `PdoMapping`,
/// `Backup`, `Setting`.
fn flags(w: &mut XmlWriter, access: u16, value: bool) {
    w.open("Flags", &[]);
    let (text, read, write) = access_flags(access);
    let mut attrs = Vec::new();
    if let Some(r) = read {
        attrs.push(("ReadRestrictions", r));
    }
    if let Some(r) = write {
        attrs.push(("WriteRestrictions", r));
    }
    w.leaf("Access", &attrs, text);
    if value {
        if let Some(m) = pdo_mapping_flag(access) {
            w.text("PdoMapping", m);
        }
        if access & access_bits::BACKUP != 0 {
            w.text("Backup", "1");
        }
        if access & access_bits::SETTINGS != 0 {
            w.text("Setting", "1");
        }
    }
    w.close("Flags");
}

fn object(w: &mut XmlWriter, o: &EsiObject) {
    w.open("Object", &[]);
    w.text("Index", &hex_index(o.index));
    w.text("Name", &xml_safe(&o.name));
    w.text("Type", &o.type_name());
    w.text("BitSize", &o.layout().1.to_string());
    match o.kind {
        ObjectKind::Var => {
            if let Some(s) = o.subs.first() {
                if has_info(s) {
                    w.open("Info", &[]);
                    info_values(w, s);
                    w.close("Info");
                }
                flags(w, s.access, true);
            }
        }
        _ => {
            if !o.subs.is_empty() {
                w.open("Info", &[]);
                for s in &o.subs {
                    w.open("SubItem", &[]);
                    w.text("Name", &xml_safe(&s.name));
                    if has_info(s) {
                        w.open("Info", &[]);
                        info_values(w, s);
                        w.close("Info");
                    }
                    w.close("SubItem");
                }
                w.close("Info");
            }
            // The object's own flags: those of sub 0 without the value flags.
            flags(w, o.subs.first().map_or(access_bits::READ, |s| s.access & 0x3F), false);
        }
    }
    w.close("Object");
}

/// A sub has something for `Info`: a fixed-size default, a non-empty
/// variable-size default, or a limit.
fn has_info(s: &EsiSub) -> bool {
    s.data_type.fixed_size().is_some() || !s.default.is_empty() || s.min.is_some() || s.max.is_some()
}

/// The form every value of a sub is written in: numbers only if default
/// and limits all have the type's size, a string only for a printable
/// VISIBLE_STRING without limits, hex bytes otherwise (exact for anything).
pub(crate) fn sub_form(s: &EsiSub) -> ValueForm {
    let forms: Vec<ValueForm> = std::iter::once(&s.default)
        .chain(s.min.iter())
        .chain(s.max.iter())
        .map(|b| value_form(s.data_type, b))
        .collect();
    match forms[0] {
        ValueForm::String if forms.len() > 1 => ValueForm::Data,
        f if forms.iter().all(|x| *x == f) => f,
        _ => ValueForm::Data,
    }
}

/// `MinValue`/`MaxValue`/`DefaultValue`, `DefaultString`, or
/// `MinData`/`MaxData`/`DefaultData` (ETG.2000 `ObjectInfoType` orders
/// the limits before the default). Variable-size types with an empty
/// default write none.
fn info_values(w: &mut XmlWriter, s: &EsiSub) {
    let fixed = s.data_type.fixed_size().is_some();
    match sub_form(s) {
        ValueForm::Number => {
            let num = |b: &Vec<u8>| format_number(s.data_type, b);
            if let Some(b) = &s.min {
                w.text("MinValue", &num(b));
            }
            if let Some(b) = &s.max {
                w.text("MaxValue", &num(b));
            }
            w.text("DefaultValue", &num(&s.default));
        }
        ValueForm::String => {
            if fixed || !s.default.is_empty() {
                w.text("DefaultString", &String::from_utf8_lossy(&s.default));
            }
        }
        ValueForm::Data => {
            if let Some(b) = &s.min {
                w.text("MinData", &hex_bytes(b));
            }
            if let Some(b) = &s.max {
                w.text("MaxData", &hex_bytes(b));
            }
            if fixed || !s.default.is_empty() {
                w.text("DefaultData", &hex_bytes(&s.default));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sub(dt: DataType, default: &[u8]) -> EsiSub {
        EsiSub {
            sub: 0,
            name: "x".into(),
            data_type: dt,
            len: dt.fixed_size().unwrap_or(default.len()),
            access: access_bits::READ,
            default: default.to_vec(),
            min: None,
            max: None,
        }
    }

    #[test]
    fn value_forms_per_sub() {
        assert_eq!(sub_form(&sub(DataType::Unsigned8, &[1])), ValueForm::Number);
        assert_eq!(sub_form(&sub(DataType::VisibleString, b"iPOS")), ValueForm::String);
        let mut s = sub(DataType::VisibleString, b"iPOS");
        s.max = Some(b"zz".to_vec());
        assert_eq!(sub_form(&s), ValueForm::Data);
        let mut s = sub(DataType::Unsigned16, &[1, 0]);
        s.min = Some(vec![1]);
        assert_eq!(sub_form(&s), ValueForm::Data, "a short limit is kept exactly");
        assert_eq!(crate::types::octet_array_name(0), "ARRAY [0..0] OF BYTE");
    }
}
