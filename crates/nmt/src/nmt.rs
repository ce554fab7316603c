//! The NMT slave: state machine plus error control, driven sans-IO.

use crate::config::{
    CONSUMER_HEARTBEAT_TIME, ERROR_BEHAVIOUR, ERROR_CONTROL_BASE, GUARD_TIME, LIFE_TIME_FACTOR, NMT_COB_ID,
    NmtConfig, PRODUCER_HEARTBEAT_TIME,
};
use crate::consumer::{self, Consumer, ConsumerEntry};
use crate::error_behaviour::{self, ErrorAction, ErrorBehaviour, ErrorClass};
use crate::events::{EventQueue, NmtEvent};
use crate::guarding::Guarding;
use crate::producer::HeartbeatProducer;
use crate::state::{InitSubState, NmtCommand, NmtState, RemoteState};
use drivebus_can::{Frame, Instant, TxSink, earliest};
use drivebus_od::{ObjectDictionary, SdoAbort};

/// The NMT slave of one device: state machine (CiA 301 §7.3.2), NMT command
/// reception, boot-up, heartbeat producer and consumer, node/life guarding
/// and the 1029h error behaviour.
///
/// Life cycle: [`Nmt::new`] starts in Initialisation (reset application, as
/// after power-on). The node loads its dictionary, then calls
/// [`Nmt::boot`], which sends the boot-up message and enters
/// Pre-operational (or Operational with `auto_start`). A reset command
/// returns [`NmtEvent::ResetApplication`] / [`NmtEvent::ResetCommunication`];
/// the node restores the dictionary parts and calls [`Nmt::boot`] again.
#[derive(Clone, Debug)]
pub struct Nmt {
    config: NmtConfig,
    node_id: u8,
    state: NmtState,
    producer: HeartbeatProducer,
    consumer: Consumer,
    guarding: Guarding,
    errors: ErrorBehaviour,
    events: EventQueue,
}

impl Nmt {
    /// A device in Initialisation (reset application), as after power-on.
    pub fn new(config: NmtConfig) -> Nmt {
        Nmt {
            node_id: config.node_id,
            config,
            state: NmtState::Initialisation(InitSubState::ResetApplication),
            producer: HeartbeatProducer::default(),
            consumer: Consumer::default(),
            guarding: Guarding::default(),
            errors: ErrorBehaviour::default(),
            events: EventQueue::new(),
        }
    }

    /// The personality this instance was built with.
    pub fn config(&self) -> &NmtConfig {
        &self.config
    }

    /// The current state.
    #[inline]
    pub fn state(&self) -> NmtState {
        self.state
    }

    /// The active node-ID.
    #[inline]
    pub fn node_id(&self) -> u8 {
        self.node_id
    }

    /// Set the node-ID used from the next [`Nmt::boot`] on (CiA 305: a
    /// node-ID configured by LSS becomes active at reset communication).
    pub fn set_node_id(&mut self, id: u8) {
        self.config.node_id = id;
        if self.state.is_initialisation() {
            self.node_id = id;
        }
    }

    fn ec_id(&self) -> u16 {
        ERROR_CONTROL_BASE + u16::from(self.node_id & 0x7F)
    }

    /// The heartbeat producer is configured and implemented: node guarding
    /// is then not used (see [`Nmt::handle_frame`]).
    pub fn heartbeat_active(&self) -> bool {
        self.config.heartbeat_supported && self.producer.period_ms() != 0
    }

