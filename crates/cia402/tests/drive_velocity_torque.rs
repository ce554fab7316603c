//! Profile velocity (CiA 402-2 §6.9), velocity mode vl (§6.5) and profile
//! torque (§6.10) on the virtual bus.

mod drive_rig;
use drive_rig::*;

const SW_REACHED: u16 = 1 << 10;
const SW_SPEED_ZERO: u16 = 1 << 12;

fn sw(r: &Rig) -> u16 {
    r.drive().statusword()
}

fn pv_rig() -> Rig {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[3]);
    r.write(0x6083, 0, &36_000_000u32.to_le_bytes());
    r.write(0x6084, 0, &72_000_000u32.to_le_bytes());
    r.write(0x606D, 0, &30_000u16.to_le_bytes());
    r.write(0x606E, 0, &5u16.to_le_bytes());
    r.write(0x606F, 0, &30_000u16.to_le_bytes());
    r.write(0x6070, 0, &5u16.to_le_bytes());
    r.enable();
    r
}

#[test]
fn pv_reaches_target_within_window() {
    let mut r = pv_rig();
    // At rest: speed = 0 (bit 12) after 6070h.
    r.run_ms(6.0);
    assert_ne!(sw(&r) & SW_SPEED_ZERO, 0);
    let target = 3_600_000i32; // 10 rev/s
    r.write(0x60FF, 0, &target.to_le_bytes());
    r.run_ms(1.0);
    assert_eq!(sw(&r) & SW_REACHED, 0);
    // Ramp time v/a = 0.1 s, then 606Eh = 5 ms in the window.
    let t = r.run_until(125, 1000.0, |r| sw(r) & SW_REACHED != 0).unwrap() + 1e-3;
    let expect = f64::from(target) / 36e6 + 5e-3;
    assert!((t - expect).abs() < 0.01 * expect + 0.5e-3, "{t} vs {expect}");
    let v = r.read(0x606C, 0) as i32;
    assert!((v - target).abs() <= 30_000, "606Ch {v}");
    assert_eq!(r.read(0x606B, 0) as i32, target);
    assert_eq!(sw(&r) & SW_SPEED_ZERO, 0, "moving: speed ≠ 0");
    // Back to zero: decelerates at 6084h (0.05 s), bit 12 after 6070h.
    r.write(0x60FF, 0, &0i32.to_le_bytes());
    let t = r.run_until(125, 1000.0, |r| sw(r) & SW_SPEED_ZERO != 0).unwrap();
    assert!(t > 0.045 && t < 0.05 + 0.01, "speed zero after {t}");
}

#[test]
fn pv_halt_decelerates_to_zero() {
    let mut r = pv_rig();
    r.write(0x60FF, 0, &(-1_800_000i32).to_le_bytes());
    r.run_ms(150.0);
    r.controlword(0x10F);
    r.run_us(200);
    assert_eq!(sw(&r) & SW_REACHED, 0, "halting");
    let t = r.run_until(125, 1000.0, |r| sw(r) & SW_REACHED != 0).unwrap() + 200e-6;
    // 605Dh = 1 (6084h): 1.8e6 / 72e6 = 25 ms, plus 606Eh.
    assert!(t < 0.025 + 0.005 + 0.005, "{t}");
    let v = r.drive().model().velocity();
    assert!(v.abs() < 2.0, "t {t} v {v}");
}

#[test]
fn pv_respects_max_motor_speed() {
    let mut r = pv_rig();
    r.write(0x6080, 0, &1_000_000u32.to_le_bytes());
    r.write(0x60FF, 0, &3_600_000i32.to_le_bytes());
    r.run_ms(200.0);
    assert_eq!(r.read(0x606B, 0) as i32, 1_000_000);
}

#[test]
fn tq_follows_the_torque_slope() {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[4]);
    r.write(0x6087, 0, &1000u32.to_le_bytes()); // 1000 ‰/s
    r.enable();
    r.write(0x6071, 0, &50i16.to_le_bytes());
    // Ramp time = Δtorque / slope = 50 / 1000 = 50 ms.
    let t = r.run_until(125, 1000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert!((t - 0.05).abs() <= 0.01 * 0.05 + 125e-6, "ramp {t}");
    assert_eq!(r.read(0x6074, 0) as i16, 50);
    // The current loop follows within a few time constants (0.2 ms).
    r.run_ms(2.0);
    let act = r.read(0x6077, 0) as i16;
    assert!((act - 50).abs() <= 3, "6077h {act}");
    // Halfway down: 6074h after 25 ms of a −50 step.
    r.write(0x6071, 0, &0i16.to_le_bytes());
    r.run_ms(25.0);
    let d = r.read(0x6074, 0) as i16;
    assert!((d - 25).abs() <= 1, "6074h {d}");
}

