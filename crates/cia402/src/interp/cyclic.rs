//! Cyclic synchronous position / velocity / torque (csp, csv, cst;
//! CiA 402-4 "cyclic synchronous modes", also IEC 61800-7-201): the target
//! (607Ah / 60FFh / 6071h) is sampled at SYNC, the drive interpolates
//! between the samples at its control rate over the cycle time 60C2h, with
//! the offsets 60B0h–60B2h as feed-forward.
//!
//! Statusword (mode-specific bits): bit 12 "drive follows the command
//! value" (target used as input to the control loop: operation enabled in
//! the mode, not halted, no following error); csp bit 13 "following error"
//! (6065h window exceeded for longer than 6066h; the drive also reports
//! fault 8611h). Bit 10 is reserved in the cyclic modes and stays 0.

use core::cmp::Ordering;

/// Controlword bit 8: halt.
pub(crate) const CW_HALT: u16 = 1 << 8;
/// Statusword bit 12 in the cyclic modes: drive follows the command value.
pub const FOLLOWS: u16 = 1 << 12;
/// Statusword bit 13 in csp: following error.
pub const FOLLOWING_ERROR: u16 = 1 << 13;
/// CiA 402 error code "following error" (603Fh / EMCY).
pub const FOLLOWING_ERROR_CODE: u16 = 0x8611;

/// Largest |target| or |offset| used; beyond it values are clamped (the
/// model's set-point limit).
pub const MAX_VALUE: f64 = 1e15;

/// One sample of an interpolated set-point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetPointSample {
    /// Value (position, velocity or torque).
    pub value: f64,
    /// Its rate of change per second.
    pub slope: f64,
    /// Rate of change of the slope per second (feed-forward).
    pub curvature: f64,
}

/// Linear interpolation between values latched at SYNC.
///
/// At each SYNC the segment restarts from the value reached so far and
/// heads for the new target, to be reached one cycle (60C2h) later; so
/// on-time SYNCs reproduce the targets exactly at the SYNC instants (one
/// cycle of delay: the target latched at SYNC k is the demand at SYNC k+1),
/// and the demand never jumps. A SYNC later than one cycle continues the
/// targets' own rate, (target − previous target) / cycle, for at most one
/// more cycle, then holds: a constant target is held however late the
/// SYNC comes. The segment's own slope also closes the distance left by
/// the previous segment; continued past the target it would carry the
/// demand beyond a constant target by that distance, and the next segment
/// back beyond it the other way — with SYNCs two cycles apart or more (a
/// 10 ms SYNC against a 1 ms 60C2h) an alternation that never dies out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interpolator {
    /// The demand at the last SYNC.
    start: f64,
    /// The segment's slope: from `start` to `target` in one cycle.
    slope: f64,
    /// The target latched at the last SYNC.
    target: f64,
    /// The targets' rate (target − previous target) / cycle: what a late
    /// SYNC continues.
    rate: f64,
    curvature: f64,
    steps: u32,
    dt_sum: f64,
    period: f64,
}

/// Relative tolerance of the cycle boundaries against the rounding of Σdt.
const EDGE: f64 = 1e-9;

impl Interpolator {
    /// Resting at `value` with cycle time `period` \[s\].
    pub fn new(value: f64, period: f64) -> Self {
        let mut i = Interpolator {
            start: 0.0,
            slope: 0.0,
            target: 0.0,
            rate: 0.0,
            curvature: 0.0,
            steps: 0,
            dt_sum: 0.0,
            period: 1e-3,
        };
        i.set_period(period);
        i.reset(value);
        i
    }

    /// Rest at `value` (bumpless entry).
    pub fn reset(&mut self, value: f64) {
        self.start = if value.is_finite() { value } else { 0.0 };
        self.target = self.start;
        self.slope = 0.0;
        self.rate = 0.0;
        self.curvature = 0.0;
        self.dt_sum = 0.0;
        self.steps = 0;
    }

    /// The cycle time \[s\]; ignored unless finite and in (0, 10 s].
    pub fn set_period(&mut self, period: f64) {
        if period.is_finite() && period > 0.0 && period <= 10.0 {
            self.period = period;
        }
    }

