//! The sans-IO master core: frames and the caller's `now` in, frames and
//! the next deadline out, exactly like the device-side protocol machines.
//!
//! [`Core`] keeps the node table (NMT state from boot-up, heartbeat and
//! guarding answers), the heartbeat/guarding monitor, the EMCY consumer,
//! the SYNC producer and guarding requests, the running SDO transfers
//! ([`sdo`]), LSS and other frame-driven operations ([`ops`]) and timers.
//! It never reads a clock, sleeps, or touches a socket: a *driver* feeds
//! it (`handle_frame`, `poll`), sends what it queued (`take_tx`) and wakes
//! it at `next_deadline`. Two drivers exist: the tokio one for real buses
//! (`driver::tokio`) and the simulated-time one on the virtual bus
//! (`driver::sim`). Completion is signalled through `tokio::sync`
//! channels, which need no runtime, so the same procedures (SDO, scan,
//! LSS, PDO configuration, CiA 402 sequences) run on both.

pub(crate) mod ops;
pub(crate) mod sdo;

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Duration;

use drivebus_can::{Frame, Instant};
use drivebus_nmt::RemoteState;
use drivebus_od::ObjectDictionary;
use tokio::sync::{broadcast, oneshot};

use crate::master::{MasterEvent, NodeStatus, SyncTick};

/// A synchronous PDO consumer, called in frame order with the frame's time.
pub(crate) type PdoSink = Arc<dyn Fn(&Frame, Instant) + Send + Sync>;

/// The SYNC producer (CiA 301 1005h/1006h/1019h on the master side).
struct SyncProducer {
    period: Duration,
    overflow: u8,
    counter: u8,
    seq: u64,
    next: Instant,
}

/// Node guarding requests to one node (CiA 301 §7.2.8.3.2.1).
struct Guard {
    period: Duration,
    next: Instant,
}

/// Counters for reports (the demo's summary, benchmarks).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Frames handed to the driver for sending.
    pub frames_out: u64,
    /// Frames received.
    pub frames_in: u64,
    /// SDO transfers started.
    pub sdo_transfers: u64,
}

/// The master's protocol state; see the module documentation.
pub(crate) struct Core {
    now: Instant,
    tx: Vec<Frame>,
    /// Frames ever queued (for `flush`: the driver reports how many it sent).
    queued: u64,
    /// The deadline the driver currently sleeps towards; a new earlier one
    /// must wake it.
    pub(crate) armed: Option<Instant>,
    timers: BTreeMap<(Instant, u64), oneshot::Sender<()>>,
    next_id: u64,
    pub(crate) sdo: sdo::SdoPool,
    ops: Vec<(u64, Box<dyn ops::Op>)>,
    pub(crate) nodes: BTreeMap<u8, NodeStatus>,
    pub(crate) events: broadcast::Sender<MasterEvent>,
    pub(crate) frames: broadcast::Sender<Frame>,
    pub(crate) sync_ticks: broadcast::Sender<SyncTick>,
    pdo: HashMap<u16, broadcast::Sender<Frame>>,
    pdo_sinks: HashMap<u16, Vec<(u64, PdoSink)>>,
    sync: Option<SyncProducer>,
    guards: BTreeMap<u8, Guard>,
    pub(crate) eds: HashMap<u8, Arc<ObjectDictionary>>,
    pub(crate) emcy_tables: HashMap<u8, Arc<HashMap<u16, String>>>,
    pub(crate) stats: Stats,
    /// Why the bus failed, once it has.
    pub(crate) closed: Option<String>,
    channel_capacity: usize,
}

