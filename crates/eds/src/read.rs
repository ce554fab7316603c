//! EDS/DCF text → [`Eds`], tolerant of vendor quirks, exact about errors.

use crate::ini::{Ini, Section};
use crate::model::{Commissioning, DeviceInfo, Diagnostic, Eds, EdsError, EdsObject, EdsVar};
use crate::value::eval;
use drivebus_od::{Access, DataType, ObjectCode, parse_int};
use std::collections::BTreeMap;

/// What reading produced: the file, plus warnings about tolerated quirks.
#[derive(Clone, Debug, PartialEq)]
pub struct ParsedEds {
    /// The file's content.
    pub eds: Eds,
    /// Quirks that were tolerated (line, message).
    pub warnings: Vec<Diagnostic>,
}

const BAUD_RATES: [u32; 9] = [10, 20, 50, 125, 250, 500, 800, 1000, 0];

/// The `[DeviceComissioning]` keys [`Commissioning`] has fields for.
const COMMISSIONING_KEYS: [&str; 7] =
    ["nodeid", "nodename", "baudrate", "netnumber", "networkname", "canopenmanager", "lss_serialnumber"];

enum Kind {
    Object(u16),
    Sub(u16, u8),
    Names(u16),
    Values(u16),
    Other,
}

fn classify(name: &str) -> Kind {
    // Case-insensitive without a lower-cased copy: called for every section.
    let hex4 = |s: &str| if s.len() == 4 { u16::from_str_radix(s, 16).ok() } else { None };
    if let Some(i) = hex4(name) {
        return Kind::Object(i);
    }
    if name.len() > 4 && name.is_char_boundary(4) {
        let (head, tail) = name.split_at(4);
        if let Some(i) = hex4(head) {
            if let Some(s) = tail.get(..3).filter(|p| p.eq_ignore_ascii_case("sub")).map(|_| &tail[3..]) {
                // CiA 306 writes the sub-index in hex ("[1600sub1A]").
                if let Ok(sub) = u8::from_str_radix(s, 16) {
                    return Kind::Sub(i, sub);
                }
            } else if tail.eq_ignore_ascii_case("name") {
                return Kind::Names(i);
            } else if tail.eq_ignore_ascii_case("value") {
                return Kind::Values(i);
            }
        }
    }
    Kind::Other
}

/// `[name]suffix`, written only into a message.
#[derive(Clone, Copy)]
struct Displayed<'a>(&'a str, &'a str);

impl std::fmt::Display for Displayed<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[{}]{}", self.0, self.1)
    }
}

struct Reader {
    errors: Vec<Diagnostic>,
    warnings: Vec<Diagnostic>,
}

impl Reader {
    fn err(&mut self, line: usize, message: String) {
        self.errors.push(Diagnostic { line, message });
    }
    fn warn(&mut self, line: usize, message: String) {
        self.warnings.push(Diagnostic { line, message });
    }

    fn num<T: TryFrom<i128>>(&mut self, sec: &Section, key: &str) -> Option<T> {
        let e = sec.get(key)?;
        if e.value.is_empty() {
            return None;
        }
        match parse_int(e.value).and_then(|v| T::try_from(v).ok()) {
            Some(v) => Some(v),
            None => {
                self.err(e.line, format!("[{}] {}={:?} is not a valid number", sec.name, e.key, e.value));
                None
            }
        }
    }

    fn flag(&mut self, sec: &Section, key: &str) -> bool {
        self.num::<i64>(sec, key).is_some_and(|v| v != 0)
    }

    fn text(sec: &Section, key: &str) -> String {
        sec.get(key).map(|e| e.value.to_string()).unwrap_or_default()
    }

    fn opt_text(sec: &Section, key: &str) -> Option<String> {
        sec.get(key).map(|e| e.value.to_string())
    }

