//! Timing supervision of the Kollmorgen drives: the interpolation period
//! 60C2h ("only multiples of 1 ms", "both values must be written", KC1
//! §7.9.2.3, AKD §6.9.2.3) and the fieldbus PLL (FBUS.PARAM02 36E6h, KC1
//! §5.4 / AKD §3.4; parameters 3496h, KC1 §7.2.2.18 / AKD §6.2.2.22;
//! FBUS.PLLTHRESH 50B1h).

use drivebus_can::Instant;
use drivebus_od::{EntryRef, ObjectDictionary, SdoAbort};

/// The 16 kHz interrupt of §7.2.2.18 (62.5 µs) the PLL stretches or
/// shortens by FBUS.COMPTIME per tick.
const TICK_NS: u64 = 62_500;

/// 60C2h: the sub written since the last complete pair, and its value.
#[derive(Debug, Clone, Default)]
pub struct PeriodPair {
    held: Option<(u8, u8)>,
}

/// Whether `units` × 10^`index` s is a positive whole number of ms.
pub fn whole_ms(units: u8, index: i8) -> bool {
    match index {
        _ if units == 0 => false,
        i if i < -3 => {
            10u32.checked_pow(u32::from((-3 - i).unsigned_abs())).is_some_and(|d| u32::from(units) % d == 0)
        }
        _ => true,
    }
}

/// What to do with a 60C2h write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeriodWrite {
    /// The first of a pair: store it, the drive keeps its period.
    Hold,
    /// The pair is complete: forward the held sub (sub, value), then pass.
    Complete(u8, u8),
}

impl PeriodPair {
    /// A write of 60C2h:`sub` (1 or 2) with `value`.
    pub fn write(&mut self, sub: u8, value: u8) -> Result<PeriodWrite, SdoAbort> {
        match self.held.take() {
            Some((other, held)) if other != sub => {
                let (units, index) = if sub == 1 { (value, held as i8) } else { (held, value as i8) };
                if !whole_ms(units, index) {
                    return Err(SdoAbort::INVALID_VALUE);
                }
                Ok(PeriodWrite::Complete(other, held))
            }
            _ => {
                self.held = Some((sub, value));
                Ok(PeriodWrite::Hold)
            }
        }
    }

    /// After a reset: no half-written pair.
    pub fn reset(&mut self) {
        self.held = None;
    }
}

/// Handles of the PLL parameters.
#[derive(Debug, Clone, Default)]
struct Refs {
    objects: usize,
    enable: Option<EntryRef>,
    dist: Option<EntryRef>,
    act: Option<EntryRef>,
    window: Option<EntryRef>,
    comp: Option<EntryRef>,
    thresh: Option<EntryRef>,
}

/// The PLL of §7.2.2.18: once per fieldbus cycle (60C2h) the drive's PLL
/// function measures the time since the last SYNC (FBUS.SYNCACT, 3496h:2)
/// and moves its next call by FBUS.COMPTIME per 62.5 µs tick towards
/// FBUS.SYNCDIST (3496h:1). Locked after FBUS.PLLTHRESH (50B1h, at
/// least one) calls inside ± FBUS.SYNCWND (3496h:3); a locked PLL leaving
/// the window is warning n125.
#[derive(Debug, Clone, Default)]
pub struct Pll {
    refs: Refs,
    /// A SYNC arrived and waits for its time stamp.
    pub sync_pending: bool,
    last_sync: Option<Instant>,
    next_call: Option<Instant>,
    in_window: u32,
    locked: bool,
    /// The PLL lost the SYNC after it had locked (warning n125).
    pub lost: bool,
}

impl Pll {
    fn resolve(&mut self, od: &ObjectDictionary) {
        let f = |i: u16, s: u8| od.find(i, s).ok();
        self.refs = Refs {
            objects: od.objects().len(),
            enable: f(0x36E6, 0),
            dist: f(0x3496, 1),
            act: f(0x3496, 2),
            window: f(0x3496, 3),
            comp: f(0x3496, 4),
            thresh: f(0x50B1, 0),
        };
    }

    /// Stops the PLL (not enabled, not a synchronized mode, a reset).
    pub fn stop(&mut self) {
        let keep = self.refs.clone();
        *self = Pll { refs: keep, ..Pll::default() };
    }

    /// Runs the PLL calls due up to `now`; `period_ns` is the 60C2h cycle,
    /// `synced_mode` whether ip or csp runs.
    pub fn run(
        &mut self,
        od: &mut ObjectDictionary,
        now: Instant,
        period_ns: Option<u64>,
        synced_mode: bool,
    ) {
        if self.refs.objects != od.objects().len() {
            self.resolve(od);
        }
        let on = self.refs.enable.is_some_and(|r| od.word(r) == 1);
        let Some(period) = period_ns.filter(|&p| on && synced_mode && p >= TICK_NS) else {
            if self.next_call.is_some() || self.lost {
                self.stop();
            }
            self.sync_pending = false;
            return;
        };
        self.calls(od, period, |t| t < now);
        if core::mem::take(&mut self.sync_pending) {
            self.last_sync = Some(now);
            // The drive's cycle runs on its own clock: half a cycle away.
            self.next_call.get_or_insert(now + drivebus_can::Duration::from_nanos(period / 2));
        }
        self.calls(od, period, |t| t <= now);
    }

    fn calls(&mut self, od: &mut ObjectDictionary, period: u64, due: impl Fn(Instant) -> bool) {
        let w = |r: Option<EntryRef>| r.map_or(0, |r| od.word(r));
        let (dist, window, comp) = (w(self.refs.dist), w(self.refs.window), w(self.refs.comp));
        let thresh = w(self.refs.thresh).max(1) as u32;
        let shift = period / TICK_NS * comp;
        while let (Some(t), Some(sync)) = (self.next_call, self.last_sync) {
            if !due(t) {
                break;
            }
            let act = t.saturating_duration_since(sync).as_nanos() as u64;
            if let Some(r) = self.refs.act {
                od.set_raw(r, &(act.min(u64::from(u32::MAX)) as u32).to_le_bytes());
            }
            if act.abs_diff(dist) < window {
                self.in_window = self.in_window.saturating_add(1);
                if self.in_window >= thresh {
                    self.locked = true;
                    self.lost = false;
                }
            } else {
                self.in_window = 0;
                self.lost |= self.locked;
                self.locked = false;
            }
            let next = if act > dist {
                period.saturating_sub(shift)
            } else if act < dist {
                period + shift
            } else {
                period
            };
            self.next_call = Some(t + drivebus_can::Duration::from_nanos(next.max(TICK_NS)));
        }
    }
}
