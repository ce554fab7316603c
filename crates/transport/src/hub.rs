//! The in-process bus hub: one ordering point that every participant
//! (TCP clients of the socketcand server, the slcan pty, in-process virtual
//! drives) sends into and receives from.
//!
//! Built on [`tokio::sync::broadcast`]: publishing never waits for a
//! receiver, so one slow participant cannot stall the bus. A receiver that
//! falls more than [`HubConfig::capacity`] frames behind loses the oldest
//! ones (in-process handles count an overrun; the socketcand server
//! disconnects such a TCP client).

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, Weak};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use drivebus_can::Frame;
use drivebus_can::fault::{FaultAction, FaultRule, XorShift64, corrupt_data};
use tokio::sync::broadcast;

use crate::handle::{CanBus, hub_handle};

/// Identifies a participant of a [`Hub`]; frames are never delivered back
/// to the participant that sent them.
pub type ParticipantId = u64;

/// A frame as it crossed the hub.
#[derive(Clone, Copy, Debug)]
pub struct HubFrame {
    /// Who sent it.
    pub from: ParticipantId,
    /// The frame.
    pub frame: Frame,
    /// Wall-clock time it was relayed, microseconds since the Unix epoch
    /// (socketcand puts this in `< frame ID SECS.USECS … >`).
    pub timestamp_us: u64,
}

/// What a fault rule does to a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaultVerdict {
    /// Relay it unchanged.
    Pass,
    /// Nobody receives it (it still occupies a paced bus).
    Drop,
    /// Receivers get this frame instead.
    Replace(Frame),
}

/// A rule the hub cannot apply: it relays frames in one synchronous step
/// and has no error frames, so [`FaultAction::Corrupt`] (an error frame and
/// the automatic retransmission) and [`FaultAction::Delay`] exist only on
/// the simulated bus (`drivebus-bus`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnsupportedFault(pub FaultAction);

impl std::fmt::Display for UnsupportedFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the real-time hub cannot apply {:?}: only drop, silent corruption, duplicate and bus-off rules",
            self.0
        )
    }
}

impl std::error::Error for UnsupportedFault {}

/// The hub's rules and the PRNG their probabilities draw from.
struct Rules {
    list: Vec<FaultRule>,
    rng: XorShift64,
}

impl Rules {
    /// What the first rule that fires does to `frame` from `from`.
    fn verdict(&mut self, frame: &Frame, from: ParticipantId) -> (FaultVerdict, bool) {
        let node = u32::try_from(from).unwrap_or(u32::MAX);
        let Rules { list, rng } = self;
        let Some(action) = list.iter_mut().find_map(|r| r.try_fire(frame, node, rng).then(|| r.action()))
        else {
            return (FaultVerdict::Pass, false);
        };
        match action {
            FaultAction::Drop | FaultAction::BusOff => (FaultVerdict::Drop, false),
            FaultAction::CorruptSilently { xor } => {
                (FaultVerdict::Replace(corrupt_data(frame, xor, rng)), false)
            }
            FaultAction::Duplicate => (FaultVerdict::Pass, true),
            // Refused by `add_fault`.
            FaultAction::Corrupt | FaultAction::Delay(_) => (FaultVerdict::Pass, false),
        }
    }
}

/// A custom fault hook: called for every frame before it is relayed.
pub type FaultHook = Arc<dyn Fn(&Frame) -> FaultVerdict + Send + Sync>;

/// Hub settings.
#[derive(Clone)]
pub struct HubConfig {
    /// Pace relaying at this CAN bit rate (bit/s): each frame occupies the
    /// hub for its exact stuffed length plus intermission
    /// ([`drivebus_can::timing::frame_bits`]). Senders wait for their slot.
    /// Timers have about 1 ms resolution, so the rate is exact on average
    /// and frames go out in bursts of up to 1 ms. `None`: as fast as possible.
    pub bitrate: Option<u32>,
    /// Frames a receiver may fall behind before it loses frames.
    pub capacity: usize,
    /// Called for every frame after the rules, if set.
    pub fault_hook: Option<FaultHook>,
}

impl Default for HubConfig {
    fn default() -> Self {
        HubConfig { bitrate: None, capacity: 8192, fault_hook: None }
    }
}

