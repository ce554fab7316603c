//! Agreement checks: an ESI (as [`SlaveDescription`], normally read back
//! from the written file) against the dictionary it came from and against
//! the EDS of the same profile, item by item. EtherCAT's own needs of a
//! dictionary are in [`check_ethercat`](crate::check_ethercat).

use crate::description::{SlaveDescription, SmKind, StateRule, apply_rules};
use crate::model::{EsiObject, EsiSub, ObjectKind, access_flags, pdo_mapping_flag};
use crate::pdo::{RX_MAPPING, TX_MAPPING, default_assignment, default_u64, entry, mapping_values};
use crate::revision::revision_firmware;
use crate::types::{format_number, hex_bytes};
use drivebus_coe::{access_bits, default_object_access};
use drivebus_eds::{Eds, EdsVar};
use drivebus_od::{DataType, Object, ObjectCode, ObjectDictionary, PersistGroup, SubObject};
use std::fmt;

/// What an ESI is compared with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Source {
    /// The object dictionary.
    Dictionary,
    /// The EDS file.
    Eds,
    /// What EtherCAT (ETG.1000.6, the masters, the manual) needs.
    EtherCat,
}

impl fmt::Display for Source {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Source::Dictionary => "dictionary",
            Source::Eds => "EDS",
            Source::EtherCat => "EtherCAT needs",
        })
    }
}

/// One disagreement.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Disagreement {
    /// What the ESI was compared with.
    pub source: Source,
    /// Object index, if it is about one.
    pub index: Option<u16>,
    /// Sub-index, if it is about one.
    pub sub: Option<u8>,
    /// Which property (`exists`, `data type`, `access`, `default`, …).
    pub field: String,
    /// What the ESI (or, for [`Source::EtherCat`], the dictionary) has.
    pub esi: String,
    /// What the dictionary or EDS has, or what EtherCAT needs.
    pub other: String,
    /// Why it matters, with the reference.
    pub note: String,
}

impl fmt::Display for Disagreement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.index, self.sub) {
            (Some(i), Some(s)) => write!(f, "{i:04X}h:{s:02X} ")?,
            (Some(i), None) => write!(f, "{i:04X}h ")?,
            _ => {}
        }
        let has = if self.source == Source::EtherCat { "dictionary" } else { "ESI" };
        write!(f, "{}: {has} {}; {} {}", self.field, self.esi, self.source, self.other)?;
        if !self.note.is_empty() {
            write!(f, " ({})", self.note)?;
        }
        Ok(())
    }
}

/// What to compare and what to require.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CheckOptions {
    /// Node-ID for `$NODEID` in EDS values (default 1).
    pub node_id: u8,
    /// Compare object and sub-object names (default true).
    pub names: bool,
    /// The device's state rules, so the expected access words match the
    /// ESI's (see [`crate::DeviceFacts::state_rules`]).
    pub state_rules: Vec<StateRule>,
    /// EtherCAT: entries every PDO mapping object must offer (subs 1..=n).
    pub mapping_entries: Option<u8>,
    /// EtherCAT: entries 1C12h/1C13h must offer; `None`: one per mapping
    /// object of the direction.
    pub assign_entries: Option<u8>,
    /// EtherCAT: the largest default PDO, in bits.
    pub max_pdo_bits: Option<u32>,
    /// EtherCAT: with PDO assignment/configuration announced, sub 0 of
    /// 1C12h/1C13h and of the mapping objects must be writable (ETG.1000.6:
    /// the master writes 0, the entries, then the count; iPOS §2.4).
    pub writable_counts: bool,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            node_id: 1,
            names: true,
            state_rules: Vec::new(),
            mapping_entries: None,
            assign_entries: None,
            max_pdo_bits: None,
            writable_counts: true,
        }
    }
}

pub(crate) struct Report {
    pub(crate) source: Source,
    pub(crate) out: Vec<Disagreement>,
}

