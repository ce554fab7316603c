//! The [`Master`] handle: the API over the sans-IO core. Every method
//! queues work in the core and awaits its completion; the driver (tokio
//! or simulated time) moves frames and time.

use std::collections::HashMap;
use std::future::Future;
use std::io;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use drivebus_can::{Frame, Instant};
use drivebus_nmt::{NmtCommand, RemoteState};
use drivebus_od::ObjectDictionary;
use drivebus_sync::TimeOfDay;
use drivebus_transport::{CanBus, CanTx, TrySendError};
use tokio::sync::{Notify, broadcast};
use tokio::task::AbortHandle;

use crate::core::{Core, PdoSink, Stats};

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
    /// The bus failed; the driver has stopped.
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
    /// When the last heartbeat / guarding answer arrived, on the master's
    /// time axis ([`Master::now`]).
    pub last_heartbeat: Option<Instant>,
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

/// Why waiting failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum WaitError {
    /// Nothing within the timeout.
    Timeout,
    /// The master's bus is closed.
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

/// How the core is driven.
pub(crate) enum Driver {
    /// A tokio task on a transport (`driver::tokio`).
    Tokio {
        clock: drivebus_transport::clock::TokioClock,
        tx: CanTx,
        /// Wakes the driver task: frames queued or an earlier deadline.
        kick: Arc<Notify>,
        /// Frames the driver has handed to the transport.
        sent: AtomicU64,
        /// Signalled whenever `sent` grows.
        sent_notify: Notify,
        /// Held while taking the core's queue and handing it to the
        /// transport: whoever holds it sends everything queued so far, in
        /// order (the driver task, or an API call that queued frames).
        send_lock: tokio::sync::Mutex<()>,
    },
    /// The simulated-time loop of `driver::sim` (it polls and sends after
    /// every step of the caller's future, so nothing needs waking).
    Sim {
        /// Simulated nanoseconds, written by the loop.
        now: AtomicU64,
    },
}

pub(crate) struct Shared {
    core: Mutex<Core>,
    pub(crate) config: MasterConfig,
    pub(crate) driver: Driver,
    /// LSS has one COB-ID pair: one LSS operation at a time.
    pub(crate) lss_lock: tokio::sync::Mutex<()>,
    tasks: Mutex<Vec<AbortHandle>>,
}

impl Drop for Shared {
    fn drop(&mut self) {
        for h in self.tasks.get_mut().unwrap_or_else(|e| e.into_inner()).drain(..) {
            h.abort();
        }
    }
}

impl Shared {
    pub(crate) fn new(config: MasterConfig, driver: Driver, now: Instant) -> Shared {
        Shared {
            core: Mutex::new(Core::new(now, config.channel_capacity)),
            config,
            driver,
            lss_lock: tokio::sync::Mutex::new(()),
            tasks: Mutex::new(Vec::new()),
        }
    }

    pub(crate) fn core(&self) -> MutexGuard<'_, Core> {
        // A panic while holding the lock leaves plain data; keep going.
        self.core.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub(crate) fn add_task(&self, h: AbortHandle) {
        self.tasks.lock().unwrap_or_else(|e| e.into_inner()).push(h);
    }

    /// The driver's now.
    pub(crate) fn now(&self) -> Instant {
        match &self.driver {
            Driver::Tokio { clock, .. } => clock.now(),
            Driver::Sim { now } => Instant::from_nanos(now.load(Ordering::Acquire)),
        }
    }

    /// Runs `f` on the core at the driver's now, then wakes the driver if
    /// `f` queued frames or armed an earlier deadline.
    pub(crate) fn with_core<R>(&self, f: impl FnOnce(&mut Core) -> R) -> R {
        self.with_core_then(true, f)
    }

    fn with_core_then<R>(&self, kick_for_frames: bool, f: impl FnOnce(&mut Core) -> R) -> R {
        let now = self.now();
        let mut c = self.core();
        c.advance(now);
        let r = f(&mut c);
        let wake = (kick_for_frames && c.has_tx()) || c.next_deadline().is_some_and(|t| c.wakes_driver(t));
        drop(c);
        if wake && let Driver::Tokio { kick, .. } = &self.driver {
            kick.notify_one();
        }
        r
    }

