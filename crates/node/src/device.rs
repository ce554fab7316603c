//! [`NodeDevice`]: a node and its application as one [`Device`], the form
//! every host runs (the virtual bus, the real-time host, tests).

use crate::{Application, Node, NodeEvent};
use drivebus_can::{Device, Frame, Instant, LinkState, TxSink};
use drivebus_od::NoHooks;

/// A [`Node`] plus its [`Application`]: one CANopen device for any host.
///
/// [`Device::start`] boots the node; frames, deadlines and link changes go
/// to the node, which calls the application and carries out its
/// [`Request`](crate::Request)s. A host reaches the concrete type through
/// [`Device::as_any_mut`] (e.g. `bus.node_mut::<NodeDevice<Drive>>(id)`).
pub struct NodeDevice<A: Application = NoHooks> {
    /// The CiA 301 device.
    pub node: Node,
    /// The application (a drive, a personality, or `NoHooks`).
    pub app: A,
}

impl<A: Application> NodeDevice<A> {
    /// Pairs a node and its application.
    pub fn new(node: Node, app: A) -> Self {
        NodeDevice { node, app }
    }

    /// Writes an object through the node's write path (see
    /// [`Node::write_object`]), e.g. for another protocol such as CoE.
    pub fn write_object(
        &mut self,
        index: u16,
        sub: u8,
        data: &[u8],
        now: Instant,
        out: &mut impl TxSink,
    ) -> Result<(), drivebus_od::SdoAbort> {
        self.node.write_object(index, sub, data, now, &mut self.app, out)
    }

    /// Reads an object through the node's read path (see
    /// [`Node::read_object`]).
    pub fn read_object(&mut self, index: u16, sub: u8, now: Instant) -> Result<&[u8], drivebus_od::SdoAbort> {
        self.node.read_object(index, sub, now, &mut self.app)
    }
}

impl<A: Application + 'static> Device for NodeDevice<A> {
    fn start(&mut self, now: Instant, mut out: &mut dyn TxSink) {
        self.node.boot(now, &mut self.app, &mut out);
    }

    #[inline]
    fn handle_frame(&mut self, frame: &Frame, now: Instant, mut out: &mut dyn TxSink) {
        self.node.handle_frame(frame, now, &mut self.app, &mut out);
    }

    #[inline]
    fn poll(&mut self, now: Instant, mut out: &mut dyn TxSink) -> Option<Instant> {
        self.node.poll(now, &mut self.app, &mut out)
    }

    fn link_changed(&mut self, state: LinkState, now: Instant, mut out: &mut dyn TxSink) {
        self.node.link_changed(state, now, &mut self.app, &mut out);
    }

    fn as_any(&self) -> &dyn core::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn core::any::Any {
        self
    }
}

impl Node {
    /// The controller's link state changed: bus-off raises 8140h (1001h
    /// bit 4) and the recovery sends it and its error reset (CiA 301
    /// §7.2.7); the application hears it ([`NodeEvent::Link`]) and its
    /// requests are carried out.
    pub fn link_changed<A: Application + ?Sized>(
        &mut self,
        state: LinkState,
        now: Instant,
        app: &mut A,
        out: &mut impl TxSink,
    ) {
        self.s.link.now = now;
        match state {
            LinkState::BusOff { .. } => self.bus_off(now, app, out),
            LinkState::Active | LinkState::ErrorPassive => self.bus_recovered(now),
            LinkState::Disconnected => {}
        }
        app.on_event(&mut self.s.cx(&mut self.od), NodeEvent::Link(state));
        if self.run_requests(now, app, out) {
            self.poll_services(now, app, out);
        }
    }
}
