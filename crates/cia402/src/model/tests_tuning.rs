//! Run-time parameters: gains, motor data, direction-dependent limits and
//! the I²t foldback change what the running model does.

use super::tests::run;
use super::*;

/// The largest |position error| \[rad\] while the demand ramps at
/// `speed` rad/s for `seconds` (velocity feed-forward included).
fn ramp_error(m: &mut DriveModel, speed: f64, seconds: f64) -> f64 {
    let dt = m.params().control_period();
    let n = libm::round(seconds / dt) as u64;
    let mut worst: f64 = 0.0;
    for k in 1..=n {
        let p = speed * k as f64 * dt;
        m.set_demand(Demand::Position { position: p, velocity: speed, acceleration: 0.0 });
        m.step(dt);
        worst = worst.max((p - m.position()).abs());
    }
    worst
}

fn tuned(f: impl FnOnce(&mut DriveParams)) -> DriveModel {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    let mut p = *m.params();
    f(&mut p);
    m.set_params(p).unwrap();
    m
}

#[test]
fn higher_position_gain_follows_closer() {
    // Without feed-forward the lag is the speed over the gain.
    let with_kp = |kp: f64| {
        ramp_error(
            &mut tuned(|p| {
                p.control.position_kp = kp;
                p.control.velocity_feedforward = 0.0;
            }),
            20.0,
            0.3,
        )
    };
    let (soft, stiff) = (with_kp(20.0), with_kp(300.0));
    assert!(stiff < soft * 0.5, "kp 300: {stiff}, kp 20: {soft}");
}

#[test]
fn velocity_feedforward_share_matters() {
    let full = ramp_error(&mut tuned(|_| {}), 20.0, 0.3);
    let none = ramp_error(&mut tuned(|p| p.control.velocity_feedforward = 0.0), 20.0, 0.3);
    assert!(none > full * 3.0, "without feed-forward {none}, with {full}");
}

#[test]
fn higher_velocity_gain_rejects_a_load_step_better() {
    let sag = |kp: f64| {
        let mut m = tuned(|p| p.control.velocity_kp = kp);
        m.set_demand(Demand::Velocity { velocity: 50.0, acceleration: 0.0 });
        run(&mut m, 0.3);
        m.inject(ModelInjection::LoadTorqueStep(-0.5));
        let dt = m.params().control_period();
        let mut worst: f64 = 0.0;
        for _ in 0..400 {
            m.step(dt);
            worst = worst.max(50.0 - m.velocity());
        }
        worst
    };
    let (low, high) = (sag(0.02), sag(0.2));
    assert!(high < low * 0.5, "kp 0.2: {high}, kp 0.02: {low}");
}

#[test]
fn larger_inertia_accelerates_slower_at_the_same_torque() {
    let speed_after = |j: f64| {
        let mut m = tuned(|p| p.motor.rotor_inertia = j);
        m.set_demand(Demand::Torque(0.2));
        run(&mut m, 0.01);
        m.velocity()
    };
    let (light, heavy) = (speed_after(1.6e-5), speed_after(6.4e-5));
    // J·dω/dt = T − friction: four times the total inertia (3.2e-5 →
    // 8.0e-5 with the load) takes 2.5 times longer.
    assert!((light / heavy - 2.5).abs() < 0.1, "{light} vs {heavy}");
}

#[test]
fn torque_constant_scales_the_torque_of_a_current() {
    let mut m = tuned(|p| p.motor.kt = 0.8);
    m.set_demand(Demand::Torque(0.4));
    run(&mut m, 0.01);
    assert!((m.current() - 0.5).abs() < 0.01, "0.4 Nm at 0.8 Nm/A: {} A", m.current());
}

#[test]
fn machine_fixed_parameters_are_refused() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    let mut p = *m.params();
    p.encoder.counts_per_rev = 4096;
    assert_eq!(m.set_params(p).unwrap_err().field, "encoder");
    let mut p = *m.params();
    p.control.control_rate_hz = 4000.0;
    assert_eq!(m.set_params(p).unwrap_err().field, "control.control_rate_hz");
    let mut p = *m.params();
    p.motor.kt = -1.0;
    assert_eq!(m.set_params(p).unwrap_err().field, "motor.kt");
    assert_eq!(m.params().motor.kt, DriveParams::servo_small().motor.kt, "unchanged");
}

