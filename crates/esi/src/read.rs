//! ETG.2000 XML → [`SlaveDescription`]: reads what [`crate::write`]
//! writes (and the same elements in other vendors' files), so a written
//! file can be compared with the dictionary and EDS it came from.

use crate::description::{
    CoeDetails, ConfigArea, DcOpMode, Eeprom, EsiPdo, EsiProfile, FmmuUsage, Mailbox, MailboxArea,
    MailboxTimeouts, PdoEntry, SlaveDescription, SmKind, SyncManager, SyncSignal,
};
use crate::model::{EsiObject, EsiSub, ObjectKind, parse_states};
use crate::types::{parse_hex_bytes, parse_hex_dec, parse_number, parse_type_name};
use crate::xml::{Element, XmlError, parse};
use drivebus_coe::access_bits::*;
use drivebus_od::DataType;
use std::collections::HashMap;

/// Why a file could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadError {
    /// Where: an element path such as `Device/Profile/Dictionary/Object #x1018`.
    pub at: String,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for ReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.at, self.message)
    }
}

impl std::error::Error for ReadError {}

impl From<XmlError> for ReadError {
    fn from(e: XmlError) -> Self {
        ReadError { at: format!("byte {}", e.position), message: e.message }
    }
}

fn fail<T>(at: &str, message: impl Into<String>) -> Result<T, ReadError> {
    Err(ReadError { at: at.to_string(), message: message.into() })
}

/// Read the first device of an ESI file.
pub fn read(xml: &str) -> Result<SlaveDescription, ReadError> {
    match read_all(xml)?.into_iter().next() {
        Some(d) => Ok(d),
        None => fail("Descriptions/Devices", "no Device"),
    }
}

/// Read every device of an ESI file.
pub fn read_all(xml: &str) -> Result<Vec<SlaveDescription>, ReadError> {
    let root = parse(xml)?;
    if root.name != "EtherCATInfo" {
        return fail(&root.name, "the root element is not EtherCATInfo");
    }
    let Some(vendor) = root.child("Vendor") else { return fail("EtherCATInfo", "no Vendor") };
    let vendor_id = u32_of(vendor.child_text("Id"), "Vendor/Id")?;
    let vendor_name = vendor.child_text("Name").unwrap_or_default().to_string();
    let Some(desc) = root.child("Descriptions") else { return fail("EtherCATInfo", "no Descriptions") };
    let groups: Vec<(&str, &str)> = desc
        .child("Groups")
        .map(|g| {
            g.all("Group")
                .map(|g| (g.child_text("Type").unwrap_or_default(), name_of(g).unwrap_or_default()))
                .collect()
        })
        .unwrap_or_default();
    let Some(devices) = desc.child("Devices") else { return fail("Descriptions", "no Devices") };
    devices.all("Device").map(|d| device(d, vendor_id, &vendor_name, &groups)).collect()
}

/// The `Name` in English (LcId 1033), else the first one.
fn name_of(e: &Element) -> Option<&str> {
    e.all("Name")
        .find(|n| n.attr("LcId") == Some("1033"))
        .or_else(|| e.child("Name"))
        .map(|n| n.text.as_str())
}

fn u32_of(text: Option<&str>, at: &str) -> Result<u32, ReadError> {
    match text.and_then(parse_hex_dec).and_then(|v| u32::try_from(v).ok()) {
        Some(v) => Ok(v),
        None => fail(at, format!("{:?} is not a 32-bit number", text.unwrap_or(""))),
    }
}

fn num<T: TryFrom<i128>>(text: Option<&str>, at: &str) -> Result<T, ReadError> {
    match text.and_then(parse_hex_dec).and_then(|v| T::try_from(v).ok()) {
        Some(v) => Ok(v),
        None => fail(at, format!("{:?} is not a number in range", text.unwrap_or(""))),
    }
}

fn flag(text: Option<&str>) -> bool {
    matches!(text.map(str::trim), Some("1" | "true" | "True" | "TRUE"))
}

