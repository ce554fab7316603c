//! The EMCY producer: 1001h, 1003h, 1014h, 1015h (CiA 301 §7.2.7, §7.5.2).

use crate::codes::ErrorRegister;
use crate::{
    COB_ID_INVALID, OD_COB_ID_EMCY, OD_ERROR_HISTORY, OD_ERROR_REGISTER, OD_INHIBIT_TIME_EMCY, can_id_of,
    check_cob_id_write, u32_of,
};
use alloc::vec::Vec;
use drivebus_can::{CanId, Duration, Frame, Instant, TxSink};
use drivebus_od::{
    Access, DataType, Object, ObjectCode, ObjectDictionary, PersistGroup, SdoAbort, SubObject, Value,
};

/// Most errors tracked as active at once; further raises are still sent and
/// recorded in 1003h but cannot be cleared individually.
pub const MAX_ACTIVE: usize = 16;
/// Capacity of the transmit queue (frames waiting for the inhibit time).
pub const QUEUE_LEN: usize = 16;
/// Largest 1003h history CiA 301 §7.5.2 allows (sub-indices 1..254).
pub const MAX_HISTORY: u8 = 254;

/// One error currently active on the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ActiveError {
    /// Emergency error code.
    pub code: u16,
    /// 1001h bits this error holds set (bit 0 is implied).
    pub register_bits: u8,
    /// When it was raised.
    pub since: Instant,
}

/// A queued EMCY payload (frozen when the event happened) and its time.
#[derive(Clone, Copy, Debug)]
struct Queued {
    payload: [u8; 8],
    at: Instant,
}

const EMPTY: Queued = Queued { payload: [0; 8], at: Instant::ZERO };
const NO_ERROR: ActiveError = ActiveError { code: 0, register_bits: 0, since: Instant::ZERO };

/// The EMCY producer of one node.
///
/// Events ([`Emcy::raise`], [`Emcy::clear`], [`Emcy::send_raw`]) update
/// 1001h/1003h at once and queue a frame; [`Emcy::poll`] puts queued frames
/// on the bus no closer together than the inhibit time 1015h. Nothing
/// allocates after [`Emcy::install`].
#[derive(Clone, Debug)]
pub struct Emcy {
    cob_id: u32,
    can_id: Option<CanId>,
    inhibit: Duration,
    active: [ActiveError; MAX_ACTIVE],
    n_active: usize,
    /// Newest first; capacity fixed at install.
    history: Vec<u32>,
    history_len: u8,
    queue: [Queued; QUEUE_LEN],
    q_head: usize,
    q_len: usize,
    /// When the last frame went out (the inhibit time runs from here).
    last_sent: Option<Instant>,
    dropped: u32,
    partial_reset: bool,
}

impl Emcy {
    /// Insert 1001h, 1003h (when `history_len > 0`, capped at 254), 1014h
    /// and 1015h with their CiA 301 defaults and return the producer.
    ///
    /// 1014h defaults to `80h + node_id` (`$NODEID`-relative); for a node-ID
    /// outside 1..=127 (unconfigured LSS node) it defaults to invalid.
    pub fn install(od: &mut ObjectDictionary, node_id: u8, history_len: u8) -> Emcy {
        let history_len = history_len.min(MAX_HISTORY);
        od.insert(Object::with_code(OD_ERROR_REGISTER, ObjectCode::Var, "Error register").with_sub(
            SubObject::new(0, "Error register", DataType::Unsigned8, Access::Ro, Value::U8(0)).mappable(),
        ));
        if history_len > 0 {
            let mut o = Object::with_code(OD_ERROR_HISTORY, ObjectCode::Array, "Pre-defined error field")
                .with_sub(
                    SubObject::new(0, "Number of errors", DataType::Unsigned8, Access::Rw, Value::U8(0))
                        .hooked(),
                );
            for k in 1..=history_len {
                o = o.with_sub(
                    SubObject::new(
                        k,
                        alloc::format!("Standard error field {k}"),
                        DataType::Unsigned32,
                        Access::Ro,
                        Value::U32(0),
                    )
                    .hooked(),
                );
            }
            od.insert(o);
            // The error count is live data, not a parameter 1010h stores.
            if let Some(s) = od.get_mut(OD_ERROR_HISTORY, 0) {
                s.persist = PersistGroup::Volatile;
            }
        }
        let cob_id = Emcy::default_cob_id(node_id);
        let mut cob =
            SubObject::new(0, "COB-ID EMCY", DataType::Unsigned32, Access::Rw, Value::U32(cob_id)).hooked();
        cob.node_id_relative = true;
        od.insert(Object::with_code(OD_COB_ID_EMCY, ObjectCode::Var, "COB-ID EMCY").with_sub(cob));
        od.insert(Object::with_code(OD_INHIBIT_TIME_EMCY, ObjectCode::Var, "Inhibit time EMCY").with_sub(
            SubObject::new(0, "Inhibit time EMCY", DataType::Unsigned16, Access::Rw, Value::U16(0)).hooked(),
        ));
        let mut e = Emcy {
            cob_id,
            can_id: None,
            inhibit: Duration::ZERO,
            active: [NO_ERROR; MAX_ACTIVE],
            n_active: 0,
            history: Vec::with_capacity(history_len as usize),
            history_len,
            queue: [EMPTY; QUEUE_LEN],
            q_head: 0,
            q_len: 0,
            last_sent: None,
            dropped: 0,
            partial_reset: true,
        };
        e.apply_cob_id(cob_id);
        e
    }