    /// The cycle time \[s\].
    pub fn period(&self) -> f64 {
        self.period
    }

    fn elapsed(&self) -> f64 {
        // Reaching the next SYNC instant exactly despite rounding of Σdt.
        let t = self.dt_sum;
        if (t - self.period).abs() <= EDGE * self.period { self.period } else { t.min(2.0 * self.period) }
    }

    /// The demand now.
    pub fn value(&self) -> f64 {
        let t = self.elapsed();
        if t <= self.period {
            self.start + self.slope * t
        } else {
            self.target + self.rate * (t - self.period)
        }
    }

    /// The demand's rate of change now: the segment's slope within the
    /// cycle, the targets' rate in the cycle after, then 0 (held).
    pub fn rate(&self) -> f64 {
        let t = self.dt_sum;
        if t < self.period * (1.0 - EDGE) {
            self.slope
        } else if t < 2.0 * self.period * (1.0 - EDGE) {
            self.rate
        } else {
            0.0
        }
    }

    /// SYNC: head for `target` over the next cycle. A non-finite target
    /// holds the present value.
    pub fn sync(&mut self, target: f64) {
        let now = self.value();
        // The slope the demand had over the last cycle (the segment's, up
        // to an on-time SYNC).
        let old = if self.dt_sum <= self.period * (1.0 + EDGE) { self.slope } else { self.rate() };
        self.start = now;
        if target.is_finite() {
            let target = target.clamp(-MAX_VALUE, MAX_VALUE);
            self.slope = (target - now) / self.period;
            self.rate = (target - self.target) / self.period;
            self.target = target;
        } else {
            self.slope = 0.0;
            self.rate = 0.0;
            self.target = now;
        }
        // The average rate of change of the slope over the last cycle.
        self.curvature = if self.steps > 0 { (self.slope - old) / self.period } else { 0.0 };
        self.dt_sum = 0.0;
        self.steps = 0;
    }

    /// SYNC without a new target (an ip buffer underflow): hold the present
    /// value.
    pub fn hold(&mut self) {
        self.sync(f64::NAN);
    }

    /// The demand for the control period starting now, then advances by
    /// `dt`. The model's loops compare the demand with the position sampled
    /// at the start of the period and add the feed-forward over it, so the
    /// demand refers to the period's start: the value latched at a SYNC is
    /// output from the first period after the next SYNC on.
    pub fn step(&mut self, dt: f64) -> SetPointSample {
        let t = self.dt_sum;
        let sample = SetPointSample {
            value: self.value(),
            slope: self.rate(),
            curvature: if t >= self.period * (1.0 - EDGE) { 0.0 } else { self.curvature },
        };
        if dt.is_finite() && dt > 0.0 {
            self.dt_sum += dt;
            self.steps = self.steps.saturating_add(1);
        }
        sample
    }
}

/// Following error supervision (6065h window, 6066h time-out, 60F4h actual).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FollowingWatch {
    /// 6065h window \[units\]; `None` = off (6065h = FFFF FFFFh).
    pub window: Option<f64>,
    /// 6066h time-out \[s\].
    pub timeout: f64,
    timer: f64,
    error: f64,
    exceeded: bool,
}

impl FollowingWatch {
    /// A watch with the given window and time-out.
    pub fn new(window: Option<f64>, timeout: f64) -> Self {
        FollowingWatch { window, timeout, timer: 0.0, error: 0.0, exceeded: false }
    }

    /// Checks `demand − actual` over a period of `dt`; returns whether the
    /// window has been exceeded for longer than the time-out.
    pub fn check(&mut self, demand: f64, actual: f64, dt: f64) -> bool {
        self.error = demand - actual;
        let outside = match self.window {
            // NaN counts as outside.
            Some(w) => !matches!(self.error.abs().partial_cmp(&w), Some(Ordering::Less | Ordering::Equal)),
            None => false,
        };
        self.timer = if outside { self.timer + dt.max(0.0) } else { 0.0 };
        self.exceeded = outside && self.timer > self.timeout;
        self.exceeded
    }

    /// 60F4h following error actual value \[units\].
    pub fn error(&self) -> f64 {
        self.error
    }

