//! [`Node`]: one CiA 301 device.

use crate::app::{Application, FrameFilter, NodeEvent};
use crate::config::NodeConfig;
use crate::dictionary::{build_dictionary, mark_node_relative, node_relative};
use crate::owners::{Dispatch, Link, Services, dirty, resolve};
use crate::storage::{MemoryStorage, Storage};
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::{CanId, Frame, Instant, TxSink, earliest};
use drivebus_emcy::{Emcy, register_bit_for};
use drivebus_lss::LssSlave;
use drivebus_nmt::{InitSubState, Nmt, NmtCommand, NmtState, Service};
use drivebus_od::{ObjectDictionary, SdoAbort};
use drivebus_pdo::{Pdo, PdoRx};
use drivebus_sdo::server::SdoServer;
use drivebus_sync::SyncService;

/// EMCY for a SYNC with the wrong length (CiA 301 Table 21).
pub(crate) const EMCY_SYNC_LEN: u16 = 0x8240;

/// A complete CiA 301 device: the services of the communication profile
/// over one object dictionary, sans-IO.
///
/// Drive it with [`Node::boot`] once, then [`Node::handle_frame`] for every
/// received frame and [`Node::poll`] at (or after) the deadline it returns.
/// Application behaviour plugs in through an [`Application`] passed to each
/// call, so the node never owns or knows the application;
/// [`crate::NodeDevice`] pairs the two as one [`drivebus_can::Device`].
pub struct Node {
    pub(crate) cfg: NodeConfig,
    pub(crate) od: ObjectDictionary,
    pub(crate) s: Services,
    pub(crate) sdo: Vec<SdoServer>,
    pub(crate) lss: Option<LssSlave>,
    pub(crate) node_id: u8,
    /// Service behind each 11-bit identifier (see `route`), rebuilt when a
    /// COB-ID changes: frame dispatch is one table load.
    pub(crate) routes: Vec<u8>,
    /// The NMT state `routes` was built for.
    pub(crate) routes_state: NmtState,
    /// Each service's next deadline (`svc` order) and their earliest.
    pub(crate) deadlines: [Option<Instant>; crate::poll::SERVICES],
    pub(crate) next_deadline: Option<Instant>,
    /// `od.generation()` when the PDO service last looked: the dictionary
    /// counts changes of the entries event-driven TPDOs map (all entries,
    /// when one maps a live entry) and nothing else.
    pub(crate) seen_generation: u64,
    /// The requests being carried out (swapped with `s.requests`).
    pub(crate) running: Vec<crate::app::Request>,
    /// Errors raised with a device-defined register (code, bits).
    pub(crate) app_errors: Vec<(u16, u8)>,
    /// The controller is bus-off (8140h is active until it recovers).
    pub(crate) bus_off: bool,
}

/// A node's configuration and its finished dictionary (the services'
/// objects merged in, node-relative defaults marked, owners resolved):
/// everything [`Node::with_dictionary`] computes before it sets up the
/// services. Building one costs two dictionary builds; making a node of
/// it ([`NodeTemplate::node`]) costs a copy of the dictionary, so many
/// nodes of one configuration (a fuzz target's input, a simulation) are
/// built once.
#[derive(Clone, Debug)]
pub struct NodeTemplate {
    cfg: NodeConfig,
    od: ObjectDictionary,
}

impl NodeTemplate {
    /// The template of `Node::new(cfg)`: the dictionary `cfg` describes.
    pub fn new(cfg: NodeConfig) -> NodeTemplate {
        let cfg = normalized(cfg);
        let mut od = build_dictionary(&cfg, cfg.node_id);
        // The dictionary is the services' own: nothing to merge (merging
        // it with itself changes nothing), only the node-relative marks.
        for (index, sub) in node_relative(&cfg, &od, cfg.node_id) {
            if let Some(s) = od.get_mut(index, sub) {
                s.node_id_relative = true;
            }
        }
        resolve(&mut od);
        NodeTemplate { cfg, od }
    }

    /// The template of `Node::with_dictionary(cfg, od, _)`.
    pub fn with_dictionary(cfg: NodeConfig, mut od: ObjectDictionary) -> NodeTemplate {
        let cfg = normalized(cfg);
        let generated = build_dictionary(&cfg, cfg.node_id);
        crate::dictionary::merge_services(&mut od, &generated);
        mark_node_relative(&cfg, &generated, cfg.node_id, &mut od);
        resolve(&mut od);
        NodeTemplate { cfg, od }
    }