    /// A value description from a section's keys (VAR object or sub-object).
    /// `suffix` follows the section name in messages (formatted only for one).
    fn var(&mut self, sec: &Section, suffix: &str) -> Option<EdsVar> {
        let what = Displayed(sec.name, suffix);
        let dt_entry = sec.get("DataType");
        let data_type = match dt_entry {
            None => {
                self.err(sec.line, format!("{what}: DataType missing"));
                return None;
            }
            Some(_) => self.num::<u16>(sec, "DataType")?,
        };
        let access = match sec.get("AccessType") {
            None => {
                self.warn(sec.line, format!("{what}: AccessType missing, assuming ro"));
                Access::Ro
            }
            Some(e) => match Access::from_name(e.value) {
                Some(a) => a,
                None => {
                    self.err(
                        e.line,
                        format!("{what}: AccessType {:?} is not ro/wo/rw/rwr/rww/const", e.value),
                    );
                    return None;
                }
            },
        };
        let mut v = EdsVar::new(Self::text(sec, "ParameterName"), data_type, access);
        v.line = sec.line;
        v.default = Self::opt_text(sec, "DefaultValue");
        v.parameter_value = Self::opt_text(sec, "ParameterValue");
        v.low_limit = Self::opt_text(sec, "LowLimit").filter(|s| !s.is_empty());
        v.high_limit = Self::opt_text(sec, "HighLimit").filter(|s| !s.is_empty());
        v.pdo_mapping = self.flag(sec, "PDOMapping");
        v.obj_flags = self.num::<u32>(sec, "ObjFlags").unwrap_or(0);
        v.upload_file = Self::opt_text(sec, "UploadFile");
        v.download_file = Self::opt_text(sec, "DownloadFile");
        v.denotation = Self::opt_text(sec, "Denotation");
        if let Some(dt) = DataType::from_index(data_type) {
            for key in ["DefaultValue", "ParameterValue", "LowLimit", "HighLimit"] {
                if let Some(e) = sec.get(key)
                    && !e.value.is_empty()
                    && let Err(m) = eval(e.value, dt, 1)
                {
                    self.err(e.line, format!("{what}: {key}: {m}"));
                }
            }
        } else if !(0x0001..=0x0FFF).contains(&data_type) {
            self.err(
                dt_entry.map_or(sec.line, |e| e.line),
                format!("{what}: DataType {data_type:#06x} unknown"),
            );
        }
        Some(v)
    }

    fn list(&mut self, ini: &Ini, name: &str) -> Vec<u16> {
        let Some(sec) = ini.section(name) else { return Vec::new() };
        let n: usize = self.num(sec, "SupportedObjects").unwrap_or(0);
        let mut out = Vec::new();
        for i in 1..=n {
            match sec.get(&i.to_string()) {
                Some(e) => match parse_int(e.value).and_then(|v| u16::try_from(v).ok()) {
                    Some(v) => out.push(v),
                    None => self.err(e.line, format!("[{name}] {i}={:?} is not an index", e.value)),
                },
                None => self.warn(sec.line, format!("[{name}] entry {i} of {n} missing")),
            }
        }
        out
    }
}

/// Read an EDS or DCF. Quirks (case, whitespace, comments, missing optional
/// keys, sub-index 0 inconsistencies, unknown sections) become warnings; real
/// errors (bad numbers, unknown types or access, malformed values) are all
/// collected and returned with their line numbers.
pub fn parse(text: &str) -> Result<ParsedEds, EdsError> {
    let ini = Ini::parse(text);
    let mut r = Reader { errors: Vec::new(), warnings: Vec::new() };
    for (line, m) in &ini.warnings {
        r.warn(*line, m.clone());
    }
    for (line, m) in &ini.errors {
        r.err(*line, m.clone());
    }
    let mut eds = Eds::default();

    if let Some(s) = ini.section("FileInfo") {
        eds.file_info = s.entries.iter().map(|e| (e.key.to_string(), e.value.to_string())).collect();
    } else {
        r.warn(0, "[FileInfo] missing".into());
    }
    match ini.section("DeviceInfo") {
        Some(s) => eds.device_info = device_info(&mut r, s),
        None => r.warn(0, "[DeviceInfo] missing".into()),
    }
    if let Some(s) = ini.section("DummyUsage") {
        eds.dummy_usage = dummy_usage(&mut r, s);
    }
    if let Some(s) = ini.section("Comments") {
        let n: usize = r.num(s, "Lines").unwrap_or(0);
        eds.comments = (1..=n).map(|i| Reader::text(s, &format!("Line{i}"))).collect();
    }
    eds.mandatory = r.list(&ini, "MandatoryObjects");
    eds.optional = r.list(&ini, "OptionalObjects");
    eds.manufacturer = r.list(&ini, "ManufacturerObjects");
    eds.commissioning = commissioning(&mut r, &ini);

    // Objects first, then their sub-objects and compact name/value lists.
    let known = [
        "fileinfo",
        "deviceinfo",
        "dummyusage",
        "comments",
        "mandatoryobjects",
        "optionalobjects",
        "manufacturerobjects",
        "devicecomissioning",
        "devicecommissioning",
    ];
    for sec in &ini.sections {
        if let Kind::Object(index) = classify(sec.name) {
            if let Some(o) = object(&mut r, sec, index) {
                eds.objects.insert(index, o);
            }
        } else if matches!(classify(sec.name), Kind::Other)
            && !known.contains(&sec.name.to_ascii_lowercase().as_str())
        {
            r.warn(sec.line, format!("section [{}] not interpreted; kept as is", sec.name));
            eds.other_sections.push((
                sec.name.to_string(),
                sec.entries.iter().map(|e| (e.key.to_string(), e.value.to_string())).collect(),
            ));
        }
    }
    sub_sections(&mut r, &ini, &mut eds.objects);
    for o in eds.objects.values_mut() {
        finish_object(&mut r, o);
    }
    for &i in eds.mandatory.iter().chain(&eds.optional).chain(&eds.manufacturer) {
        if !eds.objects.contains_key(&i) {
            r.err(0, format!("object {i:04X} is listed but has no section"));
        }
    }
    if r.errors.is_empty() {
        Ok(ParsedEds { eds, warnings: r.warnings })
    } else {
        // In file order; the consequences found at the end (no line: an
        // object listed without its section) after the causes with lines.
        r.errors.sort_by_key(|d| (d.line == 0, d.line));
        Err(EdsError { errors: r.errors })
    }
}