    /// Whether the last check exceeded the window for longer than the time-out.
    pub fn exceeded(&self) -> bool {
        self.exceeded
    }

    /// Restart the time-out.
    pub fn reset(&mut self) {
        self.timer = 0.0;
        self.exceeded = false;
        self.error = 0.0;
    }
}

/// Settings shared by the cyclic modes, in position units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CyclicConfig {
    /// 60C2h cycle time \[s\].
    pub period: f64,
    /// 6065h following error window \[units\] (`None` = off).
    pub following_window: Option<f64>,
    /// 6066h following error time-out \[s\].
    pub following_timeout: f64,
    /// Deceleration on halt \[units/s²\] (csp/csv) or torque slope
    /// \[per mille/s\] (cst).
    pub halt_deceleration: f64,
}

/// Velocity ramp to rest used on halt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HaltRamp {
    pub(crate) position: f64,
    pub(crate) velocity: f64,
}

impl HaltRamp {
    pub(crate) fn step(&mut self, decel: f64, dt: f64) -> (f64, f64, f64) {
        let d = if decel.is_finite() && decel > 0.0 { decel * dt } else { f64::INFINITY };
        let v0 = self.velocity;
        self.velocity = if v0.abs() <= d { 0.0 } else { v0 - d.copysign(v0) };
        self.position += 0.5 * (v0 + self.velocity) * dt;
        (self.position, self.velocity, if dt > 0.0 { (self.velocity - v0) / dt } else { 0.0 })
    }
}

/// Output of a cyclic mode period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CyclicOutput {
    /// Demand (position \[units\], velocity \[units/s\] or torque \[per mille\]).
    pub demand: f64,
    /// Its feed-forward derivative (csp: velocity; csv: acceleration; cst: 0).
    pub feed_forward: f64,
    /// csp: acceleration feed-forward \[units/s²\]; 0 otherwise.
    pub feed_forward2: f64,
    /// Statusword bits 12/13.
    pub status: u16,
    /// A fault to raise now (8611h following error), once.
    pub fault: Option<u16>,
}

/// Which cyclic mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CyclicKind {
    /// Cyclic synchronous position (8).
    Position,
    /// Cyclic synchronous velocity (9).
    Velocity,
    /// Cyclic synchronous torque (10).
    Torque,
}

/// A cyclic synchronous mode engine (csp, csv or cst).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cyclic {
    kind: CyclicKind,
    interp: Interpolator,
    /// Offset added to the demand (60B0h / 60B1h / 60B2h).
    offset: f64,
    /// Offset added to the feed-forward (csp: 60B1h).
    ff_offset: f64,
    watch: FollowingWatch,
    halt: Option<HaltRamp>,
    faulted: bool,
    last: f64,
}

impl Cyclic {
    /// An engine resting at `value` (csp: the position demand; csv: the
    /// velocity demand; cst: the torque demand).
    pub fn new(kind: CyclicKind, value: f64, config: &CyclicConfig) -> Self {
        Cyclic {
            kind,
            interp: Interpolator::new(value, config.period),
            offset: 0.0,
            ff_offset: 0.0,
            watch: FollowingWatch::new(config.following_window, config.following_timeout),
            halt: None,
            faulted: false,
            last: value,
        }
    }

    /// The mode.
    pub fn kind(&self) -> CyclicKind {
        self.kind
    }

    /// Re-enter at `value` bumplessly; clears the following-error latch.
    pub fn enter(&mut self, value: f64) {
        self.interp.reset(value);
        self.offset = 0.0;
        self.ff_offset = 0.0;
        self.watch.reset();
        self.halt = None;
        self.faulted = false;
        self.last = value;
    }

    /// SYNC: latch `target` (607Ah / 60FFh / 6071h) with the offset
    /// (60B0h / 60B1h / 60B2h) and, for csp, the velocity offset 60B1h.
    pub fn sync(&mut self, target: f64, offset: f64, ff_offset: f64, config: &CyclicConfig) {
        self.interp.set_period(config.period);
        self.watch.window = config.following_window;
        self.watch.timeout = config.following_timeout;
        if self.halt.is_some() {
            return;
        }
        // The interpolator runs on the target alone; the offsets are added
        // on output, so changing them is a step as CiA 402-4 intends
        // (offsets are the master's feed-forward, not trajectory points).
        self.interp.sync(target);
        let clean = |v: f64| if v.is_finite() { v.clamp(-MAX_VALUE, MAX_VALUE) } else { 0.0 };
        self.offset = clean(offset);
        self.ff_offset = clean(ff_offset);
    }

