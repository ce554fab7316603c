//! `DriveConfig::fixed_factor_group` (Technosoft iPOS §5.2.2): 6091h,
//! 6092h, 6096h and 6097h are stored set-up parameters; the units in
//! force stay those the drive was built with.

mod drive_rig;
use drive_rig::*;
use drivebus_cia402::drive::DriveConfig;

#[test]
fn factor_objects_are_stored_without_changing_the_units() {
    let cfg = DriveConfig { fixed_factor_group: true, ..DriveConfig::default() };
    let mut r = Rig::with_config(cfg);
    r.start();
    let before = *r.drive().units();
    for index in [0x6091, 0x6092, 0x6096, 0x6097] {
        r.write(index, 1, &1u32.to_le_bytes());
        r.write(index, 2, &1u32.to_le_bytes());
        assert_eq!(r.read(index, 1), 1);
        r.write_aborts(index, 1, &0u32.to_le_bytes(), 0x0609_0032);
    }
    assert_eq!(*r.drive().units(), before, "units unchanged");
    // Without the switch the same writes change the units.
    let mut r = Rig::generic();
    r.start();
    let before = *r.drive().units();
    r.write(0x6092, 1, &1u32.to_le_bytes());
    assert_ne!(*r.drive().units(), before);
}