/// `[DummyUsage]`: which dummy data types (`DummyXXXX=1`) the device can map.
fn dummy_usage(r: &mut Reader, s: &Section) -> BTreeMap<u16, bool> {
    let mut out = BTreeMap::new();
    for e in &s.entries {
        let index = e
            .key
            .split_at_checked(5)
            .filter(|(p, t)| p.eq_ignore_ascii_case("dummy") && t.len() == 4)
            .filter(|(_, t)| t.chars().all(|c| c.is_ascii_hexdigit()))
            .and_then(|(_, t)| u16::from_str_radix(t, 16).ok());
        match (index, parse_int(e.value)) {
            (Some(i), Some(v)) => {
                out.insert(i, v != 0);
            }
            (Some(_), None) => {
                r.err(e.line, format!("[DummyUsage] {}={:?} is not a valid number", e.key, e.value))
            }
            (None, _) => r.warn(e.line, format!("[DummyUsage] key {:?} is not DummyXXXX; ignored", e.key)),
        }
    }
    out
}

/// `[DeviceComissioning]` (a DCF's; CiA 306's spelling, the two-m one
/// accepted with a warning).
fn commissioning(r: &mut Reader, ini: &Ini) -> Option<Commissioning> {
    let comm = ini.section("DeviceComissioning").or_else(|| {
        let s = ini.section("DeviceCommissioning");
        if let Some(s) = s {
            r.warn(
                s.line,
                "[DeviceCommissioning] spelled with two m; CiA 306 writes DeviceComissioning".into(),
            );
        }
        s
    });
    comm.map(|s| Commissioning {
        node_id: r.num(s, "NodeID").unwrap_or(0),
        node_name: Reader::text(s, "NodeName"),
        baudrate: r.num(s, "Baudrate").unwrap_or(0),
        net_number: r.num(s, "NetNumber").unwrap_or(0),
        network_name: Reader::text(s, "NetworkName"),
        canopen_manager: r.flag(s, "CANopenManager"),
        lss_serial_number: r.num(s, "LSS_SerialNumber"),
        other: s
            .entries
            .iter()
            .filter(|e| !COMMISSIONING_KEYS.contains(&e.key.to_ascii_lowercase().as_str()))
            .map(|e| (e.key.to_string(), e.value.to_string()))
            .collect(),
    })
}