impl Report {
    pub(crate) fn new(source: Source) -> Report {
        Report { source, out: Vec::new() }
    }
    pub(crate) fn add(
        &mut self,
        index: Option<u16>,
        sub: Option<u8>,
        field: &str,
        esi: impl Into<String>,
        other: impl Into<String>,
        note: &str,
    ) {
        self.out.push(Disagreement {
            source: self.source,
            index,
            sub,
            field: field.into(),
            esi: esi.into(),
            other: other.into(),
            note: note.into(),
        });
    }
    fn diff(&mut self, index: u16, sub: Option<u8>, field: &str, esi: String, other: String) {
        if esi != other {
            self.add(Some(index), sub, field, esi, other, "");
        }
    }
}

/// A 32-bit identity number, with its ASCII reading when it has one.
fn ident(v: u32) -> String {
    match revision_firmware(v) {
        Some(s) => format!("#x{v:08X} (\"{s}\")"),
        None => format!("#x{v:08X}"),
    }
}

/// Access text of a word: `rw`, `rw (write PreOP)`.
pub(crate) fn access_text(word: u16) -> String {
    let (a, r, w) = access_flags(word);
    let mut s = a.to_string();
    if let Some(r) = r {
        s += &format!(" (read {r})");
    }
    if let Some(w) = w {
        s += &format!(" (write {w})");
    }
    s
}

/// A value for a report: numbers as ESI writes them, strings quoted, bytes in hex.
fn value_text(dt: DataType, b: &[u8]) -> String {
    match dt.fixed_size() {
        Some(n)
            if n == b.len()
                && dt.num_kind().is_some()
                && !matches!(dt, DataType::Real32 | DataType::Real64) =>
        {
            format_number(dt, b)
        }
        _ if dt == DataType::VisibleString => format!("{:?}", String::from_utf8_lossy(b)),
        _ => format!("data {}", hex_bytes(b)),
    }
}

fn opt_value(dt: DataType, b: &Option<Vec<u8>>) -> String {
    b.as_deref().map_or_else(|| "none".to_string(), |b| value_text(dt, b))
}

/// Compare one described sub-object with the one it should describe.
fn compare_sub(r: &mut Report, index: u16, esi: &EsiSub, want: &EsiSub, names: bool) {
    let sub = Some(esi.sub);
    if names {
        r.diff(index, sub, "name", format!("{:?}", esi.name), format!("{:?}", want.name));
    }
    r.diff(index, sub, "data type", esi.data_type.name().into(), want.data_type.name().into());
    r.diff(index, sub, "bit size", esi.bits().to_string(), want.bits().to_string());
    let rw = access_bits::READ | access_bits::WRITE;
    r.diff(index, sub, "access", access_text(esi.access & rw), access_text(want.access & rw));
    let map = |w: u16| pdo_mapping_flag(w).unwrap_or("none").to_string();
    r.diff(index, sub, "PDO mapping", map(esi.access), map(want.access));
    let keep = |w: u16| match (w & access_bits::BACKUP != 0, w & access_bits::SETTINGS != 0) {
        (true, true) => "backup, settings",
        (true, false) => "backup",
        (false, true) => "settings",
        (false, false) => "none",
    };
    r.diff(index, sub, "backup/settings", keep(esi.access).into(), keep(want.access).into());
    let dt = want.data_type;
    r.diff(index, sub, "default", value_text(dt, &esi.default), value_text(dt, &want.default));
    r.diff(index, sub, "low limit", opt_value(dt, &esi.min), opt_value(dt, &want.min));
    r.diff(index, sub, "high limit", opt_value(dt, &esi.max), opt_value(dt, &want.max));
}

/// Compare a described object with the one it should describe.
fn compare_object(r: &mut Report, esi: &EsiObject, want: &EsiObject, names: bool) {
    let i = esi.index;
    if names {
        r.diff(i, None, "name", format!("{:?}", esi.name), format!("{:?}", want.name));
    }
    // An ARRAY ETG.2000 cannot express as one is a record; both are fine.
    let shape = |k: ObjectKind| if k == ObjectKind::Var { "single value" } else { "sub-indexed" };
    r.diff(i, None, "object code", shape(esi.kind).into(), shape(want.kind).into());
    for w in &want.subs {
        match esi.get(w.sub) {
            Some(e) => compare_sub(r, i, e, w, names && want.kind != ObjectKind::Var),
            None => r.add(Some(i), Some(w.sub), "exists", "absent", "present", ""),
        }
    }
    for e in esi.subs.iter().filter(|e| want.get(e.sub).is_none()) {
        r.add(Some(i), Some(e.sub), "exists", "present", "absent", "");
    }
}

