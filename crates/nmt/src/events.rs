//! Events the NMT service hands to the node, and the fixed queue for the ones
//! found by `poll`.

use crate::state::{NmtState, RemoteState};

/// Something the node must act on. NMT never calls another service: the
/// node wires these (PDOs on state change, EMCY 8130h on a timeout, the 1029h
/// reaction through [`crate::Nmt::on_error`], ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NmtEvent {
    /// The local NMT state changed (NMT command, boot, 1029h, local request).
    StateChanged {
        /// The state before.
        from: NmtState,
        /// The state now.
        to: NmtState,
    },
    /// Reset node (81h) or a local reset: restore 2000h–9FFFh and the
    /// communication parameters 1000h–1FFFh to their power-on values, then
    /// call [`crate::Nmt::boot`].
    ResetApplication,
    /// Reset communication (82h) or a local reset: restore 1000h–1FFFh to
    /// their power-on values, then call [`crate::Nmt::boot`].
    ResetCommunication,
    /// A monitored heartbeat (1016h entry) did not arrive in time.
    HeartbeatTimeout {
        /// The producer's node-ID.
        node: u8,
    },
    /// The first heartbeat of a node after a [`NmtEvent::HeartbeatTimeout`].
    HeartbeatRecovered {
        /// The producer's node-ID.
        node: u8,
        /// The state it reports.
        state: RemoteState,
    },
    /// A monitored node sent its boot-up message (state 00h). Its
    /// monitoring restarts with its next heartbeat (CiA 301 §7.2.8.3.2.2:
    /// monitoring starts with the first heartbeat).
    RemoteBootup {
        /// The node-ID.
        node: u8,
    },
    /// A monitored node reports a state other than the last one seen
    /// (including its first heartbeat).
    RemoteStateChange {
        /// The node-ID.
        node: u8,
        /// The state it reports now.
        state: RemoteState,
    },
    /// Life guarding: no node-guarding request within guard time × life time
    /// factor (CiA 301 §7.2.8.3.2.1, "life guarding event, occurred").
    LifeGuardingLost,
    /// Life guarding: a request arrived after [`NmtEvent::LifeGuardingLost`]
    /// ("life guarding event, resolved").
    LifeGuardingResolved,
}

/// Capacity of the queue of events found by `poll`.
pub const EVENT_QUEUE_LEN: usize = 16;

/// A fixed-capacity FIFO of events (no allocation). Producers check
/// [`EventQueue::is_full`] first and keep their condition pending when it is
/// full, so nothing is lost: the next `poll` reports it.
#[derive(Clone, Debug)]
pub(crate) struct EventQueue {
    buf: [Option<NmtEvent>; EVENT_QUEUE_LEN],
    head: usize,
    len: usize,
}

impl EventQueue {
    pub(crate) const fn new() -> Self {
        EventQueue { buf: [None; EVENT_QUEUE_LEN], head: 0, len: 0 }
    }
    pub(crate) fn is_full(&self) -> bool {
        self.len == EVENT_QUEUE_LEN
    }
    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.len == 0
    }
    /// Returns false (and drops nothing already queued) when full.
    pub(crate) fn push(&mut self, ev: NmtEvent) -> bool {
        if self.is_full() {
            return false;
        }
        let i = (self.head + self.len) % EVENT_QUEUE_LEN;
        self.buf[i] = Some(ev);
        self.len += 1;
        true
    }
    pub(crate) fn pop(&mut self) -> Option<NmtEvent> {
        if self.len == 0 {
            return None;
        }
        let ev = self.buf[self.head].take();
        self.head = (self.head + 1) % EVENT_QUEUE_LEN;
        self.len -= 1;
        ev
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifo_with_capacity() {
        let mut q = EventQueue::new();
        assert!(q.is_empty());
        for n in 0..EVENT_QUEUE_LEN as u8 {
            assert!(q.push(NmtEvent::HeartbeatTimeout { node: n }));
        }
        assert!(q.is_full());
        assert!(!q.push(NmtEvent::LifeGuardingLost));
        assert_eq!(q.pop(), Some(NmtEvent::HeartbeatTimeout { node: 0 }));
        assert!(q.push(NmtEvent::LifeGuardingLost));
        for n in 1..EVENT_QUEUE_LEN as u8 {
            assert_eq!(q.pop(), Some(NmtEvent::HeartbeatTimeout { node: n }));
        }
        assert_eq!(q.pop(), Some(NmtEvent::LifeGuardingLost));
        assert_eq!(q.pop(), None);
    }
}
