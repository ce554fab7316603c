//! The object dictionary a described device serves over CoE: the ESI's
//! `Dictionary/Objects` where the description has one, else the objects
//! a master needs, made from what the description says (device type,
//! name, identity, sync manager types, PDO mapping and assignment, and
//! the mapped objects themselves).

use crate::description::{EsiPdo, SlaveDescription, SmKind};
use crate::model::{EsiObject, EsiSub, ObjectKind};
use drivebus_coe::access_bits::{READ, RXPDO, TXPDO, WRITE};
use drivebus_od::{Access, DataType, Object, ObjectCode, ObjectDictionary, SubObject};
use std::collections::BTreeMap;

impl EsiObject {
    /// The dictionary object: access from the access word (writable →
    /// `rw`, `rww` or `rwr` by the PDO direction it maps into), PDO
    /// mappable if it maps in either direction, defaults and limits as
    /// described (a default of the wrong length is zero-filled).
    pub fn to_object(&self) -> Object {
        let code = match self.kind {
            ObjectKind::Var if self.subs.first().is_some_and(|s| s.data_type == DataType::Domain) => {
                ObjectCode::Domain
            }
            ObjectKind::Var => ObjectCode::Var,
            ObjectKind::Array => ObjectCode::Array,
            ObjectKind::Record => ObjectCode::Record,
        };
        let mut o = Object::with_code(self.index, code, self.name.clone());
        for s in &self.subs {
            o = o.with_sub(s.to_sub_object());
        }
        o
    }
}

impl EsiSub {
    /// The dictionary entry, see [`EsiObject::to_object`].
    pub fn to_sub_object(&self) -> SubObject {
        let a = self.access;
        let access = match (a & WRITE != 0, a & READ != 0, a & (RXPDO | TXPDO)) {
            (false, _, _) => Access::Ro,
            (true, false, _) => Access::Wo,
            (true, true, m) if m == RXPDO => Access::Rww,
            (true, true, m) if m == TXPDO => Access::Rwr,
            (true, true, _) => Access::Rw,
        };
        let fit = |v: &[u8]| match self.data_type.fixed_size() {
            Some(n) => {
                let mut v = v.to_vec();
                v.resize(n, 0);
                v
            }
            None => v.to_vec(),
        };
        let mut s =
            SubObject::from_bytes(self.sub, self.name.clone(), self.data_type, access, fit(&self.default));
        s.pdo_mappable = a & (RXPDO | TXPDO) != 0;
        let n = self.data_type.fixed_size();
        let limit = |v: &Option<Vec<u8>>| v.clone().filter(|v| n.is_some_and(|n| n == v.len()));
        s.low_limit = limit(&self.min);
        s.high_limit = limit(&self.max);
        if n.is_none() && self.len > 0 {
            s = s.max_len(self.len.max(self.default.len()));
        }
        s
    }
}

/// The objects `d`'s device serves: its own dictionary, completed by the
/// objects of [`objects_from_description`] it lacks (an ESI without 1C00h
/// still describes its SM types, and SOEM reads them), in index order.
pub fn device_objects(d: &SlaveDescription) -> Vec<EsiObject> {
    let mut all: BTreeMap<u16, EsiObject> =
        objects_from_description(d).into_iter().map(|o| (o.index, o)).collect();
    all.extend(d.objects.iter().map(|o| (o.index, o.clone())));
    all.into_values().collect()
}

/// The dictionary of `objects`.
pub fn dictionary(objects: &[EsiObject]) -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    for o in objects {
        od.insert(o.to_object());
    }
    od
}

fn sub(sub: u8, name: &str, data_type: DataType, access: u16, default: Vec<u8>) -> EsiSub {
    let len = data_type.fixed_size().unwrap_or(default.len());
    EsiSub { sub, name: name.into(), data_type, len, access, default, min: None, max: None }
}

fn var(index: u16, name: &str, data_type: DataType, default: Vec<u8>) -> EsiObject {
    EsiObject {
        index,
        name: name.into(),
        kind: ObjectKind::Var,
        subs: vec![sub(0, name, data_type, READ, default)],
    }
}

fn array(index: u16, name: &str, data_type: DataType, values: &[Vec<u8>]) -> EsiObject {
    let mut subs = vec![sub(0, "SubIndex 000", DataType::Unsigned8, READ, vec![values.len() as u8])];
    for (i, v) in values.iter().enumerate() {
        subs.push(sub(i as u8 + 1, &format!("SubIndex {:03}", i + 1), data_type, READ, v.clone()));
    }
    EsiObject { index, name: name.into(), kind: ObjectKind::Array, subs }
}

