//! Profile position mode (CiA 402-2 §6.7 / IEC 61800-7-201 "profile
//! position"): set-point handshake (controlword bit 4 new set-point,
//! statusword bit 12 set-point acknowledge), single set-point (bit 5 change
//! immediately) and set of set-points (one buffered), bit 6 relative, bit 9
//! change on set-point, halt (bit 8, 605Dh), software limits 607Dh, position
//! range 607Bh, target reached by 6067h/6068h.
//!
//! With 6086h = 3 the moves are S-curves ([`SCurve`]): a new set-point
//! while moving (bit 5, or the next of a set with bit 9) is planned from
//! the present position, velocity *and* acceleration, so change
//! immediately stays jerk-limited (CiA 402-2 allows bit 5 with every
//! profile type); a drive may refuse bit 5 with the S-curve instead
//! ([`DriveConfig::scurve_forbids_change_immediately`](super::DriveConfig::scurve_forbids_change_immediately),
//! Technosoft iPOS). Halt and the stop reactions keep their linear ramps.

use super::profile::{Jerk, Limits, Ramp, SCurve, Shape, Trajectory};

/// A buffered set-point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Pending {
    pub target: f64,
    pub change_on_setpoint: bool,
}

/// Profile position state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Pp {
    pub traj: Trajectory,
    /// The S-curve of a jerk-limited move (in force while `s_curve`).
    pub scurve: SCurve,
    /// The running move is `scurve`, not `traj`.
    pub s_curve: bool,
    /// Time into `traj` \[s\].
    pub t: f64,
    /// The target of the running (or last) move \[position units\].
    pub target: f64,
    pub buffered: Option<Pending>,
    /// Statusword bit 12.
    pub ack: bool,
    /// Rising edge of controlword bit 4 not yet processed.
    pub edge: bool,
    /// The controlword of that edge (bits 5, 6, 9 qualify the set-point).
    pub edge_cw: u16,
    pub bit4: bool,
    /// The last target was clamped by 607Dh (statusword bit 11).
    pub limited: bool,
    pub halted: bool,
    pub halt_ramp: Ramp,
    /// A move is in progress (trajectory not finished).
    pub moving: bool,
    /// A set-point was refused because bit 5 is not allowed with the
    /// S-curve (`PpIn::forbid_change_immediately`); the drive takes it.
    pub rejected: bool,
}

/// Inputs of one profile position period.
pub(crate) struct PpIn {
    pub cw: u16,
    pub target_raw: i32,
    pub lim: Limits,
    pub shape: Shape,
    pub halt_dec: f64,
    pub soft_limits: (i32, i32),
    pub range: (i32, i32),
    /// How a target on a modulo axis is reached (60F2h bits 7–6, "rado"):
    /// [`Rado::Shortest`] unless a personality sets another.
    pub rado: Rado,
    pub dt: f64,
    /// The running target counts as reached (actual in the position
    /// window, [`TargetReached::ActualInWindow`](super::TargetReached)):
    /// a buffered set-point starts now.
    pub running_reached: bool,
    /// Present acceleration demand (continuity of the jerk-limited ramp).
    pub acc: f64,
    /// Jerk for [`Shape::JerkLimited`]; `None` runs the linear ramp.
    pub jerk: Option<Jerk>,
    /// With [`Shape::JerkLimited`], a set-point with bit 5 is refused
    /// ([`DriveConfig::scurve_forbids_change_immediately`](super::DriveConfig::scurve_forbids_change_immediately)).
    pub forbid_change_immediately: bool,
}

/// Positioning on a modulo axis (607Bh), CiA 402-2 60F2h bits 7–6.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Rado {
    /// 00: as a linear axis: an absolute target is reached from the
    /// wrapped position without wrapping the target, a relative move goes
    /// its whole way (moves over a modulo value).
    Linear,
    /// 01: only in the negative direction.
    Negative,
    /// 10: only in the positive direction.
    Positive,
    /// 11: the shortest way.
    #[default]
    Shortest,
}

impl Rado {
    /// From 60F2h (bits 7–6).
    pub fn from_option_code(code: u16) -> Rado {
        match (code >> 6) & 3 {
            0 => Rado::Linear,
            1 => Rado::Negative,
            2 => Rado::Positive,
            _ => Rado::Shortest,
        }
    }
}

/// Wraps `x` into the position range `[lo, hi]` (modulo axis, 607Bh).
pub(crate) fn wrap(x: f64, lo: i32, hi: i32) -> f64 {
    if lo >= hi {
        return x;
    }
    let (lo, span) = (f64::from(lo), f64::from(hi) - f64::from(lo) + 1.0);
    let r = libm::fmod(x - lo, span);
    lo + if r < 0.0 { r + span } else { r }
}

impl Pp {
    /// Forgets any move: hold at `pos`.
    pub fn reset(&mut self, pos: f64) {
        *self = Pp { target: pos, bit4: self.bit4, ..Pp::default() };
        self.traj = Trajectory::plan(
            pos,
            0.0,
            pos,
            Limits { velocity: 1.0, acceleration: 1.0, deceleration: 1.0 },
            Shape::Linear,
        );
    }

    /// Controlword bits 4 edges (called on every controlword write).
    pub fn controlword(&mut self, cw: u16) {
        let b4 = cw & 0x10 != 0;
        if b4 && !self.bit4 {
            self.edge = true;
            self.edge_cw = cw;
        }
        self.bit4 = b4;
    }

