//! The plant's signals: brake on a loaded axis, digital and analog inputs,
//! outputs wired back, master encoder, temperature reading.

use super::tests::run;
use super::*;

const RELEASE: f64 = 0.05;
const APPLY: f64 = 0.03;

/// A servo on a vertical axis: 0.5 Nm of gravity pulling negative, a brake
/// holding 2 Nm.
fn hanging(brake: bool) -> DriveModel {
    let mut p = DriveParams::servo_small();
    p.axis.load = LoadTorque::Constant(-0.5);
    if brake {
        p.io.brake = Some(BrakeParams { release_delay: RELEASE, apply_delay: APPLY, holding_torque: 2.0 });
    }
    DriveModel::new(p).unwrap()
}

#[test]
fn engaged_brake_holds_a_loaded_axis() {
    let mut m = hanging(true);
    assert_eq!(m.brake(), BrakeState { fitted: true, commanded: true, engaged: true, pending: false });
    run(&mut m, 1.0);
    assert_eq!(m.position(), 0.0, "the brake holds the load with the power stage off");
    // The motor pushing with 1 Nm (less than brake and load) moves nothing.
    m.set_demand(Demand::Torque(1.0));
    run(&mut m, 0.5);
    assert_eq!(m.position(), 0.0);
    // Without a brake the same axis falls.
    let mut free = hanging(false);
    run(&mut free, 0.2);
    assert!(free.position() < -1.0, "{}", free.position());
}

#[test]
fn released_brake_lets_the_load_fall_after_the_release_delay() {
    let mut m = hanging(true);
    let dt = m.params().control_period();
    m.set_brake(false);
    let mut t = 0.0;
    while m.brake().engaged {
        assert!(m.brake().pending && !m.brake().commanded);
        assert_eq!(m.position(), 0.0, "no motion while the brake still holds (t = {t})");
        m.step(dt);
        t += dt;
        assert!(t < 1.0);
    }
    assert!((t - RELEASE).abs() <= dt, "released after {t} s, delay {RELEASE} s");
    assert!(!m.brake().pending);
    run(&mut m, 0.1);
    assert!(m.position() < -0.1, "the load falls with the power stage off: {}", m.position());
}

#[test]
fn brake_applies_after_the_apply_delay_and_stops_the_fall() {
    let mut m = hanging(true);
    let dt = m.params().control_period();
    m.set_brake(false);
    run(&mut m, RELEASE + 0.05);
    m.set_brake(true);
    let mut t = 0.0;
    while !m.brake().engaged {
        m.step(dt);
        t += dt;
        assert!(t < 1.0);
    }
    assert!((t - APPLY).abs() <= dt, "applied after {t} s, delay {APPLY} s");
    // Slips against the motion until the shaft stands, then holds.
    run(&mut m, 0.2);
    let p = m.position();
    run(&mut m, 0.5);
    assert_eq!(m.position(), p);
    assert_eq!(m.velocity(), 0.0);
}

#[test]
fn overloaded_brake_slips() {
    let mut p = DriveParams::servo_small();
    p.axis.load = LoadTorque::Constant(-0.5);
    p.io.brake = Some(BrakeParams { release_delay: 0.0, apply_delay: 0.0, holding_torque: 0.3 });
    let mut m = DriveModel::new(p).unwrap();
    run(&mut m, 0.2);
    assert!(m.position() < -0.1, "0.5 Nm beyond a 0.3 Nm brake: {}", m.position());
}

#[test]
fn forced_brake_overrides_the_command_until_cleared() {
    let mut m = hanging(true);
    m.inject(ModelInjection::Brake(Some(false)));
    assert!(!m.brake().engaged && m.brake().commanded);
    run(&mut m, 0.1);
    assert!(m.position() < -0.1, "held released, the load falls");
    m.inject(ModelInjection::Clear);
    assert!(m.brake().engaged);
    m.set_brake(false);
    m.inject(ModelInjection::Brake(Some(true)));
    run(&mut m, 0.2);
    assert!(m.brake().engaged && !m.brake().commanded, "stuck engaged");
}

#[test]
fn digital_inputs_levels_and_wired_outputs() {
    let mut p = DriveParams::servo_small();
    p.io.digital_inputs = 0b101;
    p.io.wiring[1] = 9; // output 2 drives input 9
    let mut m = DriveModel::new(p).unwrap();
    assert_eq!(m.digital_inputs(), 0b101);
    assert!(m.digital_input(1) && !m.digital_input(2) && m.digital_input(3));
    assert!(!m.digital_input(0) && !m.digital_input(17), "no such lines");
    m.inject(ModelInjection::DigitalInput { line: 2, level: true });
    m.inject(ModelInjection::DigitalInput { line: 1, level: false });
    m.inject(ModelInjection::DigitalInput { line: 17, level: true });
    assert_eq!(m.digital_inputs(), 0b110);
    m.set_outputs(0b10);
    assert_eq!(m.outputs(), 0b10);
    assert!(m.digital_input(9), "output 2 is wired to input 9");
    m.set_outputs(0b01);
    assert!(!m.digital_input(9));
    // Clear removes forced conditions, not the plant's levels.
    m.inject(ModelInjection::Clear);
    assert_eq!(m.digital_inputs(), 0b110);
}