fn device(
    d: &Element,
    vendor_id: u32,
    vendor_name: &str,
    groups: &[(&str, &str)],
) -> Result<SlaveDescription, ReadError> {
    let Some(ty) = d.child("Type") else { return fail("Device", "no Type") };
    let group_type = d.child_text("GroupType").unwrap_or_default().to_string();
    let group_name = groups.iter().find(|(t, _)| *t == group_type).map_or("", |(_, n)| n).to_string();
    let mailbox_timeouts =
        match d.child("Info").and_then(|i| i.child("Mailbox")).and_then(|m| m.child("Timeout")) {
            Some(t) => Some(MailboxTimeouts {
                request_ms: num(t.child_text("RequestTimeout"), "Info/Mailbox/Timeout/RequestTimeout")?,
                response_ms: num(t.child_text("ResponseTimeout"), "Info/Mailbox/Timeout/ResponseTimeout")?,
            }),
            None => None,
        };
    let profile = d.child("Profile");
    let objects = match profile.and_then(|p| p.child("Dictionary")) {
        Some(dict) => dictionary(dict)?,
        None => Vec::new(),
    };
    let fmmus = d
        .all("Fmmu")
        .map(|f| match f.text.trim() {
            "Outputs" => Ok(FmmuUsage::Outputs),
            "Inputs" => Ok(FmmuUsage::Inputs),
            "MBoxState" => Ok(FmmuUsage::MBoxState),
            t => fail("Device/Fmmu", format!("unknown usage {t:?}")),
        })
        .collect::<Result<_, _>>()?;
    let sync_managers = d.all("Sm").map(sync_manager).collect::<Result<_, _>>()?;
    Ok(SlaveDescription {
        vendor_id,
        vendor_name: vendor_name.to_string(),
        product_code: u32_of(ty.attr("ProductCode"), "Device/Type@ProductCode")?,
        revision: u32_of(ty.attr("RevisionNo"), "Device/Type@RevisionNo")?,
        serial: 0,
        type_name: ty.text.clone(),
        name: name_of(d).unwrap_or_default().to_string(),
        group_type,
        group_name,
        url: d.child_text("URL").map(str::to_string),
        physics: d.attr("Physics").unwrap_or_default().to_string(),
        mailbox_timeouts,
        profile: EsiProfile {
            number: num(profile.and_then(|p| p.child_text("ProfileNo")).or(Some("0")), "Profile/ProfileNo")?,
            add_info: num(profile.and_then(|p| p.child_text("AddInfo")).or(Some("0")), "Profile/AddInfo")?,
        },
        objects,
        fmmus,
        sync_managers,
        rx_pdos: d.all("RxPdo").map(|p| pdo(p, "RxPdo")).collect::<Result<_, _>>()?,
        tx_pdos: d.all("TxPdo").map(|p| pdo(p, "TxPdo")).collect::<Result<_, _>>()?,
        mailbox: d.child("Mailbox").map(|m| Mailbox {
            data_link_layer: flag(m.attr("DataLinkLayer")),
            coe: m.child("CoE").map(|c| CoeDetails {
                sdo_info: flag(c.attr("SdoInfo")),
                pdo_assign: flag(c.attr("PdoAssign")),
                pdo_config: flag(c.attr("PdoConfig")),
                pdo_upload: flag(c.attr("PdoUpload")),
                complete_access: flag(c.attr("CompleteAccess")),
            }),
            foe: m.child("FoE").is_some(),
            eoe: m.child("EoE").is_some(),
        }),
        dc: match d.child("Dc") {
            Some(dc) => dc.all("OpMode").map(op_mode).collect::<Result<_, _>>()?,
            None => Vec::new(),
        },
        eeprom: eeprom(d.child("Eeprom"))?,
    })
}