    /// The 1014h default for `node_id`: `80h + node_id`, or invalid (bit 31)
    /// for a node-ID outside 1..=127.
    pub const fn default_cob_id(node_id: u8) -> u32 {
        if node_id >= 1 && node_id <= 127 { 0x80 + node_id as u32 } else { COB_ID_INVALID | 0x80 }
    }

    /// The EMCY identifier, `None` while 1014h is invalid.
    pub fn can_id(&self) -> Option<CanId> {
        self.can_id
    }

    /// Whether clearing one error while others remain sends an EMCY with
    /// code 0000h and the remaining register (CiA 301 §7.2.7 transition
    /// 2, optional: "may"). Default `true`, as the KC1, AKD and SSD 630
    /// manuals describe. The reset after the *last* error is always sent.
    pub fn set_partial_reset(&mut self, on: bool) {
        self.partial_reset = on;
    }

    /// The current error register 1001h: the OR of the active errors' bits,
    /// plus the generic bit 0 whenever any error is active (§7.5.2 (1001h)).
    pub fn error_register(&self) -> u8 {
        let mut r = 0;
        for e in self.active() {
            r |= e.register_bits | ErrorRegister::GENERIC;
        }
        r
    }

    /// The active errors, oldest first.
    pub fn active(&self) -> &[ActiveError] {
        &self.active[..self.n_active]
    }

    /// The 1003h history as stored, newest first (low 16 bits: error code,
    /// high 16 bits: additional information, 0 here).
    pub fn history(&self) -> &[u32] {
        &self.history
    }

    /// Frames lost because the queue was full.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// True while the COB-ID is valid (bit 31 = 0).
    pub fn is_valid(&self) -> bool {
        self.can_id.is_some()
    }

    /// Signal an error: record it as active, set its 1001h bits (and the
    /// generic bit), push it to 1003h sub 1 (older entries shift down, the
    /// oldest falls off) and queue the EMCY `code | 1001h | manufacturer`.
    ///
    /// `register_bits` usually is [`crate::register_bit_for`]`(code)`.
    /// Returns `false` (and does nothing) when `code` is already active:
    /// an EMCY is sent once per error occurrence (§7.2.7).
    pub fn raise(
        &mut self,
        od: &mut ObjectDictionary,
        code: u16,
        register_bits: u8,
        manufacturer: [u8; 5],
        now: Instant,
    ) -> bool {
        if self.active().iter().any(|e| e.code == code) {
            return false;
        }
        let register_bits = register_bits & !ErrorRegister::RESERVED;
        if self.n_active < MAX_ACTIVE {
            self.active[self.n_active] = ActiveError { code, register_bits, since: now };
            self.n_active += 1;
        }
        let reg = self.error_register() | register_bits | ErrorRegister::GENERIC;
        if self.history_len > 0 {
            if self.history.len() == self.history_len as usize {
                self.history.pop();
            }
            self.history.insert(0, code as u32);
        }
        self.write_od(od, reg);
        self.enqueue(code, reg, manufacturer, now);
        true
    }

