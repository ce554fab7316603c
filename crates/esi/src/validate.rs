//! Is a file an ESI the masters can use? Well-formed XML, the elements
//! ETG.2000 makes mandatory, the schema's element order in `Device`, and
//! what TwinCAT, SOEM and ethercrab rely on.

use crate::types::{parse_hex_bytes, parse_hex_dec, parse_type_name};
use crate::xml::{Element, parse};
use std::fmt;

/// One problem found by [`validate`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// True if a master cannot use the file as it is; false for a warning.
    pub error: bool,
    /// Where, as an element path.
    pub at: String,
    /// What is wrong and who needs it.
    pub message: String,
}

impl Problem {
    /// True for an error, false for a warning.
    pub fn is_error(&self) -> bool {
        self.error
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} at {}: {}", if self.error { "error" } else { "warning" }, self.at, self.message)
    }
}

struct V {
    out: Vec<Problem>,
}

impl V {
    fn err(&mut self, at: &str, m: impl Into<String>) {
        self.out.push(Problem { error: true, at: at.into(), message: m.into() });
    }
    fn warn(&mut self, at: &str, m: impl Into<String>) {
        self.out.push(Problem { error: false, at: at.into(), message: m.into() });
    }
    /// A mandatory child whose text is a number (`#x` hex or decimal).
    fn number(&mut self, e: &Element, child: &str, at: &str) -> Option<i128> {
        match e.child_text(child) {
            None => {
                self.err(at, format!("{child} missing"));
                None
            }
            Some(t) => {
                let v = parse_hex_dec(t);
                if v.is_none() {
                    self.err(&format!("{at}/{child}"), format!("{t:?} is not a number"));
                }
                v
            }
        }
    }
    fn attr_number(&mut self, e: &Element, attr: &str, at: &str, required: bool) -> Option<i128> {
        match e.attr(attr) {
            None if required => {
                self.err(at, format!("@{attr} missing"));
                None
            }
            None => None,
            Some(t) => {
                let v = parse_hex_dec(t);
                if v.is_none() {
                    self.err(&format!("{at}@{attr}"), format!("{t:?} is not a number"));
                }
                v
            }
        }
    }
}

/// The `Device` children in the order the ETG.2000 schema sequences them.
const DEVICE_ORDER: &[&str] = &[
    "Type",
    "HideType",
    "AlternativeType",
    "SubDevice",
    "Name",
    "Comment",
    "URL",
    "Info",
    "GroupType",
    "Profile",
    "Fmmu",
    "Sm",
    "Su",
    "RxPdo",
    "TxPdo",
    "Mailbox",
    "Dc",
    "Slots",
    "ESC",
    "Eeprom",
    "Electrical",
    "Image16x14",
    "ImageFile16x14",
    "ImageData16x14",
    "VendorSpecific",
];

/// Check an ESI file. Errors: not well-formed XML; no `EtherCATInfo`,
/// `Vendor/Id`, `Descriptions/Devices/Device`; a device without `Type`
/// with numeric `@ProductCode` and `@RevisionNo`, `Name`, or `GroupType`
/// naming a `Group`; `Device` children out of schema order; `Sm` without
/// numeric `@StartAddress`/`@ControlByte` or of unknown kind; a `Mailbox`
/// without `MBoxOut`/`MBoxIn` sync managers with sizes (SOEM and ethercrab
/// configure SM0/SM1 from them); PDOs without `Index`, entries without
/// `Index`/`BitLen` (and `SubIndex`/`DataType` unless a gap), a PDO `@Sm`
/// that is not an `Outputs` (RxPdo) or `Inputs` (TxPdo) sync manager;
/// process data without an `Outputs`/`Inputs` FMMU (ethercrab stops with
/// `NotFound{Fmmu}`); `Dc/OpMode` without `Name` or numeric
/// `AssignActivate`; `Eeprom` without `ByteSize` or with `ConfigData`
/// that is not 14 hex bytes at most; dictionary objects without numeric
/// `Index`, `Name`, `Type`, `BitSize`, or whose type is neither a base
/// type nor defined in `DataTypes`. Warnings: CoE without `Profile/Dictionary`
/// (TwinCAT then shows no names offline), an EEPROM size that is not a
/// power of two from 128 bytes.
pub fn validate(xml: &str) -> Vec<Problem> {
    let mut v = V { out: Vec::new() };
    let root = match parse(xml) {
        Ok(r) => r,
        Err(e) => {
            v.err(&format!("byte {}", e.position), format!("not well-formed XML: {}", e.message));
            return v.out;
        }
    };
    if root.name != "EtherCATInfo" {
        v.err(&root.name, "the root element must be EtherCATInfo");
        return v.out;
    }
    match root.child("Vendor") {
        Some(ven) => {
            v.number(ven, "Id", "Vendor");
        }
        None => v.err("EtherCATInfo", "Vendor missing"),
    }
    let Some(desc) = root.child("Descriptions") else {
        v.err("EtherCATInfo", "Descriptions missing");
        return v.out;
    };
    let groups: Vec<&str> = desc
        .child("Groups")
        .map(|g| g.all("Group").filter_map(|g| g.child_text("Type")).collect())
        .unwrap_or_default();
    let devices: Vec<&Element> = desc.child("Devices").map(|d| d.all("Device").collect()).unwrap_or_default();
    if devices.is_empty() {
        v.err("Descriptions", "no Devices/Device");
    }
    for (n, d) in devices.iter().enumerate() {
        device(&mut v, d, &format!("Device[{n}]"), &groups);
    }
    v.out
}

