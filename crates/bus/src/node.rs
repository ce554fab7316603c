//! What can be attached to the bus.

use alloc::collections::VecDeque;
use drivebus_can::{Frame, Instant, TxSink};

/// Identifies a station (node or probe) on one [`Bus`](crate::Bus).
/// Numbered from 0 in attachment order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(pub u32);

/// A probe: a station without logic that tests drive by hand
/// ([`Bus::send_from`](crate::Bus::send_from)) and read back
/// ([`Bus::take_received`](crate::Bus::take_received)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ProbeId(pub(crate) NodeId);

impl ProbeId {
    /// The station id of this probe (for fault rules and node state calls).
    #[inline]
    pub const fn node(self) -> NodeId {
        self.0
    }
}

impl From<ProbeId> for NodeId {
    #[inline]
    fn from(p: ProbeId) -> NodeId {
        p.0
    }
}

/// A station's transmit queue as seen by the node: frames pushed here are
/// queued FIFO; only the head competes in arbitration.
///
/// A concrete type (not `dyn FnMut`) so pushing a frame is a plain
/// `VecDeque::push_back`; it implements [`TxSink`] so sans-IO protocol
/// machines can emit straight into it.
pub struct Outbox<'a> {
    pub(crate) queue: &'a mut VecDeque<Frame>,
}

impl Outbox<'_> {
    /// Queue one frame behind the ones already waiting.
    #[inline]
    pub fn push(&mut self, frame: Frame) {
        self.queue.push_back(frame);
    }
    /// Frames waiting in this station's queue (the head may be in arbitration).
    #[inline]
    pub fn pending(&self) -> usize {
        self.queue.len()
    }
}

impl TxSink for Outbox<'_> {
    #[inline]
    fn send(&mut self, frame: Frame) {
        self.queue.push_back(frame);
    }
}

/// Something attached to the bus, driven by the sans-IO contract of
/// `DEVELOPERS.md`.
///
/// The bus calls [`poll`](BusNode::poll) when a node is attached, at every
/// deadline it returned, and right after every [`handle_frame`](BusNode::handle_frame)
/// (a received frame may move the node's next deadline). A deadline at or
/// before `now` is treated as one nanosecond later, so a node cannot stall
/// simulated time.
pub trait BusNode {
    /// A frame was received at `now` (the end of its EOF on the wire).
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut Outbox<'_>);
    /// Do the work due at `now`; return the next deadline, `None` for none.
    fn poll(&mut self, now: Instant, out: &mut Outbox<'_>) -> Option<Instant>;
    /// A transmission by another station was destroyed and the bus carried
    /// an error frame ending at `now`. Default: ignored. The node is polled
    /// right after.
    fn handle_error_frame(&mut self, now: Instant, out: &mut Outbox<'_>) {
        let _ = (now, out);
    }
    /// This station went bus-off, recovered, was disconnected or
    /// reconnected. Frames queued while not [`LinkState::Active`] are
    /// discarded. Default: ignored. The node is polled right after.
    fn link_changed(&mut self, state: LinkState, now: Instant, out: &mut Outbox<'_>) {
        let _ = (state, now, out);
    }
}

impl<N: BusNode + ?Sized> BusNode for alloc::boxed::Box<N> {
    #[inline]
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut Outbox<'_>) {
        (**self).handle_frame(frame, now, out)
    }
    #[inline]
    fn poll(&mut self, now: Instant, out: &mut Outbox<'_>) -> Option<Instant> {
        (**self).poll(now, out)
    }
    #[inline]
    fn handle_error_frame(&mut self, now: Instant, out: &mut Outbox<'_>) {
        (**self).handle_error_frame(now, out)
    }
    #[inline]
    fn link_changed(&mut self, state: LinkState, now: Instant, out: &mut Outbox<'_>) {
        (**self).link_changed(state, now, out)
    }
}

/// Connection state of a station.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkState {
    /// Transmits and receives normally.
    Active,
    /// Its controller is bus-off: nothing it queues reaches the bus and it
    /// receives nothing. `recover_at` is when automatic recovery completes.
    BusOff {
        /// Automatic recovery time, `None` when only [`Bus::recover`](crate::Bus::recover) helps.
        recover_at: Option<Instant>,
    },
    /// Unplugged: nothing in, nothing out, until reconnected.
    Disconnected,
}
