//! Frames in CANopen words, for `dump` and `monitor`: the pre-defined
//! connection set (CiA 301 §7.3.5), object names from `--eds` or the
//! CiA 301/402 dictionary, and PDOs decoded by their mapping.

use std::collections::HashMap;

use drivebus_master::sdo_wire::{CS_ABORT, EXPEDITED, expedited_len, scs};
use drivebus_master::{CanId, Frame};
use drivebus_master::{DataType, MappedObject, PdoMapEntry, SdoAbort, Value, find_mapped, pdo_layout};

use crate::dict::Dict;

/// COB-ID → (label such as `TPDO1 node 5`, mapping).
pub type PdoMaps = HashMap<u16, (String, Vec<PdoMapEntry>)>;

/// Where `index:sub` sits in a PDO of `mapping`: (bit offset, bits).
pub fn mapped_at(mapping: &[PdoMapEntry], index: u16, sub: u8) -> Option<(usize, usize)> {
    find_mapped(mapping.iter().copied(), index, sub).map(|m| (m.bit_offset, usize::from(m.entry.bits)))
}

/// The little-endian bytes of the `bits` bits (whole bytes) at bit `at`
/// of a PDO's `data`, or `None` past the end or for a partial byte.
pub fn entry_bytes(data: &[u8], at: usize, bits: usize) -> Option<Vec<u8>> {
    if !bits.is_multiple_of(8) {
        return None;
    }
    let place = MappedObject { entry: PdoMapEntry::new(0, 0, u8::try_from(bits).ok()?), bit_offset: at };
    place.read(data).map(|raw| raw.to_le_bytes()[..bits / 8].to_vec())
}

/// One PDO, value by value.
fn pdo(f: &Frame, dict: &Dict, (label, mapping): &(String, Vec<PdoMapEntry>)) -> String {
    let mut parts = Vec::new();
    for place in pdo_layout(mapping.iter().copied()) {
        let m = place.entry;
        let bits = usize::from(m.bits);
        let what = dict.name(m.index, m.sub).unwrap_or_else(|| format!("{:04X}h:{:02X}", m.index, m.sub));
        let what = what.rsplit(" / ").next().unwrap_or(&what).to_owned();
        // Dummy entries (index below 1000h) only take room.
        if m.index < 0x1000 {
            continue;
        }
        let Some(raw) = place.read(f.data()) else {
            parts.push(format!("{what}: frame too short"));
            break;
        };
        let bytes = raw.to_le_bytes();
        let value = match dict.data_type(m.index, m.sub) {
            Some(dt) if bits.is_multiple_of(8) => match Value::decode(dt, &bytes[..bits / 8]) {
                Ok(_) if dt == DataType::Unsigned16 && m.index == 0x6041 => format!(
                    "0x{:04X} ({})",
                    raw,
                    drivebus_master::DriveState::from_statusword(raw as u16).name()
                ),
                Ok(v)
                    if v.as_i128().is_some_and(|i| i >= 0)
                        && (m.index == 0x6040 || dt == DataType::Unsigned32 && m.index < 0x2000) =>
                {
                    format!("0x{raw:0w$X}", w = bits / 4)
                }
                Ok(v) => v.to_string(),
                Err(_) => format!("0x{raw:X}"),
            },
            _ => raw.to_string(),
        };
        parts.push(format!("{what} = {value}"));
    }
    format!("{label}: {}", parts.join(", "))
}

/// The mapped objects of a PDO (dummy entries left out) with their column
/// names, `LABEL INDEXh:SUB NAME`.
pub fn pdo_columns(dict: &Dict, (label, mapping): &(String, Vec<PdoMapEntry>)) -> Vec<String> {
    mapping
        .iter()
        .filter(|m| m.index >= 0x1000)
        .map(|m| {
            let what = dict.name(m.index, m.sub).unwrap_or_default();
            let what = what.rsplit(" / ").next().unwrap_or(&what).to_owned();
            format!("{label} {:04X}h:{:02X} {what}", m.index, m.sub).trim_end().to_owned()
        })
        .collect()
}

