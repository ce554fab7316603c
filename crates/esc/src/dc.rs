//! Distributed clocks (ESC data sheet Section I "Distributed Clocks",
//! Section II 0x0900–0x09FF).
//!
//! **Local clock.** Each ESC has a free-running local clock derived from
//! the caller's `now`: `local = offset + now·(1 + drift)` (drift in ppb),
//! plus the corrections of the time control loop. Receive times (0x0900,
//! 0x0918) are local times; the system time 0x0910 is `local + 0x0920`.
//!
//! **Time control loop** (simplified; the real ESC adds or drops single
//! clock ticks at a rate set by 0x0930). Every ECAT write to 0x0910 (FRMW/
//! ARMW from the reference clock, or a plain write) is a sample
//! `e = received + delay(0x0928) − own system time`, 32-bit if only
//! 0x0910–0x0913 were written. The loop is a PI controller:
//!
//! * phase: half of `e` is slewed in over the expected interval to the
//!   next sample (at most [`MAX_SLEW_PPB`]), then stops;
//! * frequency: `e / 8` per sample interval is added to a frequency
//!   correction (at most ±[`MAX_FREQ_PPB`]), which learns the drift.
//!
//! With these gains the error decays by about 0.7 per sample (poles
//! 0.69 ± 0.11i), so a few dozen FRMW samples bring a line of slaves to
//! within a few nanoseconds of the reference, and the loop keeps tracking
//! a drift of up to the frequency limit with no steady-state error. Time
//! never steps: the local clock stays monotonic. A write to 0x0930 (speed
//! counter start) or to a filter depth resets the loop, as on the ESC;
//! masters do this after clearing 0x0910 during their reset. 0x092C holds
//! the filtered difference (depth 0x0934) in sign/magnitude form, bit 31
//! set when the local copy is smaller than the received time; 0x0932 holds
//! the frequency correction in units of 0.1 ppm.
//!
//! **SYNC unit.** Activating cyclic operation (0x0981 bit 0) with SYNC0
//! (bit 1) schedules pulses at `start time (0x0990) + k·cycle (0x09A0)`;
//! cycle 0 is single-shot. A start time already in the past is met when the
//! lower 32 bits of the system time next equal it (the ESC compares 32 bits,
//! so the first pulse comes up to 4.3 s later), unless the plausibility
//! check (bit 5) is on, which fires the first pulse at once. Bit 3 activates
//! on writing the start time. SYNC1 (bit 2) follows each SYNC0 by the SYNC1
//! cycle time when that is shorter than the SYNC0 cycle; otherwise it comes
//! with every n-th SYNC0 (n = SYNC1 cycle / SYNC0 cycle) shifted by the
//! remainder. Each pulse sets 0x098E/0x098F (cleared when read).

use drivebus_base::Instant;

const PPB: i128 = 1_000_000_000;

/// `n / d` for `d > 0`, rounding toward zero: in 64 bits when both fit,
/// which is every call of a running line (deadlines a few ms ahead); a
/// 128-bit division is a library call ten times slower, and these run on
/// every poll of every slave (`Esc::next_deadline`).
#[inline]
fn div(n: i128, d: i128) -> i128 {
    match (i64::try_from(n), i64::try_from(d)) {
        (Ok(n), Ok(d)) if d > 0 => i128::from(n / d),
        _ => n / d,
    }
}

/// Largest frequency correction the loop applies (500 ppm).
pub const MAX_FREQ_PPB: i64 = 500_000;
/// Largest phase slew rate (1000 ppm).
pub const MAX_SLEW_PPB: i64 = 1_000_000;
/// Shortest sample interval the loop assumes (several writes in one frame).
const MIN_INTERVAL_NS: u64 = 10_000;
/// Longest sample interval the loop assumes.
const MAX_INTERVAL_NS: u64 = 100_000_000;

/// How an ESC's local clock relates to the caller's clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ClockConfig {
    /// Local time at the caller's `Instant::ZERO`, in ns.
    pub offset_ns: u64,
    /// Frequency error of the local oscillator in parts per billion
    /// (positive: runs fast).
    pub drift_ppb: i32,
}

/// The local clock with its control-loop corrections.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LocalClock {
    anchor_t: u64,
    anchor_local: u64,
    drift: i64,
    freq: i64,
    pending: i64,
    slew: i64,
}

impl LocalClock {
    pub fn new(cfg: ClockConfig) -> Self {
        LocalClock {
            anchor_t: 0,
            anchor_local: cfg.offset_ns,
            // ±10 %: beyond that no oscillator would be called a clock.
            drift: i64::from(cfg.drift_ppb).clamp(-100_000_000, 100_000_000),
            freq: 0,
            pending: 0,
            slew: 0,
        }
    }

