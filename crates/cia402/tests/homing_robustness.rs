//! No input makes the homing engine panic, and finite inputs give finite
//! set-points (DEVELOPERS.md: nothing panics on input).

use drivebus_cia402::homing::{
    Homing, HomingCommand, HomingConfig, HomingEvent, HomingInput, HomingRegistry,
};
use drivebus_cia402::model::{EventKind, Switches};
use proptest::prelude::*;

fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e6f64..1e6,
        Just(0.0),
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(1e300),
    ]
}

fn kind() -> impl Strategy<Value = EventKind> {
    prop_oneof![
        Just(EventKind::Index),
        Just(EventKind::NegativeLimit),
        Just(EventKind::PositiveLimit),
        Just(EventKind::Home),
        Just(EventKind::HardStop),
        Just(EventKind::Stall),
    ]
}

prop_compose! {
    fn event()(kind in kind(), active: bool, position in any_f64(), positive_direction: bool) -> HomingEvent {
        HomingEvent { kind, active, position, positive_direction }
    }
}

proptest! {
    #[test]
    fn arbitrary_periods_never_panic(
        method: i8,
        speeds in (any_f64(), any_f64(), any_f64(), any_f64()),
        periods in prop::collection::vec(
            (any::<u16>(), any_f64(), any::<(bool, bool, bool)>(), prop::collection::vec(event(), 0..4), any_f64()),
            1..60,
        ),
    ) {
        let mut h = Homing::new(HomingRegistry::standard());
        h.enter(0.0, 0);
        let config = HomingConfig {
            method,
            switch_speed: speeds.0,
            zero_speed: speeds.1,
            acceleration: speeds.2,
            home_offset: speeds.3,
            units_per_rev: 360.0,
        };
        for (cw, position, (n, p, home), events, dt) in periods {
            let input = HomingInput {
                position,
                velocity: 0.0,
                torque: 0.0,
                switches: Switches { negative_limit: n, positive_limit: p, home },
                events: &events,
            };
            let out = h.step(cw, &config, &input, dt);
            prop_assert_eq!(out.status & !0x3400, 0);
            let finite_in = position.is_finite() && events.iter().all(|e| e.position.is_finite())
                && config.is_valid() && dt.is_finite();
            if let (HomingCommand::Position { position, .. }, true) = (out.command, finite_in) {
                prop_assert!(position.is_finite());
            }
        }
    }
}
