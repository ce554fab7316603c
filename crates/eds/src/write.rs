//! [`Eds`] → EDS/DCF text.

use crate::model::{Eds, EdsObject, EdsVar};
use std::fmt::Write;

/// Write the file. Reading the result gives back an equal [`Eds`].
pub fn write(eds: &Eds) -> String {
    let mut w = String::new();
    section(&mut w, "FileInfo", eds.file_info.iter().map(|(k, v)| (k.clone(), v.clone())));
    let d = &eds.device_info;
    let mut di: Vec<(String, String)> = vec![
        ("VendorName".into(), d.vendor_name.clone()),
        ("ProductName".into(), d.product_name.clone()),
        ("OrderCode".into(), d.order_code.clone()),
    ];
    for (k, v) in [
        ("VendorNumber", d.vendor_number),
        ("ProductNumber", d.product_number),
        ("RevisionNumber", d.revision_number),
    ] {
        if let Some(v) = v {
            di.push((k.into(), format!("0x{v:08X}")));
        }
    }
    for b in [10, 20, 50, 125, 250, 500, 800, 1000] {
        di.push((format!("BaudRate_{b}"), (d.baud_rates.contains(&b) as u8).to_string()));
    }
    di.extend([
        ("SimpleBootUpMaster".into(), (d.simple_boot_up_master as u8).to_string()),
        ("SimpleBootUpSlave".into(), (d.simple_boot_up_slave as u8).to_string()),
        ("Granularity".into(), d.granularity.to_string()),
        ("DynamicChannelsSupported".into(), d.dynamic_channels_supported.to_string()),
        ("GroupMessaging".into(), (d.group_messaging as u8).to_string()),
        ("NrOfRXPDO".into(), d.nr_of_rx_pdo.to_string()),
        ("NrOfTXPDO".into(), d.nr_of_tx_pdo.to_string()),
        ("LSS_Supported".into(), (d.lss_supported as u8).to_string()),
    ]);
    di.extend(d.other.iter().cloned());
    section(&mut w, "DeviceInfo", di.into_iter());
    // The entries the file has, and only those (CiA 306 §4.5 lists none for
    // 0000h; a tool's 0010h–001Bh entries stay).
    if !eds.dummy_usage.is_empty() {
        section(
            &mut w,
            "DummyUsage",
            eds.dummy_usage.iter().map(|(i, u)| (format!("Dummy{i:04X}"), (*u as u8).to_string())),
        );
    }
    let mut comments = vec![("Lines".to_string(), eds.comments.len().to_string())];
    comments.extend(eds.comments.iter().enumerate().map(|(i, l)| (format!("Line{}", i + 1), l.clone())));
    section(&mut w, "Comments", comments.into_iter());
    for (name, list) in [
        ("MandatoryObjects", &eds.mandatory),
        ("OptionalObjects", &eds.optional),
        ("ManufacturerObjects", &eds.manufacturer),
    ] {
        let mut e = vec![("SupportedObjects".to_string(), list.len().to_string())];
        e.extend(list.iter().enumerate().map(|(i, x)| ((i + 1).to_string(), format!("0x{x:04X}"))));
        section(&mut w, name, e.into_iter());
    }
    for o in eds.objects.values() {
        object(&mut w, o);
    }
    if let Some(c) = &eds.commissioning {
        let mut e = vec![
            ("NodeID".to_string(), format!("0x{:02X}", c.node_id)),
            ("NodeName".to_string(), c.node_name.clone()),
            ("Baudrate".to_string(), c.baudrate.to_string()),
            ("NetNumber".to_string(), c.net_number.to_string()),
            ("NetworkName".to_string(), c.network_name.clone()),
            ("CANopenManager".to_string(), (c.canopen_manager as u8).to_string()),
        ];
        if let Some(s) = c.lss_serial_number {
            e.push(("LSS_SerialNumber".to_string(), format!("0x{s:08X}")));
        }
        e.extend(c.other.iter().cloned());
        section(&mut w, "DeviceComissioning", e.into_iter());
    }
    for (name, entries) in &eds.other_sections {
        section(&mut w, name, entries.iter().cloned());
    }
    w
}

fn section(w: &mut String, name: &str, entries: impl Iterator<Item = (String, String)>) {
    let _ = writeln!(w, "[{name}]");
    for (k, v) in entries {
        let _ = writeln!(w, "{k}={v}");
    }
    w.push('\n');
}

fn var_keys(v: &EdsVar, out: &mut Vec<(String, String)>) {
    out.push(("DataType".into(), format!("0x{:04X}", v.data_type)));
    out.push(("AccessType".into(), v.access.name().into()));
    let opt = |out: &mut Vec<(String, String)>, k: &str, v: &Option<String>| {
        if let Some(v) = v {
            out.push((k.into(), v.clone()));
        }
    };
    opt(out, "DefaultValue", &v.default);
    opt(out, "ParameterValue", &v.parameter_value);
    opt(out, "LowLimit", &v.low_limit);
    opt(out, "HighLimit", &v.high_limit);
    out.push(("PDOMapping".into(), (v.pdo_mapping as u8).to_string()));
    if v.obj_flags != 0 {
        out.push(("ObjFlags".into(), format!("0x{:X}", v.obj_flags)));
    }
    opt(out, "UploadFile", &v.upload_file);
    opt(out, "DownloadFile", &v.download_file);
    opt(out, "Denotation", &v.denotation);
}

fn object(w: &mut String, o: &EdsObject) {
    let mut e = vec![
        ("ParameterName".to_string(), o.name.clone()),
        ("ObjectType".to_string(), format!("0x{:X}", o.object_type as u8)),
    ];
    if o.obj_flags != 0 {
        e.push(("ObjFlags".into(), format!("0x{:X}", o.obj_flags)));
    }
    if let Some(n) = o.compact_sub_obj {
        e.push(("CompactSubObj".into(), n.to_string()));
        if let Some(v) = &o.var {
            var_keys(v, &mut e);
        }
        section(w, &format!("{:04X}", o.index), e.into_iter());
        for (suffix, map) in [("Name", &o.compact_names), ("Value", &o.compact_values)] {
            if !map.is_empty() {
                let mut e = vec![("NrOfEntries".to_string(), map.len().to_string())];
                e.extend(map.iter().map(|(k, v)| (k.to_string(), v.clone())));
                section(w, &format!("{:04X}{suffix}", o.index), e.into_iter());
            }
        }
        return;
    }
    if let Some(v) = &o.var {
        var_keys(v, &mut e);
        section(w, &format!("{:04X}", o.index), e.into_iter());
        return;
    }
    e.push(("SubNumber".into(), format!("0x{:X}", o.subs.len())));
    section(w, &format!("{:04X}", o.index), e.into_iter());
    for (sub, v) in &o.subs {
        let mut e = vec![("ParameterName".to_string(), v.name.clone()), ("ObjectType".into(), "0x7".into())];
        var_keys(v, &mut e);
        section(w, &format!("{:04X}sub{sub:X}", o.index), e.into_iter());
    }
}
