//! The bus: stations, configuration and the public API.

use alloc::boxed::Box;
use alloc::collections::{BinaryHeap, VecDeque};
use alloc::string::String;
use alloc::vec::Vec;
use core::cmp::{Ordering, Reverse};
use core::fmt;
use core::time::Duration;
use drivebus_can::{Device, Frame, Instant, LinkState};

use crate::candump::{self, CandumpRecord, LogEntry};
use crate::node::{NodeId, ProbeId};
use crate::stats::{BusStats, LoadWindow};
use crate::timing::{BUS_OFF_RECOVERY_BITS, bits_duration};
use drivebus_can::fault::{FaultRule, XorShift64};

/// How the bus behaves.
#[derive(Clone, Debug)]
pub struct BusConfig {
    /// Bit rate in bit/s. `None` (or `Some(0)`): frames take no time but are
    /// still sent one by one in arbitration order.
    pub bitrate: Option<u32>,
    /// Deliver every frame to its transmitter too (like SocketCAN's
    /// `recv_own_msgs`). Off: as on a real bus, a transmitter does not
    /// receive its own frame.
    pub echo: bool,
    /// Seed of the PRNG used by probabilistic fault rules and random bit flips.
    pub seed: u64,
    /// A bus-off station recovers by itself after 128 × 11 bit times. Needs a
    /// bitrate: in zero-time mode recovery would be instantaneous and an
    /// always-corrupting rule would loop forever, so there it is manual.
    pub auto_recovery: bool,
    /// Window for [`Bus::bus_load_window`].
    pub load_window: Duration,
    /// Keep the frame log in memory ([`Bus::log`]). It grows with every
    /// delivered frame: turn it off or drain it with [`Bus::take_log`] in
    /// long runs.
    pub log: bool,
    /// Microseconds added to simulated time in candump timestamps.
    pub log_epoch_us: u64,
    /// Interface name in candump lines.
    pub interface: String,
}

impl Default for BusConfig {
    fn default() -> Self {
        BusConfig {
            bitrate: None,
            echo: false,
            seed: 0x5EED,
            auto_recovery: true,
            load_window: Duration::from_secs(1),
            log: true,
            log_epoch_us: 0,
            interface: String::from("can0"),
        }
    }
}

impl BusConfig {
    /// Zero-time bus (the default).
    pub fn zero_time() -> Self {
        Self::default()
    }
    /// Bit-timed bus at `bitrate` bit/s.
    pub fn with_bitrate(bitrate: u32) -> Self {
        BusConfig { bitrate: Some(bitrate), ..Self::default() }
    }
    pub(crate) fn rate(&self) -> Option<u32> {
        self.bitrate.filter(|&b| b > 0)
    }
}

/// Handle of a rule added with [`Bus::add_fault`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RuleId(pub(crate) u32);

pub(crate) enum Endpoint {
    /// A device and whether it was started.
    Node(Box<dyn Device>, bool),
    Probe {
        received: Vec<(Instant, Frame)>,
        capture: bool,
    },
    /// A node whose power is off ([`Bus::power_off`]): no device.
    Off,
}

pub(crate) struct Station {
    pub(crate) endpoint: Endpoint,
    /// FIFO transmit queue; only the head competes in arbitration, like a
    /// controller with a single transmit buffer fed in order. This is what
    /// lets a low-priority head delay a later high-priority frame.
    pub(crate) queue: VecDeque<Frame>,
    pub(crate) link: LinkState,
    pub(crate) deadline: Option<Instant>,
    /// Transmit error counter (ISO 11898-1 fault confinement: +8 per error,
    /// −1 per success, bus-off above 255). Receive errors are not modelled.
    pub(crate) tec: u16,
    /// The head is the second transmission of a duplicated frame.
    pub(crate) head_is_retry: bool,
}

/// What happens when the frame on the wire completes.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Outcome {
    Deliver { frame: Frame, altered: bool },
    Drop,
    Delay(Duration),
    Duplicate,
    Error { bus_off: bool },
}

pub(crate) struct InFlight {
    pub(crate) from: usize,
    pub(crate) frame: Frame,
    pub(crate) done_at: Instant,
    pub(crate) outcome: Outcome,
}

