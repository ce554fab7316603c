//! [`Node`]: one CiA 301 device.

use crate::app::{Application, NodeEvent};
use crate::config::NodeConfig;
use crate::dictionary::{build_dictionary, mark_node_relative, rebase_node_id};
use crate::hooks::{CommHooks, Services};
use crate::storage::{MemoryStorage, Slot, Storage, apply_image};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::{CanId, Frame, Instant, TxSink, earliest};
use drivebus_emcy::{Emcy, EmcyConsumer, register_bit_for};
use drivebus_lss::{LssAddress, LssEvent, LssSlave, StoreStatus};
use drivebus_nmt::{ErrorClass, InitSubState, Nmt, NmtCommand, NmtEvent, NmtState, Service};
use drivebus_od::{ObjectDictionary, PersistGroup};
use drivebus_pdo::{Pdo, PdoRx};
use drivebus_sdo::server::{FIRST_PARAM_INDEX, SdoServer};
use drivebus_sync::{SyncService, TimeService};

/// EMCY for a heartbeat or life-guarding loss (CiA 301 Table 21).
const EMCY_GUARD: u16 = 0x8130;
/// EMCY for a SYNC with the wrong length (CiA 301 Table 21).
const EMCY_SYNC_LEN: u16 = 0x8240;
/// 1029h class of communication errors (sub 1).
const COMM_ERROR: ErrorClass = ErrorClass(1);

/// A complete CiA 301 device: the services of the communication profile
/// over one object dictionary, sans-IO.
///
/// Drive it with [`Node::boot`] once, then [`Node::handle_frame`] for every
/// received frame and [`Node::poll`] at (or after) the deadline it returns.
/// Application behaviour plugs in through an [`Application`] passed to each
/// call, so the node never owns or knows the application.
pub struct Node {
    cfg: NodeConfig,
    od: ObjectDictionary,
    s: Services,
    sdo: Vec<SdoServer>,
    lss: Option<LssSlave>,
    node_id: u8,
    /// Service behind each 11-bit identifier (see `route`), rebuilt when a
    /// COB-ID changes: frame dispatch is one table load.
    routes: Vec<u8>,
    /// The deadline the last full poll computed, and what it depended on:
    /// an idle poll before it returns at once.
    next_deadline: Option<Instant>,
    polled_generation: u64,
    dirty: bool,
}

/// Route codes in [`Node::routes`].
mod route {
    pub const NONE: u8 = 0;
    pub const NMT: u8 = 1;
    pub const ERROR_CONTROL: u8 = 2;
    pub const LSS: u8 = 3;
    pub const SYNC: u8 = 4;
    pub const TIME: u8 = 5;
    pub const EMCY_CONSUMER: u8 = 6;
    pub const PDO: u8 = 7;
    /// SDO server `i` is `SDO + i`.
    pub const SDO: u8 = 8;
}

impl Node {
    /// A device with the dictionary `NodeConfig` describes and parameters
    /// stored in memory.
    pub fn new(cfg: NodeConfig) -> Node {
        Node::with_storage(cfg, Box::new(MemoryStorage::new()))
    }

    /// A device whose 1010h/1011h parameters live in `storage`.
    pub fn with_storage(cfg: NodeConfig, storage: Box<dyn Storage + Send>) -> Node {
        let od = build_dictionary(&cfg, cfg.node_id);
        Node::with_dictionary(cfg, od, storage)
    }

