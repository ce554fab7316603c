//! Heartbeat consumer (CiA 301 §7.2.8.3.2.2, object 1016h).

use crate::config::{CONSUMER_HEARTBEAT_TIME, MAX_CONSUMER_ENTRIES};
use crate::events::{EventQueue, NmtEvent};
use crate::state::RemoteState;
use alloc::vec::Vec;
use drivebus_can::{Duration, Instant};
use drivebus_od::{ObjectDictionary, SdoAbort, check_len, le_u64};

/// One decoded 1016h entry: bits 16..23 node-ID, bits 0..15 time in ms,
/// bits 24..31 reserved (0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConsumerEntry {
    /// The monitored node-ID.
    pub node: u8,
    /// The consumer heartbeat time in ms.
    pub time_ms: u16,
}

impl ConsumerEntry {
    /// Decode a 1016h sub-index value.
    #[inline]
    pub const fn from_raw(v: u32) -> ConsumerEntry {
        ConsumerEntry { node: (v >> 16) as u8, time_ms: v as u16 }
    }
    /// Encode as a 1016h sub-index value.
    #[inline]
    pub const fn raw(self) -> u32 {
        ((self.node as u32) << 16) | self.time_ms as u32
    }
    /// CiA 301: an entry with time 0, node-ID 0 or node-ID > 127 is not used.
    #[inline]
    pub const fn is_used(self) -> bool {
        self.time_ms != 0 && self.node != 0 && self.node <= 127
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Monitor {
    /// Not used, or the device is in Initialisation.
    Off,
    /// Configured; monitoring starts with the next heartbeat.
    Waiting,
    /// A heartbeat must arrive before `deadline`.
    Active { deadline: Instant },
    /// Timed out; waiting for the heartbeat that recovers it.
    TimedOut,
}

#[derive(Clone, Copy, Debug)]
struct Slot {
    entry: ConsumerEntry,
    monitor: Monitor,
    last: Option<RemoteState>,
    /// A timeout was reported and no heartbeat has recovered it yet (kept
    /// across a boot-up message, which only restarts monitoring).
    timed_out: bool,
}

impl Slot {
    const UNUSED: Slot = Slot {
        entry: ConsumerEntry { node: 0, time_ms: 0 },
        monitor: Monitor::Off,
        last: None,
        timed_out: false,
    };
}

/// The heartbeat consumer table.
#[derive(Clone, Debug, Default)]
pub(crate) struct Consumer {
    slots: Vec<Slot>,
    running: bool,
}

impl Consumer {
    /// Size the table from 1016h sub 0 and read every entry. Allocates only
    /// here (configuration time), never on the frame path.
    pub(crate) fn configure(&mut self, od: &ObjectDictionary) {
        let n = od.get_u64(CONSUMER_HEARTBEAT_TIME, 0).unwrap_or(0).min(MAX_CONSUMER_ENTRIES.into()) as usize;
        if self.slots.len() != n {
            self.slots.clear();
            self.slots.resize(n, Slot::UNUSED);
        }
        // Unchanged entries keep their running supervision.
        for i in 0..n {
            let raw = od.get_u32(CONSUMER_HEARTBEAT_TIME, i as u8 + 1).unwrap_or(0);
            self.set_entry(i as u8 + 1, raw);
        }
    }

    /// Take a new value for 1016h `sub`. A changed entry restarts its
    /// monitoring (waits for the next heartbeat); an unchanged one is kept.
    pub(crate) fn set_entry(&mut self, sub: u8, raw: u32) {
        let Some(slot) = (sub as usize).checked_sub(1).and_then(|i| self.slots.get_mut(i)) else {
            return;
        };
        let entry = ConsumerEntry::from_raw(raw);
        if slot.entry == entry && slot.monitor != Monitor::Off {
            return;
        }
        *slot = Slot { entry, ..Slot::UNUSED };
        if entry.is_used() && self.running {
            slot.monitor = Monitor::Waiting;
        }
    }

    /// Start monitoring (after boot-up): every used entry waits for its
    /// first heartbeat.
    pub(crate) fn start(&mut self) {
        self.running = true;
        for s in &mut self.slots {
            *s = Slot { entry: s.entry, ..Slot::UNUSED };
            if s.entry.is_used() {
                s.monitor = Monitor::Waiting;
            }
        }
    }

    /// Stop monitoring (entering Initialisation).
    pub(crate) fn stop(&mut self) {
        self.running = false;
        for s in &mut self.slots {
            *s = Slot { entry: s.entry, ..Slot::UNUSED };
        }
    }

    /// The configured entries (decoded), in sub-index order.
    pub(crate) fn entries(&self) -> impl Iterator<Item = ConsumerEntry> + '_ {
        self.slots.iter().map(|s| s.entry)
    }

    /// The last state heard from a monitored node.
    pub(crate) fn remote_state(&self, node: u8) -> Option<RemoteState> {
        self.slot(node).and_then(|i| self.slots[i].last)
    }

    /// Whether a monitored node is currently timed out.
    pub(crate) fn is_timed_out(&self, node: u8) -> bool {
        self.slot(node).is_some_and(|i| self.slots[i].timed_out)
    }

    fn slot(&self, node: u8) -> Option<usize> {
        // Duplicates are refused on write (0604 0043), so at most one used
        // entry per node. Linear scan over at most 127 entries, no allocation.
        self.slots.iter().position(|s| s.entry.node == node && s.entry.is_used())
    }

    /// A heartbeat (or boot-up) `byte` from `node` at `now`.
    pub(crate) fn on_heartbeat(&mut self, node: u8, byte: u8, now: Instant) -> Option<NmtEvent> {
        if !self.running {
            return None;
        }
        let i = self.slot(node)?;
        let s = &mut self.slots[i];
        let state = RemoteState::from_code(byte);
        let prev = s.last.replace(state);
        if state == RemoteState::BootUp {
            // The producer restarted and may come back with another 1017h:
            // monitor again from its first heartbeat.
            s.monitor = Monitor::Waiting;
            return Some(NmtEvent::RemoteBootup { node });
        }
        let first = s.monitor == Monitor::Waiting;
        s.monitor = Monitor::Active { deadline: now + Duration::from_millis(s.entry.time_ms.into()) };
        if s.timed_out {
            s.timed_out = false;
            return Some(NmtEvent::HeartbeatRecovered { node, state });
        }
        // The first heartbeat (also the first after a boot-up) always
        // reports the state: before it the producer's state is unknown.
        if first || prev != Some(state) {
            return Some(NmtEvent::RemoteStateChange { node, state });
        }
        None
    }

    /// Report due timeouts into `q`; returns the next deadline. When `q` is
    /// full the timeout stays pending and `now` is returned, so the next
    /// poll reports it.
    pub(crate) fn poll(&mut self, now: Instant, q: &mut EventQueue) -> Option<Instant> {
        let mut next: Option<Instant> = None;
        for s in &mut self.slots {
            let Monitor::Active { deadline } = s.monitor else { continue };
            if now >= deadline {
                if q.push(NmtEvent::HeartbeatTimeout { node: s.entry.node }) {
                    s.monitor = Monitor::TimedOut;
                    s.timed_out = true;
                    continue;
                }
                next = drivebus_can::earliest(next, Some(now));
            } else {
                next = drivebus_can::earliest(next, Some(deadline));
            }
        }
        next
    }
}

/// The 1016h write check: length, reserved bits, and CiA 301 §7.5.2.26:
/// two used entries for the same node-ID → `0604 0043`.
pub(crate) fn check_write(od: &ObjectDictionary, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
    if sub == 0 {
        return Ok(());
    }
    check_len(drivebus_od::DataType::Unsigned32, data.len())?;
    let raw = le_u64(data) as u32;
    if raw >> 24 != 0 {
        // Bits 24..31 are reserved (0).
        return Err(SdoAbort::INVALID_VALUE);
    }
    let new = ConsumerEntry::from_raw(raw);
    if !new.is_used() {
        return Ok(());
    }
    let n = od.get_u64(CONSUMER_HEARTBEAT_TIME, 0).unwrap_or(0).min(MAX_CONSUMER_ENTRIES.into()) as u8;
    for other in (1..=n).filter(|&s| s != sub) {
        let e = ConsumerEntry::from_raw(od.get_u32(CONSUMER_HEARTBEAT_TIME, other).unwrap_or(0));
        if e.is_used() && e.node == new.node {
            return Err(SdoAbort::PARAM_INCOMPATIBLE);
        }
    }
    Ok(())
}