    /// The configuration (node-ID normalised: FFh when outside 1..=127).
    pub fn config(&self) -> &NodeConfig {
        &self.cfg
    }

    /// The dictionary a node of this template starts with.
    pub fn od(&self) -> &ObjectDictionary {
        &self.od
    }

    /// A node of this template with parameters in `storage`: the same as
    /// the `Node` constructor the template stands for.
    pub fn node(&self, storage: Box<dyn Storage + Send>) -> Node {
        Node::assemble(self.cfg.clone(), self.od.clone(), storage)
    }

    /// Makes `node` a fresh node of this template, as [`NodeTemplate::node`]
    /// would, reusing the buffers of its dictionary: where the old node's
    /// dictionary has the template's structure (any node of this template
    /// does), the copy allocates nothing.
    pub fn renew(&self, node: &mut Node, storage: Box<dyn Storage + Send>) {
        let mut od = core::mem::take(&mut node.od);
        od.clone_from(&self.od);
        *node = Node::assemble(self.cfg.clone(), od, storage);
    }

    /// This template for node-ID `node_id`: the configuration's node-IDs
    /// (its own, NMT's, and the PDO one where it was in step) set to
    /// `node_id`, and every node-relative entry (default and value) moved
    /// by the difference, in its width. A copy of the dictionary instead of
    /// the two dictionary builds of [`NodeTemplate::with_dictionary`]. It
    /// is that template for `node_id` only where every node-relative entry
    /// is the node-ID plus a constant: a caller that cannot know checks it
    /// once against [`NodeTemplate::with_dictionary`] (equal configuration
    /// and dictionary). `None` when either node-ID is outside 1..=127.
    pub fn moved_to(&self, node_id: u8) -> Option<NodeTemplate> {
        let from = self.cfg.node_id;
        if !(1..=127).contains(&from) || !(1..=127).contains(&node_id) {
            return None;
        }
        let mut cfg = self.cfg.clone();
        cfg.node_id = node_id;
        cfg.nmt.node_id = node_id;
        if cfg.pdo.node_id == from {
            cfg.pdo.node_id = node_id;
        }
        let mut od = self.od.clone();
        if node_id != from {
            let d = u64::from(node_id).wrapping_sub(u64::from(from));
            let shift = |b: &[u8]| {
                let n = b.len().min(8);
                drivebus_od::le_u64(b).wrapping_add(d).to_le_bytes()[..n].to_vec()
            };
            let relative: Vec<(u16, u8)> = od
                .objects()
                .iter()
                .flat_map(|o| o.subs().iter().filter(|s| s.node_id_relative).map(move |s| (o.index, s.sub)))
                .collect();
            for (index, sub) in relative {
                let Ok(r) = od.find(index, sub) else { continue };
                let value = shift(od.bytes(r));
                od.set_raw(r, &value);
                if let Some(s) = od.get_mut(index, sub) {
                    s.default = shift(&s.default);
                }
            }
        }
        Some(NodeTemplate { cfg, od })
    }

    /// [`NodeTemplate::node`], consuming the template.
    pub fn into_node(self, storage: Box<dyn Storage + Send>) -> Node {
        Node::assemble(self.cfg, self.od, storage)
    }

    /// The configuration and the dictionary, to edit before
    /// [`Node::assemble`].
    #[cfg(feature = "std")]
    pub(crate) fn into_parts(self) -> (NodeConfig, ObjectDictionary) {
        (self.cfg, self.od)
    }
}

/// `cfg` with its node-ID in 1..=127 or FFh (unconfigured), also for NMT.
fn normalized(mut cfg: NodeConfig) -> NodeConfig {
    let node_id = if (1..=127).contains(&cfg.node_id) || cfg.node_id == 0xFF { cfg.node_id } else { 0xFF };
    cfg.node_id = node_id;
    cfg.nmt.node_id = node_id;
    cfg
}

/// Route codes in [`Node::routes`].
pub(crate) mod route {
    pub const NONE: u8 = 0;
    pub const NMT: u8 = 1;
    pub const ERROR_CONTROL: u8 = 2;
    pub const LSS: u8 = 3;
    pub const SYNC: u8 = 4;
    pub const PDO: u8 = 7;
    /// Through `dispatch_configurable` (shared identifiers, TIME, EMCY
    /// consumer, services the NMT state does not allow a fast path).
    pub const OTHER: u8 = 8;
    /// SDO server `i` is `SDO + i`.
    pub const SDO: u8 = 9;
}

