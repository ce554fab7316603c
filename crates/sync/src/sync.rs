//! SYNC (CiA 301 §7.2.5): consumer, producer, synchronous window, loss watch.

use crate::{
    COB_ID_PRODUCE, OD_COB_ID_SYNC, OD_CYCLE_PERIOD, OD_SYNC_COUNTER_OVERFLOW, OD_SYNC_WINDOW, can_id_of,
    check_cob_id, le_of,
};
use drivebus_can::{CanId, Duration, Frame, Instant, TxSink};
use drivebus_od::{Access, DataType, Object, ObjectCode, ObjectDictionary, SdoAbort, SubObject, Value};

/// A SYNC happened: received from the bus, or produced by this node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncEvent {
    /// The counter byte of a DLC-1 SYNC (CiA 301 §7.2.5), `None` for DLC 0.
    pub counter: Option<u8>,
    /// Set when the DLC does not match 1019h: the node raises EMCY 8240h
    /// "unexpected SYNC data length" (CiA 301 §7.2.5).
    pub length_error: Option<SyncLengthError>,
}

/// A SYNC whose DLC differs from the one 1019h configures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncLengthError {
    /// DLC 1019h implies: 0 without counter, 1 with counter.
    pub expected: u8,
    /// DLC received.
    pub actual: u8,
}

/// No SYNC arrived within the configured multiple of 1006h.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncTimeout {
    /// When the last SYNC was seen.
    pub last_sync: Instant,
}

/// What [`SyncService::poll`] did and when to call it next.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SyncPoll {
    /// The SYNC this node just produced; the local node treats it like a
    /// received one (own frames are not received back from the controller).
    pub produced: Option<SyncEvent>,
    /// SYNC loss detected (reported once per loss).
    pub timeout: Option<SyncTimeout>,
    /// Next deadline (next SYNC to produce, or the loss deadline).
    pub next: Option<Instant>,
}

/// SYNC consumer and producer of one node.
#[derive(Clone, Debug)]
pub struct SyncService {
    cob_id: u32,
    can_id: CanId,
    period: Duration,
    window: Duration,
    overflow: u8,
    /// Counter of the next produced SYNC (1..=overflow).
    counter: u8,
    /// Producer: when the next SYNC is due; `None` = at the next poll.
    next_due: Option<Instant>,
    last_sync: Option<Instant>,
    timeout_permille: u32,
    timed_out: bool,
}