/// The values of a PDO's mapped objects as plain numbers (signed where the
/// type is; dummy entries left out), in [`pdo_columns`] order; `None` for
/// an entry past the end of a short frame.
pub fn pdo_numbers(f: &Frame, dict: &Dict, mapping: &[PdoMapEntry]) -> Vec<Option<String>> {
    let mut out = Vec::new();
    for place in pdo_layout(mapping.iter().copied()) {
        let m = place.entry;
        let bits = usize::from(m.bits);
        let raw = place.read(f.data());
        if m.index < 0x1000 {
            continue;
        }
        out.push(raw.map(|raw| match dict.data_type(m.index, m.sub) {
            Some(dt) if bits.is_multiple_of(8) => match Value::decode(dt, &raw.to_le_bytes()[..bits / 8]) {
                Ok(v) => v.to_string(),
                Err(_) => raw.to_string(),
            },
            _ => raw.to_string(),
        }));
    }
    out
}

fn name(dict: &Dict, index: u16, sub: u8) -> String {
    match dict.name(index, sub) {
        Some(n) => format!("{index:04X}h:{sub:02X} ({n})"),
        None => format!("{index:04X}h:{sub:02X}"),
    }
}

fn u32_at(d: &[u8; 8], i: usize) -> u32 {
    u32::from_le_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]])
}

/// One frame in CANopen words (pre-defined connection set, CiA 301 §7.3.5);
/// PDOs with a known mapping are decoded value by value.
pub fn decode(f: &Frame, dict: &Dict, pdos: &PdoMaps) -> String {
    let id = match f.id() {
        CanId::Standard(id) => id,
        CanId::Extended(id) => return format!("extended frame {id:08X}"),
    };
    let d = f.raw_data();
    let len = f.len();
    let node = id & 0x7F;
    if f.is_rtr() {
        return match id {
            0x701..=0x77F => format!("node guarding request to node {node}"),
            _ => format!("remote request {id:03X}"),
        };
    }
    match id {
        0x000 => {
            let cs = match d[0] {
                0x01 => "start",
                0x02 => "stop",
                0x80 => "enter pre-operational",
                0x81 => "reset node",
                0x82 => "reset communication",
                _ => "unknown command",
            };
            let who = if d[1] == 0 { "all nodes".to_owned() } else { format!("node {}", d[1]) };
            format!("NMT {cs} → {who}")
        }
        0x080 if len == 0 => "SYNC".to_owned(),
        0x080 => format!("SYNC counter {}", d[0]),
        0x081..=0x0FF => {
            let code = u16::from_le_bytes([d[0], d[1]]);
            if code == 0 {
                return format!("EMCY node {node}: error reset / no error");
            }
            let text = drivebus_master::emcy_description(code).unwrap_or("manufacturer specific");
            format!("EMCY node {node}: {code:04X}h {text}, register {:02X}h", d[2])
        }
        0x100 => "TIME".to_owned(),
        _ if pdos.contains_key(&id) => pdo(f, dict, &pdos[&id]),
        0x180..=0x57F => {
            let (kind, n) = match id & 0x780 {
                0x180 => ("TPDO1", node),
                0x200 => ("RPDO1", node),
                0x280 => ("TPDO2", node),
                0x300 => ("RPDO2", node),
                0x380 => ("TPDO3", node),
                0x400 => ("RPDO3", node),
                0x480 => ("TPDO4", node),
                _ => ("RPDO4", node),
            };
            let hex: Vec<String> = f.data().iter().map(|b| format!("{b:02X}")).collect();
            format!("{kind} node {n}: {}", hex.join(" "))
        }
        0x581..=0x5FF => format!("SDO node {node} → master: {}", sdo(d, true, dict)),
        0x601..=0x67F => format!("SDO master → node {node}: {}", sdo(d, false, dict)),
        0x701..=0x77F => {
            let st = match d[0] & 0x7F {
                0x00 => "boot-up",
                0x04 => "stopped",
                0x05 => "operational",
                0x7F => "pre-operational",
                _ => "unknown state",
            };
            if d[0] == 0 { format!("boot-up node {node}") } else { format!("heartbeat node {node}: {st}") }
        }
        0x7E4 => format!("LSS slave → master cs {:02X}h", d[0]),
        0x7E5 => format!("LSS master → slave cs {:02X}h", d[0]),
        _ => format!("frame {id:03X}"),
    }
}

