//! The mailbox server: one request mailbox in, response mailboxes out.

use crate::AlState;
use crate::access::ObjectAccess;
use crate::coe::emergency::{Emergency, EmergencyQueue, EmergencyQueueFull};
use crate::coe::{CoeConfig, CoeServer, Out};
use crate::foe::{FileHandler, FoeEnd, FoeServer};
use crate::mailbox::{
    HEADER_LEN, MAX_MAILBOX_SIZE, MIN_MAILBOX_SIZE, MailboxErrorCode, MailboxHeader, MailboxType,
    ResponseQueue, next_counter,
};
use alloc::vec::Vec;
use drivebus_base::{Duration, Instant};

/// Configuration of a [`MailboxServer`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MailboxConfig {
    /// SM0 length: the mailbox the master writes (default 128).
    pub rx_size: usize,
    /// SM1 length: the mailbox the master reads (default 128).
    pub tx_size: usize,
    /// Response buffers, at least 2 (default 4); one is kept for
    /// "no more memory" replies.
    pub response_slots: usize,
    /// Emergencies that can wait to be read (default 8; 0 disables them).
    pub emergency_slots: usize,
    /// Longest gap between two mailboxes of a segmented SDO transfer or a
    /// fragmented SDO Information answer before it is dropped (default 2 s).
    pub sdo_timeout: Duration,
    /// Longest gap between two packets of an FoE transfer (default 30 s).
    pub foe_timeout: Duration,
    /// Largest segmented download accepted, in bytes (default 1 MiB).
    pub max_download: usize,
    /// Complete access is offered (SII "CoE details" bit 5; default true).
    /// Without it a CA request is aborted with `0601 0000`.
    pub complete_access: bool,
    /// SDO Information is offered (SII "CoE details" bit 1; default true).
    /// Without it the service gets a mailbox error.
    pub sdo_info: bool,
}

impl Default for MailboxConfig {
    fn default() -> Self {
        MailboxConfig {
            rx_size: 128,
            tx_size: 128,
            response_slots: 4,
            emergency_slots: 8,
            sdo_timeout: Duration::from_secs(2),
            foe_timeout: Duration::from_secs(30),
            max_download: 1 << 20,
            complete_access: true,
            sdo_info: true,
        }
    }
}

impl MailboxConfig {
    /// The defaults with these SM0/SM1 lengths.
    pub fn with_sizes(rx_size: usize, tx_size: usize) -> Self {
        MailboxConfig { rx_size, tx_size, ..MailboxConfig::default() }
    }
}

/// A mailbox length outside
/// [`MIN_MAILBOX_SIZE`]..=[`MAX_MAILBOX_SIZE`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MailboxSizeError {
    /// The refused length.
    pub size: usize,
}

impl core::fmt::Display for MailboxSizeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "mailbox size {} outside {MIN_MAILBOX_SIZE}..={MAX_MAILBOX_SIZE}", self.size)
    }
}

#[cfg(feature = "std")]
impl std::error::Error for MailboxSizeError {}

fn check_size(size: usize) -> Result<(), MailboxSizeError> {
    if (MIN_MAILBOX_SIZE..=MAX_MAILBOX_SIZE).contains(&size) {
        Ok(())
    } else {
        Err(MailboxSizeError { size })
    }
}

/// Counters for diagnostics and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MailboxStats {
    /// Request mailboxes handed in.
    pub requests: u64,
    /// Requests dropped as repetitions (same counter as the previous one).
    pub repeated: u64,
    /// Requests ignored because the mailbox does not run (INIT).
    pub ignored: u64,
    /// Requests refused because the response queue was full.
    pub refused: u64,
    /// Mailbox error replies queued.
    pub mailbox_errors: u64,
    /// Emergencies handed out.
    pub emergencies_sent: u64,
    /// Emergencies refused by a full queue.
    pub emergencies_dropped: u64,
}

/// The slave's mailbox: dispatches request mailboxes by type to the CoE
/// and FoE machines, answers everything else with a mailbox error, and
/// hands out responses and emergencies in order. See the crate
/// documentation for how an ESC layer drives it.
#[derive(Clone, Debug)]
pub struct MailboxServer {
    config: MailboxConfig,
    responses: ResponseQueue,
    /// The last mailbox handed out, kept for the SM1 repeat request.
    last: Vec<u8>,
    has_last: bool,
    emergencies: EmergencyQueue,
    coe: CoeServer,
    foe: FoeServer,
    /// Counter of the last request (0: none yet, or not counted).
    rx_counter: u8,
    /// Counter of the last response.
    tx_counter: u8,
    /// ESM state of the last request: in BOOT no CoE goes out, emergencies
    /// included.
    state: AlState,
    stats: MailboxStats,
}

