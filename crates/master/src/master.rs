//! The master core: receive task, node table, events, NMT, heartbeat and
//! guarding monitor, EMCY consumer, SYNC and TIME producers.

use std::collections::{BTreeMap, HashMap};
use std::future::Future;
use std::io;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use drivebus_can::Frame;
use drivebus_nmt::{NmtCommand, RemoteState};
use drivebus_od::ObjectDictionary;
use drivebus_sync::TimeOfDay;
use drivebus_transport::{CanBus, CanRx, CanTx};
use tokio::sync::{Notify, broadcast, mpsc};
use tokio::task::AbortHandle;
use tokio::time::Instant as TokioInstant;

use crate::clock::Clock;

/// Master-wide settings.
#[derive(Clone, Debug)]
pub struct MasterConfig {
    /// Default SDO response timeout.
    pub sdo_timeout: Duration,
    /// Default SDO retries after a timeout.
    pub sdo_retries: u8,
    /// Capacity of the event and PDO broadcast channels.
    pub channel_capacity: usize,
}

impl Default for MasterConfig {
    fn default() -> Self {
        MasterConfig { sdo_timeout: Duration::from_millis(500), sdo_retries: 0, channel_capacity: 1024 }
    }
}

/// Something the master saw on the bus.
#[derive(Clone, Debug, PartialEq)]
pub enum MasterEvent {
    /// A boot-up message (700h + node, `[00]`).
    Bootup {
        /// Node-ID.
        node: u8,
    },
    /// A heartbeat or node-guarding answer.
    Heartbeat {
        /// Node-ID.
        node: u8,
        /// Reported state.
        state: RemoteState,
    },
    /// A monitored node missed its heartbeat / guarding deadline.
    HeartbeatLost {
        /// Node-ID.
        node: u8,
    },
    /// A node reported as lost is heard again.
    HeartbeatRecovered {
        /// Node-ID.
        node: u8,
    },
    /// An emergency message (080h + node).
    Emcy {
        /// Node-ID.
        node: u8,
        /// Error code (0000h: error reset / no error).
        code: u16,
        /// Error register (1001h).
        register: u8,
        /// Manufacturer-specific bytes.
        data: [u8; 5],
        /// Text of the code: the node's registered table first, then the
        /// CiA 301/402 standard texts.
        text: Option<String>,
    },
    /// The bus failed; the receive task has ended.
    BusError {
        /// Why.
        reason: String,
    },
}

/// What the master knows about a node.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeStatus {
    /// Last reported NMT state (heartbeat, guarding or boot-up).
    pub state: Option<RemoteState>,
    /// When the last heartbeat / guarding answer arrived.
    pub last_heartbeat: Option<TokioInstant>,
    /// Heartbeat / guarding timeout being monitored.
    pub monitor: Option<Duration>,
    /// The monitored deadline passed without a heartbeat.
    pub lost: bool,
    /// Boot-ups seen.
    pub bootups: u64,
    /// Frames seen from the node (heartbeat, SDO response, EMCY).
    pub frames: u64,
}

/// A SYNC sent by the master's producer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncTick {
    /// SYNCs sent since the producer started (1 for the first).
    pub seq: u64,
    /// The counter byte, when the producer uses one.
    pub counter: Option<u8>,
}

/// Why waiting for a node failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum WaitError {
    /// Nothing within the timeout.
    Timeout,
    /// The master's receive task ended.
    Closed,
}

impl std::fmt::Display for WaitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            WaitError::Timeout => "timed out",
            WaitError::Closed => "the master's bus is closed",
        })
    }
}

impl std::error::Error for WaitError {}

/// A synchronous PDO consumer (see [`Master::add_pdo_sink`]).
pub(crate) type PdoSink = Arc<dyn Fn(&Frame) + Send + Sync>;

#[derive(Default)]
pub(crate) struct State {
    pub(crate) sdo_routes: HashMap<u16, mpsc::UnboundedSender<Frame>>,
    pub(crate) sdo_locks: HashMap<u16, Arc<tokio::sync::Mutex<()>>>,
    pub(crate) pdo: HashMap<u16, broadcast::Sender<Frame>>,
    /// Synchronous PDO consumers, called in the receive task in frame
    /// order (so after an SDO response they have seen every earlier PDO).
    pdo_sinks: HashMap<u16, Vec<(u64, PdoSink)>>,
    next_sink: u64,
    pub(crate) nodes: BTreeMap<u8, NodeStatus>,
    pub(crate) eds: HashMap<u8, Arc<ObjectDictionary>>,
    pub(crate) emcy_tables: HashMap<u8, Arc<HashMap<u16, String>>>,
    sync_task: Option<AbortHandle>,
    guard_tasks: HashMap<u8, AbortHandle>,
}

