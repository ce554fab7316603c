//! What a front end (the `drivebus` tool, the Python package) knows
//! about objects: an EDS first, then the CiA 301/402 standard objects
//! (`drivebus_objects`), and how a user writes an object: hex indices
//! (`6041`, `0x6041`, `6041h`, `6041:00`, `6041sub0`) or names
//! (`statusword`, `identity/vendor-id`). One parser, so every front end
//! takes the same spellings and says the same when one is wrong.

use std::fmt;

use drivebus_eds::{Eds, EdsVar};
use drivebus_od::DataType;

/// An object, sub-index or number written wrongly; the message says how
/// to write it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DictError(pub String);

impl fmt::Display for DictError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for DictError {}

macro_rules! bail {
    ($($t:tt)*) => { return Err(DictError(format!($($t)*))) };
}

/// The object dictionary description a front end uses.
#[derive(Default)]
pub struct Dict {
    /// The device's EDS/DCF, when given.
    pub eds: Option<Eds>,
}

/// Parses a hexadecimal number: `6041`, `0x6041`, `6041h`.
pub fn hex(s: &str) -> Option<u32> {
    let t = s.trim();
    let t = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")).unwrap_or(t);
    let t = t.strip_suffix('h').or_else(|| t.strip_suffix('H')).unwrap_or(t);
    if t.is_empty() || t.len() > 8 {
        return None;
    }
    u32::from_str_radix(t, 16).ok()
}

/// Parses a number as people write values: `0x..`/`..h` hex, else decimal.
pub fn number(s: &str) -> Result<u32, DictError> {
    let t = s.trim();
    let r = if t.starts_with("0x") || t.starts_with("0X") || t.ends_with('h') || t.ends_with('H') {
        hex(t)
    } else {
        t.parse::<u32>().ok()
    };
    r.ok_or_else(|| DictError(format!("`{s}` is not a number (decimal, or hex as 0x6A or 6Ah)")))
}

/// Parses a hex sub-index.
pub fn sub_index(s: &str) -> Result<u8, DictError> {
    let v = hex(s)
        .ok_or_else(|| DictError(format!("`{s}` is not a sub-index: write it in hex (0, 1A, 0x1A)")))?;
    u8::try_from(v).map_err(|_| DictError(format!("sub-index `{s}` is above FFh")))
}

fn norm(s: &str) -> String {
    s.chars().filter(char::is_ascii_alphanumeric).map(|c| c.to_ascii_lowercase()).collect()
}

/// The variable description of `index`/`sub` in an EDS.
pub fn eds_var(eds: &Eds, index: u16, sub: u8) -> Option<&EdsVar> {
    let o = eds.objects.get(&index)?;
    match &o.var {
        Some(v) if sub == 0 && o.subs.is_empty() => Some(v),
        _ => o.subs.get(&sub),
    }
}

impl Dict {
    /// The object's name and, for a sub-object, `Object / Entry`.
    pub fn name(&self, index: u16, sub: u8) -> Option<String> {
        if let Some(o) = self.eds.as_ref().and_then(|e| e.objects.get(&index)) {
            if o.subs.is_empty() {
                return Some(o.name.clone());
            }
            return Some(match o.subs.get(&sub) {
                Some(v) => format!("{} / {}", o.name, v.name),
                None => o.name.clone(),
            });
        }
        drivebus_objects::entry(index, sub).map(|e| e.full_name())
    }

    /// The data type of `index`/`sub`.
    pub fn data_type(&self, index: u16, sub: u8) -> Option<DataType> {
        if let Some(e) = &self.eds
            && let Some(v) = eds_var(e, index, sub)
        {
            return DataType::from_index(v.data_type);
        }
        drivebus_objects::entry(index, sub).map(|e| e.data_type)
    }

    /// The sub-indices of a RECORD/ARRAY (`None` for a VAR or an unknown object).
    pub fn entries(&self, index: u16) -> Option<Vec<u8>> {
        if let Some(o) = self.eds.as_ref().and_then(|e| e.objects.get(&index)) {
            return (!o.subs.is_empty()).then(|| o.subs.keys().copied().collect());
        }
        let o = drivebus_objects::object(index)?;
        (o.def.kind != drivebus_objects::Kind::Var).then(|| o.entries().map(|e| e.sub).collect())
    }

    /// A name as an object: `(index, Some(sub))` for a VAR or an entry,
    /// `(index, None)` for a record/array.
    fn find(&self, name: &str) -> Option<(u16, Option<u8>)> {
        if let Some(eds) = &self.eds {
            let (o, s) = match name.split_once('/') {
                Some((o, s)) => (norm(o), Some(norm(s))),
                None => (norm(name), None),
            };
            let hits: Vec<(u16, Option<u8>)> = eds
                .objects
                .iter()
                .filter(|(_, obj)| norm(&obj.name) == o)
                .filter_map(|(i, obj)| match &s {
                    None => Some((*i, obj.subs.is_empty().then_some(0))),
                    Some(s) => {
                        obj.subs.iter().find(|(_, v)| norm(&v.name) == *s).map(|(k, _)| (*i, Some(*k)))
                    }
                })
                .collect();
            if hits.len() == 1 {
                return Some(hits[0]);
            }
        }
        drivebus_objects::find(name)
    }

