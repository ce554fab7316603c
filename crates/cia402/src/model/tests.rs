//! Motor, loop, thermal and DC link checks against analytic solutions
//! computed independently of the implementation.

use super::*;

pub(super) fn run(m: &mut DriveModel, seconds: f64) {
    let dt = m.params().control_period();
    let n = libm::round(seconds / dt) as u64;
    for _ in 0..n {
        m.step(dt);
    }
}

pub(super) fn frictionless(mut p: DriveParams) -> DriveParams {
    p.motor.viscous_friction = 0.0;
    p.motor.coulomb_friction = 0.0;
    p.motor.static_friction = 0.0;
    p
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

#[test]
fn presets_are_valid() {
    for p in [DriveParams::servo_small(), DriveParams::servo_medium(), DriveParams::stepper()] {
        p.validate().unwrap();
        DriveModel::new(p).unwrap();
    }
}

#[test]
fn invalid_parameters_are_refused() {
    let mut p = DriveParams::servo_small();
    p.motor.kt = f64::NAN;
    assert_eq!(p.validate().unwrap_err().field, "motor.kt");
    let mut p = DriveParams::servo_small();
    p.control.control_rate_hz = 1000.0;
    assert_eq!(DriveModel::new(p).unwrap_err().field, "control.control_rate_hz");
    let mut p = DriveParams::servo_small();
    p.motor.static_friction = 0.0;
    assert!(p.validate().is_err());
    let mut p = DriveParams::servo_small();
    p.axis.home_switch = Some((2.0, 1.0));
    assert!(p.validate().is_err());
    let mut p = DriveParams::servo_small();
    p.axis.gear_ratio = 1e300;
    p.axis.positive_limit = Some(1e300);
    assert!(DriveModel::new(p).is_err());
    let mut p = DriveParams::stepper();
    if let MotorKind::Stepper(s) = &mut p.motor.kind {
        s.full_steps = 202;
    }
    assert!(p.validate().is_err());
}

#[test]
fn bad_inputs_do_nothing() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    assert!(!m.set_demand(Demand::Torque(f64::INFINITY)));
    assert_eq!(m.demand(), Demand::Off);
    let before = m.clone();
    for dt in [0.0, -1.0, f64::NAN, 1.0] {
        assert!(m.step(dt).is_empty());
    }
    assert_eq!(m, before);
    assert!(!m.set_motion(f64::NAN, 0.0));
}

/// Pure inertia under constant torque: ω = T/J·t (current lag 0.2 ms
/// shifts this by < 0.1 % at the sample times).
#[test]
fn constant_torque_accelerates_inertia() {
    let mut m = DriveModel::new(frictionless(DriveParams::servo_small())).unwrap();
    let (t, j) = (0.1, 3.2e-5);
    m.set_demand(Demand::Torque(t));
    for k in 1..=4 {
        run(&mut m, 0.05);
        let time = 0.05 * f64::from(k);
        assert!(rel(m.velocity(), t / j * time) < 0.005, "{} at {time}", m.velocity());
    }
}

/// Coasting with viscous friction only: ω = ω₀·e^(−t·b/J).
#[test]
fn viscous_decay_time_constant() {
    let mut p = frictionless(DriveParams::servo_small());
    p.motor.viscous_friction = 1e-5;
    let mut m = DriveModel::new(p).unwrap();
    let tau = 3.2e-5 / 1e-5;
    m.set_motion(0.0, 100.0);
    run(&mut m, tau / 2.0);
    assert!(rel(m.velocity(), 100.0 * (-0.5f64).exp()) < 0.005);
    run(&mut m, tau / 2.0);
    assert!(rel(m.velocity(), 100.0 / core::f64::consts::E) < 0.005);
}

/// Coulomb friction: linear deceleration to exactly zero at t = J·ω₀/T_c,
/// then rest without chatter.
#[test]
fn coulomb_friction_stops_without_chatter() {
    let mut p = frictionless(DriveParams::servo_small());
    p.motor.coulomb_friction = 0.01;
    p.motor.static_friction = 0.015;
    let mut m = DriveModel::new(p).unwrap();
    m.set_motion(0.0, 100.0);
    run(&mut m, 0.16);
    assert!(rel(m.velocity(), 50.0) < 0.005);
    for _ in 0..8000 {
        m.step(1.0 / 8000.0);
        assert!(m.velocity() >= 0.0);
    }
    assert_eq!(m.velocity(), 0.0);
    // A torque below break-away does not move the shaft.
    m.set_demand(Demand::Torque(0.012));
    run(&mut m, 0.1);
    assert_eq!(m.velocity(), 0.0);
    m.set_demand(Demand::Torque(0.02));
    run(&mut m, 0.01);
    assert!(m.velocity() > 0.0);
}

