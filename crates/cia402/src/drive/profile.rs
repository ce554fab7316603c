//! Set-point generators: the profile position trapezoid with exact analytic
//! timing (CiA 402-2 §6.7 profile position; 6086h motion profile type 0
//! linear ramp, 1 sin² ramp, 3 jerk-limited ramp) and a slew-limited ramp
//! for velocity, torque and stop ramps.
//!
//! The jerk-limited ramp ([`SCurve::plan`]) is the
//! 7-segment S-curve: every velocity change is a jerk-up / constant
//! acceleration / jerk-down triple, so acceleration is continuous and
//! bounded by the profile acceleration (speed rising) or deceleration
//! (speed falling), jerk by [`Jerk`].

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
    /// 3: jerk-limited ramp (7-segment S-curve); planned with
    /// [`SCurve::plan`] (through [`Trajectory::plan`], which has no jerk,
    /// it is the linear ramp).
    JerkLimited,
}

/// Jerk limits of a jerk-limited move \[position units/s³\] (60A4h).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jerk {
    /// Jerk while the speed rises (60A4h:1).
    pub acceleration: f64,
    /// Jerk while the speed falls (60A4h:2).
    pub deceleration: f64,
}

impl Jerk {
    /// Both jerks positive and finite: an S-curve can be planned.
    pub fn valid(&self) -> bool {
        [self.acceleration, self.deceleration].iter().all(|x| x.is_finite() && *x > 0.0)
    }
}

/// One constant-jerk piece of a jerk-limited trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct JerkSegment {
    t0: f64,
    dur: f64,
    p0: f64,
    v0: f64,
    a0: f64,
    /// Jerk over the piece.
    j: f64,
}

impl JerkSegment {
    fn eval(&self, tau: f64) -> (f64, f64, f64) {
        let (a, j) = (self.a0, self.j);
        let p = self.p0 + tau * (self.v0 + tau * (a / 2.0 + tau * j / 6.0));
        (p, self.v0 + tau * (a + tau * j / 2.0), a + j * tau)
    }
}

/// Capacity of a jerk-limited plan: acceleration to 0 (1), a stop (3),
/// then accelerate / cruise / decelerate (7) — 11, one spare.
const MAX_JERK_SEGMENTS: usize = 12;

/// Durations `(t_jerk, t_const)` of a velocity change by `dv` ≥ 0 with
/// acceleration limit `a` and jerk `j`: jerk for `t_jerk`, constant `a`
/// for `t_const`, jerk back for `t_jerk`. When `dv` is too small to reach
/// `a` (`dv < a²/j`) the acceleration peaks at `√(dv·j)`.
fn ramp_times(dv: f64, a: f64, j: f64) -> (f64, f64) {
    if dv.is_nan() || dv <= 0.0 {
        (0.0, 0.0)
    } else if dv * j >= a * a {
        (a / j, (dv / a - a / j).max(0.0))
    } else {
        (libm::sqrt(dv / j), 0.0)
    }
}

/// Duration of a velocity change by `dv` (see [`ramp_times`]).
fn ramp_duration(dv: f64, a: f64, j: f64) -> f64 {
    let (tj, ta) = ramp_times(dv, a, j);
    2.0 * tj + ta
}

