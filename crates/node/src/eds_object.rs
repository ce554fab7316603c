//! 1021h: the device's EDS, generated from its running dictionary so a
//! master can read the device description off the device (CiA 301
//! §7.5.2.21, CiA 306).

use drivebus_eds::{DeviceInfo, from_od, write};
use drivebus_od::ObjectDictionary;
use drivebus_pdo::PdoConfig;

/// What the served EDS takes from the device's own description rather
/// than from the dictionary.
#[derive(Debug, Clone, Default)]
pub(crate) struct Given {
    /// The node is an LSS slave.
    pub lss: bool,
    /// `[DeviceInfo]`: names, numbers, bit rates.
    pub device_info: Option<DeviceInfo>,
    /// `[FileInfo]`: file name, versions, dates, authors.
    pub file_info: Option<Vec<(String, String)>>,
}

/// The EDS text of `od` as node `node_id` has it now, with `[DeviceInfo]`
/// and `[FileInfo]` from `given` (the device's own description), the PDO
/// counts, granularity and LSS from the running node. The 1021h value
/// itself is left out of the description's default (it would describe
/// itself recursively); everything else is exactly the dictionary.
pub(crate) fn generate(od: &ObjectDictionary, node_id: u8, pdo: &PdoConfig, given: &Given) -> String {
    let lss = given.lss;
    let mut info = given.device_info.clone().unwrap_or_else(|| DeviceInfo {
        product_name: od
            .get(0x1008, 0)
            .map(|s| String::from_utf8_lossy(s.bytes()).into_owned())
            .unwrap_or_default(),
        baud_rates: vec![10, 20, 50, 125, 250, 500, 800, 1000],
        simple_boot_up_slave: true,
        // CiA 306 §4.4: the numbers are 1018h's.
        vendor_number: od.get_u32(0x1018, 1),
        product_number: od.get_u32(0x1018, 2),
        revision_number: od.get_u32(0x1018, 3),
        ..DeviceInfo::default()
    });
    // What the running node knows better than any description.
    info.granularity = match pdo.granularity {
        drivebus_pdo::Granularity::Bit => 1,
        drivebus_pdo::Granularity::Byte => 8,
    };
    info.nr_of_rx_pdo = pdo.rpdo_count;
    info.nr_of_tx_pdo = pdo.tpdo_count;
    info.lss_supported = lss;
    let mut described = od.clone();
    if let Some(s) = described.get_mut(0x1021, 0) {
        s.default.clear();
    }
    if let Ok(r) = described.find(0x1021, 0) {
        described.set_raw(r, &[]);
    }
    let mut eds = from_od(&described, info, node_id, false);
    if let Some(file_info) = &given.file_info {
        eds.file_info = file_info.clone();
    }
    for t in 1..=7u16 {
        eds.dummy_usage.insert(t, pdo.dummy_supported(t));
    }
    write(&eds)
}
