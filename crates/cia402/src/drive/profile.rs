//! Set-point generators: the profile position trapezoid with exact analytic
//! timing (CiA 402-2 §6.7 profile position; 6086h motion profile type 0
//! linear ramp, 1 sin² ramp) and a slew-limited ramp for velocity, torque
//! and stop ramps.

use core::f64::consts::PI;

/// One constant-mean-acceleration piece of a trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Segment {
    /// Start time relative to the plan \[s\].
    t0: f64,
    /// Duration \[s\].
    dur: f64,
    p0: f64,
    v0: f64,
    /// Velocity change over the segment.
    dv: f64,
}

/// Ramp shape (6086h motion profile type).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Shape {
    /// 0: linear ramp (trapezoidal velocity profile).
    #[default]
    Linear,
    /// 1: sin² ramp (jerk-limited): acceleration `2a·sin²(πt/T)`, same
    /// ramp times and distances as the linear ramp.
    SinSquared,
}

/// A planned point-to-point move: up to four segments (brake from a wrong
/// direction, accelerate, cruise, decelerate), evaluated analytically.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Trajectory {
    seg: [Segment; 5],
    n: usize,
    target: f64,
    shape: Shape,
}

/// Limits of a move, all magnitudes in position units (/s, /s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Profile velocity (> 0).
    pub velocity: f64,
    /// Profile acceleration (> 0).
    pub acceleration: f64,
    /// Profile deceleration (> 0).
    pub deceleration: f64,
}

impl Limits {
    /// Every limit positive and finite: a motion can be planned.
    pub(crate) fn valid(&self) -> bool {
        [self.velocity, self.acceleration, self.deceleration].iter().all(|x| x.is_finite() && *x > 0.0)
    }
}

impl Trajectory {
    /// Plans a move from `(p0, v0)` to rest at `target`. With invalid
    /// limits the trajectory jumps to the target at once (zero duration).
    pub fn plan(p0: f64, v0: f64, target: f64, lim: Limits, shape: Shape) -> Trajectory {
        let mut t = Trajectory { target, shape, ..Trajectory::default() };
        if !lim.valid() || !p0.is_finite() || !v0.is_finite() || !target.is_finite() {
            return t;
        }
        let (a, d) = (lim.acceleration, lim.deceleration);
        let (mut p, mut v, mut now) = (p0, v0, 0.0);
        // At most: brake away-motion, brake overshoot (then reverse), then
        // the three-phase profile.
        for _ in 0..3 {
            let dist = target - p;
            if dist == 0.0 && v == 0.0 {
                break;
            }
            let s = if dist > 0.0 || (dist == 0.0 && v < 0.0) { 1.0 } else { -1.0 };
            let u = s * v;
            let big_d = s * dist;
            if u < 0.0 || u * u / (2.0 * d) > big_d * (1.0 + 1e-12) + 1e-12 {
                // Moving away, or cannot stop before the target: stop first.
                let dur = u.abs() / d;
                t.push(now, dur, p, v, -v);
                p += v * dur / 2.0;
                v = 0.0;
                now += dur;
                continue;
            }
            let vmax = lim.velocity;
            let vp = if u > vmax {
                vmax
            } else {
                let peak = libm::sqrt((big_d + u * u / (2.0 * a)) / (1.0 / (2.0 * a) + 1.0 / (2.0 * d)));
                peak.min(vmax).max(u.min(vmax))
            };
            // Phase 1: u → vp (accelerate with a, or slow down with d).
            let r1 = if vp >= u { a } else { d };
            let t1 = (vp - u).abs() / r1;
            let x1 = (u + vp) / 2.0 * t1;
            let x3 = vp * vp / (2.0 * d);
            let t3 = vp / d;
            let x2 = (big_d - x1 - x3).max(0.0);
            let t2 = if vp > 0.0 { x2 / vp } else { 0.0 };
            t.push(now, t1, p, v, s * (vp - u));
            p += s * x1;
            now += t1;
            t.push(now, t2, p, s * vp, 0.0);
            p += s * x2;
            now += t2;
            t.push(now, t3, p, s * vp, -s * vp);
            break;
        }
        t
    }

    fn push(&mut self, t0: f64, dur: f64, p0: f64, v0: f64, dv: f64) {
        if dur > 0.0 && self.n < self.seg.len() {
            self.seg[self.n] = Segment { t0, dur, p0, v0, dv };
            self.n += 1;
        }
    }

    /// The target.
    pub fn target(&self) -> f64 {
        self.target
    }

    /// Total duration \[s\].
    pub fn duration(&self) -> f64 {
        match self.n {
            0 => 0.0,
            n => self.seg[n - 1].t0 + self.seg[n - 1].dur,
        }
    }

    /// Whether `t` lies in the final deceleration segment (or after it).
    pub fn decelerating(&self, t: f64) -> bool {
        self.n == 0 || t >= self.seg[self.n - 1].t0
    }

