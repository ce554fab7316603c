//! The standard objects of CiA 301 (communication profile, 1000h–1FFFh)
//! and CiA 402 (drives and motion control, 6000h–67FFh) as data: index,
//! sub-indices, names, data types, access and PDO mappability, so tools
//! can name, type and decode them without an EDS.
//!
//! ```
//! use drivebus_objects::{entry, find};
//! let e = entry(0x6041, 0).unwrap();
//! assert_eq!(e.name(), "Statusword");
//! assert_eq!(e.data_type, drivebus_od::DataType::Unsigned16);
//! assert_eq!(find("statusword"), Some((0x6041, Some(0))));
//! assert_eq!(entry(0x1A01, 3).unwrap().name(), "Application object 3");
//! ```
//!
//! Object ranges (PDO and SDO parameters) are one entry each; `{n}` in a
//! name is the PDO/SDO number (from the index) for objects and the
//! sub-index for sub-objects. Access is what the standards give; devices
//! may restrict it (e.g. a read-only mapping). Sources: CiA 301 v4.2 §7.5
//! tables, CiA 302-2/-3 for 1F50h–1F80h, CiA 402-2 v4 §6–§12.
#![cfg_attr(not(test), no_std)]

extern crate alloc;

#[macro_use]
mod macros;
mod table;
mod table402;
mod units;

pub use units::unit;

use alloc::borrow::Cow;
use alloc::string::String;

pub use drivebus_od::{Access, DataType};

/// Which standard defines an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Standard {
    /// CiA 301 communication profile (and CiA 302 objects 1F50h–1F80h).
    Cia301,
    /// CiA 402 drives and motion control.
    Cia402,
}

/// The object code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// One value (sub-index 0).
    Var,
    /// Sub-index 0 holds the count; the other entries share one type.
    Array,
    /// Sub-index 0 holds the highest sub-index; entries of their own types.
    Record,
}

/// One sub-index or a run of sub-indices with the same description.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SubDef {
    /// First sub-index.
    pub first: u8,
    /// Last sub-index (equal to `first` for one entry).
    pub last: u8,
    /// Name; `{n}` stands for the sub-index.
    pub name: &'static str,
    /// Data type.
    pub data_type: DataType,
    /// Access.
    pub access: Access,
    /// May be mapped into a PDO.
    pub pdo: bool,
}

/// One object or a run of objects with the same description.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Def {
    /// First index.
    pub first: u16,
    /// Last index (equal to `first` for one object).
    pub last: u16,
    /// Name; `{n}` stands for the number in the run, from 1.
    pub name: &'static str,
    /// Object code.
    pub kind: Kind,
    /// Defining standard.
    pub profile: Standard,
    /// Sub-objects, ascending.
    pub subs: &'static [SubDef],
}

/// An object of the dictionary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectInfo {
    /// Index.
    pub index: u16,
    /// The description it comes from.
    pub def: &'static Def,
}

/// One entry (index, sub-index) of the dictionary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EntryInfo {
    /// Index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// The object description.
    pub object: &'static Def,
    /// The sub-object description.
    pub def: &'static SubDef,
    /// Data type.
    pub data_type: DataType,
    /// Access.
    pub access: Access,
    /// May be mapped into a PDO.
    pub pdo: bool,
}

fn fill(pattern: &'static str, n: u32) -> Cow<'static, str> {
    if pattern.contains("{n}") {
        Cow::Owned(pattern.replace("{n}", &itoa(n)))
    } else {
        Cow::Borrowed(pattern)
    }
}

fn itoa(n: u32) -> String {
    use core::fmt::Write;
    let mut s = String::new();
    let _ = write!(s, "{n}");
    s
}

impl ObjectInfo {
    /// The object's name.
    pub fn name(&self) -> Cow<'static, str> {
        fill(self.def.name, u32::from(self.index - self.def.first) + 1)
    }

    /// The entry at `sub`.
    pub fn entry(&self, sub: u8) -> Option<EntryInfo> {
        let def = self.def.subs.iter().find(|s| (s.first..=s.last).contains(&sub))?;
        Some(EntryInfo {
            index: self.index,
            sub,
            object: self.def,
            def,
            data_type: def.data_type,
            access: def.access,
            pdo: def.pdo,
        })
    }

    /// Every entry the standard allows, in sub-index order (ranges expanded).
    pub fn entries(&self) -> impl Iterator<Item = EntryInfo> + '_ {
        self.def.subs.iter().flat_map(move |d| (d.first..=d.last).filter_map(move |s| self.entry(s)))
    }
}

