//! Physical model of a servo or stepper motor on an axis, with the drive's
//! internal cascaded control loops, an incremental encoder, switches, end
//! stops, DC link and winding temperature, stepped at the control rate.
//!
//! Everything is on the motor shaft in SI units: angle θ \[rad\], speed ω
//! \[rad/s\], current i \[A\], torque \[Nm\]. The mode layer converts to
//! position units with [`DriveModel::rad_to_units`] (feed constant and gear
//! ratio) or works in encoder counts ([`DriveModel::position_counts`]).
//!
//! Equations (servo, per step of length `dt`; exact exponentials where the
//! subsystem is linear so the 4–16 kHz step is stable for any parameters):
//! - current loop: `τᵢ·di/dt = i* − i`, `i*` clamped to `±i_max` and to the
//!   voltage window `|R·i + kₑ·ω| ≤ V_bus` (inductance neglected), so the
//!   current loop saturates near maximum speed;
//! - mechanics: `J·dω/dt = kₜ·i + T_load − b·ω − T_c·sgn ω`, with stiction
//!   (the shaft stays at rest while `|kₜ·i + T_load| ≤ T_s`) and a velocity
//!   zero-crossing clamp so friction never reverses the motion;
//! - end stops: inelastic (infinitely stiff limit of a stiff stop): position
//!   clamped, inward velocity removed;
//! - thermal: `C_th·dϑ/dt = R·i² − (ϑ − ϑ_amb)/R_th`;
//! - DC link: `d(½CV²)/dt = −(R·i + kₑ·ω)·i − P_brake`, the supply clamps
//!   from below at the nominal voltage (diode rectifier).
//!
//! Stepper: torque `T_h·a·sin(N_r·(θ* − θ))` towards the micro-stepped
//! command `θ*` with `N_r = full_steps/4` rotor teeth, `a ≤ 1` the current
//! the chopper can still drive at speed, `a = min(1, V/(I·√(R² + (N_r ω L)²)))`.

mod detect;
pub mod events;
pub mod io;
pub mod params;
mod physics;
pub mod tuning;

pub use events::{Event, EventKind, Faults, MAX_EVENTS, ModelInjection, StepEvents, SwitchInput, Switches};
pub use io::{ANALOG_INPUTS, BrakeParams, BrakeState, DIGITAL_LINES, IoParams};
pub use params::{
    AxisKind, AxisParams, BusParams, ControlParams, DriveParams, EncoderParams, LoadTorque, MotorKind,
    MotorParams, ParamError, StepperParams,
};
pub use tuning::FoldbackParams;

use core::f64::consts::PI;

/// Set-point from the operating mode, in motor-shaft units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Demand {
    /// Power stage off: no torque, the motor coasts.
    Off,
    /// Cascaded position → velocity → current loops, with feed-forward.
    Position {
        /// Position demand \[rad\].
        position: f64,
        /// Velocity feed-forward \[rad/s\].
        velocity: f64,
        /// Acceleration feed-forward \[rad/s²\] (× inertia / kₜ into current).
        acceleration: f64,
    },
    /// Velocity → current loops.
    Velocity {
        /// Velocity demand \[rad/s\].
        velocity: f64,
        /// Acceleration feed-forward \[rad/s²\].
        acceleration: f64,
    },
    /// Torque demand \[Nm\] straight into the current loop (profile torque,
    /// cyclic synchronous torque). A stepper in open loop holds instead.
    Torque(f64),
    /// Braking at the voltage limit: windings short-circuited through the
    /// lower switches, `i = −kₑ·ω/R` limited to `±i_max`, no bus energy.
    ShortCircuit,
}

impl Demand {
    fn kind(&self) -> u8 {
        match self {
            Demand::Off => 0,
            Demand::Position { .. } => 1,
            Demand::Velocity { .. } => 2,
            Demand::Torque(_) => 3,
            Demand::ShortCircuit => 4,
        }
    }

    /// Finite and within ±[`Demand::MAX_SETPOINT`].
    fn is_valid(&self) -> bool {
        let ok = |v: f64| v.is_finite() && v.abs() <= Self::MAX_SETPOINT;
        match *self {
            Demand::Position { position, velocity, acceleration } => {
                ok(position) && ok(velocity) && ok(acceleration)
            }
            Demand::Velocity { velocity, acceleration } => ok(velocity) && ok(acceleration),
            Demand::Torque(t) => ok(t),
            Demand::Off | Demand::ShortCircuit => true,
        }
    }

