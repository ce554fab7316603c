//! `FactorGroup::scaling` (Technosoft iPOS §5.2): while scaling objects
//! are in force, 6091h, 6092h, 6096h and 6097h are stored set-up
//! parameters; the units follow the scaling (`Drive::set_scaling`).

mod drive_rig;
use drive_rig::*;
use drivebus_cia402::drive::{DriveConfig, FactorGroup, Scaling};

#[test]
fn factor_objects_are_stored_without_changing_the_units() {
    let d = DriveConfig::default();
    let scaling = Some(Scaling::unit((1, 1), (1, 1)));
    let cfg = DriveConfig { factor: FactorGroup { scaling, ..d.factor }, ..d };
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

#[test]
fn set_scaling_puts_the_scaling_objects_in_force() {
    let mut r = Rig::generic();
    r.start();
    let chain = *r.drive().units();
    let two_to_one = Scaling { position: (0x2_0000, 0x1_0000), ..Scaling::unit((1, 1), (1, 1)) };
    assert!(r.drive_mut().set_scaling(Some(two_to_one)));
    assert_eq!(r.drive().units().pos_to_inc(1000), 2000);
    // A zero term is refused and changes nothing.
    let zero = Scaling { velocity: (0, 1), ..two_to_one };
    assert!(!r.drive_mut().set_scaling(Some(zero)));
    assert_eq!(r.drive().units().pos_to_inc(1000), 2000);
    // While in force, a chain write is stored only.
    r.write(0x6092, 1, &1u32.to_le_bytes());
    assert_eq!(r.drive().units().pos_to_inc(1000), 2000);
    // Back to the chain (with the stored feed).
    assert!(r.drive_mut().set_scaling(None));
    assert_ne!(*r.drive().units(), chain);
    assert_eq!(r.drive().units().pos_to_inc(1), 1 << 20);
}

#[test]
fn set_position_increments_shifts_the_reference() {
    let mut r = Rig::generic();
    r.start();
    r.run_ms(5.0);
    let counts = r.drive().model().position_counts();
    r.drive_mut().set_position_increments(12_345);
    r.run_ms(5.0);
    assert_eq!(r.read(0x6063, 0) as i32, 12_345);
    let pos = r.drive().units().inc_to_pos(12_345);
    assert_eq!(r.read(0x6064, 0) as i32 as i64, pos);
    assert_eq!(r.drive().model().position_counts(), counts, "the axis does not move");
}
