//! Time, events and resets of a [`Node`]: `poll` visits only the services
//! whose inputs changed ([`dirty`]) or whose deadline came.

use crate::app::{Application, NodeEvent};
use crate::dictionary::rebase_node_id;
use crate::node::Node;
use crate::owners::dirty;
use crate::storage::{Slot, apply_image};
use alloc::vec::Vec;
use drivebus_can::{CanId, Frame, Instant, TxSink, earliest};
use drivebus_emcy::EmcyConsumer;
use drivebus_lss::{LssEvent, LssSlave, StoreStatus};
use drivebus_nmt::{ErrorClass, NmtEvent, NmtState, Service};
use drivebus_od::{ObjectDictionary, PersistGroup};
use drivebus_sdo::server::{FIRST_PARAM_INDEX, SdoServer};
use drivebus_sync::TimeService;

/// EMCY for a heartbeat or life-guarding loss (CiA 301 Table 21).
const EMCY_GUARD: u16 = 0x8130;
/// EMCY "recovered from bus off" (CiA 301 Table 21).
pub(crate) const EMCY_BUS_OFF: u16 = 0x8140;
/// 1029h class of communication errors (sub 1).
const COMM_ERROR: ErrorClass = ErrorClass(1);

/// Number of deadline slots in [`Node::deadlines`].
pub(crate) const SERVICES: usize = 6;

/// Deadline slots.
pub(crate) mod svc {
    pub const NMT: usize = 0;
    pub const SYNC: usize = 1;
    pub const PDO: usize = 2;
    pub const SDO: usize = 3;
    pub const EMCY: usize = 4;
    pub const APP: usize = 5;
}

#[inline]
fn due(d: Option<Instant>, now: Instant) -> bool {
    d.is_some_and(|d| now >= d)
}