/// Voltage headroom: with load current I the speed saturates where
/// V_bus = kₑ·ω + R·I, i.e. ω = (V − R·I)/kₑ.
#[test]
fn bus_voltage_limits_speed() {
    let mut p = frictionless(DriveParams::servo_small());
    p.bus.capacitance = 0.0;
    p.axis.load = LoadTorque::Constant(-0.4); // I = 1 A at steady state
    let mut m = DriveModel::new(p).unwrap();
    m.set_demand(Demand::Torque(2.0));
    run(&mut m, 0.1);
    let expect = (320.0 - 5.0 * 1.0) / 0.4;
    assert!(rel(m.velocity(), expect) < 0.005, "{}", m.velocity());
    assert!(rel(m.current(), 1.0) < 0.005, "{}", m.current());
    // Lower bus (under-voltage injection) lowers the ceiling accordingly.
    m.inject(ModelInjection::BusVoltage(Some(160.0)));
    run(&mut m, 0.2);
    assert!(rel(m.velocity(), (160.0 - 5.0) / 0.4) < 0.005, "{}", m.velocity());
}

/// First-order thermal model: ϑ − ϑ_amb = R_th·P·(1 − e^(−t/(R_th·C_th))).
#[test]
fn thermal_step_response_and_over_temperature() {
    let mut p = DriveParams::servo_small();
    p.motor.thermal_resistance = 2.0;
    p.motor.thermal_capacity = 0.5;
    p.motor.max_temperature = 60.0;
    // Blocked rotor: the load balances the motor torque, stiction holds.
    p.axis.load = LoadTorque::Constant(-0.8);
    let mut m = DriveModel::new(p).unwrap();
    m.set_demand(Demand::Torque(0.8)); // 2 A → P = 5 Ω · 4 A² = 20 W
    let rise = 2.0 * 20.0;
    run(&mut m, 1.0);
    assert_eq!(m.velocity(), 0.0);
    assert!(rel(m.temperature() - 25.0, rise * (1.0 - (-1.0f64).exp())) < 0.005);
    assert!(!m.faults().over_temperature, "{}", m.temperature());
    run(&mut m, 4.0);
    assert!(rel(m.temperature() - 25.0, rise * (1.0 - (-5.0f64).exp())) < 0.005);
    assert!(m.faults().over_temperature, "{}", m.temperature());
    assert_eq!(m.faults().error_code(), Some(0x4310));
    // Still hot: a fault reset does not clear it.
    assert!(m.clear_faults().over_temperature);
    m.set_demand(Demand::Off);
    run(&mut m, 5.0);
    assert!(!m.clear_faults().any());
}

/// Velocity step into current saturation: anti-windup keeps the overshoot
/// small and the loop settles.
#[test]
fn velocity_step_settles_without_windup() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    m.set_demand(Demand::Velocity { velocity: 600.0, acceleration: 0.0 });
    let dt = 1.0 / 8000.0;
    let mut peak: f64 = 0.0;
    let mut saturated = 0;
    for _ in 0..800 {
        m.step(dt);
        peak = peak.max(m.velocity());
        if m.current().abs() > 0.99 * 6.4 {
            saturated += 1;
        }
    }
    assert!(saturated > 40, "the step must saturate the current loop ({saturated})");
    assert!(peak < 600.0 * 1.05, "overshoot {peak}");
    assert!(rel(m.velocity(), 600.0) < 0.01, "{}", m.velocity());
}

/// Gravity-like constant load held by the cascaded loops: zero steady-state
/// error with integral action (velocity PI, or position PI), and the
/// analytic offset T/(kₜ·K_v·K_p) with none.
#[test]
fn position_holds_against_gravity() {
    let load = -0.3;
    let base = {
        let mut p = frictionless(DriveParams::servo_small());
        p.axis.load = LoadTorque::Constant(load);
        p
    };
    let one_count = 2.0 * core::f64::consts::PI / f64::from(1u32 << 20);
    let hold = |p: DriveParams| {
        let mut m = DriveModel::new(p).unwrap();
        m.set_demand(Demand::Position { position: 0.0, velocity: 0.0, acceleration: 0.0 });
        run(&mut m, 1.0);
        m
    };
    let m = hold(base);
    assert!(m.position().abs() <= 1.5 * one_count, "{}", m.position());
    let mut p = base;
    p.control.velocity_ki = 0.0;
    p.control.position_ki = 4500.0;
    let m = hold(p);
    assert!(m.position().abs() <= 1.5 * one_count, "{}", m.position());
    p.control.position_ki = 0.0;
    let m = hold(p);
    let expect = load / (0.4 * 0.075 * 150.0);
    assert!(rel(m.position(), expect) < 0.02, "{} vs {expect}", m.position());
}

#[test]
fn regeneration_raises_bus_to_over_voltage() {
    let mut p = DriveParams::servo_small();
    p.bus.capacitance = 20e-6;
    p.bus.brake_on_voltage = None;
    let brake = |p: DriveParams| {
        let mut m = DriveModel::new(p).unwrap();
        m.set_demand(Demand::Velocity { velocity: 600.0, acceleration: 0.0 });
        run(&mut m, 0.1);
        assert!(!m.faults().any());
        m.set_demand(Demand::Velocity { velocity: 0.0, acceleration: 0.0 });
        let mut vmax: f64 = 0.0;
        for _ in 0..800 {
            m.step(1.0 / 8000.0);
            vmax = vmax.max(m.bus_voltage());
        }
        (m, vmax)
    };
    let (m, vmax) = brake(p);
    assert!(vmax > 420.0);
    assert_eq!(m.faults().error_code(), Some(0x3210));
    // A braking resistor keeps the bus near its switch-on voltage.
    p.bus.brake_on_voltage = Some(380.0);
    p.bus.brake_resistance = 10.0;
    let (m, vmax) = brake(p);
    assert!(!m.faults().any(), "{vmax}");
    assert!((380.0..400.0).contains(&vmax), "{vmax}");
}