pub(crate) struct Inner {
    pub(crate) tx: CanTx,
    pub(crate) clock: Clock,
    pub(crate) config: MasterConfig,
    pub(crate) events: broadcast::Sender<MasterEvent>,
    pub(crate) frames: broadcast::Sender<Frame>,
    pub(crate) lss: broadcast::Sender<Frame>,
    pub(crate) lss_lock: tokio::sync::Mutex<()>,
    pub(crate) sync_ticks: broadcast::Sender<SyncTick>,
    state: Mutex<State>,
    monitor: Notify,
}

impl Inner {
    pub(crate) fn state(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock leaves plain data; keep going.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Background tasks of one master; aborted when the last [`Master`] clone
/// is dropped.
struct Tasks(Mutex<Vec<AbortHandle>>);

impl Tasks {
    fn push(&self, h: AbortHandle) {
        let mut v = self.0.lock().unwrap_or_else(|e| e.into_inner());
        v.retain(|h| !h.is_finished());
        v.push(h);
    }
}

impl Drop for Tasks {
    fn drop(&mut self) {
        for h in self.0.lock().unwrap_or_else(|e| e.into_inner()).drain(..) {
            h.abort();
        }
    }
}

/// An async CANopen master on one bus. Cheap to clone; the background
/// tasks (receive, heartbeat monitor, SYNC producer, guarding) stop when
/// the last clone is dropped.
#[derive(Clone)]
pub struct Master {
    pub(crate) inner: Arc<Inner>,
    tasks: Arc<Tasks>,
}

impl std::fmt::Debug for Master {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Master").finish_non_exhaustive()
    }
}

impl Master {
    /// A master with the default configuration. Must be called inside a
    /// tokio runtime (it spawns the receive task).
    pub fn new(bus: CanBus) -> Master {
        Master::with_config(bus, MasterConfig::default())
    }

    /// A master with `config`.
    pub fn with_config(bus: CanBus, config: MasterConfig) -> Master {
        let (tx, rx) = bus.split();
        let cap = config.channel_capacity.max(16);
        let inner = Arc::new(Inner {
            tx,
            clock: Clock::new(),
            events: broadcast::channel(cap).0,
            frames: broadcast::channel(cap.max(4096)).0,
            lss: broadcast::channel(256).0,
            lss_lock: tokio::sync::Mutex::new(()),
            sync_ticks: broadcast::channel(64).0,
            config,
            state: Mutex::new(State::default()),
            monitor: Notify::new(),
        });
        let tasks = Arc::new(Tasks(Mutex::new(Vec::new())));
        tasks.push(tokio::spawn(rx_loop(inner.clone(), rx)).abort_handle());
        tasks.push(tokio::spawn(monitor_loop(inner.clone())).abort_handle());
        Master { inner, tasks }
    }

    /// The configuration.
    pub fn config(&self) -> &MasterConfig {
        &self.inner.config
    }

    /// Sends a raw frame.
    pub async fn send(&self, frame: Frame) -> io::Result<()> {
        self.inner.tx.send(frame).await
    }

    /// Every received frame from now on (a bus monitor). Slow readers lose
    /// the oldest frames.
    pub fn subscribe_frames(&self) -> broadcast::Receiver<Frame> {
        self.inner.frames.subscribe()
    }

    /// Events from now on.
    pub fn subscribe_events(&self) -> broadcast::Receiver<MasterEvent> {
        self.inner.events.subscribe()
    }

    /// SYNCs sent by this master's producer from now on.
    pub fn subscribe_sync(&self) -> broadcast::Receiver<SyncTick> {
        self.inner.sync_ticks.subscribe()
    }

    /// Uses `od` (e.g. from an EDS via `drivebus_eds::to_od`) for the data
    /// types of `node`'s objects in [`SdoHandle::read_value`](crate::SdoHandle::read_value).
    pub fn set_eds(&self, node: u8, od: ObjectDictionary) {
        self.inner.state().eds.insert(node, Arc::new(od));
    }

    /// Builder form of [`set_eds`](Self::set_eds).
    pub fn with_eds(self, node: u8, od: ObjectDictionary) -> Master {
        self.set_eds(node, od);
        self
    }

    /// The dictionary registered for `node`.
    pub fn eds(&self, node: u8) -> Option<Arc<ObjectDictionary>> {
        self.inner.state().eds.get(&node).cloned()
    }

