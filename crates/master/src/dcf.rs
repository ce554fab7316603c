//! A live node's dictionary as a DCF (CiA 306): every readable entry of a
//! template (the node's EDS, or the CiA 301/402 standard objects the node
//! has) uploaded by SDO, then `drivebus_eds::dcf` makes the DCF model
//! (`ParameterValue`s, `[DeviceComissioning]`) and `drivebus_eds::write`
//! turns it into text.

use std::collections::BTreeMap;

use drivebus_eds::{Commissioning, Eds, EdsObject, EdsVar};
use drivebus_objects::Kind;
use drivebus_od::{DataType, ObjectCode, SdoAbort};

use crate::master::Master;
use crate::sdo::{SdoError, SdoHandle};

/// What a dump read and what it left out.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DumpReport {
    /// Entries read and written as `ParameterValue`.
    pub read: usize,
    /// Entries the node refused to read (write-only, aborted): index, sub, abort.
    pub refused: Vec<(u16, u8, SdoAbort)>,
    /// Entries whose value has another size than their data type (the
    /// node's object differs from the template): index, sub, bytes read.
    /// No value is written for them.
    pub mismatched: Vec<(u16, u8, usize)>,
}

fn missing(e: &SdoError) -> bool {
    matches!(e.abort_code(), Some(c) if c == SdoAbort::NO_OBJECT || c == SdoAbort::NO_SUB_INDEX)
}

/// Values read so far, by index and sub-index, as the SDO upload gave them.
type Values = BTreeMap<(u16, u8), Vec<u8>>;

/// Uploads one entry into `values`; `Ok(false)` when the entry does not
/// exist. Write-only entries and DOMAINs are not read (a DCF keeps no
/// value for them, and a DOMAIN may be megabytes: 1021h, 1F50h).
async fn fill(
    sdo: &SdoHandle,
    index: u16,
    sub: u8,
    var: &EdsVar,
    values: &mut Values,
    report: &mut DumpReport,
) -> Result<bool, SdoError> {
    if !var.access.readable() || DataType::from_index(var.data_type) == Some(DataType::Domain) {
        return Ok(true);
    }
    match sdo.upload(index, sub).await {
        Ok(data) => {
            let size = DataType::from_index(var.data_type).and_then(DataType::fixed_size);
            if size.is_some_and(|n| n != data.len()) {
                report.mismatched.push((index, sub, data.len()));
            } else {
                values.insert((index, sub), data);
                report.read += 1;
            }
            Ok(true)
        }
        Err(e) if missing(&e) => Ok(false),
        Err(SdoError::Abort { code, .. }) => {
            report.refused.push((index, sub, code));
            Ok(true)
        }
        Err(e) => Err(e),
    }
}

fn var_of(e: &drivebus_objects::EntryInfo) -> EdsVar {
    let mut v = EdsVar::new(e.name().into_owned(), e.data_type as u16, e.access);
    v.pdo_mapping = e.pdo;
    v
}

/// The DCF text model: `template` with `values` as `ParameterValue`s and
/// `[DeviceComissioning]`, written by `drivebus_eds::dcf` (compact objects
/// expanded, `LastEDS`, values that fit CiA 306).
fn finish(template: &Eds, node: u8, values: &Values) -> Eds {
    let commissioning = Commissioning { node_id: node, ..Commissioning::default() };
    drivebus_eds::dcf(template, commissioning, |index, sub, _| values.get(&(index, sub)).cloned())
}

impl Master {
    /// Reads every readable entry of `template` (an EDS of the node) from
    /// `node` and returns the node's DCF: the EDS with the values as
    /// `ParameterValue`s and `[DeviceComissioning]` (`drivebus_eds::dcf`).
    /// Entries the node does not have are dropped from the result.
    pub async fn dump_dcf(&self, node: u8, mut template: Eds) -> Result<(Eds, DumpReport), SdoError> {
        let sdo = self.sdo(node);
        let mut report = DumpReport::default();
        let mut values = Values::new();
        let mut absent: Vec<(u16, Vec<u8>)> = Vec::new();
        for (index, obj) in &template.objects {
            // A VAR is its own sub 0; records, arrays and compact objects
            // have their sub-objects listed.
            let entries: Vec<(u8, &EdsVar)> = if obj.subs.is_empty() {
                obj.var.iter().map(|v| (0, v)).collect()
            } else {
                obj.subs.iter().map(|(k, v)| (*k, v)).collect()
            };
            let mut lacks = Vec::new();
            for (sub, var) in entries {
                if !fill(&sdo, *index, sub, var, &mut values, &mut report).await? {
                    lacks.push(sub);
                }
            }
            if !lacks.is_empty() {
                absent.push((*index, lacks));
            }
        }
        for (index, subs) in absent {
            let Some(obj) = template.objects.get_mut(&index) else { continue };
            if subs.contains(&0) {
                template.objects.remove(&index);
                for list in [&mut template.mandatory, &mut template.optional, &mut template.manufacturer] {
                    list.retain(|i| *i != index);
                }
                continue;
            }
            for s in subs {
                obj.subs.remove(&s);
            }
        }
        Ok((finish(&template, node, &values), report))
    }