/// The type of a mapped entry: the one the description names, else the
/// unsigned type of its length (BOOLEAN for one bit).
fn entry_type(data_type: Option<DataType>, bits: u8) -> DataType {
    data_type.filter(|t| t.fixed_size().is_some()).unwrap_or(match bits {
        1 => DataType::Boolean,
        2..=8 => DataType::Unsigned8,
        9..=16 => DataType::Unsigned16,
        17..=32 => DataType::Unsigned32,
        _ => DataType::Unsigned64,
    })
}

/// The objects a master reads from a CoE device, made from a description
/// without a dictionary (an SII image): 1000h device type, 1008h name,
/// 1018h identity, 1C00h sync manager types, the mapping objects with
/// their default mapping, the assignment objects 1C10h + n of the process
/// data SMs, and the mapped objects (RxPDO entries `rww`, TxPDO entries
/// `ro`, both mappable, zero). All read-only but the mapped outputs: the
/// mapping stays the described default.
pub fn objects_from_description(d: &SlaveDescription) -> Vec<EsiObject> {
    let mut out: BTreeMap<u16, EsiObject> = BTreeMap::new();
    let device_type = u32::from(d.profile.number) | (u32::from(d.profile.add_info) << 16);
    out.insert(0x1000, var(0x1000, "Device type", DataType::Unsigned32, device_type.to_le_bytes().to_vec()));
    let name = if d.type_name.is_empty() { &d.name } else { &d.type_name };
    out.insert(0x1008, var(0x1008, "Device name", DataType::VisibleString, name.as_bytes().to_vec()));
    let mut id =
        EsiObject { index: 0x1018, name: "Identity".into(), kind: ObjectKind::Record, subs: Vec::new() };
    id.subs.push(sub(0, "Number of entries", DataType::Unsigned8, READ, vec![4]));
    for (i, (n, v)) in [
        ("Vendor ID", d.vendor_id),
        ("Product code", d.product_code),
        ("Revision", d.revision),
        ("Serial number", d.serial),
    ]
    .into_iter()
    .enumerate()
    {
        id.subs.push(sub(i as u8 + 1, n, DataType::Unsigned32, READ, v.to_le_bytes().to_vec()));
    }
    out.insert(0x1018, id);
    let types: Vec<Vec<u8>> = d.sync_managers.iter().map(|s| vec![s.kind.code()]).collect();
    out.insert(0x1C00, array(0x1C00, "Sync manager type", DataType::Unsigned8, &types));
    for (n, s) in d.sync_managers.iter().enumerate() {
        let pdos = match s.kind {
            SmKind::Outputs => &d.rx_pdos,
            SmKind::Inputs => &d.tx_pdos,
            _ => continue,
        };
        let assigned: Vec<Vec<u8>> =
            pdos.iter().filter(|p| p.sm == Some(n as u8)).map(|p| p.index.to_le_bytes().to_vec()).collect();
        let index = 0x1C10 + n as u16;
        out.insert(index, array(index, &format!("SM{n} PDO assignment"), DataType::Unsigned16, &assigned));
    }
    for (pdos, access) in [(&d.rx_pdos, READ | WRITE | RXPDO), (&d.tx_pdos, READ | TXPDO)] {
        for p in pdos.iter() {
            out.insert(p.index, mapping(p));
            mapped(&mut out, p, access);
        }
    }
    out.into_values().collect()
}

fn mapping(p: &EsiPdo) -> EsiObject {
    let values: Vec<Vec<u8>> = p
        .entries
        .iter()
        .map(|e| {
            ((u32::from(e.index) << 16) | (u32::from(e.sub) << 8) | u32::from(e.bit_len))
                .to_le_bytes()
                .to_vec()
        })
        .collect();
    let name = if p.name.is_empty() { format!("PDO {:04X}h", p.index) } else { p.name.clone() };
    EsiObject { kind: ObjectKind::Record, ..array(p.index, &name, DataType::Unsigned32, &values) }
}

