//! The ESI view of a dictionary: what ETG.2000 `Dictionary/Objects` can
//! say about each object, and nothing it cannot. Built from an
//! [`ObjectDictionary`] and read back from a file, so the two compare.

use crate::types::{bit_size, type_name, xml_safe};
use drivebus_coe::access_bits;
use drivebus_od::{DataType, Object, ObjectCode, SubObject};

/// How an object is laid out in `Dictionary/DataTypes`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ObjectKind {
    /// One value, typed by a base or sized type (`UDINT`, `STRING(4)`).
    Var,
    /// Sub 0 and elements 1..=n of one type and one access: a `DTxxxx`
    /// type whose `Elements` sub-item has the array type `DTxxxxARR`.
    Array,
    /// Sub-items with their own `SubIdx`, type and flags (`DT1018`). An
    /// ARRAY whose elements differ in type or access, or have gaps, is
    /// written this way too: `ArrayInfo` has one set of flags for all.
    Record,
}

/// One sub-object as the ESI describes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EsiSub {
    /// Sub-index.
    pub sub: u8,
    /// Name (characters XML cannot carry replaced by U+FFFD).
    pub name: String,
    /// CoE data type.
    pub data_type: DataType,
    /// Size in bytes (the string length for `STRING(n)`).
    pub len: usize,
    /// ETG.1000.6 object access word ([`access_bits`]): readable and
    /// writable per ESM state, RxPDO/TxPDO mappable, backup, settings —
    /// the word SDO Information reports for the same entry.
    pub access: u16,
    /// Default value, little-endian.
    pub default: Vec<u8>,
    /// Lowest allowed value, little-endian.
    pub min: Option<Vec<u8>>,
    /// Highest allowed value, little-endian.
    pub max: Option<Vec<u8>>,
}

impl EsiSub {
    /// Bits the value takes (`BitSize`).
    pub fn bits(&self) -> u32 {
        bit_size(self.data_type, self.len)
    }
    /// The ESI type name of the value (`UDINT`, `STRING(4)`).
    pub fn type_name(&self) -> String {
        type_name(self.data_type, self.len)
    }
}

/// One object of `Dictionary/Objects`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EsiObject {
    /// Index.
    pub index: u16,
    /// Name.
    pub name: String,
    /// Layout.
    pub kind: ObjectKind,
    /// Sub-objects in sub-index order (a VAR has only sub 0).
    pub subs: Vec<EsiSub>,
}

impl EsiObject {
    /// The object as the ESI describes it, with each sub's access word
    /// from `access` (normally [`drivebus_coe::default_object_access`]
    /// with the device's state rules applied).
    pub fn from_od(obj: &Object, access: impl Fn(u16, &SubObject) -> u16) -> EsiObject {
        let subs: Vec<EsiSub> = obj
            .subs()
            .iter()
            .map(|s| EsiSub {
                sub: s.sub,
                name: xml_safe(&s.name).into_owned(),
                data_type: s.data_type,
                len: value_len(s),
                access: access(obj.index, s),
                default: s.default.clone(),
                min: s.low_limit.clone(),
                max: s.high_limit.clone(),
            })
            .collect();
        let simple = matches!(obj.code, ObjectCode::Var | ObjectCode::Domain | ObjectCode::DefType);
        let kind = if simple && subs.len() == 1 && subs[0].sub == 0 {
            ObjectKind::Var
        } else if obj.code == ObjectCode::Array && is_uniform_array(&subs) {
            ObjectKind::Array
        } else {
            ObjectKind::Record
        };
        let name = xml_safe(&obj.name).into_owned();
        let mut subs = subs;
        if kind == ObjectKind::Var {
            // ETG.2000 names a VAR once: its value takes the object's name.
            subs[0].name = name.clone();
        }
        EsiObject { index: obj.index, name, kind, subs }
    }

