//! The generic drive: node and drive with the CiA 402 pre-defined PDO set.

use super::{Drive, DriveConfig};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_node::{Node, NodeConfig, NodeDevice};
use drivebus_pdo::{PdoDefaults, PdoKind, map_entry, set_defaults};

/// The CiA 402 pre-defined PDO set (CiA 402-3 style): RPDO1 6040h, RPDO2
/// 6040h+607Ah, RPDO3 6040h+60FFh, RPDO4 6040h+6071h; TPDO1 6041h
/// (event-driven), TPDO2 6041h+6064h, TPDO3 6041h+606Ch, TPDO4 6041h+6077h
/// (synchronous, every SYNC).
pub fn default_pdo_mapping(node: &mut Node) {
    let cfg = node.config().pdo;
    let cw = map_entry(0x6040, 0, 16);
    let sw = map_entry(0x6041, 0, 16);
    let rpdos: [Vec<u32>; 4] = [
        alloc::vec![cw],
        alloc::vec![cw, map_entry(0x607A, 0, 32)],
        alloc::vec![cw, map_entry(0x60FF, 0, 32)],
        alloc::vec![cw, map_entry(0x6071, 0, 16)],
    ];
    let tpdos: [Vec<u32>; 4] = [
        alloc::vec![sw],
        alloc::vec![sw, map_entry(0x6064, 0, 32)],
        alloc::vec![sw, map_entry(0x606C, 0, 32)],
        alloc::vec![sw, map_entry(0x6077, 0, 16)],
    ];
    let od = node.od_mut();
    for (n, e) in rpdos.iter().enumerate() {
        // A device with fewer PDOs simply lacks the later ones.
        let _ = set_defaults(od, &cfg, PdoKind::Rpdo, n as u16, &PdoDefaults::new(e));
    }
    for (n, e) in tpdos.iter().enumerate() {
        let tt = if n == 0 { 255 } else { 1 };
        let d = PdoDefaults { transmission_type: tt, ..PdoDefaults::new(e) };
        let _ = set_defaults(od, &cfg, PdoKind::Tpdo, n as u16, &d);
    }
    // Re-resolve the PDO service (insert_object reloads it).
    if let Some(o) = node.od().object(0x6502).cloned() {
        node.insert_object(o);
    }
}

/// A fully featured CiA 402 servo drive (pp, vl, pv, tq; small servo model,
/// 8 kHz, 0.001° position units) with the pre-defined PDO set: a
/// [`drivebus_can::Device`] for any host (the virtual bus, a real bus).
pub fn generic_drive(node_id: u8) -> NodeDevice<Drive> {
    generic_drive_with(node_id, DriveConfig::default(), Vec::new())
}

/// [`generic_drive`] with a drive configuration and mode handlers.
pub fn generic_drive_with(
    node_id: u8,
    cfg: DriveConfig,
    handlers: Vec<Box<dyn super::ModeHandler + Send>>,
) -> NodeDevice<Drive> {
    let mut nc = NodeConfig::new(node_id);
    nc.device_type = 0x0002_0192; // CiA 402, servo drive
    nc.device_name = Some("drivebus virtual drive".into());
    let mut node = Node::new(nc);
    let drive = match Drive::install_with(&mut node, cfg, handlers) {
        Ok(d) => d,
        // The built-in presets always validate; a bad custom configuration
        // falls back to the default drive rather than failing the bus.
        Err(_) => Drive::install(&mut node, DriveConfig::default()).expect("default drive config is valid"),
    };
    default_pdo_mapping(&mut node);
    NodeDevice::new(node, drive)
}