    /// Position, velocity and acceleration at `t` seconds after the start;
    /// exactly `(target, 0, 0)` from [`Trajectory::duration`] on.
    pub fn at(&self, t: f64) -> (f64, f64, f64) {
        for s in &self.seg[..self.n] {
            if t < s.t0 + s.dur {
                let tau = (t - s.t0).max(0.0);
                return eval(s, tau, self.shape);
            }
        }
        (self.target, 0.0, 0.0)
    }
}

fn eval(s: &Segment, tau: f64, shape: Shape) -> (f64, f64, f64) {
    let a = s.dv / s.dur;
    match shape {
        Shape::Linear => (s.p0 + s.v0 * tau + a * tau * tau / 2.0, s.v0 + a * tau, a),
        Shape::SinSquared => {
            // a(τ) = 2ā·sin²(πτ/T): v = v0 + Δv(τ/T − sin(2πτ/T)/2π),
            // p = p0 + v0τ + Δv(τ²/2T + (cos(2πτ/T) − 1)·T/4π²).
            let w = 2.0 * PI / s.dur;
            let (sn, cs) = (libm::sin(w * tau), libm::cos(w * tau));
            let p = s.p0 + s.v0 * tau + s.dv * (tau * tau / (2.0 * s.dur) + (cs - 1.0) / (w * w * s.dur));
            let v = s.v0 + s.dv * (tau / s.dur - sn / (2.0 * PI));
            (p, v, a * (1.0 - cs))
        }
    }
}

/// Moves a value towards a target at a limited rate (velocity ramps for
/// pv/vl and stopping, torque slope 6087h for tq).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Ramp {
    /// Present value.
    pub value: f64,
    /// Rate of the last step (derivative).
    pub rate: f64,
}

impl Ramp {
    /// One step of `dt` towards `target`, rising in magnitude at `up`/s and
    /// falling at `down`/s (a zero or invalid rate jumps).
    pub fn step(&mut self, target: f64, up: f64, down: f64, dt: f64) -> f64 {
        let diff = target - self.value;
        let away_from_zero = target.abs() > self.value.abs() && target * self.value >= 0.0;
        let rate = if away_from_zero { up } else { down };
        let max = rate * dt;
        let old = self.value;
        if !(max.is_finite() && max > 0.0) || diff.abs() <= max {
            self.value = target;
        } else {
            self.value += max.copysign(diff);
        }
        self.rate = (self.value - old) / dt;
        self.value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIM: Limits = Limits { velocity: 100.0, acceleration: 1000.0, deceleration: 500.0 };

    #[test]
    fn trapezoid_duration_is_analytic() {
        let t = Trajectory::plan(0.0, 0.0, 50.0, LIM, Shape::Linear);
        // T = D/v + v/2a + v/2d.
        let expect = 50.0 / 100.0 + 100.0 / 2000.0 + 100.0 / 1000.0;
        assert!((t.duration() - expect).abs() < 1e-12);
        assert_eq!(t.at(expect + 1.0), (50.0, 0.0, 0.0));
        let (p, v, _) = t.at(0.05);
        assert!((v - 50.0).abs() < 1e-9 && (p - 1.25).abs() < 1e-9);
    }

    #[test]
    fn short_move_is_triangular() {
        let t = Trajectory::plan(0.0, 0.0, -3.0, LIM, Shape::Linear);
        // vp² (1/2a + 1/2d) = D.
        let vp = (3.0f64 / (1.0 / 2000.0 + 1.0 / 1000.0)).sqrt();
        assert!((t.duration() - (vp / 1000.0 + vp / 500.0)).abs() < 1e-12);
        let (p, _, _) = t.at(t.duration() - 1e-9);
        assert!((p + 3.0).abs() < 1e-6);
    }

    #[test]
    fn reversal_and_sin2_reach_target() {
        let t = Trajectory::plan(0.0, 100.0, 1.0, LIM, Shape::SinSquared);
        // Stops in 0.2 s at 10, then returns 9 units (triangular).
        let vp = (9.0f64 / (1.0 / 2000.0 + 1.0 / 1000.0)).sqrt();
        assert!((t.duration() - (0.2 + vp / 1000.0 + vp / 500.0)).abs() < 1e-12);
        let (p, v, _) = t.at(0.2);
        assert!((p - 10.0).abs() < 1e-9 && v.abs() < 1e-9);
        let (p, _, _) = t.at(t.duration() - 1e-7);
        assert!((p - 1.0).abs() < 1e-6);
    }

    #[test]
    fn ramp_rates() {
        let mut r = Ramp::default();
        let mut n = 0;
        // Binary-exact numbers: 8 / (128 · 1/128) = 8 steps up.
        while r.step(8.0, 128.0, 64.0, 1.0 / 128.0) != 8.0 {
            n += 1;
        }
        assert_eq!(n, 7);
        // Down at half the rate: 16 steps.
        let mut m = 1;
        while r.step(0.0, 128.0, 64.0, 1.0 / 128.0) != 0.0 {
            m += 1;
        }
        assert_eq!(m, 16);
    }
}