    /// A device around an existing dictionary (e.g. built from an EDS):
    /// communication objects it lacks are added, those it has keep their
    /// descriptions but are routed to the services.
    pub fn with_dictionary(
        mut cfg: NodeConfig,
        mut od: ObjectDictionary,
        storage: Box<dyn Storage + Send>,
    ) -> Node {
        let node_id =
            if (1..=127).contains(&cfg.node_id) || cfg.node_id == 0xFF { cfg.node_id } else { 0xFF };
        cfg.node_id = node_id;
        cfg.nmt.node_id = node_id;
        let generated = build_dictionary(&cfg, node_id);
        crate::dictionary::merge_services(&mut od, &generated);
        mark_node_relative(&cfg, &generated, node_id, &mut od);
        // CiA 305 §3.2: the LSS address is 1018h:01h–04h. A dictionary
        // from elsewhere (an EDS) keeps its own 1018h, so the identity is
        // read back from it: one source for SDO and LSS.
        let ident = &mut cfg.identity;
        for (sub, part) in [
            (1, &mut ident.vendor_id),
            (2, &mut ident.product_code),
            (3, &mut ident.revision),
            (4, &mut ident.serial),
        ] {
            if let Some(v) = od.get_u32(0x1018, sub) {
                *part = v;
            }
        }
        let s = Services {
            nmt: Nmt::new(cfg.nmt),
            pdo: Pdo::new(&cfg.pdo, &od),
            emcy: Emcy::install(&mut ObjectDictionary::new(), node_id, cfg.emcy_history),
            emcy_consumer: None,
            sync: SyncService::install(&mut ObjectDictionary::new(), node_id),
            time: None,
            storage,
            sdo_params_dirty: false,
            comm_changed: false,
            pending_nmt: None,
            now: Instant::ZERO,
            #[cfg(feature = "std")]
            eds_info: (cfg.lss, cfg.eds_device_info.clone()),
        };
        let lss = cfg.lss.then(|| {
            let id = cfg.identity;
            LssSlave::new(
                LssAddress {
                    vendor_id: id.vendor_id,
                    product_code: id.product_code,
                    revision: id.revision,
                    serial: id.serial,
                },
                node_id,
                0,
            )
        });
        let mut node = Node {
            cfg,
            od,
            s,
            sdo: Vec::new(),
            lss,
            node_id,
            routes: alloc::vec![route::NONE; 0x800],
            next_deadline: None,
            polled_generation: 0,
            dirty: true,
        };
        node.load_lss_config();
        node
    }

    /// The object dictionary.
    pub fn od(&self) -> &ObjectDictionary {
        &self.od
    }
    /// The object dictionary, for the application to push live values
    /// (`set_le`, `set_raw`, `write_local`). Add objects with
    /// [`Node::insert_object`], not through this reference: services hold
    /// resolved handles into the dictionary.
    pub fn od_mut(&mut self) -> &mut ObjectDictionary {
        self.dirty = true;
        &mut self.od
    }

    /// Add (or replace) an object and re-resolve every service's handles.
    pub fn insert_object(&mut self, obj: drivebus_od::Object) {
        self.od.insert(obj);
        self.s.pdo.reload(&self.od);
        self.rebuild_routes();
        self.dirty = true;
    }
    /// The configuration the node was built from.
    pub fn config(&self) -> &NodeConfig {
        &self.cfg
    }
    /// The active node-ID (FFh while unconfigured).
    pub fn node_id(&self) -> u8 {
        self.node_id
    }
    /// The NMT state.
    pub fn nmt_state(&self) -> NmtState {
        self.s.nmt.state()
    }
    /// The EMCY producer (active errors, 1001h, history).
    pub fn emcy(&self) -> &Emcy {
        &self.s.emcy
    }
    /// The PDO service.
    pub fn pdo(&self) -> &Pdo {
        &self.s.pdo
    }
    /// The NMT and error-control service.
    pub fn nmt(&self) -> &Nmt {
        &self.s.nmt
    }
    /// The SYNC service.
    pub fn sync(&self) -> &SyncService {
        &self.s.sync
    }
    /// The parameter storage.
    pub fn storage_mut(&mut self) -> &mut (dyn Storage + Send) {
        &mut *self.s.storage
    }

