//! 1021h: the device's EDS, generated from its running dictionary so a
//! master can read the device description off the device (CiA 301
//! §7.5.2.21, CiA 306).

use drivebus_eds::{DeviceInfo, from_od, write};
use drivebus_od::ObjectDictionary;
use drivebus_pdo::PdoConfig;

/// The EDS text of `od` as node `node_id` has it now. The 1021h value
/// itself is left out of the description's default (it would describe
/// itself recursively); everything else is exactly the dictionary.
pub(crate) fn generate(od: &ObjectDictionary, node_id: u8, pdo: &PdoConfig) -> String {
    let info = DeviceInfo {
        vendor_name: String::new(),
        vendor_number: od.get_u32(0x1018, 1),
        product_name: od
            .get(0x1008, 0)
            .map(|s| String::from_utf8_lossy(s.bytes()).into_owned())
            .unwrap_or_default(),
        product_number: od.get_u32(0x1018, 2),
        revision_number: od.get_u32(0x1018, 3),
        baud_rates: vec![10, 20, 50, 125, 250, 500, 800, 1000],
        simple_boot_up_slave: true,
        granularity: match pdo.granularity {
            drivebus_pdo::Granularity::Bit => 1,
            drivebus_pdo::Granularity::Byte => 8,
        },
        nr_of_rx_pdo: pdo.rpdo_count,
        nr_of_tx_pdo: pdo.tpdo_count,
        lss_supported: od.object(0x1018).is_some(),
        ..DeviceInfo::default()
    };
    let mut described = od.clone();
    if let Some(s) = described.get_mut(0x1021, 0) {
        s.default.clear();
    }
    if let Ok(r) = described.find(0x1021, 0) {
        described.set_raw(r, &[]);
    }
    let mut eds = from_od(&described, info, node_id, false);
    for t in 2..=7u16 {
        eds.dummy_usage[t as usize] = pdo.dummy_supported(t);
    }
    write(&eds)
}
