//! CiA 402-2 objects whose effect the other drive tests do not show on
//! their own (the standard behaviour ledger, `crates/personality/
//! ledger-standard.tsv`): the factor group and polarity, the quick-stop,
//! shutdown and disable-operation reactions, the profile limits, the torque
//! and current limits, the position window and time, the vl deceleration
//! and the actual values, each on the generic drive through its objects.

mod drive_rig;
use core::f64::consts::PI;
use drive_rig::*;
use drivebus_cia402::drive::Injection;
use drivebus_cia402::model::ModelInjection as Plant;

const REV: f64 = 360_000.0; // position units per motor revolution (generic)
const SW_REACHED: u16 = 1 << 10;

fn pp_rig() -> Rig {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[1]);
    r
}

/// Starts a pp move to `target` (absolute, single set-point).
fn move_to(r: &mut Rig, target: i32) {
    r.write(0x607A, 0, &target.to_le_bytes());
    r.controlword(0x0F);
    r.controlword(0x1F);
    r.run_ms(1.0);
    r.controlword(0x0F);
}

/// pv at `v` position units/s, enabled, settled.
fn pv_at(r: &mut Rig, v: i32) {
    r.write(0x6060, 0, &[3]);
    r.enable();
    r.write(0x60FF, 0, &v.to_le_bytes());
    r.run_ms(300.0);
}

/// 6091h gear ratio and 6092h feed constant set the position unit; 607Eh
/// bit 7 reverses it (CiA 402-2 factor group).
#[test]
fn gear_ratio_feed_and_polarity_scale_the_position() {
    for (polarity, sign) in [(0u8, 1.0), (0x80, -1.0)] {
        let mut r = pp_rig();
        // 1000 units per driving shaft revolution, 2 motor revolutions per
        // shaft revolution: 500 units are one motor revolution.
        r.write(0x6092, 1, &1000u32.to_le_bytes());
        r.write(0x6091, 1, &2u32.to_le_bytes());
        r.write(0x607E, 0, &[polarity]);
        r.write(0x6081, 0, &1000u32.to_le_bytes());
        r.write(0x6083, 0, &10_000u32.to_le_bytes());
        r.write(0x6084, 0, &10_000u32.to_le_bytes());
        r.enable();
        move_to(&mut r, 500);
        r.run_ms(1000.0);
        let motor = r.drive().model().position();
        assert!((motor - sign * 2.0 * PI).abs() < 0.01, "polarity {polarity:02X}h: {motor} rad");
        assert_eq!(r.read(0x6064, 0) as i32, 500);
    }
}

/// 6096h velocity factor and 6097h acceleration factor scale velocity and
/// acceleration units.
#[test]
fn velocity_and_acceleration_factors_scale_their_units() {
    let mut r = Rig::generic();
    r.write(0x6092, 1, &1000u32.to_le_bytes()); // 1000 units per revolution
    r.write(0x6096, 1, &10u32.to_le_bytes()); // 1 velocity unit = 10 units/s
    r.write(0x6097, 1, &10u32.to_le_bytes()); // 1 acceleration unit = 10 units/s²
    r.write(0x6060, 0, &[3]);
    r.write(0x6083, 0, &100u32.to_le_bytes()); // 1000 units/s² = 1 rev/s²
    r.enable();
    r.write(0x60FF, 0, &100i32.to_le_bytes()); // 1000 units/s = 1 rev/s
    r.run_ms(500.0);
    let w = r.drive().model().velocity();
    assert!((w - PI).abs() < 0.1, "half-way up the 1 s ramp: {w} rad/s");
    r.run_ms(700.0);
    let w = r.drive().model().velocity();
    assert!((w - 2.0 * PI).abs() < 0.05, "1 rev/s: {w} rad/s");
    assert_eq!(r.read(0x606B, 0) as i32, 100);
}