fn sync_manager(s: &Element) -> Result<SyncManager, ReadError> {
    let kind = match s.text.trim() {
        "MBoxOut" => SmKind::MBoxOut,
        "MBoxIn" => SmKind::MBoxIn,
        "Outputs" => SmKind::Outputs,
        "Inputs" => SmKind::Inputs,
        t => return fail("Device/Sm", format!("unknown kind {t:?}")),
    };
    Ok(SyncManager {
        kind,
        start: num(s.attr("StartAddress"), "Device/Sm@StartAddress")?,
        default_size: s.attr("DefaultSize").map(|v| num(Some(v), "Device/Sm@DefaultSize")).transpose()?,
        control: num(s.attr("ControlByte"), "Device/Sm@ControlByte")?,
        enable: flag(s.attr("Enable")),
    })
}

fn pdo(p: &Element, tag: &str) -> Result<EsiPdo, ReadError> {
    let at = format!("Device/{tag} {}", p.child_text("Index").unwrap_or("?"));
    let entries = p
        .all("Entry")
        .map(|e| {
            let index: u16 = num(e.child_text("Index"), &format!("{at}/Entry/Index"))?;
            Ok(PdoEntry {
                index,
                sub: num(e.child_text("SubIndex").or(Some("0")), &format!("{at}/Entry/SubIndex"))?,
                bit_len: num(e.child_text("BitLen"), &format!("{at}/Entry/BitLen"))?,
                name: e.child_text("Name").unwrap_or_default().to_string(),
                data_type: e.child_text("DataType").and_then(|t| parse_type_name(t, None)).map(|(dt, _)| dt),
            })
        })
        .collect::<Result<_, ReadError>>()?;
    Ok(EsiPdo {
        index: num(p.child_text("Index"), &format!("{at}/Index"))?,
        name: p.child_text("Name").unwrap_or_default().to_string(),
        sm: p.attr("Sm").map(|s| num(Some(s), &format!("{at}@Sm"))).transpose()?,
        fixed: flag(p.attr("Fixed")),
        mandatory: flag(p.attr("Mandatory")),
        entries,
    })
}

fn op_mode(m: &Element) -> Result<DcOpMode, ReadError> {
    let signal = |n: u8| -> Result<Option<SyncSignal>, ReadError> {
        let cycle = m.child(&format!("CycleTimeSync{n}"));
        let shift = m.child_text(&format!("ShiftTimeSync{n}"));
        if cycle.is_none() && shift.is_none() {
            return Ok(None);
        }
        let at = format!("Dc/OpMode/CycleTimeSync{n}");
        Ok(Some(SyncSignal {
            cycle_ns: num(cycle.map(|c| c.text.as_str()).or(Some("0")), &at)?,
            factor: num(cycle.and_then(|c| c.attr("Factor")).or(Some("1")), &at)?,
            shift_ns: num(shift.or(Some("0")), &format!("Dc/OpMode/ShiftTimeSync{n}"))?,
        }))
    };
    Ok(DcOpMode {
        name: m.child_text("Name").unwrap_or_default().to_string(),
        desc: m.child_text("Desc").unwrap_or_default().to_string(),
        assign_activate: num(m.child_text("AssignActivate"), "Dc/OpMode/AssignActivate")?,
        sync0: signal(0)?,
        sync1: signal(1)?,
    })
}

fn eeprom(e: Option<&Element>) -> Result<Eeprom, ReadError> {
    let Some(e) = e else {
        return Ok(Eeprom { byte_size: 0, config: ConfigArea::default(), bootstrap: None });
    };
    let bytes = |name: &str| -> Result<Option<Vec<u8>>, ReadError> {
        match e.child_text(name) {
            None => Ok(None),
            Some(t) => match parse_hex_bytes(t) {
                Some(b) => Ok(Some(b)),
                None => fail(&format!("Eeprom/{name}"), format!("{t:?} is not hex bytes")),
            },
        }
    };
    let bootstrap = bytes("BootStrap")?.map(|b| {
        let w = |i: usize| b.get(2 * i..2 * i + 2).map_or(0, |x| u16::from_le_bytes([x[0], x[1]]));
        MailboxArea { rx_offset: w(0), rx_size: w(1), tx_offset: w(2), tx_size: w(3) }
    });
    Ok(Eeprom {
        byte_size: num(e.child_text("ByteSize").or(Some("0")), "Eeprom/ByteSize")?,
        config: ConfigArea::from_bytes(&bytes("ConfigData")?.unwrap_or_default()),
        bootstrap,
    })
}