    fn rate(&self) -> i128 {
        PPB + i128::from(self.drift) + i128::from(self.freq)
    }

    fn slewed(&self, dt: u64) -> i64 {
        let max = div(i128::from(dt) * i128::from(self.slew), PPB).min(i128::from(i64::MAX)) as i64;
        self.pending.signum() * self.pending.saturating_abs().min(max)
    }

    /// Local time at caller time `t` (t before the last anchor is clamped).
    pub fn local(&self, t: Instant) -> u64 {
        let dt = t.as_nanos().saturating_sub(self.anchor_t);
        let base = div(i128::from(dt) * self.rate(), PPB) as i64;
        self.anchor_local.wrapping_add(base.wrapping_add(self.slewed(dt)) as u64)
    }

    /// Changes the oscillator's frequency error from `t` on (a drifting
    /// clock as a fault); the local time stays continuous.
    pub fn set_drift(&mut self, t: Instant, drift_ppb: i32) {
        self.reanchor(t);
        self.drift = i64::from(drift_ppb).clamp(-100_000_000, 100_000_000);
    }

    /// Moves the anchor to `t`, consuming the slew done so far.
    fn reanchor(&mut self, t: Instant) {
        let dt = t.as_nanos().saturating_sub(self.anchor_t);
        let done = self.slewed(dt);
        self.anchor_local = self.local(t);
        self.pending -= done;
        self.anchor_t = self.anchor_t.max(t.as_nanos());
    }

    /// Earliest caller instant at or after the anchor when the local time
    /// reaches `target` (wrapping distance, so `target` must be ahead).
    pub fn instant_of(&self, target: u64) -> Instant {
        let delta = i128::from(target.wrapping_sub(self.anchor_local) as i64);
        if delta <= 0 {
            return Instant::from_nanos(self.anchor_t);
        }
        let rate = self.rate();
        let sign = i128::from(self.pending.signum());
        let slope1 = rate + sign * i128::from(self.slew);
        let t_end = if self.slew > 0 {
            div(i128::from(self.pending.unsigned_abs()) * PPB, i128::from(self.slew))
        } else {
            0
        };
        let gain1 = div(t_end * slope1, PPB);
        let dt = if delta <= gain1 && slope1 > 0 {
            div(delta * PPB + slope1 - 1, slope1)
        } else {
            t_end + div((delta - gain1) * PPB + rate - 1, rate)
        };
        let mut t = self.anchor_t.saturating_add(dt.clamp(0, i128::from(u64::MAX / 2)) as u64);
        // Integer rounding: step forward until the local time has arrived.
        for _ in 0..4 {
            if self.local(Instant::from_nanos(t)).wrapping_sub(target) as i64 >= 0 {
                break;
            }
            t += 1;
        }
        Instant::from_nanos(t)
    }

    /// One control-loop sample: `e` ns error (positive: behind), `interval`
    /// ns since the previous sample.
    pub fn sample(&mut self, t: Instant, e: i64, interval: u64) {
        self.reanchor(t);
        let interval = interval.clamp(MIN_INTERVAL_NS, MAX_INTERVAL_NS);
        let df = (i128::from(e) * PPB / 8 / i128::from(interval))
            .clamp(-2 * i128::from(MAX_FREQ_PPB), 2 * i128::from(MAX_FREQ_PPB)) as i64;
        self.freq = (self.freq + df).clamp(-MAX_FREQ_PPB, MAX_FREQ_PPB);
        self.pending = e / 2;
        let wanted = (i128::from(self.pending.unsigned_abs()) * PPB / i128::from(interval))
            .min(i128::from(MAX_SLEW_PPB));
        self.slew = (wanted as i64).max(1);
    }

    /// Forgets the loop state (0x0930 write).
    pub fn reset_loop(&mut self, t: Instant) {
        self.reanchor(t);
        self.freq = 0;
        self.pending = 0;
        self.slew = 0;
    }

    /// Frequency correction in ppb (for 0x0932 and tests).
    pub fn correction_ppb(&self) -> i64 {
        self.freq
    }
}

/// State of the SYNC signal unit.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SyncUnit {
    pub active: bool,
    pub sync0_next: Option<u64>,
    pub sync1_next: Option<u64>,
    pub sync0_pulses: u64,
    pub cycle0: u32,
    pub cycle1: u32,
    pub sync0_on: bool,
    pub sync1_on: bool,
}

