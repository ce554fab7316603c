//! Encoder, switches, end stops and stepper checks.

use super::tests::{frictionless, run};
use super::*;
use core::f64::consts::PI;

const DT: f64 = 1.0 / 8000.0;

fn collect(m: &mut DriveModel, steps: usize) -> Vec<Event> {
    let mut all = Vec::new();
    for _ in 0..steps {
        all.extend_from_slice(m.step(DT).as_slice());
    }
    all
}

/// N revolutions pass the index N times, each at exactly φ + 2πk.
#[test]
fn index_pulse_once_per_revolution() {
    let mut p = frictionless(DriveParams::servo_small());
    p.encoder.index_angle = 1.0;
    let mut m = DriveModel::new(p).unwrap();
    m.set_motion(0.0, 50.0);
    // 10 revolutions + a bit: θ from 0 to 2π·10 + 0.5 (index at 1 rad ⇒ 10 pulses).
    let steps = libm::round((20.0 * PI + 0.5) / 50.0 / DT) as usize;
    let ev = collect(&mut m, steps);
    let idx: Vec<_> = ev.iter().filter(|e| e.kind == EventKind::Index).collect();
    assert_eq!(idx.len(), 10);
    for (k, e) in idx.iter().enumerate() {
        let x = 1.0 + 2.0 * PI * k as f64;
        assert!((e.position - x).abs() < 1e-12);
        assert_eq!(e.counts, libm::floor(x * m.counts_per_rad()) as i64);
        assert!(e.positive_direction && (0.0..=1.0).contains(&e.fraction));
    }
    // And back: the same 10 pulses in reverse order.
    m.set_motion(m.position(), -50.0);
    let ev = collect(&mut m, steps);
    let idx: Vec<_> = ev.iter().filter(|e| e.kind == EventKind::Index).collect();
    assert_eq!(idx.len(), 10);
    assert!((idx[0].position - (1.0 + 18.0 * PI)).abs() < 1e-12);
    assert!(!idx[0].positive_direction);
    // Several revolutions per step are all counted.
    m.set_motion(0.0, 200_000.0);
    let mut n = 0;
    for _ in 0..100 {
        n += m.step(DT).index_crossings();
    }
    let revs = m.position() / (2.0 * PI);
    assert!((f64::from(n) - revs).abs() <= 1.0, "{n} vs {revs}");
}

fn switched_axis() -> DriveParams {
    let mut p = frictionless(DriveParams::servo_small());
    p.axis.negative_limit = Some(-90.0);
    p.axis.positive_limit = Some(90.0);
    p.axis.home_switch = Some((10.0, 20.0));
    p
}

/// Switch edges are reported at the switch position, within one count.
#[test]
fn switch_edges_located_within_one_count() {
    let mut m = DriveModel::new(switched_axis()).unwrap();
    assert!(!m.switches().negative_limit);
    assert_eq!(m.switches().digital_inputs(), 0, "at 0°, inside no switch");
    m.set_motion(-2.0, 20.0);
    assert_eq!(m.switches().digital_inputs(), 1);
    let ev = collect(&mut m, 8000 * 2 / 10);
    let cpr = m.counts_per_rad();
    let deg = |d: f64| d * PI / 180.0;
    let sw: Vec<_> = ev.iter().filter(|e| e.kind != EventKind::Index).collect();
    let expect = [
        (EventKind::NegativeLimit, false, deg(-90.0)),
        (EventKind::Home, true, deg(10.0)),
        (EventKind::Home, false, deg(20.0)),
        (EventKind::PositiveLimit, true, deg(90.0)),
    ];
    assert_eq!(sw.len(), expect.len(), "{sw:?}");
    for (e, (kind, active, x)) in sw.iter().zip(expect) {
        assert_eq!((e.kind, e.active), (kind, active));
        assert!((e.counts as f64 - x * cpr).abs() <= 1.0);
        assert!(e.positive_direction);
    }
    assert_eq!(m.switches().digital_inputs(), 0b010);
    // Crossing the whole home switch within one step yields both edges in order.
    m.set_motion(deg(5.0), deg(20.0) / DT);
    let ev = m.step(DT).clone();
    let homes: Vec<_> = ev.iter().filter(|e| e.kind == EventKind::Home).collect();
    assert_eq!(homes.len(), 2);
    assert!(homes[0].active && !homes[1].active && homes[0].fraction < homes[1].fraction);
    assert!(!m.switches().home);
}

/// A limit switch with hysteresis turns on at its edge and off only the
/// hysteresis back inside it, where the release edge is reported.
#[test]
fn limit_switch_hysteresis() {
    let mut p = switched_axis();
    p.axis.limit_hysteresis = 1.0;
    let mut m = DriveModel::new(p).unwrap();
    let deg = |d: f64| d * PI / 180.0;
    let cpr = m.counts_per_rad();
    let at = |m: &mut DriveModel, d: f64| {
        m.set_motion(m.position(), (deg(d) - m.position()) / DT);
        let ev: Vec<_> = m.step(DT).iter().filter(|e| e.kind == EventKind::PositiveLimit).copied().collect();
        m.set_motion(m.position(), 0.0);
        ev
    };
    at(&mut m, 89.5);
    let on = at(&mut m, 90.5);
    assert_eq!(on.len(), 1);
    assert!(on[0].active && (on[0].counts as f64 - deg(90.0) * cpr).abs() <= 1.0);
    assert!(at(&mut m, 89.5).is_empty(), "still active inside the hysteresis");
    assert!(m.switches().positive_limit);
    let off = at(&mut m, 88.5);
    assert_eq!(off.len(), 1);
    assert!(!off[0].active && (off[0].counts as f64 - deg(89.0) * cpr).abs() <= 1.0);
    assert!(at(&mut m, 89.8).is_empty(), "not active again before the edge");
    assert!(!m.switches().positive_limit);
}