    fn absolute_target(&self, i: &PpIn, pos: f64) -> (f64, bool) {
        let raw = f64::from(i.target_raw);
        // Bit 6: relative to the preceding target (60F2h default).
        let relative = self.edge_cw & 0x40 != 0;
        let mut t = if relative { self.target + raw } else { raw };
        let (lo, hi) = i.range;
        if lo < hi {
            let w = wrap(t, lo, hi);
            let span = f64::from(hi) - f64::from(lo) + 1.0;
            let here = wrap(pos, lo, hi);
            let mut d = w - here;
            match i.rado {
                // An absolute target is taken from the wrapped position as on
                // a linear axis (a relative move keeps its whole way).
                Rado::Linear => d = t - here,
                Rado::Negative if d > 0.0 => d -= span,
                Rado::Positive if d < 0.0 => d += span,
                Rado::Shortest if d > span / 2.0 => d -= span,
                Rado::Shortest if d < -span / 2.0 => d += span,
                _ => {}
            }
            if !(relative && i.rado == Rado::Linear) {
                t = pos + d;
            }
        }
        let (smin, smax) = i.soft_limits;
        if smin != 0 || smax != 0 {
            let c = t.clamp(f64::from(smin), f64::from(smax.max(smin)));
            return (c, c != t);
        }
        (t, false)
    }

    fn start(&mut self, target: f64, p: f64, v: f64, i: &PpIn) {
        self.target = target;
        match (i.shape, i.jerk) {
            // CiA 402-2 pp: a change of set-point on the fly re-plans the
            // S-curve from the present position, velocity and acceleration
            // (continuous in all three, see `SCurve::plan`).
            (Shape::JerkLimited, Some(j)) => {
                self.scurve = SCurve::plan(p, v, i.acc, target, i.lim, j);
                self.s_curve = true;
            }
            _ => {
                self.traj = Trajectory::plan(p, v, target, i.lim, i.shape);
                self.s_curve = false;
            }
        }
        self.t = 0.0;
        self.moving = true;
    }

    /// One control period: returns the demand `(position, velocity,
    /// acceleration)` and updates the handshake. `(p, v)` is the present
    /// demand.
    pub fn step(&mut self, i: &PpIn, p: f64, v: f64) -> (f64, f64, f64) {
        let halt = i.cw & 0x100 != 0;
        if self.edge && !self.ack && !i.lim.valid() {
            // A zero 6081h/6083h/6084h cannot be planned: the set-point is
            // refused (not acknowledged, no motion) rather than jumped to.
            self.edge = false;
        } else if self.edge
            && !self.ack
            && i.forbid_change_immediately
            && i.shape == Shape::JerkLimited
            && self.edge_cw & 0x20 != 0
        {
            // Technosoft iPOS §7.1.2: with the S-curve bit 5 must be 0;
            // the set-point is ignored (not acknowledged) and reported.
            self.edge = false;
            self.rejected = true;
        } else if self.edge && !self.ack {
            self.edge = false;
            let (t, limited) = self.absolute_target(i, p);
            self.limited = limited;
            if self.edge_cw & 0x20 != 0 || !self.moving {
                // Single set-point / idle: the new target applies at once.
                self.buffered = None;
                self.start(t, p, v, i);
            } else {
                self.buffered = Some(Pending { target: t, change_on_setpoint: self.edge_cw & 0x200 != 0 });
            }
            self.ack = true;
        } else if self.edge && self.ack {
            // Buffer full: the set-point is ignored (CiA 402-2 §6.7.x).
            self.edge = false;
        }
        if self.ack && !self.bit4 && self.buffered.is_none() {
            self.ack = false;
        }
        if halt {
            if !self.halted {
                self.halted = true;
                self.halt_ramp = Ramp { value: v, rate: 0.0 };
            }
            let nv = self.halt_ramp.step(0.0, i.halt_dec, i.halt_dec, i.dt);
            return (p + (v + nv) / 2.0 * i.dt, nv, self.halt_ramp.rate);
        }
        if self.halted {
            // Halt released: continue to the target from where we are.
            self.halted = false;
            if self.moving {
                let t = self.target;
                self.start(t, p, v, i);
            }
        }
        if self.moving {
            self.t += i.dt;
            if let Some(b) = self.buffered
                && (self.t >= self.duration()
                    || i.running_reached
                    || (b.change_on_setpoint && self.decelerating(self.t)))
            {
                // Next set-point of the set: bit 9 continues without stopping
                // (dropped if a ramp was set to 0 meanwhile).
                self.buffered = None;
                if i.lim.valid() {
                    self.start(b.target, p, v, i);
                    self.t = i.dt;
                }
            }
            if self.t >= self.duration() {
                self.moving = false;
            }
        }
        if self.s_curve { self.scurve.at(self.t) } else { self.traj.at(self.t) }
    }

    /// Duration of the running move \[s\].
    fn duration(&self) -> f64 {
        if self.s_curve { self.scurve.duration() } else { self.traj.duration() }
    }

    /// Whether the running move is in its final deceleration at `t`.
    fn decelerating(&self, t: f64) -> bool {
        if self.s_curve { self.scurve.decelerating(t) } else { self.traj.decelerating(t) }
    }
}
