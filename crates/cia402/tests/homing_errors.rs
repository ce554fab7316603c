//! Homing interruption (halt, bit 4 falling), error cases and a pluggable
//! manufacturer method (CiA 402-2 §6.7; statusword bits 10/12/13).

mod homing_support;

use drivebus_cia402::homing::{
    HomingContext, HomingError, HomingMethod, HomingRegistry, HomingState, MethodStep,
};
use drivebus_cia402::model::EventKind;
use homing_support::*;

const STOPS: (Option<f64>, Option<f64>) = (Some(-1200.0), Some(1200.0));

#[test]
fn halt_interrupts_and_a_new_edge_restarts() {
    let p = axis(Some(-1000.0), Some(1000.0), Some((100.0, 500.0)), STOPS, -300.0);
    let mut rig = Rig::new(p, config(23));
    rig.controlword = 0x1F;
    for _ in 0..800 {
        rig.step();
    }
    assert_eq!(rig.homing.state(), HomingState::Running);
    // Halt (bit 8): decelerate with the homing acceleration; bits 10/12/13
    // read 0/0/0 while moving, then 1/0/0 "interrupted".
    rig.controlword = 0x11F;
    let mut moving_steps = 0;
    while rig.step() != 0x0400 {
        moving_steps += 1;
        assert!(moving_steps < 8000, "did not stop");
    }
    assert_eq!(rig.homing.state(), HomingState::Interrupted);
    // 1800°/s at 36 000°/s²: 50 ms = 400 periods of deceleration.
    assert!((390..=410).contains(&moving_steps), "{moving_steps}");
    assert!(rig.model.velocity().abs() < 0.5);
    for _ in 0..100 {
        assert_eq!(rig.step(), 0x0400);
    }
    // Releasing halt with bit 4 still set does not restart.
    rig.controlword = 0x1F;
    for _ in 0..100 {
        assert_eq!(rig.step(), 0x0400);
    }
    // Bit 4 low then high: a fresh run completes on the lower edge (23).
    rig.controlword = 0x0F;
    rig.step();
    let status = rig.run(20.0);
    assert_eq!(status, 0x1400);
    assert!((rig.reference_raw() - 100.0).abs() <= COUNT_DEG);
    assert_eq!(rig.statuses, [0x0400, 0x0000, 0x0400, 0x0000, 0x1000, 0x1400]);
}

#[test]
fn bit4_falling_interrupts() {
    let p = axis(Some(-1000.0), Some(1000.0), None, STOPS, 0.0);
    let mut rig = Rig::new(p, config(17));
    rig.controlword = 0x1F;
    for _ in 0..400 {
        rig.step();
    }
    rig.controlword = 0x0F;
    let mut n = 0;
    while rig.step() != 0x0400 && n < 8000 {
        n += 1;
    }
    assert_eq!(rig.homing.state(), HomingState::Interrupted);
}

fn expect_error(mut rig: Rig, error: HomingError) {
    rig.controlword = 0x1F;
    let mut last = 0;
    for _ in 0..(20.0 / DT) as usize {
        last = rig.step();
        if last == 0x2400 {
            break;
        }
    }
    assert_eq!(last, 0x2400, "{:?}", rig.homing.state());
    assert_eq!(rig.homing.state(), HomingState::Error(error));
    assert_eq!(rig.resets, 0);
}

#[test]
fn limit_switch_never_found_before_the_hard_stop() {
    // Method 1 without a negative limit switch: the axis runs into the stop.
    let rig = Rig::new(axis(None, Some(1000.0), None, STOPS, 0.0), config(1));
    expect_error(rig, HomingError::SwitchNotFound);
}

