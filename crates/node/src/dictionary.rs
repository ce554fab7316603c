//! Building the communication area of a node's dictionary.

use crate::config::NodeConfig;
use alloc::vec::Vec;
use drivebus_emcy::{Emcy, EmcyConsumer};
use drivebus_od::{Access, DataType, Object, ObjectDictionary, SubObject, Value, le_u64};
use drivebus_sync::{SyncService, TimeService};

/// The objects a node with `cfg` has, with CiA 301 defaults for `node_id`.
pub fn build_dictionary(cfg: &NodeConfig, node_id: u8) -> ObjectDictionary {
    // COB-ID defaults need a real node-ID; an unconfigured node uses 1
    // until LSS gives it one (the defaults are rebased then).
    let id = if (1..=127).contains(&node_id) { node_id } else { 1 };
    let mut od = ObjectDictionary::new();
    od.insert(Object::var(
        0x1000,
        "Device type",
        DataType::Unsigned32,
        Access::Ro,
        Value::U32(cfg.device_type),
    ));
    Emcy::install(&mut od, id, cfg.emcy_history);
    SyncService::install(&mut od, id);
    // Optional objects a device may lack: the services keep their
    // power-on setting (no inhibit time, no window, no counter).
    for (present, index) in [
        (cfg.emcy_inhibit, drivebus_emcy::OD_INHIBIT_TIME_EMCY),
        (cfg.sync_window, drivebus_sync::OD_SYNC_WINDOW),
        (cfg.sync_counter, drivebus_sync::OD_SYNC_COUNTER_OVERFLOW),
    ] {
        if !present {
            od.remove(index);
        }
    }
    for (index, name, text) in [
        (0x1008, "Manufacturer device name", &cfg.device_name),
        (0x1009, "Manufacturer hardware version", &cfg.hardware_version),
        (0x100A, "Manufacturer software version", &cfg.software_version),
    ] {
        if let Some(t) = text {
            od.insert(Object::var(
                index,
                name,
                DataType::VisibleString,
                Access::Const,
                Value::Str(t.clone()),
            ));
        }
    }
    let mut nmt = cfg.nmt;
    nmt.node_id = id;
    drivebus_nmt::install(&mut od, &nmt, cfg.heartbeat_consumers);
    if cfg.error_classes > 0 {
        drivebus_nmt::install_error_behaviour(&mut od, cfg.error_classes);
    }
    if cfg.store_restore {
        install_store_restore(&mut od);
    }
    if cfg.time {
        TimeService::install(&mut od);
    }
    #[cfg(feature = "std")]
    if cfg.eds_object {
        install_eds_objects(&mut od);
    }
    install_identity(&mut od, &cfg.identity);
    if cfg.emcy_consumers > 0 {
        EmcyConsumer::install(&mut od, cfg.emcy_consumers);
    }
    drivebus_sdo::server::install_server_params(&mut od, id, 1 + cfg.extra_sdo_servers);
    if !cfg.sdo_server_param {
        od.remove(drivebus_sdo::server::FIRST_PARAM_INDEX);
    }
    let mut pdo = cfg.pdo;
    pdo.node_id = id;
    drivebus_pdo::install(&mut od, &pdo);
    od
}

/// 1010h and 1011h: store and restore on command, for every area.
fn install_store_restore(od: &mut ObjectDictionary) {
    for (index, name) in [(0x1010, "Store parameters"), (0x1011, "Restore default parameters")] {
        let mut o = Object::array(index, name, DataType::Unsigned32, Access::Rw, 4, Value::U32(1));
        for (sub, n) in [
            (1, "all parameters"),
            (2, "communication parameters"),
            (3, "application parameters"),
            (4, "manufacturer parameters"),
        ] {
            // Reads give the capability (bit 0: on command), writes take a signature.
            o = o.with_sub(
                SubObject::new(
                    sub,
                    alloc::format!("{name}: {n}"),
                    DataType::Unsigned32,
                    Access::Rw,
                    Value::U32(1),
                )
                .hooked()
                .persist(drivebus_od::PersistGroup::Volatile),
            );
        }
        od.insert(o);
    }
}

/// 1021h and 1022h: the device description, read like any DOMAIN
/// (CiA 301 §7.5.2.21).
#[cfg(feature = "std")]
fn install_eds_objects(od: &mut ObjectDictionary) {
    od.insert(
        Object::with_code(0x1021, drivebus_od::ObjectCode::Domain, "Store EDS").with_sub(
            SubObject::new(
                0,
                "Store EDS",
                DataType::Domain,
                Access::Ro,
                Value::Bytes(alloc::vec::Vec::new()),
            )
            .hooked(),
        ),
    );
    od.insert(Object::var(0x1022, "Storage format", DataType::Unsigned8, Access::Ro, Value::U8(0)));
}