/// A pulse that became due.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Pulse {
    pub system_time: u64,
    pub missed: u32,
}

impl SyncUnit {
    /// Starts cyclic operation at system time `now_sys`.
    pub fn activate(&mut self, activation: u8, start: u64, cycle0: u32, cycle1: u32, now_sys: u64) {
        let first = if start.wrapping_sub(now_sys) as i64 > 0 {
            start
        } else if activation & 0x20 != 0 {
            now_sys
        } else {
            // Lower 32 bits compared: wait for the next match.
            let d = (start as u32).wrapping_sub(now_sys as u32);
            now_sys.wrapping_add(if d == 0 { 1 << 32 } else { u64::from(d) })
        };
        *self = SyncUnit {
            active: true,
            sync0_next: Some(first),
            sync1_next: None,
            sync0_pulses: 0,
            cycle0,
            cycle1,
            sync0_on: activation & 0x02 != 0,
            sync1_on: activation & 0x04 != 0,
        };
        self.schedule_sync1(first, 0);
    }

    /// Stops cyclic operation.
    pub fn deactivate(&mut self) {
        *self = SyncUnit::default();
    }

    fn schedule_sync1(&mut self, sync0: u64, pulse_index: u64) {
        if !self.sync1_on {
            self.sync1_next = None;
            return;
        }
        let (c0, c1) = (u64::from(self.cycle0), u64::from(self.cycle1));
        if c0 == 0 || c1 < c0 {
            self.sync1_next = Some(sync0.wrapping_add(c1));
        } else {
            let n = c1 / c0;
            if pulse_index.is_multiple_of(n) {
                self.sync1_next = Some(sync0.wrapping_add(c1 % c0));
            }
        }
    }

    /// The SYNC0 pulse due at or before `now_sys`, if any; advances the
    /// schedule (several overdue pulses are reported once, as `missed`).
    pub fn take_sync0(&mut self, now_sys: u64) -> Option<Pulse> {
        let next = self.sync0_next?;
        if (now_sys.wrapping_sub(next) as i64) < 0 {
            return None;
        }
        let c = u64::from(self.cycle0);
        let (due, missed) = match now_sys.wrapping_sub(next).checked_div(c) {
            None => {
                self.sync0_next = None; // single shot
                (next, 0)
            }
            Some(k) => {
                let due = next.wrapping_add(k * c);
                self.sync0_next = Some(due.wrapping_add(c));
                (due, k.min(u64::from(u32::MAX)) as u32)
            }
        };
        let idx = self.sync0_pulses + u64::from(missed);
        self.sync0_pulses = idx + 1;
        if self.sync1_next.is_none() || self.cycle1 < self.cycle0 {
            self.schedule_sync1(due, idx);
        }
        self.sync0_on.then_some(Pulse { system_time: due, missed })
    }

    /// The SYNC1 pulse due at or before `now_sys`, if any.
    pub fn take_sync1(&mut self, now_sys: u64) -> Option<Pulse> {
        let next = self.sync1_next?;
        if (now_sys.wrapping_sub(next) as i64) < 0 {
            return None;
        }
        self.sync1_next = None;
        Some(Pulse { system_time: next, missed: 0 })
    }

    /// Earliest pending pulse time.
    pub fn next_due(&self) -> Option<u64> {
        let a = self.sync0_next.filter(|_| self.sync0_on || self.sync1_on);
        match (a, self.sync1_next) {
            (Some(x), Some(y)) => Some(if (y.wrapping_sub(x) as i64) < 0 { y } else { x }),
            (x, None) => x,
            (None, y) => y,
        }
    }
}

/// Sign/magnitude encoding of 0x092C.
pub(crate) fn diff_register(mean: i64) -> u32 {
    let mag = mean.unsigned_abs().min(0x7FFF_FFFF) as u32;
    if mean > 0 { mag | 0x8000_0000 } else { mag }
}

#[cfg(test)]
mod tests {
    #[test]
    fn division_fast_path_equals_the_128_bit_one() {
        use proptest::prelude::*;
        proptest!(|(n in any::<i64>(), d in 1..=i64::MAX, wide in any::<i128>(), wd in 1..=i128::MAX)| {
            let (n, d) = (i128::from(n), i128::from(d));
            prop_assert_eq!(super::div(n, d), n / d);
            prop_assert_eq!(super::div(wide, wd), wide / wd);
            prop_assert_eq!(super::div(wide, d), wide / d);
            prop_assert_eq!(super::div(n, wd), n / wd);
            prop_assert_eq!(super::div(-n.abs(), d), -n.abs() / d);
        });
    }

    use super::*;

