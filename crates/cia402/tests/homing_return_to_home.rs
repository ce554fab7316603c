//! Homing with "return to the home position after the stop": the final
//! 6064h is 607Ch (± 2) with the option and 607Ch ± the braking distance
//! v²/2a in the final direction without it. Position units: 0.001°.

#[path = "drive_rig/mod.rs"]
mod drive_rig;

use drive_rig::{ID, Rig};
use drivebus_cia402::drive::{DriveConfig, ModeHandler, generic_drive_with};
use drivebus_cia402::homing::HomingMode;
use drivebus_cia402::model::DriveParams;

const HOME_OFFSET: i32 = 12_345;
/// 6099h:2, the speed of the final approach \[0.001°/s\].
const ZERO_SPEED: f64 = 180_000.0;
/// 609Ah \[0.001°/s²\].
const ACC: f64 = 36_000_000.0;

/// Where return-to-home is switched on.
#[derive(Clone, Copy)]
enum Return {
    Off,
    Handler,
    Config,
}

fn rig(opt: Return) -> Rig {
    let mut p = DriveParams::servo_small();
    p.encoder.index_angle = 0.3;
    p.axis.negative_limit = Some(-1000.0);
    p.axis.positive_limit = Some(1000.0);
    p.axis.negative_stop = Some(-1200.0);
    p.axis.positive_stop = Some(1200.0);
    let hm = HomingMode::default().with_return_to_home(matches!(opt, Return::Handler));
    let handlers: Vec<Box<dyn ModeHandler + Send>> = vec![Box::new(hm)];
    let cfg = DriveConfig { homing_return_to_home: matches!(opt, Return::Config), ..DriveConfig::servo(p) };
    let mut rig = Rig::with(generic_drive_with(ID, cfg, handlers));
    rig.start();
    rig.write(0x6060, 0, &[6]);
    rig.write(0x6099, 1, &1_800_000u32.to_le_bytes()); // 1800°/s
    rig.write(0x6099, 2, &(ZERO_SPEED as u32).to_le_bytes());
    rig.write(0x609A, 0, &(ACC as u32).to_le_bytes());
    rig.write(0x607C, 0, &HOME_OFFSET.to_le_bytes());
    rig.enable();
    rig.run_ms(2.0);
    rig
}

/// Homes with `method` (rising edge of bit 4), sampling the status every
/// period; returns the final 6064h and whether "attained, target not
/// reached" (bits 12/10 = 1/0) was seen before "completed".
fn home_watching(rig: &mut Rig, method: i8) -> (i32, bool) {
    rig.controlword(0x0F);
    rig.write(0x6098, 0, &[method as u8]);
    rig.run_ms(1.0);
    rig.controlword(0x1F);
    let mut attained_moving = false;
    let mut done = false;
    for _ in 0..80_000 {
        rig.run_us(125);
        let sw = rig.drive().statusword() & 0x3400;
        attained_moving |= sw == 0x1000;
        if sw == 0x1400 {
            done = true;
            break;
        }
    }
    assert!(done, "homing did not complete: {:04X}", rig.drive().statusword());
    rig.run_ms(50.0);
    (rig.read(0x6064, 0) as i32, attained_moving)
}

/// Braking distance of the homing profile from the zero-search speed.
fn braking() -> f64 {
    ZERO_SPEED * ZERO_SPEED / (2.0 * ACC) // 450 units = 0.45°
}

#[test]
fn without_the_option_the_axis_stops_past_home() {
    // Method 1: final approach positive (index right of the NLS).
    let mut r = rig(Return::Off);
    let (p, seen) = home_watching(&mut r, 1);
    let want = f64::from(HOME_OFFSET) + braking();
    eprintln!("method 1 without return: 6064h {p}, 607Ch + v²/2a = {want}");
    // Tolerance: the reference lies inside a control period (v·dt = 22.5).
    assert!((f64::from(p) - want).abs() <= 30.0, "method 1: 6064h {p}, expected ≈ {want}");
    assert!(seen, "attained while braking");
    // Method 18: final approach negative (leaving the PLS).
    let (p, _) = home_watching(&mut r, 18);
    let want = f64::from(HOME_OFFSET) - braking();
    eprintln!("method 18 without return: 6064h {p}, 607Ch − v²/2a = {want}");
    assert!((f64::from(p) - want).abs() <= 30.0, "method 18: 6064h {p}, expected ≈ {want}");
}

#[test]
fn with_the_option_the_axis_returns_to_home() {
    for opt in [Return::Handler, Return::Config] {
        let mut r = rig(opt);
        let (p, seen) = home_watching(&mut r, 1);
        assert!((p - HOME_OFFSET).abs() <= 2, "method 1: 6064h {p}");
        assert!(seen, "bit 12 set before bit 10 (reference taken, still moving)");
        let (p, seen) = home_watching(&mut r, 18);
        assert!((p - HOME_OFFSET).abs() <= 2, "method 18: 6064h {p}");
        assert!(seen);
        // Method 35 (current position): nothing to return; completes at once.
        let (p, _) = home_watching(&mut r, 35);
        assert!((p - HOME_OFFSET).abs() <= 2, "method 35: 6064h {p}");
    }
}

#[test]
fn halt_during_the_return_interrupts() {
    let mut r = rig(Return::Handler);
    r.write(0x6098, 0, &[1]);
    r.controlword(0x1F);
    let attained = r.run_until(125, 10_000.0, |r| r.drive().statusword() & 0x3400 == 0x1000);
    assert!(attained.is_some());
    r.controlword(0x11F); // halt
    let rest = r.run_until(125, 1000.0, |r| r.drive().statusword() & 0x3400 == 0x0400);
    assert!(rest.is_some(), "interrupted at rest: {:04X}", r.drive().statusword());
}

/// `Drive::set_homing_keeps_position` (Technosoft iPOS 210Bh bit 12): the
/// reference is found but the position is not reset; the return goes back
/// to the point found, so 6064h ends where the reference was, in the
/// coordinates the axis had.
#[test]
fn keeping_the_position_returns_to_the_point_found() {
    let mut r = rig(Return::Config);
    // Method 1 once with reset: the reference is then at 607Ch.
    let (p, _) = home_watching(&mut r, 1);
    assert!((p - HOME_OFFSET).abs() <= 2);
    // Move the coordinates away, then home again keeping them.
    r.dn_mut().app.set_position_increments(0);
    r.run_ms(2.0);
    let shifted = r.read(0x6064, 0) as i32;
    r.dn_mut().app.set_homing_keeps_position(true);
    let (p, _) = home_watching(&mut r, 1);
    // The same physical point, seen in the shifted coordinates.
    assert!((p - shifted).abs() <= 30, "6064h {p}, the reference in kept coordinates {shifted}");
    assert!((p - HOME_OFFSET).abs() > 1000, "not reset to 607Ch");
}