/// The access word a `Flags` element states (no `Flags`: read-only).
pub fn access_word(flags: Option<&Element>) -> u16 {
    let Some(f) = flags else { return READ };
    let acc = f.child("Access");
    let states = |attr: &str| acc.and_then(|a| a.attr(attr)).and_then(parse_states).unwrap_or(7);
    let (read, write) = (states("ReadRestrictions"), states("WriteRestrictions") << 3);
    let mut w = match acc.map(|a| a.text.trim().to_ascii_lowercase()).as_deref() {
        Some("rw") => read | write,
        Some("wo") => write,
        _ => read,
    };
    match f.child_text("PdoMapping").map(|m| m.trim().to_ascii_uppercase()).as_deref() {
        Some("R") => w |= RXPDO,
        Some("T") => w |= TXPDO,
        Some("RT" | "TR") => w |= RXPDO | TXPDO,
        _ => {}
    }
    if flag(f.child_text("Backup")) {
        w |= BACKUP;
    }
    if flag(f.child_text("Setting")) {
        w |= SETTINGS;
    }
    w
}

fn dictionary(dict: &Element) -> Result<Vec<EsiObject>, ReadError> {
    let types: HashMap<&str, &Element> = dict
        .child("DataTypes")
        .map(|t| t.all("DataType").filter_map(|d| Some((d.child_text("Name")?, d))).collect())
        .unwrap_or_default();
    let mut objects: Vec<EsiObject> = match dict.child("Objects") {
        Some(o) => o.all("Object").map(|o| object(o, &types)).collect::<Result<_, _>>()?,
        None => Vec::new(),
    };
    objects.sort_by_key(|o| o.index);
    Ok(objects)
}

