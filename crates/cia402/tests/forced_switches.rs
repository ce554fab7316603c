//! Forced switch inputs (`model::ModelInjection::ForceSwitch`): a limit switch
//! that trips without the axis being there (an obstacle, a broken wire of
//! a normally-closed switch) or a dead one. The level shows in 60FDh and as
//! an edge at the present position, so the drive reacts to it as to the
//! axis reaching the switch (CiA 402-2 §6.2: 60FDh bits 0–2).

use drivebus_cia402::model::{
    AxisParams, Demand, DriveModel, DriveParams, EventKind, ModelInjection, SwitchInput,
};

fn model() -> DriveModel {
    let mut p = DriveParams::servo_small();
    p.axis = AxisParams {
        negative_limit: Some(-1000.0),
        positive_limit: Some(1000.0),
        home_switch: Some((100.0, 200.0)),
        ..AxisParams::rotary_degrees(1.6e-5)
    };
    DriveModel::new(p).unwrap()
}

const DT: f64 = 1.0 / 8000.0;

#[test]
fn a_forced_limit_switch_is_an_edge_where_the_axis_is_and_a_release_too() {
    let mut m = model();
    m.step(DT);
    assert!(!m.switches().positive_limit);
    m.inject(ModelInjection::ForceSwitch(SwitchInput::PositiveLimit, Some(true)));
    let e = *m.step(DT).first(EventKind::PositiveLimit).expect("edge");
    assert!(e.active);
    assert_eq!(e.position, m.position());
    assert!(m.switches().positive_limit);
    assert_eq!(m.switches().digital_inputs(), 0b010);
    // Held: no further edge.
    assert!(m.step(DT).first(EventKind::PositiveLimit).is_none());
    m.inject(ModelInjection::ForceSwitch(SwitchInput::PositiveLimit, None));
    let e = *m.step(DT).first(EventKind::PositiveLimit).expect("release edge");
    assert!(!e.active);
    assert!(!m.switches().positive_limit);
}

#[test]
fn a_dead_switch_hides_the_axis_edges_until_released() {
    let mut m = model();
    m.inject(ModelInjection::ForceSwitch(SwitchInput::Home, Some(false)));
    m.step(DT);
    assert!(m.set_demand(Demand::Velocity { velocity: 40.0, acceleration: 1e4 }));
    let mut home_edges = 0;
    let mut t = 0.0;
    // 0° → past the home switch [100°, 200°] (40 rad/s ≈ 2292°/s).
    while m.rad_to_units(m.position()) < 300.0 && t < 2.0 {
        home_edges += m.step(DT).iter().filter(|e| e.kind == EventKind::Home).count();
        assert!(!m.switches().home);
        t += DT;
    }
    assert!(m.rad_to_units(m.position()) >= 300.0);
    assert_eq!(home_edges, 0);
    // Released outside the switch: its level was already inactive, no edge.
    m.inject(ModelInjection::ForceSwitch(SwitchInput::Home, None));
    assert!(m.step(DT).first(EventKind::Home).is_none());
}

#[test]
fn clear_releases_forced_switches() {
    let mut m = model();
    m.inject(ModelInjection::ForceSwitch(SwitchInput::NegativeLimit, Some(true)));
    m.step(DT);
    assert!(m.switches().negative_limit);
    m.inject(ModelInjection::Clear);
    let e = *m.step(DT).first(EventKind::NegativeLimit).expect("release edge");
    assert!(!e.active);
    assert!(!m.switches().negative_limit);
}
