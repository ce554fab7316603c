//! The time source of a host: the machine's monotonic clock, or simulated
//! time that only moves when the host (or a test) moves it.

use drivebus_can::{Duration, Instant};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::SystemTime;

/// 2025-01-01T00:00:00Z: the wall-clock origin of simulated time, so that
/// captures of simulated runs are reproducible.
const SIM_EPOCH_UNIX_NS: u64 = 1_735_689_600_000_000_000;

#[derive(Debug)]
enum Source {
    Real { base: std::time::Instant, unix_base_ns: u64 },
    Simulated { ns: AtomicU64 },
}

/// A shared clock handle (cheap to clone).
///
/// Not `drivebus_transport::clock::TokioClock`: the EtherCAT host runs on
/// plain threads without tokio, its time can be simulated (moved only by
/// the host or a test, shared by every handle) and it carries a wall-clock
/// origin for pcapng timestamps.
#[derive(Debug, Clone)]
pub struct Clock(Arc<Source>);

impl Clock {
    /// The machine's monotonic clock; `Instant::ZERO` is now.
    pub fn real() -> Clock {
        let unix_base_ns = SystemTime::now()
            .duration_since(SystemTime::UNIX_EPOCH)
            .map(|d| d.as_nanos() as u64)
            .unwrap_or(0);
        Clock(Arc::new(Source::Real { base: std::time::Instant::now(), unix_base_ns }))
    }

    /// Simulated time starting at `start`.
    pub fn simulated(start: Instant) -> Clock {
        Clock(Arc::new(Source::Simulated { ns: AtomicU64::new(start.as_nanos()) }))
    }

    /// True for simulated time.
    pub fn is_simulated(&self) -> bool {
        matches!(*self.0, Source::Simulated { .. })
    }

    /// Now.
    pub fn now(&self) -> Instant {
        match &*self.0 {
            Source::Real { base, .. } => Instant::from_nanos(base.elapsed().as_nanos() as u64),
            Source::Simulated { ns } => Instant::from_nanos(ns.load(Ordering::Acquire)),
        }
    }

    /// Simulated time: moves forward to `t` (never back). Real time: no-op.
    pub fn advance_to(&self, t: Instant) {
        if let Source::Simulated { ns } = &*self.0 {
            ns.fetch_max(t.as_nanos(), Ordering::AcqRel);
        }
    }

    /// Simulated time: moves forward by `d`.
    pub fn advance(&self, d: Duration) {
        self.advance_to(self.now() + d);
    }

    /// The `std` instant of `t` (real time only).
    pub fn to_std(&self, t: Instant) -> Option<std::time::Instant> {
        match &*self.0 {
            Source::Real { base, .. } => Some(*base + Duration::from_nanos(t.as_nanos())),
            Source::Simulated { .. } => None,
        }
    }

    /// Nanoseconds for ethercrab's `now` callbacks (DC offsets): the clock
    /// itself, so master and slaves agree on one time base.
    pub fn ethercat_ns(&self) -> u64 {
        self.now().as_nanos()
    }

    /// Unix time of `t` in ns (for capture timestamps).
    pub fn unix_ns(&self, t: Instant) -> u64 {
        match &*self.0 {
            Source::Real { unix_base_ns, .. } => unix_base_ns + t.as_nanos(),
            Source::Simulated { .. } => SIM_EPOCH_UNIX_NS + t.as_nanos(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simulated_time_moves_only_forward_and_on_request() {
        let c = Clock::simulated(Instant::from_micros(5));
        assert!(c.is_simulated());
        c.advance_to(Instant::from_micros(3));
        assert_eq!(c.now(), Instant::from_micros(5));
        c.advance(Duration::from_micros(10));
        assert_eq!(c.now(), Instant::from_micros(15));
        assert_eq!(c.to_std(c.now()), None);
        assert_eq!(c.unix_ns(Instant::ZERO), SIM_EPOCH_UNIX_NS);
    }

    #[test]
    fn real_time_is_monotonic() {
        let c = Clock::real();
        let a = c.now();
        let b = c.now();
        assert!(b >= a);
        assert!(c.to_std(a).is_some());
    }
}