    /// [`with_core`](Self::with_core), then sends what `f` queued from the
    /// calling task when the transport takes it at once (no hop through
    /// the driver task; the driver sends it otherwise).
    pub(crate) fn with_core_and_send<R>(&self, f: impl FnOnce(&mut Core) -> R) -> R {
        let r = self.with_core_then(false, f);
        self.pump();
        r
    }

    /// Hands the core's queue to the transport without waiting. Never
    /// awaits: the caller's future may be left unpolled (a select, a
    /// probe polled once), and a lock held across an await there would
    /// stall the driver task. What the transport cannot take at once, or
    /// what another sender is busy with, is left to the driver (kicked).
    fn pump(&self) {
        let Driver::Tokio { tx, kick, sent, sent_notify, send_lock, .. } = &self.driver else { return };
        let Ok(_sending) = send_lock.try_lock() else {
            kick.notify_one();
            return;
        };
        let mut n = 0u64;
        {
            let mut c = self.core();
            let mut out = Vec::new();
            c.take_tx(&mut out);
            let mut frames = out.into_iter();
            while let Some(f) = frames.next() {
                match tx.try_send(f) {
                    Ok(()) => n += 1,
                    Err(TrySendError::Busy(f)) => {
                        c.requeue_front(std::iter::once(f).chain(frames));
                        kick.notify_one();
                        break;
                    }
                    Err(TrySendError::Failed(e)) => {
                        c.bus_error(e.to_string());
                        break;
                    }
                }
            }
        }
        if n > 0 {
            sent.fetch_add(n, Ordering::AcqRel);
            sent_notify.notify_waiters();
        }
    }
}

/// An async CANopen master on one bus. Cheap to clone; the driver stops
/// when the last clone is dropped.
///
/// Built with [`Master::new`] on a transport (driven by a tokio task), or
/// by [`SimBus`](crate::SimBus) on the deterministic virtual bus (driven in
/// simulated time). Both run the same code.
#[derive(Clone)]
pub struct Master {
    pub(crate) inner: Arc<Shared>,
}

impl std::fmt::Debug for Master {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Master").finish_non_exhaustive()
    }
}

impl Master {
    /// A master with the default configuration on `bus`, driven by a tokio
    /// task. Must be called inside a tokio runtime.
    pub fn new(bus: CanBus) -> Master {
        Master::with_config(bus, MasterConfig::default())
    }

    /// A master with `config`.
    pub fn with_config(bus: CanBus, config: MasterConfig) -> Master {
        crate::driver::tokio::spawn(bus, config)
    }

    /// Opens the bus named by `url` (`socketcand://HOST:PORT/CHANNEL`,
    /// `slcan:///dev/ttyUSB0?bitrate=N`, `socketcan://can0`, `virtual`;
    /// see `drivebus_transport::BusUrl`) and starts a master on it.
    pub async fn open(url: &str, config: MasterConfig) -> Result<Master, drivebus_transport::TransportError> {
        Ok(Master::with_config(drivebus_transport::open(url).await?, config))
    }

    /// The configuration.
    pub fn config(&self) -> &MasterConfig {
        &self.inner.config
    }

    /// The master's time: nanoseconds since it started (tokio driver) or
    /// the simulated bus time (virtual-bus driver).
    pub fn now(&self) -> Instant {
        self.inner.now()
    }

    /// Frame and transfer counters.
    pub fn stats(&self) -> Stats {
        let c = self.inner.core();
        Stats { sdo_transfers: c.sdo.started, ..c.stats }
    }

    /// Waits `d` on the master's clock.
    pub async fn sleep(&self, d: Duration) {
        let rx = self.inner.with_core(|c| {
            let at = c.now() + d;
            c.timer(at)
        });
        // A closed core (master dropped) ends the wait too.
        let _ = rx.await;
    }