/// 6085h quick stop deceleration is the quick-stop ramp (605Ah = 2).
#[test]
fn quick_stop_deceleration_sets_the_ramp() {
    for (dec, expect) in [(3_600_000u32, 0.1), (7_200_000, 0.05)] {
        let mut r = Rig::generic();
        r.write(0x6085, 0, &dec.to_le_bytes());
        pv_at(&mut r, 360_000); // 1 rev/s
        r.controlword(0x0B);
        let t = r.run_until(125, 1000.0, |r| r.drive().statusword() & 0x4F == 0x40).unwrap();
        // Switch on disabled once at rest (within the standstill margin).
        assert!(t > 0.9 * expect && t < expect + 0.01, "6085h {dec}: stopped after {t} s");
    }
}

/// 605Bh shutdown and 605Ch disable operation option codes: 1 ramps down
/// on 6084h before the transition, 0 switches off at once.
#[test]
fn shutdown_and_disable_operation_option_codes() {
    for (object, cw, state) in [(0x605Bu16, 0x06u16, 0x21u16), (0x605C, 0x07, 0x23)] {
        for option in [0i16, 1] {
            let mut r = Rig::generic();
            r.write(object, 0, &option.to_le_bytes());
            r.write(0x6084, 0, &3_600_000u32.to_le_bytes()); // 0.1 s from 1 rev/s
            pv_at(&mut r, 360_000);
            r.controlword(cw);
            r.run_ms(50.0);
            let sw = r.statusword() & 0x6F;
            if option == 0 {
                assert_eq!(sw, state, "{object:04X}h = 0: at once");
            } else {
                assert_eq!(sw, 0x27, "{object:04X}h = 1: still enabled, ramping");
                let w = r.drive().model().velocity();
                assert!((w - PI).abs() < 0.3, "half-way down the ramp: {w}");
                r.run_ms(60.0);
                assert_eq!(r.statusword() & 0x6F, state, "{object:04X}h = 1: after the ramp");
            }
        }
    }
}

/// 607Fh max profile velocity caps 6081h; 60C5h / 60C6h max acceleration
/// and deceleration cap 6083h / 6084h.
#[test]
fn profile_limits_cap_the_pp_profile() {
    let mut r = pp_rig();
    r.write(0x6081, 0, &720_000u32.to_le_bytes()); // 2 rev/s …
    r.write(0x607F, 0, &360_000u32.to_le_bytes()); // … capped at 1 rev/s
    r.write(0x6083, 0, &36_000_000u32.to_le_bytes()); // 100 rev/s² …
    r.write(0x60C5, 0, &3_600_000u32.to_le_bytes()); // … capped at 10 rev/s²
    r.write(0x6084, 0, &36_000_000u32.to_le_bytes());
    r.write(0x60C6, 0, &1_800_000u32.to_le_bytes()); // 5 rev/s²
    r.enable();
    move_to(&mut r, (2.0 * REV) as i32);
    // 50 ms at 10 rev/s²: 0.5 rev/s.
    r.run_ms(49.0);
    let v = r.read(0x606B, 0) as i32;
    assert!((v - 180_000).abs() < 5_000, "accelerating at 60C5h: {v}");
    r.run_ms(500.0);
    assert_eq!(r.read(0x606B, 0) as i32, 360_000, "at 607Fh");
    // Decelerating at 5 rev/s² from 1 rev/s takes 0.2 s: the move of
    // 2 rev ends 0.1 + 1.9 - ... later; check the slope on the way down.
    let t = r.run_until(125, 3000.0, |r| r.drive().demand_velocity() < 359_000.0).unwrap();
    assert!(t > 0.5, "{t}");
    r.run_ms(100.0);
    let v = r.read(0x606B, 0) as i32;
    assert!((v - 180_000).abs() < 5_000, "decelerating at 60C6h: {v}");
}

/// 6073h max current limits the torque demand like 6072h.
#[test]
fn max_current_limits_the_torque() {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[4]);
    r.write(0x6073, 0, &40u16.to_le_bytes());
    r.write(0x6087, 0, &100_000u32.to_le_bytes());
    r.enable();
    r.write(0x6071, 0, &500i16.to_le_bytes());
    r.run_ms(5.0);
    assert_eq!(r.read(0x6074, 0) as i16, 40);
    // 6078h current actual, in ‰ of 6075h, follows.
    let i = r.read(0x6078, 0) as i16;
    assert!((i - 40).abs() <= 3, "6078h {i}");
}