impl std::fmt::Debug for HubConfig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HubConfig")
            .field("bitrate", &self.bitrate)
            .field("capacity", &self.capacity)
            .field("fault_hook", &self.fault_hook.is_some())
            .finish()
    }
}

struct HubInner {
    tx: broadcast::Sender<HubFrame>,
    next_id: AtomicU64,
    bitrate: Option<u32>,
    hook: Option<FaultHook>,
    rules: Mutex<Rules>,
    /// When the paced bus is free again.
    busy_until: Mutex<std::time::Instant>,
    relayed: AtomicU64,
    dropped: AtomicU64,
}

/// An in-process CAN bus hub; clones share the same bus.
#[derive(Clone)]
pub struct Hub {
    inner: Arc<HubInner>,
}

impl Default for Hub {
    fn default() -> Self {
        Hub::new(HubConfig::default())
    }
}

impl std::fmt::Debug for Hub {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Hub").field("relayed", &self.relayed()).finish_non_exhaustive()
    }
}

impl Hub {
    /// A new, empty bus.
    pub fn new(cfg: HubConfig) -> Hub {
        let (tx, _) = broadcast::channel(cfg.capacity.max(16));
        Hub {
            inner: Arc::new(HubInner {
                tx,
                next_id: AtomicU64::new(1),
                bitrate: cfg.bitrate.filter(|&b| b > 0),
                hook: cfg.fault_hook,
                rules: Mutex::new(Rules { list: Vec::new(), rng: XorShift64::new(1) }),
                busy_until: Mutex::new(std::time::Instant::now()),
                relayed: AtomicU64::new(0),
                dropped: AtomicU64::new(0),
            }),
        }
    }

    /// A new participant: a handle that receives every frame the others
    /// send from now on, and whose frames reach everybody else. This is how
    /// virtual drives hosted in the process join the bus.
    pub fn attach(&self) -> CanBus {
        let (id, rx) = self.join();
        hub_handle(self.clone(), id, rx)
    }

    /// A fresh participant id and a subscription (lower-level than
    /// [`attach`](Hub::attach); the subscriber must skip its own frames).
    pub fn join(&self) -> (ParticipantId, broadcast::Receiver<HubFrame>) {
        (self.inner.next_id.fetch_add(1, Ordering::Relaxed), self.inner.tx.subscribe())
    }

    /// A subscription to every frame relayed from now on.
    pub fn subscribe(&self) -> broadcast::Receiver<HubFrame> {
        self.inner.tx.subscribe()
    }

    /// A fresh participant id.
    pub fn new_participant(&self) -> ParticipantId {
        self.inner.next_id.fetch_add(1, Ordering::Relaxed)
    }

    /// Adds a fault rule; rules are tried in order, the first that fires
    /// applies (a rule's `from` is the sending participant's id). Drop and
    /// bus-off rules drop the frame, silent corruption relays the altered
    /// frame, duplicate relays it twice.
    pub fn add_fault(&self, rule: FaultRule) -> Result<(), UnsupportedFault> {
        if matches!(rule.action(), FaultAction::Corrupt | FaultAction::Delay(_)) {
            return Err(UnsupportedFault(rule.action()));
        }
        if let Ok(mut r) = self.inner.rules.lock() {
            r.list.push(rule);
        }
        Ok(())
    }

    /// Removes every fault rule.
    pub fn clear_faults(&self) {
        if let Ok(mut r) = self.inner.rules.lock() {
            r.list.clear();
        }
    }

    /// Removes the rules that will never fire again; returns how many are
    /// left.
    pub fn prune_faults(&self) -> usize {
        self.inner.rules.lock().map_or(0, |mut r| {
            r.list.retain(|x| !x.is_spent());
            r.list.len()
        })
    }

    /// Frames relayed so far.
    pub fn relayed(&self) -> u64 {
        self.inner.relayed.load(Ordering::Relaxed)
    }

    /// Frames dropped by fault injection so far.
    pub fn dropped(&self) -> u64 {
        self.inner.dropped.load(Ordering::Relaxed)
    }

    /// The bitrate frames are paced to, `None` when unpaced.
    pub fn bitrate(&self) -> Option<u32> {
        self.inner.bitrate
    }

