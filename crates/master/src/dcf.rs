//! A live node's dictionary as a DCF (CiA 306): every readable entry of a
//! template (the node's EDS, or the CiA 301/402 standard objects the node
//! has) uploaded by SDO and written as its `ParameterValue`, plus the
//! `[DeviceComissioning]` section. `drivebus_eds::write` turns it into text.

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
}

fn missing(e: &SdoError) -> bool {
    matches!(e.abort_code(), Some(c) if c == SdoAbort::NO_OBJECT || c == SdoAbort::NO_SUB_INDEX)
}

/// Uploads one entry into `var.parameter_value`; `Ok(false)` when the
/// entry does not exist.
async fn fill(
    sdo: &SdoHandle,
    index: u16,
    sub: u8,
    var: &mut EdsVar,
    report: &mut DumpReport,
) -> Result<bool, SdoError> {
    if !var.access.readable() {
        return Ok(true);
    }
    match sdo.upload(index, sub).await {
        Ok(data) => {
            let text = match DataType::from_index(var.data_type) {
                Some(dt) => drivebus_eds::format_value(dt, &data),
                None => data.iter().map(|b| format!("{b:02X}")).collect(),
            };
            var.parameter_value = Some(text);
            report.read += 1;
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

impl Master {
    /// Reads every readable entry of `template` (an EDS of the node) from
    /// `node` into its `ParameterValue`s and adds `[DeviceComissioning]`.
    /// Entries the node does not have are dropped from the result.
    pub async fn dump_dcf(&self, node: u8, mut template: Eds) -> Result<(Eds, DumpReport), SdoError> {
        let sdo = self.sdo(node);
        let mut report = DumpReport::default();
        let mut gone = Vec::new();
        for (index, obj) in template.objects.iter_mut() {
            if let Some(v) = &mut obj.var {
                if !fill(&sdo, *index, 0, v, &mut report).await? {
                    gone.push(*index);
                }
                continue;
            }
            let mut absent = Vec::new();
            for (sub, v) in obj.subs.iter_mut() {
                if !fill(&sdo, *index, *sub, v, &mut report).await? {
                    absent.push(*sub);
                }
            }
            if absent.contains(&0) {
                gone.push(*index);
            }
            for s in absent {
                obj.subs.remove(&s);
            }
        }
        for i in gone {
            template.objects.remove(&i);
        }
        template.commissioning = Some(Commissioning { node_id: node, ..Commissioning::default() });
        Ok((template, report))
    }

    /// Like [`dump_dcf`](Self::dump_dcf) without an EDS: the CiA 301/402
    /// standard objects the node answers for (manufacturer objects need
    /// the node's EDS). PDO and SDO parameter runs are read up to the first
    /// one the node lacks.
    pub async fn dump_standard_dcf(&self, node: u8) -> Result<(Eds, DumpReport), SdoError> {
        let sdo = self.sdo(node);
        let mut report = DumpReport::default();
        let mut objects = BTreeMap::new();
        for def in drivebus_objects::defs() {
            for index in def.first..=def.last {
                let Some(info) = drivebus_objects::object(index) else { break };
                let Some(obj) = self.probe_object(&sdo, info, &mut report).await? else { break };
                objects.insert(index, obj);
            }
        }
        let mut eds = Eds { objects, ..Eds::default() };
        let info = &mut eds.device_info;
        info.product_name = sdo.read::<String>(0x1008, 0).await.unwrap_or_else(|_| format!("node {node}"));
        info.vendor_number = sdo.read::<u32>(0x1018, 1).await.ok();
        info.product_number = sdo.read::<u32>(0x1018, 2).await.ok();
        info.revision_number = sdo.read::<u32>(0x1018, 3).await.ok();
        let count = |base: u16| eds.objects.range(base..base + 0x200).count() as u16;
        eds.device_info.nr_of_rx_pdo = count(0x1400);
        eds.device_info.nr_of_tx_pdo = count(0x1800);
        eds.commissioning = Some(Commissioning { node_id: node, ..Commissioning::default() });
        Ok((eds, report))
    }

    async fn probe_object(
        &self,
        sdo: &SdoHandle,
        info: drivebus_objects::ObjectInfo,
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
            let mut v = var_of(&zero);
            if !fill(sdo, index, 0, &mut v, report).await? {
                return Ok(None);
            }
            // A write-only VAR cannot prove it exists: keep it only when read.
            if v.parameter_value.is_none() && !zero.access.readable() {
                return Ok(None);
            }
            obj.var = Some(v);
            return Ok(Some(obj));
        }
        let mut v0 = var_of(&zero);
        if !fill(sdo, index, 0, &mut v0, report).await? {
            return Ok(None);
        }
        let highest = v0
            .parameter_value
            .as_deref()
            .and_then(|t| u8::from_str_radix(t.trim_start_matches("0x"), 16).ok())
            .unwrap_or(0);
        obj.subs.insert(0, v0);
        for e in info.entries().filter(|e| e.sub != 0 && e.sub <= highest) {
            let mut v = var_of(&e);
            if fill(sdo, index, e.sub, &mut v, report).await? {
                obj.subs.insert(e.sub, v);
            }
        }
        obj.sub_number = Some(obj.subs.len() as u8);
        Ok(Some(obj))
    }
}
