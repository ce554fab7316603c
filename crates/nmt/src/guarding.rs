//! Node guarding slave and life guarding (CiA 301 §7.2.8.3.2.1, 100Ch/100Dh).

use crate::events::{EventQueue, NmtEvent};
use drivebus_can::{Duration, Frame, Instant, TxSink};

/// The guarding responder and the life-guarding timer.
///
/// - Each remote request on 700h + node-ID (any DLC) is answered with one
///   byte: bit 7 toggle, bits 0..6 the state code. The toggle is 0 in the
///   first answer after reset communication and alternates with every
///   answer (CiA 301 §7.2.8.3.2.1; SSD 630 §8 "first toggle after power-on
///   is 0").
/// - Life guarding starts with the first request received, and only when
///   guard time × life time factor is non-zero. No request within that life
///   time → "life guarding event occurred"; the next request → "resolved".
///   A loss is reported once; the timer is re-armed only by a request.
#[derive(Clone, Debug, Default)]
pub(crate) struct Guarding {
    toggle: bool,
    guard_ms: u16,
    factor: u8,
    deadline: Option<Instant>,
    lost: bool,
}

impl Guarding {
    /// Back to the reset-communication state: toggle 0, life guarding idle.
    pub(crate) fn reset(&mut self) {
        self.toggle = false;
        self.deadline = None;
        self.lost = false;
    }

    /// Stop life guarding without touching the toggle (heartbeat took over,
    /// or 100Ch × 100Dh became 0). An outstanding loss ends with it: returns
    /// true if one was outstanding, so the caller reports it resolved.
    pub(crate) fn disable(&mut self) -> bool {
        self.deadline = None;
        core::mem::take(&mut self.lost)
    }

    /// Guard time × life time factor, if both non-zero.
    pub(crate) fn life_time(&self) -> Option<Duration> {
        let ms = u64::from(self.guard_ms) * u64::from(self.factor);
        (ms != 0).then(|| Duration::from_millis(ms))
    }

    /// Take new 100Ch/100Dh values. A running timer restarts from `now`
    /// with the new life time; a zero product disables life guarding (see
    /// [`Guarding::disable`] for the return value).
    pub(crate) fn set_times(&mut self, guard_ms: u16, factor: u8, now: Instant) -> bool {
        self.guard_ms = guard_ms;
        self.factor = factor;
        match self.life_time() {
            None => self.disable(),
            Some(lt) => {
                if self.deadline.is_some() {
                    self.deadline = Some(now + lt);
                }
                false
            }
        }
    }

    /// Whether a life-guarding loss is outstanding.
    pub(crate) fn is_lost(&self) -> bool {
        self.lost
    }

    /// Answer a guarding request at `now`; `life` says whether life
    /// guarding is evaluated at all.
    pub(crate) fn on_request(
        &mut self,
        now: Instant,
        id: u16,
        state: u8,
        life: bool,
        out: &mut impl TxSink,
    ) -> Option<NmtEvent> {
        let byte = (u8::from(self.toggle) << 7) | (state & 0x7F);
        out.send(Frame::new(id, &[byte]));
        self.toggle = !self.toggle;
        if !life {
            return None;
        }
        let lt = self.life_time()?;
        self.deadline = Some(now + lt);
        if self.lost {
            self.lost = false;
            return Some(NmtEvent::LifeGuardingResolved);
        }
        None
    }

    /// Report a due loss into `q`; returns the next deadline (`now` if the
    /// queue was full, so the loss is reported on the next poll).
    pub(crate) fn poll(&mut self, now: Instant, q: &mut EventQueue) -> Option<Instant> {
        let due = self.deadline?;
        if now < due {
            return Some(due);
        }
        if q.push(NmtEvent::LifeGuardingLost) {
            self.lost = true;
            self.deadline = None;
            None
        } else {
            Some(now)
        }
    }
}