#[test]
fn current_limits_differ_by_direction() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    m.set_current_limits(2.0, 1.0).unwrap();
    m.set_demand(Demand::Torque(10.0));
    run(&mut m, 0.005);
    assert!((m.current() - 2.0).abs() < 1e-6, "positive: {}", m.current());
    m.set_demand(Demand::Torque(-10.0));
    run(&mut m, 0.005);
    assert!((m.current() + 1.0).abs() < 1e-6, "negative: {}", m.current());
    assert!(m.set_current_limits(f64::NAN, 1.0).is_err());
    assert!(m.set_current_limits(-1.0, 1.0).is_err());
}

#[test]
fn velocity_limits_differ_by_direction() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    m.set_velocity_limits(100.0, 30.0).unwrap();
    m.set_demand(Demand::Velocity { velocity: 300.0, acceleration: 0.0 });
    run(&mut m, 0.3);
    assert!((m.velocity() - 100.0).abs() < 1.0, "positive: {}", m.velocity());
    m.set_demand(Demand::Velocity { velocity: -300.0, acceleration: 0.0 });
    run(&mut m, 0.3);
    assert!((m.velocity() + 30.0).abs() < 1.0, "negative: {}", m.velocity());
}

#[test]
fn foldback_brings_a_blocked_motor_down_to_its_continuous_current() {
    let mut p = DriveParams::servo_small();
    p.axis.positive_stop = Some(1.0);
    let mut m = DriveModel::new(p).unwrap();
    let f = FoldbackParams { continuous: 1.6, peak: 6.4, time_constant: 0.1 };
    m.set_foldback(Some(f)).unwrap();
    m.set_demand(Demand::Torque(10.0));
    run(&mut m, 0.01);
    assert!(m.current() > 6.0, "cold: the peak current, {}", m.current());
    run(&mut m, 2.0);
    assert!(m.at_hard_stop() == Some(true));
    let i = m.current();
    assert!((i - 1.6).abs() < 0.2, "folded back to the continuous current: {i}");
    assert!(m.foldback_current().unwrap() < 1.8);
    // Unloaded it recovers towards the peak.
    m.set_demand(Demand::Off);
    run(&mut m, 1.0);
    assert!(m.foldback_current().unwrap() > 6.0, "{:?}", m.foldback_current());
    assert!(m.set_foldback(Some(FoldbackParams { peak: 1.0, ..f })).is_err());
    m.set_foldback(None).unwrap();
    assert_eq!(m.foldback_current(), None);
}

#[test]
fn current_feedforward_adds_an_offset_and_friction_compensation() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    m.set_current_feedforward(0.5, 0.0).unwrap();
    m.set_demand(Demand::Torque(0.0));
    run(&mut m, 0.005);
    assert!((m.current() - 0.5).abs() < 1e-3, "offset: {}", m.current());
    // Friction compensation pushes the way the motor turns.
    m.set_current_feedforward(0.0, 0.3).unwrap();
    m.set_motion(0.0, -10.0);
    run(&mut m, 0.002);
    assert!((m.current() + 0.3).abs() < 0.01, "friction, turning negative: {}", m.current());
    assert!(m.set_current_feedforward(0.0, -1.0).is_err());
    assert!(m.set_current_feedforward(f64::NAN, 0.0).is_err());
}

#[test]
fn voltage_limit_caps_the_speed_at_the_back_emf() {
    let top = |limit: f64| {
        let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
        m.set_voltage_limit(limit).unwrap();
        m.set_demand(Demand::Velocity { velocity: 600.0, acceleration: 0.0 });
        run(&mut m, 0.5);
        m.velocity()
    };
    let (free, capped) = (top(f64::INFINITY), top(100.0));
    // kₑ = 0.4 V·s/rad: 100 V hold at most 250 rad/s.
    assert!(free > 590.0, "{free}");
    assert!(capped < 250.0 && capped > 200.0, "{capped}");
}

#[test]
fn regen_power_while_braking_into_the_chopper() {
    let mut p = DriveParams::servo_small();
    p.axis.load_inertia = 1e-3;
    let mut m = DriveModel::new(p).unwrap();
    m.set_demand(Demand::Velocity { velocity: 300.0, acceleration: 0.0 });
    run(&mut m, 0.5);
    assert_eq!(m.regen_power(), 0.0, "motoring");
    m.set_demand(Demand::Velocity { velocity: 0.0, acceleration: 0.0 });
    let dt = m.params().control_period();
    let mut peak: f64 = 0.0;
    for _ in 0..2000 {
        m.step(dt);
        peak = peak.max(m.regen_power());
    }
    // Braking at 2.56 N·m from 300 rad/s returns up to ~770 W.
    assert!(peak > 100.0 && peak < 1000.0, "{peak} W");
}
