//! The sans-IO machines' `now`, derived from `tokio::time`.

use drivebus_can::Instant;
use std::time::Duration;

/// Nanoseconds since a fixed tokio instant; monotonic (tokio's clock is).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Clock {
    start: tokio::time::Instant,
}

impl Clock {
    pub(crate) fn new() -> Clock {
        Clock { start: tokio::time::Instant::now() }
    }

    /// The current time on the sans-IO time axis.
    pub(crate) fn now(&self) -> Instant {
        Instant::from_nanos(u64::try_from(self.start.elapsed().as_nanos()).unwrap_or(u64::MAX))
    }

    /// The tokio instant of a sans-IO deadline. Far-future deadlines (up to
    /// `Instant::MAX`) are capped at a year so the addition cannot overflow.
    pub(crate) fn at(&self, t: Instant) -> tokio::time::Instant {
        let d = Duration::from_nanos(t.as_nanos()).min(Duration::from_secs(365 * 86_400));
        self.start + d
    }
}
