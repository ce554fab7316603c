//! The PDO service: configuration state and the sans-IO runtime.

use crate::check::stored_entries;
use crate::cobid::{COB_NO_RTR, can_id, is_valid};
use crate::config::PdoConfig;
use crate::events::{EventQueue, PdoEvent};
use crate::mapping::{PdoKind, Plan, resolve};
use crate::objects::{
    SUB_COB_ID, SUB_EVENT_TIMER, SUB_INHIBIT_TIME, SUB_SYNC_START, SUB_TRANSMISSION_TYPE,
    TT_EVENT_MANUFACTURER, TT_EVENT_PROFILE, TT_EVENT_RTR, TT_SYNC_RTR, classify, comm_index, map_index,
};
use alloc::vec;
use alloc::vec::Vec;
use drivebus_can::{CanId, Frame, Instant, MAX_DATA_LEN, TxSink};
use drivebus_od::{ObjectDictionary, SdoAbort};

/// Number of 11-bit identifiers (size of the direct lookup tables).
const STD_IDS: usize = 0x800;

#[inline]
fn after(now: Instant, ns: u64) -> Instant {
    Instant::from_nanos(now.as_nanos().saturating_add(ns))
}

/// Configuration of one PDO as read from its records.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
struct Setup {
    /// `Some` only when the PDO is valid, its id usable and its mapping non-empty.
    id: Option<CanId>,
    /// RTR may trigger it (TPDO: device support and COB-ID bit 30 clear).
    rtr: bool,
    ttype: u8,
    inhibit_ns: u64,
    /// TPDO event timer / RPDO deadline, ns (0 = off).
    timer_ns: u64,
    start: u8,
    plan: Plan,
}

fn read_setup(od: &ObjectDictionary, cfg: &PdoConfig, kind: PdoKind, n: u16) -> Setup {
    let ci = comm_index(kind, n);
    let get = |sub| od.get_u64(ci, sub).unwrap_or(0);
    let cob = od.get_u32(ci, SUB_COB_ID).unwrap_or(crate::cobid::COB_INVALID);
    let plan = resolve(od, cfg, kind, &stored_entries(od, map_index(kind, n))).unwrap_or_default();
    // CiA 301 7.5.2.36: sub 0 = 0 disables the mapping; an empty PDO is treated as not existing.
    let id = if is_valid(cob) && !plan.segs.is_empty() { can_id(cob) } else { None };
    Setup {
        id,
        rtr: kind == PdoKind::Tpdo && cfg.rtr_supported && cob & COB_NO_RTR == 0,
        ttype: get(SUB_TRANSMISSION_TYPE) as u8,
        inhibit_ns: if kind == PdoKind::Tpdo { get(SUB_INHIBIT_TIME) * 100_000 } else { 0 },
        timer_ns: get(SUB_EVENT_TIMER) * 1_000_000,
        start: if kind == PdoKind::Tpdo { get(SUB_SYNC_START) as u8 } else { 0 },
        plan,
    }
}

#[derive(Clone, Debug, Default)]
struct Rpdo {
    s: Setup,
    latch: [u8; MAX_DATA_LEN],
    latched: bool,
    deadline: Option<Instant>,
    timed_out: bool,
}

impl Rpdo {
    fn reset(&mut self) {
        self.latched = false;
        self.deadline = None;
        self.timed_out = false;
    }
}

#[derive(Clone, Debug, Default)]
struct Tpdo {
    s: Setup,
    sync_count: u8,
    await_start: bool,
    /// Application event / RTR on an event-driven or acyclic TPDO.
    requested: bool,
    /// RTR on a synchronous TPDO: send at the next SYNC.
    rtr_pending: bool,
    last: [u8; MAX_DATA_LEN],
    has_last: bool,
    /// Type 252: data sampled at the last SYNC, sent on RTR.
    synced: [u8; MAX_DATA_LEN],
    has_synced: bool,
    next_allowed: Instant,
    event_deadline: Option<Instant>,
    /// Only these bits of the packed data count as a change of state
    /// (`None`: every bit). A device feature, kept across reconfiguration.
    change_mask: Option<[u8; MAX_DATA_LEN]>,
}

impl Tpdo {
    fn reset(&mut self) {
        self.sync_count = 0;
        self.await_start = self.s.start != 0;
        self.requested = false;
        self.rtr_pending = false;
        self.has_last = false;
        self.has_synced = false;
        self.next_allowed = Instant::ZERO;
        self.event_deadline = None;
    }