/// 1018h from the node's identity.
fn install_identity(od: &mut ObjectDictionary, ident: &drivebus_can::Identity) {
    od.insert(
        Object::record(0x1018, "Identity object")
            .with_sub(SubObject::new(
                1,
                "Vendor-ID",
                DataType::Unsigned32,
                Access::Ro,
                Value::U32(ident.vendor_id),
            ))
            .with_sub(SubObject::new(
                2,
                "Product code",
                DataType::Unsigned32,
                Access::Ro,
                Value::U32(ident.product_code),
            ))
            .with_sub(SubObject::new(
                3,
                "Revision number",
                DataType::Unsigned32,
                Access::Ro,
                Value::U32(ident.revision),
            ))
            .with_sub(SubObject::new(
                4,
                "Serial number",
                DataType::Unsigned32,
                Access::Ro,
                Value::U32(ident.serial),
            )),
    );
}

/// Bring a dictionary from elsewhere (an EDS) up to what the services
/// need: objects it lacks are added from `generated`; sub-objects it has
/// keep their description and value but take the service as their owner.
pub fn merge_services(od: &mut ObjectDictionary, generated: &ObjectDictionary) {
    for g in generated.objects() {
        if od.object(g.index).is_none() {
            od.insert(g.clone());
            continue;
        }
        for gs in g.subs() {
            if let Some(s) = od.get_mut(g.index, gs.sub) {
                if gs.owner != drivebus_od::Owner::NONE {
                    s.owner = gs.owner;
                }
                s.live |= gs.live;
            } else if let Some(o) = od.object_mut(g.index) {
                let merged = o.clone().with_sub(gs.clone());
                *o = merged;
            }
        }
    }
}

/// Mark the numeric defaults that follow the node-ID (COB-IDs such as
/// 1014h = 80h + node-ID): they are the ones that differ between the same
/// configuration built for two node-IDs.
pub fn mark_node_relative(
    cfg: &NodeConfig,
    generated: &ObjectDictionary,
    generated_id: u8,
    od: &mut ObjectDictionary,
) {
    for (index, sub) in node_relative(cfg, generated, generated_id) {
        if let Some(s) = od.get_mut(index, sub) {
            s.node_id_relative = true;
        }
    }
}

/// The entries of `generated` (built from `cfg` for `generated_id`) whose
/// defaults follow the node-ID (see [`mark_node_relative`]).
pub fn node_relative(cfg: &NodeConfig, generated: &ObjectDictionary, generated_id: u8) -> Vec<(u16, u8)> {
    // `generated` was built for `generated_id` (1 when unconfigured); one
    // more build for a neighbouring node-ID shows which defaults move with it.
    let id = if (1..=127).contains(&generated_id) { generated_id } else { 1 };
    let other = if id == 127 { 126 } else { id + 1 };
    // The mapping entries (up to 64 per PDO) have no node-ID in their
    // defaults (they hold object indices): the neighbour is built without
    // them, which halves its cost. Their sub 0 is still compared.
    let mut neighbour = cfg.clone();
    neighbour.pdo.max_entries = 0;
    let b = build_dictionary(&neighbour, other);
    let step = u64::from(other).wrapping_sub(u64::from(id));
    let mut out = Vec::new();
    for o in generated.objects() {
        for sa in o.subs() {
            let Some(sb) = b.get(o.index, sa.sub) else { continue };
            if sa.data_type.num_kind().is_some()
                && le_u64(&sb.default).wrapping_sub(le_u64(&sa.default)) == step
            {
                out.push((o.index, sa.sub));
            }
        }
    }
    out
}

/// Move node-relative defaults from node-ID `from` to `to` (LSS changed
/// the node-ID); values equal to the old default move along.
pub fn rebase_node_id(od: &mut ObjectDictionary, from: u8, to: u8) {
    let from = if (1..=127).contains(&from) { from } else { 1 };
    let to_eff = if (1..=127).contains(&to) { to } else { 1 };
    let indices: alloc::vec::Vec<(u16, u8)> = od
        .objects()
        .iter()
        .flat_map(|o| o.subs().iter().filter(|s| s.node_id_relative).map(move |s| (o.index, s.sub)))
        .collect();
    for (index, sub) in indices {
        let Some(s) = od.get_mut(index, sub) else { continue };
        let n = s.default.len().min(8);
        let old = le_u64(&s.default);
        let new = old.wrapping_sub(from as u64).wrapping_add(to_eff as u64);
        let was_default = s.bytes() == s.default.as_slice();
        s.default = new.to_le_bytes()[..n].to_vec();
        if was_default {
            let d = s.default.clone();
            if let Ok(r) = od.find(index, sub) {
                od.set_raw(r, &d);
            }
        }
    }
}