    /// The ESI type name of the object: the value's type for a VAR,
    /// `DTxxxx` otherwise.
    pub fn type_name(&self) -> String {
        match self.kind {
            ObjectKind::Var => self.subs.first().map_or_else(|| "DOMAIN".into(), EsiSub::type_name),
            _ => format!("DT{:04X}", self.index),
        }
    }

    /// `DTxxxxARR`, the element array type of an [`ObjectKind::Array`].
    pub fn array_type_name(&self) -> String {
        format!("DT{:04X}ARR", self.index)
    }

    /// One sub-object.
    pub fn get(&self, sub: u8) -> Option<&EsiSub> {
        self.subs.iter().find(|s| s.sub == sub)
    }

    /// Bit offset of every sub-object (`BitOffs`) and the total bit size of
    /// the object (`BitSize`), laid out as a complete access image
    /// (ETG.1000.6; `drivebus-coe` `complete.rs`): sub 0 takes 16 bits,
    /// BOOLEANs pack, everything else starts on a byte.
    pub fn layout(&self) -> (Vec<u32>, u32) {
        if self.kind == ObjectKind::Var {
            return (vec![0], self.subs.first().map_or(0, EsiSub::bits));
        }
        let mut offs = Vec::with_capacity(self.subs.len());
        let mut at = 0u32;
        for s in &self.subs {
            if s.sub == 0 {
                offs.push(at);
                at = at.saturating_add(s.bits().max(16).checked_next_multiple_of(8).unwrap_or(u32::MAX));
                continue;
            }
            if s.data_type != DataType::Boolean {
                at = at.checked_next_multiple_of(8).unwrap_or(at);
            }
            offs.push(at);
            at = at.saturating_add(s.bits());
        }
        (offs, at.checked_next_multiple_of(8).unwrap_or(at))
    }
}

/// Bytes a value takes: fixed types their size, strings and domains the
/// longer of the default and the declared maximum.
pub fn value_len(s: &SubObject) -> usize {
    s.data_type.fixed_size().unwrap_or_else(|| s.max_len.unwrap_or(0).max(s.default.len()))
}

/// Sub 0 is an UNSIGNED8 and subs 1..=n follow without gaps, all of one
/// fixed-size type and one access word.
fn is_uniform_array(subs: &[EsiSub]) -> bool {
    let Some((s0, elems)) = subs.split_first() else { return false };
    let Some(first) = elems.first() else { return false };
    s0.sub == 0
        && s0.data_type == DataType::Unsigned8
        && s0.len == 1
        && first.data_type.fixed_size().is_some()
        && elems.iter().enumerate().all(|(i, e)| {
            usize::from(e.sub) == i + 1 && e.data_type == first.data_type && e.access == first.access
        })
}

/// ETG.2000 `Access` text and the `ReadRestrictions`/`WriteRestrictions`
/// of an access word: `("rw", None, Some("PreOP"))`. An entry neither
/// readable nor writable cannot be said; it is written `ro`.
pub fn access_flags(word: u16) -> (&'static str, Option<&'static str>, Option<&'static str>) {
    let read = word & access_bits::READ;
    let write = (word & access_bits::WRITE) >> 3;
    let restr = |bits: u16| if bits == 7 { None } else { states_name(bits) };
    match (read, write) {
        (_, 0) => ("ro", restr(read), None),
        (0, _) => ("wo", None, restr(write)),
        _ => ("rw", restr(read), restr(write)),
    }
}

/// The state-set names ETG.2000 uses in `ReadRestrictions` and
/// `WriteRestrictions` (bit 0 PRE-OP, bit 1 SAFE-OP, bit 2 OP).
pub fn states_name(bits: u16) -> Option<&'static str> {
    Some(match bits {
        1 => "PreOP",
        2 => "SafeOP",
        3 => "PreOP_SafeOP",
        4 => "OP",
        5 => "PreOP_OP",
        6 => "SafeOP_OP",
        _ => return None,
    })
}

/// Inverse of [`states_name`] (case-insensitive); `None` for unknown text.
pub fn parse_states(text: &str) -> Option<u16> {
    (1..=6).find(|b| states_name(*b).is_some_and(|n| n.eq_ignore_ascii_case(text.trim())))
}