    /// Put `buf` on the bus and remember it; event-driven types restart
    /// their inhibit and event timers.
    #[inline]
    fn emit(&mut self, buf: &[u8; MAX_DATA_LEN], now: Instant, out: &mut impl TxSink) {
        let Some(id) = self.s.id else { return };
        let len = usize::from(self.s.plan.len);
        let frame = match id {
            // Full classic frame: built without a length-dependent copy.
            CanId::Standard(v) if len == 8 => Ok(Frame::new8(v, *buf)),
            _ => Frame::try_new(id, &buf[..len.min(MAX_DATA_LEN)]),
        };
        if let Ok(f) = frame {
            out.send(f);
        }
        self.last = *buf;
        self.has_last = true;
        self.requested = false;
        self.rtr_pending = false;
        if self.s.ttype >= TT_EVENT_RTR {
            self.next_allowed = after(now, self.s.inhibit_ns);
            self.event_deadline = (self.s.timer_ns != 0).then(|| after(now, self.s.timer_ns));
        }
    }

    #[inline]
    fn changed(&self, buf: &[u8; MAX_DATA_LEN]) -> bool {
        let n = usize::from(self.s.plan.len).min(MAX_DATA_LEN);
        if !self.has_last {
            return true;
        }
        match &self.change_mask {
            None => buf[..n] != self.last[..n],
            Some(m) => (0..n).any(|i| (buf[i] ^ self.last[i]) & m[i] != 0),
        }
    }
}

#[inline]
fn lookup(std: &[u16], ext: &[(u32, u16)], id: CanId) -> Option<usize> {
    match id {
        CanId::Standard(v) => match std.get(usize::from(v)) {
            Some(&x) if x != 0 => Some(usize::from(x) - 1),
            _ => None,
        },
        CanId::Extended(v) => ext.binary_search_by_key(&v, |e| e.0).ok().map(|i| usize::from(ext[i].1)),
    }
}

/// The PDO service of one device: every RPDO and TPDO, their lookup tables
/// and timers. Sans-IO: driven by [`Pdo::handle_frame`], [`Pdo::on_sync`]
/// and [`Pdo::poll`]; NMT gating (PDOs only in OPERATIONAL) is the node's.
///
/// [`EntryRef`](drivebus_od::EntryRef)s are resolved at configuration time:
/// after inserting or removing objects, or restoring defaults (1011h), call
/// [`Pdo::reload`].
#[derive(Clone, Debug)]
pub struct Pdo {
    cfg: PdoConfig,
    rpdos: Vec<Rpdo>,
    tpdos: Vec<Tpdo>,
    rx_std: Vec<u16>,
    rx_ext: Vec<(u32, u16)>,
    tx_std: Vec<u16>,
    tx_ext: Vec<(u32, u16)>,
    sync_rpdos: Vec<u16>,
    monitored_rpdos: Vec<u16>,
    sync_tpdos: Vec<u16>,
    event_tpdos: Vec<u16>,
    events: EventQueue,
    seen_gen: Option<u64>,
}

impl Pdo {
    /// Build the service from the objects [`crate::install`] created (and any
    /// defaults or stored values since).
    pub fn new(cfg: &PdoConfig, od: &ObjectDictionary) -> Pdo {
        let cfg = cfg.normalized();
        let mut p = Pdo {
            cfg,
            rpdos: vec![Rpdo::default(); usize::from(cfg.rpdo_count)],
            tpdos: vec![Tpdo::default(); usize::from(cfg.tpdo_count)],
            rx_std: if cfg.rpdo_count > 0 { vec![0; STD_IDS] } else { Vec::new() },
            rx_ext: Vec::new(),
            tx_std: if cfg.tpdo_count > 0 && cfg.rtr_supported { vec![0; STD_IDS] } else { Vec::new() },
            tx_ext: Vec::new(),
            sync_rpdos: Vec::new(),
            monitored_rpdos: Vec::new(),
            sync_tpdos: Vec::new(),
            event_tpdos: Vec::new(),
            events: EventQueue::new(),
            seen_gen: None,
        };
        p.reload(od);
        p
    }

    /// The (normalised) configuration.
    pub fn config(&self) -> &PdoConfig {
        &self.cfg
    }

