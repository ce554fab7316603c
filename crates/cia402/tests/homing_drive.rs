//! Homing end to end: `HomingMode` plugged into the CiA 402 drive on the
//! virtual bus, configured and started by SDO (6060h = 6, 6098h, 6099h,
//! 609Ah, 607Ch, controlword bit 4), result read from 6041h / 6064h.
//! Position units: 0.001° (the generic servo's factor group).

#[path = "drive_rig/mod.rs"]
mod drive_rig;

use drive_rig::{ID, Rig};
use drivebus_cia402::drive::{DriveConfig, ModeHandler, generic_drive_with};
use drivebus_cia402::homing::HomingMode;
use drivebus_cia402::model::DriveParams;

/// Index pulse at 0.3 rad = 17.188 733 9°.
const INDEX_DEG: f64 = 0.3 * 180.0 / core::f64::consts::PI;

fn rig(setup: impl FnOnce(&mut DriveParams)) -> Rig {
    let mut p = DriveParams::servo_small();
    p.encoder.index_angle = 0.3;
    setup(&mut p);
    let handlers: Vec<Box<dyn ModeHandler + Send>> = vec![Box::new(HomingMode::default())];
    let mut rig = Rig::with(generic_drive_with(ID, DriveConfig::servo(p), handlers));
    rig.start();
    rig.write(0x6060, 0, &[6]);
    rig.write(0x6099, 1, &1_800_000u32.to_le_bytes()); // 1800°/s
    rig.write(0x6099, 2, &180_000u32.to_le_bytes()); // 180°/s
    rig.write(0x609A, 0, &36_000_000u32.to_le_bytes()); // 36 000°/s²
    rig.write(0x607C, 0, &12_345i32.to_le_bytes()); // 12.345°
    rig.enable();
    rig.run_ms(2.0);
    rig
}

fn home(rig: &mut Rig, method: i8, expected_reference_deg: f64) {
    rig.write(0x6098, 0, &[method as u8]);
    rig.run_ms(1.0);
    rig.controlword(0x1F);
    rig.run_ms(1.0);
    assert_eq!(rig.statusword() & 0x3400, 0x0000, "in progress");
    let done = rig.run_until(1000, 10_000.0, |r| {
        let sw = r.drive().statusword();
        sw & 0x3000 != 0 && sw & 0x0400 != 0
    });
    assert!(done.is_some(), "homing did not end: {:04X}", rig.drive().statusword());
    assert_eq!(rig.statusword() & 0x3400, 0x1400, "homing completed");
    // 6064h = home offset + how far the shaft stands from the reference.
    let shaft_deg = rig.drive().model().position().to_degrees();
    let want = 12_345.0 + (shaft_deg - expected_reference_deg) * 1000.0;
    let got = rig.read(0x6064, 0) as i32;
    assert!((f64::from(got) - want).abs() <= 1.5, "6064h {got}, expected {want:.1}");
}

#[test]
fn method_8_and_24_through_sdo() {
    // Home switch [100°, 500°], start at −300°: method 8 = first index
    // right of the lower edge (377.19°); then 24 = the lower edge itself.
    let mut rig = rig(|p| {
        p.axis.home_switch = Some((100.0, 500.0));
        p.axis.initial_position = -300.0;
    });
    assert_eq!(rig.statusword() & 0x3400, 0x0400, "not started");
    home(&mut rig, 8, INDEX_DEG + 360.0);
    rig.controlword(0x0F);
    assert_eq!(rig.statusword() & 0x3400, 0x1400, "completed stays until the next start");
    home(&mut rig, 24, 100.0);
    // 60E3h lists the supported methods.
    assert_eq!(rig.read(0x60E3, 1) as u8, 1);
}

#[test]
fn method_1_with_limit_switches() {
    // Negative limit switch at −1000°: first index right of it, −702.81°.
    let mut rig = rig(|p| {
        p.axis.negative_limit = Some(-1000.0);
        p.axis.positive_limit = Some(1000.0);
        p.axis.negative_stop = Some(-1200.0);
        p.axis.positive_stop = Some(1200.0);
    });
    home(&mut rig, 1, INDEX_DEG - 720.0);
}

/// Method 1 references the negative limit switch: reaching it is the
/// method's event, not a limit. No stop, no warning (bit 7) and no
/// internal limit (bit 11) while homing, whatever the limit-switch
/// reaction outside homing.
#[test]
fn limit_switch_is_a_reference_while_homing() {
    let mut rig = rig(|p| {
        p.axis.negative_limit = Some(-1000.0);
        p.axis.negative_stop = Some(-1200.0);
    });
    rig.write(0x6098, 0, &[1]);
    rig.controlword(0x1F);
    let mut on_switch = false;
    let done = rig.run_until(1000, 10_000.0, |r| {
        let sw = r.drive().statusword();
        assert_eq!(sw & 0x0880, 0, "warning / internal limit while homing: {sw:04X}");
        on_switch |= r.drive().model().switches().negative_limit;
        sw & 0x3400 == 0x1400
    });
    assert!(done.is_some(), "homing did not complete: {:04X}", rig.statusword());
    assert!(on_switch, "the search reached the switch");
}

/// 6099h:1 is the speed of the switch search, 6099h:2 the speed that
/// leaves the switch, 609Ah the acceleration of both (method 17: the
/// negative limit switch).
#[test]
fn homing_speeds_and_acceleration_follow_6099h_and_609ah() {
    let mut rig = rig(|p| {
        p.axis.negative_limit = Some(-1000.0);
        p.axis.positive_limit = Some(1000.0);
        p.axis.negative_stop = Some(-1200.0);
        p.axis.positive_stop = Some(1200.0);
    });
    rig.write(0x6098, 0, &[17]);
    rig.controlword(0x1F);
    // 1800°/s at 36 000°/s² takes 50 ms: 720°/s after 20 ms.
    rig.run_ms(20.0);
    let v = rig.read(0x606B, 0) as i32;
    assert!((v + 720_000).abs() < 20_000, "accelerating at 609Ah: {v}");
    rig.run_ms(100.0);
    assert_eq!(rig.read(0x606B, 0) as i32, -1_800_000, "searching at 6099h:1");
    // On the switch: back out at 6099h:2.
    let t = rig.run_until(125, 2000.0, |r| r.drive().demand_velocity() > 0.0);
    assert!(t.is_some(), "reversed at the switch");
    rig.run_ms(50.0);
    assert_eq!(rig.read(0x606B, 0) as i32, 180_000, "leaving the switch at 6099h:2");
}
