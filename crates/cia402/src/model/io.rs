//! The plant's signals besides the axis: general-purpose digital inputs
//! and outputs, analog inputs, an analog output, a master encoder (pulse/direction) input, a
//! holding brake and the motor temperature reading.
//!
//! Their power-on values are [`IoParams`] (a machine file sets them); at
//! run time they change through [`super::ModelInjection`] (the machine's
//! schedule, a test) and the drive sets the outputs and the brake command
//! ([`DriveModel::set_outputs`], [`DriveModel::set_brake`]). Personalities
//! read them from [`DriveModel`]: [`DriveModel::digital_inputs`],
//! [`DriveModel::analog_input`], [`DriveModel::master_position`],
//! [`DriveModel::master_velocity`], [`DriveModel::brake`],
//! [`DriveModel::temperature`].

use super::DriveModel;

/// General-purpose digital input lines (numbered 1..=16; line `n` is bit
/// `n − 1` of a level mask).
pub const DIGITAL_LINES: usize = 16;

/// Analog input channels (numbered 1..=4).
pub const ANALOG_INPUTS: usize = 4;

/// Largest analog input magnitude accepted \[V\].
pub const MAX_VOLTS: f64 = 1000.0;

/// Largest master encoder position \[counts\] and speed \[counts/s\].
pub const MAX_MASTER: f64 = 1e15;

/// A holding brake on the motor shaft.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrakeParams {
    /// From the release command until the brake is free \[s\].
    pub release_delay: f64,
    /// From the apply command until the brake holds \[s\].
    pub apply_delay: f64,
    /// Torque the engaged brake holds at the motor shaft \[Nm\]; beyond it
    /// the brake slips with this torque against the motion.
    pub holding_torque: f64,
}

/// Power-on values of the plant's signals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IoParams {
    /// Digital input levels (bit `n − 1`: line `n` high).
    pub digital_inputs: u16,
    /// Analog input voltages \[V\], channel `n` at index `n − 1`.
    pub analog_inputs: [f64; ANALOG_INPUTS],
    /// Output lines wired back to input lines: entry `k` is the input line
    /// (1..=16) output line `k + 1` drives, 0 for none. An input reads high
    /// while its level or a wired output is high.
    pub wiring: [u8; DIGITAL_LINES],
    /// Master encoder position at power-on \[counts\].
    pub master_position: f64,
    /// Master encoder speed \[counts/s\] (constant until changed).
    pub master_velocity: f64,
    /// The holding brake, `None`: none fitted.
    pub brake: Option<BrakeParams>,
    /// A motor temperature reading \[°C\] in place of the thermal model's
    /// (a sensor stuck, a test's hot motor); `None`: the thermal model.
    pub motor_temperature: Option<f64>,
}

impl Default for IoParams {
    /// All inputs low, 0 V, nothing wired, the master at rest at 0, no
    /// brake, the thermal model's temperature.
    fn default() -> Self {
        IoParams {
            digital_inputs: 0,
            analog_inputs: [0.0; ANALOG_INPUTS],
            wiring: [0; DIGITAL_LINES],
            master_position: 0.0,
            master_velocity: 0.0,
            brake: None,
            motor_temperature: None,
        }
    }
}

/// What the brake does now ([`DriveModel::brake`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct BrakeState {
    /// A brake is fitted (otherwise the rest is `false`).
    pub fitted: bool,
    /// The drive commands it engaged (its brake output is off).
    pub commanded: bool,
    /// It actually holds.
    pub engaged: bool,
    /// Its release or apply delay is running (the command is not yet
    /// what the brake does).
    pub pending: bool,
}

/// Run-time state of the signals (inside [`DriveModel`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Io {
    pub digital: u16,
    pub outputs: u16,
    pub analog: [f64; ANALOG_INPUTS],
    pub master_pos: f64,
    pub master_vel: f64,
    /// Brake command: engaged.
    pub brake_cmd: bool,
    /// What the brake does by its command and delays.
    pub brake_natural: bool,
    /// Time the command has differed from `brake_natural` \[s\].
    pub brake_timer: f64,
    /// Time since the command last changed \[s\] (infinite: never).
    pub brake_age: f64,
    /// Forced brake (stuck engaged, held released).
    pub brake_forced: Option<bool>,
    pub temperature: Option<f64>,
    /// The drive's analog output \[V\].
    pub analog_out: f64,
}

impl Io {
    pub(super) fn new(p: &IoParams) -> Io {
        Io {
            digital: p.digital_inputs,
            outputs: 0,
            analog: p.analog_inputs,
            master_pos: p.master_position,
            master_vel: p.master_velocity,
            // Power-on: the drive is disabled, the brake holds.
            brake_cmd: true,
            brake_natural: true,
            brake_timer: 0.0,
            brake_age: f64::INFINITY,
            brake_forced: None,
            temperature: p.motor_temperature,
            analog_out: 0.0,
        }
    }
}