    #[test]
    fn local_clock_runs_with_offset_and_drift() {
        let c = LocalClock::new(ClockConfig { offset_ns: 1_000, drift_ppb: 100_000 });
        assert_eq!(c.local(Instant::ZERO), 1_000);
        // 100 ppm fast: 1 s of caller time is 1.0001 s local.
        assert_eq!(c.local(Instant::from_millis(1000)), 1_000 + 1_000_100_000);
    }

    #[test]
    fn instant_of_inverts_local() {
        let mut c = LocalClock::new(ClockConfig { offset_ns: 5, drift_ppb: -37_000 });
        c.sample(Instant::from_millis(1), 4_000, 1_000_000);
        for target in [10u64, 999_999, 1_000_003, 1_002_500, 77_777_777] {
            let t = c.instant_of(target);
            assert!(c.local(t) >= target, "{target}");
            if t.as_nanos() > 1_000_000 {
                assert!(c.local(Instant::from_nanos(t.as_nanos() - 1)) < target, "{target}: earliest");
            }
        }
    }

    #[test]
    fn loop_learns_drift_and_phase() {
        // Reference runs exactly at caller time; this clock is 80 ppm slow
        // and 3 µs behind.
        let mut c = LocalClock::new(ClockConfig { offset_ns: 0, drift_ppb: -80_000 });
        let mut t = 1_000_000u64;
        c.reanchor(Instant::from_nanos(t));
        c.anchor_local = t - 3_000;
        let mut e = 0;
        for _ in 0..200 {
            t += 1_000_000;
            let now = Instant::from_nanos(t);
            e = t as i64 - c.local(now) as i64;
            c.sample(now, e, 1_000_000);
        }
        assert!(e.abs() <= 2, "residual {e} ns");
        assert!((c.correction_ppb() - 80_000).abs() < 500, "learned {} ppb", c.correction_ppb());
    }

    #[test]
    fn local_clock_is_monotonic_under_corrections() {
        let mut c = LocalClock::new(ClockConfig { offset_ns: 0, drift_ppb: 0 });
        let mut last = 0;
        for k in 1..2000u64 {
            let t = Instant::from_nanos(k * 10_000);
            if k % 7 == 0 {
                c.sample(t, if k % 2 == 0 { -1_000_000 } else { 1_000_000 }, 10_000);
            }
            let l = c.local(t);
            assert!(l >= last);
            last = l;
        }
    }

    #[test]
    fn sync_unit_schedules_pulses() {
        let mut s = SyncUnit::default();
        s.activate(0x03, 10_000, 1_000, 0, 5_000);
        assert_eq!(s.next_due(), Some(10_000));
        assert_eq!(s.take_sync0(9_999), None);
        assert_eq!(s.take_sync0(10_000), Some(Pulse { system_time: 10_000, missed: 0 }));
        assert_eq!(s.take_sync0(13_500), Some(Pulse { system_time: 13_000, missed: 2 }));
        assert_eq!(s.next_due(), Some(14_000));
    }

    #[test]
    fn start_time_in_the_past_waits_for_32_bit_match_unless_plausibility_check() {
        let mut s = SyncUnit::default();
        s.activate(0x03, 1_000, 1_000, 0, 2_000);
        assert_eq!(s.next_due(), Some(1_000 + (1 << 32)));
        s.activate(0x23, 1_000, 1_000, 0, 2_000);
        assert_eq!(s.next_due(), Some(2_000));
    }

    #[test]
    fn sync1_shift_and_multiple() {
        let mut s = SyncUnit::default();
        s.activate(0x07, 1_000, 1_000, 300, 0);
        assert_eq!(s.take_sync0(1_000).map(|p| p.system_time), Some(1_000));
        assert_eq!(s.next_due(), Some(1_300));
        assert_eq!(s.take_sync1(1_300).map(|p| p.system_time), Some(1_300));
        // SYNC1 cycle = 2 × SYNC0 cycle: every second SYNC0.
        s.activate(0x07, 1_000, 1_000, 2_000, 0);
        assert_eq!(s.sync1_next, Some(1_000));
        s.take_sync0(1_000);
        s.take_sync1(1_000);
        s.take_sync0(2_000);
        assert_eq!(s.sync1_next, None);
        s.take_sync0(3_000);
        assert_eq!(s.sync1_next, Some(3_000));
    }

    #[test]
    fn diff_register_sign() {
        assert_eq!(diff_register(5), 0x8000_0005);
        assert_eq!(diff_register(-5), 5);
        assert_eq!(diff_register(i64::MIN), 0x7FFF_FFFF);
    }
}