    /// Extra EMCY texts for `node` (personality / manufacturer codes); they
    /// take precedence over the standard texts.
    pub fn add_emcy_texts<S: Into<String>>(&self, node: u8, texts: impl IntoIterator<Item = (u16, S)>) {
        let mut st = self.inner.state();
        let mut table: HashMap<u16, String> =
            st.emcy_tables.get(&node).map(|t| (**t).clone()).unwrap_or_default();
        table.extend(texts.into_iter().map(|(c, s)| (c, s.into())));
        st.emcy_tables.insert(node, Arc::new(table));
    }

    /// The text for EMCY `code` from `node`.
    pub fn emcy_text(&self, node: u8, code: u16) -> Option<String> {
        emcy_text(&self.inner.state(), node, code)
    }

    // ---- NMT ----

    /// Sends NMT `cmd` to `node` (0 = all nodes).
    pub async fn nmt(&self, node: u8, cmd: NmtCommand) -> io::Result<()> {
        self.send(Frame::new(0x000, &[cmd.cs(), node])).await
    }

    /// Resets `node` (NMT reset node) and waits for its boot-up.
    pub async fn reset_node(&self, node: u8, timeout: Duration) -> Result<(), WaitError> {
        let boot = self.expect_bootup(node, timeout);
        self.nmt(node, NmtCommand::ResetNode).await.map_err(|_| WaitError::Closed)?;
        boot.await
    }

    /// Resets `node`'s communication and waits for its boot-up.
    pub async fn reset_communication(&self, node: u8, timeout: Duration) -> Result<(), WaitError> {
        let boot = self.expect_bootup(node, timeout);
        self.nmt(node, NmtCommand::ResetCommunication).await.map_err(|_| WaitError::Closed)?;
        boot.await
    }

    /// A future resolving at the next boot-up of `node` (0: any node). It
    /// listens from the moment this is called, so create it *before*
    /// sending the command that causes the boot-up.
    pub fn expect_bootup(
        &self,
        node: u8,
        timeout: Duration,
    ) -> impl Future<Output = Result<(), WaitError>> + 'static {
        self.expect(timeout, move |e| matches!(e, MasterEvent::Bootup { node: n } if node == 0 || *n == node))
    }

    /// Waits for the next boot-up of `node` (see [`expect_bootup`](Self::expect_bootup) to avoid races).
    pub async fn wait_for_bootup(&self, node: u8, timeout: Duration) -> Result<(), WaitError> {
        self.expect_bootup(node, timeout).await
    }

    /// Waits for the next heartbeat (or guarding answer, or boot-up) of `node`.
    pub async fn wait_for_heartbeat(&self, node: u8, timeout: Duration) -> Result<RemoteState, WaitError> {
        let mut rx = self.subscribe_events();
        let fut = async move {
            loop {
                match rx.recv().await {
                    Ok(MasterEvent::Heartbeat { node: n, state }) if n == node => return Ok(state),
                    Ok(MasterEvent::Bootup { node: n }) if n == node => return Ok(RemoteState::BootUp),
                    Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                    Err(broadcast::error::RecvError::Closed) => return Err(WaitError::Closed),
                }
            }
        };
        tokio::time::timeout(timeout, fut).await.unwrap_or(Err(WaitError::Timeout))
    }

