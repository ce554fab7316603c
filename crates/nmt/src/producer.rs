//! Heartbeat producer (CiA 301 §7.2.8.3.2.2, object 1017h).

use drivebus_can::{Duration, Frame, Instant, TxSink};

/// Sends `700h + node-ID, [state]` every 1017h milliseconds (a device's
/// [`Nmt`](crate::Nmt), and a master or tool that produces a heartbeat).
///
/// Timing decisions (CiA 301 leaves them open):
/// - the first heartbeat goes one period after the boot-up message, and one
///   period after 1017h is written (a write restarts the timer);
/// - periods are counted from the previous deadline, not from when `poll`
///   ran, so a late poll does not drift the schedule; if a whole period was
///   missed, one heartbeat is sent and the schedule restarts from `now`
///   (no burst of stale heartbeats);
/// - a state change does not send an extra heartbeat: the next periodic one
///   carries the new state.
#[derive(Clone, Debug, Default)]
pub struct HeartbeatProducer {
    period_ms: u16,
    next: Option<Instant>,
}

impl HeartbeatProducer {
    /// The configured period (0 = off).
    pub fn period_ms(&self) -> u16 {
        self.period_ms
    }

    /// Take a new 1017h value; if `running`, restart the timer at `now`.
    pub fn set_period(&mut self, ms: u16, now: Instant, running: bool) {
        self.period_ms = ms;
        self.next = if running && ms != 0 { Some(now + Duration::from_millis(ms.into())) } else { None };
    }

    /// The next heartbeat's time, when running.
    pub fn next(&self) -> Option<Instant> {
        self.next
    }

    /// Start after the boot-up message sent at `now`.
    pub fn start(&mut self, now: Instant) {
        self.set_period(self.period_ms, now, true);
    }

    /// Stop (entering Initialisation).
    pub fn stop(&mut self) {
        self.next = None;
    }

    /// Send the heartbeat if due; returns the next deadline.
    pub fn poll(&mut self, now: Instant, id: u16, state: u8, out: &mut impl TxSink) -> Option<Instant> {
        let due = self.next?;
        if now < due {
            return Some(due);
        }
        out.send(Frame::new(id, &[state]));
        let period = Duration::from_millis(self.period_ms.into());
        let mut next = due + period;
        if next <= now {
            next = now + period;
        }
        self.next = Some(next);
        self.next
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn late_poll_does_not_burst() {
        let mut p = HeartbeatProducer::default();
        let mut out = Vec::new();
        p.set_period(10, Instant::ZERO, true);
        assert_eq!(p.poll(Instant::from_millis(9), 0x701, 5, &mut out), Some(Instant::from_millis(10)));
        assert!(out.is_empty());
        assert_eq!(p.poll(Instant::from_millis(12), 0x701, 5, &mut out), Some(Instant::from_millis(20)));
        assert_eq!(p.poll(Instant::from_millis(55), 0x701, 5, &mut out), Some(Instant::from_millis(65)));
        assert_eq!(out.len(), 2);
        p.set_period(0, Instant::from_millis(60), true);
        assert_eq!(p.poll(Instant::from_millis(100), 0x701, 5, &mut out), None);
    }
}