fn compare_objects(r: &mut Report, d: &SlaveDescription, want: &[EsiObject], names: bool) {
    for w in want {
        match d.object(w.index) {
            Some(e) => compare_object(r, e, w, names),
            None => r.add(Some(w.index), None, "exists", "absent", "present", ""),
        }
    }
    for e in d.objects.iter().filter(|e| want.iter().all(|w| w.index != e.index)) {
        r.add(Some(e.index), None, "exists", "present", "absent", "");
    }
}

/// Identity and profile against 1018h and 1000h values.
fn compare_identity(r: &mut Report, d: &SlaveDescription, id: [Option<u32>; 3], device_type: Option<u32>) {
    let names = ["vendor ID", "product code", "revision number"];
    let esi = [d.vendor_id, d.product_code, d.revision];
    for k in 0..3 {
        match id[k] {
            Some(v) if v != esi[k] => {
                r.add(Some(0x1018), Some(k as u8 + 1), names[k], ident(esi[k]), ident(v), "")
            }
            _ => {}
        }
    }
    if let Some(t) = device_type {
        r.diff(0x1000, Some(0), "ProfileNo", d.profile.number.to_string(), (t & 0xFFFF).to_string());
        r.diff(0x1000, Some(0), "AddInfo", d.profile.add_info.to_string(), (t >> 16).to_string());
    }
}

/// Does `d` (an ESI, normally read back from the written file) describe
/// `od`? Identity (1018h against `Vendor/Id` and `Type`), profile (1000h),
/// every object and sub-object (existence, name, data type, bit size,
/// access with the state rules, PDO mappability, backup/settings, default,
/// limits), every PDO mapping object (the `RxPdo`/`TxPdo` entries against
/// the default mapping, `@Sm` against 1C12h/1C13h) and the process data
/// SM sizes of the default assignment.
pub fn check_dictionary(
    d: &SlaveDescription,
    od: &ObjectDictionary,
    opts: &CheckOptions,
) -> Vec<Disagreement> {
    let mut r = Report::new(Source::Dictionary);
    let id = [1, 2, 3].map(|s| default_u64(od, 0x1018, s).map(|v| v as u32));
    compare_identity(&mut r, d, id, default_u64(od, 0x1000, 0).map(|v| v as u32));
    let rules = &opts.state_rules;
    let want: Vec<EsiObject> = od
        .objects()
        .iter()
        .map(|o| EsiObject::from_od(o, |i, s| apply_rules(rules, i, s.sub, default_object_access(s))))
        .collect();
    compare_objects(&mut r, d, &want, opts.names);
    for (rx, range) in [(true, RX_MAPPING), (false, TX_MAPPING)] {
        let pdos = if rx { &d.rx_pdos } else { &d.tx_pdos };
        let tag = if rx { "RxPdo" } else { "TxPdo" };
        let kind = if rx { SmKind::Outputs } else { SmKind::Inputs };
        let sm = d.sm(kind).map(|(n, _)| n);
        let assigned = default_assignment(od, rx).unwrap_or_default();
        for o in od.objects().iter().filter(|o| range.contains(&o.index)) {
            let Some(p) = pdos.iter().find(|p| p.index == o.index) else {
                r.add(Some(o.index), None, tag, "absent", "mapping object present", "");
                continue;
            };
            let want: Vec<String> =
                mapping_values(od, o.index).iter().map(|v| entry_text(&entry(od, *v))).collect();
            let got: Vec<String> = p.entries.iter().map(entry_text).collect();
            r.diff(o.index, None, &format!("{tag} entries"), got.join(", "), want.join(", "));
            let want_sm = assigned.contains(&o.index).then_some(sm).flatten();
            r.diff(o.index, None, &format!("{tag} Sm"), opt_sm(p.sm), opt_sm(want_sm));
        }
        for p in pdos.iter().filter(|p| od.object(p.index).is_none() || !range.contains(&p.index)) {
            r.add(Some(p.index), None, tag, "present", "no such mapping object", "");
        }
        let order: Vec<u16> = pdos.iter().filter(|p| p.sm.is_some()).map(|p| p.index).collect();
        let want_order: Vec<u16> = assigned.iter().copied().filter(|i| od.object(*i).is_some()).collect();
        if order != want_order {
            let list = |v: &[u16]| v.iter().map(|i| format!("{i:04X}h")).collect::<Vec<_>>().join(", ");
            let at = if rx { 0x1C12 } else { 0x1C13 };
            r.add(Some(at), None, "default assignment", list(&order), list(&want_order), "");
        }
        if let Some((_, s)) = d.sm(kind) {
            let bits: u32 =
                assigned.iter().map(|i| mapping_values(od, *i).iter().map(|v| v & 0xFF).sum::<u32>()).sum();
            let want = bits.div_ceil(8).to_string();
            let got = s.default_size.map_or_else(|| "none".to_string(), |n| n.to_string());
            if got != want {
                r.add(
                    None,
                    None,
                    &format!("Sm {} DefaultSize", kind.name()),
                    got,
                    want,
                    "bytes of the default assignment",
                );
            }
        }
    }
    r.out
}