    fn expect(
        &self,
        timeout: Duration,
        pred: impl Fn(&MasterEvent) -> bool + Send + 'static,
    ) -> impl Future<Output = Result<(), WaitError>> + 'static {
        let mut rx = self.subscribe_events();
        async move {
            let fut = async move {
                loop {
                    match rx.recv().await {
                        Ok(e) if pred(&e) => return Ok(()),
                        Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                        Err(broadcast::error::RecvError::Closed) => return Err(WaitError::Closed),
                    }
                }
            };
            tokio::time::timeout(timeout, fut).await.unwrap_or(Err(WaitError::Timeout))
        }
    }

    /// The last state `node` reported.
    pub fn node_state(&self, node: u8) -> Option<RemoteState> {
        self.inner.state().nodes.get(&node).and_then(|s| s.state)
    }

    /// Everything known about `node`.
    pub fn node_status(&self, node: u8) -> Option<NodeStatus> {
        self.inner.state().nodes.get(&node).cloned()
    }

    /// Nodes heard so far (boot-up, heartbeat, guarding, SDO response,
    /// EMCY): the passive scan.
    pub fn seen_nodes(&self) -> Vec<u8> {
        self.inner.state().nodes.iter().filter(|(_, s)| s.frames > 0).map(|(n, _)| *n).collect()
    }

    /// Monitors `node`'s heartbeat: [`MasterEvent::HeartbeatLost`] when
    /// none arrives within `timeout` (monitoring starts with the next
    /// heartbeat, as a CiA 301 consumer). `None` stops monitoring.
    pub fn monitor_heartbeat(&self, node: u8, timeout: Option<Duration>) {
        let mut st = self.inner.state();
        let s = st.nodes.entry(node).or_default();
        s.monitor = timeout;
        s.lost = false;
        drop(st);
        self.inner.monitor.notify_one();
    }

    /// Starts node guarding of `node` (CiA 301 §7.2.8.3.2.1): a remote
    /// frame on 700h+node every `period`; lost after `period × life_factor`
    /// without an answer. Needs a transport that carries RTR frames
    /// (virtual, SocketCAN, slcan; not socketcand): on others the first
    /// request fails and is returned.
    pub async fn start_guarding(&self, node: u8, period: Duration, life_factor: u8) -> io::Result<()> {
        let rtr = Frame::remote(0x700 + u16::from(node & 0x7F), 1);
        self.send(rtr).await?;
        self.monitor_heartbeat(node, Some(period * u32::from(life_factor.max(1))));
        let tx = self.inner.tx.clone();
        let h = tokio::spawn(async move {
            let mut tick = tokio::time::interval_at(TokioInstant::now() + period, period);
            tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            loop {
                tick.tick().await;
                if tx.send(rtr).await.is_err() {
                    return;
                }
            }
        })
        .abort_handle();
        self.tasks.push(h.clone());
        if let Some(old) = self.inner.state().guard_tasks.insert(node, h) {
            old.abort();
        }
        Ok(())
    }

    /// Stops guarding `node` and its monitoring.
    pub fn stop_guarding(&self, node: u8) {
        if let Some(h) = self.inner.state().guard_tasks.remove(&node) {
            h.abort();
        }
        self.monitor_heartbeat(node, None);
    }

    // ---- SYNC / TIME ----

    /// Starts the SYNC producer (080h) with `period`; with `counter_overflow`
    /// in 2..=240 the frames carry a counter 1..=overflow (CiA 301 1019h),
    /// otherwise they are empty. Replaces a running producer.
    pub fn start_sync(&self, period: Duration, counter_overflow: u8) {
        let tx = self.inner.tx.clone();
        let ticks = self.inner.sync_ticks.clone();
        let period = period.max(Duration::from_micros(100));
        let h = tokio::spawn(async move {
            let mut tick = tokio::time::interval(period);
            // Late ticks are skipped, not bunched: a burst of SYNCs would
            // make synchronous drives jump.
            tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
            let mut counter = 0u8;
            let mut seq = 0u64;
            loop {
                tick.tick().await;
                let c = if (2..=240).contains(&counter_overflow) {
                    counter = if counter >= counter_overflow { 1 } else { counter + 1 };
                    Some(counter)
                } else {
                    None
                };
                let frame = match c {
                    Some(c) => Frame::new(0x080, &[c]),
                    None => Frame::new(0x080, &[]),
                };
                if tx.send(frame).await.is_err() {
                    return;
                }
                seq += 1;
                let _ = ticks.send(SyncTick { seq, counter: c });
            }
        })
        .abort_handle();
        self.tasks.push(h.clone());
        if let Some(old) = self.inner.state().sync_task.replace(h) {
            old.abort();
        }
    }

    /// Stops the SYNC producer.
    pub fn stop_sync(&self) {
        if let Some(h) = self.inner.state().sync_task.take() {
            h.abort();
        }
    }

    /// True while the SYNC producer runs.
    pub fn sync_running(&self) -> bool {
        self.inner.state().sync_task.as_ref().is_some_and(|h| !h.is_finished())
    }

    /// Sends a TIME stamp (100h) for `unix_ms` milliseconds since the Unix
    /// epoch. Times before 1984 or after 2163 cannot be encoded.
    pub async fn send_time(&self, unix_ms: u64) -> io::Result<()> {
        let t = TimeOfDay::from_unix_ms(unix_ms)
            .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "time outside 1984..2163"))?;
        self.send(Frame::new(0x100, &t.to_bytes())).await
    }

    // ---- PDO ----

    /// Frames received on `cob_id` (TPDOs of the nodes) from now on.
    pub fn subscribe_pdo(&self, cob_id: u16) -> broadcast::Receiver<Frame> {
        let cap = self.inner.config.channel_capacity.max(16);
        self.inner.state().pdo.entry(cob_id).or_insert_with(|| broadcast::channel(cap).0).subscribe()
    }

    /// Registers `f` to be called in the receive task for every frame on
    /// `cob_id`; it must be quick and must not call back into the master.
    pub(crate) fn add_pdo_sink(&self, cob_id: u16, f: PdoSink) -> u64 {
        let mut st = self.inner.state();
        st.next_sink += 1;
        let id = st.next_sink;
        st.pdo_sinks.entry(cob_id).or_default().push((id, f));
        id
    }

    /// Removes a sink added by [`add_pdo_sink`](Self::add_pdo_sink).
    pub(crate) fn remove_pdo_sink(&self, id: u64) {
        for v in self.inner.state().pdo_sinks.values_mut() {
            v.retain(|(i, _)| *i != id);
        }
    }

    /// Sends a PDO (an RPDO of the nodes) on `cob_id`; at most 8 bytes.
    pub async fn send_pdo(&self, cob_id: u16, data: &[u8]) -> io::Result<()> {
        let id = drivebus_can::CanId::standard(cob_id)
            .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "COB-ID above 7FFh"))?;
        let f = Frame::try_new(id, data)
            .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "PDO longer than 8 bytes"))?;
        self.send(f).await
    }
}