/// Adds the objects `p` maps (index 0 is a gap), keeping what is there.
fn mapped(out: &mut BTreeMap<u16, EsiObject>, p: &EsiPdo, access: u16) {
    for e in p.entries.iter().filter(|e| e.index != 0) {
        // Objects below 2000h are communication objects, not process data.
        if e.index < 0x2000 {
            continue;
        }
        let t = entry_type(e.data_type, e.bit_len);
        let name =
            if e.name.is_empty() { format!("Entry {:04X}h:{:02X}", e.index, e.sub) } else { e.name.clone() };
        let zero = vec![0; t.fixed_size().unwrap_or(0)];
        let o = out.entry(e.index).or_insert_with(|| EsiObject {
            index: e.index,
            name: if e.sub == 0 { name.clone() } else { p.name.clone() },
            kind: if e.sub == 0 { ObjectKind::Var } else { ObjectKind::Record },
            subs: if e.sub == 0 {
                Vec::new()
            } else {
                vec![sub(0, "SubIndex 000", DataType::Unsigned8, READ, vec![0])]
            },
        });
        if o.subs.iter().all(|s| s.sub != e.sub) {
            o.subs.push(sub(e.sub, &name, t, access, zero));
            o.subs.sort_by_key(|s| s.sub);
        }
        if o.kind == ObjectKind::Record {
            let highest = o.subs.last().map_or(0, |s| s.sub);
            if let Some(s0) = o.subs.first_mut().filter(|s| s.sub == 0 && s.data_type == DataType::Unsigned8)
            {
                s0.default = vec![highest];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::PdoEntry;

    fn el2004_like() -> SlaveDescription {
        let xml = "<EtherCATInfo><Vendor><Id>2</Id></Vendor><Descriptions><Devices><Device>\
            <Type ProductCode='#x07d43052' RevisionNo='#x00100000'>EL2004</Type>\
            <Sm StartAddress='#x1000' ControlByte='#x26' Enable='1' DefaultSize='128'>MBoxOut</Sm>\
            <Sm StartAddress='#x1080' ControlByte='#x22' Enable='1' DefaultSize='128'>MBoxIn</Sm>\
            <Sm StartAddress='#x0f00' ControlByte='#x44' Enable='1'>Outputs</Sm>\
            </Device></Devices></Descriptions></EtherCATInfo>";
        let mut d = crate::read(xml).unwrap();
        d.rx_pdos = (0..4u16)
            .map(|i| EsiPdo {
                index: 0x1600 + i,
                name: format!("Channel {}", i + 1),
                sm: Some(2),
                fixed: true,
                mandatory: true,
                entries: vec![PdoEntry {
                    index: 0x7000 + 0x10 * i,
                    sub: 1,
                    bit_len: 1,
                    name: "Output".into(),
                    data_type: Some(DataType::Boolean),
                }],
            })
            .collect();
        d
    }

    #[test]
    fn objects_made_from_pdos() {
        let d = el2004_like();
        let od = dictionary(&objects_from_description(&d));
        assert_eq!(od.get_u32(0x1018, 1), Some(d.vendor_id));
        assert_eq!(od.get_u32(0x1C12, 0), Some(4), "four PDOs assigned to SM2");
        assert_eq!(od.get_u32(0x1C12, 4), Some(0x1603));
        assert_eq!(od.get_u32(0x1601, 1), Some(0x7010_0101));
        let out = od.get(0x7030, 1).unwrap();
        assert_eq!((out.data_type, out.access, out.pdo_mappable), (DataType::Boolean, Access::Rww, true));
        assert_eq!(od.get_u32(0x7030, 0), Some(1), "sub 0: highest sub-index");
    }

    #[test]
    fn a_dictionary_is_completed_not_replaced() {
        let mut d = el2004_like();
        d.objects = vec![var(0x1000, "Device type", DataType::Unsigned32, vec![0x92, 1, 0, 0])];
        let all = device_objects(&d);
        assert_eq!(
            all.iter().find(|o| o.index == 0x1000).unwrap().subs[0].default,
            [0x92, 1, 0, 0],
            "the ESI's"
        );
        assert!(all.iter().any(|o| o.index == 0x1C00), "SM types added");
        assert!(all.windows(2).all(|w| w[0].index < w[1].index));
    }

    #[test]
    fn sub_object_access_from_the_word() {
        let s = |access| sub(1, "x", DataType::Unsigned16, access, vec![1]).to_sub_object();
        assert_eq!(s(READ).access, Access::Ro);
        assert_eq!(s(READ | WRITE | RXPDO).access, Access::Rww);
        assert_eq!(s(READ | WRITE | TXPDO).access, Access::Rwr);
        assert_eq!(s(READ | WRITE).access, Access::Rw);
        assert_eq!(s(READ).bytes(), [1, 0], "short default zero-filled");
    }
}