/// 6067h position window and 6068h position window time decide statusword
/// bit 10 in pp.
#[test]
fn position_window_and_time_decide_target_reached() {
    let mut r = pp_rig();
    r.write(0x6068, 0, &50u16.to_le_bytes());
    r.write(0x6067, 0, &1000u32.to_le_bytes());
    r.write(0x6065, 0, &u32::MAX.to_le_bytes());
    r.enable();
    r.run_ms(40.0);
    assert_eq!(r.statusword() & SW_REACHED, 0, "inside 6067h for 40 of 6068h's 50 ms");
    r.run_ms(15.0);
    assert_ne!(r.statusword() & SW_REACHED, 0);
    // A load pushes the axis out of the window: bit 10 drops; back in, it
    // returns after 6068h.
    r.drive_mut().inject(Injection::Model(Plant::LoadTorqueStep(5.0)));
    let t = r.run_until(125, 500.0, |r| r.drive().statusword() & SW_REACHED == 0).unwrap();
    let off = (r.drive().position() as f64 - 0.0).abs();
    assert!(off > 1000.0 && off < 3000.0, "left the window after {t} s at {off}");
    r.drive_mut().inject(Injection::Model(Plant::LoadTorqueStep(0.0)));
    let t = r.run_until(125, 2000.0, |r| r.drive().statusword() & SW_REACHED != 0).unwrap();
    assert!(t >= 0.05, "{t}");
}

/// 6049h vl velocity deceleration: Δspeed per Δtime on the way down.
#[test]
fn vl_deceleration_ramps_down() {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[2]);
    r.write(0x6048, 1, &6000u32.to_le_bytes());
    r.write(0x6048, 2, &1u16.to_le_bytes());
    r.write(0x6049, 1, &300u32.to_le_bytes()); // 300 rpm per 1 s
    r.write(0x6049, 2, &1u16.to_le_bytes());
    r.enable();
    r.write(0x6042, 0, &300i16.to_le_bytes());
    r.run_ms(200.0);
    assert_eq!(r.read(0x6043, 0) as i16, 300);
    r.write(0x6042, 0, &0i16.to_le_bytes());
    r.run_ms(500.0);
    let d = r.read(0x6043, 0) as i16;
    assert!((d - 150).abs() <= 1, "6043h {d}");
}

/// The actual values: 6062h position demand, 6063h internal position
/// (encoder increments), 60F4h following error, 6079h DC link voltage.
#[test]
fn actual_values_follow_the_drive() {
    let mut r = pp_rig();
    // mV: the supply's 320 V at rest.
    assert_eq!(r.read(0x6079, 0), 320_000);
    r.enable();
    move_to(&mut r, (REV / 4.0) as i32);
    r.run_ms(1000.0);
    assert_eq!(r.read(0x6062, 0) as i32, 90_000);
    // 2^20 increments per revolution.
    let inc = r.read(0x6063, 0) as i32;
    assert!((inc - (1 << 18)).abs() <= 300, "6063h {inc}");
    // A load the motor cannot hold pushes the axis off: the demand stays,
    // 60F4h is demand − actual.
    r.write(0x6065, 0, &u32::MAX.to_le_bytes());
    r.drive_mut().inject(Injection::Model(Plant::LoadTorqueStep(5.0)));
    r.run_ms(20.0);
    let (demand, actual, fe) = (r.read(0x6062, 0) as i32, r.read(0x6064, 0) as i32, r.read(0x60F4, 0) as i32);
    assert_eq!(demand, 90_000);
    assert!(actual > 95_000, "pushed off: {actual}");
    assert!((fe - (demand - actual)).abs() <= 1, "60F4h {fe}, {demand} − {actual}");
    r.drive_mut().inject(Injection::Model(Plant::LoadTorqueStep(0.0)));
    // What the DC link is forced to.
    r.drive_mut().inject(Injection::Model(Plant::BusVoltage(Some(300.0))));
    r.run_ms(1.0);
    assert_eq!(r.read(0x6079, 0), 300_000);
}