impl Node {
    /// A device with the dictionary `NodeConfig` describes and parameters
    /// stored in memory.
    pub fn new(cfg: NodeConfig) -> Node {
        Node::with_storage(cfg, Box::new(MemoryStorage::new()))
    }

    /// A device whose 1010h/1011h parameters live in `storage`.
    pub fn with_storage(cfg: NodeConfig, storage: Box<dyn Storage + Send>) -> Node {
        NodeTemplate::new(cfg).into_node(storage)
    }

    /// A device around an existing dictionary (e.g. built from an EDS):
    /// communication objects it lacks are added, those it has keep their
    /// descriptions but are owned by the services.
    pub fn with_dictionary(cfg: NodeConfig, od: ObjectDictionary, storage: Box<dyn Storage + Send>) -> Node {
        NodeTemplate::with_dictionary(cfg, od).into_node(storage)
    }

    /// The node of a finished configuration and dictionary (see
    /// [`NodeTemplate`]): the services are set up from them.
    pub(crate) fn assemble(
        mut cfg: NodeConfig,
        od: ObjectDictionary,
        storage: Box<dyn Storage + Send>,
    ) -> Node {
        let node_id = cfg.node_id;
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
            link: Link {
                dirty: dirty::ALL | dirty::ROUTES | dirty::PDO_MAP,
                requests: Vec::with_capacity(8),
                node_id,
                now: Instant::ZERO,
            },
            sdo_params_dirty: false,
            pending_nmt: None,
            #[cfg(feature = "std")]
            eds_info: crate::eds_object::Given {
                lss: cfg.lss,
                device_info: cfg.eds_device_info.clone(),
                file_info: cfg.eds_file_info.clone(),
                file: cfg.eds_text.clone(),
            },
        };
        let lss = cfg.lss.then(|| LssSlave::new(cfg.identity, node_id, 0));
        let mut node = Node {
            cfg,
            od,
            s,
            sdo: Vec::new(),
            lss,
            node_id,
            routes: alloc::vec![route::NONE; 0x800],
            routes_state: NmtState::Initialisation(InitSubState::Initialising),
            deadlines: [None; crate::poll::SERVICES],
            next_deadline: None,
            seen_generation: 0,
            running: Vec::with_capacity(8),
            app_errors: Vec::new(),
            bus_off: false,
        };
        node.load_lss_config();
        node
    }

    /// The object dictionary.
    pub fn od(&self) -> &ObjectDictionary {
        &self.od
    }
    /// The object dictionary, for pushing live values (`set_le`,
    /// `set_raw`) from outside an application callback. Every service is
    /// polled at the next [`Node::poll`]. Add objects with
    /// [`Node::insert_object`], not through this reference: services hold
    /// resolved handles into the dictionary. Writes that must reach their
    /// owner go through [`Node::write_object`].
    pub fn od_mut(&mut self) -> &mut ObjectDictionary {
        self.s.link.dirty |= dirty::ALL;
        &mut self.od
    }

    /// Add (or replace) an object: its `hooked()` entries get their owner,
    /// and every service re-resolves its handles.
    pub fn insert_object(&mut self, obj: drivebus_od::Object) {
        self.insert_objects([obj]);
    }

    /// Add (or replace) several objects: [`Node::insert_object`] for each,
    /// with the services re-resolved once, after the last (installing an
    /// application's hundred objects one by one re-resolves a hundred times).
    pub fn insert_objects(&mut self, objs: impl IntoIterator<Item = drivebus_od::Object>) {
        for obj in objs {
            self.od.insert(obj);
        }
        resolve(&mut self.od);
        self.s.pdo.reload(&self.od);
        self.s.link.dirty |= dirty::ALL | dirty::ROUTES | dirty::PDO_MAP;
        self.rebuild_routes();
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

    /// Puts `storage` in place of the parameter storage and returns the
    /// old one: the non-volatile memory handed to a device built again at
    /// power-on (before its boot loads it).
    pub fn replace_storage(&mut self, storage: Box<dyn Storage + Send>) -> Box<dyn Storage + Send> {
        core::mem::replace(&mut self.s.storage, storage)
    }

    /// Power on: load stored parameters, start the services, send the
    /// boot-up message, enter pre-operational and tell the application
    /// ([`Application::on_start`]). An unconfigured node (node-ID FFh)
    /// stays silent, answering only LSS. What the application requests at
    /// start is carried out by the next [`Node::poll`].
    pub fn boot<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A, out: &mut impl TxSink) {
        self.s.link.now = now;
        self.load_groups(&[
            crate::storage::Slot::Manufacturer,
            crate::storage::Slot::Application,
            crate::storage::Slot::Communication,
        ]);
        self.start_communication(now, app, out);
        app.on_start(&mut self.s.cx(&mut self.od));
    }

    /// Reads an object the way every protocol does (SDO upload, CoE, a
    /// local tool): access check, the owner's refresh of a live entry, the
    /// bytes. The SDO server runs this same path.
    pub fn read_object<A: Application + ?Sized>(
        &mut self,
        index: u16,
        sub: u8,
        now: Instant,
        app: &mut A,
    ) -> Result<&[u8], SdoAbort> {
        self.s.link.now = now;
        let mut d = Dispatch { s: &mut self.s, app };
        self.od.read(&mut d, index, sub)
    }

    /// Writes an object the way every protocol does (SDO download, CoE, a
    /// local tool): the whole write path of `DEVELOPERS.md` — find, access,
    /// type/length/limits, the watcher's veto and the owner's check, store,
    /// the owner's apply — then the node's follow-ups (reconfigured
    /// identifiers, NMT events, the application's requests). The SDO
    /// server runs this same path. Frames the follow-ups produce (a reset
    /// communication's boot-up) go to `out`.
    pub fn write_object<A: Application + ?Sized>(
        &mut self,
        index: u16,
        sub: u8,
        data: &[u8],
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) -> Result<(), SdoAbort> {
        self.s.link.now = now;
        let r = {
            let mut d = Dispatch { s: &mut self.s, app: &mut *app };
            self.od.write(&mut d, index, sub, data)
        };
        self.after_write(now, app, out);
        if self.run_requests(now, app, out) {
            self.poll_services(now, app, out);
        }
        r
    }

    /// Signal an error: 1001h, 1003h and an EMCY frame (CiA 301 §7.2.7).
    /// Returns false if the code was already active.
    pub fn raise_emcy(&mut self, code: u16, manufacturer: [u8; 5], now: Instant) -> bool {
        self.s.link.dirty |= dirty::EMCY;
        self.s.emcy.raise(&mut self.od, code, register_bit_for(code), manufacturer, now)
    }

    /// Signal an error with explicit 1001h bits (CiA 301 bookkeeping).
    pub fn raise_emcy_with_register(
        &mut self,
        code: u16,
        register: u8,
        manufacturer: [u8; 5],
        now: Instant,
    ) -> bool {
        self.s.link.dirty |= dirty::EMCY;
        self.s.emcy.raise(&mut self.od, code, register, manufacturer, now)
    }

    /// An error went away (the error-reset EMCY goes when the last clears).
    pub fn clear_emcy(&mut self, code: u16, now: Instant) -> bool {
        self.s.link.dirty |= dirty::EMCY;
        self.s.emcy.clear(&mut self.od, code, now)
    }

    /// Every active error went away.
    pub fn clear_all_emcy(&mut self, now: Instant) {
        self.s.link.dirty |= dirty::EMCY;
        self.s.emcy.clear_all(&mut self.od, now)
    }

    /// Record an entry in the 1003h history without an EMCY frame (a
    /// personality that sends its own frame with [`Node::send_raw_emcy`]):
    /// low 16 bits the error code, high 16 bits additional information.
    pub fn record_emcy_history(&mut self, entry: u32) {
        self.s.link.dirty |= dirty::EMCY;
        self.s.emcy.record(&mut self.od, entry)
    }

    /// Send an EMCY outside the error bookkeeping (personality quirks).
    pub fn send_raw_emcy(&mut self, code: u16, register: u8, bytes: [u8; 5], now: Instant) {
        self.s.link.dirty |= dirty::EMCY;
        self.s.emcy.send_raw(code, register, bytes, now)
    }

    /// Restrict change-of-state detection of TPDO `n` (0-based) to the bits
    /// of `mask` (see `drivebus_pdo::Pdo::set_change_mask`).
    pub fn set_tpdo_change_mask(&mut self, n: u16, mask: Option<[u8; drivebus_can::MAX_DATA_LEN]>) -> bool {
        self.s.link.dirty |= dirty::PDO;
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
        self.s.link.dirty |= dirty::PDO;
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
        self.s.link.dirty |= dirty::ALL;
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
        self.s.link.now = now;
        self.set_nmt_state(to, now, app, out);
    }

    /// Handle one received frame. The application's
    /// [`filter_frame`](Application::filter_frame) sees it first.
    pub fn handle_frame<A: Application + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let replaced;
        let frame = match app.filter_frame(&self.od, self.node_id, frame) {
            FrameFilter::Pass => frame,
            FrameFilter::Replace(f) => {
                replaced = f;
                &replaced
            }
            FrameFilter::Drop => return,
        };
        self.s.link.now = now;
        self.dispatch_frame(frame, now, app, out);
        if !self.s.link.requests.is_empty() {
            self.frame_requests(now, app, out);
        }
    }

    /// What the application asked for while a frame was handled goes out
    /// with this frame's answers.
    #[cold]
    #[inline(never)]
    fn frame_requests<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A, out: &mut impl TxSink) {
        if self.run_requests(now, app, out) {
            self.poll_services(now, app, out);
        }
    }

    #[inline]
    fn dispatch_frame<A: Application + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let Some(id) = frame.std_id() else {
            return self.other_frame(route::OTHER, frame, now, app, out);
        };
        // The table already holds what the NMT state allows (CiA 301
        // §7.3.2.2): no state check on the hot paths.
        match self.routes[usize::from(id & 0x7FF)] {
            route::NONE => {}
            route::PDO => self.pdo_frame(frame, now, app, out),
            route::SYNC if frame.id() == self.s.sync.can_id() => self.sync_frame(frame, now, app, out),
            r if r >= route::SDO => self.sdo_frame(usize::from(r - route::SDO), frame, now, app, out),
            r => self.other_frame(r, frame, now, app, out),
        }
    }

    /// An RPDO (or a remote request for a TPDO).
    #[inline]
    fn pdo_frame<A: Application + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        // RPDO timers moved, mapped values changed.
        self.s.link.dirty |= dirty::PDO;
        let (pdo, mut hooks) = self.s.pdo_and_app(&mut *app);
        match pdo.handle_frame(frame, now, &mut self.od, &mut hooks, out) {
            PdoRx::Handled => {}
            PdoRx::Event(ev) => {
                self.on_pdo_event(ev, now, app);
                self.drain_pdo_events(now, app);
            }
            // Not a PDO after all (e.g. an RTR on an RPDO id): the other
            // services sharing identifiers get a look.
            PdoRx::NotPdo => self.dispatch_configurable(frame, now, app, out),
        }
    }

    /// The rarer frames: NMT, error control, LSS, and whatever shares an
    /// identifier or is not allowed a fast path in this state.
    #[cold]
    #[inline(never)]
    fn other_frame<A: Application + ?Sized>(
        &mut self,
        r: u8,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        match r {
            route::LSS => {
                self.s.link.dirty |= dirty::ALL;
                self.on_lss_frame(frame, now, app, out);
            }
            route::NMT | route::ERROR_CONTROL => {
                self.s.link.dirty |= dirty::NMT;
                if let Some(ev) = self.s.nmt.handle_frame(frame, now, out) {
                    self.on_nmt_event(ev, now, app, out);
                }
            }
            _ => {
                self.s.link.dirty |= dirty::ALL;
                if !self.s.nmt.state().is_initialisation() {
                    self.dispatch_configurable(frame, now, app, out);
                }
            }
        }
    }

    /// One SDO request to server `i`, through the write path.
    #[inline]
    fn sdo_frame<A: Application + ?Sized>(
        &mut self,
        i: usize,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let mut d = Dispatch { s: &mut self.s, app: &mut *app };
        self.sdo[i].handle_frame(frame, now, &mut self.od, &mut d, out);
        // A transfer only moves this server's own timeout: fold it into the
        // cached deadlines rather than polling every service (an early
        // wake-up is harmless, a late one is not).
        let dl = self.sdo[i].poll(now, out);
        let k = crate::poll::svc::SDO;
        self.deadlines[k] = earliest(self.deadlines[k], dl);
        self.next_deadline = earliest(self.next_deadline, dl);
        self.after_write(now, app, out);
    }

    /// A SYNC: the synchronous PDOs, then the application.
    #[inline]
    fn sync_frame<A: Application + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        if let Some(ev) = self.s.sync.handle_frame(frame, now) {
            // The consumer's timeout moved.
            self.s.link.dirty |= dirty::SYNC;
            if ev.length_error.is_some() {
                self.raise_emcy(EMCY_SYNC_LEN, [0; 5], now);
            }
            self.on_sync(ev.counter, now, app, out);
        }
    }

    /// Rebuild the identifier → service table from the services' current
    /// COB-IDs and the NMT state (after boot, a state change and any
    /// communication object change): a service the state does not allow
    /// routes through the checks of `dispatch_configurable`.
    pub(crate) fn rebuild_routes(&mut self) {
        self.s.link.dirty &= !dirty::ROUTES;
        let state = self.s.nmt.state();
        self.routes_state = state;
        let t = &mut self.routes;
        t.iter_mut().for_each(|x| *x = route::NONE);
        let lss = if self.lss.is_some() { route::LSS } else { route::NONE };
        if state.is_initialisation() {
            // Nothing but LSS before boot (an unconfigured node waits for it).
            t[usize::from(drivebus_lss::MASTER_TO_SLAVE)] = lss;
            return;
        }
        let gate = |svc: Service, r: u8| if state.allows(svc) { r } else { route::OTHER };
        let mut set = |id: Option<CanId>, r: u8| {
            if let Some(CanId::Standard(i)) = id {
                t[usize::from(i & 0x7FF)] = r;
            }
        };
        // Lowest priority first: later entries win a shared identifier,
        // in the order dispatch_configurable checks them.
        let cfg = *self.s.pdo.config();
        for n in 0..cfg.rpdo_count {
            set(self.s.pdo.can_id(drivebus_pdo::PdoKind::Rpdo, n), gate(Service::Pdo, route::PDO));
        }
        for n in 0..cfg.tpdo_count {
            set(self.s.pdo.can_id(drivebus_pdo::PdoKind::Tpdo, n), gate(Service::Pdo, route::PDO));
        }
        if let Some(o) = self.od.object(0x1028) {
            for sub in o.subs().iter().skip(1) {
                let cob = drivebus_od::le_u64(sub.bytes()) as u32;
                if cob & 0xA000_0000 == 0 {
                    set(CanId::standard((cob & 0x7FF) as u16), route::OTHER);
                }
            }
        }
        if self.s.time.is_some()
            && let Some(cob) = self.od.get_u32(0x1012, 0)
            && cob & 0xA000_0000 == 0x8000_0000
        {
            set(CanId::standard((cob & 0x7FF) as u16), route::OTHER);
        }
        for (i, s) in self.sdo.iter().enumerate().take(usize::from(u8::MAX - route::SDO)) {
            set(s.rx_cob_id(), gate(Service::Sdo, route::SDO + i as u8));
        }
        set(Some(self.s.sync.can_id()), gate(Service::Sync, route::SYNC));
        t[0x000] = route::NMT;
        for x in &mut t[0x701..=0x77F] {
            *x = route::ERROR_CONTROL;
        }
        t[usize::from(drivebus_lss::MASTER_TO_SLAVE)] = lss;
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
            if state.allows(Service::Sync) {
                self.sync_frame(frame, now, app, out);
            }
            return;
        }
        if state.allows(Service::Sdo) {
            for i in 0..self.sdo.len() {
                if self.sdo[i].rx_cob_id() == Some(fid) {
                    self.sdo_frame(i, frame, now, app, out);
                    return;
                }
            }
        }
        if let Some(t) = &self.s.time
            && state.allows(Service::Time)
            && let Some(tod) = t.handle_frame(frame)
        {
            app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::Time(tod));
            return;
        }
        if let Some(c) = &self.s.emcy_consumer
            && state.allows(Service::Emcy)
            && let Some(rx) = c.handle_frame(frame)
        {
            app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::Emcy(rx));
            return;
        }
        if state.allows(Service::Pdo) {
            self.s.link.dirty |= dirty::PDO;
            let (pdo, mut hooks) = self.s.pdo_and_app(&mut *app);
            let rx = pdo.handle_frame(frame, now, &mut self.od, &mut hooks, out);
            if let PdoRx::Event(ev) = rx {
                self.on_pdo_event(ev, now, app);
            }
            self.drain_pdo_events(now, app);
        }
    }
}