    /// True when frames are paced to a bitrate ([`publish`](Self::publish)
    /// may wait).
    pub fn is_paced(&self) -> bool {
        self.inner.bitrate.is_some()
    }

    /// Relays `frame` from participant `from` to everybody else; on a paced
    /// hub, first waits for the frame's slot on the bus.
    pub async fn publish(&self, from: ParticipantId, frame: Frame) {
        if let Some(bitrate) = self.inner.bitrate {
            let bits = drivebus_can::timing::frame_bits(&frame).total();
            let dur = drivebus_can::timing::bits_duration(bits, bitrate);
            let now = std::time::Instant::now();
            let end = match self.inner.busy_until.lock() {
                Ok(mut busy) => {
                    let end = (*busy).max(now) + dur;
                    *busy = end;
                    end
                }
                Err(_) => now,
            };
            // Sleep only when ahead by more than the timer resolution.
            if end.saturating_duration_since(now) > Duration::from_millis(1) {
                tokio::time::sleep_until(end.into()).await;
            }
        }
        self.publish_now(from, frame);
    }

    /// Relays without pacing (fault rules still apply).
    pub fn publish_now(&self, from: ParticipantId, frame: Frame) {
        let (mut verdict, twice) = match self.inner.rules.lock() {
            Ok(mut rules) => rules.verdict(&frame, from),
            Err(_) => (FaultVerdict::Pass, false),
        };
        if verdict == FaultVerdict::Pass
            && let Some(h) = &self.inner.hook
        {
            verdict = h(&frame);
        }
        let frame = match verdict {
            FaultVerdict::Pass => frame,
            FaultVerdict::Replace(f) => f,
            FaultVerdict::Drop => {
                self.inner.dropped.fetch_add(1, Ordering::Relaxed);
                return;
            }
        };
        self.inner.relayed.fetch_add(1, Ordering::Relaxed);
        let timestamp_us = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_micros() as u64);
        // Err only when nobody listens, which is fine on a bus.
        let _ = self.inner.tx.send(HubFrame { from, frame, timestamp_us });
        if twice {
            self.inner.relayed.fetch_add(1, Ordering::Relaxed);
            let _ = self.inner.tx.send(HubFrame { from, frame, timestamp_us });
        }
    }
}

/// Named in-process buses for `virtual://NAME`. Weak so a bus disappears
/// with its last handle (tests on separate runtimes do not share state).
static VIRTUAL: LazyLock<Mutex<HashMap<String, Weak<HubInner>>>> = LazyLock::new(Default::default);

/// The in-process bus called `name`, created on first use.
pub fn virtual_hub(name: &str) -> Hub {
    let Ok(mut map) = VIRTUAL.lock() else { return Hub::default() };
    map.retain(|_, w| w.strong_count() > 0);
    if let Some(inner) = map.get(name).and_then(Weak::upgrade) {
        return Hub { inner };
    }
    let hub = Hub::default();
    map.insert(name.to_owned(), Arc::downgrade(&hub.inner));
    hub
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_drop_corrupt_and_duplicate_on_the_hub() {
        let hub = Hub::default();
        let mut rx = hub.subscribe();
        hub.add_fault(FaultRule::drop_frames().ids(0x100..=0x1FF).skip(1).every(2).times(2)).unwrap();
        hub.add_fault(FaultRule::corrupt_with([0xFF; 8]).id(0x201)).unwrap();
        hub.add_fault(FaultRule::duplicate().id(0x301)).unwrap();
        assert!(hub.add_fault(FaultRule::corrupt()).is_err());
        for _ in 0..4 {
            hub.publish_now(1, Frame::new(0x180, &[1]));
        }
        hub.publish_now(1, Frame::new(0x201, &[0x0F]));
        hub.publish_now(1, Frame::new(0x301, &[]));
        let mut got = Vec::new();
        while let Ok(f) = rx.try_recv() {
            got.push(f.frame);
        }
        let f180 = Frame::new(0x180, &[1]);
        let dup = Frame::new(0x301, &[]);
        assert_eq!(got, [f180, f180, Frame::new(0x201, &[0xF0]), dup, dup]);
        assert_eq!(hub.dropped(), 2);
        assert_eq!(hub.prune_faults(), 2);
    }
}