#[test]
fn analog_inputs_in_volts() {
    let mut p = DriveParams::servo_small();
    p.io.analog_inputs = [1.5, 0.0, -2.0, 0.0];
    let mut m = DriveModel::new(p).unwrap();
    assert_eq!((m.analog_input(1), m.analog_input(3)), (1.5, -2.0));
    m.inject(ModelInjection::AnalogInput { channel: 2, volts: 7.25 });
    m.inject(ModelInjection::AnalogInput { channel: 2, volts: f64::NAN });
    m.inject(ModelInjection::AnalogInput { channel: 5, volts: 1.0 });
    assert_eq!(m.analog_input(2), 7.25);
    assert_eq!((m.analog_input(0), m.analog_input(5)), (0.0, 0.0));
    let mut bad = DriveParams::servo_small();
    bad.io.analog_inputs[0] = f64::INFINITY;
    assert_eq!(bad.validate().unwrap_err().field, "io.analog_inputs");
}

#[test]
fn master_encoder_runs_at_its_speed() {
    let mut p = DriveParams::servo_small();
    p.io.master_position = 100.0;
    p.io.master_velocity = 4000.0;
    let mut m = DriveModel::new(p).unwrap();
    assert_eq!(m.master_position(), 100);
    run(&mut m, 0.5);
    assert_eq!(m.master_position(), 2100);
    assert_eq!(m.master_velocity(), 4000.0);
    m.inject(ModelInjection::MasterPosition(-10.0));
    m.inject(ModelInjection::MasterVelocity(-2000.0));
    run(&mut m, 0.25);
    assert_eq!(m.master_position(), -510);
    m.inject(ModelInjection::MasterVelocity(f64::NAN));
    assert_eq!(m.master_velocity(), -2000.0);
}

#[test]
fn forced_temperature_reads_and_trips() {
    let mut p = DriveParams::servo_small();
    p.io.motor_temperature = Some(60.0);
    let mut m = DriveModel::new(p).unwrap();
    assert_eq!(m.temperature(), 60.0);
    m.inject(ModelInjection::MotorTemperature(Some(100.0)));
    m.step(1e-4);
    assert_eq!(m.temperature(), 100.0);
    assert!(!m.faults().over_temperature, "below the 120 °C limit");
    m.inject(ModelInjection::MotorTemperature(Some(130.0)));
    assert!(m.faults().over_temperature);
    assert_eq!(m.faults().error_code(), Some(0x4310));
    // Back to the machine's reading; the latched flag clears on reset.
    m.inject(ModelInjection::Clear);
    assert_eq!(m.temperature(), 60.0);
    assert!(!m.clear_faults().over_temperature);
    m.inject(ModelInjection::MotorTemperature(None));
    assert_eq!(m.temperature(), 60.0);
}

#[test]
fn thermal_model_without_a_forced_reading() {
    let mut m = DriveModel::new(DriveParams::servo_small()).unwrap();
    assert_eq!(m.temperature(), 25.0);
    m.inject(ModelInjection::MotorTemperature(Some(80.0)));
    m.inject(ModelInjection::MotorTemperature(None));
    assert_eq!(m.temperature(), 25.0, "back to the thermal model");
}

#[test]
fn brake_command_age_counts_from_the_last_change() {
    let mut m = hanging(true);
    assert_eq!(m.brake_command_age(), f64::INFINITY, "never commanded");
    m.set_brake(false);
    run(&mut m, 0.1);
    assert!((m.brake_command_age() - 0.1).abs() < 1e-6, "{}", m.brake_command_age());
    m.set_brake(false);
    assert!(m.brake_command_age() > 0.09, "the same command again changes nothing");
    m.set_brake(true);
    assert_eq!(m.brake_command_age(), 0.0);
}

#[test]
fn analog_output_is_what_the_drive_sets() {
    let mut m = hanging(false);
    assert_eq!(m.analog_output(), 0.0);
    m.set_analog_output(-2.5);
    assert_eq!(m.analog_output(), -2.5);
    m.set_analog_output(f64::NAN);
    m.set_analog_output(1e9);
    assert_eq!(m.analog_output(), -2.5, "refused values change nothing");
}