    /// Largest magnitude accepted for any set-point value.
    pub const MAX_SETPOINT: f64 = 1e15;
}

/// Switch, stop and stepper constants derived once from the parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Derived {
    inertia: f64,
    counts_per_rad: f64,
    rad_per_unit: f64,
    neg_limit: Option<f64>,
    pos_limit: Option<f64>,
    /// Limit switch hysteresis \[rad\].
    limit_hysteresis: f64,
    home: Option<(f64, f64)>,
    neg_stop: Option<f64>,
    pos_stop: Option<f64>,
    /// Stepper: rotor teeth (electrical periods per revolution), 0 for servo.
    teeth: f64,
    /// Stepper: one micro-step \[rad\].
    microstep: f64,
}

/// Per-`dt` coefficients, recomputed only when `dt` changes.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Coeffs {
    dt: f64,
    current: f64,
    viscous: f64,
    thermal: f64,
    vel_filter: f64,
    brake: f64,
}

/// A motor on an axis with its drive's power stage and inner loops.
#[derive(Debug, Clone, PartialEq)]
pub struct DriveModel {
    p: DriveParams,
    d: Derived,
    k: Coeffs,
    cmd: Demand,
    // mechanical and electrical state
    theta: f64,
    omega: f64,
    current: f64,
    torque: f64,
    temperature: f64,
    bus_voltage: f64,
    /// Power the braking resistor dissipated in the last step \[W\].
    regen_power: f64,
    // sensing
    counts: i64,
    prev_counts: i64,
    vel_meas: f64,
    // control
    int_pos: f64,
    int_vel: f64,
    vel_saturated: bool,
    // stepper
    step_target: f64,
    slip: i64,
    // supervision
    contact: i8,
    stall_timer: f64,
    stalled: bool,
    /// Reported switch levels (60FDh): the axis' levels unless forced.
    switches: Switches,
    /// Switch levels from the axis position alone.
    natural: Switches,
    /// Forced levels (negative limit, positive limit, home): a tripped or
    /// broken switch, set by [`ModelInjection::ForceSwitch`].
    forced: [Option<bool>; 3],
    /// `forced` as of the last step (a release is an edge too).
    prev_forced: [Option<bool>; 3],
    faults: Faults,
    force_oc: bool,
    force_ot: bool,
    force_bus: Option<f64>,
    encoder_failed: bool,
    load_step: f64,
    /// Inputs, outputs, master encoder, brake, temperature reading.
    io: io::Io,
    /// Run-time current and speed limits, foldback.
    limits: tuning::Limits,
    events: StepEvents,
}

fn opt_rad(v: Option<f64>, f: f64, field: &'static str) -> Result<Option<f64>, ParamError> {
    match v {
        Some(v) if !(v * f).is_finite() => Err(ParamError { field, reason: "out of range" }),
        Some(v) => Ok(Some(v * f)),
        None => Ok(None),
    }
}