impl MailboxServer {
    /// A server with these mailbox sizes and options. Every buffer a
    /// response needs is allocated here.
    pub fn new(config: MailboxConfig) -> Result<MailboxServer, MailboxSizeError> {
        check_size(config.rx_size)?;
        check_size(config.tx_size)?;
        let coe = CoeConfig {
            timeout: config.sdo_timeout,
            max_download: config.max_download,
            complete_access: config.complete_access,
            sdo_info: config.sdo_info,
        };
        Ok(MailboxServer {
            config,
            responses: ResponseQueue::new(config.response_slots, config.tx_size),
            last: Vec::with_capacity(config.tx_size),
            has_last: false,
            emergencies: EmergencyQueue::new(config.emergency_slots),
            coe: CoeServer::new(coe),
            foe: FoeServer::new(config.foe_timeout),
            rx_counter: 0,
            tx_counter: 0,
            state: AlState::Init,
            stats: MailboxStats::default(),
        })
    }

    /// The configuration in force.
    pub fn config(&self) -> &MailboxConfig {
        &self.config
    }

    /// Counters since creation.
    pub fn stats(&self) -> MailboxStats {
        MailboxStats { mailbox_errors: self.responses.errors, ..self.stats }
    }

    /// Change the SM0/SM1 lengths (the bootstrap mailbox of BOOT has its
    /// own, SII words 14h-17h). Resets the mailbox like [`Self::reset`].
    pub fn set_mailbox_sizes<F: FileHandler + ?Sized>(
        &mut self,
        rx_size: usize,
        tx_size: usize,
        files: &mut F,
    ) -> Result<(), MailboxSizeError> {
        check_size(rx_size)?;
        check_size(tx_size)?;
        self.reset(files);
        self.config.rx_size = rx_size;
        self.config.tx_size = tx_size;
        self.responses.resize(tx_size);
        self.last.clear();
        self.last.reserve(tx_size);
        Ok(())
    }

    /// The mailbox stops or starts (ESM INIT ⇄ PRE-OP/BOOT, ETG.1000.6
    /// "start/stop mailbox"): running transfers end silently, queued
    /// responses and emergencies are dropped, both counters start over.
    pub fn reset<F: FileHandler + ?Sized>(&mut self, files: &mut F) {
        self.coe.reset();
        self.foe.end(files, FoeEnd::Reset);
        self.responses.clear();
        self.emergencies.clear();
        self.has_last = false;
        self.rx_counter = 0;
        self.tx_counter = 0;
    }

    /// No transfer in progress and nothing waiting to be sent.
    pub fn is_idle(&self) -> bool {
        !self.coe.busy() && self.foe.is_idle() && self.responses.is_empty() && self.emergencies.len() == 0
    }

    /// Something is waiting for SM1: [`Self::next_response`] would return
    /// it (unless a deadline passes first).
    pub fn has_response(&self) -> bool {
        !self.responses.is_empty() || self.coe.fragments_pending() || self.emergency_due()
    }

    fn emergency_due(&self) -> bool {
        self.emergencies.len() > 0 && !self.coe.busy() && self.state != AlState::Boot
    }

    /// Queue a CoE emergency. It is handed out by [`Self::next_response`]
    /// after every pending response, never while an SDO conversation of
    /// several mailboxes is under way (see the crate documentation) and not
    /// while the last request came in BOOT, where the mailbox carries FoE
    /// only.
    pub fn queue_emergency(
        &mut self,
        code: u16,
        register: u8,
        data: [u8; 5],
    ) -> Result<(), EmergencyQueueFull> {
        let r = self.emergencies.push(Emergency { code, register, data });
        if r.is_err() {
            self.stats.emergencies_dropped += 1;
        }
        r
    }

    /// Emergencies waiting.
    pub fn pending_emergencies(&self) -> usize {
        self.emergencies.len()
    }

    /// Handle one request mailbox as the master wrote it into SM0 (the
    /// whole SM0 area or just the header and service data), in ESM state
    /// `state`. Responses are queued for [`Self::next_response`].
    pub fn handle_request<A, F>(
        &mut self,
        request: &[u8],
        now: Instant,
        state: AlState,
        objects: &mut A,
        files: &mut F,
    ) where
        A: ObjectAccess + ?Sized,
        F: FileHandler + ?Sized,
    {
        self.stats.requests += 1;
        self.state = state;
        self.expire(now, files);
        if !state.has_mailbox() {
            // ETG.1000.6: no mailbox in INIT; an ESC would not deliver it.
            self.stats.ignored += 1;
            return;
        }
        let Some(h) = MailboxHeader::decode(request) else {
            return self.error(MailboxErrorCode::SYNTAX);
        };
        // ETG.1000.4 §5.6: a request repeated with the same counter (the
        // master retrying a write it thinks was lost) is not executed
        // again; the master gets the answer through the SM1 repeat.
        if h.counter != 0 && h.counter == self.rx_counter {
            self.stats.repeated += 1;
            return;
        }
        self.rx_counter = h.counter;
        let length = usize::from(h.length);
        if request.len() > self.config.rx_size || HEADER_LEN + length > request.len() {
            return self.error(MailboxErrorCode::INVALID_SIZE);
        }
        if length == 0 {
            return self.error(MailboxErrorCode::SIZE_TOO_SHORT);
        }
        if !self.responses.has_room() {
            self.stats.refused += 1;
            return self.error(MailboxErrorCode::NO_MORE_MEMORY);
        }
        if h.channel != 0 {
            return self.error(MailboxErrorCode::INVALID_CHANNEL);
        }
        let body = &request[HEADER_LEN..HEADER_LEN + length];
        let mut out = Out { q: &mut self.responses, cap: self.config.tx_size - HEADER_LEN };
        match h.mailbox_type {
            // BOOT offers FoE only (ETG.1000.6 §6.4.1; iPOS manual §3.1).
            MailboxType::Coe if state != AlState::Boot => self.coe.handle(body, now, objects, &mut out),
            MailboxType::Foe if files.supported() => {
                let rx_cap = self.config.rx_size - HEADER_LEN;
                self.foe.handle(body, now, state, rx_cap, files, &mut out);
            }
            MailboxType::Error => self.error(MailboxErrorCode::SYNTAX),
            // EoE, AoE, SoE, VoE and reserved types, CoE in BOOT, FoE
            // without a file handler.
            _ => self.error(MailboxErrorCode::UNSUPPORTED_PROTOCOL),
        }
    }

