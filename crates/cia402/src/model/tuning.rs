//! What a drive's parameters change in the running model: its loop gains
//! and motor data ([`DriveModel::set_params`]), direction-dependent current
//! and speed limits ([`DriveModel::set_current_limits`],
//! [`DriveModel::set_velocity_limits`]) and an I²t current foldback
//! ([`DriveModel::set_foldback`]).
//!
//! The foldback follows `i²` through a first-order filter of the motor's
//! thermal time constant; while the filtered value is above the continuous
//! current squared the foldback current falls towards the continuous
//! current with that time constant, below it recovers towards the peak
//! current. The power stage never drives more than the foldback current.

use super::{DriveModel, DriveParams, ParamError};

/// The I²t foldback's ratings ([`DriveModel::set_foldback`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FoldbackParams {
    /// Current the motor may carry for ever \[A\].
    pub continuous: f64,
    /// Current available with a cold motor \[A\] (≥ `continuous`).
    pub peak: f64,
    /// Time constant of the I²t filter and of the foldback \[s\].
    pub time_constant: f64,
}

/// The I²t foldback's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Foldback {
    pub p: FoldbackParams,
    /// Filtered `i²` \[A²\].
    pub i2t: f64,
    /// Foldback current \[A\].
    pub current: f64,
    /// `1 − e^(−dt/τ)` for the `dt` it was computed for.
    pub k: (f64, f64),
}

/// Run-time limits of the power stage and the loops, and the current
/// feed-forwards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Limits {
    /// Current limit in the positive / negative direction \[A\] (magnitudes).
    pub current: [f64; 2],
    /// Speed limit in the positive / negative direction \[rad/s\].
    pub velocity: [f64; 2],
    pub foldback: Option<Foldback>,
    /// Constant current added to the command \[A\] (gravity compensation).
    pub current_offset: f64,
    /// Current added in the direction of motion \[A\] (friction
    /// compensation).
    pub friction: f64,
    /// Largest voltage the power stage applies to the motor \[V\].
    pub voltage: f64,
}

impl Limits {
    pub(super) fn none() -> Limits {
        Limits {
            current: [f64::INFINITY; 2],
            velocity: [f64::INFINITY; 2],
            foldback: None,
            current_offset: 0.0,
            friction: 0.0,
            voltage: f64::INFINITY,
        }
    }
}

fn magnitude(field: &'static str, v: f64) -> Result<f64, ParamError> {
    if v.is_nan() || v < 0.0 {
        return Err(ParamError { field, reason: "must be >= 0 (infinity: no limit)" });
    }
    Ok(v)
}