#[test]
fn short_circuit_braking_stops_the_motor() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    m.set_motion(0.0, 600.0);
    m.set_demand(Demand::ShortCircuit);
    run(&mut m, 0.2);
    assert!(m.velocity().abs() < 1.0, "{}", m.velocity());
    assert!(!m.faults().any());
}

#[test]
fn fault_injection() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    let cases = [
        (ModelInjection::OverCurrent, 0x2310),
        (ModelInjection::BusOverVoltage, 0x3210),
        (ModelInjection::BusUnderVoltage, 0x3220),
        (ModelInjection::EncoderFailure, 0x7305),
        (ModelInjection::OverTemperature, 0x4310),
    ];
    for (inj, code) in cases {
        m.inject(inj);
        m.step(1.0 / 8000.0);
        assert_eq!(m.faults().error_code(), Some(code), "{inj:?}");
        assert!(m.clear_faults().any(), "condition still forced");
        m.inject(ModelInjection::Clear);
        m.step(1.0 / 8000.0);
        assert!(!m.clear_faults().any(), "{inj:?}");
    }
    // Encoder failure freezes the reading.
    m.set_motion(0.0, 10.0);
    m.inject(ModelInjection::EncoderFailure);
    let c = m.position_counts();
    run(&mut m, 0.01);
    assert_eq!(m.position_counts(), c);
    assert!(m.position() > 0.05);
    // A load torque step moves a free rotor.
    m.inject(ModelInjection::Clear);
    m.set_motion(0.0, 0.0);
    m.inject(ModelInjection::LoadTorqueStep(-0.5));
    run(&mut m, 0.01);
    assert!(m.velocity() < 0.0);
}

#[test]
fn medium_servo_tracks_a_position_ramp() {
    let mut m = DriveModel::new(DriveParams::servo_medium()).unwrap();
    let dt = m.params().control_period();
    let v = 100.0;
    let mut err: f64 = 0.0;
    for k in 0..8000 {
        let t = f64::from(k) * dt;
        m.set_demand(Demand::Position { position: v * t, velocity: v, acceleration: 0.0 });
        m.step(dt);
        if k > 2000 {
            err = err.max((v * (t + dt) - m.position()).abs());
        }
    }
    assert!(err < 0.01, "following error {err} rad");
}

/// Position-dependent load: a free unbalanced arm swings with the small-angle
/// period 2π·√(J/T_peak) (direct drive, so output angle = motor angle).
#[test]
fn pendulum_load_small_angle_period() {
    let mut p = frictionless(DriveParams::servo_small());
    let peak = 0.01;
    p.axis.load = LoadTorque::Pendulum { peak, zero: 0.0 };
    let mut m = DriveModel::new(p).unwrap();
    m.set_motion(0.01, 0.0);
    let dt = 1.0 / 8000.0;
    let mut crossings = Vec::new();
    let mut prev = m.position();
    for k in 0..40_000 {
        m.step(dt);
        let x = m.position();
        if prev > 0.0 && x <= 0.0 {
            // Interpolated downward zero crossing time.
            crossings.push((f64::from(k) + prev / (prev - x)) * dt);
        }
        prev = x;
    }
    let period = 2.0 * core::f64::consts::PI * (3.2e-5 / peak).sqrt();
    assert!(crossings.len() >= 3);
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    assert!(rel(measured, period) < 0.005, "{measured} vs {period}");
}

/// The preset loop tunings are stable at every supported control rate.
#[test]
fn presets_stable_from_4_to_16_khz() {
    for base in [DriveParams::servo_small(), DriveParams::servo_medium()] {
        for rate in [4000.0, 8000.0, 16000.0] {
            let mut p = base;
            p.control.control_rate_hz = rate;
            let mut m = DriveModel::new(p).unwrap();
            m.set_demand(Demand::Velocity { velocity: 50.0, acceleration: 0.0 });
            let mut peak: f64 = 0.0;
            for _ in 0..(rate as usize / 5) {
                m.step(1.0 / rate);
                peak = peak.max(m.velocity());
            }
            assert!(rel(m.velocity(), 50.0) < 0.01, "{rate}: {}", m.velocity());
            assert!(peak < 50.0 * 1.3, "{rate}: overshoot {peak}");
            m.set_demand(Demand::Position { position: 1.0, velocity: 0.0, acceleration: 0.0 });
            run(&mut m, 0.3);
            assert!((m.position() - 1.0).abs() < 1e-4, "{rate}: {}", m.position());
        }
    }
}