    fn error(&mut self, code: MailboxErrorCode) {
        self.responses.push_error(code);
    }

    /// The next mailbox for SM1, with its counter set: queued responses
    /// first (in request order), then the next fragment of an SDO
    /// Information answer, then emergencies. `None` when nothing waits.
    /// The slice stays available through [`Self::last_response`].
    pub fn next_response(&mut self, now: Instant) -> Option<&[u8]> {
        self.coe.expire(now);
        let mut got = self.responses.pop_into(&mut self.last);
        if !got {
            let mut out = Out { q: &mut self.responses, cap: self.config.tx_size - HEADER_LEN };
            if self.coe.next_fragment(now, &mut out) {
                got = self.responses.pop_into(&mut self.last);
            }
        }
        if !got
            && self.emergency_due()
            && let Some(e) = self.emergencies.pop()
        {
            let body = e.body();
            let h = MailboxHeader {
                length: body.len() as u16,
                address: 0,
                channel: 0,
                priority: 0,
                mailbox_type: MailboxType::Coe,
                counter: 0,
            };
            self.last.clear();
            self.last.extend_from_slice(&h.encode());
            self.last.extend_from_slice(&body);
            self.stats.emergencies_sent += 1;
            got = true;
        }
        if !got {
            return None;
        }
        self.tx_counter = next_counter(self.tx_counter);
        self.last[5] = (self.last[5] & 0x8F) | (self.tx_counter << 4);
        self.has_last = true;
        Some(&self.last)
    }

    /// The mailbox last returned by [`Self::next_response`], for an SM1
    /// repeat request (ETG.1000.4 §5.6: the master toggles the repeat bit
    /// when it lost a read; the slave writes the same mailbox again).
    pub fn last_response(&self) -> Option<&[u8]> {
        self.has_last.then_some(self.last.as_slice())
    }

    /// End transfers whose deadline has passed (silently; an FoE handler
    /// hears [`FoeEnd::Timeout`]). Returns the next deadline, `None` when
    /// nothing is timed.
    pub fn poll<F: FileHandler + ?Sized>(&mut self, now: Instant, files: &mut F) -> Option<Instant> {
        self.expire(now, files);
        match (self.coe.deadline(), self.foe.deadline()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn expire<F: FileHandler + ?Sized>(&mut self, now: Instant, files: &mut F) {
        self.coe.expire(now);
        self.foe.expire(now, files);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::foe::NoFiles;
    use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, Value};

    #[test]
    fn emergency_mailbox_and_counters() {
        let mut s = MailboxServer::new(MailboxConfig::default()).unwrap();
        assert!(!s.has_response());
        s.queue_emergency(0xFF01, 0x81, [9, 8, 7, 6, 5]).unwrap();
        assert!(s.has_response());
        let m = s.next_response(Instant::ZERO).unwrap().to_vec();
        assert_eq!(m, [10, 0, 0, 0, 0, 0x13, 0x00, 0x10, 0x01, 0xFF, 0x81, 9, 8, 7, 6, 5]);
        assert_eq!(s.last_response(), Some(&m[..]));
        assert_eq!(s.next_response(Instant::ZERO), None);
        // The next response takes the next counter.
        let mut dev = (ObjectDictionary::new(), NoHooks);
        dev.0.insert(Object::var(0x1000, "t", DataType::Unsigned8, Access::Ro, Value::U8(5)));
        let req = [10, 0, 0, 0, 0, 0x03, 0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0];
        s.handle_request(&req, Instant::ZERO, AlState::PreOp, &mut dev, &mut NoFiles);
        let m = s.next_response(Instant::ZERO).unwrap();
        assert_eq!(m, [10, 0, 0, 0, 0, 0x23, 0x00, 0x30, 0x4F, 0x00, 0x10, 0x00, 5, 0, 0, 0]);
        assert_eq!(s.stats().requests, 1);
    }
}