#[test]
fn tq_is_limited_by_max_torque() {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[4]);
    r.write(0x6072, 0, &30u16.to_le_bytes());
    r.write(0x6087, 0, &100_000u32.to_le_bytes());
    r.enable();
    r.write(0x6071, 0, &500i16.to_le_bytes());
    r.run_ms(5.0);
    assert_eq!(r.read(0x6074, 0) as i16, 30);
}

#[test]
fn vl_ramps_with_delta_speed_over_delta_time() {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[2]);
    // 6048h: 600 rpm per 1 s.
    r.write(0x6048, 1, &600u32.to_le_bytes());
    r.write(0x6048, 2, &1u16.to_le_bytes());
    r.write(0x6046, 1, &100u32.to_le_bytes());
    r.enable();
    r.write(0x6042, 0, &300i16.to_le_bytes());
    r.run_ms(250.0);
    // 0.25 s × 600 rpm/s = 150 rpm.
    let d = r.read(0x6043, 0) as i16;
    assert!((d - 150).abs() <= 1, "6043h {d}");
    r.run_ms(500.0);
    assert_eq!(r.read(0x6043, 0) as i16, 300);
    let a = r.read(0x6044, 0) as i16;
    assert!((a - 300).abs() <= 5, "6044h {a}");
    // Below 6046h:1 the amount is raised to the minimum.
    r.write(0x6042, 0, &(-10i16).to_le_bytes());
    r.run_ms(2000.0);
    assert_eq!(r.read(0x6043, 0) as i16, -100);
}

/// 606Eh = 0 and 6070h = 0 (no window time): bits 10 and 12 follow the
/// speed at once, and are clear while the speed is outside the windows.
#[test]
fn pv_windows_with_zero_time() {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[3]);
    r.write(0x6083, 0, &36_000_000u32.to_le_bytes());
    r.write(0x6084, 0, &72_000_000u32.to_le_bytes());
    r.write(0x606D, 0, &30_000u16.to_le_bytes());
    r.write(0x606E, 0, &0u16.to_le_bytes());
    r.write(0x606F, 0, &30_000u16.to_le_bytes());
    r.write(0x6070, 0, &0u16.to_le_bytes());
    r.enable();
    r.run_ms(2.0);
    assert_eq!(sw(&r) & (SW_REACHED | SW_SPEED_ZERO), SW_REACHED | SW_SPEED_ZERO, "at rest");
    r.write(0x60FF, 0, &3_600_000i32.to_le_bytes());
    r.run_ms(20.0);
    assert_eq!(sw(&r) & (SW_REACHED | SW_SPEED_ZERO), 0, "ramping: neither bit");
    let t = r.run_until(125, 1000.0, |r| sw(r) & SW_REACHED != 0).unwrap() + 20e-3;
    assert!((t - 0.1).abs() < 0.005, "reached at the end of the ramp: {t}");
}

/// `TargetReached::ActualInWindow`: bit 10 is judged on 606Ch alone, so a
/// wide window reports "reached" while the ramp still runs.
#[test]
fn pv_reached_on_the_actual_value_alone() {
    use drivebus_cia402::drive::{DriveConfig, TargetReached};
    let cfg = DriveConfig { target_reached: TargetReached::ActualInWindow, ..DriveConfig::default() };
    let mut r = Rig::with_config(cfg);
    r.write(0x6060, 0, &[3]);
    r.write(0x6083, 0, &36_000_000u32.to_le_bytes());
    r.write(0x606D, 0, &60_000u16.to_le_bytes());
    r.write(0x606E, 0, &0u16.to_le_bytes());
    r.enable();
    r.run_ms(2.0);
    // Window 60 000 units/s around 3 600 000 at 36e6 units/s²: entered
    // ~1.7 ms before the 100 ms ramp ends (plus the actual's lag).
    r.write(0x60FF, 0, &3_600_000i32.to_le_bytes());
    let t = r.run_until(125, 1000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert!(t < 0.1 - 0.001, "reached while ramping: {t}");
    assert!(r.read(0x606B, 0) as i32 != 3_600_000, "demand still ramping");
}