impl DriveModel {
    /// Builds a model at rest at `axis.initial_position`, ambient
    /// temperature, nominal bus voltage, command [`Demand::Off`].
    pub fn new(params: DriveParams) -> Result<Self, ParamError> {
        params.validate()?;
        let a = &params.axis;
        let rad_per_unit = 2.0 * PI / a.units_per_motor_rev();
        if !(rad_per_unit.is_finite() && rad_per_unit > 0.0) {
            return Err(ParamError { field: "axis.gear_ratio", reason: "out of range" });
        }
        let (teeth, microstep) = match params.motor.kind {
            MotorKind::Servo => (0.0, 0.0),
            MotorKind::Stepper(s) => {
                (f64::from(s.full_steps / 4), 2.0 * PI / (f64::from(s.full_steps) * f64::from(s.microsteps)))
            }
        };
        let home = match a.home_switch {
            Some((lo, hi)) => {
                let (lo, hi) = (lo * rad_per_unit, hi * rad_per_unit);
                if !(lo.is_finite() && hi.is_finite()) {
                    return Err(ParamError { field: "axis.home_switch", reason: "out of range" });
                }
                Some((lo, hi))
            }
            None => None,
        };
        let d = Derived {
            inertia: params.motor.rotor_inertia + a.load_inertia,
            counts_per_rad: f64::from(params.encoder.counts_per_rev) / (2.0 * PI),
            rad_per_unit,
            neg_limit: opt_rad(a.negative_limit, rad_per_unit, "axis.negative_limit")?,
            pos_limit: opt_rad(a.positive_limit, rad_per_unit, "axis.positive_limit")?,
            limit_hysteresis: a.limit_hysteresis * rad_per_unit.abs(),
            home,
            neg_stop: opt_rad(a.negative_stop, rad_per_unit, "axis.negative_stop")?,
            pos_stop: opt_rad(a.positive_stop, rad_per_unit, "axis.positive_stop")?,
            teeth,
            microstep,
        };
        let theta = a.initial_position * rad_per_unit;
        if !theta.is_finite() || theta.abs() > 1e12 {
            return Err(ParamError { field: "axis.initial_position", reason: "out of range" });
        }
        let mut m = DriveModel {
            p: params,
            d,
            k: Coeffs { dt: 0.0, current: 0.0, viscous: 1.0, thermal: 0.0, vel_filter: 1.0, brake: 1.0 },
            cmd: Demand::Off,
            theta,
            omega: 0.0,
            current: 0.0,
            torque: 0.0,
            temperature: params.motor.ambient_temperature,
            bus_voltage: params.bus.nominal_voltage,
            regen_power: 0.0,
            counts: 0,
            prev_counts: 0,
            vel_meas: 0.0,
            int_pos: 0.0,
            int_vel: 0.0,
            vel_saturated: false,
            step_target: theta,
            slip: 0,
            contact: 0,
            stall_timer: 0.0,
            stalled: false,
            switches: Switches::default(),
            natural: Switches::default(),
            forced: [None; 3],
            prev_forced: [None; 3],
            faults: Faults::default(),
            force_oc: false,
            force_ot: false,
            force_bus: None,
            encoder_failed: false,
            load_step: 0.0,
            io: io::Io::new(&params.io),
            limits: tuning::Limits::none(),
            events: StepEvents::default(),
        };
        m.counts = m.read_counts(theta);
        m.prev_counts = m.counts;
        m.natural = m.switch_levels(theta);
        m.switches = m.natural;
        Ok(m)
    }

    /// The parameters.
    pub fn params(&self) -> &DriveParams {
        &self.p
    }

    /// Sets the demand applied from the next step on. A set-point that is
    /// not finite or beyond ±[`Demand::MAX_SETPOINT`] is refused (returns
    /// `false`, the previous demand stays). Changing the kind of demand
    /// re-initialises the loop integrators bumplessly.
    pub fn set_demand(&mut self, cmd: Demand) -> bool {
        if !cmd.is_valid() {
            return false;
        }
        let (old, new) = (self.cmd.kind(), cmd.kind());
        if old != new {
            // Start the velocity integrator at the present current so the
            // torque does not jump when a loop takes over.
            self.int_vel = self.current.clamp(-self.p.motor.max_current, self.p.motor.max_current);
            self.int_pos = 0.0;
            if let MotorKind::Stepper(_) = self.p.motor.kind {
                if old == 0 {
                    // Re-energising: the chopper starts where the rotor is.
                    self.step_target = self.theta;
                    self.slip = 0;
                } else if new != 1 {
                    self.step_target = self.demand_position();
                }
            }
        }
        self.cmd = cmd;
        true
    }

    /// The demand in force.
    pub fn demand(&self) -> Demand {
        self.cmd
    }

    /// Places the axis at `position` \[rad\] moving at `velocity` \[rad/s\]
    /// (initialisation and tests). Refused (`false`) if not finite, beyond
    /// an end stop, |position| > 1e12 rad or |velocity| > 1e9 rad/s.
    pub fn set_motion(&mut self, position: f64, velocity: f64) -> bool {
        let ok = position.is_finite()
            && velocity.is_finite()
            && position.abs() <= 1e12
            && velocity.abs() <= 1e9
            && self.d.neg_stop.is_none_or(|s| position >= s)
            && self.d.pos_stop.is_none_or(|s| position <= s);
        if ok {
            self.theta = position;
            self.omega = velocity;
            self.step_target = position;
            self.slip = 0;
            self.contact = 0;
            if !self.encoder_failed {
                self.counts = self.read_counts(position);
            }
            self.prev_counts = self.counts;
            self.vel_meas = velocity;
            self.natural = self.switch_levels_from(self.natural, position);
            self.switches = self.with_forced(self.natural);
        }
        ok
    }