fn device(v: &mut V, d: &Element, at: &str, groups: &[&str]) {
    let mut last = 0;
    for c in &d.children {
        match DEVICE_ORDER.iter().position(|n| *n == c.name) {
            Some(p) if p < last => {
                v.err(&format!("{at}/{}", c.name), format!("after {}: ETG.2000 order", DEVICE_ORDER[last]))
            }
            Some(p) => last = p,
            None => v.warn(&format!("{at}/{}", c.name), "not an ETG.2000 Device element"),
        }
    }
    match d.child("Type") {
        Some(t) => {
            v.attr_number(t, "ProductCode", &format!("{at}/Type"), true);
            v.attr_number(t, "RevisionNo", &format!("{at}/Type"), true);
        }
        None => v.err(at, "Type missing"),
    }
    if d.child("Name").is_none() {
        v.err(at, "Name missing");
    }
    match d.child_text("GroupType") {
        None => v.err(at, "GroupType missing (TwinCAT files devices by group)"),
        Some(g) if !groups.contains(&g) => {
            v.err(&format!("{at}/GroupType"), format!("{g:?} names no Groups/Group"))
        }
        Some(_) => {}
    }
    let kinds = sync_managers(v, d, at);
    process_data(v, d, at, &kinds);
    if let Some(dc) = d.child("Dc") {
        for (i, m) in dc.all("OpMode").enumerate() {
            let mat = format!("{at}/Dc/OpMode[{i}]");
            if m.child("Name").is_none() {
                v.err(&mat, "Name missing");
            }
            v.number(m, "AssignActivate", &mat);
        }
    }
    match d.child("Eeprom") {
        Some(e) => {
            let eat = format!("{at}/Eeprom");
            if let Some(n) = v.number(e, "ByteSize", &eat)
                && (n < 128 || n.count_ones() != 1)
            {
                v.warn(&eat, format!("ByteSize {n} is not a power of two of at least 128"));
            }
            match e.child_text("ConfigData").map(parse_hex_bytes) {
                Some(Some(b)) if b.len() <= 14 => {}
                Some(_) => v.err(&eat, "ConfigData must be at most 14 hex bytes (SII words 0–6)"),
                None => v.warn(&eat, "ConfigData missing: the ESC starts with an unconfigured PDI"),
            }
        }
        None => v.warn(at, "Eeprom missing: a tool cannot program the SII from this file"),
    }
    if let Some(dict) = d.child("Profile").and_then(|p| p.child("Dictionary")) {
        dictionary(v, dict, &format!("{at}/Profile/Dictionary"));
    }
}