fn opt_sm(sm: Option<u8>) -> String {
    sm.map_or_else(|| "not assigned".to_string(), |s| format!("SM{s}"))
}

fn entry_text(e: &crate::description::PdoEntry) -> String {
    if e.index == 0 {
        format!("gap {}", e.bit_len)
    } else {
        format!("{:04X}:{:02X}/{}", e.index, e.sub, e.bit_len)
    }
}

/// A sub-object as the EDS states it, in the dictionary's terms (the
/// conversion `drivebus_eds::to_od` makes, kept here so a value that does
/// not evaluate becomes a finding instead of an error).
fn eds_sub(index: u16, sub: u8, v: &EdsVar, node_id: u8) -> Result<SubObject, String> {
    let dt = DataType::from_index(v.data_type).ok_or_else(|| format!("DataType {:#06x}", v.data_type))?;
    let eval = |t: &Option<String>| -> Result<Option<Vec<u8>>, String> {
        match t.as_deref().map(str::trim) {
            None | Some("") => Ok(None),
            Some(s) => drivebus_eds::eval(s, dt, node_id).map(Some),
        }
    };
    let default = eval(&v.default)?.unwrap_or_else(|| vec![0; dt.fixed_size().unwrap_or(0)]);
    let mut s = SubObject::from_bytes(sub, v.name.clone(), dt, v.access, default);
    s.pdo_mappable = v.pdo_mapping;
    s.low_limit = eval(&v.low_limit)?;
    s.high_limit = eval(&v.high_limit)?;
    if s.access.writable() {
        s.persist = PersistGroup::for_index(index);
    }
    Ok(s)
}