fn emcy_text(st: &State, node: u8, code: u16) -> Option<String> {
    st.emcy_tables
        .get(&node)
        .and_then(|t| t.get(&code).cloned())
        .or_else(|| drivebus_emcy::describe(code).map(str::to_owned))
}

async fn rx_loop(inner: Arc<Inner>, mut rx: CanRx) {
    loop {
        match rx.recv().await {
            Ok(f) => dispatch(&inner, f),
            Err(e) => {
                let _ = inner.events.send(MasterEvent::BusError { reason: e.to_string() });
                return;
            }
        }
    }
}

fn dispatch(inner: &Inner, f: Frame) {
    if inner.frames.receiver_count() > 0 {
        let _ = inner.frames.send(f);
    }
    let Some(id) = f.std_id() else { return };
    let mut st = inner.state();
    if let Some(route) = st.sdo_routes.get(&id) {
        let _ = route.send(f);
    }
    if let Some(p) = st.pdo.get(&id) {
        let _ = p.send(f);
    }
    if let Some(sinks) = st.pdo_sinks.get(&id) {
        for (_, sink) in sinks {
            sink(&f);
        }
    }
    let node = (id & 0x7F) as u8;
    match id & 0x780 {
        0x080 if node != 0 && !f.is_rtr() => {
            if let Some(m) = drivebus_emcy::decode(&f) {
                st.nodes.entry(node).or_default().frames += 1;
                let text = emcy_text(&st, node, m.code);
                let _ = inner.events.send(MasterEvent::Emcy {
                    node,
                    code: m.code,
                    register: m.register,
                    data: m.data,
                    text,
                });
            }
        }
        0x580 if node != 0 && !f.is_rtr() => st.nodes.entry(node).or_default().frames += 1,
        0x700 if node != 0 && !f.is_rtr() && !f.is_empty() => {
            let state = RemoteState::from_code(f.data()[0]);
            let s = st.nodes.entry(node).or_default();
            let was_lost = std::mem::take(&mut s.lost);
            s.frames += 1;
            s.state = Some(state);
            s.last_heartbeat = Some(TokioInstant::now());
            if state == RemoteState::BootUp {
                s.bootups += 1;
                let _ = inner.events.send(MasterEvent::Bootup { node });
            } else {
                let _ = inner.events.send(MasterEvent::Heartbeat { node, state });
            }
            if was_lost {
                let _ = inner.events.send(MasterEvent::HeartbeatRecovered { node });
            }
            drop(st);
            inner.monitor.notify_one();
            return;
        }
        _ => {}
    }
    drop(st);
    if id == drivebus_lss::SLAVE_TO_MASTER {
        let _ = inner.lss.send(f);
    }
}

/// Raises `HeartbeatLost` for monitored nodes whose deadline passed.
async fn monitor_loop(inner: Arc<Inner>) {
    loop {
        let now = TokioInstant::now();
        let mut next: Option<TokioInstant> = None;
        {
            let mut st = inner.state();
            for (node, s) in st.nodes.iter_mut() {
                let (Some(t), Some(last), false) = (s.monitor, s.last_heartbeat, s.lost) else { continue };
                let deadline = last + t;
                if deadline <= now {
                    s.lost = true;
                    let _ = inner.events.send(MasterEvent::HeartbeatLost { node: *node });
                } else {
                    next = Some(next.map_or(deadline, |n: TokioInstant| n.min(deadline)));
                }
            }
        }
        let until = next.unwrap_or_else(|| now + Duration::from_secs(3600));
        tokio::select! {
            () = tokio::time::sleep_until(until) => {}
            () = inner.monitor.notified() => {}
        }
    }
}