    /// Runs `fut` for at most `d` on the master's clock; a lost bus ends
    /// the wait with [`WaitError::Closed`].
    pub async fn timeout<T>(&self, d: Duration, fut: impl Future<Output = T>) -> Result<T, WaitError> {
        tokio::select! {
            biased;
            v = fut => Ok(v),
            () = self.sleep(d) => Err(if self.bus_lost().is_some() { WaitError::Closed } else { WaitError::Timeout }),
        }
    }

    /// Why the bus was lost (the transport's words: "socketcand server
    /// closed the connection"), once it has been; `None` while it works.
    pub fn bus_lost(&self) -> Option<String> {
        self.inner.core().closed.clone()
    }

    /// Resolves when the bus is lost, with the reason (never on a bus
    /// that keeps working): a command that only listens (a trace, a
    /// gateway) selects on it to end instead of waiting for ever.
    pub async fn lost(&self) -> String {
        let mut rx = self.subscribe_events();
        loop {
            if let Some(why) = self.bus_lost() {
                return why;
            }
            match rx.recv().await {
                Ok(MasterEvent::BusError { reason }) => return reason,
                Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => {
                    return self.bus_lost().unwrap_or_else(|| "the master's bus is closed".into());
                }
            }
        }
    }

    /// Sends a raw frame (after everything queued before it).
    pub async fn send(&self, frame: Frame) -> io::Result<()> {
        if frame.is_rtr()
            && let Driver::Tokio { tx, .. } = &self.inner.driver
            && !tx.carries_rtr()
        {
            return Err(io::Error::new(
                io::ErrorKind::Unsupported,
                "this transport cannot carry RTR frames (socketcand)",
            ));
        }
        self.inner.with_core_and_send(|c| match &c.closed {
            Some(why) => Err(io::Error::new(io::ErrorKind::BrokenPipe, why.clone())),
            None => {
                c.send(frame);
                Ok(())
            }
        })
    }

    /// False when the transport cannot carry remote (RTR) frames
    /// (socketcand): [`send`](Self::send) refuses them and none are ever
    /// received.
    pub fn carries_rtr(&self) -> bool {
        match &self.inner.driver {
            Driver::Sim { .. } => true,
            Driver::Tokio { tx, .. } => tx.carries_rtr(),
        }
    }

    /// The error frames and error counters the transport reports
    /// (SocketCAN); `None` where it reports none (socketcand, slcan, the
    /// virtual bus).
    pub fn bus_errors(&self) -> Option<drivebus_transport::BusErrors> {
        match &self.inner.driver {
            Driver::Sim { .. } => None,
            Driver::Tokio { tx, .. } => tx.bus_errors(),
        }
    }

    /// Waits until every frame queued so far has been written by the
    /// transport (see `CanTx::flush`): after this, a program may report
    /// success and exit.
    pub async fn flush(&self) -> io::Result<()> {
        match &self.inner.driver {
            Driver::Sim { .. } => Ok(()),
            Driver::Tokio { tx, kick, sent, sent_notify, .. } => {
                let target = self.inner.core().queued();
                loop {
                    let notified = sent_notify.notified();
                    if sent.load(Ordering::Acquire) >= target {
                        break;
                    }
                    if let Some(why) = &self.inner.core().closed {
                        return Err(io::Error::new(io::ErrorKind::BrokenPipe, why.clone()));
                    }
                    kick.notify_one();
                    notified.await;
                }
                tx.flush().await
            }
        }
    }

    /// [`flush`](Self::flush), then closes the transport connection so the
    /// peer has every frame (TCP FIN after the data; slcan `C`). The master
    /// is unusable afterwards.
    pub async fn close(&self) -> io::Result<()> {
        self.flush().await?;
        match &self.inner.driver {
            Driver::Sim { .. } => Ok(()),
            Driver::Tokio { tx, .. } => tx.close().await,
        }
    }

    /// Every received frame from now on (a bus monitor). Slow readers lose
    /// the oldest frames.
    pub fn subscribe_frames(&self) -> broadcast::Receiver<Frame> {
        let c = self.inner.core();
        if c.closed.is_some() { closed_receiver() } else { c.frames.subscribe() }
    }

