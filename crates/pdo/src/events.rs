//! Events the node turns into EMCY frames or application notifications.

use drivebus_od::SdoAbort;

/// Something the node must act on (services never call each other).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PdoEvent {
    /// RPDO `rpdo` (0-based) arrived with fewer bytes than mapped: not
    /// processed (CiA 301 7.2.2.4). The node sends EMCY 8210h.
    RpdoLengthError {
        /// RPDO number, 0-based.
        rpdo: u16,
        /// DLC received.
        len: u8,
    },
    /// RPDO arrived with more bytes than mapped: processed, surplus ignored.
    /// The node may send EMCY 8220h.
    RpdoLengthExceeded {
        /// RPDO number, 0-based.
        rpdo: u16,
        /// DLC received.
        len: u8,
    },
    /// No RPDO within its event time (deadline monitoring, 1400h+n sub 5).
    /// Raised once until the next reception. The node sends EMCY 8250h.
    RpdoTimeout {
        /// RPDO number, 0-based.
        rpdo: u16,
    },
    /// First RPDO received after an [`PdoEvent::RpdoTimeout`]: the node may
    /// reset the 8250h error.
    RpdoResumed {
        /// RPDO number, 0-based.
        rpdo: u16,
    },
    /// Writing a mapped object from an RPDO was refused (limits, hook).
    RpdoWriteFailed {
        /// RPDO number, 0-based.
        rpdo: u16,
        /// Mapped object index.
        index: u16,
        /// Mapped object sub-index.
        sub: u8,
        /// Why.
        abort: SdoAbort,
    },
    /// A read hook refused sampling a mapped object for a TPDO; the stored
    /// value was sent.
    TpdoReadFailed {
        /// TPDO number, 0-based.
        tpdo: u16,
        /// Mapped object index.
        index: u16,
        /// Mapped object sub-index.
        sub: u8,
        /// Why.
        abort: SdoAbort,
    },
}

impl PdoEvent {
    /// The CiA 301 EMCY error code the node should send for this event
    /// (Table 26), or `None` when none is defined.
    pub const fn emcy_code(&self) -> Option<u16> {
        match self {
            PdoEvent::RpdoLengthError { .. } => Some(0x8210),
            PdoEvent::RpdoLengthExceeded { .. } => Some(0x8220),
            PdoEvent::RpdoTimeout { .. } => Some(0x8250),
            _ => None,
        }
    }
}

/// What [`crate::Pdo::handle_frame`] made of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PdoRx {
    /// Not on the COB-ID of an active RPDO or (for remote frames) TPDO.
    NotPdo,
    /// Consumed, nothing to report.
    Handled,
    /// Consumed with an event (further events of the same frame, if any,
    /// wait in [`crate::Pdo::pop_event`]).
    Event(PdoEvent),
}

/// Capacity of the event queue; more events between drains are counted as lost.
pub const EVENT_QUEUE_LEN: usize = 32;

/// A fixed ring so queueing never allocates.
#[derive(Clone, Debug)]
pub(crate) struct EventQueue {
    buf: [Option<PdoEvent>; EVENT_QUEUE_LEN],
    head: usize,
    len: usize,
    pub(crate) lost: u32,
}

impl EventQueue {
    pub(crate) const fn new() -> Self {
        EventQueue { buf: [None; EVENT_QUEUE_LEN], head: 0, len: 0, lost: 0 }
    }
    pub(crate) fn push(&mut self, e: PdoEvent) {
        if self.len == EVENT_QUEUE_LEN {
            self.lost = self.lost.saturating_add(1);
            return;
        }
        self.buf[(self.head + self.len) % EVENT_QUEUE_LEN] = Some(e);
        self.len += 1;
    }
    #[inline]
    pub(crate) fn is_empty(&self) -> bool {
        self.len == 0
    }
    pub(crate) fn pop(&mut self) -> Option<PdoEvent> {
        if self.len == 0 {
            return None;
        }
        let e = self.buf[self.head].take();
        self.head = (self.head + 1) % EVENT_QUEUE_LEN;
        self.len -= 1;
        e
    }
    pub(crate) fn clear(&mut self) {
        *self = EventQueue { lost: self.lost, ..EventQueue::new() };
    }
}