#[test]
fn error_while_moving_reads_bit13_only() {
    // Method 3 whose home switch lies beyond the positive limit switch: the
    // limit switch is unexpected, the axis decelerates with 0/0/1, then 1/0/1.
    let p = axis(Some(-1000.0), Some(1000.0), Some((1100.0, 1.0e6)), (None, None), 0.0);
    let mut rig = Rig::new(p, config(3));
    expect_error_sequence(&mut rig);
    assert_eq!(rig.homing.state(), HomingState::Error(HomingError::UnexpectedLimitSwitch));
}

fn expect_error_sequence(rig: &mut Rig) {
    rig.controlword = 0x1F;
    for _ in 0..(20.0 / DT) as usize {
        if rig.step() == 0x2400 {
            break;
        }
    }
    assert_eq!(rig.statuses, [0x0400, 0x0000, 0x2000, 0x2400]);
}

#[test]
fn momentary_switch_missing_reverses_once_then_fails() {
    // Method 7 with no home switch: positive to PLS, reverse, then NLS.
    let p = axis(Some(-1000.0), Some(1000.0), None, STOPS, 0.0);
    let mut rig = Rig::new(p, config(7));
    expect_error_sequence(&mut rig);
    assert_eq!(rig.homing.state(), HomingState::Error(HomingError::UnexpectedLimitSwitch));
    // It got past the start going negative, so it did reverse at PLS.
    assert!(rig.actual() < -900.0);
}

#[test]
fn unsupported_method_and_bad_parameters_fail_at_rest() {
    let p = axis(None, None, None, (None, None), 0.0);
    let rig = Rig::new(p, config(15));
    expect_error(rig, HomingError::UnsupportedMethod);
    let mut c = config(17);
    c.zero_speed = 0.0;
    let rig = Rig::new(p, c);
    expect_error(rig, HomingError::InvalidParameters);
    assert!(!HomingRegistry::standard().is_supported(-1));
}

#[test]
fn index_never_seen_is_an_error() {
    // Method 34 fed directly: 1.1 revolutions of travel without an index
    // pulse (a broken index track) ends the search.
    use drivebus_cia402::homing::StandardMethod;
    use drivebus_cia402::model::Switches;
    let c = config(34);
    let ctx = |position: f64| HomingContext {
        config: &c,
        position,
        velocity: 180.0,
        switches: Switches::default(),
        events: &[],
        torque: 0.0,
    };
    let mut m = StandardMethod::new(34).unwrap();
    assert_eq!(m.begin(&ctx(0.0)), MethodStep::Move(180.0));
    assert_eq!(m.update(&ctx(390.0)), MethodStep::Move(180.0));
    assert_eq!(m.update(&ctx(397.0)), MethodStep::Failed(HomingError::IndexNotFound));
    assert!(StandardMethod::new(15).is_none() && StandardMethod::new(36).is_none());
}

/// A manufacturer method −1: move negative until blocked at the hard stop
/// and take the stop as the home position.
struct HardStopNegative;

impl HomingMethod for HardStopNegative {
    fn code(&self) -> i8 {
        -1
    }
    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        MethodStep::Move(-ctx.config.zero_speed)
    }
    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        match ctx.events.iter().find(|e| e.kind == EventKind::HardStop) {
            Some(e) => MethodStep::Found(e.position),
            None => MethodStep::Move(-ctx.config.zero_speed),
        }
    }
}

#[test]
fn manufacturer_method_plugs_in() {
    let mut registry = HomingRegistry::standard();
    registry.register(Box::new(HardStopNegative));
    assert!(registry.is_supported(-1));
    let codes: Vec<i8> = registry.codes().collect();
    assert_eq!(codes.len(), 33);
    assert_eq!(&codes[..4], &[1, 2, 3, 4]);
    assert_eq!(codes[32], -1);
    let p = axis(None, None, None, (Some(-200.0), Some(200.0)), 0.0);
    let mut rig = Rig::with_registry(p, config(-1), registry);
    assert_eq!(rig.run(20.0), 0x1400);
    assert!((rig.reference_raw() + 200.0).abs() <= COUNT_DEG);
}