impl IoParams {
    /// Checks ranges: finite values, wired lines in 1..=16, brake delays
    /// and torque not negative.
    pub(super) fn validate(&self) -> Result<(), super::ParamError> {
        let err = |field, reason| Err(super::ParamError { field, reason });
        if self.analog_inputs.iter().any(|v| !(v.is_finite() && v.abs() <= MAX_VOLTS)) {
            return err("io.analog_inputs", "must be finite, within ±1000 V");
        }
        if self.wiring.iter().any(|&l| usize::from(l) > DIGITAL_LINES) {
            return err("io.wiring", "input lines are 1..=16 (0: not wired)");
        }
        for (f, v) in
            [("io.master_position", self.master_position), ("io.master_velocity", self.master_velocity)]
        {
            if !(v.is_finite() && v.abs() <= MAX_MASTER) {
                return err(f, "must be finite, within ±1e15");
            }
        }
        if let Some(b) = self.brake {
            for (f, v) in
                [("io.brake.release_delay", b.release_delay), ("io.brake.apply_delay", b.apply_delay)]
            {
                if !(v.is_finite() && (0.0..=1e3).contains(&v)) {
                    return err(f, "must be a time in 0..=1000 s");
                }
            }
            if !(b.holding_torque.is_finite()
                && (0.0..=super::params::MAX_TORQUE).contains(&b.holding_torque))
            {
                return err("io.brake.holding_torque", "out of the supported range");
            }
        }
        if let Some(t) = self.motor_temperature
            && !(t.is_finite() && (-273.0..=1e4).contains(&t))
        {
            return err("io.motor_temperature", "must be a temperature in °C");
        }
        Ok(())
    }
}

impl DriveModel {
    /// Digital input levels (bit `n − 1`: line `n`), outputs wired back
    /// included.
    pub fn digital_inputs(&self) -> u16 {
        let mut v = self.io.digital;
        // Only the lines set (usually none): the drive asks every period.
        let mut set = self.io.outputs;
        while set != 0 {
            let k = set.trailing_zeros() as usize;
            set &= set - 1;
            if let Some(&to) = self.p.io.wiring.get(k)
                && to != 0
            {
                v |= 1 << (to - 1);
            }
        }
        v
    }

    /// Level of digital input `line` (1..=16; others read low).
    pub fn digital_input(&self, line: u8) -> bool {
        (1..=DIGITAL_LINES as u8).contains(&line) && self.digital_inputs() & (1 << (line - 1)) != 0
    }

    /// Voltage of analog input `channel` (1..=4; others read 0 V) \[V\].
    pub fn analog_input(&self, channel: u8) -> f64 {
        usize::from(channel).checked_sub(1).and_then(|i| self.io.analog.get(i)).copied().unwrap_or(0.0)
    }

    /// The drive's digital output lines (bit `n − 1`: line `n`).
    pub fn outputs(&self) -> u16 {
        self.io.outputs
    }

    /// Sets the drive's digital output lines (the drive's 60FEh or a
    /// personality's output objects); wired ones drive their inputs.
    pub fn set_outputs(&mut self, lines: u16) {
        self.io.outputs = lines;
    }

    /// Master encoder position \[counts\] (whole counts, towards −∞).
    pub fn master_position(&self) -> i64 {
        // `as` saturates; the position is bounded by MAX_MASTER plus the
        // motion of the run.
        libm::floor(self.io.master_pos) as i64
    }

    /// Master encoder speed \[counts/s\].
    pub fn master_velocity(&self) -> f64 {
        self.io.master_vel
    }

    /// Commands the holding brake: `true` engaged (the drive's brake output
    /// off), `false` released. It follows after its release or apply delay.
    pub fn set_brake(&mut self, engage: bool) {
        if engage != self.io.brake_cmd {
            self.io.brake_cmd = engage;
            self.io.brake_timer = 0.0;
            self.io.brake_age = 0.0;
        }
    }

    /// Sets the drive's analog output \[V\] (a non-finite value or one
    /// beyond ±1000 V is ignored).
    pub fn set_analog_output(&mut self, volts: f64) {
        if volts.is_finite() && volts.abs() <= MAX_VOLTS {
            self.io.analog_out = volts;
        }
    }

    /// The drive's analog output \[V\] as the machine sees it.
    pub fn analog_output(&self) -> f64 {
        self.io.analog_out
    }

    /// Seconds since the drive last changed its brake command (infinite
    /// before the first change).
    pub fn brake_command_age(&self) -> f64 {
        self.io.brake_age
    }

    /// The holding brake: fitted, commanded, engaged, delay pending.
    pub fn brake(&self) -> BrakeState {
        match self.p.io.brake {
            None => BrakeState::default(),
            Some(_) => BrakeState {
                fitted: true,
                commanded: self.io.brake_cmd,
                engaged: self.brake_engaged(),
                pending: self.io.brake_cmd != self.io.brake_natural,
            },
        }
    }

    /// Whether the brake holds the shaft now.
    pub(super) fn brake_engaged(&self) -> bool {
        self.p.io.brake.is_some() && self.io.brake_forced.unwrap_or(self.io.brake_natural)
    }

    /// Torque the brake resists motion with now \[Nm\] (0: free).
    pub(super) fn brake_torque(&self) -> f64 {
        match self.p.io.brake {
            Some(b) if self.brake_engaged() => b.holding_torque,
            _ => 0.0,
        }
    }

    /// The signals over one step: the master encoder moves, the brake's
    /// delay runs.
    pub(super) fn io_step(&mut self, dt: f64) {
        let io = &mut self.io;
        io.master_pos = (io.master_pos + io.master_vel * dt).clamp(-2.0 * MAX_MASTER, 2.0 * MAX_MASTER);
        io.brake_age += dt;
        if let Some(b) = self.p.io.brake
            && io.brake_cmd != io.brake_natural
        {
            io.brake_timer += dt;
            let delay = if io.brake_cmd { b.apply_delay } else { b.release_delay };
            // Whole steps: a delay ends in the step it elapses in.
            if io.brake_timer + 1e-9 >= delay {
                io.brake_natural = io.brake_cmd;
                io.brake_timer = 0.0;
            }
        }
    }
}