    /// Events from now on.
    pub fn subscribe_events(&self) -> broadcast::Receiver<MasterEvent> {
        let c = self.inner.core();
        if c.closed.is_some() { closed_receiver() } else { c.events.subscribe() }
    }

    /// SYNCs sent by this master's producer from now on.
    pub fn subscribe_sync(&self) -> broadcast::Receiver<SyncTick> {
        let c = self.inner.core();
        if c.closed.is_some() { closed_receiver() } else { c.sync_ticks.subscribe() }
    }

    /// Uses `od` (e.g. from an EDS via `drivebus_eds::to_od`) for the data
    /// types of `node`'s objects in [`SdoHandle::read_value`](crate::SdoHandle::read_value).
    pub fn set_eds(&self, node: u8, od: ObjectDictionary) {
        self.inner.core().eds.insert(node, Arc::new(od));
    }

    /// Builder form of [`set_eds`](Self::set_eds).
    pub fn with_eds(self, node: u8, od: ObjectDictionary) -> Master {
        self.set_eds(node, od);
        self
    }

    /// The dictionary registered for `node`.
    pub fn eds(&self, node: u8) -> Option<Arc<ObjectDictionary>> {
        self.inner.core().eds.get(&node).cloned()
    }

    /// Extra EMCY texts for `node` (personality / manufacturer codes); they
    /// take precedence over the standard texts.
    pub fn add_emcy_texts<S: Into<String>>(&self, node: u8, texts: impl IntoIterator<Item = (u16, S)>) {
        let mut c = self.inner.core();
        let mut table: HashMap<u16, String> =
            c.emcy_tables.get(&node).map(|t| (**t).clone()).unwrap_or_default();
        table.extend(texts.into_iter().map(|(code, s)| (code, s.into())));
        c.emcy_tables.insert(node, Arc::new(table));
    }

    /// The text for EMCY `code` from `node`.
    pub fn emcy_text(&self, node: u8, code: u16) -> Option<String> {
        self.inner.core().emcy_text(node, code)
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
        self.timeout(timeout, fut).await.unwrap_or(Err(WaitError::Timeout))
    }