    /// Check an SDO download to a PDO object before it is stored; the exact
    /// CiA 301 abort if refused. Indices that are not PDO objects of this
    /// device pass (`Ok`). Rules (CiA 301 7.5.2.35..38):
    ///
    /// * COB-ID: changing bits 0..29 while the PDO exists (bit 31 clear in
    ///   the old and new value), a restricted or malformed CAN-ID, or
    ///   creating a PDO whose stored mapping no longer resolves → `0609 0030`.
    /// * TPDO COB-ID with bit 30 clear (RTR allowed) on a device without RTR
    ///   support → `0609 0030`.
    /// * Transmission type 241..251, 252/253 on an RPDO or without RTR
    ///   support → `0609 0030`.
    /// * TPDO inhibit time or SYNC start value changed while the TPDO
    ///   exists → `0609 0030`; SYNC start value above 240 → `0609 0031`.
    /// * Mapping (sub 0 or entries) while the PDO exists → `0609 0030`; an
    ///   entry while sub 0 ≠ 0 → `0609 0030`; sub 0 above the maximum
    ///   number of entries → `0609 0031`; then per entry: absent object →
    ///   `0602 0000`, not mappable / wrong direction / wrong length /
    ///   unsupported dummy → `0604 0041`; total above the PDO length →
    ///   `0604 0042`.
    /// * A value of the wrong size → `0607 0012` / `0607 0013`.
    pub fn check_write(
        &self,
        od: &ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        crate::check::check_write(&self.cfg, od, index, sub, data)
    }

    /// Re-read the PDO that `index` belongs to after a write was stored.
    /// Its runtime state restarts if its configuration changed.
    pub fn reconfigure(&mut self, od: &ObjectDictionary, index: u16, sub: u8) {
        let _ = sub;
        if let Some((kind, n, _)) = classify(&self.cfg, index) {
            self.load(od, kind, n);
            self.rebuild_tables();
        }
    }

    /// Re-read every PDO (after restore defaults, a node-id change, or an
    /// object inserted/removed, which invalidates resolved entries).
    pub fn reload(&mut self, od: &ObjectDictionary) {
        for n in 0..self.cfg.rpdo_count {
            self.load(od, PdoKind::Rpdo, n);
        }
        for n in 0..self.cfg.tpdo_count {
            self.load(od, PdoKind::Tpdo, n);
        }
        self.rebuild_tables();
    }

    fn load(&mut self, od: &ObjectDictionary, kind: PdoKind, n: u16) {
        let s = read_setup(od, &self.cfg, kind, n);
        match kind {
            PdoKind::Rpdo => {
                if let Some(p) = self.rpdos.get_mut(usize::from(n))
                    && p.s != s
                {
                    p.s = s;
                    p.reset();
                }
            }
            PdoKind::Tpdo => {
                if let Some(t) = self.tpdos.get_mut(usize::from(n))
                    && t.s != s
                {
                    t.s = s;
                    t.reset();
                }
            }
        }
    }

    fn rebuild_tables(&mut self) {
        self.rx_std.fill(0);
        self.tx_std.fill(0);
        self.rx_ext.clear();
        self.tx_ext.clear();
        self.sync_rpdos.clear();
        self.monitored_rpdos.clear();
        self.sync_tpdos.clear();
        self.event_tpdos.clear();
        // Reverse order so the lowest-numbered PDO wins a shared 11-bit id.
        for (n, p) in self.rpdos.iter().enumerate().rev() {
            if let Some(CanId::Standard(v)) = p.s.id
                && let Some(x) = self.rx_std.get_mut(usize::from(v))
            {
                *x = n as u16 + 1;
            }
        }
        for (n, p) in self.rpdos.iter().enumerate() {
            if let Some(id) = p.s.id {
                if let CanId::Extended(v) = id {
                    self.rx_ext.push((v, n as u16));
                }
                if p.s.ttype <= 240 {
                    self.sync_rpdos.push(n as u16);
                }
                if p.s.timer_ns != 0 {
                    self.monitored_rpdos.push(n as u16);
                }
            }
        }
        for (n, t) in self.tpdos.iter().enumerate().rev() {
            if t.s.rtr
                && let Some(CanId::Standard(v)) = t.s.id
                && let Some(x) = self.tx_std.get_mut(usize::from(v))
            {
                *x = n as u16 + 1;
            }
        }
        for (n, t) in self.tpdos.iter().enumerate() {
            if let Some(id) = t.s.id {
                if let (true, CanId::Extended(v)) = (t.s.rtr, id) {
                    self.tx_ext.push((v, n as u16));
                }
                match t.s.ttype {
                    0..=240 | TT_SYNC_RTR => self.sync_tpdos.push(n as u16),
                    TT_EVENT_MANUFACTURER | TT_EVENT_PROFILE => self.event_tpdos.push(n as u16),
                    // 253 runs on RTR only; 241..=251 are reserved and never sent.
                    _ => {}
                }
            }
        }
        // Stable sort keeps the lowest PDO number first among equal ids.
        self.rx_ext.sort_by_key(|e| e.0);
        self.rx_ext.dedup_by_key(|e| e.0);
        self.tx_ext.sort_by_key(|e| e.0);
        self.tx_ext.dedup_by_key(|e| e.0);
        self.seen_gen = None;
    }