#[test]
fn hard_stop_stalls_the_motor() {
    let mut p = DriveParams::servo_small();
    p.axis.positive_stop = Some(45.0);
    let mut m = DriveModel::new(p).unwrap();
    m.set_demand(Demand::Velocity { velocity: 100.0, acceleration: 0.0 });
    let ev = collect(&mut m, 8000 * 3 / 10);
    let stop = PI / 4.0;
    let hit = ev.iter().find(|e| e.kind == EventKind::HardStop).unwrap();
    assert!(hit.active && (hit.position - stop).abs() < 1e-12);
    assert!(ev.iter().any(|e| e.kind == EventKind::Stall));
    assert_eq!(m.position(), stop);
    assert_eq!(m.velocity(), 0.0);
    assert!(m.stalled());
    assert_eq!(m.at_hard_stop(), Some(true));
    assert!(m.current() > 0.99 * 6.4, "velocity loop winds up to the limit: {}", m.current());
    m.set_demand(Demand::Velocity { velocity: -10.0, acceleration: 0.0 });
    run(&mut m, 0.1);
    assert!(m.position() < stop);
    assert!(!m.stalled());
    assert_eq!(m.at_hard_stop(), None);
}

#[test]
fn unit_conversion() {
    let mut p = DriveParams::servo_small();
    p.axis.kind = AxisKind::Linear;
    p.axis.feed_constant = 5.0; // mm per output revolution
    p.axis.gear_ratio = 2.0; // motor revolutions per output revolution
    p.axis.initial_position = 10.0;
    let m = DriveModel::new(p).unwrap();
    assert!((m.rad_to_units(2.0 * PI) - 2.5).abs() < 1e-12);
    assert!((m.rad_to_units(m.position()) - 10.0).abs() < 1e-12);
    assert!((m.units_to_rad(2.5) - 2.0 * PI).abs() < 1e-12);
    let j = AxisParams::reflected_mass_inertia(10.0, 0.005);
    assert!((j - 10.0 * (0.005 / (2.0 * PI)).powi(2)).abs() < 1e-18);
}

fn stepper(load: f64, closed_loop: bool) -> DriveModel {
    let mut p = DriveParams::stepper();
    p.axis.load = LoadTorque::Constant(load);
    if let MotorKind::Stepper(s) = &mut p.motor.kind {
        s.closed_loop = closed_loop;
    }
    DriveModel::new(p).unwrap()
}

const FULL_STEP: f64 = 2.0 * PI / 200.0;

/// Below the pull-out torque the rotor follows the micro-steps: lag under
/// load = asin(T_L/T_h)/N_r (< one full step), no lost steps.
#[test]
fn stepper_follows_below_pull_out() {
    let mut m = stepper(-0.8, false);
    m.set_demand(Demand::Velocity { velocity: 2.0 * PI, acceleration: 0.0 });
    run(&mut m, 1.0);
    m.set_demand(Demand::Position { position: m.demand_position(), velocity: 0.0, acceleration: 0.0 });
    run(&mut m, 0.5);
    assert!((m.demand_position() - 2.0 * PI).abs() < 1e-9);
    let lag = (0.8f64 / 1.2).asin() / 50.0;
    let err = m.demand_position() - m.position();
    assert!((err - lag).abs() < 0.05 * lag + 0.003, "lag {err} vs {lag}");
    assert!(err < FULL_STEP);
    assert_eq!(m.lost_steps(), 0);
    assert!(!m.stalled());
    // Micro-step quantisation of the demand.
    m.set_demand(Demand::Position { position: 0.3 * FULL_STEP / 16.0, velocity: 0.0, acceleration: 0.0 });
    assert!((m.demand_position() - 2.0 * PI).abs() < 1e-9);
    m.step(1.0 / 4000.0);
    assert_eq!(m.demand_position(), 0.0);
}

/// Above the pull-out torque the rotor slips by whole electrical periods
/// (4 full steps = 64 micro-steps each).
#[test]
fn stepper_stalls_above_pull_out() {
    let mut m = stepper(-1.5, false);
    m.set_demand(Demand::Position { position: 0.0, velocity: 0.0, acceleration: 0.0 });
    let mut stall_events = 0;
    for _ in 0..400 {
        stall_events += m.step(1.0 / 4000.0).iter().filter(|e| e.kind == EventKind::Stall).count();
    }
    assert!(m.stalled());
    assert!(stall_events > 0);
    let lost = m.lost_steps();
    assert!(lost >= 64 && lost % 64 == 0, "{lost}");
    assert!(m.position() < -4.0 * FULL_STEP);
    assert_eq!(m.demand_position(), 0.0, "open loop: the drive does not notice");
}

#[test]
fn closed_loop_stepper_does_not_lose_steps() {
    let mut m = stepper(-1.0, true);
    m.set_demand(Demand::Velocity { velocity: 2.0 * PI, acceleration: 0.0 });
    run(&mut m, 1.0);
    m.set_demand(Demand::Position { position: m.demand_position(), velocity: 0.0, acceleration: 0.0 });
    run(&mut m, 0.5);
    assert_eq!(m.lost_steps(), 0);
    assert!((m.demand_position() - m.position()).abs() < FULL_STEP);
    // Overloaded: pushed back, reported as stall, still no step loss.
    m.inject(ModelInjection::LoadTorqueStep(-0.5));
    run(&mut m, 0.2);
    assert!(m.stalled());
    assert_eq!(m.lost_steps(), 0);
}
