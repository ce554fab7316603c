//! A node and its application as one station of the virtual bus.

use crate::{Application, Node};
use drivebus_bus::{BusNode, Outbox};
use drivebus_can::{Frame, Instant, earliest};
use drivebus_od::NoHooks;

/// A [`Node`] plus its [`Application`], attachable to a
/// [`drivebus_bus::Bus`]. It boots at the first poll (when attached).
pub struct SimNode<A: Application = NoHooks> {
    /// The CiA 301 device.
    pub node: Node,
    /// The application (a drive, or `NoHooks`).
    pub app: A,
    booted: bool,
}

impl<A: Application> SimNode<A> {
    /// Wrap a node and its application.
    pub fn new(node: Node, app: A) -> Self {
        SimNode { node, app, booted: false }
    }
}

impl<A: Application> BusNode for SimNode<A> {
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut Outbox<'_>) {
        if self.booted {
            self.node.handle_frame(frame, now, &mut self.app, out);
        }
    }

    fn poll(&mut self, now: Instant, out: &mut Outbox<'_>) -> Option<Instant> {
        if !self.booted {
            self.booted = true;
            self.node.boot(now, &mut self.app, out);
        }
        let next = self.node.poll(now, &mut self.app, out);
        earliest(next, self.app.poll(self.node.od_mut(), now))
    }
}