/// The sections that add to an object: `[XXXXsubN]` and the compact
/// `[XXXXName]`/`[XXXXValue]` lists.
fn sub_sections(r: &mut Reader, ini: &Ini, objects: &mut BTreeMap<u16, EdsObject>) {
    for sec in &ini.sections {
        match classify(sec.name) {
            Kind::Sub(index, sub) => {
                let Some(v) = r.var(sec, "") else { continue };
                match objects.get_mut(&index) {
                    Some(o) if o.compact_sub_obj.is_some() => r.warn(
                        sec.line,
                        format!("[{}] ignored: object {index:04X} uses CompactSubObj", sec.name),
                    ),
                    Some(o) => {
                        o.subs.insert(sub, v);
                    }
                    None => r.err(sec.line, format!("[{}] has no object section [{index:04X}]", sec.name)),
                }
            }
            Kind::Names(index) | Kind::Values(index) => {
                let names = matches!(classify(sec.name), Kind::Names(_));
                let n: usize = r.num(sec, "NrOfEntries").unwrap_or(0);
                let mut map = BTreeMap::new();
                for e in &sec.entries {
                    if e.key.eq_ignore_ascii_case("NrOfEntries") {
                        continue;
                    }
                    match parse_int(e.key).and_then(|v| u8::try_from(v).ok()) {
                        Some(sub) => {
                            map.insert(sub, e.value.to_string());
                        }
                        None => r.err(e.line, format!("[{}] key {:?} is not a sub-index", sec.name, e.key)),
                    }
                }
                if map.len() != n {
                    r.warn(sec.line, format!("[{}] NrOfEntries={n} but {} entries", sec.name, map.len()));
                }
                match objects.get_mut(&index) {
                    Some(o) if names => o.compact_names = map,
                    Some(o) => o.compact_values = map,
                    None => r.err(sec.line, format!("[{}] has no object section [{index:04X}]", sec.name)),
                }
            }
            _ => {}
        }
    }
}

fn device_info(r: &mut Reader, s: &Section) -> DeviceInfo {
    let mut d = DeviceInfo {
        vendor_name: Reader::text(s, "VendorName"),
        vendor_number: r.num(s, "VendorNumber"),
        product_name: Reader::text(s, "ProductName"),
        product_number: r.num(s, "ProductNumber"),
        revision_number: r.num(s, "RevisionNumber"),
        order_code: Reader::text(s, "OrderCode"),
        simple_boot_up_master: r.flag(s, "SimpleBootUpMaster"),
        simple_boot_up_slave: r.flag(s, "SimpleBootUpSlave"),
        granularity: r.num(s, "Granularity").unwrap_or(8),
        dynamic_channels_supported: r.num(s, "DynamicChannelsSupported").unwrap_or(0),
        group_messaging: r.flag(s, "GroupMessaging"),
        nr_of_rx_pdo: r.num(s, "NrOfRXPDO").unwrap_or(0),
        nr_of_tx_pdo: r.num(s, "NrOfTXPDO").unwrap_or(0),
        lss_supported: r.flag(s, "LSS_Supported"),
        ..DeviceInfo::default()
    };
    for b in BAUD_RATES.iter().filter(|b| **b != 0) {
        if r.flag(s, &format!("BaudRate_{b}")) {
            d.baud_rates.push(*b);
        }
    }
    const KNOWN: [&str; 14] = [
        "vendorname",
        "vendornumber",
        "productname",
        "productnumber",
        "revisionnumber",
        "ordercode",
        "simplebootupmaster",
        "simplebootupslave",
        "granularity",
        "dynamicchannelssupported",
        "groupmessaging",
        "nrofrxpdo",
        "nroftxpdo",
        "lss_supported",
    ];
    for e in &s.entries {
        let k = e.key.to_ascii_lowercase();
        if !KNOWN.contains(&k.as_str()) && !k.starts_with("baudrate_") {
            d.other.push((e.key.to_string(), e.value.to_string()));
        }
    }
    d
}

fn object(r: &mut Reader, sec: &Section, index: u16) -> Option<EdsObject> {
    let name = Reader::text(sec, "ParameterName");
    let code = match r.num::<u8>(sec, "ObjectType") {
        Some(c) => match ObjectCode::from_code(c) {
            Some(c) => c,
            None => {
                let line = sec.get("ObjectType").map_or(sec.line, |e| e.line);
                r.err(line, format!("[{}] ObjectType {c:#x} unknown", sec.name));
                return None;
            }
        },
        // CiA 306: ObjectType may be omitted for VAR.
        None => ObjectCode::Var,
    };
    let mut o = EdsObject {
        index,
        name,
        object_type: code,
        sub_number: r.num(sec, "SubNumber"),
        compact_sub_obj: r.num::<u8>(sec, "CompactSubObj").filter(|n| *n > 0),
        obj_flags: r.num(sec, "ObjFlags").unwrap_or(0),
        var: None,
        subs: BTreeMap::new(),
        compact_names: BTreeMap::new(),
        compact_values: BTreeMap::new(),
        line: sec.line,
    };
    let has_value_keys = sec.get("DataType").is_some();
    match code {
        ObjectCode::Var | ObjectCode::Domain | ObjectCode::DefType => {
            o.var = r.var(sec, "");
            o.var.as_ref()?;
        }
        _ if o.compact_sub_obj.is_some() => {
            o.var = r.var(sec, " (CompactSubObj)");
            o.var.as_ref()?;
        }
        _ if has_value_keys => {
            r.warn(sec.line, format!("[{}] value keys on an ARRAY/RECORD ignored", sec.name));
        }
        _ => {}
    }
    Some(o)
}

