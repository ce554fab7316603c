//! 3080h Sync Guard (§6.4.12): counts the received SYNCs, measures every
//! period against the expected one and raises EMCY 82B2h "SYNC period
//! breach" once its out-of-sync counter passes the threshold.

use drivebus_can::Instant;

/// The 3080h:01 bits (§6.4.12).
pub mod option {
    /// Monitoring enabled (0 → 1 clears the counters).
    pub const ENABLE: u8 = 1 << 0;
    /// EMCY on a breach.
    pub const EMERGENCY: u8 = 1 << 1;
    /// Reset the out-of-sync counter (on the write).
    pub const RESET_OUT_OF_SYNC: u8 = 1 << 5;
    /// Reset the peak (on the write).
    pub const RESET_PEAK: u8 = 1 << 6;
    /// Reset the SYNC counter (on the write).
    pub const RESET_COUNTER: u8 = 1 << 7;
}

/// The sync guard's settings (3080h:04–06) and counters (03h, 07h, 08h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SyncGuard {
    /// 3080h:01 as last written.
    pub options: u8,
    /// 3080h:04 Sync_Expected_Period_SYGD \[µs\].
    pub expected_us: u32,
    /// 3080h:05 Sync_Max_Jitter_SYGD \[µs\].
    pub jitter_us: u16,
    /// 3080h:06 Out_Of_Sync_Threshold_SYGD.
    pub threshold: u8,
    /// 3080h:03 Sync_Counter_SYGD.
    pub count: u32,
    /// 3080h:07 Peak_Out_Of_Sync_SYGD.
    pub peak: u8,
    /// 3080h:08 Out_Of_Sync_Counter_SYGD.
    pub out_of_sync: u8,
    last: Option<Instant>,
}

/// Why a 3080h write is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// 04h–06h "Changeable only with monitoring disabled".
    MonitoringEnabled,
    /// Enabling with a jitter over 50 % of the period ("the activation of
    /// the monitoring will generate an error").
    JitterTooLarge,
}

impl SyncGuard {
    /// Whether monitoring is on.
    pub fn enabled(&self) -> bool {
        self.options & option::ENABLE != 0
    }

    /// Checks a write of sub `sub` with `value` before it is stored.
    pub fn check(&self, sub: u8, value: u32) -> Result<(), Refusal> {
        match sub {
            4..=6 if self.enabled() => Err(Refusal::MonitoringEnabled),
            1 if value as u8 & option::ENABLE != 0
                && !self.enabled()
                && u64::from(self.jitter_us) * 2 > u64::from(self.expected_us) =>
            {
                Err(Refusal::JitterTooLarge)
            }
            _ => Ok(()),
        }
    }

    /// Takes a stored write of 3080h:01.
    pub fn write_options(&mut self, value: u8) {
        if value & option::ENABLE != 0 && !self.enabled() {
            self.out_of_sync = 0;
            self.peak = 0;
            self.count = 0;
            self.last = None;
        }
        if value & option::RESET_OUT_OF_SYNC != 0 {
            self.out_of_sync = 0;
        }
        if value & option::RESET_PEAK != 0 {
            self.peak = 0;
        }
        if value & option::RESET_COUNTER != 0 {
            self.count = 0;
        }
        if value & option::ENABLE == 0 {
            self.last = None;
        }
        self.options = value;
    }

    /// A SYNC received at `now`: the counters move; `true` when the
    /// out-of-sync counter just passed the threshold with the emergency
    /// enabled (raise 82B2h).
    pub fn on_sync(&mut self, now: Instant) -> bool {
        self.count = self.count.wrapping_add(1);
        if !self.enabled() {
            return false;
        }
        let Some(last) = self.last.replace(now) else { return false };
        let period_us = (now.saturating_duration_since(last).as_nanos() / 1000) as u64;
        let deviation = period_us.abs_diff(u64::from(self.expected_us));
        let before = self.out_of_sync;
        self.out_of_sync = if deviation > u64::from(self.jitter_us) {
            self.out_of_sync.saturating_add(10)
        } else {
            self.out_of_sync.saturating_sub(1)
        };
        self.peak = self.peak.max(self.out_of_sync);
        self.options & option::EMERGENCY != 0 && before <= self.threshold && self.out_of_sync > self.threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_can::Duration;

    fn guard() -> SyncGuard {
        let mut g = SyncGuard { expected_us: 10_000, jitter_us: 1000, threshold: 15, ..SyncGuard::default() };
        g.write_options(option::ENABLE | option::EMERGENCY);
        g
    }

    #[test]
    fn late_syncs_count_ten_good_ones_one() {
        let mut g = guard();
        let mut t = Instant::ZERO;
        assert!(!g.on_sync(t));
        t += Duration::from_millis(10);
        assert!(!g.on_sync(t));
        assert_eq!(g.out_of_sync, 0);
        t += Duration::from_millis(20);
        assert!(!g.on_sync(t), "10 is not beyond 15");
        assert_eq!(g.out_of_sync, 10);
        t += Duration::from_millis(10);
        assert!(!g.on_sync(t));
        assert_eq!(g.out_of_sync, 9);
        t += Duration::from_millis(20);
        assert!(g.on_sync(t), "19 passes 15");
        t += Duration::from_millis(20);
        assert!(!g.on_sync(t), "reported once");
        assert_eq!((g.out_of_sync, g.peak, g.count), (29, 29, 6));
        g.write_options(option::ENABLE | option::RESET_OUT_OF_SYNC | option::RESET_COUNTER);
        assert_eq!((g.out_of_sync, g.peak, g.count), (0, 29, 0));
    }

    #[test]
    fn settings_only_while_disabled() {
        let g = guard();
        assert_eq!(g.check(4, 2000), Err(Refusal::MonitoringEnabled));
        let mut off = SyncGuard { expected_us: 1000, jitter_us: 600, ..SyncGuard::default() };
        assert_eq!(off.check(1, 1), Err(Refusal::JitterTooLarge));
        off.jitter_us = 500;
        assert_eq!(off.check(1, 1), Ok(()));
        assert_eq!(off.check(5, 100), Ok(()));
    }
}