impl Core {
    pub(crate) fn new(now: Instant, channel_capacity: usize) -> Core {
        let cap = channel_capacity.max(16);
        Core {
            now,
            tx: Vec::new(),
            queued: 0,
            armed: None,
            timers: BTreeMap::new(),
            next_id: 0,
            sdo: sdo::SdoPool::default(),
            ops: Vec::new(),
            nodes: BTreeMap::new(),
            events: broadcast::channel(cap).0,
            frames: broadcast::channel(cap.max(4096)).0,
            sync_ticks: broadcast::channel(64).0,
            pdo: HashMap::new(),
            pdo_sinks: HashMap::new(),
            sync: None,
            guards: BTreeMap::new(),
            eds: HashMap::new(),
            emcy_tables: HashMap::new(),
            stats: Stats::default(),
            closed: None,
            channel_capacity: cap,
        }
    }

    /// The time of the last `handle_frame`/`poll`/`advance`.
    pub(crate) fn now(&self) -> Instant {
        self.now
    }

    /// Moves the core's notion of now forward (never back).
    pub(crate) fn advance(&mut self, now: Instant) {
        if now > self.now {
            self.now = now;
        }
    }

    pub(crate) fn id(&mut self) -> u64 {
        self.next_id += 1;
        self.next_id
    }

    /// Queues a frame for the driver.
    pub(crate) fn send(&mut self, f: Frame) {
        self.tx.push(f);
        self.queued += 1;
        self.stats.frames_out += 1;
    }

    /// Frames queued since the last call, in bus order.
    pub(crate) fn take_tx(&mut self, into: &mut Vec<Frame>) {
        into.append(&mut self.tx);
    }

    /// Puts frames taken by [`take_tx`](Self::take_tx) but not sent back
    /// in front of the queue (still counted as queued).
    pub(crate) fn requeue_front(&mut self, frames: impl IntoIterator<Item = Frame>) {
        let rest = std::mem::take(&mut self.tx);
        self.tx.extend(frames);
        self.tx.extend(rest);
    }

    /// True when frames wait to be sent.
    pub(crate) fn has_tx(&self) -> bool {
        !self.tx.is_empty()
    }

    /// Frames ever queued.
    pub(crate) fn queued(&self) -> u64 {
        self.queued
    }

    /// True if a new deadline `t` is earlier than what the driver sleeps towards.
    pub(crate) fn wakes_driver(&self, t: Instant) -> bool {
        self.armed.is_none_or(|a| t < a)
    }

    /// A timer firing at `at`.
    pub(crate) fn timer(&mut self, at: Instant) -> oneshot::Receiver<()> {
        let (tx, rx) = oneshot::channel();
        let id = self.id();
        // A lost bus has no driver left to fire timers: waits end at once.
        if at <= self.now || self.closed.is_some() {
            let _ = tx.send(());
        } else {
            self.timers.insert((at, id), tx);
        }
        rx
    }

    /// Starts a frame-driven operation (LSS, fastscan) now.
    pub(crate) fn start_op(&mut self, mut op: Box<dyn ops::Op>) -> u64 {
        let id = self.id();
        // No driver runs a lost bus: dropping the op ends its future now.
        if self.closed.is_some() {
            return id;
        }
        let now = self.now;
        let mut out = Vec::new();
        op.start(now, &mut out);
        for f in out {
            self.send(f);
        }
        if !op.done() {
            self.ops.push((id, op));
        }
        id
    }

    /// Drops an operation whose future went away.
    pub(crate) fn cancel_op(&mut self, id: u64) {
        self.ops.retain(|(i, _)| *i != id);
    }

