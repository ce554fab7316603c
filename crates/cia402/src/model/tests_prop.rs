//! Property tests: arbitrary (finite) inputs never panic and never make the
//! state non-finite.

use super::*;
use proptest::prelude::*;

#[derive(Debug, Clone)]
enum Op {
    Cmd(Demand),
    Step(f64),
    Inject(ModelInjection),
    Motion(f64, f64),
    Clear,
}

fn big() -> impl Strategy<Value = f64> {
    prop_oneof![-1e3..1e3f64, -1e308..1e308f64, Just(0.0)]
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        2 => prop_oneof![
            Just(Demand::Off),
            Just(Demand::ShortCircuit),
            big().prop_map(Demand::Torque),
            (big(), big()).prop_map(|(velocity, acceleration)| Demand::Velocity { velocity, acceleration }),
            (big(), big(), big()).prop_map(|(position, velocity, acceleration)| Demand::Position { position, velocity, acceleration }),
        ].prop_map(Op::Cmd),
        6 => prop_oneof![Just(1.0 / 8000.0), Just(1.0 / 4000.0), -1.0..0.02f64].prop_map(Op::Step),
        1 => prop_oneof![
            Just(ModelInjection::OverCurrent),
            Just(ModelInjection::OverTemperature),
            Just(ModelInjection::BusOverVoltage),
            Just(ModelInjection::BusUnderVoltage),
            Just(ModelInjection::EncoderFailure),
            Just(ModelInjection::Clear),
            big().prop_map(ModelInjection::LoadTorqueStep),
            big().prop_map(|v| ModelInjection::BusVoltage(Some(v))),
        ].prop_map(Op::Inject),
        1 => (big(), big()).prop_map(|(p, v)| Op::Motion(p, v)),
        1 => Just(Op::Clear),
    ]
}

fn params(kind: u8) -> DriveParams {
    let mut p = match kind {
        0 => DriveParams::servo_small(),
        1 => DriveParams::servo_medium(),
        2 => DriveParams::stepper(),
        _ => {
            let mut p = DriveParams::stepper();
            if let MotorKind::Stepper(s) = &mut p.motor.kind {
                s.closed_loop = true;
            }
            p
        }
    };
    p.axis.negative_limit = Some(-100.0);
    p.axis.positive_limit = Some(100.0);
    p.axis.home_switch = Some((-5.0, 5.0));
    p.axis.negative_stop = Some(-200.0);
    p.axis.positive_stop = Some(200.0);
    p.axis.load = LoadTorque::Pendulum { peak: 0.1, zero: 0.3 };
    p.control.position_ki = 100.0;
    p
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]
    #[test]
    fn state_stays_finite(kind in 0u8..4, ops in proptest::collection::vec(op(), 0..200)) {
        let mut m = DriveModel::new(params(kind)).unwrap();
        for o in ops {
            match o {
                Op::Cmd(c) => { m.set_demand(c); }
                Op::Step(dt) => {
                    let ev = m.step(dt);
                    prop_assert!(ev.len() <= MAX_EVENTS);
                    for e in ev.iter() {
                        prop_assert!(e.position.is_finite() && (0.0..=1.0).contains(&e.fraction));
                    }
                }
                Op::Inject(i) => m.inject(i),
                Op::Motion(p, v) => { m.set_motion(p, v); }
                Op::Clear => { m.clear_faults(); }
            }
            for v in [m.position(), m.velocity(), m.current(), m.torque(), m.temperature(),
                      m.bus_voltage(), m.velocity_measured(), m.demand_position()] {
                prop_assert!(v.is_finite(), "{m:?}");
            }
            prop_assert!(m.position() >= m.units_to_rad(-200.0) - 1e-9);
            prop_assert!(m.position() <= m.units_to_rad(200.0) + 1e-9);
            prop_assert!(m.current().abs() <= m.params().motor.max_current + 1e-9);
        }
    }
}