pub(crate) enum TimedKind {
    Send { station: usize, frame: Frame },
    Deliver { from: usize, frame: Frame },
}

pub(crate) struct Timed {
    pub(crate) at: Instant,
    pub(crate) seq: u64,
    pub(crate) kind: TimedKind,
}

// Ordered by time, then insertion order, so equal times stay FIFO.
impl PartialEq for Timed {
    fn eq(&self, o: &Self) -> bool {
        (self.at, self.seq) == (o.at, o.seq)
    }
}
impl Eq for Timed {}
impl PartialOrd for Timed {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Timed {
    fn cmp(&self, o: &Self) -> Ordering {
        (self.at, self.seq).cmp(&(o.at, o.seq))
    }
}

/// A log sink: receives every candump line (without newline) as it happens.
pub type LogSink = Box<dyn FnMut(&str)>;

/// The virtual CAN bus on simulated time. See the crate documentation.
pub struct Bus {
    pub(crate) cfg: BusConfig,
    pub(crate) now: Instant,
    pub(crate) stations: Vec<Station>,
    pub(crate) inflight: Option<InFlight>,
    /// When the bus is idle again (end of the last intermission).
    pub(crate) idle_at: Instant,
    pub(crate) timed: BinaryHeap<Reverse<Timed>>,
    pub(crate) seq: u64,
    pub(crate) rules: Vec<Option<FaultRule>>,
    pub(crate) rng: XorShift64,
    pub(crate) stats: BusStats,
    pub(crate) window: LoadWindow,
    pub(crate) stats_origin: Instant,
    pub(crate) log: Vec<LogEntry>,
    pub(crate) sink: Option<LogSink>,
    pub(crate) line: String,
    external: Option<ProbeId>,
}

impl fmt::Debug for Bus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Bus")
            .field("now", &self.now)
            .field("stations", &self.stations.len())
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl Bus {
    /// An empty bus at time zero.
    pub fn new(cfg: BusConfig) -> Self {
        Bus {
            rng: XorShift64::new(cfg.seed),
            window: LoadWindow::new(cfg.load_window),
            cfg,
            now: Instant::ZERO,
            stations: Vec::new(),
            inflight: None,
            idle_at: Instant::ZERO,
            timed: BinaryHeap::new(),
            seq: 0,
            rules: Vec::new(),
            stats: BusStats::default(),
            stats_origin: Instant::ZERO,
            log: Vec::new(),
            sink: None,
            line: String::new(),
            external: None,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &BusConfig {
        &self.cfg
    }

    /// Current simulated time.
    pub fn now(&self) -> Instant {
        self.now
    }

    fn add_station(&mut self, endpoint: Endpoint, deadline: Option<Instant>) -> NodeId {
        let id = NodeId(u32::try_from(self.stations.len()).unwrap_or(u32::MAX));
        self.stations.push(Station {
            endpoint,
            queue: VecDeque::new(),
            link: LinkState::Active,
            deadline,
            tec: 0,
            head_is_retry: false,
        });
        id
    }

    /// Attaches a device. It is started ([`Device::start`]) and polled at
    /// the next step, so it can still be configured through
    /// [`Bus::node_mut`] until then; it hears no frame before it started.
    pub fn attach<D: Device + 'static>(&mut self, device: D) -> NodeId {
        self.add_station(Endpoint::Node(Box::new(device), false), Some(self.now))
    }

    /// Attaches a probe that records every frame it receives.
    pub fn attach_probe(&mut self) -> ProbeId {
        ProbeId(self.add_station(Endpoint::Probe { received: Vec::new(), capture: true }, None))
    }

    /// The node attached as `id`, if it is a `T`.
    pub fn node<T: 'static>(&self, id: NodeId) -> Option<&T> {
        match &self.station(id)?.endpoint {
            Endpoint::Node(n, _) => n.as_any().downcast_ref(),
            Endpoint::Probe { .. } | Endpoint::Off => None,
        }
    }

    /// The node attached as `id`, mutably, if it is a `T`. If you change
    /// what it will do, call [`Bus::wake`] so it is polled again.
    pub fn node_mut<T: 'static>(&mut self, id: NodeId) -> Option<&mut T> {
        match &mut self.station_mut(id)?.endpoint {
            Endpoint::Node(n, _) => n.as_any_mut().downcast_mut(),
            Endpoint::Probe { .. } | Endpoint::Off => None,
        }
    }

