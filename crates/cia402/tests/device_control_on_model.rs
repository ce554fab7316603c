//! The state machine driving the motor model the way the mode layer will:
//! stopping reactions are executed on the model and completed with
//! `motion_stopped` (CiA 402-2 §6.2, 605Ah / 605Eh).

use drivebus_cia402::model::{Demand, DriveModel, DriveParams, ModelInjection};
use drivebus_cia402::state_machine::{DriveFunction, Options, Reaction, State, StateMachine};

const DT: f64 = 1.0 / 8000.0;

/// Minimal stand-in for the mode layer: profile velocity + reactions.
struct Axis {
    sm: StateMachine,
    model: DriveModel,
    target_velocity: f64,
    ramp_velocity: f64,
}

impl Axis {
    fn new(options: Options) -> Self {
        let mut sm = StateMachine::new(options);
        sm.self_test_passed();
        Axis {
            sm,
            model: DriveModel::new(DriveParams::servo_small()).unwrap(),
            target_velocity: 0.0,
            ramp_velocity: 0.0,
        }
    }

    /// One control period.
    fn cycle(&mut self) {
        let (slow, quick) = (2_000.0, 20_000.0); // 6084h / 6085h in rad/s²
        let cmd = match self.sm.drive_function() {
            DriveFunction::Disabled => {
                self.ramp_velocity = self.model.velocity();
                Demand::Off
            }
            DriveFunction::Enabled => {
                self.ramp_velocity = self.target_velocity;
                Demand::Velocity { velocity: self.target_velocity, acceleration: 0.0 }
            }
            DriveFunction::Holding => Demand::Velocity { velocity: 0.0, acceleration: 0.0 },
            DriveFunction::Stopping(r) => {
                let decel = match r {
                    Reaction::SlowDownRamp => slow,
                    Reaction::QuickStopRamp => quick,
                    // Current limit: ask for an instant stop, the loop saturates.
                    Reaction::CurrentLimit => f64::INFINITY,
                    Reaction::VoltageLimit | Reaction::DisableDrive => 0.0,
                };
                if r == Reaction::VoltageLimit {
                    self.ramp_velocity = 0.0;
                    Demand::ShortCircuit
                } else if r == Reaction::DisableDrive {
                    self.ramp_velocity = 0.0;
                    Demand::Off
                } else {
                    let dv = (decel * DT).min(self.ramp_velocity.abs());
                    self.ramp_velocity -= dv * self.ramp_velocity.signum();
                    Demand::Velocity { velocity: self.ramp_velocity, acceleration: 0.0 }
                }
            }
        };
        self.model.set_demand(cmd);
        self.model.step(DT);
        if let Some(code) = self.model.faults().error_code() {
            self.sm.fault(code);
        }
        if matches!(self.sm.drive_function(), DriveFunction::Stopping(_))
            && self.ramp_velocity.abs() < 1e-9
            && self.model.velocity().abs() < 1.0
        {
            self.sm.motion_stopped();
        }
    }

    fn run(&mut self, seconds: f64) {
        for _ in 0..(seconds / DT) as usize {
            self.cycle();
        }
    }
}

#[test]
fn quick_stop_ramp_then_switch_on_disabled() {
    let mut a = Axis::new(Options::default()); // 605Ah = 2
    a.sm.controlword(0x06);
    a.sm.controlword(0x0F);
    a.target_velocity = 400.0;
    a.run(0.2);
    assert!((a.model.velocity() - 400.0).abs() < 4.0);
    a.sm.controlword(0x02);
    assert_eq!(a.sm.state(), State::QuickStopActive);
    // 400 rad/s at 20000 rad/s² takes 20 ms.
    a.run(0.015);
    assert_eq!(a.sm.state(), State::QuickStopActive);
    assert!(a.model.velocity() > 50.0);
    a.run(0.05);
    assert_eq!(a.sm.state(), State::SwitchOnDisabled);
    assert!(a.model.velocity().abs() < 1.0);
}

#[test]
fn over_temperature_fault_reaction_stops_then_fault() {
    let mut o = Options::default();
    o.set_fault_reaction(1).unwrap();
    let mut a = Axis::new(o);
    a.sm.controlword(0x06);
    a.sm.controlword(0x0F);
    a.target_velocity = 300.0;
    a.run(0.2);
    a.model.inject(ModelInjection::OverTemperature);
    a.cycle();
    assert_eq!(a.sm.state(), State::FaultReactionActive);
    assert_eq!(a.sm.fault_code(), 0x4310);
    // Slow-down ramp at 2000 rad/s² from 300 rad/s: 150 ms.
    a.run(0.1);
    assert_eq!(a.sm.state(), State::FaultReactionActive);
    a.run(0.1);
    assert_eq!(a.sm.state(), State::Fault);
    assert_eq!(a.sm.statusword() & 0x4F, 0x08);
    // Reset while the condition persists: the fault comes straight back.
    a.sm.controlword(0x80);
    assert!(a.model.clear_faults().any());
    a.cycle();
    assert_eq!(a.sm.state(), State::Fault);
    a.model.inject(ModelInjection::Clear);
    a.sm.controlword(0x00);
    a.sm.controlword(0x80);
    assert!(!a.model.clear_faults().any());
    a.cycle();
    assert_eq!(a.sm.state(), State::SwitchOnDisabled);
}

#[test]
fn voltage_limit_quick_stop_holds_in_quick_stop_active() {
    let mut o = Options::default();
    o.set_quick_stop(8).unwrap();
    let mut a = Axis::new(o);
    a.sm.controlword(0x06);
    a.sm.controlword(0x0F);
    a.target_velocity = 500.0;
    a.run(0.2);
    a.sm.controlword(0x02);
    a.run(0.3);
    assert_eq!(a.sm.state(), State::QuickStopActive);
    assert_eq!(a.sm.drive_function(), DriveFunction::Holding);
    assert!(a.model.velocity().abs() < 1.0);
    // Transition 16 back to Operation enabled.
    a.sm.controlword(0x0F);
    assert_eq!(a.sm.state(), State::OperationEnabled);
}