    /// Resolves an object as the user wrote it, with an optional separate
    /// sub-index argument. `Ok((index, None))`: no sub-index given (the
    /// caller picks 0 or the whole record).
    pub fn resolve(&self, object: &str, sub: Option<&str>) -> Result<(u16, Option<u8>), DictError> {
        let o = object.trim();
        let (idx_text, inline_sub) = if let Some((i, s)) = o.split_once(':') {
            (i, Some(s))
        } else if let Some(p) = o.to_ascii_lowercase().find("sub") {
            (&o[..p], Some(&o[p + 3..]))
        } else {
            (o, None)
        };
        let parsed = hex(idx_text)
            .and_then(|v| u16::try_from(v).ok())
            // A name like "add" also parses as hex: only up to 4 digits or
            // with 0x / h counts as an index.
            .filter(|_| {
                idx_text.len() <= 4
                    || idx_text.to_ascii_lowercase().starts_with("0x")
                    || idx_text.ends_with(['h', 'H'])
            });
        if let Some(index) = parsed {
            let sub = match (inline_sub, sub) {
                (Some(_), Some(s)) => bail!("`{object}` has a sub-index already; drop `{s}`"),
                (Some(s), None) | (None, Some(s)) => Some(sub_index(s)?),
                (None, None) => None,
            };
            return Ok((index, sub));
        }
        let Some((index, named_sub)) = self.find(o) else {
            bail!(
                "`{object}` is not an object: write the index in hex (6041, 0x6041, 6041h, 6041:00) or a CiA 301/402 name (statusword, identity/vendor-id)"
            )
        };
        match (named_sub, sub) {
            (Some(_), Some(s)) => bail!("`{object}` names one entry already; drop the sub-index `{s}`"),
            (Some(n), None) => Ok((index, Some(n))),
            (None, Some(s)) => Ok((index, Some(sub_index(s)?))),
            (None, None) => Ok((index, None)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_in_every_spelling() {
        let d = Dict::default();
        for s in ["6041", "0x6041", "6041h", "6041H", "0X6041"] {
            assert_eq!(d.resolve(s, None).unwrap(), (0x6041, None), "{s}");
        }
        assert_eq!(d.resolve("6041:00", None).unwrap(), (0x6041, Some(0)));
        assert_eq!(d.resolve("0x1018:4", None).unwrap(), (0x1018, Some(4)));
        assert_eq!(d.resolve("1018sub4", None).unwrap(), (0x1018, Some(4)));
        assert_eq!(d.resolve("0x1018sub0A", None).unwrap(), (0x1018, Some(10)));
        assert_eq!(d.resolve("1018", Some("0A")).unwrap(), (0x1018, Some(10)));
        assert_eq!(d.resolve("1600", Some("10")).unwrap(), (0x1600, Some(0x10)));
        assert_eq!(d.resolve("statusword", None).unwrap(), (0x6041, Some(0)));
        // The first words of a name, when only one object starts so (`sdo --help`).
        assert_eq!(d.resolve("identity", None).unwrap(), (0x1018, None));
        assert_eq!(d.resolve("identity object", None).unwrap(), (0x1018, None));
        assert_eq!(d.resolve("identity object/serial number", None).unwrap(), (0x1018, Some(4)));
        assert_eq!(d.resolve("identity object", Some("2")).unwrap(), (0x1018, Some(2)));
        assert!(d.resolve("statusword", Some("1")).unwrap_err().to_string().contains("drop the sub-index"));
        assert!(d.resolve("6041:00", Some("1")).is_err());
        assert!(d.resolve("60x1", None).unwrap_err().to_string().contains("write the index in hex"));
        assert!(d.resolve("10000", None).is_err());
        assert!(d.resolve("1018:100", None).unwrap_err().to_string().contains("above FFh"));
    }

    #[test]
    fn names_and_types_without_an_eds() {
        let d = Dict::default();
        assert_eq!(d.name(0x6041, 0).as_deref(), Some("Statusword"));
        assert_eq!(d.data_type(0x1017, 0), Some(DataType::Unsigned16));
        assert_eq!(d.entries(0x1018), Some(vec![0, 1, 2, 3, 4]));
        assert_eq!(d.entries(0x6041), None);
        assert_eq!(number("0x6A").unwrap(), 0x6A);
        assert_eq!(number("6Ah").unwrap(), 0x6A);
        assert_eq!(number("106").unwrap(), 106);
        assert!(number("x").is_err());
    }

    proptest::proptest! {
        /// Whatever the user types as an object or sub-index: a result or an error.
        #[test]
        fn any_object_text_resolves_or_errs(obj in "[0-9A-Fa-fxXhH:sub ]{0,14}|\\PC{0,30}", sub in proptest::option::of("\\PC{0,6}")) {
            let _ = Dict::default().resolve(&obj, sub.as_deref());
            let _ = number(&obj);
            let _ = sub_index(&obj);
        }
    }
}