/// Does `d` agree with the EDS of the same profile? `[DeviceInfo]`
/// identity (VendorNumber, ProductNumber, RevisionNumber, VendorName,
/// ProductName) and every object and sub-object of the file, compared as
/// [`check_dictionary`] compares them; values are evaluated with
/// `opts.node_id`.
pub fn check_eds(d: &SlaveDescription, eds: &Eds, opts: &CheckOptions) -> Vec<Disagreement> {
    let mut r = Report::new(Source::Eds);
    let di = &eds.device_info;
    compare_identity(&mut r, d, [di.vendor_number, di.product_number, di.revision_number], None);
    if opts.names {
        r.diff(0x1018, None, "VendorName", format!("{:?}", d.vendor_name), format!("{:?}", di.vendor_name));
        r.diff(0x1018, None, "ProductName", format!("{:?}", d.type_name), format!("{:?}", di.product_name));
    }
    let mut want = Vec::new();
    for o in eds.objects.values().filter(|o| o.object_type != ObjectCode::Null) {
        let vars: Vec<(u8, &EdsVar)> = match &o.var {
            Some(v) if o.compact_sub_obj.is_none() => vec![(0, v)],
            _ => o.subs.iter().map(|(k, v)| (*k, v)).collect(),
        };
        let mut obj = Object::with_code(o.index, o.object_type, o.name.clone());
        let mut subs = Vec::new();
        for (sub, v) in vars {
            match eds_sub(o.index, sub, v, opts.node_id) {
                Ok(s) => subs.push(s),
                Err(m) => r.add(Some(o.index), Some(sub), "EDS value", "-", m, "does not evaluate"),
            }
        }
        for s in &subs {
            obj = obj.with_sub(s.clone());
        }
        // `with_sub` keeps a constant sub 0 equal to the highest sub-index;
        // the file's own value is what is checked.
        for (slot, s) in obj.subs_mut().iter_mut().zip(&subs) {
            slot.default.clone_from(&s.default);
        }
        let rules = &opts.state_rules;
        want.push(EsiObject::from_od(&obj, |i, s| apply_rules(rules, i, s.sub, default_object_access(s))));
    }
    compare_objects(&mut r, d, &want, opts.names);
    r.out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::DeviceFacts;
    use drivebus_od::{Access, Value};

    fn od() -> ObjectDictionary {
        let mut od = ObjectDictionary::new();
        od.insert(Object::var(
            0x1000,
            "Device type",
            DataType::Unsigned32,
            Access::Ro,
            Value::U32(0x0002_0192),
        ));
        od.insert(
            Object::record(0x1018, "Identity")
                .with_sub(SubObject::new(1, "Vendor", DataType::Unsigned32, Access::Ro, Value::U32(9)))
                .with_sub(SubObject::new(2, "Product", DataType::Unsigned32, Access::Ro, Value::U32(8)))
                .with_sub(SubObject::new(3, "Revision", DataType::Unsigned32, Access::Ro, Value::U32(7))),
        );
        od.insert(Object::var(0x2000, "Gain", DataType::Real32, Access::Rw, Value::F32(1.5)));
        od
    }

    #[test]
    fn identity_profile_and_values_are_compared() {
        let od = od();
        let d = SlaveDescription::new(&od, &DeviceFacts::new(9, "v", 8, 7, "p"));
        assert_eq!(check_dictionary(&d, &od, &CheckOptions::default()), Vec::new());
        let mut bad = d.clone();
        bad.revision = u32::from_be_bytes(*b"515J");
        bad.profile.add_info = 6;
        bad.objects[2].subs[0].default = 2.5f32.to_le_bytes().to_vec();
        bad.objects[2].name = "gain".into();
        let got: Vec<String> =
            check_dictionary(&bad, &od, &CheckOptions::default()).iter().map(|f| f.to_string()).collect();
        assert_eq!(
            got,
            [
                "1018h:03 revision number: ESI #x3531354A (\"515J\"); dictionary #x00000007",
                "1000h:00 AddInfo: ESI 6; dictionary 2",
                "2000h name: ESI \"gain\"; dictionary \"Gain\"",
                "2000h:00 default: ESI data 00002040; dictionary data 0000C03F",
            ]
        );
        let quiet = CheckOptions { names: false, ..CheckOptions::default() };
        assert_eq!(check_dictionary(&bad, &od, &quiet).len(), 3);
    }

    #[test]
    fn the_eds_is_checked_as_written() {
        let text = "[DeviceInfo]\nVendorNumber=9\nProductNumber=8\nRevisionNumber=7\nVendorName=v\nProductName=p\n\
            [1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x20192\n\
            [1018]\nParameterName=Identity\nObjectType=0x9\nSubNumber=4\n\
            [1018sub0]\nParameterName=n\nObjectType=0x7\nDataType=0x0005\nAccessType=const\nDefaultValue=4\n\
            [1018sub1]\nParameterName=Vendor\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=9\n\
            [1018sub2]\nParameterName=Product\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=8\n\
            [1018sub3]\nParameterName=Revision\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=7\n\
            [2000]\nParameterName=Gain\nObjectType=0x7\nDataType=0x0008\nAccessType=rw\nDefaultValue=1.5\n";
        let eds = drivebus_eds::parse(text).unwrap().eds;
        let od = od();
        let d = SlaveDescription::new(&od, &DeviceFacts::new(9, "v", 8, 7, "p"));
        // 1018h:00 is 4 in the file; the dictionary (with_sub) keeps it at 3.
        let got: Vec<String> =
            check_eds(&d, &eds, &CheckOptions::default()).iter().map(|f| f.to_string()).collect();
        assert_eq!(
            got,
            [
                "1018h:00 name: ESI \"Highest sub-index supported\"; EDS \"n\"",
                "1018h:00 default: ESI #x03; EDS #x04"
            ]
        );
    }
}