fn object(o: &Element, types: &HashMap<&str, &Element>) -> Result<EsiObject, ReadError> {
    let index: u16 = num(o.child_text("Index"), "Dictionary/Object/Index")?;
    let at = format!("Object #x{index:04X}");
    let name = o.child_text("Name").unwrap_or_default().to_string();
    let ty = o.child_text("Type").unwrap_or_default();
    let bits: Option<u32> = o.child_text("BitSize").and_then(|b| num(Some(b), "").ok());
    let info = o.child("Info");
    let def = types.get(ty).filter(|d| d.child("SubItem").is_some());
    let Some(def) = def else {
        let Some((dt, len)) = parse_type_name(ty, bits) else {
            if types.contains_key(ty) {
                // A DTxxxx type without sub-items: an object without sub-objects.
                return Ok(EsiObject { index, name, kind: ObjectKind::Record, subs: Vec::new() });
            }
            return fail(&at, format!("unknown type {ty:?}"));
        };
        let s = sub_with_values(0, name.clone(), dt, len, access_word(o.child("Flags")), info, &at)?;
        return Ok(EsiObject { index, name, kind: ObjectKind::Var, subs: vec![s] });
    };
    let info_subs: Vec<&Element> = info.map(|i| i.all("SubItem").collect()).unwrap_or_default();
    let items: Vec<&Element> = def.all("SubItem").collect();
    let array = items.iter().find(|i| i.child("SubIdx").is_none()).and_then(|i| {
        let t = types.get(i.child_text("Type")?)?;
        t.child("ArrayInfo").map(|a| (*i, *t, a))
    });
    let mut subs = Vec::new();
    if let Some((item, arr, ainfo)) = array {
        if let Some(s0) = items.iter().find(|i| i.child_text("SubIdx").map(str::trim) == Some("0")) {
            let (dt, len) = item_type(s0, &at)?;
            let n = info_subs
                .first()
                .and_then(|i| i.child_text("Name"))
                .unwrap_or(s0.child_text("Name").unwrap_or_default());
            subs.push(sub_with_values(
                0,
                n.into(),
                dt,
                len,
                access_word(s0.child("Flags")),
                info_subs.first().and_then(|i| i.child("Info")),
                &at,
            )?);
        }
        let count: usize = num(ainfo.child_text("Elements"), &format!("{at}: ArrayInfo/Elements"))?;
        let total: u32 = num(item.child_text("BitSize").or(Some("0")), &format!("{at}: Elements/BitSize"))?;
        let elem_bits = u32::try_from(count).ok().filter(|c| *c > 0).map_or(0, |c| total / c);
        let base = arr.child_text("BaseType").unwrap_or_default();
        let Some((dt, len)) = parse_type_name(base, Some(elem_bits)) else {
            return fail(&at, format!("unknown array base type {base:?}"));
        };
        let access = access_word(item.child("Flags"));
        for k in 0..count {
            // Elements are subs 1..=n whatever LBound the array type names
            // (SSC writes 1, IEC-style names such as `ARRAY [0..3] OF UINT` 0).
            let Some(sub) = u8::try_from(k).ok().and_then(|k| k.checked_add(1)) else {
                return fail(&at, "more than 255 array elements");
            };
            let isub = info_subs.get(subs.len());
            let n = isub
                .and_then(|i| i.child_text("Name"))
                .map_or_else(|| format!("SubIndex {sub:03}"), str::to_string);
            subs.push(sub_with_values(sub, n, dt, len, access, isub.and_then(|i| i.child("Info")), &at)?);
        }
        return Ok(EsiObject { index, name, kind: ObjectKind::Array, subs });
    }
    // Record: Info sub-items match by position when there is one per
    // sub-item (ETG.2000 also allows matching by name).
    for (pos, item) in items.iter().enumerate() {
        let sub: u8 = num(item.child_text("SubIdx"), &format!("{at}: SubItem/SubIdx"))?;
        let iname = item.child_text("Name").unwrap_or_default();
        let isub = if info_subs.len() == items.len() {
            info_subs.get(pos).copied()
        } else {
            info_subs.iter().copied().find(|i| i.child_text("Name") == Some(iname))
        };
        let (dt, len) = item_type(item, &at)?;
        subs.push(sub_with_values(
            sub,
            iname.into(),
            dt,
            len,
            access_word(item.child("Flags")),
            isub.and_then(|i| i.child("Info")),
            &at,
        )?);
    }
    subs.sort_by_key(|s| s.sub);
    Ok(EsiObject { index, name, kind: ObjectKind::Record, subs })
}

/// A sub-item's data type and byte length, from `Type` and `BitSize`.
fn item_type(item: &Element, at: &str) -> Result<(DataType, usize), ReadError> {
    let ty = item.child_text("Type").unwrap_or_default();
    let bits = item.child_text("BitSize").and_then(|b| num::<u32>(Some(b), "").ok());
    match parse_type_name(ty, bits) {
        Some(t) => Ok(t),
        None => fail(at, format!("unknown sub-item type {ty:?}")),
    }
}