    /// An error went away. If it was the last one, queue the error-reset
    /// EMCY (code 0000h, 1001h, zeros); if others remain and partial resets
    /// are on, queue 0000h with the remaining register (§7.2.7).
    /// Returns `false` if `code` was not active.
    pub fn clear(&mut self, od: &mut ObjectDictionary, code: u16, now: Instant) -> bool {
        let Some(i) = self.active().iter().position(|e| e.code == code) else { return false };
        self.active.copy_within(i + 1..self.n_active, i);
        self.n_active -= 1;
        let reg = self.error_register();
        self.write_od(od, reg);
        if self.n_active == 0 || self.partial_reset {
            self.enqueue(0x0000, reg, [0; 5], now);
        }
        true
    }

    /// Clear every active error and queue one error-reset EMCY (if any was active).
    pub fn clear_all(&mut self, od: &mut ObjectDictionary, now: Instant) {
        if self.n_active == 0 {
            return;
        }
        self.n_active = 0;
        self.write_od(od, 0);
        self.enqueue(0x0000, 0, [0; 5], now);
    }

    /// Queue an EMCY with a custom payload, outside the error bookkeeping
    /// (no change of 1001h, 1003h or the active list). Personality hook:
    /// e.g. the SSD 630 sends `0000h` with its firmware version "Vxxxx" in
    /// the manufacturer bytes after initialisation (seed003 §9 transition 0).
    pub fn send_raw(&mut self, code: u16, register: u8, bytes: [u8; 5], now: Instant) {
        self.enqueue(code, register, bytes, now);
    }

    /// Record an entry in the 1003h history without signalling it: no
    /// frame, no 1001h change, nothing made active. For a device that sends
    /// its own EMCY frame ([`Emcy::send_raw`]), so that 1003h and its reads
    /// ([`Emcy::check_read`]) keep one history. `entry`: low 16 bits the
    /// error code, high 16 bits additional information (CiA 301 §7.5.2.5).
    pub fn record(&mut self, od: &mut ObjectDictionary, entry: u32) {
        if self.history_len == 0 {
            return;
        }
        if self.history.len() == self.history_len as usize {
            self.history.pop();
        }
        self.history.insert(0, entry);
        self.write_history(od);
    }

    /// Empty the 1003h history (what writing 0 to 1003h sub 0 does).
    pub fn clear_history(&mut self, od: &mut ObjectDictionary) {
        self.history.clear();
        let reg = self.error_register();
        self.write_od(od, reg);
    }

    /// Drop queued frames (e.g. on NMT reset communication).
    pub fn discard_queue(&mut self) {
        self.q_head = 0;
        self.q_len = 0;
    }

    /// Send queued EMCYs that are due: the first immediately, then one per
    /// inhibit time (1015h). Returns when the next queued frame becomes due.
    /// With an invalid COB-ID queued frames are discarded, nothing is sent.
    pub fn poll(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        let Some(id) = self.can_id else {
            self.discard_queue();
            return None;
        };
        while self.q_len > 0 {
            let q = self.queue[self.q_head];
            let due = match self.last_sent {
                Some(t) if t + self.inhibit > q.at => t + self.inhibit,
                _ => q.at,
            };
            if now < due {
                return Some(due);
            }
            // Length 8 and a checked id: cannot fail.
            if let Ok(f) = Frame::try_new(id, &q.payload) {
                out.send(f);
            }
            self.last_sent = Some(now);
            self.q_head = (self.q_head + 1) % QUEUE_LEN;
            self.q_len -= 1;
        }
        None
    }