    /// Advances the model by `dt` seconds (one control period) and returns
    /// the events that happened in it. `dt` outside `(0, 10 ms]` or not
    /// finite does nothing.
    pub fn step(&mut self, dt: f64) -> &StepEvents {
        self.events.clear();
        if !(dt.is_finite() && dt > 0.0 && dt <= 0.01) {
            return &self.events;
        }
        if dt != self.k.dt {
            self.k = physics::coeffs(&self.p, self.d.inertia, dt);
        }
        let theta0 = self.theta;
        self.sense(dt);
        self.io_step(dt);
        match self.p.motor.kind {
            MotorKind::Servo => self.servo_step(dt),
            MotorKind::Stepper(s) => self.stepper_step(dt, s),
        }
        self.foldback_step(dt);
        self.thermal_step();
        self.bus_step(dt);
        self.detect(theta0);
        self.forced_edges();
        self.supervise();
        &self.events
    }

    /// Events of the last step.
    pub fn events(&self) -> &StepEvents {
        &self.events
    }

    /// Applies a fault injection.
    pub fn inject(&mut self, what: ModelInjection) {
        match what {
            ModelInjection::OverCurrent => self.force_oc = true,
            ModelInjection::OverTemperature => self.force_ot = true,
            ModelInjection::BusOverVoltage => self.force_bus = Some(self.p.bus.over_voltage * 1.05),
            ModelInjection::BusUnderVoltage => self.force_bus = Some(self.p.bus.under_voltage * 0.9),
            ModelInjection::BusVoltage(v) => {
                self.force_bus = v.filter(|v| v.is_finite() && (0.0..=1e6).contains(v));
                if self.force_bus.is_none() {
                    self.bus_voltage = self.p.bus.nominal_voltage;
                }
            }
            ModelInjection::EncoderFailure => self.encoder_failed = true,
            ModelInjection::ForceSwitch(which, level) => self.forced[which as usize] = level,
            ModelInjection::LoadTorqueStep(t) => {
                if t.is_finite() && t.abs() <= params::MAX_TORQUE {
                    self.load_step = t;
                }
            }
            ModelInjection::DigitalInput { line, level } => {
                if (1..=DIGITAL_LINES as u8).contains(&line) {
                    let bit = 1u16 << (line - 1);
                    self.io.digital = if level { self.io.digital | bit } else { self.io.digital & !bit };
                }
            }
            ModelInjection::AnalogInput { channel, volts } => {
                let slot = usize::from(channel).checked_sub(1).and_then(|i| self.io.analog.get_mut(i));
                if let Some(v) = slot
                    && volts.is_finite()
                    && volts.abs() <= io::MAX_VOLTS
                {
                    *v = volts;
                }
            }
            ModelInjection::MasterVelocity(v) => {
                if v.is_finite() && v.abs() <= io::MAX_MASTER {
                    self.io.master_vel = v;
                }
            }
            ModelInjection::MasterPosition(p) => {
                if p.is_finite() && p.abs() <= io::MAX_MASTER {
                    self.io.master_pos = p;
                }
            }
            ModelInjection::MotorTemperature(t) => {
                let t = t.filter(|t| t.is_finite() && (-273.0..=1e4).contains(t));
                self.io.temperature = t.or(self.p.io.motor_temperature);
            }
            ModelInjection::Brake(b) => self.io.brake_forced = b,
            ModelInjection::Clear => {
                self.io.temperature = self.p.io.motor_temperature;
                self.io.brake_forced = None;
                self.force_oc = false;
                self.force_ot = false;
                if self.force_bus.take().is_some() {
                    // The forced voltage was fictitious: back to the supply.
                    self.bus_voltage = self.p.bus.nominal_voltage;
                }
                self.encoder_failed = false;
                self.load_step = 0.0;
                self.forced = [None; 3];
            }
        }
        if let Some(v) = self.force_bus {
            self.bus_voltage = v;
        }
        self.supervise();
    }

    /// Fault reset: clears the latched flags whose condition has gone and
    /// returns those that remain.
    pub fn clear_faults(&mut self) -> Faults {
        self.faults = Faults::default();
        self.supervise();
        self.faults
    }

    /// Latched fault flags.
    pub fn faults(&self) -> Faults {
        self.faults
    }

    /// True motor angle \[rad\].
    pub fn position(&self) -> f64 {
        self.theta
    }

    /// True motor speed \[rad/s\].
    pub fn velocity(&self) -> f64 {
        self.omega
    }

    /// Encoder reading \[counts\] (frozen after an encoder failure).
    pub fn position_counts(&self) -> i64 {
        self.counts
    }

