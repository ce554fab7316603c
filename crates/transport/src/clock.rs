//! The sans-IO machines' `now` on tokio's clock: one clock for every tokio
//! task that drives a sans-IO machine (the real-time host of a CAN
//! `Device` and the master's tokio driver).

use drivebus_can::Instant;
use std::time::Duration;

/// Nanoseconds since a fixed tokio instant; monotonic (tokio's clock is),
/// and paused or advanced with tokio's test time.
#[derive(Clone, Copy, Debug)]
pub struct TokioClock {
    start: tokio::time::Instant,
}

impl TokioClock {
    /// A clock whose `Instant::ZERO` is now.
    pub fn start() -> TokioClock {
        TokioClock { start: tokio::time::Instant::now() }
    }

    /// The current time on the sans-IO time axis.
    pub fn now(&self) -> Instant {
        Instant::from_nanos(u64::try_from(self.start.elapsed().as_nanos()).unwrap_or(u64::MAX))
    }

    /// The tokio instant of a sans-IO deadline. Far-future deadlines (up to
    /// `Instant::MAX`) are capped at a year so the addition cannot overflow.
    pub fn at(&self, t: Instant) -> tokio::time::Instant {
        self.start + Duration::from_nanos(t.as_nanos()).min(Duration::from_secs(365 * 86_400))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_deadlines_and_caps_far_ones() {
        let c = TokioClock::start();
        let (a, b) = (c.now(), c.now());
        assert!(a <= b, "monotonic");
        assert_eq!(c.at(Instant::from_nanos(7_000_000)), c.start + Duration::from_millis(7));
        assert_eq!(c.at(Instant::MAX), c.start + Duration::from_secs(365 * 86_400));
    }
}