impl DriveModel {
    /// Changes the motor, bus and control parameters of the running model
    /// (a drive's tuning and motor objects): the state (position, speed,
    /// current, temperature) stays, the derived coefficients follow from
    /// the next step. The motor kind, encoder, axis geometry, control rate
    /// and the plant's signals are those of the machine and cannot change
    /// (`ParamError` names the field), nor can anything fail
    /// [`DriveParams::validate`].
    pub fn set_params(&mut self, p: DriveParams) -> Result<(), ParamError> {
        p.validate()?;
        let fixed = |field: &'static str, same: bool| {
            if same { Ok(()) } else { Err(ParamError { field, reason: "fixed by the machine" }) }
        };
        let (a, b) = (&self.p.axis, &p.axis);
        fixed(
            "motor.kind",
            core::mem::discriminant(&self.p.motor.kind) == core::mem::discriminant(&p.motor.kind),
        )?;
        fixed("encoder", self.p.encoder == p.encoder)?;
        fixed(
            "axis",
            a.kind == b.kind
                && a.feed_constant == b.feed_constant
                && a.gear_ratio == b.gear_ratio
                && a.negative_limit == b.negative_limit
                && a.positive_limit == b.positive_limit
                && a.limit_hysteresis == b.limit_hysteresis
                && a.home_switch == b.home_switch
                && a.negative_stop == b.negative_stop
                && a.positive_stop == b.positive_stop,
        )?;
        fixed("control.control_rate_hz", self.p.control.control_rate_hz == p.control.control_rate_hz)?;
        fixed("io", self.p.io == p.io)?;
        self.p = p;
        self.d.inertia = p.motor.rotor_inertia + p.axis.load_inertia;
        // Recomputed at the next step.
        self.k.dt = 0.0;
        let imax = p.motor.max_current;
        self.int_vel = self.int_vel.clamp(-imax, imax);
        let vmax = p.motor.max_speed;
        self.int_pos = self.int_pos.clamp(-vmax, vmax);
        Ok(())
    }

    /// Limits the current the power stage drives to `positive` A in the
    /// positive and `negative` A (a magnitude) in the negative direction,
    /// within the motor's maximum; `f64::INFINITY` lifts a limit. Refused
    /// (`ParamError`) for a negative or NaN value.
    pub fn set_current_limits(&mut self, positive: f64, negative: f64) -> Result<(), ParamError> {
        self.limits.current =
            [magnitude("current_limit.positive", positive)?, magnitude("current_limit.negative", negative)?];
        Ok(())
    }

    /// The current limits in force \[A\]: positive, negative (magnitudes,
    /// within the motor's maximum and the foldback).
    pub fn current_limits(&self) -> (f64, f64) {
        let cap = self.current_cap();
        (self.limits.current[0].min(cap), self.limits.current[1].min(cap))
    }

    /// Limits the speed the loops command to `positive` rad/s in the
    /// positive and `negative` rad/s (a magnitude) in the negative
    /// direction, within the motor's maximum speed; `f64::INFINITY` lifts a
    /// limit.
    pub fn set_velocity_limits(&mut self, positive: f64, negative: f64) -> Result<(), ParamError> {
        self.limits.velocity = [
            magnitude("velocity_limit.positive", positive)?,
            magnitude("velocity_limit.negative", negative)?,
        ];
        Ok(())
    }

    /// Switches the I²t foldback on with `p` (`None`: off, the power stage
    /// drives up to the motor's maximum current). A new rating starts from
    /// a cold motor.
    pub fn set_foldback(&mut self, p: Option<FoldbackParams>) -> Result<(), ParamError> {
        let Some(p) = p else {
            self.limits.foldback = None;
            return Ok(());
        };
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(p.continuous) && ok(p.peak) && p.peak >= p.continuous && p.peak <= 1e5) {
            return Err(ParamError { field: "foldback", reason: "need 0 < continuous <= peak" });
        }
        if !(ok(p.time_constant) && p.time_constant <= 1e6) {
            return Err(ParamError { field: "foldback.time_constant", reason: "must be in (0, 1e6] s" });
        }
        let (i2t, current) = match self.limits.foldback {
            Some(f) => (f.i2t, f.current.min(p.peak)),
            None => (0.0, p.peak),
        };
        self.limits.foldback = Some(Foldback { p, i2t, current, k: (0.0, 0.0) });
        Ok(())
    }

    /// Adds `offset` A to the current command (a constant load such as
    /// gravity carried without the loops' error) and `friction` A in the
    /// direction the motor turns (above 0.1 % of its maximum speed), in
    /// every mode with the power stage on; within the current limits.
    pub fn set_current_feedforward(&mut self, offset: f64, friction: f64) -> Result<(), ParamError> {
        let ok = |v: f64| v.is_finite() && v.abs() <= 1e5;
        if !(ok(offset) && ok(friction) && friction >= 0.0) {
            return Err(ParamError { field: "current_feedforward", reason: "out of range (friction >= 0)" });
        }
        self.limits.current_offset = offset;
        self.limits.friction = friction;
        Ok(())
    }

    /// Limits the voltage the power stage applies to the motor to `volts`
    /// (the motor's rating, below the DC bus); `f64::INFINITY`: the bus
    /// alone limits.
    pub fn set_voltage_limit(&mut self, volts: f64) -> Result<(), ParamError> {
        self.limits.voltage = magnitude("voltage_limit", volts)?;
        Ok(())
    }

    /// The current feed-forward for the present speed \[A\].
    pub(super) fn current_feedforward(&self) -> f64 {
        let l = &self.limits;
        let w = self.omega;
        let moving = w.abs() > 1e-3 * self.p.motor.max_speed;
        l.current_offset + if moving { l.friction * w.signum() } else { 0.0 }
    }

    /// The foldback current \[A\] (`None`: no foldback): what the power
    /// stage may drive now.
    pub fn foldback_current(&self) -> Option<f64> {
        self.limits.foldback.map(|f| f.current)
    }

    /// The foldback's filtered `i²` \[A²\] (`None`: no foldback).
    pub fn foldback_i2t(&self) -> Option<f64> {
        self.limits.foldback.map(|f| f.i2t)
    }

    /// The motor's maximum current, folded back.
    pub(super) fn current_cap(&self) -> f64 {
        let imax = self.p.motor.max_current;
        match self.limits.foldback {
            Some(f) => imax.min(f.current),
            None => imax,
        }
    }

    /// The speed window `[lo, hi]` the loops may command.
    pub(super) fn velocity_window(&self) -> (f64, f64) {
        let v = self.p.motor.max_speed;
        (-v.min(self.limits.velocity[1]), v.min(self.limits.velocity[0]))
    }

    /// One step of the foldback after the current moved.
    pub(super) fn foldback_step(&mut self, dt: f64) {
        let i = self.current;
        let Some(f) = &mut self.limits.foldback else { return };
        if f.k.0 != dt {
            f.k = (dt, -libm::expm1(-dt / f.p.time_constant));
        }
        let k = f.k.1;
        f.i2t += (i * i - f.i2t) * k;
        let c = f.p.continuous;
        let target = if f.i2t > c * c { c } else { f.p.peak };
        f.current += (target - f.current) * k;
    }
}
