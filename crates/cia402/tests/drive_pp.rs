//! Profile position (CiA 402-2 §6.7) on the virtual bus: analytic move
//! times, set-point handshake, set of set-points, change immediately,
//! relative moves, software limits, halt, position range.

mod drive_rig;
use drive_rig::*;

const V: u32 = 7_200_000; // 20 rev/s in 0.001°/s
const A: u32 = 72_000_000;
const D: u32 = 36_000_000;
const SW_ACK: u16 = 1 << 12;
const SW_REACHED: u16 = 1 << 10;
const SW_LIMIT: u16 = 1 << 11;

/// Analytic trapezoid duration from rest to rest.
fn trapezoid(dist: f64, v: f64, a: f64, d: f64) -> f64 {
    let vp = (dist / (1.0 / (2.0 * a) + 1.0 / (2.0 * d))).sqrt();
    if vp <= v { vp / a + vp / d } else { dist / v + v / (2.0 * a) + v / (2.0 * d) }
}

fn rig() -> Rig {
    let mut r = Rig::generic();
    r.write(0x6081, 0, &V.to_le_bytes());
    r.write(0x6083, 0, &A.to_le_bytes());
    r.write(0x6084, 0, &D.to_le_bytes());
    r.write(0x6067, 0, &360u32.to_le_bytes()); // 0.36°
    r.write(0x6068, 0, &0u16.to_le_bytes());
    r.enable();
    r.run_ms(1.0);
    r
}

fn sw(r: &Rig) -> u16 {
    r.drive().statusword()
}

/// Sets 607Ah and raises bit 4 with `bits` (5, 6, 9), waits for the
/// acknowledge (bit 12), then lowers bit 4.
fn setpoint(r: &mut Rig, target: i32, bits: u16) {
    r.write(0x607A, 0, &target.to_le_bytes());
    r.controlword(0x0F | 0x10 | bits);
    r.run_until(25, 5.0, |r| sw(r) & SW_ACK != 0).expect("acknowledged");
    r.controlword(0x0F | bits);
}

fn move_time(dist: i32) {
    let mut r = rig();
    r.write(0x607A, 0, &dist.to_le_bytes());
    r.controlword(0x1F);
    let t_ack = r.run_until(25, 5.0, |r| sw(r) & SW_ACK != 0).expect("acknowledged");
    assert!(t_ack <= 125e-6 + 25e-6, "ack within one control period: {t_ack}");
    r.controlword(0x0F);
    let t = r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).expect("target reached") + t_ack;
    let expect = trapezoid(f64::from(dist).abs(), f64::from(V), f64::from(A), f64::from(D));
    eprintln!("move {dist}: {t:.6} s, analytic {expect:.6} s");
    assert!((t - expect).abs() <= 0.01 * expect, "move {dist}: {t} s vs analytic {expect} s");
    let pos = r.read(0x6064, 0) as i32;
    assert!((pos - dist).abs() <= 360, "final position {pos} within 6067h of {dist}");
    assert_eq!(r.read(0x6062, 0) as i32, dist, "demand ends exactly on target");
}

#[test]
fn trapezoidal_move_duration_is_analytic() {
    move_time(3_600_000); // 10 revolutions: cruise phase
}

#[test]
fn triangular_move_duration_is_analytic() {
    move_time(-360_000); // 1 revolution: never reaches 6081h
}

#[test]
fn sin2_profile_has_same_duration() {
    let mut r = rig();
    r.write(0x6086, 0, &1i16.to_le_bytes());
    setpoint(&mut r, 1_800_000, 0);
    r.controlword(0x0F);
    let t = r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    let expect = trapezoid(1.8e6, f64::from(V), f64::from(A), f64::from(D));
    assert!((t - expect).abs() <= 0.01 * expect, "{t} vs {expect}");
}