/// The sync managers (their kinds, in order) and the mailbox's.
fn sync_managers(v: &mut V, d: &Element, at: &str) -> Vec<String> {
    let mut kinds = Vec::new();
    for (i, s) in d.all("Sm").enumerate() {
        let sat = format!("{at}/Sm[{i}]");
        v.attr_number(s, "StartAddress", &sat, true);
        v.attr_number(s, "ControlByte", &sat, true);
        let size = v.attr_number(s, "DefaultSize", &sat, false);
        let kind = s.text.trim().to_string();
        if !["MBoxOut", "MBoxIn", "Outputs", "Inputs"].contains(&kind.as_str()) {
            v.err(&sat, format!("kind {kind:?} is not MBoxOut, MBoxIn, Outputs or Inputs"));
        }
        if kind.starts_with("MBox") && size.is_none_or(|n| n <= 0) {
            v.err(&sat, "a mailbox sync manager needs a DefaultSize");
        }
        kinds.push(kind);
    }
    let mailbox = d.child("Mailbox");
    if let Some(m) = mailbox {
        if !kinds.iter().any(|k| k == "MBoxOut") || !kinds.iter().any(|k| k == "MBoxIn") {
            v.err(&format!("{at}/Mailbox"), "a mailbox needs MBoxOut and MBoxIn sync managers");
        }
        if m.child("CoE").is_some() && d.child("Profile").and_then(|p| p.child("Dictionary")).is_none() {
            v.warn(
                &format!("{at}/Profile"),
                "CoE without a Dictionary: TwinCAT shows no object names offline",
            );
        }
    }
    kinds
}

/// The PDOs: their Fmmu, sync manager and entries.
fn process_data(v: &mut V, d: &Element, at: &str, kinds: &[String]) {
    let fmmus: Vec<&str> = d.all("Fmmu").map(|f| f.text.trim()).collect();
    for (tag, want, fmmu) in [("RxPdo", "Outputs", "Outputs"), ("TxPdo", "Inputs", "Inputs")] {
        let pdos: Vec<&Element> = d.all(tag).collect();
        if !pdos.is_empty() && !fmmus.contains(&fmmu) {
            v.err(at, format!("{tag}s without an {fmmu} Fmmu (ethercrab: NotFound Fmmu)"));
        }
        for (i, p) in pdos.iter().enumerate() {
            let pat = format!("{at}/{tag}[{i}]");
            v.number(p, "Index", &pat);
            if let Some(sm) = v.attr_number(p, "Sm", &pat, false) {
                let ok = usize::try_from(sm).ok().and_then(|s| kinds.get(s)).is_some_and(|k| k == want);
                if !ok {
                    v.err(&format!("{pat}@Sm"), format!("SM{sm} is not an {want} sync manager"));
                }
            }
            for (k, e) in p.all("Entry").enumerate() {
                let eat = format!("{pat}/Entry[{k}]");
                let index = v.number(e, "Index", &eat);
                v.number(e, "BitLen", &eat);
                if index.is_some_and(|i| i != 0) {
                    v.number(e, "SubIndex", &eat);
                    match e.child_text("DataType") {
                        None => v.err(&eat, "DataType missing"),
                        Some(t) if parse_type_name(t, None).is_none() => {
                            v.warn(&format!("{eat}/DataType"), format!("{t:?} is not a CoE base type"))
                        }
                        Some(_) => {}
                    }
                }
            }
        }
    }
}

