//! `DriveConfig::zero_ramp`: what 6083h / 6084h / 609Ah = 0 means.
//! `Refused` (CiA 402 default of drivebus): a written 0 is aborted.
//! `RefusesMotion`: 0 is taken; pp does not acknowledge a set-point, pv
//! holds velocity 0, hm reports a homing error. `DriveRamp` (Kollmorgen
//! KC1/AKD): 0 selects the drive's own ramp, the dictionary keeps the 0.

mod drive_rig;
use drive_rig::*;
use drivebus_cia402::drive::{DriveConfig, ModeHandler, ZeroRamp, generic_drive_with};
use drivebus_cia402::homing::HomingMode;

const SW_ACK: u16 = 1 << 12;
const SW_HOMING_ERROR: u16 = 1 << 13;

fn rig(zero: ZeroRamp) -> Rig {
    let cfg = DriveConfig { zero_ramp: zero, ..DriveConfig::default() };
    let handlers: Vec<Box<dyn ModeHandler + Send>> = vec![Box::new(HomingMode::default())];
    let mut r = Rig::with(generic_drive_with(ID, cfg, handlers));
    r.start();
    r
}

#[test]
fn refused_by_default() {
    let mut r = rig(ZeroRamp::Refused);
    for index in [0x6083, 0x6084, 0x609A] {
        r.write_aborts(index, 0, &0u32.to_le_bytes(), 0x0609_0032);
    }
}

#[test]
fn zero_refuses_pp_pv_and_hm() {
    let mut r = rig(ZeroRamp::RefusesMotion);
    r.write(0x6083, 0, &0u32.to_le_bytes());
    r.write(0x609A, 0, &0u32.to_le_bytes());
    assert_eq!(r.read(0x6083, 0), 0);
    // pp: the set-point is not acknowledged and nothing moves.
    r.write(0x6060, 0, &[1]);
    r.enable();
    r.write(0x607A, 0, &90_000i32.to_le_bytes());
    r.controlword(0x1F);
    r.run_ms(50.0);
    assert_eq!(r.statusword() & SW_ACK, 0, "not acknowledged");
    assert_eq!(r.read(0x6062, 0) as i32, 0, "no demand");
    r.controlword(0x0F);
    // pv: velocity held at 0.
    r.write(0x6060, 0, &[3]);
    r.write(0x60FF, 0, &360_000i32.to_le_bytes());
    r.run_ms(100.0);
    assert!((r.read(0x606B, 0) as i32).abs() < 1000, "no velocity demand");
    r.write(0x60FF, 0, &0i32.to_le_bytes());
    // hm: homing error.
    r.write(0x6060, 0, &[6]);
    r.write(0x6098, 0, &[37]);
    r.run_ms(1.0);
    r.controlword(0x1F);
    r.run_ms(5.0);
    assert_ne!(r.statusword() & SW_HOMING_ERROR, 0, "homing error");
    // A ramp set again: pp moves.
    r.write(0x6083, 0, &36_000_000u32.to_le_bytes());
    r.write(0x6060, 0, &[1]);
    r.controlword(0x0F);
    r.run_ms(1.0);
    r.controlword(0x1F);
    r.run_ms(5.0);
    assert_ne!(r.statusword() & SW_ACK, 0, "acknowledged");
}

#[test]
fn zero_selects_the_drive_ramp() {
    let ramp = 36_000_000;
    let mut r = rig(ZeroRamp::DriveRamp { acceleration: ramp, deceleration: ramp, homing: ramp });
    r.write(0x6083, 0, &0u32.to_le_bytes());
    r.write(0x6084, 0, &0u32.to_le_bytes());
    r.write(0x609A, 0, &0u32.to_le_bytes());
    assert_eq!(r.read(0x6083, 0), 0, "the dictionary keeps 0");
    // pv at the drive's ramp: 360 000 units/s in 10 ms.
    r.write(0x6060, 0, &[3]);
    r.write(0x60FF, 0, &360_000i32.to_le_bytes());
    r.enable();
    r.run_ms(5.0);
    let half = r.read(0x606B, 0) as i32;
    assert!((120_000..=240_000).contains(&half), "ramping at 6083h's fallback: {half}");
    r.run_ms(50.0);
    assert_eq!(r.read(0x606B, 0) as i32, 360_000);
    // hm 37 (set home here) completes.
    r.write(0x60FF, 0, &0i32.to_le_bytes());
    r.run_ms(50.0);
    r.write(0x6060, 0, &[6]);
    r.write(0x6098, 0, &[37]);
    r.run_ms(1.0);
    r.controlword(0x1F);
    r.run_ms(5.0);
    assert_eq!(r.statusword() & 0x3400, 0x1400, "homing attained");
}

#[test]
fn zero_torque_slope_refuses_torque() {
    let mut r = Rig::generic();
    r.start();
    r.write(0x6060, 0, &[4]);
    r.write(0x6087, 0, &0u32.to_le_bytes());
    r.write(0x6071, 0, &500i16.to_le_bytes());
    r.enable();
    r.run_ms(20.0);
    assert_eq!(r.read(0x6074, 0) as i16, 0, "no torque demand at 6087h = 0");
    r.write(0x6087, 0, &1_000_000u32.to_le_bytes());
    r.run_ms(20.0);
    assert_eq!(r.read(0x6074, 0) as i16, 500, "a slope set: the demand follows");
}
