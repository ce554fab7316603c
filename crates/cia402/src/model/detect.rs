//! Switch and index-pulse edge detection between two steps. The motion in a
//! step is taken as the straight segment θ₀ → θ₁, so each switch boundary is
//! crossed at most once per step and its crossing is located exactly.

use super::physics::frac;
use super::{DriveModel, Event, EventKind, Switches};
use core::f64::consts::PI;

impl DriveModel {
    pub(super) fn event_at(&self, kind: EventKind, active: bool, position: f64, f: f64) -> Event {
        Event {
            kind,
            active,
            position,
            counts: if self.encoder_failed { self.counts } else { self.read_counts(position) },
            positive_direction: self.omega >= 0.0,
            fraction: f,
        }
    }

    pub(super) fn switch_levels(&self, th: f64) -> Switches {
        Switches {
            negative_limit: self.d.neg_limit.is_some_and(|b| th <= b),
            positive_limit: self.d.pos_limit.is_some_and(|b| th >= b),
            home: self.d.home.is_some_and(|(lo, hi)| lo <= th && th <= hi),
        }
    }

    /// The switch levels at `th` coming from `old`: an active limit switch
    /// releases only the hysteresis back inside its edge.
    pub(super) fn switch_levels_from(&self, old: Switches, th: f64) -> Switches {
        let mut s = self.switch_levels(th);
        let h = self.d.limit_hysteresis;
        if old.negative_limit {
            s.negative_limit = self.d.neg_limit.is_some_and(|b| th <= b + h);
        }
        if old.positive_limit {
            s.positive_limit = self.d.pos_limit.is_some_and(|b| th >= b - h);
        }
        s
    }

    /// `s` with the forced levels in place of the axis' ones.
    pub(super) fn with_forced(&self, s: Switches) -> Switches {
        let [n, p, h] = self.forced;
        Switches {
            negative_limit: n.unwrap_or(s.negative_limit),
            positive_limit: p.unwrap_or(s.positive_limit),
            home: h.unwrap_or(s.home),
        }
    }

    /// After [`Self::detect`]: a level that changed because a switch was
    /// forced or released (not by motion) is an edge at the present
    /// position, so the drive and homing see a tripped switch as a switch.
    pub(super) fn forced_edges(&mut self) {
        let now = self.with_forced(self.natural);
        let was = self.switches;
        let th = self.theta;
        for (i, kind, a, b) in [
            (0, EventKind::NegativeLimit, was.negative_limit, now.negative_limit),
            (1, EventKind::PositiveLimit, was.positive_limit, now.positive_limit),
            (2, EventKind::Home, was.home, now.home),
        ] {
            let touched = self.forced[i].is_some() || self.prev_forced[i].is_some();
            if touched && a != b {
                let e = self.event_at(kind, b, th, 1.0);
                self.events.push(e);
            }
        }
        self.switches = now;
        self.prev_forced = self.forced;
    }

    fn edge(&mut self, kind: EventKind, active: bool, th0: f64, th1: f64, at: f64) {
        let mut e = self.event_at(kind, active, at, frac(th0, th1, at));
        e.positive_direction = th1 > th0;
        self.events.push(e);
    }

    pub(super) fn detect(&mut self, th0: f64) {
        let th1 = self.theta;
        if th1 == th0 {
            return;
        }
        let up = th1 > th0;
        let old = self.natural;
        let new = self.switch_levels_from(old, th1);
        // A switch forced now or in the last step changes level by the
        // fault, not by motion: `forced_edges` reports it.
        let touched = |i: usize| self.forced[i].is_some() || self.prev_forced[i].is_some();
        let (fneg, fpos, fhome) = (touched(0), touched(1), touched(2));
        let h = self.d.limit_hysteresis;
        // A forced switch shows no edge of the axis: its level is the fault's.
        if let Some(b) = self.d.neg_limit.filter(|_| !fneg && old.negative_limit != new.negative_limit) {
            let at = if new.negative_limit { b } else { b + h };
            self.edge(EventKind::NegativeLimit, new.negative_limit, th0, th1, at);
        }
        if let Some(b) = self.d.pos_limit.filter(|_| !fpos && old.positive_limit != new.positive_limit) {
            let at = if new.positive_limit { b } else { b - h };
            self.edge(EventKind::PositiveLimit, new.positive_limit, th0, th1, at);
        }
        if let Some((lo, hi)) = self.d.home.filter(|_| !fhome) {
            // Each boundary on its own, so passing the whole switch inside
            // one step still yields both edges.
            if (th0 < lo) != (th1 < lo) {
                self.edge(EventKind::Home, up, th0, th1, lo);
            }
            if (th0 > hi) != (th1 > hi) {
                self.edge(EventKind::Home, !up, th0, th1, hi);
            }
        }
        self.natural = new;
        if !self.encoder_failed {
            self.index_edges(th0, th1);
        }
    }

    /// Index pulses at `φ + 2πk` in the half-open segment (θ₀, θ₁].
    fn index_edges(&mut self, th0: f64, th1: f64) {
        let phi = self.p.encoder.index_angle;
        let rev = 2.0 * PI;
        let k0 = libm::floor((th0 - phi) / rev);
        let k1 = libm::floor((th1 - phi) / rev);
        // Moving up: k0+1 ..= k1. Moving down the pulse at exactly θ₀ was
        // already reported, so k1+1 ..= k0 minus the one at θ₀ if on it.
        let (first, last, step) = if th1 > th0 {
            (k0 + 1.0, k1, 1.0)
        } else {
            let on_start = phi + k0 * rev == th0;
            let hi = if on_start { k0 - 1.0 } else { k0 };
            let lo = libm::ceil((th1 - phi) / rev);
            (hi, lo, -1.0)
        };
        let count = (last - first) * step + 1.0;
        if count < 1.0 {
            return;
        }
        let mut k = first;
        let mut stored = 0u32;
        while stored < super::MAX_EVENTS as u32 && (k - last) * step <= 0.0 {
            let x = phi + k * rev;
            self.edge(EventKind::Index, true, th0, th1, x);
            stored += 1;
            k += step;
        }
        let rest = count - f64::from(stored);
        if rest >= 1.0 {
            self.events.add_index_crossings(rest.min(f64::from(u32::MAX)) as u32);
        }
    }
}