    /// 60F4h following error actual value (csp) \[units\].
    pub fn following_error(&self) -> f64 {
        self.watch.error()
    }

    /// The demand of the last period.
    pub fn demand(&self) -> f64 {
        self.last
    }

    /// One control period. `actual` is the position actual value (csp; the
    /// others ignore it): the sample of the previous period's start, as the
    /// model delivers it between steps. `controlword` for halt (bit 8).
    pub fn step(&mut self, controlword: u16, actual: f64, config: &CyclicConfig, dt: f64) -> CyclicOutput {
        let halt = controlword & CW_HALT != 0;
        let dt = if dt.is_finite() && dt > 0.0 { dt } else { 0.0 };
        let (demand, ff, ff2) = if halt {
            let ramp =
                self.halt.get_or_insert(HaltRamp { position: self.last, velocity: self.interp_rate() });
            match self.kind {
                CyclicKind::Position => ramp.step(config.halt_deceleration, dt),
                // csv: ramp the velocity demand; cst: ramp the torque down.
                CyclicKind::Velocity | CyclicKind::Torque => {
                    let mut r = HaltRamp { position: 0.0, velocity: ramp.position };
                    let (_, v, a) = r.step(config.halt_deceleration, dt);
                    ramp.position = v;
                    (v, a, 0.0)
                }
            }
        } else {
            if self.halt.take().is_some() {
                // Halt released: resume from where the ramp left the demand.
                self.interp.reset(self.last - self.offset);
            }
            let s = self.interp.step(dt);
            match self.kind {
                CyclicKind::Position => (s.value + self.offset, s.slope + self.ff_offset, s.curvature),
                CyclicKind::Velocity => (s.value + self.offset, s.slope, 0.0),
                CyclicKind::Torque => (s.value + self.offset, 0.0, 0.0),
            }
        };
        // `actual` is the encoder sample the loops took at the start of the
        // previous period, the one they compared with the previous demand:
        // 60F4h pairs those two.
        let previous = core::mem::replace(&mut self.last, demand);
        let mut status = 0;
        let mut fault = None;
        if self.kind == CyclicKind::Position && self.watch.check(previous, actual, dt) {
            status |= FOLLOWING_ERROR;
            if !self.faulted {
                self.faulted = true;
                fault = Some(FOLLOWING_ERROR_CODE);
            }
        }
        if !halt && status & FOLLOWING_ERROR == 0 {
            status |= FOLLOWS;
        }
        CyclicOutput { demand, feed_forward: ff, feed_forward2: ff2, status, fault }
    }

    fn interp_rate(&self) -> f64 {
        match self.kind {
            CyclicKind::Position => self.interp.rate() + self.ff_offset,
            // csv / cst ramps start from the present demand value.
            CyclicKind::Velocity | CyclicKind::Torque => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A SYNC half a cycle early leaves the demand short of the target;
    /// then SYNCs ten cycles apart (a 10 ms SYNC against a 1 ms 60C2h)
    /// with the target constant: the demand reaches it within the cycle and
    /// stays on it, never carried past it to swing back from the other side
    /// at the next SYNC.
    #[test]
    fn syncs_far_apart_hold_a_constant_target() {
        let mut i = Interpolator::new(0.0, 1e-3);
        i.sync(100.0);
        for _ in 0..4 {
            i.step(1.25e-4);
        }
        assert_eq!(i.value(), 50.0);
        let mut demand = Vec::new();
        for _ in 0..6 {
            i.sync(100.0);
            for _ in 0..80 {
                demand.push(i.step(1.25e-4).value);
            }
        }
        assert!(demand.iter().all(|&v| (50.0..=100.0).contains(&v)), "{demand:?}");
        assert!(demand[8..].iter().all(|&v| v == 100.0), "{demand:?}");
        assert_eq!(i.rate(), 0.0);
    }
}