    /// Polls node `id` at the current time on the next step.
    pub fn wake(&mut self, id: NodeId) {
        let now = self.now;
        if let Some(st) = self.station_mut(id)
            && matches!(st.endpoint, Endpoint::Node(..))
        {
            st.deadline = Some(now);
        }
    }

    pub(crate) fn station(&self, id: NodeId) -> Option<&Station> {
        self.stations.get(usize::try_from(id.0).ok()?)
    }

    pub(crate) fn station_mut(&mut self, id: NodeId) -> Option<&mut Station> {
        self.stations.get_mut(usize::try_from(id.0).ok()?)
    }

    /// Queues `frame` at the back of station `from`'s transmit queue now.
    /// False if the station is unknown or not on the bus (frame discarded).
    pub fn send_from(&mut self, from: impl Into<NodeId>, frame: Frame) -> bool {
        let from = from.into();
        let Some(st) = self.station_mut(from) else { return false };
        if !st.link.is_on_bus() {
            self.stats.discarded += 1;
            return false;
        }
        st.queue.push_back(frame);
        true
    }

    /// Queues `frame` on station `from` at time `at` (now if `at` is past).
    /// False if the station is unknown.
    pub fn send_at(&mut self, from: impl Into<NodeId>, frame: Frame, at: Instant) -> bool {
        let from = from.into();
        let Ok(station) = usize::try_from(from.0) else { return false };
        if station >= self.stations.len() {
            return false;
        }
        self.push_timed(at.max(self.now), TimedKind::Send { station, frame });
        true
    }

    /// Injects an external frame (e.g. from a TCP client) at time `at`: it is
    /// sent by a built-in probe station that captures nothing, competing in
    /// arbitration like any other station.
    pub fn inject(&mut self, frame: Frame, at: Instant) {
        let p = self.external_probe();
        self.send_at(p, frame, at);
    }

    /// The built-in station that [`Bus::inject`] sends from (created on first use).
    pub fn external_probe(&mut self) -> ProbeId {
        match self.external {
            Some(p) => p,
            None => {
                let p =
                    ProbeId(self.add_station(Endpoint::Probe { received: Vec::new(), capture: false }, None));
                self.external = Some(p);
                p
            }
        }
    }