/// Whether sub 0 of `index` is "highest sub-index supported" (CiA 301
/// §7.4.3), so its DefaultValue must reach the sub-objects described. Not
/// so where CiA 301 gives sub 0 a value of its own and the sub-objects are
/// the room for it: 1003h (number of errors, §7.5.2.5) and the PDO mapping
/// records (number of mapped objects, §7.5.2.36/38; a default mapping
/// uses fewer entries than the record has), and the EtherCAT sync manager
/// PDO assignments 1C10h–1C2Fh (number of assigned PDOs, ETG.1000.6).
fn sub0_is_highest(index: u16) -> bool {
    !matches!(index, 0x1003 | 0x1600..=0x17FF | 0x1A00..=0x1BFF | 0x1C10..=0x1C2F)
}

/// Expand compact objects and check sub-index 0 against the sub-objects.
fn finish_object(r: &mut Reader, o: &mut EdsObject) {
    if !matches!(o.object_type, ObjectCode::Array | ObjectCode::Record) || o.compact_sub_obj.is_some() {
        o.sub_number = None;
    }
    if let (Some(n), Some(t)) = (o.compact_sub_obj, o.var.clone()) {
        let mut s0 = EdsVar::new("NrOfObjects", DataType::Unsigned8 as u16, Access::Ro);
        s0.default = Some(n.to_string());
        o.subs.insert(0, s0);
        for i in 1..=n {
            let mut v = t.clone();
            v.name = o.compact_names.get(&i).cloned().unwrap_or_else(|| format!("{}{i}", o.name));
            if let Some(val) = o.compact_values.get(&i) {
                v.default = Some(val.clone());
            }
            o.subs.insert(i, v);
        }
        return;
    }
    if !matches!(o.object_type, ObjectCode::Array | ObjectCode::Record) {
        return;
    }
    if o.subs.is_empty() {
        r.warn(o.line, format!("object {:04X} is an ARRAY/RECORD without sub-objects", o.index));
        return;
    }
    let highest = o.subs.keys().next_back().copied().unwrap_or(0);
    match o.subs.get(&0) {
        None => {
            r.warn(o.line, format!("object {:04X} has no sub 0; added with {highest}", o.index));
            let mut s0 = EdsVar::new("Highest sub-index supported", DataType::Unsigned8 as u16, Access::Ro);
            s0.default = Some(highest.to_string());
            o.subs.insert(0, s0);
        }
        Some(s0) => {
            let v = s0.default.as_deref().and_then(parse_int);
            if s0.data_type != DataType::Unsigned8 as u16 {
                r.warn(s0.line, format!("object {:04X} sub 0 is not UNSIGNED8", o.index));
            } else if sub0_is_highest(o.index) && v.is_some_and(|v| v < highest as i128) {
                r.warn(
                    s0.line,
                    format!("object {:04X} sub 0 default is below the highest sub-index {highest}", o.index),
                );
            }
        }
    }
    if let Some(n) = o.sub_number
        && n as usize != o.subs.len()
    {
        r.warn(o.line, format!("object {:04X} SubNumber={n} but {} sub-objects", o.index, o.subs.len()));
    }
    // The sub-objects are the truth; SubNumber is derived from them.
    o.sub_number = Some(o.subs.len() as u8);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classify_sections() {
        assert!(matches!(classify("1018sub1"), Kind::Sub(0x1018, 1)));
        assert!(matches!(classify("1600SUB1A"), Kind::Sub(0x1600, 0x1A)));
        assert!(matches!(classify("1003Value"), Kind::Values(0x1003)));
        assert!(matches!(classify("1003name"), Kind::Names(0x1003)));
        assert!(matches!(classify("FileInfo"), Kind::Other));
        assert!(matches!(classify("6040"), Kind::Object(0x6040)));
    }
}