fn dictionary(v: &mut V, dict: &Element, at: &str) {
    let types: Vec<&str> = dict
        .child("DataTypes")
        .map(|t| t.all("DataType").filter_map(|d| d.child_text("Name")).collect())
        .unwrap_or_default();
    let Some(objects) = dict.child("Objects") else {
        v.err(at, "Objects missing");
        return;
    };
    for (i, o) in objects.all("Object").enumerate() {
        let oat = format!("{at}/Object[{i}]");
        v.number(o, "Index", &oat);
        v.number(o, "BitSize", &oat);
        if o.child("Name").is_none() {
            v.err(&oat, "Name missing");
        }
        match o.child_text("Type") {
            None => v.err(&oat, "Type missing"),
            Some(t) if !types.contains(&t) => {
                let base = parse_type_name(t, None).is_some();
                if base {
                    v.warn(&format!("{oat}/Type"), format!("{t:?} is not listed in DataTypes"));
                } else {
                    v.err(&format!("{oat}/Type"), format!("{t:?} is neither a base type nor in DataTypes"));
                }
            }
            Some(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "<EtherCATInfo><Vendor><Id>#x2</Id></Vendor><Descriptions><Groups><Group><Type>G</Type>\
        <Name>g</Name></Group></Groups><Devices>";
    const TAIL: &str = "</Devices></Descriptions></EtherCATInfo>";

    fn problems(device: &str) -> Vec<String> {
        validate(&format!("{HEAD}<Device>{device}</Device>{TAIL}"))
            .into_iter()
            .map(|p| format!("{}: {}", if p.error { "E" } else { "W" }, p.message))
            .collect()
    }

    const OK: &str = "<Type ProductCode='#x1' RevisionNo='1'>t</Type><Name>n</Name><GroupType>G</GroupType>\
        <Eeprom><ByteSize>256</ByteSize><ConfigData>0504</ConfigData></Eeprom>";

    #[test]
    fn a_minimal_device_is_valid() {
        assert_eq!(problems(OK), Vec::<String>::new());
        assert!(validate("<a>").iter().all(|p| p.error && p.message.contains("well-formed")));
        assert!(validate("<a/>")[0].message.contains("EtherCATInfo"));
    }

    #[test]
    fn each_rule_reports() {
        let cases: &[(&str, &str)] = &[
            ("<Name>n</Name><GroupType>G</GroupType>", "Type missing"),
            (
                "<Type ProductCode='x' RevisionNo='1'>t</Type><Name>n</Name><GroupType>G</GroupType>",
                "\"x\" is not a number",
            ),
            (
                "<Type ProductCode='1' RevisionNo='1'>t</Type><Name>n</Name><GroupType>H</GroupType>",
                "names no Groups/Group",
            ),
            (
                "<Type ProductCode='1' RevisionNo='1'>t</Type><GroupType>G</GroupType><Name>n</Name>",
                "ETG.2000 order",
            ),
            (
                &format!("{OK}<Sm StartAddress='#x1000' ControlByte='#x26'>MBoxOut</Sm>"),
                "needs a DefaultSize",
            ),
            (&format!("{OK}<Sm StartAddress='#x1000' ControlByte='#x26'>Mailbox</Sm>"), "is not MBoxOut"),
            (&format!("{OK}<Mailbox><CoE/></Mailbox>"), "needs MBoxOut and MBoxIn"),
            (&format!("{OK}<RxPdo Sm='0'><Index>#x1600</Index></RxPdo>"), "without an Outputs Fmmu"),
            (
                "<Type ProductCode='1' RevisionNo='1'>t</Type><Name>n</Name><GroupType>G</GroupType><Fmmu>Outputs</Fmmu>\
                 <Sm StartAddress='#x1000' ControlByte='#x20'>Inputs</Sm><RxPdo Sm='0'><Index>#x1600</Index>\
                 <Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>16</BitLen></Entry></RxPdo>",
                "SM0 is not an Outputs sync manager",
            ),
            (
                "<Type ProductCode='1' RevisionNo='1'>t</Type><Name>n</Name><GroupType>G</GroupType><Fmmu>Outputs</Fmmu>\
                 <RxPdo><Index>#x1600</Index><Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>16</BitLen></Entry></RxPdo>",
                "DataType missing",
            ),
            (
                &format!("{OK}<Dc><OpMode><Name>DC</Name><AssignActivate>on</AssignActivate></OpMode></Dc>"),
                "\"on\" is not a number",
            ),
            (
                "<Type ProductCode='1' RevisionNo='1'>t</Type><Name>n</Name><GroupType>G</GroupType>\
                 <Eeprom><ByteSize>256</ByteSize><ConfigData>000102030405060708090A0B0C0D0E</ConfigData></Eeprom>",
                "at most 14 hex bytes",
            ),
            (
                "<Type ProductCode='1' RevisionNo='1'>t</Type><Name>n</Name><GroupType>G</GroupType>\
                 <Eeprom><ByteSize>300</ByteSize><ConfigData>00</ConfigData></Eeprom>",
                "not a power of two",
            ),
            (
                "<Type ProductCode='1' RevisionNo='1'>t</Type><Name>n</Name><GroupType>G</GroupType><Profile><Dictionary>\
                 <Objects><Object><Index>#x2000</Index><Name>x</Name><Type>DT2000</Type><BitSize>8</BitSize></Object>\
                 </Objects></Dictionary></Profile>",
                "neither a base type nor in DataTypes",
            ),
            (
                "<Type ProductCode='1' RevisionNo='1'>t</Type><Name>n</Name><GroupType>G</GroupType>",
                "Eeprom missing",
            ),
        ];
        for (device, want) in cases {
            let p = problems(device);
            assert!(p.iter().any(|m| m.contains(want)), "{want:?} not in {p:?}");
        }
    }
}