fn sdo(d: &[u8; 8], from_server: bool, dict: &Dict) -> String {
    let idx = u16::from_le_bytes([d[1], d[2]]);
    let sub = d[3];
    if d[0] == CS_ABORT {
        let a = SdoAbort(u32_at(d, 4));
        return format!(
            "abort {} code 0x{:08X} {}",
            name(dict, idx, sub),
            a.0,
            a.description().unwrap_or("unknown abort code")
        );
    }
    // Without the size indicated an expedited frame shows all 4 bytes.
    let expedited_n = |d0: u8| expedited_len(d0).unwrap_or(4);
    match (from_server, scs(d[0])) {
        (false, 1) => {
            if d[0] & EXPEDITED != 0 {
                let n = expedited_n(d[0]);
                let hex: Vec<String> = d[4..4 + n].iter().map(|b| format!("{b:02X}")).collect();
                format!("write {} = {}", name(dict, idx, sub), hex.join(" "))
            } else {
                format!("write {} ({} bytes, segmented)", name(dict, idx, sub), u32_at(d, 4))
            }
        }
        (false, 2) => format!("read {}", name(dict, idx, sub)),
        (false, 0) => "download segment".to_owned(),
        (false, 3) => "upload segment request".to_owned(),
        (false, 5) => "block upload".to_owned(),
        (false, 6) => format!("block download {}", name(dict, idx, sub)),
        (true, 2) => {
            if d[0] & EXPEDITED != 0 {
                let n = expedited_n(d[0]);
                let mut b = [0u8; 4];
                b[..n].copy_from_slice(&d[4..4 + n]);
                let v = u32::from_le_bytes(b);
                format!("{} = {v} (0x{v:0w$X})", name(dict, idx, sub), w = n * 2)
            } else {
                format!("{} is {} bytes (segmented)", name(dict, idx, sub), u32_at(d, 4))
            }
        }
        (true, 3) => format!("written {}", name(dict, idx, sub)),
        (true, 0) => "upload segment".to_owned(),
        (true, 1) => "download segment ack".to_owned(),
        (true, 5) => "block download response".to_owned(),
        (true, 6) => "block upload response".to_owned(),
        _ => format!("cs {:02X}h", d[0]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_entry_is_found_and_cut_from_its_pdo() {
        let map = [PdoMapEntry::new(0x6041, 0, 16), PdoMapEntry::new(0x6064, 0, 32)];
        assert_eq!(mapped_at(&map, 0x6064, 0), Some((16, 32)));
        assert_eq!(mapped_at(&map, 0x606C, 0), None);
        let data = [0x37, 0x02, 0xA0, 0x0F, 0x00, 0x00];
        assert_eq!(entry_bytes(&data, 16, 32), Some(vec![0xA0, 0x0F, 0, 0]));
        // Short frame, partial byte.
        assert_eq!(entry_bytes(&data[..4], 16, 32), None);
        assert_eq!(entry_bytes(&data, 0, 4), None);
    }

    #[test]
    fn decodes_the_predefined_connection_set() {
        let d = |id: u16, data: &[u8]| decode(&Frame::new(id, data), &Dict::default(), &PdoMaps::new());
        assert_eq!(d(0x000, &[0x01, 0x05]), "NMT start → node 5");
        assert_eq!(d(0x000, &[0x81, 0x00]), "NMT reset node → all nodes");
        assert_eq!(d(0x080, &[]), "SYNC");
        assert_eq!(d(0x080, &[7]), "SYNC counter 7");
        assert_eq!(d(0x705, &[0x00]), "boot-up node 5");
        assert_eq!(d(0x705, &[0x7F]), "heartbeat node 5: pre-operational");
        assert_eq!(d(0x705, &[0x05]), "heartbeat node 5: operational");
        assert!(d(0x085, &[0x11, 0x86, 0x20, 0, 0, 0, 0, 0]).starts_with("EMCY node 5: 8611h"));
        assert_eq!(d(0x185, &[0x37, 0x02]), "TPDO1 node 5: 37 02");
        assert_eq!(d(0x305, &[0x0F, 0x00]), "RPDO2 node 5: 0F 00");
        assert_eq!(
            d(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]),
            "SDO master → node 5: read 1000h:00 (Device type)"
        );
        assert_eq!(
            d(0x585, &[0x43, 0x00, 0x10, 0, 0x92, 0x01, 0x02, 0x00]),
            "SDO node 5 → master: 1000h:00 (Device type) = 131474 (0x00020192)"
        );
        assert_eq!(
            d(0x605, &[0x2B, 0x17, 0x10, 0, 0x64, 0x00, 0, 0]),
            "SDO master → node 5: write 1017h:00 (Producer heartbeat time) = 64 00"
        );
        // e = 1, s = 0: the size is not indicated, so all 4 bytes are shown
        // (they used to be cut to one).
        assert_eq!(
            d(0x605, &[0x22, 0x17, 0x10, 0, 0x64, 0x00, 0, 0]),
            "SDO master → node 5: write 1017h:00 (Producer heartbeat time) = 64 00 00 00"
        );
        assert!(
            d(0x585, &[0x80, 0x00, 0x20, 0, 0x00, 0x00, 0x02, 0x06])
                .contains("abort 2000h:00 code 0x06020000 Object does not exist")
        );
        // Short or odd frames never panic.
        for id in [0x000u16, 0x080, 0x085, 0x185, 0x585, 0x605, 0x705, 0x7E4, 0x7E5, 0x123] {
            for len in 0..=8 {
                let _ = d(id, &[0xFF; 8][..len]);
            }
        }
    }

    #[test]
    fn object_names_come_from_the_eds() {
        let dict = Dict { eds: Some(drivebus_personality::Profile::Akd.parse_eds().eds) };
        let s = decode(&Frame::new(0x601, &[0x40, 0x41, 0x60, 0, 0, 0, 0, 0]), &dict, &PdoMaps::new());
        assert!(s.starts_with("SDO master → node 1: read 6041h:00 ("), "{s}");
    }

    #[test]
    fn pdos_decoded_by_their_mapping() {
        let mut maps = PdoMaps::new();
        maps.insert(
            0x185,
            ("TPDO1 node 5".into(), vec![PdoMapEntry::new(0x6041, 0, 16), PdoMapEntry::new(0x6064, 0, 32)]),
        );
        let s = decode(&Frame::new(0x185, &[0x37, 0x02, 0xFE, 0xFF, 0xFF, 0xFF]), &Dict::default(), &maps);
        assert_eq!(s, "TPDO1 node 5: Statusword = 0x0237 (operation enabled), Position actual value = -2");
        // Short frames and bit-sized entries never panic.
        let s = decode(&Frame::new(0x185, &[0x37]), &Dict::default(), &maps);
        assert!(s.contains("too short"), "{s}");
        maps.insert(
            0x190,
            ("x".into(), vec![PdoMapEntry::new(0x2000, 0, 1), PdoMapEntry::new(0x2001, 0, 7)]),
        );
        let s = decode(&Frame::new(0x190, &[0x03]), &Dict::default(), &maps);
        assert_eq!(s, "x: 2000h:00 = 1, 2001h:00 = 1");
        // Plain numbers for CSV, one column per mapped object.
        let m = &maps[&0x185];
        assert_eq!(
            pdo_columns(&Dict::default(), m),
            ["TPDO1 node 5 6041h:00 Statusword", "TPDO1 node 5 6064h:00 Position actual value"]
        );
        let f = Frame::new(0x185, &[0x37, 0x02, 0xFE, 0xFF, 0xFF, 0xFF]);
        assert_eq!(pdo_numbers(&f, &Dict::default(), &m.1), [Some("567".into()), Some("-2".into())]);
        assert_eq!(pdo_numbers(&Frame::new(0x185, &[0x37, 0x02]), &Dict::default(), &m.1)[1], None);
    }
}
