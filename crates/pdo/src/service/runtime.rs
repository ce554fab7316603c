//! Frame, SYNC and timer handling (CiA 301 7.2.2.2 transmission modes,
//! 7.2.2.4 RPDO length errors, 7.5.2.35/37 event timer and inhibit time).

use super::{Pdo, Tpdo, lookup};
use crate::events::{PdoEvent, PdoRx};
use crate::mapping::{apply, sample};
use crate::objects::{TT_EVENT_MANUFACTURER, TT_EVENT_PROFILE, TT_EVENT_RTR, TT_SYNC_RTR};
use drivebus_can::{CanId, Frame, Instant, MAX_DATA_LEN, TxSink, earliest};
use drivebus_od::{ObjectDictionary, ObjectHooks};

impl Pdo {
    /// Process a received frame. Data frames on an active RPDO's COB-ID
    /// (11 or 29 bit) are checked against the mapped length: shorter →
    /// [`PdoEvent::RpdoLengthError`], not processed; longer → processed and
    /// [`PdoEvent::RpdoLengthExceeded`]. Event-driven RPDOs (254/255) are
    /// written into the dictionary at once through `write_local` semantics
    /// (limits and hooks; plain objects copied in place); synchronous ones
    /// (0..240) are latched and written at the next [`Pdo::on_sync`].
    /// Remote frames on a TPDO that allows RTR trigger it: 253 sampled and
    /// sent now, 252 sent now with the data sampled at the last SYNC,
    /// 254/255 now (inhibit time permitting), 0..240 at the next SYNC.
    #[inline]
    pub fn handle_frame<H: ObjectHooks + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) -> PdoRx {
        if frame.is_rtr() {
            return self.handle_rtr(frame.id(), now, od, hooks, out);
        }
        let Some(n) = lookup(&self.rx_std, &self.rx_ext, frame.id()) else { return PdoRx::NotPdo };
        let Some(p) = self.rpdos.get_mut(n) else { return PdoRx::NotPdo };
        let rpdo = n as u16;
        // Processed against the zero-padded buffer; `len` decides validity.
        let data = frame.raw_data();
        let len = frame.len() as u8;
        if len < p.s.plan.len {
            return PdoRx::Event(PdoEvent::RpdoLengthError { rpdo, len });
        }
        let mut first = (len > p.s.plan.len).then_some(PdoEvent::RpdoLengthExceeded { rpdo, len });
        if p.s.timer_ns != 0 {
            p.deadline = Some(super::after(now, p.s.timer_ns));
            if p.timed_out {
                p.timed_out = false;
                let e = PdoEvent::RpdoResumed { rpdo };
                match first {
                    None => first = Some(e),
                    Some(_) => self.events.push(e),
                }
            }
        }
        if p.s.ttype <= 240 {
            // CiA 301 7.2.2.2: synchronous RPDO data is actuated at the next SYNC.
            p.latch = *data;
            p.latched = true;
        } else {
            apply(&p.s.plan, od, hooks, rpdo, &mut self.events, data);
        }
        match first {
            Some(e) => PdoRx::Event(e),
            None => PdoRx::Handled,
        }
    }

    fn handle_rtr<H: ObjectHooks + ?Sized>(
        &mut self,
        id: CanId,
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) -> PdoRx {
        let Some(n) = lookup(&self.tx_std, &self.tx_ext, id) else { return PdoRx::NotPdo };
        let Some(t) = self.tpdos.get_mut(n) else { return PdoRx::NotPdo };
        match t.s.ttype {
            TT_EVENT_RTR => {
                // 253: sampled at the request and sent at once.
                let mut buf = [0u8; MAX_DATA_LEN];
                sample(&t.s.plan, od, hooks, n as u16, &mut self.events, &mut buf);
                t.emit(&buf, now, out);
            }
            // 252: the data sampled at the last SYNC (CiA 301 Table 71);
            // before any SYNC, the data sampled at the next one.
            TT_SYNC_RTR if t.has_synced => {
                let buf = t.synced;
                t.emit(&buf, now, out);
            }
            0..=240 | TT_SYNC_RTR => t.rtr_pending = true,
            TT_EVENT_MANUFACTURER | TT_EVENT_PROFILE => {
                t.requested = true;
                if now >= t.next_allowed {
                    let mut buf = [0u8; MAX_DATA_LEN];
                    sample(&t.s.plan, od, hooks, n as u16, &mut self.events, &mut buf);
                    t.emit(&buf, now, out);
                }
            }
            _ => {}
        }
        PdoRx::Handled
    }

    /// A SYNC was received (`counter` if it carried one, CiA 301 7.2.5).
    /// Latched synchronous RPDOs are written first, then synchronous TPDOs
    /// are sampled and sent: type 0 if requested or its data changed since
    /// it was last sent, 1..240 on every n-th SYNC (starting at the SYNC
    /// whose counter equals the SYNC start value, 1800h+n sub 6, when both
    /// are non-zero); 252 is sampled for the next RTR (and sent if a remote
    /// request came before the first SYNC).
    #[inline]
    pub fn on_sync<H: ObjectHooks + ?Sized>(
        &mut self,
        counter: Option<u8>,
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        // Sample first: a synchronous TPDO reports the state at the SYNC,
        // before this SYNC's RPDO data takes effect (a device acts on
        // received data in its next cycle, not in the past).
        for &n in &self.sync_tpdos {
            let Some(t) = self.tpdos.get_mut(usize::from(n)) else { continue };
            let mut buf = [0u8; MAX_DATA_LEN];
            let send = match t.s.ttype {
                0 => {
                    // Acyclic: the "event" is a request or a change of the data.
                    sample(&t.s.plan, od, hooks, n, &mut self.events, &mut buf);
                    t.requested || t.rtr_pending || t.changed(&buf)
                }
                1..=240 => {
                    let due = sync_due(t, counter);
                    if due || t.rtr_pending {
                        sample(&t.s.plan, od, hooks, n, &mut self.events, &mut buf);
                    }
                    due || t.rtr_pending
                }
                TT_SYNC_RTR => {
                    sample(&t.s.plan, od, hooks, n, &mut self.events, &mut buf);
                    t.synced = buf;
                    t.has_synced = true;
                    t.rtr_pending
                }
                _ => false,
            };
            if send {
                t.emit(&buf, now, out);
            }
        }
        for &n in &self.sync_rpdos {
            if let Some(p) = self.rpdos.get_mut(usize::from(n))
                && p.latched
            {
                p.latched = false;
                apply(&p.s.plan, od, hooks, n, &mut self.events, &p.latch);
            }
        }
    }

    /// Timers and change-of-state. Event-driven TPDOs (254/255) are sent
    /// when their event timer (sub 5, ms) expires, when requested, or when
    /// their packed data differs from what was last sent (only re-packed
    /// when the dictionary's generation moved, or always for TPDOs mapping
    /// hooked objects), never sooner than the inhibit time (sub 3, 100 µs)
    /// after the previous one: a change inside it goes out when it ends.
    /// RPDO deadlines that passed raise [`PdoEvent::RpdoTimeout`] once.
    /// Returns the earliest deadline.
    pub fn poll<H: ObjectHooks + ?Sized>(
        &mut self,
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) -> Option<Instant> {
        let mut next = None;
        for &n in &self.monitored_rpdos {
            let Some(p) = self.rpdos.get_mut(usize::from(n)) else { continue };
            if let Some(d) = p.deadline {
                if now >= d {
                    p.deadline = None;
                    p.timed_out = true;
                    self.events.push(PdoEvent::RpdoTimeout { rpdo: n });
                } else {
                    next = earliest(next, Some(d));
                }
            }
        }
        let gen_moved = self.seen_gen != Some(od.generation());
        for &n in &self.event_tpdos {
            let Some(t) = self.tpdos.get_mut(usize::from(n)) else { continue };
            if t.event_deadline.is_some_and(|d| now >= d) {
                t.requested = true;
            }
            let mut buf = [0u8; MAX_DATA_LEN];
            let mut fresh = false;
            if !t.requested && (gen_moved || t.s.plan.hooked || !t.has_last) {
                sample(&t.s.plan, od, hooks, n, &mut self.events, &mut buf);
                fresh = true;
                t.requested = t.changed(&buf);
            }
            if t.requested && now >= t.next_allowed {
                if !fresh {
                    sample(&t.s.plan, od, hooks, n, &mut self.events, &mut buf);
                }
                t.emit(&buf, now, out);
            }
            if t.requested {
                next = earliest(next, Some(t.next_allowed));
            }
            next = earliest(next, t.event_deadline);
        }
        self.seen_gen = Some(od.generation());
        next
    }
}

/// Cyclic synchronous TPDO (1..240): is this SYNC a transmission SYNC?
#[inline]
fn sync_due(t: &mut Tpdo, counter: Option<u8>) -> bool {
    if t.await_start {
        match counter {
            Some(c) => {
                // CiA 301 7.5.2.37 sub 6: the first transmission is at the
                // SYNC whose counter equals the start value.
                if c != t.s.start {
                    return false;
                }
                t.await_start = false;
                t.sync_count = 0;
                return true;
            }
            // A SYNC without counter: the start value does not apply.
            None => t.await_start = false,
        }
    }
    t.sync_count = t.sync_count.saturating_add(1);
    if t.sync_count >= t.s.ttype {
        t.sync_count = 0;
        true
    } else {
        false
    }
}