impl SyncService {
    /// Insert 1005h (default 80h, consumer), 1006h, 1007h (0 = off) and
    /// 1019h (0 = no counter) and return the service. `node_id` is taken
    /// for a uniform service constructor; the SYNC COB-ID is not
    /// node-relative.
    pub fn install(od: &mut ObjectDictionary, node_id: u8) -> SyncService {
        let _ = node_id;
        let var = |index, name: &'static str, dt, v: Value| {
            Object::with_code(index, ObjectCode::Var, name)
                .with_sub(SubObject::new(0, name, dt, Access::Rw, v).hooked())
        };
        od.insert(var(OD_COB_ID_SYNC, "COB-ID SYNC message", DataType::Unsigned32, Value::U32(0x80)));
        od.insert(var(OD_CYCLE_PERIOD, "Communication cycle period", DataType::Unsigned32, Value::U32(0)));
        od.insert(var(OD_SYNC_WINDOW, "Synchronous window length", DataType::Unsigned32, Value::U32(0)));
        od.insert(var(
            OD_SYNC_COUNTER_OVERFLOW,
            "Synchronous counter overflow value",
            DataType::Unsigned8,
            Value::U8(0),
        ));
        SyncService {
            cob_id: 0x80,
            can_id: CanId::Standard(0x80),
            period: Duration::ZERO,
            window: Duration::ZERO,
            overflow: 0,
            counter: 1,
            next_due: None,
            last_sync: None,
            timeout_permille: 1500,
            timed_out: false,
        }
    }

    /// The SYNC identifier (from 1005h).
    pub fn can_id(&self) -> CanId {
        self.can_id
    }
    /// True when 1005h bit 30 makes this node the SYNC producer.
    pub fn is_producer(&self) -> bool {
        self.cob_id & COB_ID_PRODUCE != 0
    }
    /// True while the producer runs (bit 30 set and 1006h ≠ 0).
    pub fn is_producing(&self) -> bool {
        self.is_producer() && !self.period.is_zero()
    }
    /// Communication cycle period 1006h (zero: off).
    pub fn period(&self) -> Duration {
        self.period
    }
    /// Synchronous counter overflow value 1019h (0: no counter).
    pub fn counter_overflow(&self) -> u8 {
        self.overflow
    }
    /// When the last SYNC was received or produced.
    pub fn last_sync(&self) -> Option<Instant> {
        self.last_sync
    }

    /// SYNC loss is reported after `permille / 1000` × 1006h without SYNC
    /// (default 1500 = 1.5 periods, the usual CiA 402 drive tolerance;
    /// 0 disables). CiA 301 §7.5.2 (1006h) lets consumers use 1006h to watch SYNC.
    pub fn set_timeout_factor_permille(&mut self, permille: u32) {
        self.timeout_permille = permille;
    }

    /// Restart the producer's counter at 1, so the first SYNC after a
    /// (re)start carries 1 (CiA 301 §7.2.5); the node calls this when the
    /// producer resumes, e.g. on entering Operational. Starting or stopping
    /// the producer (1005h bit 30, 1006h) and writing 1019h reset it too.
    pub fn reset_counter(&mut self) {
        self.counter = 1;
    }

    /// A frame from the bus: `Some` for a SYNC on the 1005h identifier.
    ///
    /// Both DLC 0 and DLC 1 are accepted as SYNC whatever 1019h says, and a
    /// DLC that does not match 1019h is flagged in
    /// [`SyncEvent::length_error`] so the node can send EMCY 8240h
    /// (CiA 301 §7.2.5): losing a control cycle over a counter byte would
    /// be worse than reporting it. Longer frames are treated the same way
    /// (SYNC without counter, flagged). RTR frames are ignored, and so are
    /// SYNCs on our identifier while this node is the active producer
    /// (another producer would be a configuration error; our own SYNC is
    /// reported by [`SyncService::poll`]).
    #[inline]
    pub fn handle_frame(&mut self, frame: &Frame, now: Instant) -> Option<SyncEvent> {
        if frame.id() != self.can_id || frame.is_rtr() || self.is_producing() {
            return None;
        }
        let len = frame.len() as u8;
        let expected = (self.overflow != 0) as u8;
        let counter = if len == 1 { Some(frame.raw_data()[0]) } else { None };
        let length_error =
            if len == expected { None } else { Some(SyncLengthError { expected, actual: len }) };
        self.last_sync = Some(now);
        self.timed_out = false;
        Some(SyncEvent { counter, length_error })
    }

    /// True while synchronous PDOs may be processed: 1007h is 0 (no
    /// window), or less than 1007h has passed since the last SYNC
    /// (CiA 301 §7.5.2 (1007h)). Before the first SYNC a configured window is closed.
    #[inline]
    pub fn window_open(&self, now: Instant) -> bool {
        match self.window_closes_at() {
            None => self.window.is_zero(),
            Some(t) => now < t,
        }
    }

    /// When the current synchronous window closes (`None`: no window, or no SYNC yet).
    pub fn window_closes_at(&self) -> Option<Instant> {
        if self.window.is_zero() {
            return None;
        }
        self.last_sync.map(|t| t + self.window)
    }

    /// Check for SYNC loss: `Some` once when no SYNC arrived for the
    /// configured multiple of 1006h after the first one. Only as a consumer
    /// with 1006h ≠ 0.
    pub fn sync_timeout(&mut self, now: Instant) -> Option<SyncTimeout> {
        let deadline = self.timeout_deadline()?;
        if now < deadline {
            return None;
        }
        self.timed_out = true;
        self.last_sync.map(|last_sync| SyncTimeout { last_sync })
    }

    fn timeout_deadline(&self) -> Option<Instant> {
        if self.timed_out || self.is_producing() || self.timeout_permille == 0 || self.period.is_zero() {
            return None;
        }
        let ns = self.period.as_nanos().saturating_mul(self.timeout_permille as u128) / 1000;
        let d = Duration::from_nanos(u64::try_from(ns).unwrap_or(u64::MAX));
        self.last_sync.map(|t| t + d)
    }

    /// Produce a SYNC when due (1005h bit 30 and 1006h ≠ 0): DLC 0, or
    /// DLC 1 with the counter 1..=1019h, wrapping to 1 (CiA 301 §7.2.5).
    /// The first SYNC goes at the first poll after the producer starts,
    /// then one per period on a fixed grid; a late poll sends one SYNC and
    /// skips the missed slots. Also checks SYNC loss as a consumer.
    pub fn poll(&mut self, now: Instant, out: &mut impl TxSink) -> SyncPoll {
        let mut r = SyncPoll::default();
        if self.is_producing() {
            let due = *self.next_due.get_or_insert(now);
            if now >= due {
                let c = [self.counter];
                let data: &[u8] = if self.overflow == 0 { &[] } else { &c };
                if let Ok(f) = Frame::try_new(self.can_id, data) {
                    out.send(f);
                }
                r.produced = Some(SyncEvent { counter: data.first().copied(), length_error: None });
                if self.overflow != 0 {
                    self.counter = if self.counter >= self.overflow { 1 } else { self.counter + 1 };
                }
                self.last_sync = Some(now);
                let p = self.period.as_nanos() as u64;
                let late = now.as_nanos() - due.as_nanos();
                self.next_due = Some(Instant::from_nanos(
                    due.as_nanos().saturating_add((late / p + 1).saturating_mul(p)),
                ));
            }
            r.next = self.next_due;
        } else {
            r.timeout = self.sync_timeout(now);
            r.next = self.timeout_deadline();
        }
        r
    }

    /// The abort for an SDO write this service refuses:
    /// * 1005h: bad or restricted CAN-ID, or bits 0..29 changed while bit 30
    ///   (producer) is set → `0609 0030` (CiA 301 §7.5.2 (1005h));
    /// * 1019h: 1 or 241..255 → `0609 0030`; any write while 1006h ≠ 0 →
    ///   `0800 0022` (CiA 301 §7.5.2 (1019h)).
    ///
    /// Other indices: `Ok`.
    pub fn check_write(
        &self,
        od: &ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        match (index, sub) {
            (OD_COB_ID_SYNC, 0) => {
                let new = le_of(DataType::Unsigned32, data)?;
                let old = od.get_u32(OD_COB_ID_SYNC, 0).unwrap_or(self.cob_id);
                check_cob_id(old, new, COB_ID_PRODUCE)
            }
            (OD_SYNC_COUNTER_OVERFLOW, 0) => {
                let v = le_of(DataType::Unsigned8, data)?;
                if v == 1 || v > 240 {
                    return Err(SdoAbort::INVALID_VALUE);
                }
                if od.get_u32(OD_CYCLE_PERIOD, 0).unwrap_or(0) != 0 {
                    return Err(SdoAbort::DEVICE_STATE);
                }
                Ok(())
            }
            (OD_CYCLE_PERIOD | OD_SYNC_WINDOW, 0) => le_of(DataType::Unsigned32, data).map(|_| ()),
            _ => Ok(()),
        }
    }

    /// Re-read an object of this service after a write was stored.
    pub fn reconfigure(&mut self, od: &ObjectDictionary, index: u16, sub: u8) {
        if let Some(v) = od.get_u32(index, sub) {
            self.apply_value(index, sub, v);
        }
    }

    /// Take the stored value `v` of `(index, sub)` (what [`reconfigure`]
    /// reads, handed over by a caller that holds it: no dictionary search).
    ///
    /// [`reconfigure`]: SyncService::reconfigure
    pub fn apply_value(&mut self, index: u16, sub: u8, v: u32) {
        if sub != 0 {
            return;
        }
        match index {
            OD_COB_ID_SYNC => {
                let was = self.is_producing();
                self.cob_id = v;
                // check_write guarantees a representable id; keep the old one otherwise.
                if let Some(id) = can_id_of(v) {
                    self.can_id = id;
                }
                if self.is_producing() != was {
                    self.restart();
                }
            }
            OD_CYCLE_PERIOD => {
                let was = self.is_producing();
                self.period = Duration::from_micros(v as u64);
                if self.is_producing() != was {
                    self.restart();
                } else if let (true, Some(last)) = (was, self.last_sync) {
                    // The new period counts from the last SYNC: no gap, no burst.
                    self.next_due = Some(last + self.period);
                }
            }
            OD_SYNC_WINDOW => self.window = Duration::from_micros(v as u64),
            OD_SYNC_COUNTER_OVERFLOW => {
                self.overflow = v as u8;
                self.counter = 1;
            }
            _ => {}
        }
    }

    /// Re-read every object (after restore or reset communication).
    pub fn reconfigure_all(&mut self, od: &ObjectDictionary) {
        for i in [OD_COB_ID_SYNC, OD_CYCLE_PERIOD, OD_SYNC_WINDOW, OD_SYNC_COUNTER_OVERFLOW] {
            self.reconfigure(od, i, 0);
        }
    }

    fn restart(&mut self) {
        self.next_due = None;
        self.counter = 1;
        self.timed_out = false;
    }
}