/// `PdoMapping` text of an access word: `R`, `T`, `RT` or none.
pub fn pdo_mapping_flag(word: u16) -> Option<&'static str> {
    match (word & access_bits::RXPDO != 0, word & access_bits::TXPDO != 0) {
        (true, true) => Some("RT"),
        (true, false) => Some("R"),
        (false, true) => Some("T"),
        (false, false) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use access_bits::*;
    use drivebus_coe::default_object_access;
    use drivebus_od::{Access, Value};

    #[test]
    fn access_words_to_flags_and_back() {
        assert_eq!(access_flags(READ), ("ro", None, None));
        assert_eq!(access_flags(READ | WRITE), ("rw", None, None));
        assert_eq!(access_flags(READ | WRITE_PREOP), ("rw", None, Some("PreOP")));
        assert_eq!(access_flags(WRITE), ("wo", None, None));
        assert_eq!(access_flags(READ_PREOP | READ_SAFEOP), ("ro", Some("PreOP_SafeOP"), None));
        assert_eq!(access_flags(0), ("ro", None, None));
        for b in 1..=6 {
            assert_eq!(parse_states(states_name(b).unwrap()), Some(b));
        }
        assert_eq!(parse_states("preop_op"), Some(5));
        assert_eq!(parse_states("Init"), None);
        assert_eq!(pdo_mapping_flag(READ | TXPDO), Some("T"));
        assert_eq!(pdo_mapping_flag(RXPDO | TXPDO), Some("RT"));
    }

    #[test]
    fn kinds_and_layout() {
        let acc = |_: u16, s: &SubObject| default_object_access(s);
        let id = Object::record(0x1018, "Identity")
            .with_sub(SubObject::new(1, "Vendor ID", DataType::Unsigned32, Access::Ro, Value::U32(0x1A3)))
            .with_sub(SubObject::new(2, "Product", DataType::Unsigned32, Access::Ro, Value::U32(1)));
        let e = EsiObject::from_od(&id, acc);
        assert_eq!((e.kind, e.type_name()), (ObjectKind::Record, "DT1018".to_string()));
        assert_eq!(e.layout(), (vec![0, 16, 48], 80));

        let assign =
            Object::array(0x1C12, "RxPDO assign", DataType::Unsigned16, Access::Rw, 4, Value::U16(0));
        let e = EsiObject::from_od(&assign, acc);
        assert_eq!(e.kind, ObjectKind::Array);
        assert_eq!(e.layout(), (vec![0, 16, 32, 48, 64], 80));

        let bools = Object::record(0x2000, "Bits")
            .with_sub(SubObject::new(1, "a", DataType::Boolean, Access::Rw, Value::Bool(true)))
            .with_sub(SubObject::new(2, "b", DataType::Boolean, Access::Rw, Value::Bool(false)))
            .with_sub(SubObject::new(3, "c", DataType::Unsigned8, Access::Rw, Value::U8(0)));
        assert_eq!(EsiObject::from_od(&bools, acc).layout(), (vec![0, 16, 17, 24], 32));

        // An ARRAY with a read-only element is written as a record.
        let mut mixed = Object::array(0x2001, "Mixed", DataType::Unsigned8, Access::Rw, 2, Value::U8(0));
        mixed.subs_mut()[2].access = Access::Ro;
        assert_eq!(EsiObject::from_od(&mixed, acc).kind, ObjectKind::Record);

        let s = Object::var(
            0x1008,
            "Name\u{1}",
            DataType::VisibleString,
            Access::Const,
            Value::Str("iPOS".into()),
        );
        let e = EsiObject::from_od(&s, acc);
        assert_eq!(
            (e.kind, e.type_name(), e.name.as_str()),
            (ObjectKind::Var, "STRING(4)".to_string(), "Name\u{FFFD}")
        );
        assert_eq!(e.layout(), (vec![0], 32));
    }
}