    /// Power on: load stored parameters, start the services, send the
    /// boot-up message and enter pre-operational. An unconfigured node
    /// (node-ID FFh) stays silent, answering only LSS.
    pub fn boot<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A, out: &mut impl TxSink) {
        self.s.now = now;
        self.load_groups(&[Slot::Manufacturer, Slot::Application, Slot::Communication]);
        self.start_communication(now, app, out);
    }

    /// Signal an error: 1001h, 1003h and an EMCY frame (CiA 301 §7.2.7).
    /// Returns false if the code was already active.
    pub fn raise_emcy(&mut self, code: u16, manufacturer: [u8; 5], now: Instant) -> bool {
        self.dirty = true;
        self.s.emcy.raise(&mut self.od, code, register_bit_for(code), manufacturer, now)
    }

    /// Signal an error with explicit 1001h bits.
    pub fn raise_emcy_with_register(
        &mut self,
        code: u16,
        register: u8,
        manufacturer: [u8; 5],
        now: Instant,
    ) -> bool {
        self.dirty = true;
        self.s.emcy.raise(&mut self.od, code, register, manufacturer, now)
    }

    /// An error went away (the error-reset EMCY goes when the last clears).
    pub fn clear_emcy(&mut self, code: u16, now: Instant) -> bool {
        self.dirty = true;
        self.s.emcy.clear(&mut self.od, code, now)
    }

    /// Every active error went away.
    pub fn clear_all_emcy(&mut self, now: Instant) {
        self.dirty = true;
        self.s.emcy.clear_all(&mut self.od, now)
    }

    /// Record an entry in the 1003h history without an EMCY frame (a
    /// personality that sends its own frame with [`Node::send_raw_emcy`]):
    /// low 16 bits the error code, high 16 bits additional information.
    pub fn record_emcy_history(&mut self, entry: u32) {
        self.dirty = true;
        self.s.emcy.record(&mut self.od, entry)
    }

    /// Send an EMCY outside the error bookkeeping (personality quirks).
    pub fn send_raw_emcy(&mut self, code: u16, register: u8, bytes: [u8; 5], now: Instant) {
        self.dirty = true;
        self.s.emcy.send_raw(code, register, bytes, now)
    }

    /// Restrict change-of-state detection of TPDO `n` (0-based) to the bits
    /// of `mask` (see `drivebus_pdo::Pdo::set_change_mask`).
    pub fn set_tpdo_change_mask(&mut self, n: u16, mask: Option<[u8; drivebus_can::MAX_DATA_LEN]>) -> bool {
        self.dirty = true;
        self.s.pdo.set_change_mask(n, mask)
    }

    /// Send a TIME stamp if this node is the TIME producer (1012h bit 30)
    /// and TIME is allowed in the current NMT state. Returns whether it went.
    pub fn send_time(&mut self, time: drivebus_sync::TimeOfDay, out: &mut impl TxSink) -> bool {
        match &self.s.time {
            Some(t) if self.s.nmt.state().allows(Service::Time) => t.transmit(time, out),
            _ => false,
        }
    }

    /// Ask for an event-driven / acyclic TPDO (0-based number).
    pub fn request_tpdo(&mut self, n: u16) -> bool {
        self.dirty = true;
        self.s.pdo.request_tpdo(n)
    }

    /// A local NMT transition (e.g. the application stopping on a fault).
    pub fn set_nmt_state<A: Application + ?Sized>(
        &mut self,
        to: NmtState,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        self.dirty = true;
        if let Some(ev) = self.s.nmt.set_state(to) {
            self.on_nmt_event(ev, now, app, out);
        }
    }

    /// A local NMT command: the device acts on it as on one received for
    /// its node-ID (state change, reset node, reset communication with
    /// boot-up), but [`drivebus_nmt::NmtConfig::supported_commands`] does
    /// not apply — that set limits what a master may send, not what the
    /// device's own application does (e.g. "operational after power-on").
    pub fn nmt_command<A: Application + ?Sized>(
        &mut self,
        cmd: NmtCommand,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let to = match cmd {
            NmtCommand::Start => NmtState::Operational,
            NmtCommand::Stop => NmtState::Stopped,
            NmtCommand::EnterPreOperational => NmtState::PreOperational,
            NmtCommand::ResetNode => NmtState::Initialisation(InitSubState::ResetApplication),
            NmtCommand::ResetCommunication => NmtState::Initialisation(InitSubState::ResetCommunication),
        };
        self.s.now = now;
        self.set_nmt_state(to, now, app, out);
    }

    /// Handle one received frame.
    pub fn handle_frame<A: Application + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        self.s.now = now;
        let Some(id) = frame.std_id() else {
            // 29-bit identifiers can carry PDOs, SYNC and SDOs when configured.
            self.dirty = true;
            if !self.s.nmt.state().is_initialisation() {
                self.dispatch_configurable(frame, now, app, out);
            }
            return;
        };
        let r = self.routes[usize::from(id & 0x7FF)];
        if r == route::LSS {
            self.dirty = true;
            self.on_lss_frame(frame, now, app, out);
            return;
        }
        let state = self.s.nmt.state();
        if state.is_initialisation() {
            return;
        }
        match r {
            route::NONE => {}
            route::NMT | route::ERROR_CONTROL => {
                self.dirty = true;
                if let Some(ev) = self.s.nmt.handle_frame(frame, now, out) {
                    self.on_nmt_event(ev, now, app, out);
                }
            }
            r if r >= route::SDO => {
                let i = usize::from(r - route::SDO);
                if state.allows(Service::Sdo) && i < self.sdo.len() {
                    let mut hooks = CommHooks { s: &mut self.s, app };
                    self.sdo[i].handle_frame(frame, now, &mut self.od, &mut hooks, out);
                    // A transfer only moves this server's own timeout: fold
                    // it into the cached deadline rather than forcing a full
                    // poll (an early wake-up is harmless, a late one is not).
                    let d = self.sdo[i].poll(now, out);
                    self.next_deadline = earliest(self.next_deadline, d);
                    self.after_sdo_write(now, app, out);
                }
            }
            route::PDO if state.allows(Service::Pdo) => {
                self.dirty = true;
                let rx = self.s.pdo.handle_frame(frame, now, &mut self.od, &mut AppOnly(&mut *app), out);
                match rx {
                    PdoRx::Event(ev) => {
                        self.on_pdo_event(ev, now, app);
                        self.drain_pdo_events(now, app);
                    }
                    // Events beyond the first are only queued when a first was returned.
                    PdoRx::Handled => {}
                    // Not a PDO after all (e.g. an RTR on an RPDO id): the
                    // other services sharing identifiers get a look.
                    PdoRx::NotPdo => self.dispatch_configurable(frame, now, app, out),
                }
            }
            _ => {
                self.dirty = true;
                self.dispatch_configurable(frame, now, app, out);
            }
        }
    }

    /// Rebuild the identifier → service table from the services' current
    /// COB-IDs (after boot and after any communication object changed).
    fn rebuild_routes(&mut self) {
        let t = &mut self.routes;
        t.iter_mut().for_each(|x| *x = route::NONE);
        let mut set = |id: Option<CanId>, r: u8| {
            if let Some(CanId::Standard(i)) = id {
                t[usize::from(i & 0x7FF)] = r;
            }
        };
        // Lowest priority first: later entries win a shared identifier,
        // in the order dispatch_configurable checks them.
        let cfg = *self.s.pdo.config();
        for n in 0..cfg.rpdo_count {
            set(self.s.pdo.can_id(drivebus_pdo::PdoKind::Rpdo, n), route::PDO);
        }
        for n in 0..cfg.tpdo_count {
            set(self.s.pdo.can_id(drivebus_pdo::PdoKind::Tpdo, n), route::PDO);
        }
        if let Some(o) = self.od.object(0x1028) {
            for sub in o.subs().iter().skip(1) {
                let cob = drivebus_od::le_u64(sub.bytes()) as u32;
                if cob & 0xA000_0000 == 0 {
                    set(CanId::standard((cob & 0x7FF) as u16), route::EMCY_CONSUMER);
                }
            }
        }
        if self.s.time.is_some()
            && let Some(cob) = self.od.get_u32(0x1012, 0)
            && cob & 0xA000_0000 == 0x8000_0000
        {
            set(CanId::standard((cob & 0x7FF) as u16), route::TIME);
        }
        for (i, s) in self.sdo.iter().enumerate().take(usize::from(u8::MAX - route::SDO)) {
            set(s.rx_cob_id(), route::SDO + i as u8);
        }
        set(Some(self.s.sync.can_id()), route::SYNC);
        t[0x000] = route::NMT;
        for x in &mut t[0x701..=0x77F] {
            *x = route::ERROR_CONTROL;
        }
        t[usize::from(drivebus_lss::MASTER_TO_SLAVE)] =
            if self.lss.is_some() { route::LSS } else { route::NONE };
    }

    /// Frames whose identifiers come from the dictionary: SYNC, TIME, EMCY
    /// consumer, SDO servers, RPDOs and TPDO remote requests.
    fn dispatch_configurable<A: Application + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let state = self.s.nmt.state();
        let fid = frame.id();
        if fid == self.s.sync.can_id() {
            if state.allows(Service::Sync)
                && let Some(ev) = self.s.sync.handle_frame(frame, now)
            {
                if ev.length_error.is_some() {
                    self.raise_emcy(EMCY_SYNC_LEN, [0; 5], now);
                }
                self.on_sync(ev.counter, now, app, out);
            }
            return;
        }
        if state.allows(Service::Sdo) {
            for i in 0..self.sdo.len() {
                if self.sdo[i].rx_cob_id() == Some(fid) {
                    let mut hooks = CommHooks { s: &mut self.s, app };
                    self.sdo[i].handle_frame(frame, now, &mut self.od, &mut hooks, out);
                    self.after_sdo_write(now, app, out);
                    return;
                }
            }
        }
        if let Some(t) = &self.s.time
            && state.allows(Service::Time)
            && let Some(tod) = t.handle_frame(frame)
        {
            app.on_event(&mut self.od, NodeEvent::Time(tod), now);
            return;
        }
        if let Some(c) = &self.s.emcy_consumer
            && state.allows(Service::Emcy)
            && let Some(rx) = c.handle_frame(frame)
        {
            app.on_event(&mut self.od, NodeEvent::Emcy(rx), now);
            return;
        }
        if state.allows(Service::Pdo) {
            let rx = self.s.pdo.handle_frame(frame, now, &mut self.od, &mut AppOnly(&mut *app), out);
            if let PdoRx::Event(ev) = rx {
                self.on_pdo_event(ev, now, app);
            }
            self.drain_pdo_events(now, app);
        }
    }

    /// Do the timed work due at `now`; returns when to call again.
    pub fn poll<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) -> Option<Instant> {
        // Nothing received, nothing written and no deadline reached since
        // the last full poll: nothing can be due.
        if !self.dirty
            && self.od.generation() == self.polled_generation
            && self.next_deadline.is_none_or(|d| now < d)
        {
            return self.next_deadline;
        }
        let next = self.poll_services(now, app, out);
        self.dirty = false;
        self.polled_generation = self.od.generation();
        self.next_deadline = next;
        next
    }

    fn poll_services<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) -> Option<Instant> {
        self.s.now = now;
        let state = self.s.nmt.state();
        if state.is_initialisation() {
            return None;
        }
        let mut next = self.s.nmt.poll(now, out);
        while let Some(ev) = self.s.nmt.pop_event() {
            self.on_nmt_event(ev, now, app, out);
        }
        if state.allows(Service::Sync) {
            let sp = self.s.sync.poll(now, out);
            if let Some(ev) = sp.produced {
                self.on_sync(ev.counter, now, app, out);
            }
            if sp.timeout.is_some() {
                app.on_event(&mut self.od, NodeEvent::SyncTimeout, now);
            }
            next = earliest(next, sp.next);
        }
        if self.s.nmt.state().allows(Service::Pdo) {
            next = earliest(next, self.s.pdo.poll(now, &mut self.od, &mut AppOnly(&mut *app), out));
            self.drain_pdo_events(now, app);
        }
        for s in &mut self.sdo {
            next = earliest(next, s.poll(now, out));
        }
        if self.s.nmt.state().allows(Service::Emcy) {
            next = earliest(next, self.s.emcy.poll(now, out));
        } else {
            // Stopped: EMCYs are not sent (CiA 301 §7.3.2.2) and not kept.
            self.s.emcy.discard_queue();
        }
        next
    }

    fn on_sync<A: Application + ?Sized>(
        &mut self,
        counter: Option<u8>,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        if self.s.nmt.state().allows(Service::Pdo) {
            self.s.pdo.on_sync(counter, now, &mut self.od, &mut AppOnly(&mut *app), out);
            self.drain_pdo_events(now, app);
        }
        app.on_sync(&mut self.od, counter, now);
    }

    fn drain_pdo_events<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A) {
        while let Some(ev) = self.s.pdo.pop_event() {
            self.on_pdo_event(ev, now, app);
        }
    }

    fn on_pdo_event<A: Application + ?Sized>(
        &mut self,
        ev: drivebus_pdo::PdoEvent,
        now: Instant,
        app: &mut A,
    ) {
        match ev {
            drivebus_pdo::PdoEvent::RpdoResumed { .. } => {
                self.s.emcy.clear(&mut self.od, 0x8250, now);
            }
            drivebus_pdo::PdoEvent::RpdoTimeout { rpdo } => {
                app.on_event(&mut self.od, NodeEvent::RpdoTimeout { rpdo }, now);
            }
            _ => {}
        }
        if let Some(code) = ev.emcy_code() {
            self.raise_emcy(code, [0; 5], now);
        }
    }

    /// Follow-ups of an SDO write that could not run inside the hook: an
    /// NMT event from reconfiguring error control, rebuilt SDO servers.
    fn after_sdo_write<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A, out: &mut impl TxSink) {
        if let Some(ev) = self.s.pending_nmt.take() {
            self.on_nmt_event(ev, now, app, out);
        }
        if core::mem::take(&mut self.s.comm_changed) {
            self.dirty = true;
            self.rebuild_routes();
        }
        if core::mem::take(&mut self.s.sdo_params_dirty) {
            for s in &mut self.sdo {
                if let Some(i) = s.param_index() {
                    s.reconfigure(&self.od, i);
                }
            }
            self.rebuild_routes();
        }
    }

    fn on_nmt_event<A: Application + ?Sized>(
        &mut self,
        ev: NmtEvent,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let od = &mut self.od;
        match ev {
            NmtEvent::StateChanged { from, to } => {
                if from == NmtState::Operational {
                    // Leaving operational drops latched synchronous data and timers.
                    self.s.pdo.reset();
                }
                if to == NmtState::Stopped {
                    // SDO is not available in stopped: transfers end silently.
                    self.sdo.iter_mut().for_each(SdoServer::reset);
                    self.s.emcy.discard_queue();
                }
                app.on_event(od, NodeEvent::NmtState { from, to }, now);
            }
            NmtEvent::ResetApplication => {
                app.on_event(od, NodeEvent::ResetApplication, now);
                self.reset_groups(&[PersistGroup::Manufacturer, PersistGroup::Application]);
                self.reset_communication(now, app, out);
            }
            NmtEvent::ResetCommunication => self.reset_communication(now, app, out),
            NmtEvent::HeartbeatTimeout { node } => {
                self.comm_error(now, app, out);
                app.on_event(&mut self.od, NodeEvent::HeartbeatTimeout { node }, now);
            }
            NmtEvent::HeartbeatRecovered { node, .. } => {
                self.comm_recovered(now);
                app.on_event(&mut self.od, NodeEvent::HeartbeatRecovered { node }, now);
            }
            NmtEvent::RemoteBootup { node } => app.on_event(od, NodeEvent::RemoteBootup { node }, now),
            NmtEvent::RemoteStateChange { node, state } => {
                app.on_event(od, NodeEvent::RemoteState { node, state }, now)
            }
            NmtEvent::LifeGuardingLost => {
                self.comm_error(now, app, out);
                app.on_event(&mut self.od, NodeEvent::LifeGuardingLost, now);
            }
            NmtEvent::LifeGuardingResolved => {
                self.comm_recovered(now);
                app.on_event(&mut self.od, NodeEvent::LifeGuardingResolved, now);
            }
        }
    }

    /// A communication error: EMCY 8130h and the 1029h reaction.
    fn comm_error<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A, out: &mut impl TxSink) {
        self.raise_emcy(EMCY_GUARD, [0; 5], now);
        if let Some(ev) = self.s.nmt.on_error(COMM_ERROR) {
            self.on_nmt_event(ev, now, app, out);
        }
    }

    fn comm_recovered(&mut self, now: Instant) {
        let any_lost = self.s.nmt.is_life_guarding_lost()
            || self.s.nmt.consumer_entries().any(|e| self.s.nmt.is_heartbeat_timed_out(e.node));
        if !any_lost {
            self.clear_emcy(EMCY_GUARD, now);
        }
    }

    /// Reset communication (CiA 301 §7.3.2.1): communication parameters to
    /// their power-on values, a pending LSS node-ID becomes active, then
    /// boot-up.
    fn reset_communication<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        if let Some(lss) = &mut self.lss {
            let id = lss.reset_communication();
            if id != self.node_id {
                rebase_node_id(&mut self.od, self.node_id, id);
                self.node_id = id;
                self.cfg.node_id = id;
                self.cfg.nmt.node_id = id;
                self.s.nmt.set_node_id(id);
            }
        }
        self.reset_groups(&[PersistGroup::Communication]);
        app.on_event(&mut self.od, NodeEvent::ResetCommunication, now);
        self.start_communication(now, app, out);
    }

    /// Defaults, then stored values, for `groups`.
    fn reset_groups(&mut self, groups: &[PersistGroup]) {
        self.od.restore_defaults(|_, s| groups.contains(&s.persist));
        let slots: Vec<Slot> = groups.iter().filter_map(|g| Slot::of(*g)).collect();
        self.load_groups(&slots);
    }

    fn load_groups(&mut self, slots: &[Slot]) {
        for &slot in slots {
            let group = match slot {
                Slot::Communication => PersistGroup::Communication,
                Slot::Application => PersistGroup::Application,
                Slot::Manufacturer => PersistGroup::Manufacturer,
                Slot::Lss => continue,
            };
            // A missing, unreadable or corrupt image leaves the defaults:
            // better a node with defaults than no node.
            if let Ok(Some(img)) = self.s.storage.load(slot) {
                let _ = apply_image(&mut self.od, group, &img);
            }
        }
    }

    /// The node-ID stored by LSS "store configuration" wins over the configured one.
    fn load_lss_config(&mut self) {
        let Some(lss) = &self.lss else { return };
        let Ok(Some(img)) = self.s.storage.load(Slot::Lss) else { return };
        if img.len() == 2 && (drivebus_lss::is_configurable_node_id(img[0])) && img[0] != self.node_id {
            let id = img[0];
            let mut l = LssSlave::new(*lss.identity(), id, img[1]);
            core::mem::swap(self.lss.as_mut().expect("checked above"), &mut l);
            rebase_node_id(&mut self.od, self.node_id, id);
            self.node_id = id;
            self.cfg.node_id = id;
            self.cfg.nmt.node_id = id;
            self.s.nmt.set_node_id(id);
        }
    }

    /// Re-read every service's configuration and boot (or wait for LSS).
    fn start_communication<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let id = self.node_id;
        self.s.emcy.reconfigure_all(&mut self.od);
        self.s.emcy.clear_history(&mut self.od);
        self.s.emcy_consumer = if self.cfg.emcy_consumers > 0 {
            let mut c = EmcyConsumer::install(&mut ObjectDictionary::new(), self.cfg.emcy_consumers);
            c.reconfigure_all(&self.od);
            Some(c)
        } else {
            None
        };
        self.s.sync.reconfigure_all(&self.od);
        self.s.sync.reset_counter();
        self.s.time = if self.cfg.time {
            let mut t = TimeService::install(&mut ObjectDictionary::new());
            t.reconfigure(&self.od, drivebus_sync::OD_COB_ID_TIME, 0);
            Some(t)
        } else {
            None
        };
        self.s.pdo.reload(&self.od);
        self.s.pdo.reset();
        self.sdo = SdoServer::servers_from_od(&self.od, self.cfg.sdo);
        if self.od.object(FIRST_PARAM_INDEX).is_none() {
            // No 1200h: the default server on its pre-defined identifiers
            // (CiA 301 §7.3.5), 600h/580h + node-ID.
            let sid = u16::from(if (1..=127).contains(&id) { id } else { 1 });
            let (rx, tx) = (CanId::Standard(0x600 + sid), CanId::Standard(0x580 + sid));
            self.sdo.insert(0, SdoServer::new(rx, tx, self.cfg.sdo));
        }
        self.rebuild_routes();
        self.dirty = true;
        if !(1..=127).contains(&id) {
            return;
        }
        if let Some(ev) = self.s.nmt.boot(&self.od, now, out) {
            self.on_nmt_event(ev, now, app, out);
        }
    }

    fn on_lss_frame<A: Application + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let Some(lss) = &mut self.lss else { return };
        let Some(ev) = lss.handle_frame(frame, now, out) else { return };
        match ev {
            LssEvent::NodeIdConfigured(id) => app.on_event(&mut self.od, NodeEvent::LssNodeId(id), now),
            LssEvent::StoreRequested { node_id, bit_timing } => {
                let status = match self.s.storage.save(Slot::Lss, &[node_id, bit_timing]) {
                    Ok(()) => StoreStatus::Stored,
                    Err(_) => StoreStatus::AccessError,
                };
                lss.complete_store(status, out);
            }
            LssEvent::ActivateBitTiming { delay_ms } => {
                let index = lss.active_bit_timing();
                app.on_event(&mut self.od, NodeEvent::LssActivateBitTiming { index, delay_ms }, now);
            }
            LssEvent::ResetCommunication { .. } => {
                // An unconfigured node got its node-ID: start up on our own (CiA 305).
                self.s.nmt.set_node_id(lss.pending_node_id());
                self.reset_communication(now, app, out);
            }
            _ => {}
        }
    }
}

/// Hooks for the PDO service: mapped application objects go to the
/// application; communication objects are never PDO-mapped by services.
struct AppOnly<'a, A: ?Sized>(&'a mut A);

impl<A: Application + ?Sized> drivebus_od::ObjectHooks for AppOnly<'_, A> {
    fn on_read(
        &mut self,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
    ) -> Result<(), drivebus_od::SdoAbort> {
        self.0.on_read(od, index, sub)
    }
    fn on_write(
        &mut self,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<drivebus_od::WriteOutcome, drivebus_od::SdoAbort> {
        self.0.on_write(od, index, sub, data)
    }
    fn after_write(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) {
        self.0.after_write(od, index, sub)
    }
}