#[test]
fn set_of_setpoints_buffers_one_and_holds_ack() {
    let mut r = rig();
    setpoint(&mut r, 360_000, 0);
    r.run_us(200);
    r.controlword(0x0F);
    r.run_us(200);
    // First set-point running, buffer empty: acknowledge cleared.
    assert_eq!(sw(&r) & SW_ACK, 0);
    setpoint(&mut r, 720_000, 0);
    r.run_us(200);
    r.controlword(0x0F);
    r.run_us(200);
    // Buffered: bit 12 stays set while the buffer is occupied.
    assert_ne!(sw(&r) & SW_ACK, 0);
    // A third set-point while the buffer is full is ignored.
    setpoint(&mut r, 5_000_000, 0);
    r.run_us(200);
    r.controlword(0x0F);
    let t1 = trapezoid(360_000.0, f64::from(V), f64::from(A), f64::from(D));
    let t_free = r.run_until(125, 2000.0, |r| sw(r) & SW_ACK == 0).unwrap() + 800e-6;
    assert!((t_free - t1).abs() < 0.01 * t1, "buffer freed at the end of move 1: {t_free} vs {t1}");
    let t2 = trapezoid(360_000.0, f64::from(V), f64::from(A), f64::from(D));
    let t_done = r.run_until(125, 2000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert!((t_done - t2).abs() < 0.01 * t2 + 2e-3, "second move {t_done} vs {t2}");
    assert!((r.read(0x6064, 0) as i32 - 720_000).abs() <= 360);
}

#[test]
fn change_immediately_reverses_at_once() {
    let mut r = rig();
    setpoint(&mut r, 3_600_000, 0);
    r.controlword(0x0F);
    r.run_ms(200.0);
    assert_eq!(sw(&r) & SW_REACHED, 0);
    r.write(0x607A, 0, &0i32.to_le_bytes());
    r.controlword(0x3F);
    r.run_us(200);
    assert_ne!(sw(&r) & SW_ACK, 0);
    r.controlword(0x0F);
    r.run_us(200);
    assert_eq!(sw(&r) & SW_ACK, 0);
    r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert!((r.read(0x6064, 0) as i32).abs() <= 360);
}

#[test]
fn change_on_setpoint_passes_without_stopping() {
    let mut r = rig();
    setpoint(&mut r, 1_800_000, 0);
    r.controlword(0x0F);
    r.run_ms(10.0);
    setpoint(&mut r, 3_600_000, 1 << 9);
    r.controlword(0x0F);
    // The axis passes 1 800 000 at speed: never at rest in between.
    let mut min_v_after_start = f64::MAX;
    for _ in 0..400 {
        r.run_ms(1.0);
        let p = r.drive().position();
        if p > 400_000 && p < 3_000_000 {
            min_v_after_start = min_v_after_start.min(r.drive().demand_velocity());
        }
    }
    assert!(min_v_after_start > 0.5 * f64::from(V), "kept moving: {min_v_after_start}");
    r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert!((r.read(0x6064, 0) as i32 - 3_600_000).abs() <= 360);
}

#[test]
fn relative_moves_add_to_the_previous_target() {
    let mut r = rig();
    for k in 1..=3 {
        setpoint(&mut r, 100_000, 1 << 6);
        r.controlword(0x4F);
        r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
        assert!((r.read(0x6064, 0) as i32 - 100_000 * k).abs() <= 360);
    }
}

#[test]
fn software_limits_clamp_and_flag_internal_limit() {
    let mut r = rig();
    r.write(0x607D, 2, &500_000i32.to_le_bytes());
    r.write(0x607D, 1, &(-500_000i32).to_le_bytes());
    setpoint(&mut r, 1_000_000, 0);
    r.controlword(0x0F);
    r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert_ne!(sw(&r) & SW_LIMIT, 0, "bit 11 internal limit active");
    assert!((r.read(0x6064, 0) as i32 - 500_000).abs() <= 360);
    setpoint(&mut r, 0, 0);
    r.controlword(0x0F);
    r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert_eq!(sw(&r) & SW_LIMIT, 0);
}

#[test]
fn halt_stops_and_resumes() {
    let mut r = rig();
    setpoint(&mut r, 3_600_000, 0);
    r.controlword(0x0F);
    r.run_ms(300.0);
    r.controlword(0x10F);
    // 605Dh = 1: profile deceleration; stop time v/d.
    let t = r.run_until(125, 1000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert!(t <= f64::from(V) / f64::from(D) + 0.002, "halted in {t}");
    let p = r.drive().position();
    assert!(p < 3_600_000 - 360);
    r.controlword(0x0F);
    r.run_us(200);
    assert_eq!(sw(&r) & SW_REACHED, 0, "moving again");
    r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    assert!((r.read(0x6064, 0) as i32 - 3_600_000).abs() <= 360);
}

#[test]
fn modulo_axis_takes_the_short_way() {
    let mut r = rig();
    r.write(0x607B, 2, &359_999i32.to_le_bytes());
    setpoint(&mut r, 350_000, 0);
    r.controlword(0x0F);
    r.run_until(125, 3000.0, |r| sw(r) & SW_REACHED != 0).unwrap();
    // 0 → 350° the short way is −10°; 6064h shows the wrapped value.
    assert!((r.drive().position() + 10_000).abs() <= 360, "{}", r.drive().position());
    assert!((r.read(0x6064, 0) as i32 - 350_000).abs() <= 360);
}

/// `TargetReached::ActualInWindow`: with a wide position window bit 10
/// sets before the trajectory ends, and a buffered set-point starts there
/// (the acknowledge clears) instead of at the trajectory's end.
#[test]
fn reached_on_the_actual_position_alone() {
    use drivebus_cia402::drive::{DriveConfig, TargetReached};
    let t1 = trapezoid(360_000.0, f64::from(V), f64::from(A), f64::from(D));
    let run = |rule: TargetReached| {
        let cfg = DriveConfig { target_reached: rule, ..DriveConfig::default() };
        let mut r = Rig::with_config(cfg);
        r.write(0x6081, 0, &V.to_le_bytes());
        r.write(0x6083, 0, &A.to_le_bytes());
        r.write(0x6084, 0, &D.to_le_bytes());
        r.write(0x6067, 0, &36_000u32.to_le_bytes()); // 36°
        r.write(0x6068, 0, &0u16.to_le_bytes());
        r.enable();
        r.run_ms(1.0);
        setpoint(&mut r, 360_000, 0);
        r.run_us(200);
        r.controlword(0x0F);
        r.run_us(200);
        setpoint(&mut r, 720_000, 0);
        r.run_us(200);
        r.controlword(0x0F);
        r.run_us(200);
        assert_ne!(sw(&r) & SW_ACK, 0, "buffered");
        assert_eq!(sw(&r) & SW_REACHED, 0, "far from the target");
        r.run_until(125, 2000.0, |r| sw(r) & SW_ACK == 0).unwrap() + 800e-6
    };
    let by_window = run(TargetReached::ActualInWindow);
    let by_profile = run(TargetReached::ProfileDone);
    assert!((by_profile - t1).abs() < 0.01 * t1, "profile rule: at the end {by_profile} vs {t1}");
    // 36° before a target approached at D = 36 000°/s²: sqrt(2·36/36000) s early.
    let early = (2.0 * 36.0 / 36_000.0f64).sqrt();
    assert!((t1 - by_window - early).abs() < 0.003, "window rule: {by_window} = {t1} − ~{early}");
}