/// Closed-form peak velocity of a move from rest over `dist` that does not
/// reach the velocity limit (the caller checked), when both ramps reach
/// their acceleration limit or neither does; `None` otherwise (mixed
/// cases and moving starts are quartics: the caller bisects).
///
/// - both reach a, d: `vp²·(1/a + 1/d)/2 + vp·(a/ja + d/jd)/2 = D`;
/// - neither: `vp^{3/2}·(1/√ja + 1/√jd) = D`.
fn rest_peak(u: f64, dist: f64, a: f64, d: f64, ja: f64, jd: f64) -> Option<f64> {
    if u != 0.0 || dist.is_nan() || dist <= 0.0 {
        return None;
    }
    // Peak velocities above which each ramp reaches its acceleration limit.
    let (sat_a, sat_d) = (a * a / ja, d * d / jd);
    let k2 = (1.0 / a + 1.0 / d) / 2.0;
    let k1 = (a / ja + d / jd) / 2.0;
    // Stable root of k2·vp² + k1·vp − D = 0.
    let both = 2.0 * dist / (k1 + libm::sqrt(k1 * k1 + 4.0 * k2 * dist));
    if both.is_finite() && both >= sat_a && both >= sat_d {
        return Some(both);
    }
    let c = 1.0 / libm::sqrt(ja) + 1.0 / libm::sqrt(jd);
    let r = dist / c;
    let neither = libm::cbrt(r * r);
    (neither.is_finite() && neither > 0.0 && neither < sat_a && neither < sat_d).then_some(neither)
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

/// A planned jerk-limited point-to-point move (6086h = 3): up to 12
/// constant-jerk pieces, evaluated analytically. Kept apart from
/// [`Trajectory`] so the trapezoid's plan stays small on the hot path.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SCurve {
    seg: [JerkSegment; MAX_JERK_SEGMENTS],
    n: usize,
    target: f64,
    /// Start of the final deceleration \[s\].
    decel: f64,
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

impl SCurve {
    /// Plans a jerk-limited move (6086h = 3) from `(p0, v0, a0)` to rest at
    /// `target`.
    ///
    /// From rest this is the time-optimal 7-segment S-curve under the
    /// velocity, acceleration/deceleration and jerk limits: the peak velocity
    /// is the profile velocity if the move is long enough, else the largest
    /// peak whose accelerate + decelerate distance fits (short moves may
    /// reach neither the velocity nor the acceleration limit).
    ///
    /// From a moving start (change set immediately, set of set-points, halt
    /// released) the plan stays continuous in position, velocity *and*
    /// acceleration, so the motor never sees a step of acceleration:
    /// 1. a non-zero `a0` is first brought to 0 at the jerk limit (the
    ///    acceleration jerk while the speed grows, else the deceleration
    ///    jerk);
    /// 2. if the axis then moves away from the target, cannot stop before
    ///    it, or runs faster than the profile velocity and cannot slow down
    ///    to it within the distance, it stops on an S-curve first (and then
    ///    moves back or on from rest);
    /// 3. otherwise: S-curve to the peak velocity (up with the acceleration
    ///    limits, down with the deceleration limits when above the profile
    ///    velocity), cruise, S-curve to rest at the target.
    ///
    /// This is not time-optimal from a moving start (step 1 may cost up to
    /// two jerk times) but never exceeds a limit the start state was not
    /// already beyond.
    ///
    /// Each piece's duration is closed-form. The peak velocity of a move too
    /// short to cruise is closed-form from rest when both ramps reach their
    /// acceleration limit or neither does (always so for a = d, one jerk);
    /// otherwise (one ramp saturated, or a moving start: quartics) it is
    /// the root of the monotone distance function, found by bisection to
    /// full f64 resolution. With invalid limits or jerk the trajectory
    /// jumps to the target.
    pub fn plan(p0: f64, v0: f64, a0: f64, target: f64, lim: Limits, jerk: Jerk) -> SCurve {
        let mut t = SCurve { target, ..SCurve::default() };
        if !lim.valid() || !jerk.valid() || ![p0, v0, a0, target].iter().all(|x| x.is_finite()) {
            return t;
        }
        let (a, d, vmax) = (lim.acceleration, lim.deceleration, lim.velocity);
        let (ja, jd) = (jerk.acceleration, jerk.deceleration);
        let mut st = (p0, v0, a0);
        let mut now = 0.0;
        if a0 != 0.0 {
            // Speed growing (or from standstill): the end of an acceleration
            // phase; else the end of a deceleration phase.
            let j = if a0 * v0 >= 0.0 { ja } else { jd };
            t.jpush(&mut now, &mut st, a0.abs() / j, -a0.signum() * j);
            st.2 = 0.0;
        }
        // At most: stop (moving away / overshooting / too fast), then the
        // move from rest; one spare pass.
        for _ in 0..4 {
            let (p, v) = (st.0, st.1);
            let dist = target - p;
            if dist == 0.0 && v == 0.0 {
                break;
            }
            let s = if dist > 0.0 || (dist == 0.0 && v < 0.0) { 1.0 } else { -1.0 };
            let u = s * v;
            let big_d = s * dist;
            // Rounding slack: a stop landing a hair past the target is taken.
            let tol = 1e-12 * (1.0 + big_d.abs());
            // Distance of u → vp (speed up with a/ja, down with d/jd), then
            // vp → 0 with d/jd; each ramp covers its mean speed × duration.
            let reach = |vp: f64| {
                let first = if vp >= u { ramp_duration(vp - u, a, ja) } else { ramp_duration(u - vp, d, jd) };
                (u + vp) / 2.0 * first + vp / 2.0 * ramp_duration(vp, d, jd)
            };
            let stop = u / 2.0 * ramp_duration(u, d, jd);
            if u < 0.0 || stop > big_d + tol || (u > vmax && reach(vmax) > big_d + tol) {
                t.jramp(&mut now, &mut st, 0.0, d, jd);
                continue;
            }
            let vp = if u > vmax || reach(vmax) <= big_d {
                vmax
            } else if let Some(vp) = rest_peak(u, big_d, a, d, ja, jd) {
                vp
            } else {
                let (mut lo, mut hi) = (u, vmax);
                for _ in 0..200 {
                    let mid = lo + (hi - lo) / 2.0;
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if reach(mid) <= big_d {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                lo
            };
            let cruise = if vp > 0.0 { (big_d - reach(vp)).max(0.0) / vp } else { 0.0 };
            let (r, j) = if vp >= u { (a, ja) } else { (d, jd) };
            t.jramp(&mut now, &mut st, s * vp, r, j);
            t.jpush(&mut now, &mut st, cruise, 0.0);
            t.decel = now;
            t.jramp(&mut now, &mut st, 0.0, d, jd);
            break;
        }
        t
    }

    /// Appends a constant-jerk piece and advances the state `(p, v, a)`.
    fn jpush(&mut self, now: &mut f64, st: &mut (f64, f64, f64), dur: f64, j: f64) {
        if dur.is_nan() || dur <= 0.0 {
            return;
        }
        let seg = JerkSegment { t0: *now, dur, p0: st.0, v0: st.1, a0: st.2, j };
        // Capacity suffices by construction (see MAX_JERK_SEGMENTS).
        if let Some(slot) = self.seg.get_mut(self.n) {
            *slot = seg;
            self.n += 1;
        }
        *st = seg.eval(dur);
        *now += dur;
    }

    /// Appends the S-curve triple taking the velocity to `v_to` with
    /// acceleration limit `amax` and jerk `j` (from zero acceleration).
    fn jramp(&mut self, now: &mut f64, st: &mut (f64, f64, f64), v_to: f64, amax: f64, j: f64) {
        let dv = v_to - st.1;
        let (tj, ta) = ramp_times(dv.abs(), amax, j);
        let js = j.copysign(dv);
        self.jpush(now, st, tj, js);
        self.jpush(now, st, ta, 0.0);
        self.jpush(now, st, tj, -js);
        // The ramp ends exactly at v_to with no acceleration (rounding).
        st.1 = v_to;
        st.2 = 0.0;
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

    /// Whether `t` lies in the final deceleration (or after it).
    pub fn decelerating(&self, t: f64) -> bool {
        self.n == 0 || t >= self.decel
    }

    /// Position, velocity and acceleration at `t` seconds after the start;
    /// exactly `(target, 0, 0)` from [`SCurve::duration`] on.
    pub fn at(&self, t: f64) -> (f64, f64, f64) {
        for s in &self.seg[..self.n] {
            if t < s.t0 + s.dur {
                return s.eval((t - s.t0).max(0.0));
            }
        }
        (self.target, 0.0, 0.0)
    }
}

fn eval(s: &Segment, tau: f64, shape: Shape) -> (f64, f64, f64) {
    let a = s.dv / s.dur;
    match shape {
        // A jerk-limited plan never has trapezoid segments; were one asked
        // for through `plan`, it is the linear ramp.
        Shape::Linear | Shape::JerkLimited => (s.p0 + s.v0 * tau + a * tau * tau / 2.0, s.v0 + a * tau, a),
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

    // ---- jerk-limited ramp (6086h = 3) ----

    const J: Jerk = Jerk { acceleration: 20_000.0, deceleration: 20_000.0 };
    const SYM: Limits = Limits { velocity: 100.0, acceleration: 1000.0, deceleration: 1000.0 };

    /// Samples `t` every `h` seconds: the largest |v|, |a|, |Δa/h|, and
    /// whether everything stayed finite.
    fn sample(t: &SCurve, h: f64) -> (f64, f64, f64, bool) {
        let (mut vm, mut am, mut jm, mut finite) = (0.0f64, 0.0f64, 0.0f64, true);
        let n = (t.duration() / h).ceil() as usize + 2;
        let mut prev = t.at(0.0).2;
        for k in 0..=n {
            let (p, v, a) = t.at(k as f64 * h);
            finite &= p.is_finite() && v.is_finite() && a.is_finite();
            vm = vm.max(v.abs());
            am = am.max(a.abs());
            if k > 0 {
                jm = jm.max((a - prev).abs() / h);
            }
            prev = a;
        }
        (vm, am, jm, finite)
    }

    /// Independent closed forms of the symmetric rest-to-rest S-curve
    /// (a = d, one jerk j, distance D, velocity limit v):
    /// - v and a reached: T = D/v + v/a + a/j;
    /// - v reached, a not (v < a²/j): T = D/v + 2√(v/j);
    /// - a reached, v not: peak vp from vp²/a + vp·a/j = D, T = 2(vp/a + a/j);
    /// - neither: T = 4·∛(D/2j).
    fn analytic(dist: f64, v: f64, a: f64, j: f64) -> f64 {
        let d_min_full = v * (v / a + a / j); // both limits just reached
        if v * j >= a * a {
            if dist >= d_min_full {
                return dist / v + v / a + a / j;
            }
            // a reached? needs D ≥ 2a³/j² (the distance of a triangle at a).
            if dist >= 2.0 * a * a * a / (j * j) {
                let vp = a / 2.0 * (-a / j + (a * a / (j * j) + 4.0 * dist / a).sqrt());
                return 2.0 * (vp / a + a / j);
            }
            return 4.0 * (dist / (2.0 * j)).cbrt();
        }
        // v < a²/j: a is never reached.
        let d_full_v = 2.0 * v * (v / j).sqrt();
        if dist >= d_full_v { dist / v + 2.0 * (v / j).sqrt() } else { 4.0 * (dist / (2.0 * j)).cbrt() }
    }

    #[test]
    fn scurve_durations_match_the_analytic_s_curve() {
        // a²/j = 50 < v = 100: the four regimes by distance, then v < a²/j.
        let cases = [
            (50.0, SYM, J),                              // v and a reached (D ≥ 100·(0.1+0.05) = 15)
            (2.0, SYM, J),                               // a reached, v not (2a³/j² = 5e-3 ≤ 2 < 15)
            (0.001, SYM, J),                             // neither
            (-30.0, SYM, J),                             // negative direction
            (30.0, Limits { velocity: 20.0, ..SYM }, J), // v < a²/j = 50: a never reached
            (0.1, Limits { velocity: 20.0, ..SYM }, J),  // short: neither
        ];
        for (dist, lim, j) in cases {
            let t = SCurve::plan(0.0, 0.0, 0.0, dist, lim, j);
            let want = analytic(dist.abs(), lim.velocity, lim.acceleration, j.acceleration);
            assert!(
                (t.duration() - want).abs() <= 1e-9 * want.max(1.0),
                "D={dist}: {} vs {want}",
                t.duration()
            );
            assert_eq!(t.at(t.duration()), (dist, 0.0, 0.0));
            let (p, v, a) = t.at(t.duration() * (1.0 - 1e-12));
            assert!((p - dist).abs() < 1e-9 && v.abs() < 1e-6 && a.abs() < 1e-3, "{p} {v} {a}");
            let (vm, am, jm, finite) = sample(&t, 1e-5);
            assert!(finite);
            assert!(vm <= lim.velocity * (1.0 + 1e-9), "v {vm}");
            assert!(am <= lim.acceleration * (1.0 + 1e-9), "a {am}");
            assert!(jm <= j.acceleration * (1.0 + 1e-6), "j {jm}");
        }
    }

    #[test]
    fn scurve_position_at_phase_ends_is_analytic() {
        // Full profile: after the jerk phase p = j·tj³/6, after the
        // acceleration p(ta + tj) = v·(v/a + a/j)/2.
        let t = SCurve::plan(0.0, 0.0, 0.0, 50.0, SYM, J);
        let tj = 1000.0 / 20_000.0;
        let (p, v, a) = t.at(tj);
        assert!((p - 20_000.0 * tj * tj * tj / 6.0).abs() < 1e-9);
        assert!((v - 20_000.0 * tj * tj / 2.0).abs() < 1e-9 && (a - 1000.0).abs() < 1e-6);
        let t_acc = 100.0 / 1000.0 + tj;
        let (p, v, _) = t.at(t_acc);
        assert!((p - 100.0 * t_acc / 2.0).abs() < 1e-9 && (v - 100.0).abs() < 1e-9);
    }

    #[test]
    fn scurve_asymmetric_ramps() {
        // a ≠ d, ja ≠ jd, long move: T = D/v + (v/a + a/ja)/2 + (v/d + d/jd)/2.
        let lim = Limits { velocity: 100.0, acceleration: 1000.0, deceleration: 400.0 };
        let j = Jerk { acceleration: 40_000.0, deceleration: 8_000.0 };
        let t = SCurve::plan(10.0, 0.0, 0.0, 110.0, lim, j);
        let want = 100.0 / 100.0 + (0.1 + 0.025) / 2.0 + (0.25 + 0.05) / 2.0;
        assert!((t.duration() - want).abs() < 1e-12, "{}", t.duration());
        assert!(t.decelerating(want - 0.3 + 1e-9) && !t.decelerating(want - 0.3 - 1e-6));
        assert_eq!(t.at(t.duration()).0, 110.0);
    }

    #[test]
    fn scurve_mixed_saturation_matches_the_quartic() {
        // a²/ja = 50 (not reached), d²/jd = 0.5 (reached) for vp ≈ 10:
        // D = vp^{3/2}/√ja + vp²/2d + vp·d/2jd, solved here by Newton;
        // T = 2√(vp/ja) + vp/d + d/jd.
        let (a, d, ja, jd) = (1000.0f64, 100.0f64, 20_000.0f64, 20_000.0f64);
        let dist = 0.7;
        let f = |vp: f64| vp.powf(1.5) / ja.sqrt() + vp * vp / (2.0 * d) + vp * d / (2.0 * jd) - dist;
        let df = |vp: f64| 1.5 * vp.sqrt() / ja.sqrt() + vp / d + d / (2.0 * jd);
        let mut vp = 10.0;
        for _ in 0..50 {
            vp -= f(vp) / df(vp);
        }
        assert!(vp > 0.5 && vp < 50.0, "regime: {vp}");
        let want = 2.0 * (vp / ja).sqrt() + vp / d + d / jd;
        let lim = Limits { velocity: 100.0, acceleration: a, deceleration: d };
        let t = SCurve::plan(0.0, 0.0, 0.0, dist, lim, Jerk { acceleration: ja, deceleration: jd });
        assert!((t.duration() - want).abs() < 1e-12, "{} vs {want}", t.duration());
        assert!((t.at(want).0 - dist).abs() < 1e-12);
        assert_eq!(t.at(t.duration()).0, dist);
    }

    #[test]
    fn scurve_from_a_moving_start_is_continuous() {
        // Moving towards, away, too fast, accelerating and decelerating.
        let starts = [(50.0, 0.0), (-80.0, 0.0), (300.0, 0.0), (60.0, 900.0), (60.0, -900.0), (-20.0, 500.0)];
        for (v0, a0) in starts {
            for target in [-5.0, 0.5, 3.0, 40.0] {
                let t = SCurve::plan(0.0, v0, a0, target, SYM, J);
                let (p, v, a) = t.at(0.0);
                assert!(p.abs() < 1e-12 && (v - v0).abs() < 1e-12 && (a - a0).abs() < 1e-9);
                assert_eq!(t.at(t.duration()), (target, 0.0, 0.0));
                let (pe, ve, _) = t.at(t.duration() * (1.0 - 1e-13));
                assert!((pe - target).abs() < 1e-9 && ve.abs() < 1e-6, "{v0} {a0} → {target}: {pe}");
                let (vm, am, jm, finite) = sample(&t, 1e-5);
                assert!(finite);
                assert!(vm <= v0.abs().max(100.0) + a0 * a0 / (2.0 * 20_000.0) + 1e-9, "v {vm}");
                assert!(am <= a0.abs().max(1000.0) * (1.0 + 1e-9), "a {am}");
                assert!(jm <= 20_000.0 * (1.0 + 1e-6), "j {jm}");
            }
        }
    }

    #[test]
    fn scurve_invalid_limits_jump() {
        let t = SCurve::plan(0.0, 0.0, 0.0, 5.0, SYM, Jerk { acceleration: 0.0, deceleration: 1.0 });
        assert_eq!(t.duration(), 0.0);
        assert_eq!(t.at(0.0), (5.0, 0.0, 0.0));
        let t = SCurve::plan(0.0, f64::NAN, 0.0, 5.0, SYM, J);
        assert_eq!(t.at(1.0), (5.0, 0.0, 0.0));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]
        #[test]
        fn scurve_always_ends_on_target(
            dist in -1e6f64..1e6,
            v in 1e-1f64..1e5,
            a in 1e-1f64..1e6,
            d in 1e-1f64..1e6,
            j in 1e-1f64..1e8,
            v0f in -2.0f64..2.0,
            moving in proptest::bool::ANY,
        ) {
            let lim = Limits { velocity: v, acceleration: a, deceleration: d };
            let jerk = Jerk { acceleration: j, deceleration: j * 0.5 };
            let v0 = if moving { v0f * v } else { 0.0 };
            let t = SCurve::plan(0.0, v0, 0.0, dist, lim, jerk);
            let dur = t.duration();
            proptest::prop_assert!(dur.is_finite() && dur >= 0.0);
            proptest::prop_assert_eq!(t.at(dur), (dist, 0.0, 0.0));
            let (pe, _, _) = t.at(dur * (1.0 - 1e-12));
            proptest::prop_assert!((pe - dist).abs() <= 1e-6 * (1.0 + dist.abs() + v0.abs() * dur));
            // Sampled derivative bounds (jerk checked on the acceleration
            // differences, which are exact for piecewise-linear a).
            let n = 2000usize;
            let h = dur / n as f64;
            let mut prev = t.at(0.0).2;
            for k in 0..=n {
                let (p, vv, aa) = t.at(k as f64 * h);
                proptest::prop_assert!(p.is_finite() && vv.is_finite() && aa.is_finite());
                proptest::prop_assert!(vv.abs() <= v.max(v0.abs()) * (1.0 + 1e-9) + 1e-9);
                proptest::prop_assert!(aa.abs() <= a.max(d) * (1.0 + 1e-9) + 1e-9);
                if k > 0 && h > 0.0 {
                    proptest::prop_assert!((aa - prev).abs() <= j * h * (1.0 + 1e-6) + 1e-9 * a.max(d));
                }
                prev = aa;
            }
        }
    }
}
