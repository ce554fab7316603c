//! `IoConfig::keep_unmasked_command` (Technosoft iPOS §4.5.3): 60FEh:1
//! keeps the command as written, the bit mask 60FEh:2 selects which bits
//! reach the outputs and the outputs change when the mask is written.

mod drive_rig;
use drive_rig::*;
use drivebus_cia402::drive::{DriveConfig, IoConfig};

#[test]
fn the_command_waits_for_the_mask() {
    let mut cfg = DriveConfig::default();
    cfg.io = IoConfig { output_mask: 0, keep_unmasked_command: true, ..cfg.io };
    let mut r = Rig::with_config(cfg);
    r.start();
    r.write(0x60FE, 1, &0x0003_0000u32.to_le_bytes());
    assert_eq!(r.read(0x60FE, 1), 0x0003_0000, "stored as written");
    assert_eq!(r.drive().digital_outputs(), 0, "mask 0: no output");
    r.write(0x60FE, 2, &0x0001_0000u32.to_le_bytes());
    assert_eq!(r.drive().digital_outputs(), 0x0001_0000, "the mask applies the command");
    r.write(0x60FE, 1, &0x0002_0000u32.to_le_bytes());
    assert_eq!(r.drive().digital_outputs(), 0);
    assert_eq!(r.read(0x60FE, 1), 0x0002_0000);
}