    /// Injects the frames of a candump log at their times relative to
    /// `epoch_us`; records before the epoch are skipped. Returns how many.
    pub fn replay<'a>(
        &mut self,
        records: impl IntoIterator<Item = &'a CandumpRecord>,
        epoch_us: u64,
    ) -> usize {
        let mut n = 0;
        for r in records {
            if let Some(at) = r.instant(epoch_us) {
                self.inject(r.frame, at);
                n += 1;
            }
        }
        n
    }

    pub(crate) fn push_timed(&mut self, at: Instant, kind: TimedKind) {
        self.seq += 1;
        self.timed.push(Reverse(Timed { at, seq: self.seq, kind }));
    }

    /// Frames a probe received so far, with their times, without taking them.
    pub fn received(&self, probe: ProbeId) -> &[(Instant, Frame)] {
        match self.station(probe.0).map(|s| &s.endpoint) {
            Some(Endpoint::Probe { received, .. }) => received,
            _ => &[],
        }
    }

    /// Takes the frames a probe received, with their delivery times.
    pub fn take_received_timed(&mut self, probe: ProbeId) -> Vec<(Instant, Frame)> {
        match self.station_mut(probe.0).map(|s| &mut s.endpoint) {
            Some(Endpoint::Probe { received, .. }) => core::mem::take(received),
            _ => Vec::new(),
        }
    }

    /// Takes the frames a probe received.
    pub fn take_received(&mut self, probe: ProbeId) -> Vec<Frame> {
        self.take_received_timed(probe).into_iter().map(|(_, f)| f).collect()
    }

    /// Frames waiting in a station's transmit queue.
    pub fn pending(&self, id: impl Into<NodeId>) -> usize {
        self.station(id.into()).map_or(0, |s| s.queue.len())
    }

    /// Connection state of a station (`None` if unknown).
    pub fn link_state(&self, id: impl Into<NodeId>) -> Option<LinkState> {
        self.station(id.into()).map(|s| s.link)
    }

    /// Transmit error counter of a station.
    pub fn tec(&self, id: impl Into<NodeId>) -> Option<u16> {
        self.station(id.into()).map(|s| s.tec)
    }

    /// Index of a station, if it exists.
    fn index(&self, id: NodeId) -> Option<usize> {
        usize::try_from(id.0).ok().filter(|&i| i < self.stations.len())
    }

    /// Puts a station bus-off now (queue flushed; automatic recovery if configured).
    pub fn set_bus_off(&mut self, id: impl Into<NodeId>) {
        if let Some(i) = self.index(id.into()) {
            self.go_bus_off(i);
        }
    }

    /// Ends a station's bus-off state now (error counter reset).
    pub fn recover(&mut self, id: impl Into<NodeId>) {
        if let Some(i) = self.index(id.into())
            && matches!(self.stations[i].link, LinkState::BusOff { .. })
        {
            self.stations[i].link = LinkState::Active;
            self.stations[i].tec = 0;
            self.notify_link(i);
        }
    }

    /// Unplugs a station: its queue is flushed, it sends and receives
    /// nothing (a frame it has on the wire completes). Its node keeps being
    /// polled, as a device whose cable was pulled keeps running.
    pub fn disconnect(&mut self, id: impl Into<NodeId>) {
        if let Some(i) = self.index(id.into())
            && self.stations[i].link != LinkState::Disconnected
        {
            let st = &mut self.stations[i];
            st.link = LinkState::Disconnected;
            st.head_is_retry = false;
            st.discard_if_offline(&mut self.stats);
            self.notify_link(i);
        }
    }

    /// Plugs a disconnected station back in (a node whose power is off
    /// stays off: [`Bus::power_on`]).
    pub fn reconnect(&mut self, id: impl Into<NodeId>) {
        if let Some(i) = self.index(id.into())
            && self.stations[i].link == LinkState::Disconnected
            && !matches!(self.stations[i].endpoint, Endpoint::Off)
        {
            self.stations[i].link = LinkState::Active;
            self.notify_link(i);
        }
    }

    /// Switches a node's power off: its device is gone with everything
    /// volatile in it (returned, to look at), it sends and hears nothing, a
    /// frame it has on the wire completes. `None` if `id` is not a node
    /// with power on.
    pub fn power_off(&mut self, id: impl Into<NodeId>) -> Option<Box<dyn Device>> {
        let i = self.index(id.into())?;
        let st = &mut self.stations[i];
        if !matches!(st.endpoint, Endpoint::Node(..)) {
            return None;
        }
        let Endpoint::Node(dev, _) = core::mem::replace(&mut st.endpoint, Endpoint::Off) else { return None };
        st.link = LinkState::Disconnected;
        st.head_is_retry = false;
        st.deadline = None;
        st.tec = 0;
        st.discard_if_offline(&mut self.stats);
        Some(dev)
    }

    /// Switches a node's power back on with `device` as it is at power-on
    /// (built again from its description and non-volatile storage, as the
    /// real one boots): it starts at the next step. False if `id` is not a
    /// node whose power is off.
    pub fn power_on<D: Device + 'static>(&mut self, id: impl Into<NodeId>, device: D) -> bool {
        let Some(i) = self.index(id.into()) else { return false };
        let st = &mut self.stations[i];
        if !matches!(st.endpoint, Endpoint::Off) {
            return false;
        }
        st.endpoint = Endpoint::Node(Box::new(device), false);
        st.link = LinkState::Active;
        st.deadline = Some(self.now);
        true
    }

    pub(crate) fn go_bus_off(&mut self, i: usize) {
        let recover_at = match (self.cfg.auto_recovery, self.cfg.rate()) {
            (true, Some(rate)) => Some(self.now + bits_duration(BUS_OFF_RECOVERY_BITS, rate)),
            _ => None,
        };
        let Some(st) = self.stations.get_mut(i) else { return };
        st.link = LinkState::BusOff { recover_at };
        st.tec = 256;
        st.head_is_retry = false;
        self.stats.discarded += st.queue.len() as u64;
        st.queue.clear();
        self.stats.bus_off += 1;
        self.notify_link(i);
    }

    /// Adds a fault rule (tried after the ones already added).
    pub fn add_fault(&mut self, rule: FaultRule) -> RuleId {
        self.rules.push(Some(rule));
        RuleId(u32::try_from(self.rules.len() - 1).unwrap_or(u32::MAX))
    }

    /// Removes a fault rule, returning it.
    pub fn remove_fault(&mut self, id: RuleId) -> Option<FaultRule> {
        self.rules.get_mut(usize::try_from(id.0).ok()?)?.take()
    }

    /// A fault rule (e.g. to read how often it fired).
    pub fn fault(&self, id: RuleId) -> Option<&FaultRule> {
        self.rules.get(usize::try_from(id.0).ok()?)?.as_ref()
    }

    /// Statistics since creation or the last [`Bus::reset_stats`].
    pub fn stats(&self) -> &BusStats {
        &self.stats
    }

    /// Clears statistics; load is then measured from now.
    pub fn reset_stats(&mut self) {
        self.stats = BusStats::default();
        self.window.clear();
        self.stats_origin = self.now;
    }

    /// Bus load (0.0..=1.0) since the statistics origin: busy time over
    /// elapsed time. Always 0 without a bitrate.
    pub fn bus_load(&self) -> f64 {
        let elapsed = self.now.saturating_duration_since(self.stats_origin).as_nanos();
        if elapsed == 0 {
            return 0.0;
        }
        // Busy time may extend past `now` while a frame is on the wire.
        (self.stats.busy.as_nanos() as f64 / elapsed as f64).min(1.0)
    }

    /// Bus load over the last [`BusConfig::load_window`].
    pub fn bus_load_window(&mut self) -> f64 {
        self.window.load(self.now, self.stats_origin).min(1.0)
    }

    /// The frames delivered so far, in delivery order (if logging is on).
    pub fn log(&self) -> &[LogEntry] {
        &self.log
    }

    /// Takes the log, leaving it empty.
    pub fn take_log(&mut self) -> Vec<LogEntry> {
        core::mem::take(&mut self.log)
    }

    /// Writes the log as candump lines, one per `\n`.
    pub fn format_log(&self, out: &mut impl fmt::Write) -> fmt::Result {
        for e in &self.log {
            candump::write_line(out, self.cfg.log_epoch_us, &self.cfg.interface, e.time, &e.frame)?;
            out.write_char('\n')?;
        }
        Ok(())
    }

    /// The log as candump lines.
    pub fn log_lines(&self) -> Vec<String> {
        self.log
            .iter()
            .map(|e| {
                let mut s = String::new();
                // Writing into a String cannot fail.
                let _ =
                    candump::write_line(&mut s, self.cfg.log_epoch_us, &self.cfg.interface, e.time, &e.frame);
                s
            })
            .collect()
    }

    /// Calls `sink` with each candump line as frames are delivered
    /// (independent of [`BusConfig::log`]).
    pub fn set_log_sink(&mut self, sink: impl FnMut(&str) + 'static) {
        self.sink = Some(Box::new(sink));
    }

    /// Writes the log in candump format to `w`.
    #[cfg(feature = "std")]
    pub fn write_log(&self, w: &mut impl std::io::Write) -> std::io::Result<()> {
        let mut s = String::new();
        self.format_log(&mut s).map_err(|_| std::io::Error::other("format error"))?;
        w.write_all(s.as_bytes())
    }

    /// Writes the log in candump format to the file at `path`.
    #[cfg(feature = "std")]
    pub fn save_log(&self, path: impl AsRef<std::path::Path>) -> std::io::Result<()> {
        let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
        self.write_log(&mut f)?;
        std::io::Write::flush(&mut f)
    }
}