    /// NMT reset / stop / leaving OPERATIONAL: drop latched data, timers,
    /// pending requests and queued events. Event-driven TPDOs send their
    /// current data at the first [`Pdo::poll`] afterwards.
    pub fn reset(&mut self) {
        self.rpdos.iter_mut().for_each(Rpdo::reset);
        self.tpdos.iter_mut().for_each(Tpdo::reset);
        self.events.clear();
        self.seen_gen = None;
    }

    /// Application-triggered event for TPDO `n` (0-based): an acyclic
    /// synchronous TPDO (type 0) goes out at the next SYNC, an event-driven
    /// one (254/255) at the next [`Pdo::poll`] the inhibit time allows.
    /// `false` if the TPDO does not exist or is not active.
    pub fn request_tpdo(&mut self, n: u16) -> bool {
        match self.tpdos.get_mut(usize::from(n)) {
            Some(t) if t.s.id.is_some() => {
                t.requested = true;
                self.seen_gen = None;
                true
            }
            _ => false,
        }
    }

    /// Restrict change-of-state detection of TPDO `n` (0-based) to the bits
    /// set in `mask` (byte `i` masks byte `i` of the PDO); `None` restores
    /// "any change". Drives use this for "send on statusword change only"
    /// and for the KC1/AKD TPDO masks 2014h–2017h. The event timer still
    /// sends regardless. `false` if the TPDO does not exist.
    pub fn set_change_mask(&mut self, n: u16, mask: Option<[u8; MAX_DATA_LEN]>) -> bool {
        match self.tpdos.get_mut(usize::from(n)) {
            Some(t) => {
                t.change_mask = mask;
                true
            }
            None => false,
        }
    }

    /// Whether events are queued (a cheap check before draining them).
    #[inline]
    pub fn has_events(&self) -> bool {
        !self.events.is_empty()
    }

    /// Next queued event (events from [`Pdo::on_sync`], [`Pdo::poll`] and
    /// any beyond the first of [`Pdo::handle_frame`]). Drain after each call.
    pub fn pop_event(&mut self) -> Option<PdoEvent> {
        self.events.pop()
    }

    /// The entries the active event-driven TPDOs (254/255) map: a change of
    /// one of them is a change of state the next [`Pdo::poll`] must see (a
    /// node marks them so it polls the PDO service only then).
    pub fn event_mapped(&self) -> impl Iterator<Item = drivebus_od::EntryRef> + '_ {
        self.event_tpdos
            .iter()
            .filter_map(|&n| self.tpdos.get(usize::from(n)))
            .flat_map(|t| t.s.plan.segs.iter().filter_map(|s| s.r))
    }

    /// Some active event-driven TPDO maps a live entry (refreshed by its
    /// owner on every sample): such a TPDO can change without a write.
    pub fn event_live(&self) -> bool {
        self.event_tpdos.iter().filter_map(|&n| self.tpdos.get(usize::from(n))).any(|t| t.s.plan.hooked)
    }

    /// Events dropped because the queue was full.
    pub fn events_lost(&self) -> u32 {
        self.events.lost
    }

    /// True if PDO `n` exists, is valid and has a non-empty mapping.
    pub fn is_active(&self, kind: PdoKind, n: u16) -> bool {
        self.setup(kind, n).is_some_and(|s| s.id.is_some())
    }

    /// The CAN identifier of an active PDO.
    pub fn can_id(&self, kind: PdoKind, n: u16) -> Option<CanId> {
        self.setup(kind, n).and_then(|s| s.id)
    }

    /// Mapped length in bytes of PDO `n` (0 when unmapped).
    pub fn mapped_len(&self, kind: PdoKind, n: u16) -> Option<usize> {
        self.setup(kind, n).map(|s| usize::from(s.plan.len))
    }

    fn setup(&self, kind: PdoKind, n: u16) -> Option<&Setup> {
        match kind {
            PdoKind::Rpdo => self.rpdos.get(usize::from(n)).map(|p| &p.s),
            PdoKind::Tpdo => self.tpdos.get(usize::from(n)).map(|t| &t.s),
        }
    }
}

mod runtime;