    /// Re-read every NMT object from `od` (1016h, 1017h, 100Ch, 100Dh,
    /// 1029h) at `now`, as if each had been written (e.g. after the node
    /// restored 1011h defaults). Allocates only for the 1016h and 1029h
    /// tables. [`Nmt::boot`] calls it. Returns
    /// [`NmtEvent::LifeGuardingResolved`] if life guarding ended while lost.
    pub fn configure(&mut self, od: &ObjectDictionary, now: Instant) -> Option<NmtEvent> {
        let running = self.state.allows(crate::Service::ErrorControl);
        let mut ev = None;
        if self.config.heartbeat_supported {
            let ms = od.get_u64(PRODUCER_HEARTBEAT_TIME, 0).unwrap_or(0) as u16;
            if ms != self.producer.period_ms() || !running {
                self.producer.set_period(ms, now, running);
            }
            self.consumer.configure(od);
            if ms != 0 && self.guarding.disable() {
                ev = Some(NmtEvent::LifeGuardingResolved);
            }
        }
        if self.config.guarding_supported {
            let guard = od.get_u64(GUARD_TIME, 0).unwrap_or(0) as u16;
            let factor = od.get_u64(LIFE_TIME_FACTOR, 0).unwrap_or(0) as u8;
            if self.guarding.set_times(guard, factor, now) {
                ev = Some(NmtEvent::LifeGuardingResolved);
            }
        }
        self.errors.configure(od);
        ev
    }

    /// Finish Initialisation: re-read the NMT objects, send the boot-up
    /// message `700h + node-ID, [00]` and enter Pre-operational (Operational
    /// with `auto_start`). Call after power-on and after the node handled
    /// [`NmtEvent::ResetApplication`] / [`NmtEvent::ResetCommunication`].
    ///
    /// Does nothing outside Initialisation. With a node-ID outside 1..=127
    /// (not configured, CiA 305) no boot-up is sent and the device stays in
    /// Initialisation (reset communication) waiting for LSS.
    pub fn boot(&mut self, od: &ObjectDictionary, now: Instant, out: &mut impl TxSink) -> Option<NmtEvent> {
        let from = self.state;
        if !from.is_initialisation() {
            return None;
        }
        self.node_id = self.config.node_id;
        if !(1..=127).contains(&self.node_id) {
            self.state = NmtState::Initialisation(InitSubState::ResetCommunication);
            return None;
        }
        self.state = NmtState::Initialisation(InitSubState::Initialising);
        // Initialisation: nothing runs yet, so no event can come out.
        let _ = self.configure(od, now);
        self.guarding.reset();
        out.send(Frame::new(self.ec_id(), &[0x00]));
        // Heartbeats start one period after the boot-up message.
        self.producer.start(now);
        self.consumer.start();
        let to = if self.config.auto_start { NmtState::Operational } else { NmtState::PreOperational };
        self.state = to;
        Some(NmtEvent::StateChanged { from, to })
    }

