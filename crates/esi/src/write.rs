//! [`SlaveDescription`] → ETG.2000 XML. Elements appear in the order the
//! ETG.2000 schema (`EtherCATInfo.xsd`) sequences them, so schema-checking
//! tools (TwinCAT) accept the file; the output is a pure function of the
//! description (no dates, no hash-map order).

use crate::description::{DcOpMode, EsiPdo, SlaveDescription, SyncSignal};
use crate::types::{hex, hex_bytes, hex_index, xml_safe};
use crate::write_dict::dictionary;
use crate::xml::XmlWriter;

/// The schema version written in `EtherCATInfo@Version`.
pub const SCHEMA_VERSION: &str = "1.6";

/// The ESI file of one device.
pub fn write(d: &SlaveDescription) -> String {
    let mut w = XmlWriter::new();
    w.open(
        "EtherCATInfo",
        &[
            ("xmlns:xsi", "http://www.w3.org/2001/XMLSchema-instance"),
            ("xsi:noNamespaceSchemaLocation", "EtherCATInfo.xsd"),
            ("Version", SCHEMA_VERSION),
        ],
    );
    w.open("Vendor", &[]);
    w.text("Id", &hex_u32(d.vendor_id));
    w.text("Name", &xml_safe(&d.vendor_name));
    w.close("Vendor");
    w.open("Descriptions", &[]);
    w.open("Groups", &[]);
    w.open("Group", &[]);
    w.text("Type", &xml_safe(&d.group_type));
    w.leaf("Name", &[("LcId", "1033")], &xml_safe(&d.group_name));
    w.close("Group");
    w.close("Groups");
    w.open("Devices", &[]);
    device(&mut w, d);
    w.close("Devices");
    w.close("Descriptions");
    w.close("EtherCATInfo");
    w.finish()
}

/// `#x` and eight hex digits (identity numbers).
pub fn hex_u32(v: u32) -> String {
    format!("#x{v:08X}")
}

fn device(w: &mut XmlWriter, d: &SlaveDescription) {
    w.open("Device", &[("Physics", &xml_safe(&d.physics))]);
    w.leaf(
        "Type",
        &[("ProductCode", &hex_u32(d.product_code)), ("RevisionNo", &hex_u32(d.revision))],
        &xml_safe(&d.type_name),
    );
    w.leaf("Name", &[("LcId", "1033")], &xml_safe(&d.name));
    if let Some(url) = &d.url {
        w.leaf("URL", &[("LcId", "1033")], &xml_safe(url));
    }
    if let Some(t) = d.mailbox_timeouts {
        w.open("Info", &[]);
        w.open("Mailbox", &[]);
        w.open("Timeout", &[]);
        w.text("RequestTimeout", &t.request_ms.to_string());
        w.text("ResponseTimeout", &t.response_ms.to_string());
        w.close("Timeout");
        w.close("Mailbox");
        w.close("Info");
    }
    w.text("GroupType", &xml_safe(&d.group_type));
    w.open("Profile", &[]);
    w.text("ProfileNo", &d.profile.number.to_string());
    w.text("AddInfo", &d.profile.add_info.to_string());
    dictionary(w, &d.objects);
    w.close("Profile");
    for f in &d.fmmus {
        w.text("Fmmu", f.name());
    }
    for s in &d.sync_managers {
        let size = s.default_size.map(|n| n.to_string());
        let start = hex_index(s.start);
        let control = format!("#x{:02X}", s.control);
        let mut attrs: Vec<(&str, &str)> = Vec::new();
        if let Some(n) = &size {
            attrs.push(("DefaultSize", n));
        }
        attrs.extend([("StartAddress", start.as_str()), ("ControlByte", &control)]);
        attrs.push(("Enable", if s.enable { "1" } else { "0" }));
        w.leaf("Sm", &attrs, s.kind.name());
    }
    for p in &d.rx_pdos {
        pdo(w, "RxPdo", p);
    }
    for p in &d.tx_pdos {
        pdo(w, "TxPdo", p);
    }
    if let Some(m) = &d.mailbox {
        w.open("Mailbox", &[("DataLinkLayer", bool_text(m.data_link_layer))]);
        if m.eoe {
            w.empty("EoE", &[("IP", "1"), ("MAC", "1")]);
        }
        if let Some(c) = m.coe {
            w.empty(
                "CoE",
                &[
                    ("SdoInfo", bool_text(c.sdo_info)),
                    ("PdoAssign", bool_text(c.pdo_assign)),
                    ("PdoConfig", bool_text(c.pdo_config)),
                    ("PdoUpload", bool_text(c.pdo_upload)),
                    ("CompleteAccess", bool_text(c.complete_access)),
                ],
            );
        }
        if m.foe {
            w.empty("FoE", &[]);
        }
        w.close("Mailbox");
    }
    if !d.dc.is_empty() {
        w.open("Dc", &[]);
        for m in &d.dc {
            op_mode(w, m);
        }
        w.close("Dc");
    }
    w.open("Eeprom", &[]);
    w.text("ByteSize", &d.eeprom.byte_size.to_string());
    w.text("ConfigData", &hex_bytes(&d.eeprom.config.bytes()));
    if let Some(b) = &d.eeprom.bootstrap {
        w.text("BootStrap", &hex_bytes(&b.bytes()));
    }
    w.close("Eeprom");
    w.close("Device");
}

fn bool_text(b: bool) -> &'static str {
    if b { "true" } else { "false" }
}

fn pdo(w: &mut XmlWriter, tag: &str, p: &EsiPdo) {
    let sm = p.sm.map(|s| s.to_string());
    let mut attrs = vec![("Fixed", bool_text(p.fixed)), ("Mandatory", bool_text(p.mandatory))];
    if let Some(s) = &sm {
        attrs.push(("Sm", s.as_str()));
    }
    w.open(tag, &attrs);
    w.text("Index", &hex_index(p.index));
    w.text("Name", &xml_safe(&p.name));
    for e in &p.entries {
        w.open("Entry", &[]);
        w.text("Index", &hex_index(e.index));
        if e.index != 0 {
            w.text("SubIndex", &hex(u64::from(e.sub)));
        }
        w.text("BitLen", &e.bit_len.to_string());
        if e.index != 0 {
            w.text("Name", &xml_safe(&e.name));
            if let Some(dt) = e.data_type {
                w.text("DataType", &crate::types::type_name(dt, dt.fixed_size().unwrap_or(0)));
            }
        }
        w.close("Entry");
    }
    w.close(tag);
}

fn op_mode(w: &mut XmlWriter, m: &DcOpMode) {
    w.open("OpMode", &[]);
    w.text("Name", &xml_safe(&m.name));
    w.text("Desc", &xml_safe(&m.desc));
    w.text("AssignActivate", &format!("#x{:04X}", m.assign_activate));
    let signal = |w: &mut XmlWriter, n: u8, s: &SyncSignal| {
        let factor = s.factor.to_string();
        w.leaf(&format!("CycleTimeSync{n}"), &[("Factor", &factor)], &s.cycle_ns.to_string());
        w.text(&format!("ShiftTimeSync{n}"), &s.shift_ns.to_string());
    };
    if let Some(s) = &m.sync0 {
        signal(w, 0, s);
    }
    if let Some(s) = &m.sync1 {
        signal(w, 1, s);
    }
    w.close("OpMode");
}