impl Node {
    /// Do the timed work due at `now`; returns when to call again.
    ///
    /// Only the services whose inputs changed since they last ran (a frame,
    /// a write their owner dispatch marked, a changed entry an event-driven
    /// TPDO maps) or whose deadline came are visited; with nothing of that
    /// this returns the cached deadline at once. Then the application's
    /// [`poll`](Application::poll) (when due or after it was called) and
    /// its requests.
    #[inline]
    pub fn poll<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) -> Option<Instant> {
        if self.s.link.dirty == 0
            && self.od.generation() == self.seen_generation
            && self.next_deadline.is_none_or(|d| now < d)
        {
            return self.next_deadline;
        }
        self.poll_slow(now, app, out)
    }

    #[inline(never)]
    fn poll_slow<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) -> Option<Instant> {
        self.poll_services(now, app, out);
        if self.s.link.dirty & dirty::APP != 0 || due(self.deadlines[svc::APP], now) {
            self.s.link.dirty &= !dirty::APP;
            self.s.link.now = now;
            let d = app.poll(&mut self.s.cx(&mut self.od));
            // The callback itself is no new input.
            self.s.link.dirty &= !dirty::APP;
            self.deadlines[svc::APP] = d;
        }
        if self.run_requests(now, app, out) {
            self.poll_services(now, app, out);
        }
        self.next_deadline = self.deadlines.iter().fold(None, |a, &d| earliest(a, d));
        self.next_deadline
    }

    /// The communication services that are dirty or due, in CiA 301 order
    /// of their frames' priority within one instant.
    pub(crate) fn poll_services<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        self.s.link.now = now;
        if self.s.link.dirty & dirty::ROUTES != 0 || self.routes_state != self.s.nmt.state() {
            self.rebuild_routes();
        }
        if self.s.link.dirty & dirty::PDO_MAP != 0 {
            self.remark();
        }
        let state = self.s.nmt.state();
        if state.is_initialisation() {
            // Nothing runs before boot: the next poll after it polls all.
            self.s.link.dirty &= dirty::APP;
            self.deadlines[..svc::APP].fill(None);
            return;
        }
        if self.s.link.dirty & dirty::NMT != 0 || due(self.deadlines[svc::NMT], now) {
            self.s.link.dirty &= !dirty::NMT;
            self.deadlines[svc::NMT] = self.s.nmt.poll(now, out);
            while let Some(ev) = self.s.nmt.pop_event() {
                self.on_nmt_event(ev, now, app, out);
            }
        }
        if self.s.link.dirty & dirty::SYNC != 0 || due(self.deadlines[svc::SYNC], now) {
            self.s.link.dirty &= !dirty::SYNC;
            self.deadlines[svc::SYNC] = None;
            if self.s.nmt.state().allows(Service::Sync) {
                let sp = self.s.sync.poll(now, out);
                self.deadlines[svc::SYNC] = sp.next;
                if let Some(ev) = sp.produced {
                    self.on_sync(ev.counter, now, app, out);
                }
                if sp.timeout.is_some() {
                    app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::SyncTimeout);
                }
            }
        }
        let pdo_input = self.od.generation() != self.seen_generation;
        if self.s.link.dirty & dirty::PDO != 0 || pdo_input || due(self.deadlines[svc::PDO], now) {
            self.s.link.dirty &= !dirty::PDO;
            self.deadlines[svc::PDO] = None;
            if self.s.nmt.state().allows(Service::Pdo) {
                let (pdo, mut hooks) = self.s.pdo_and_app(&mut *app);
                self.deadlines[svc::PDO] = pdo.poll(now, &mut self.od, &mut hooks, out);
                self.drain_pdo_events(now, app);
            }
            self.seen_generation = self.od.generation();
        }
        if self.s.link.dirty & dirty::SDO != 0 || due(self.deadlines[svc::SDO], now) {
            self.s.link.dirty &= !dirty::SDO;
            let mut next = None;
            for s in &mut self.sdo {
                next = earliest(next, s.poll(now, out));
            }
            self.deadlines[svc::SDO] = next;
        }
        if self.s.link.dirty & dirty::EMCY != 0 || due(self.deadlines[svc::EMCY], now) {
            self.s.link.dirty &= !dirty::EMCY;
            self.deadlines[svc::EMCY] = if self.s.nmt.state().allows(Service::Emcy) {
                self.s.emcy.poll(now, out)
            } else {
                // Stopped: EMCYs are not sent (CiA 301 §7.3.2.2) and not kept.
                self.s.emcy.discard_queue();
                None
            };
        }
    }

    /// Marks the entries the event-driven TPDOs map, so a change of one of
    /// them (and only that) gets the PDO service polled; every entry when
    /// one of those TPDOs maps a live value (it may change on any write).
    fn remark(&mut self) {
        self.s.link.dirty &= !dirty::PDO_MAP;
        let live = self.s.pdo.event_live();
        self.od.mark_all(live);
        if !live {
            let refs: Vec<_> = self.s.pdo.event_mapped().collect();
            for r in refs {
                self.od.set_marked(r, true);
            }
        }
        self.s.link.dirty |= dirty::PDO;
    }

    pub(crate) fn on_sync<A: Application + ?Sized>(
        &mut self,
        counter: Option<u8>,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        if self.s.nmt.state().allows(Service::Pdo) {
            self.s.link.dirty |= dirty::PDO;
            let (pdo, mut hooks) = self.s.pdo_and_app(&mut *app);
            pdo.on_sync(counter, now, &mut self.od, &mut hooks, out);
            self.drain_pdo_events(now, app);
        }
        app.on_sync(&mut self.s.cx(&mut self.od), counter);
    }

    #[inline]
    pub(crate) fn drain_pdo_events<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A) {
        if self.s.pdo.has_events() {
            self.drain_pdo_events_slow(now, app);
        }
    }

    #[inline(never)]
    fn drain_pdo_events_slow<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A) {
        while let Some(ev) = self.s.pdo.pop_event() {
            self.on_pdo_event(ev, now, app);
        }
    }

    pub(crate) fn on_pdo_event<A: Application + ?Sized>(
        &mut self,
        ev: drivebus_pdo::PdoEvent,
        now: Instant,
        app: &mut A,
    ) {
        match ev {
            drivebus_pdo::PdoEvent::RpdoResumed { .. } => {
                self.clear_emcy(0x8250, now);
            }
            drivebus_pdo::PdoEvent::RpdoTimeout { rpdo } => {
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::RpdoTimeout { rpdo });
            }
            _ => {}
        }
        if let Some(code) = ev.emcy_code() {
            self.raise_emcy(code, [0; 5], now);
        }
    }

    /// Follow-ups of a write that could not run inside the dispatch: an NMT
    /// event from reconfiguring error control, moved identifiers, rebuilt
    /// SDO servers.
    pub(crate) fn after_write<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        if let Some(ev) = self.s.pending_nmt.take() {
            self.on_nmt_event(ev, now, app, out);
        }
        if core::mem::take(&mut self.s.sdo_params_dirty) {
            for s in &mut self.sdo {
                if let Some(i) = s.param_index() {
                    s.reconfigure(&self.od, i);
                }
            }
            self.s.link.dirty |= dirty::SDO | dirty::ROUTES;
        }
        if self.s.link.dirty & dirty::ROUTES != 0 {
            self.rebuild_routes();
        }
    }

    pub(crate) fn on_nmt_event<A: Application + ?Sized>(
        &mut self,
        ev: NmtEvent,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        match ev {
            NmtEvent::StateChanged { from, to } => {
                self.s.link.dirty |= dirty::ALL;
                // Frames the new state allows (or not) route accordingly.
                self.rebuild_routes();
                if from == NmtState::Operational {
                    // Leaving operational drops latched synchronous data and timers.
                    self.s.pdo.reset();
                }
                if to == NmtState::Stopped {
                    // SDO is not available in stopped: transfers end silently.
                    self.sdo.iter_mut().for_each(SdoServer::reset);
                    self.s.emcy.discard_queue();
                }
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::NmtState { from, to });
            }
            NmtEvent::ResetApplication => {
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::ResetApplication);
                self.app_errors.clear();
                self.reset_groups(&[PersistGroup::Manufacturer, PersistGroup::Application]);
                self.reset_communication(now, app, out);
            }
            NmtEvent::ResetCommunication => self.reset_communication(now, app, out),
            NmtEvent::HeartbeatTimeout { node } => {
                self.comm_error(now, app, out);
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::HeartbeatTimeout { node });
            }
            NmtEvent::HeartbeatRecovered { node, .. } => {
                self.comm_recovered(now);
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::HeartbeatRecovered { node });
            }
            NmtEvent::RemoteBootup { node } => {
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::RemoteBootup { node })
            }
            NmtEvent::RemoteStateChange { node, state } => {
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::RemoteState { node, state })
            }
            NmtEvent::LifeGuardingLost => {
                self.comm_error(now, app, out);
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::LifeGuardingLost);
            }
            NmtEvent::LifeGuardingResolved => {
                self.comm_recovered(now);
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::LifeGuardingResolved);
            }
        }
    }

    /// A communication error: EMCY 8130h and the 1029h reaction.
    fn comm_error<A: Application + ?Sized>(&mut self, now: Instant, app: &mut A, out: &mut impl TxSink) {
        match self.config().comm_error_emcy {
            Some((bits, bytes)) => self.raise_defined(EMCY_GUARD, bits, bytes, now),
            None => {
                self.raise_emcy(EMCY_GUARD, [0; 5], now);
            }
        }
        if let Some(ev) = self.s.nmt.on_error(COMM_ERROR) {
            self.on_nmt_event(ev, now, app, out);
        }
    }

    /// The controller went bus-off: 8140h becomes active (1001h bit 4, the
    /// communication error, and 1003h; its frame cannot reach the bus) and
    /// 1029h sub 1 reacts, as CiA 301 §7.5.2.32 counts bus-off among the
    /// communication errors.
    pub(crate) fn bus_off<A: Application + ?Sized>(
        &mut self,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        if self.bus_off {
            return;
        }
        self.bus_off = true;
        match self.config().comm_error_emcy {
            Some((bits, bytes)) => self.raise_defined(EMCY_BUS_OFF, bits, bytes, now),
            None => {
                self.raise_emcy(EMCY_BUS_OFF, [0; 5], now);
            }
        }
        if let Some(ev) = self.s.nmt.on_error(COMM_ERROR) {
            self.on_nmt_event(ev, now, app, out);
        }
    }

    /// Back on the bus after bus-off: the EMCY 8140h "recovered from bus
    /// off" goes out (the one raised at bus-off was lost with the
    /// controller's queue), then the error clears with its error-reset
    /// EMCY (0000h and the register of what is still active).
    pub(crate) fn bus_recovered(&mut self, now: Instant) {
        if !core::mem::take(&mut self.bus_off) {
            return;
        }
        let defined = self.app_errors.iter().find(|(c, _)| *c == EMCY_BUS_OFF).copied();
        match (defined, self.config().comm_error_emcy) {
            (Some(_), Some((_, bytes))) => {
                let reg = self.app_errors.iter().fold(0, |a, (_, r)| a | r);
                self.send_raw_emcy(EMCY_BUS_OFF, reg, bytes, now);
                self.clear_defined(EMCY_BUS_OFF, now);
            }
            _ => {
                let reg = self.s.emcy.error_register();
                self.send_raw_emcy(EMCY_BUS_OFF, reg, [0; 5], now);
                self.clear_emcy(EMCY_BUS_OFF, now);
            }
        }
    }

    fn comm_recovered(&mut self, now: Instant) {
        let any_lost = self.s.nmt.is_life_guarding_lost()
            || self.s.nmt.consumer_entries().any(|e| self.s.nmt.is_heartbeat_timed_out(e.node));
        if !any_lost && !self.clear_defined(EMCY_GUARD, now) {
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
                self.set_node_id(id);
            }
        }
        self.reset_groups(&[PersistGroup::Communication]);
        app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::ResetCommunication);
        self.start_communication(now, app, out);
    }

    fn set_node_id(&mut self, id: u8) {
        rebase_node_id(&mut self.od, self.node_id, id);
        self.node_id = id;
        self.s.link.node_id = id;
        self.cfg.node_id = id;
        self.cfg.nmt.node_id = id;
        self.s.nmt.set_node_id(id);
    }

    /// Defaults, then stored values, for `groups`.
    fn reset_groups(&mut self, groups: &[PersistGroup]) {
        self.od.restore_defaults(|_, s| groups.contains(&s.persist));
        let slots: Vec<Slot> = groups.iter().filter_map(|g| Slot::of(*g)).collect();
        self.load_groups(&slots);
    }

    pub(crate) fn load_groups(&mut self, slots: &[Slot]) {
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
    pub(crate) fn load_lss_config(&mut self) {
        let Some(lss) = &self.lss else { return };
        let Ok(Some(img)) = self.s.storage.load(Slot::Lss) else { return };
        if img.len() == 2 && (drivebus_lss::is_configurable_node_id(img[0])) && img[0] != self.node_id {
            let id = img[0];
            let mut l = LssSlave::new(*lss.identity(), id, img[1]);
            if let Some(cur) = self.lss.as_mut() {
                core::mem::swap(cur, &mut l);
            }
            self.set_node_id(id);
        }
    }

    /// Re-read every service's configuration and boot (or wait for LSS).
    pub(crate) fn start_communication<A: Application + ?Sized>(
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
        self.s.link.dirty |= dirty::ALL | dirty::PDO_MAP;
        self.rebuild_routes();
        if !(1..=127).contains(&id) {
            return;
        }
        if let Some(ev) = self.s.nmt.boot(&self.od, now, out) {
            self.on_nmt_event(ev, now, app, out);
        }
    }

    pub(crate) fn on_lss_frame<A: Application + ?Sized>(
        &mut self,
        frame: &Frame,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        let Some(lss) = &mut self.lss else { return };
        let Some(ev) = lss.handle_frame(frame, now, out) else { return };
        match ev {
            LssEvent::NodeIdConfigured(id) => {
                app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::LssNodeId(id))
            }
            LssEvent::StoreRequested { node_id, bit_timing } => {
                let status = match self.s.storage.save(Slot::Lss, &[node_id, bit_timing]) {
                    Ok(()) => StoreStatus::Stored,
                    Err(_) => StoreStatus::AccessError,
                };
                lss.complete_store(status, out);
            }
            LssEvent::ActivateBitTiming { delay_ms } => {
                let index = lss.active_bit_timing();
                app.on_event(
                    &mut self.s.cx(&mut self.od),
                    NodeEvent::LssActivateBitTiming { index, delay_ms },
                );
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