/// A sub with its default and limits from an `Info` element.
fn sub_with_values(
    sub: u8,
    name: String,
    data_type: DataType,
    len: usize,
    access: u16,
    info: Option<&Element>,
    at: &str,
) -> Result<EsiSub, ReadError> {
    let at = format!("{at} sub {sub}");
    let value = |num_key: &str, data_key: &str| -> Result<Option<Vec<u8>>, ReadError> {
        let Some(info) = info else { return Ok(None) };
        if let Some(t) = info.child_text(num_key) {
            return match parse_number(data_type, t) {
                Some(b) => Ok(Some(b)),
                None => fail(&at, format!("{num_key} {t:?} is not a {}", data_type.name())),
            };
        }
        match info.child_text(data_key).map(|t| (t, parse_hex_bytes(t))) {
            None => Ok(None),
            Some((_, Some(b))) => Ok(Some(b)),
            Some((t, None)) => fail(&at, format!("{data_key} {t:?} is not hex bytes")),
        }
    };
    let default = match value("DefaultValue", "DefaultData")? {
        Some(b) => b,
        None => match info.and_then(|i| i.child_text("DefaultString")) {
            Some(s) => s.as_bytes().to_vec(),
            None => vec![0; data_type.fixed_size().unwrap_or(0)],
        },
    };
    Ok(EsiSub {
        sub,
        name,
        data_type,
        len,
        access,
        default,
        min: value("MinValue", "MinData")?,
        max: value("MaxValue", "MaxData")?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(xml: &str) -> u16 {
        access_word(Some(&parse(xml).unwrap()))
    }

    #[test]
    fn flags_to_access_words() {
        assert_eq!(flags("<Flags><Access>ro</Access></Flags>"), READ);
        assert_eq!(
            flags("<Flags><Access>RW</Access><PdoMapping>TR</PdoMapping></Flags>"),
            READ | WRITE | RXPDO | TXPDO
        );
        assert_eq!(
            flags(
                r#"<Flags><Access WriteRestrictions="PreOP">rw</Access><Backup>1</Backup><Setting>true</Setting></Flags>"#
            ),
            READ | WRITE_PREOP | BACKUP | SETTINGS
        );
        assert_eq!(
            flags(r#"<Flags><Access ReadRestrictions="PreOP_OP">ro</Access></Flags>"#),
            READ_PREOP | READ_OP
        );
        assert_eq!(flags("<Flags><Access>wo</Access><PdoMapping>r</PdoMapping></Flags>"), WRITE | RXPDO);
        assert_eq!(access_word(None), READ);
    }

    /// A file in another vendor's style: decimal and `0x` numbers, a
    /// group without LcId, an IEC-named array type with LBound 0 and the
    /// elements' names in `Info`,
    /// records matched by name, `DefaultData` for a REAL.
    #[test]
    fn reads_other_spellings() {
        let xml = r##"<?xml version="1.0"?>
<EtherCATInfo Version="1.2">
  <Vendor><Id>2</Id><Name>V &amp; Co</Name></Vendor>
  <Descriptions>
    <Groups><Group><Type>G</Type><Name>Group</Name></Group></Groups>
    <Devices>
      <Device Physics="YY">
        <Type ProductCode="0x10" RevisionNo="17">T1</Type>
        <Name LcId="1031">Geraet</Name><Name LcId="1033">Device</Name>
        <GroupType>G</GroupType>
        <Profile><ProfileNo>402</ProfileNo><AddInfo>2</AddInfo><Dictionary>
          <DataTypes>
            <DataType><Name>UINT</Name><BitSize>16</BitSize></DataType>
            <DataType><Name>ARRAY [0..1] OF UINT</Name><BaseType>UINT</BaseType><BitSize>32</BitSize>
              <ArrayInfo><LBound>0</LBound><Elements>2</Elements></ArrayInfo></DataType>
            <DataType><Name>DT1C12</Name><BitSize>48</BitSize>
              <SubItem><SubIdx>0</SubIdx><Name>Count</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs>
                <Flags><Access>rw</Access></Flags></SubItem>
              <SubItem><Name>Elements</Name><Type>ARRAY [0..1] OF UINT</Type><BitSize>32</BitSize><BitOffs>16</BitOffs>
                <Flags><Access WriteRestrictions="PreOP">rw</Access></Flags></SubItem></DataType>
            <DataType><Name>DT2000</Name><BitSize>48</BitSize>
              <SubItem><SubIdx>0</SubIdx><Name>n</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs></SubItem>
              <SubItem><SubIdx>1</SubIdx><Name>gain</Name><Type>REAL</Type><BitSize>32</BitSize><BitOffs>16</BitOffs>
                <Flags><Access>rw</Access></Flags></SubItem></DataType>
          </DataTypes>
          <Objects>
            <Object><Index>#x2000</Index><Name>Tuning</Name><Type>DT2000</Type><BitSize>48</BitSize>
              <Info><SubItem><Name>gain</Name><Info><DefaultData>0000C03F</DefaultData></Info></SubItem></Info></Object>
            <Object><Index>#x1c12</Index><Name>Assign</Name><Type>DT1C12</Type><BitSize>48</BitSize>
              <Info><SubItem><Name>Count</Name><Info><DefaultValue>1</DefaultValue></Info></SubItem>
                <SubItem><Name>First</Name><Info><DefaultValue>0x1600</DefaultValue></Info></SubItem></Info></Object>
            <Object><Index>4096</Index><Name>Device type</Name><Type>UDINT</Type><BitSize>32</BitSize>
              <Info><DefaultValue>131474</DefaultValue></Info><Flags><Access>ro</Access><Category>m</Category></Flags></Object>
          </Objects></Dictionary></Profile>
        <Sm StartAddress="#x1000" ControlByte="#x26" Enable="1" DefaultSize="128">MBoxOut</Sm>
        <Mailbox><CoE SdoInfo="1" CompleteAccess="0"/></Mailbox>
      </Device>
    </Devices>
  </Descriptions>
</EtherCATInfo>"##;
        let d = read(xml).unwrap();
        assert_eq!(
            (d.vendor_id, d.vendor_name.as_str(), d.product_code, d.revision),
            (2, "V & Co", 0x10, 17)
        );
        assert_eq!((d.name.as_str(), d.group_name.as_str()), ("Device", "Group"));
        assert_eq!(d.objects.iter().map(|o| o.index).collect::<Vec<_>>(), [0x1000, 0x1C12, 0x2000]);
        let a = d.object(0x1C12).unwrap();
        assert_eq!(a.kind, ObjectKind::Array);
        assert_eq!(
            a.subs.iter().map(|s| s.name.as_str()).collect::<Vec<_>>(),
            ["Count", "First", "SubIndex 002"]
        );
        assert_eq!(a.subs[1].default, vec![0x00, 0x16]);
        assert_eq!(a.subs[2].default, vec![0, 0], "no Info: zero");
        assert_eq!(a.subs[1].access, READ | WRITE_PREOP);
        let r = d.object(0x2000).unwrap();
        assert_eq!(r.subs[1].default, 1.5f32.to_le_bytes());
        assert_eq!(r.subs[0].access, READ, "no Flags: read-only");
        assert_eq!(d.object(0x1000).unwrap().subs[0].default, 0x20192u32.to_le_bytes());
        assert!(d.mailbox.is_some_and(|m| m.coe.is_some_and(|c| c.sdo_info && !c.complete_access)));
        assert_eq!(d.sync_managers[0].default_size, Some(128));
    }

    #[test]
    fn errors_say_where() {
        let e = read("<EtherCATInfo><Vendor><Id>x</Id></Vendor></EtherCATInfo>").unwrap_err();
        assert_eq!(e.at, "Vendor/Id");
        let e = read("<Other/>").unwrap_err();
        assert!(e.message.contains("EtherCATInfo"));
        let bad_default = "<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>\
            <Type ProductCode='1' RevisionNo='1'>t</Type><Profile><Dictionary><Objects><Object><Index>#x6040</Index>\
            <Name>cw</Name><Type>UINT</Type><BitSize>16</BitSize><Info><DefaultValue>70000</DefaultValue></Info>\
            </Object></Objects></Dictionary></Profile></Device></Devices></Descriptions></EtherCATInfo>";
        let e = read(bad_default).unwrap_err();
        assert_eq!(e.at, "Object #x6040 sub 0");
        assert!(e.message.contains("70000"), "{e}");
        assert!(read("<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices/></Descriptions></EtherCATInfo>").is_err());
    }
}