    /// A frame was received at `now`.
    pub(crate) fn handle_frame(&mut self, f: &Frame, now: Instant) {
        self.advance(now);
        let now = self.now;
        self.stats.frames_in += 1;
        if self.frames.receiver_count() > 0 {
            let _ = self.frames.send(*f);
        }
        let mut out = std::mem::take(&mut self.tx);
        let before = out.len();
        self.sdo.handle_frame(f, now, &mut out);
        for (_, op) in &mut self.ops {
            op.handle_frame(f, now, &mut out);
        }
        self.ops.retain(|(_, op)| !op.done());
        let added = (out.len() - before) as u64;
        self.queued += added;
        self.stats.frames_out += added;
        self.tx = out;
        let Some(id) = f.std_id() else { return };
        if let Some(p) = self.pdo.get(&id)
            && p.send(*f).is_err()
        {
            self.pdo.remove(&id);
        }
        if let Some(sinks) = self.pdo_sinks.get(&id) {
            for (_, sink) in sinks {
                sink(f, now);
            }
        }
        let node = (id & 0x7F) as u8;
        if node == 0 || f.is_rtr() {
            return;
        }
        match id & 0x780 {
            0x080 => {
                if let Some(m) = drivebus_emcy::decode(f) {
                    self.nodes.entry(node).or_default().frames += 1;
                    let text = self.emcy_text(node, m.code);
                    let _ = self.events.send(MasterEvent::Emcy {
                        node,
                        code: m.code,
                        register: m.register,
                        data: m.data,
                        text,
                    });
                }
            }
            0x580 => self.nodes.entry(node).or_default().frames += 1,
            0x700 if !f.is_empty() => {
                let state = RemoteState::from_code(f.data()[0]);
                let s = self.nodes.entry(node).or_default();
                let was_lost = std::mem::take(&mut s.lost);
                s.frames += 1;
                s.state = Some(state);
                s.last_heartbeat = Some(now);
                if state == RemoteState::BootUp {
                    s.bootups += 1;
                    let _ = self.events.send(MasterEvent::Bootup { node });
                } else {
                    let _ = self.events.send(MasterEvent::Heartbeat { node, state });
                }
                if was_lost {
                    let _ = self.events.send(MasterEvent::HeartbeatRecovered { node });
                }
            }
            _ => {}
        }
    }

    /// Does the work due at `now`; returns the next deadline.
    pub(crate) fn poll(&mut self, now: Instant) -> Option<Instant> {
        self.advance(now);
        let now = self.now;
        // Timers.
        while let Some(entry) = self.timers.first_entry() {
            if entry.key().0 > now {
                break;
            }
            let _ = entry.remove().send(());
        }
        let mut out = std::mem::take(&mut self.tx);
        let before = out.len();
        let mut next = self.sdo.poll(now, &mut out);
        for (_, op) in &mut self.ops {
            next = drivebus_can::earliest(next, op.poll(now, &mut out));
        }
        self.ops.retain(|(_, op)| !op.done());
        // SYNC producer: late ticks are skipped, not bunched (a burst of
        // SYNCs would make synchronous drives jump).
        if let Some(s) = &mut self.sync {
            if s.next <= now {
                s.counter = if (2..=240).contains(&s.overflow) {
                    if s.counter >= s.overflow { 1 } else { s.counter + 1 }
                } else {
                    0
                };
                let counter = (s.counter != 0).then_some(s.counter);
                out.push(match counter {
                    Some(c) => Frame::new(0x080, &[c]),
                    None => Frame::new(0x080, &[]),
                });
                s.seq += 1;
                let _ = self.sync_ticks.send(SyncTick { seq: s.seq, counter });
                s.next += s.period;
                if s.next <= now {
                    s.next = now + s.period;
                }
            }
            next = drivebus_can::earliest(next, Some(s.next));
        }
        for (node, g) in &mut self.guards {
            if g.next <= now {
                out.push(Frame::remote(0x700 + u16::from(*node & 0x7F), 1));
                g.next += g.period;
                if g.next <= now {
                    g.next = now + g.period;
                }
            }
            next = drivebus_can::earliest(next, Some(g.next));
        }
        let added = (out.len() - before) as u64;
        self.queued += added;
        self.stats.frames_out += added;
        self.tx = out;
        // Heartbeat / guarding monitor.
        for (node, s) in self.nodes.iter_mut() {
            let (Some(t), Some(last), false) = (s.monitor, s.last_heartbeat, s.lost) else { continue };
            let deadline = last + t;
            if deadline <= now {
                s.lost = true;
                let _ = self.events.send(MasterEvent::HeartbeatLost { node: *node });
            } else {
                next = drivebus_can::earliest(next, Some(deadline));
            }
        }
        if let Some(((t, _), _)) = self.timers.first_key_value() {
            next = drivebus_can::earliest(next, Some(*t));
        }
        next
    }