    /// The abort for an SDO write this service refuses (CiA 301 §7.5.2):
    /// 1003h sub 0 other than 0, a COB-ID change while valid, a reserved
    /// bit or a restricted / out-of-range CAN-ID → `0609 0030`. Other
    /// indices are not this service's: `Ok`.
    pub fn check_write(
        &self,
        od: &ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        match (index, sub) {
            (OD_ERROR_HISTORY, 0) => {
                drivebus_od::check_len(DataType::Unsigned8, data.len())?;
                if data[0] != 0 { Err(SdoAbort::INVALID_VALUE) } else { Ok(()) }
            }
            (OD_COB_ID_EMCY, 0) => {
                let new = u32_of(data)?;
                let old = od.get_u32(OD_COB_ID_EMCY, 0).unwrap_or(self.cob_id);
                check_cob_id_write(old, new)
            }
            _ => Ok(()),
        }
    }

    /// Refuse reads of 1003h sub-indices above the current error count with
    /// `0800 0024` "no data available" (CiA 301 §7.5.2 (1003h) leaves it open;
    /// that is the common choice). The node calls this from `on_read`.
    pub fn check_read(&self, index: u16, sub: u8) -> Result<(), SdoAbort> {
        if index == OD_ERROR_HISTORY && sub > 0 && sub as usize > self.history.len() {
            return Err(SdoAbort::NO_DATA);
        }
        Ok(())
    }

    /// Re-read an object of this service after a write was stored.
    pub fn reconfigure(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) {
        match (index, sub) {
            // check_write admits only 0: the history is deleted.
            (OD_ERROR_HISTORY, 0) if od.get_u64(OD_ERROR_HISTORY, 0) == Some(0) => self.clear_history(od),
            (OD_COB_ID_EMCY, 0) => {
                if let Some(v) = od.get_u32(OD_COB_ID_EMCY, 0) {
                    self.apply_cob_id(v);
                }
            }
            (OD_INHIBIT_TIME_EMCY, 0) => {
                let t = od.get_u64(OD_INHIBIT_TIME_EMCY, 0).unwrap_or(0);
                // Applies to the pending wait too: it runs from the last send.
                self.inhibit = Duration::from_micros(100 * t);
            }
            _ => {}
        }
    }

    /// Re-read every object (after restore or reset communication).
    pub fn reconfigure_all(&mut self, od: &mut ObjectDictionary) {
        for (i, s) in [(OD_COB_ID_EMCY, 0), (OD_INHIBIT_TIME_EMCY, 0)] {
            self.reconfigure(od, i, s);
        }
    }

    fn apply_cob_id(&mut self, v: u32) {
        self.cob_id = v;
        self.can_id = if v & COB_ID_INVALID != 0 { None } else { can_id_of(v) };
        if self.can_id.is_none() {
            self.discard_queue();
        }
    }

    fn enqueue(&mut self, code: u16, register: u8, bytes: [u8; 5], now: Instant) {
        // An invalid COB-ID means no EMCY object: nothing to send, ever.
        if self.can_id.is_none() {
            return;
        }
        if self.q_len == QUEUE_LEN {
            self.dropped = self.dropped.saturating_add(1);
            return;
        }
        let c = code.to_le_bytes();
        let payload = [c[0], c[1], register, bytes[0], bytes[1], bytes[2], bytes[3], bytes[4]];
        self.queue[(self.q_head + self.q_len) % QUEUE_LEN] = Queued { payload, at: now };
        self.q_len += 1;
    }

    /// Push 1001h and 1003h into the dictionary. Entries are resolved per
    /// event (a few binary searches): errors are rare, and a cached
    /// `EntryRef` would go stale when other services insert objects.
    fn write_od(&self, od: &mut ObjectDictionary, reg: u8) {
        if let Ok(r) = od.find(OD_ERROR_REGISTER, 0) {
            od.set_le(r, &[reg]);
        }
        self.write_history(od);
    }

    fn write_history(&self, od: &mut ObjectDictionary) {
        if self.history_len == 0 {
            return;
        }
        if let Ok(r) = od.find(OD_ERROR_HISTORY, 0) {
            od.set_le(r, &[self.history.len() as u8]);
        }
        for k in 1..=self.history_len {
            let v = self.history.get(k as usize - 1).copied().unwrap_or(0);
            if let Ok(r) = od.find(OD_ERROR_HISTORY, k) {
                od.set_le(r, &v.to_le_bytes());
            }
        }
    }
}