    fn expect(
        &self,
        timeout: Duration,
        pred: impl Fn(&MasterEvent) -> bool + Send + 'static,
    ) -> impl Future<Output = Result<(), WaitError>> + 'static {
        let mut rx = self.subscribe_events();
        let master = self.clone();
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
            master.timeout(timeout, fut).await.unwrap_or(Err(WaitError::Timeout))
        }
    }

    /// The last state `node` reported.
    pub fn node_state(&self, node: u8) -> Option<RemoteState> {
        self.inner.core().nodes.get(&node).and_then(|s| s.state)
    }

    /// Everything known about `node`.
    pub fn node_status(&self, node: u8) -> Option<NodeStatus> {
        self.inner.core().nodes.get(&node).cloned()
    }

    /// Nodes heard so far (boot-up, heartbeat, guarding, SDO response,
    /// EMCY): the passive scan.
    pub fn seen_nodes(&self) -> Vec<u8> {
        self.inner.core().nodes.iter().filter(|(_, s)| s.frames > 0).map(|(n, _)| *n).collect()
    }

    /// Monitors `node`'s heartbeat: [`MasterEvent::HeartbeatLost`] when
    /// none arrives within `timeout` (monitoring starts with the next
    /// heartbeat, as a CiA 301 consumer). `None` stops monitoring.
    pub fn monitor_heartbeat(&self, node: u8, timeout: Option<Duration>) {
        self.inner.with_core(|c| c.monitor(node, timeout));
    }

    /// Starts node guarding of `node` (CiA 301 §7.2.8.3.2.1): a remote
    /// frame on 700h+node every `period`; lost after `period × life_factor`
    /// without an answer. Needs a transport that carries RTR frames
    /// (virtual, SocketCAN, slcan; not socketcand): on others the first
    /// request fails and is returned.
    pub async fn start_guarding(&self, node: u8, period: Duration, life_factor: u8) -> io::Result<()> {
        self.send(Frame::remote(0x700 + u16::from(node & 0x7F), 1)).await?;
        self.inner.with_core(|c| {
            c.monitor(node, Some(period * u32::from(life_factor.max(1))));
            c.start_guarding(node, period);
        });
        Ok(())
    }

    /// Stops guarding `node` and its monitoring.
    pub fn stop_guarding(&self, node: u8) {
        self.inner.with_core(|c| {
            c.stop_guarding(node);
            c.monitor(node, None);
        });
    }

    // ---- SYNC / TIME ----

    /// Starts the SYNC producer (080h) with `period`; with `counter_overflow`
    /// in 2..=240 the frames carry a counter 1..=overflow (CiA 301 1019h),
    /// otherwise they are empty. Replaces a running producer.
    pub fn start_sync(&self, period: Duration, counter_overflow: u8) {
        self.inner.with_core(|c| c.start_sync(period, counter_overflow));
    }

    /// Stops the SYNC producer.
    pub fn stop_sync(&self) {
        self.inner.with_core(|c| c.stop_sync());
    }

    /// True while the SYNC producer runs.
    pub fn sync_running(&self) -> bool {
        self.inner.core().sync_running()
    }

    /// Produces this master's own heartbeat (`700h + node`, `[state]`, e.g.
    /// 05h operational) every `period_ms`, the first one period from now
    /// (CiA 301 §7.2.8.3.2.2); 0 stops it.
    pub fn start_heartbeat(&self, node: u8, state: RemoteState, period_ms: u16) {
        self.inner.with_core(|c| c.start_heartbeat(node & 0x7F, state.code(), period_ms));
    }

    /// Stops the heartbeat of [`start_heartbeat`](Self::start_heartbeat).
    pub fn stop_heartbeat(&self) {
        self.inner.with_core(|c| c.start_heartbeat(0, 0, 0));
    }

    /// Produces a TIME stamp (100h) every `period`, the first at once;
    /// `unix_ms` is the Unix time (ms) now, the stamps follow the master's
    /// clock from there (CiA 301 §7.2.6).
    pub fn start_time(&self, period: Duration, unix_ms: u64) {
        self.inner.with_core(|c| c.start_time(period, unix_ms));
    }

    /// Stops the TIME producer.
    pub fn stop_time(&self) {
        self.inner.with_core(|c| c.stop_time());
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
        let mut c = self.inner.core();
        if c.closed.is_some() { closed_receiver() } else { c.subscribe_pdo(cob_id) }
    }

    /// Calls `f` with every frame received on `cob_id` and its time, in
    /// frame order, inside the driver; it must be quick and must not call
    /// back into the master. Stops when the returned guard is dropped.
    pub fn on_pdo(&self, cob_id: u16, f: impl Fn(&Frame, Instant) + Send + Sync + 'static) -> PdoCallback {
        let id = self.add_pdo_sink(cob_id, Arc::new(f));
        PdoCallback { master: self.clone(), id }
    }

    pub(crate) fn add_pdo_sink(&self, cob_id: u16, f: PdoSink) -> u64 {
        self.inner.core().add_pdo_sink(cob_id, f)
    }

    pub(crate) fn remove_pdo_sink(&self, id: u64) {
        self.inner.core().remove_pdo_sink(id);
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

/// A receiver that reports `Closed` at once: what a subscriber gets after
/// the bus was lost.
fn closed_receiver<T: Clone>() -> broadcast::Receiver<T> {
    broadcast::channel(1).1
}

/// A PDO callback registered with [`Master::on_pdo`]; removed on drop.
pub struct PdoCallback {
    master: Master,
    id: u64,
}

impl std::fmt::Debug for PdoCallback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PdoCallback").field("id", &self.id).finish()
    }
}

impl Drop for PdoCallback {
    fn drop(&mut self) {
        self.master.remove_pdo_sink(self.id);
    }
}