/// 6088h torque profile type: only 0 (linear) is offered.
#[test]
fn torque_profile_type_is_linear_only() {
    let mut r = Rig::generic();
    r.write_aborts(0x6088, 0, &1i16.to_le_bytes(), 0x0609_0030);
    r.write(0x6088, 0, &0i16.to_le_bytes());
    assert_eq!(r.read(0x6088, 0), 0);
}

/// 6075h motor rated current and 6076h motor rated torque are the bases
/// of the per-mille values: the same 6071h asks twice the torque of a
/// motor rated twice as strong; 6078h reads in ‰ of 6075h.
#[test]
fn rated_current_and_torque_are_the_per_mille_bases() {
    let torque_at = |rated_torque: u32, rated_current: u32| {
        let mut r = Rig::generic();
        r.write(0x6060, 0, &[4]);
        r.write(0x6076, 0, &rated_torque.to_le_bytes());
        r.write(0x6075, 0, &rated_current.to_le_bytes());
        r.write(0x6087, 0, &100_000u32.to_le_bytes());
        r.enable();
        r.write(0x6071, 0, &100i16.to_le_bytes());
        r.run_ms(5.0);
        (r.drive().model().torque(), r.read(0x6078, 0) as i16)
    };
    let (t1, i1) = torque_at(640, 1600);
    let (t2, i2) = torque_at(1280, 1600);
    let (t3, i3) = torque_at(640, 3200);
    assert!((t1 - 0.064).abs() < 0.003, "100 ‰ of 0.64 N·m: {t1}");
    assert!((t2 - 2.0 * t1).abs() < 0.005, "{t2} vs {t1}");
    assert!((i2 - 2 * i1).abs() <= 4, "twice the current: {i2} vs {i1}");
    assert!(
        (t3 - t1).abs() < 0.003 && (2 * i3 - i1).abs() <= 4,
        "half the ‰ of a doubled 6075h: {i3} vs {i1}"
    );
}

/// 605Dh halt option code: 1 halts on the slow-down ramp (6084h), 2 on the
/// quick-stop ramp (6085h).
#[test]
fn halt_option_code_selects_the_ramp() {
    let mut stop_time = Vec::new();
    for option in [1i16, 2] {
        let mut r = Rig::generic();
        r.write(0x605D, 0, &option.to_le_bytes());
        r.write(0x6084, 0, &1_800_000u32.to_le_bytes()); // 0.2 s from 1 rev/s
        r.write(0x6085, 0, &18_000_000u32.to_le_bytes()); // 0.02 s
        pv_at(&mut r, 360_000);
        r.controlword(0x10F);
        let t = r.run_until(125, 1000.0, |r| r.drive().model().velocity().abs() < 0.05).unwrap();
        stop_time.push(t);
    }
    assert!((stop_time[0] - 0.2).abs() < 0.02, "605Dh = 1: {}", stop_time[0]);
    assert!((stop_time[1] - 0.02).abs() < 0.01, "605Dh = 2: {}", stop_time[1]);
}

/// 606Fh velocity threshold and 6070h velocity threshold time decide pv
/// statusword bit 12 "speed = 0".
#[test]
fn velocity_threshold_and_time_decide_speed_zero() {
    const SPEED_ZERO: u16 = 1 << 12;
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[3]);
    r.write(0x606F, 0, &60_000u16.to_le_bytes());
    r.write(0x6070, 0, &50u16.to_le_bytes());
    r.enable();
    r.run_ms(40.0);
    assert_eq!(r.statusword() & SPEED_ZERO, 0, "at rest for 40 of 6070h's 50 ms");
    r.run_ms(15.0);
    assert_ne!(r.statusword() & SPEED_ZERO, 0);
    // 36 000 units/s (0.1 rev/s) is inside a 60 000 threshold …
    r.write(0x60FF, 0, &36_000i32.to_le_bytes());
    r.run_ms(200.0);
    assert!(r.drive().model().velocity() > 0.5, "moving");
    assert_ne!(r.statusword() & SPEED_ZERO, 0, "below 606Fh");
    // … and outside a 20 000 one.
    r.write(0x606F, 0, &20_000u16.to_le_bytes());
    r.run_ms(5.0);
    assert_eq!(r.statusword() & SPEED_ZERO, 0, "above 606Fh");
}
