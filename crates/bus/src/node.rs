//! What can be attached to the bus.

use alloc::collections::VecDeque;
use drivebus_can::{Frame, TxSink};

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

/// A station's transmit queue as the bus hands it to a device: frames sent
/// here are queued FIFO; only the head competes in arbitration. The bus
/// passes it as `&mut dyn TxSink` (the [`Device`](drivebus_can::Device)
/// contract); a push is a plain `VecDeque::push_back`.
pub(crate) struct Outbox<'a> {
    pub(crate) queue: &'a mut VecDeque<Frame>,
}

impl TxSink for Outbox<'_> {
    #[inline]
    fn send(&mut self, frame: Frame) {
        self.queue.push_back(frame);
    }
}

impl From<NodeId> for u32 {
    /// The station number a [`FaultRule`](crate::FaultRule) names.
    fn from(n: NodeId) -> u32 {
        n.0
    }
}

impl From<ProbeId> for u32 {
    /// The station number a [`FaultRule`](crate::FaultRule) names.
    fn from(p: ProbeId) -> u32 {
        NodeId::from(p).0
    }
}
