//! The machine's signals besides the axis' switches: general-purpose
//! digital inputs (and drive outputs wired back to them), analog inputs,
//! a master encoder (pulse/direction) input, a holding brake and the motor
//! temperature — their power-on values, and the changes of them a
//! machine schedules at run time ([`InputChange`]).
//!
//! The physical model owns them (`drivebus_cia402::model::io`):
//! personalities read them from `drive.model()` (`digital_inputs`,
//! `analog_input`, `master_position`, `master_velocity`, `brake`,
//! `temperature`) and set the outputs and the brake through the drive
//! (`Drive::set_output_lines`, `Drive::set_brake_control`).

use super::{MachineError, err, finite, not_negative};
use drivebus_cia402::drive::DriveConfig;
use drivebus_cia402::model::{ANALOG_INPUTS, BrakeParams, DIGITAL_LINES, IoParams, ModelInjection};

/// Digital and analog inputs at power-on, and the drive's output lines
/// wired back to input lines.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Io {
    /// Input lines high at power-on (bit `n − 1`: line `n`, 1..=16).
    pub digital_inputs: u16,
    /// Analog inputs at power-on \[V\], channel `n` (1..=4) at index `n − 1`.
    pub analog_inputs: [f64; ANALOG_INPUTS],
    /// Output line `k + 1` drives input line `wiring[k]` (1..=16; 0: not
    /// wired): the input reads high while the output is on.
    pub wiring: [u8; DIGITAL_LINES],
}

/// The master encoder (pulse/direction) input that electronic gearing and
/// camming follow.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MasterEncoder {
    /// Position at power-on \[counts\].
    pub position: f64,
    /// Constant speed \[counts/s\] (a schedule changes it).
    pub velocity: f64,
}

/// A holding brake on the motor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Brake {
    /// From the drive's release command until it is free \[s\].
    pub release_delay: f64,
    /// From the apply command until it holds \[s\].
    pub apply_delay: f64,
    /// Torque it holds at the output shaft \[N·m\]; `None`: twice the
    /// motor's peak torque (it holds whatever the motor can do).
    pub holding_torque: Option<f64>,
}

/// Temperatures.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Temperature {
    /// Ambient \[°C\]: the motor starts at it and cools towards it;
    /// `None`: the motor's default (25 °C).
    pub ambient: Option<f64>,
    /// The motor temperature reading \[°C\] in place of the thermal model
    /// (a hot motor for a warning test); `None`: the thermal model.
    pub motor: Option<f64>,
}

/// An input a machine changes at run time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input {
    /// Digital input `line` (1..=16) to `level`.
    Digital {
        /// Line, 1..=16.
        line: u8,
        /// High.
        level: bool,
    },
    /// Analog input `channel` (1..=4) to `volts`.
    Analog {
        /// Channel, 1..=4.
        channel: u8,
        /// Voltage \[V\].
        volts: f64,
    },
    /// The master encoder runs at this speed \[counts/s\].
    MasterVelocity(f64),
    /// The master encoder jumps to this position \[counts\] (an event:
    /// no duration).
    MasterPosition(f64),
    /// The motor temperature reads this \[°C\].
    MotorTemperature(f64),
    /// The brake is held engaged (`true`: stuck) or released (`false`: a
    /// manual release lever) whatever the drive commands.
    Brake(bool),
}

/// A change of an input at a time after the drive started.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputChange {
    /// Seconds after the drive started (booted).
    pub at: f64,
    /// The input and its value.
    pub input: Input,
    /// How long \[s\]; then the input returns to the machine's value.
    /// `None`: it stays.
    pub duration: Option<f64>,
}

/// Largest analog input \[V\].
const MAX_VOLTS: f64 = 1000.0;

impl Input {
    /// The model's injection that sets it.
    pub(super) fn injection(self) -> ModelInjection {
        match self {
            Input::Digital { line, level } => ModelInjection::DigitalInput { line, level },
            Input::Analog { channel, volts } => ModelInjection::AnalogInput { channel, volts },
            Input::MasterVelocity(v) => ModelInjection::MasterVelocity(v),
            Input::MasterPosition(p) => ModelInjection::MasterPosition(p),
            Input::MotorTemperature(t) => ModelInjection::MotorTemperature(Some(t)),
            Input::Brake(b) => ModelInjection::Brake(Some(b)),
        }
    }