    /// Handle one received frame:
    ///
    /// - `000h` NMT command, 2 bytes `[cs, node-ID]`, for this node-ID or 0
    ///   (broadcast). Frames with another DLC are ignored (CiA 301
    ///   §7.2.8.3.1 defines exactly two bytes), as are RTR frames, unknown
    ///   command specifiers, commands the personality does not implement,
    ///   and every command while in Initialisation.
    /// - `700h + node-ID` remote frame (any DLC): node guarding, answered
    ///   when guarding is implemented and the heartbeat producer is off.
    /// - `701h..77Fh` data frames of DLC 1 from other nodes: heartbeats
    ///   for the consumer (only nodes configured in 1016h).
    ///
    /// Extended frames and everything else are ignored.
    pub fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut impl TxSink) -> Option<NmtEvent> {
        let id = frame.std_id()?;
        if id == NMT_COB_ID {
            return self.on_command(frame);
        }
        if !(ERROR_CONTROL_BASE + 1..=ERROR_CONTROL_BASE + 0x7F).contains(&id) {
            return None;
        }
        if !self.state.allows(crate::Service::ErrorControl) {
            return None;
        }
        let node = (id - ERROR_CONTROL_BASE) as u8;
        if node == self.node_id {
            if !frame.is_rtr() {
                // Our own error-control COB-ID from someone else: a
                // duplicate node-ID, not ours to handle.
                return None;
            }
            return self.on_guard_request(now, out);
        }
        if frame.is_rtr() || frame.len() != 1 || !self.config.heartbeat_supported {
            return None;
        }
        self.consumer.on_heartbeat(node, frame.data()[0], now)
    }

    fn on_command(&mut self, frame: &Frame) -> Option<NmtEvent> {
        if frame.is_rtr() || frame.len() != 2 {
            return None;
        }
        let [cs, target] = [frame.data()[0], frame.data()[1]];
        if target != 0 && target != self.node_id {
            return None;
        }
        let cmd = NmtCommand::from_cs(cs)?;
        if !self.config.supported_commands.contains(cmd) || self.state.is_initialisation() {
            return None;
        }
        self.apply_command(cmd)
    }

    /// Apply a command as if received (also for local requests).
    fn apply_command(&mut self, cmd: NmtCommand) -> Option<NmtEvent> {
        match cmd {
            NmtCommand::Start => self.change_to(NmtState::Operational),
            NmtCommand::Stop => self.change_to(NmtState::Stopped),
            NmtCommand::EnterPreOperational => self.change_to(NmtState::PreOperational),
            NmtCommand::ResetNode => {
                self.enter_init(InitSubState::ResetApplication);
                Some(NmtEvent::ResetApplication)
            }
            NmtCommand::ResetCommunication => {
                self.enter_init(InitSubState::ResetCommunication);
                Some(NmtEvent::ResetCommunication)
            }
        }
    }

    fn change_to(&mut self, to: NmtState) -> Option<NmtEvent> {
        let from = self.state;
        if from == to || from.is_initialisation() {
            return None;
        }
        self.state = to;
        Some(NmtEvent::StateChanged { from, to })
    }

    fn enter_init(&mut self, sub: InitSubState) {
        self.state = NmtState::Initialisation(sub);
        self.producer.stop();
        self.consumer.stop();
        self.guarding.reset();
    }

    fn on_guard_request(&mut self, now: Instant, out: &mut impl TxSink) -> Option<NmtEvent> {
        // CiA 301 §7.2.8.3.2: a device uses either heartbeat or node
        // guarding; with 1017h ≠ 0 the heartbeat is used, so requests go
        // unanswered and life guarding is off.
        if !self.config.guarding_supported || self.heartbeat_active() {
            return None;
        }
        let life = self.config.life_guarding_honoured;
        let id = self.ec_id();
        self.guarding.on_request(now, id, self.state.code(), life, out)
    }

    /// Do the timed work due at `now` (heartbeat producer, consumer
    /// timeouts, life guarding) and return the next deadline. Events found
    /// here are queued: drain them with [`Nmt::pop_event`].
    pub fn poll(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        if !self.state.allows(crate::Service::ErrorControl) {
            return None;
        }
        let id = self.ec_id();
        let hb = if self.config.heartbeat_supported {
            earliest(
                self.producer.poll(now, id, self.state.code(), out),
                self.consumer.poll(now, &mut self.events),
            )
        } else {
            None
        };
        earliest(hb, self.guarding.poll(now, &mut self.events))
    }

    /// The next event found by [`Nmt::poll`], oldest first.
    pub fn pop_event(&mut self) -> Option<NmtEvent> {
        self.events.pop()
    }

    /// A local state transition requested by the node or application.
    ///
    /// Pre-operational, Operational and Stopped are entered from any state
    /// but Initialisation (boot first). `Initialisation(ResetApplication)`
    /// and `Initialisation(ResetCommunication)` start a local reset and
    /// return the matching reset event; `Initialisation(Initialising)` is
    /// reached only through [`Nmt::boot`] and is ignored here.
    pub fn set_state(&mut self, to: NmtState) -> Option<NmtEvent> {
        match to {
            NmtState::PreOperational => self.apply_command(NmtCommand::EnterPreOperational),
            NmtState::Operational => self.apply_command(NmtCommand::Start),
            NmtState::Stopped => self.apply_command(NmtCommand::Stop),
            NmtState::Initialisation(InitSubState::ResetApplication) => {
                self.apply_command(NmtCommand::ResetNode)
            }
            NmtState::Initialisation(InitSubState::ResetCommunication) => {
                self.apply_command(NmtCommand::ResetCommunication)
            }
            NmtState::Initialisation(InitSubState::Initialising) => None,
        }
    }

    /// The 1029h reaction configured for `class`.
    pub fn error_action(&self, class: ErrorClass) -> ErrorAction {
        self.errors.action(class)
    }

    /// Set the reaction for `class` without 1029h (personalities that do
    /// not implement the object but have a fixed reaction). A later 1029h
    /// configuration overrides it.
    pub fn set_error_behaviour(&mut self, class: ErrorClass, value: u8) {
        self.errors.set(class, value);
    }

    /// An error of `class` occurred (heartbeat timeout, life guarding lost,
    /// bus-off, ...): apply the 1029h reaction to the NMT state and return
    /// the state change, if any, for the node to pass on.
    pub fn on_error(&mut self, class: ErrorClass) -> Option<NmtEvent> {
        let to = self.errors.action(class).target(self.state)?;
        self.change_to(to)
    }

    /// Refuse a write to an NMT object with the exact abort, before it is
    /// stored: 1016h duplicate node-ID `0604 0043`, reserved bits `0609
    /// 0030`; 1029h reserved values 3..=127 `0609 0030`. Other indices and
    /// other values are accepted (type and limits are the dictionary's).
    pub fn check_write(
        &self,
        od: &ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        match index {
            CONSUMER_HEARTBEAT_TIME => consumer::check_write(od, sub, data),
            ERROR_BEHAVIOUR => error_behaviour::check_write(sub, data),
            _ => Ok(()),
        }
    }

    /// Take a stored write into account at `now`: 1017h restarts the
    /// producer timer (and stops node/life guarding when non-zero), a
    /// changed 1016h entry restarts its monitoring, 100Ch/100Dh restart a
    /// running life-guarding timer, 1029h updates the reactions.
    ///
    /// Returns [`NmtEvent::LifeGuardingResolved`] when the write ends life
    /// guarding (1017h ≠ 0, or 100Ch × 100Dh = 0) while a loss is
    /// outstanding: the supervision that failed no longer applies.
    pub fn reconfigure(
        &mut self,
        od: &ObjectDictionary,
        index: u16,
        sub: u8,
        now: Instant,
    ) -> Option<NmtEvent> {
        let running = self.state.allows(crate::Service::ErrorControl);
        let resolved = |was_lost: bool| was_lost.then_some(NmtEvent::LifeGuardingResolved);
        match index {
            PRODUCER_HEARTBEAT_TIME if self.config.heartbeat_supported => {
                let ms = od.get_u64(PRODUCER_HEARTBEAT_TIME, 0).unwrap_or(0) as u16;
                self.producer.set_period(ms, now, running);
                if ms != 0 {
                    return resolved(self.guarding.disable());
                }
            }
            CONSUMER_HEARTBEAT_TIME if self.config.heartbeat_supported => {
                if sub == 0 {
                    self.consumer.configure(od);
                } else {
                    let raw = od.get_u32(CONSUMER_HEARTBEAT_TIME, sub).unwrap_or(0);
                    self.consumer.set_entry(sub, raw);
                }
            }
            GUARD_TIME | LIFE_TIME_FACTOR if self.config.guarding_supported => {
                let guard = od.get_u64(GUARD_TIME, 0).unwrap_or(0) as u16;
                let factor = od.get_u64(LIFE_TIME_FACTOR, 0).unwrap_or(0) as u8;
                return resolved(self.guarding.set_times(guard, factor, now));
            }
            ERROR_BEHAVIOUR => {
                if let Some(v) = od.get_u64(ERROR_BEHAVIOUR, sub)
                    && sub != 0
                {
                    self.errors.set(ErrorClass(sub), v as u8);
                }
            }
            _ => {}
        }
        None
    }

    /// The decoded 1016h entries, in sub-index order.
    pub fn consumer_entries(&self) -> impl Iterator<Item = ConsumerEntry> + '_ {
        self.consumer.entries()
    }

    /// The last state heard from a node monitored in 1016h.
    pub fn remote_state(&self, node: u8) -> Option<RemoteState> {
        self.consumer.remote_state(node)
    }

    /// Whether a node monitored in 1016h is timed out.
    pub fn is_heartbeat_timed_out(&self, node: u8) -> bool {
        self.consumer.is_timed_out(node)
    }

    /// Whether a life-guarding loss is outstanding.
    pub fn is_life_guarding_lost(&self) -> bool {
        self.guarding.is_lost()
    }
}