    /// Like [`dump_dcf`](Self::dump_dcf) without an EDS: the CiA 301/402
    /// standard objects the node answers for (manufacturer objects need
    /// the node's EDS). PDO and SDO parameter runs are read up to the first
    /// one the node lacks.
    pub async fn dump_standard_dcf(&self, node: u8) -> Result<(Eds, DumpReport), SdoError> {
        let sdo = self.sdo(node);
        let mut report = DumpReport::default();
        let mut values = Values::new();
        let mut objects = BTreeMap::new();
        for def in drivebus_objects::defs() {
            for index in def.first..=def.last {
                let Some(info) = drivebus_objects::object(index) else { break };
                let Some(obj) = probe_object(&sdo, info, &mut values, &mut report).await? else { break };
                objects.insert(index, obj);
            }
        }
        let mut eds = Eds { objects, ..Eds::default() };
        // CiA 306 §4.6: tools find the objects through these lists.
        for &index in eds.objects.keys() {
            match index {
                0x1000 | 0x1001 | 0x1018 => eds.mandatory.push(index),
                0x2000..=0x5FFF => eds.manufacturer.push(index),
                _ => eds.optional.push(index),
            }
        }
        let info = &mut eds.device_info;
        info.product_name = sdo.read::<String>(0x1008, 0).await.unwrap_or_else(|_| format!("node {node}"));
        info.vendor_number = sdo.read::<u32>(0x1018, 1).await.ok();
        info.product_number = sdo.read::<u32>(0x1018, 2).await.ok();
        info.revision_number = sdo.read::<u32>(0x1018, 3).await.ok();
        let count = |base: u16| eds.objects.range(base..base + 0x200).count() as u16;
        eds.device_info.nr_of_rx_pdo = count(0x1400);
        eds.device_info.nr_of_tx_pdo = count(0x1800);
        Ok((finish(&eds, node, &values), report))
    }
}

async fn probe_object(
    sdo: &SdoHandle,
    info: drivebus_objects::ObjectInfo,
    values: &mut Values,
    report: &mut DumpReport,
) -> Result<Option<EdsObject>, SdoError> {
    let index = info.index;
    let code = match info.def.kind {
        Kind::Var => ObjectCode::Var,
        Kind::Array => ObjectCode::Array,
        Kind::Record => ObjectCode::Record,
    };
    let mut obj = EdsObject {
        index,
        name: info.name().into_owned(),
        object_type: code,
        sub_number: None,
        compact_sub_obj: None,
        obj_flags: 0,
        var: None,
        subs: BTreeMap::new(),
        compact_names: BTreeMap::new(),
        compact_values: BTreeMap::new(),
        line: 0,
    };
    let Some(zero) = info.entry(0) else { return Ok(None) };
    if info.def.kind == Kind::Var {
        // A DOMAIN VAR (1021h …) is not read, so nothing proves it exists;
        // a DCF would hold no value for it anyway.
        if zero.data_type == DataType::Domain {
            return Ok(None);
        }
        let v = var_of(&zero);
        if !fill(sdo, index, 0, &v, values, report).await? {
            return Ok(None);
        }
        // Not the standard's VAR (an array on this node): without the
        // node's EDS nothing describes it.
        if report.mismatched.last().is_some_and(|m| (m.0, m.1) == (index, 0)) {
            return Ok(None);
        }
        // A write-only VAR cannot prove it exists: keep it only when read.
        if !values.contains_key(&(index, 0)) && !zero.access.readable() {
            return Ok(None);
        }
        obj.var = Some(v);
        return Ok(Some(obj));
    }
    let v0 = var_of(&zero);
    if !fill(sdo, index, 0, &v0, values, report).await? {
        return Ok(None);
    }
    let highest = values.get(&(index, 0)).and_then(|b| b.first().copied()).unwrap_or(0);
    obj.subs.insert(0, v0);
    for e in info.entries().filter(|e| e.sub != 0 && e.sub <= highest) {
        let v = var_of(&e);
        if fill(sdo, index, e.sub, &v, values, report).await? {
            obj.subs.insert(e.sub, v);
        }
    }
    obj.sub_number = Some(obj.subs.len() as u8);
    Ok(Some(obj))
}
