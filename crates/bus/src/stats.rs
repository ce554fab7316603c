//! Bus statistics: frame and bit counts, busy time, load.

use alloc::collections::{BTreeMap, VecDeque};
use core::time::Duration;
use drivebus_can::{CanId, Instant};

/// Counters since the bus was created (or last [`Bus::reset_stats`](crate::Bus::reset_stats)).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BusStats {
    /// Frames transmitted to completion (dropped, delayed and duplicated
    /// transmissions included; destroyed ones are counted in `error_frames`).
    pub frames: u64,
    /// Bits on the wire: frames, error frames, intermissions.
    pub bits: u64,
    /// Time the bus was not idle (zero without a bitrate).
    pub busy: Duration,
    /// Transmissions destroyed by an error frame.
    pub error_frames: u64,
    /// Transmissions no receiver got ([`FaultAction::Drop`](crate::FaultAction::Drop)).
    pub dropped: u64,
    /// Transmissions delivered with silently altered data.
    pub corrupted: u64,
    /// Transmissions whose delivery was delayed.
    pub delayed: u64,
    /// Extra transmissions caused by [`FaultAction::Duplicate`](crate::FaultAction::Duplicate).
    pub duplicated: u64,
    /// Times a station went bus-off.
    pub bus_off: u64,
    /// Frames queued by stations that were bus-off or disconnected.
    pub discarded: u64,
    /// Completed transmissions per identifier.
    pub per_id: BTreeMap<CanId, u64>,
}

/// Busy spans inside a sliding window, to compute recent bus load.
#[derive(Clone, Debug)]
pub(crate) struct LoadWindow {
    pub(crate) window: u64,
    spans: VecDeque<(u64, u64)>,
}

impl LoadWindow {
    pub(crate) fn new(window: Duration) -> Self {
        let window = u64::try_from(window.as_nanos()).unwrap_or(u64::MAX).max(1);
        LoadWindow { window, spans: VecDeque::new() }
    }

    pub(crate) fn clear(&mut self) {
        self.spans.clear();
    }

    pub(crate) fn record(&mut self, start: Instant, end: Instant) {
        if end > start {
            self.spans.push_back((start.as_nanos(), end.as_nanos()));
            self.prune(end);
        }
    }

    fn prune(&mut self, now: Instant) {
        let from = now.as_nanos().saturating_sub(self.window);
        while self.spans.front().is_some_and(|&(_, e)| e <= from) {
            self.spans.pop_front();
        }
    }

    /// Fraction of `[now - window, now]` (clipped at `origin`) the bus was busy.
    pub(crate) fn load(&mut self, now: Instant, origin: Instant) -> f64 {
        self.prune(now);
        let to = now.as_nanos();
        let from = to.saturating_sub(self.window).max(origin.as_nanos());
        if to <= from {
            return 0.0;
        }
        let busy: u64 = self.spans.iter().map(|&(s, e)| e.min(to).saturating_sub(s.max(from))).sum();
        busy as f64 / (to - from) as f64
    }
}