    /// Measured position \[rad\] (quantised encoder reading).
    pub fn position_measured(&self) -> f64 {
        self.counts as f64 / self.d.counts_per_rad
    }

    /// Measured (encoder-differentiated, filtered) speed \[rad/s\].
    pub fn velocity_measured(&self) -> f64 {
        self.vel_meas
    }

    /// Stepper: the micro-stepped demand angle \[rad\] (what an open-loop
    /// stepper drive reports as its position). Servo: the true angle.
    pub fn demand_position(&self) -> f64 {
        match self.p.motor.kind {
            MotorKind::Servo => self.theta,
            MotorKind::Stepper(_) => libm::round(self.step_target / self.d.microstep) * self.d.microstep,
        }
    }

    /// Motor current \[A\] (stepper: phase current amplitude).
    pub fn current(&self) -> f64 {
        self.current
    }

    /// Motor torque \[Nm\].
    pub fn torque(&self) -> f64 {
        self.torque
    }

    /// Motor (winding) temperature \[°C\]: the thermal model's, or the
    /// reading forced by [`IoParams::motor_temperature`] /
    /// [`ModelInjection::MotorTemperature`].
    pub fn temperature(&self) -> f64 {
        self.io.temperature.unwrap_or(self.temperature)
    }

    /// DC link voltage \[V\].
    pub fn bus_voltage(&self) -> f64 {
        self.bus_voltage
    }

    /// Power the braking resistor (the DC link's chopper) dissipates
    /// \[W\], averaged over the last step; 0 while it is off.
    pub fn regen_power(&self) -> f64 {
        self.regen_power
    }

    /// Switch levels.
    pub fn switches(&self) -> Switches {
        self.switches
    }

    /// Whether the motor is stalled (blocked at an end stop or at the current
    /// limit without motion; stepper: lost synchronism).
    pub fn stalled(&self) -> bool {
        self.stalled
    }

    /// The end stop the axis rests against: `Some(true)` positive.
    pub fn at_hard_stop(&self) -> Option<bool> {
        match self.contact {
            0 => None,
            c => Some(c > 0),
        }
    }

    /// Stepper open loop: micro-steps lost by slipping (positive: the rotor
    /// is behind a positive command). Always 0 for servo / closed loop.
    pub fn lost_steps(&self) -> i64 {
        match self.p.motor.kind {
            MotorKind::Stepper(s) => self.slip.saturating_mul(4 * i64::from(s.microsteps)),
            MotorKind::Servo => 0,
        }
    }

    /// Total inertia on the motor shaft \[kg·m²\].
    pub fn inertia(&self) -> f64 {
        self.d.inertia
    }

    /// Motor angle \[rad\] → position units.
    pub fn rad_to_units(&self, rad: f64) -> f64 {
        rad / self.d.rad_per_unit
    }

    /// Position units → motor angle \[rad\].
    pub fn units_to_rad(&self, units: f64) -> f64 {
        units * self.d.rad_per_unit
    }

    /// Encoder counts per radian.
    pub fn counts_per_rad(&self) -> f64 {
        self.d.counts_per_rad
    }

    fn read_counts(&self, theta: f64) -> i64 {
        // `as` saturates; positions are bounded far inside i64 anyway.
        libm::floor(theta * self.d.counts_per_rad) as i64
    }

    fn sense(&mut self, dt: f64) {
        if !self.encoder_failed {
            self.counts = self.read_counts(self.theta);
        }
        let delta = self.counts.saturating_sub(self.prev_counts);
        let raw = delta as f64 / (self.d.counts_per_rad * dt);
        self.prev_counts = self.counts;
        self.vel_meas += (raw - self.vel_meas) * self.k.vel_filter;
    }

    fn supervise(&mut self) {
        let m = &self.p.motor;
        let b = &self.p.bus;
        let t = self.io.temperature.unwrap_or(self.temperature);
        let f = &mut self.faults;
        f.over_current |= self.force_oc || self.current.abs() > m.overcurrent_trip;
        f.over_voltage |= self.bus_voltage > b.over_voltage;
        f.under_voltage |= self.bus_voltage < b.under_voltage;
        f.over_temperature |= self.force_ot || t > m.max_temperature;
        f.encoder |= self.encoder_failed;
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_axis;
#[cfg(test)]
mod tests_io;
#[cfg(test)]
mod tests_prop;
#[cfg(test)]
mod tests_tuning;