impl EntryInfo {
    /// The entry's name (the object's name for a VAR).
    pub fn name(&self) -> Cow<'static, str> {
        if self.object.kind == Kind::Var {
            fill(self.object.name, u32::from(self.index - self.object.first) + 1)
        } else {
            fill(self.def.name, u32::from(self.sub))
        }
    }

    /// `Object name` for a VAR, `Object name / sub name` otherwise.
    pub fn full_name(&self) -> String {
        let obj = fill(self.object.name, u32::from(self.index - self.object.first) + 1);
        if self.object.kind == Kind::Var {
            obj.into_owned()
        } else {
            let mut s = obj.into_owned();
            s.push_str(" / ");
            s.push_str(&self.name());
            s
        }
    }
}

/// Every description, ascending by index.
pub fn defs() -> impl Iterator<Item = &'static Def> {
    table::CIA301.iter().chain(table402::CIA402)
}

/// The standard object at `index`.
pub fn object(index: u16) -> Option<ObjectInfo> {
    let defs = if index < 0x6000 { table::CIA301 } else { table402::CIA402 };
    let i = defs.partition_point(|d| d.last < index);
    let def = defs.get(i)?;
    (def.first <= index).then_some(ObjectInfo { index, def })
}

/// The standard entry at `index`/`sub`.
pub fn entry(index: u16, sub: u8) -> Option<EntryInfo> {
    object(index)?.entry(sub)
}

/// Lower case, letters and digits only: how names are compared.
/// The words of a name, lower case (`Identity object` → identity, object).
fn words(s: &str) -> alloc::vec::Vec<String> {
    s.split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(|w| w.to_ascii_lowercase())
        .collect()
}

fn norm(s: &str) -> String {
    s.chars().filter(char::is_ascii_alphanumeric).map(|c| c.to_ascii_lowercase()).collect()
}

/// Finds an object or entry by name, ignoring case, spaces, `_` and `-`:
/// `statusword`, `Position actual value`, `profile_velocity` give a VAR's
/// `(index, Some(0))`; a record or array name (`identity object`) gives
/// `(index, None)`; `OBJECT/ENTRY` (`identity/vendor_id`) or a unique
/// entry name (`vendor-id`) gives the entry. Numbered runs take their
/// number where the name has it: `tpdo1 mapping parameter`.
/// `None` when nothing or several match.
pub fn find(name: &str) -> Option<(u16, Option<u8>)> {
    let (obj_part, sub_part) = match name.split_once('/') {
        Some((o, s)) => (o, Some(s)),
        None => (name, None),
    };
    let want = norm(obj_part);
    if want.is_empty() {
        return None;
    }
    let mut hits: alloc::vec::Vec<(u16, Option<u8>)> = alloc::vec::Vec::new();
    // The object's full name first, then its first words (`identity`,
    // `identity/vendor-id`: "Identity object"), when only one object starts so.
    let want_words = words(obj_part);
    for prefix in [false, true] {
        if prefix && !hits.is_empty() {
            break;
        }
        for def in defs() {
            let base = norm(def.name);
            for index in def.first..=def.last {
                let n = u32::from(index - def.first) + 1;
                let full = if def.name.contains("{n}") { norm(&fill(def.name, n)) } else { base.clone() };
                let starts = || {
                    let named =
                        if def.name.contains("{n}") { fill(def.name, n) } else { Cow::Borrowed(def.name) };
                    words(&named).starts_with(&want_words)
                };
                if (!prefix && full == want) || (prefix && starts()) {
                    let o = ObjectInfo { index, def };
                    match sub_part {
                        None => hits.push((index, (def.kind == Kind::Var).then_some(0))),
                        Some(s) => {
                            let ws = norm(s);
                            if let Some(e) = o.entries().find(|e| norm(&e.name()) == ws) {
                                hits.push((index, Some(e.sub)));
                            }
                        }
                    }
                }
                if def.first == def.last {
                    break;
                }
            }
        }
    }
    if hits.is_empty() && sub_part.is_none() {
        // A unique entry name inside a record (vendor-id, serial number).
        for def in defs().filter(|d| d.first == d.last && d.kind != Kind::Var) {
            let o = ObjectInfo { index: def.first, def };
            for e in o.entries() {
                if norm(&e.name()) == want && e.sub != 0 {
                    hits.push((def.first, Some(e.sub)));
                }
            }
        }
    }
    hits.dedup();
    if hits.len() == 1 { Some(hits[0]) } else { None }
}

#[cfg(test)]
mod tests;