    /// The earliest deadline without doing any work (for drivers that step).
    pub(crate) fn next_deadline(&self) -> Option<Instant> {
        let mut next = self.sdo.deadline();
        for (_, op) in &self.ops {
            next = drivebus_can::earliest(next, op.deadline());
        }
        if let Some(s) = &self.sync {
            next = drivebus_can::earliest(next, Some(s.next));
        }
        for g in self.guards.values() {
            next = drivebus_can::earliest(next, Some(g.next));
        }
        for s in self.nodes.values() {
            if let (Some(t), Some(last), false) = (s.monitor, s.last_heartbeat, s.lost) {
                next = drivebus_can::earliest(next, Some(last + t));
            }
        }
        if let Some(((t, _), _)) = self.timers.first_key_value() {
            next = drivebus_can::earliest(next, Some(*t));
        }
        next
    }

    /// The bus failed: tell every listener.
    /// The bus failed: tell every listener, end every transfer, wake every
    /// timer and close every channel, so nothing waits on a driver that
    /// has stopped.
    pub(crate) fn bus_error(&mut self, reason: String) {
        if self.closed.is_some() {
            return;
        }
        let _ = self.events.send(MasterEvent::BusError { reason: reason.clone() });
        self.sdo.fail_all();
        self.ops.clear();
        self.closed = Some(reason);
        for (_, t) in std::mem::take(&mut self.timers) {
            let _ = t.send(());
        }
        // Replacing the senders closes the receivers (after what was sent).
        self.events = broadcast::channel(1).0;
        self.frames = broadcast::channel(1).0;
        self.sync_ticks = broadcast::channel(1).0;
        self.pdo.clear();
        self.sync = None;
        self.guards.clear();
    }

    pub(crate) fn emcy_text(&self, node: u8, code: u16) -> Option<String> {
        self.emcy_tables
            .get(&node)
            .and_then(|t| t.get(&code).cloned())
            .or_else(|| drivebus_emcy::describe(code).map(str::to_owned))
    }

    pub(crate) fn monitor(&mut self, node: u8, timeout: Option<Duration>) {
        let s = self.nodes.entry(node).or_default();
        s.monitor = timeout;
        s.lost = false;
    }

    pub(crate) fn start_sync(&mut self, period: Duration, overflow: u8) {
        let period = period.max(Duration::from_micros(100));
        // The first SYNC goes out at once, as a started producer does.
        self.sync = Some(SyncProducer { period, overflow, counter: 0, seq: 0, next: self.now });
    }

    pub(crate) fn stop_sync(&mut self) {
        self.sync = None;
    }

    pub(crate) fn sync_running(&self) -> bool {
        self.sync.is_some()
    }

    pub(crate) fn start_guarding(&mut self, node: u8, period: Duration) {
        let period = period.max(Duration::from_millis(1));
        self.guards.insert(node, Guard { period, next: self.now + period });
    }

    pub(crate) fn stop_guarding(&mut self, node: u8) {
        self.guards.remove(&node);
    }

    pub(crate) fn subscribe_pdo(&mut self, cob_id: u16) -> broadcast::Receiver<Frame> {
        let cap = self.channel_capacity;
        self.pdo.entry(cob_id).or_insert_with(|| broadcast::channel(cap).0).subscribe()
    }

    pub(crate) fn add_pdo_sink(&mut self, cob_id: u16, f: PdoSink) -> u64 {
        let id = self.id();
        self.pdo_sinks.entry(cob_id).or_default().push((id, f));
        id
    }

    pub(crate) fn remove_pdo_sink(&mut self, id: u64) {
        for v in self.pdo_sinks.values_mut() {
            v.retain(|(i, _)| *i != id);
        }
        self.pdo_sinks.retain(|_, v| !v.is_empty());
    }
}