    /// Checks the line and the value.
    fn check(&self) -> Result<(), MachineError> {
        match *self {
            Input::Digital { line, .. } if !(1..=DIGITAL_LINES as u8).contains(&line) => {
                Err(err("line", format!("{line} is not a digital input line (1..=16)")))
            }
            Input::Analog { channel, .. } if !(1..=ANALOG_INPUTS as u8).contains(&channel) => {
                Err(err("line", format!("{channel} is not an analog input channel (1..=4)")))
            }
            Input::Analog { volts, .. } => volts_ok("value", volts),
            Input::MasterVelocity(v) | Input::MasterPosition(v) => finite("value", v),
            Input::MotorTemperature(t) => temperature_ok("value", t, -50.0, 500.0),
            Input::Digital { .. } | Input::Brake(_) => Ok(()),
        }
    }
}

fn volts_ok(key: &str, v: f64) -> Result<(), MachineError> {
    if v.is_finite() && v.abs() <= MAX_VOLTS {
        Ok(())
    } else {
        Err(err(key, format!("{v} is not a voltage within ±1000 V")))
    }
}

fn temperature_ok(key: &str, t: f64, lo: f64, hi: f64) -> Result<(), MachineError> {
    if t.is_finite() && (lo..=hi).contains(&t) {
        Ok(())
    } else {
        Err(err(key, format!("{t} is not a temperature in {lo}..={hi} °C")))
    }
}

impl InputChange {
    pub(super) fn check(&self) -> Result<(), MachineError> {
        super::faults::check_time(self.at, self.duration)?;
        if matches!(self.input, Input::MasterPosition(_)) && self.duration.is_some() {
            return Err(err("duration", "a master_position change is a jump and takes no duration"));
        }
        self.input.check()
    }
}

impl super::Machine {
    /// Checks the signals' values.
    pub(super) fn check_io(&self) -> Result<(), MachineError> {
        for v in self.io.analog_inputs {
            volts_ok("io.analog_inputs", v)?;
        }
        if let Some(l) = self.io.wiring.iter().find(|&&l| usize::from(l) > DIGITAL_LINES) {
            return Err(err("io.wiring", format!("input line {l} is not in 1..=16")));
        }
        finite("master_encoder.position", self.master_encoder.position)?;
        finite("master_encoder.velocity", self.master_encoder.velocity)?;
        if let Some(b) = &self.brake {
            for (key, v) in [("brake.release_delay", b.release_delay), ("brake.apply_delay", b.apply_delay)] {
                not_negative(key, v)?;
                if v > 1000.0 {
                    return Err(err(key, format!("{v} s is more than 1000 s")));
                }
            }
            if let Some(t) = b.holding_torque {
                not_negative("brake.holding_torque", t)?;
            }
        }
        // Ambient below every motor's winding limit.
        if let Some(t) = self.temperature.ambient {
            temperature_ok("temperature.ambient", t, -40.0, 60.0)?;
        }
        if let Some(t) = self.temperature.motor {
            temperature_ok("temperature.motor", t, -50.0, 500.0)?;
        }
        for (i, c) in self.inputs.iter().enumerate() {
            c.check().map_err(|e| MachineError { key: format!("inputs[{i}].{}", e.key), ..e })?;
        }
        Ok(())
    }

    /// Puts the signals into the drive configuration (after the motor was
    /// chosen: the brake's default torque is the motor's).
    pub(super) fn apply_io(&self, cfg: &mut DriveConfig) {
        let i = self.gear_ratio;
        let p = &mut cfg.params;
        let peak = p.motor.kt * p.motor.max_current;
        p.io = IoParams {
            digital_inputs: self.io.digital_inputs,
            analog_inputs: self.io.analog_inputs,
            wiring: self.io.wiring,
            master_position: self.master_encoder.position,
            master_velocity: self.master_encoder.velocity,
            brake: self.brake.map(|b| BrakeParams {
                release_delay: b.release_delay,
                apply_delay: b.apply_delay,
                holding_torque: b.holding_torque.map_or(2.0 * peak, |t| t / i),
            }),
            motor_temperature: self.temperature.motor,
        };
        if let Some(t) = self.temperature.ambient {
            p.motor.ambient_temperature = t;
        }
    }
}
