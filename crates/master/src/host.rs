//! Running sans-IO devices in real time on an async bus.
//!
//! A hosted device is one task: it boots the device, then loops
//! `select! { frame = bus.recv() => handle_frame, sleep_until(deadline) => poll,
//! command => run it }`, sending everything the device emitted after each
//! step. `now` is the time since the host started, from `tokio::time`
//! (monotonic). Each device is its own bus participant (its own
//! [`CanBus`]), as separate stations on a real bus: devices hear each other.
//!
//! ```no_run
//! # async fn demo() {
//! use drivebus_node::{Node, NodeConfig};
//! let hub = drivebus_transport::Hub::default();
//! let host = drivebus_master::spawn_node(Node::new(NodeConfig::new(5)), drivebus_od::NoHooks, hub.attach());
//! // ... later, reach into the device from outside:
//! host.with(|dev, _now| dev.node.raise_emcy(0x2310, [0; 5], _now)).await;
//! # }
//! ```
//!
//! [`Node`] and every application in this workspace are `Send`, so hosts
//! are ordinary tasks on the caller's (multi-threaded or current-thread)
//! runtime.

use drivebus_can::{Frame, Instant, earliest};
use drivebus_node::{Application, Node};
use drivebus_transport::{CanBus, Hub};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use crate::clock::Clock;

/// A sans-IO device a host can run: the `drivebus_bus::BusNode` contract
/// with a plain `Vec<Frame>` as the transmit queue.
pub trait Device: Send + 'static {
    /// Start the device (boot-up message, first deadlines).
    fn boot(&mut self, now: Instant, out: &mut Vec<Frame>);
    /// A frame was received at `now`.
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut Vec<Frame>);
    /// Do the work due at `now`; return the next deadline.
    fn poll(&mut self, now: Instant, out: &mut Vec<Frame>) -> Option<Instant>;
}

/// Heterogeneous devices (drives next to plain nodes) on one host list.
impl Device for Box<dyn Device> {
    fn boot(&mut self, now: Instant, out: &mut Vec<Frame>) {
        (**self).boot(now, out);
    }
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut Vec<Frame>) {
        (**self).handle_frame(frame, now, out);
    }
    fn poll(&mut self, now: Instant, out: &mut Vec<Frame>) -> Option<Instant> {
        (**self).poll(now, out)
    }
}

/// A CiA 301 [`Node`] and its [`Application`] as a hostable device (the
/// real-time twin of `drivebus_node::SimNode`).
pub struct NodeDevice<A> {
    /// The CiA 301 device.
    pub node: Node,
    /// Its application.
    pub app: A,
}

impl<A: Application + Send + 'static> Device for NodeDevice<A> {
    fn boot(&mut self, now: Instant, out: &mut Vec<Frame>) {
        self.node.boot(now, &mut self.app, out);
    }
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut Vec<Frame>) {
        self.node.handle_frame(frame, now, &mut self.app, out);
    }
    fn poll(&mut self, now: Instant, out: &mut Vec<Frame>) -> Option<Instant> {
        let next = self.node.poll(now, &mut self.app, out);
        earliest(next, self.app.poll(self.node.od_mut(), now))
    }
}

type Command<D> = Box<dyn FnOnce(&mut D, Instant, &mut Vec<Frame>) + Send>;

/// A device running in its own task. Dropping the handle does not stop
/// the device (a `serve` command spawns and forgets); use
/// [`NodeHost::stop`].
pub struct NodeHost<D> {
    cmd: mpsc::UnboundedSender<Command<D>>,
    task: JoinHandle<()>,
}

impl<D: Device> NodeHost<D> {
    /// Runs `f` on the device inside its task (between two frames) and
    /// returns its result; frames it emits through the device's own
    /// methods are sent by the next poll. `None` if the host has stopped.
    pub async fn with<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut D, Instant) -> R + Send + 'static,
    ) -> Option<R> {
        let (tx, rx) = oneshot::channel();
        let cmd: Command<D> = Box::new(move |d, now, _out| {
            let _ = tx.send(f(d, now));
        });
        self.cmd.send(cmd).ok()?;
        rx.await.ok()
    }

    /// Like [`with`](Self::with), with access to the transmit queue.
    pub async fn with_out<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut D, Instant, &mut Vec<Frame>) -> R + Send + 'static,
    ) -> Option<R> {
        let (tx, rx) = oneshot::channel();
        let cmd: Command<D> = Box::new(move |d, now, out| {
            let _ = tx.send(f(d, now, out));
        });
        self.cmd.send(cmd).ok()?;
        rx.await.ok()
    }

    /// True once the task has ended (bus closed, stopped, or panicked).
    pub fn is_finished(&self) -> bool {
        self.task.is_finished()
    }

    /// Stops the device (it simply goes silent, like a power cut).
    pub fn stop(&self) {
        self.task.abort();
    }

    /// The task, to await or abort it.
    pub fn into_join_handle(self) -> JoinHandle<()> {
        self.task
    }
}

/// Hosts a CiA 301 node with its application on `bus` (boots it first).
pub fn spawn_node<A: Application + Send + 'static>(
    node: Node,
    app: A,
    bus: CanBus,
) -> NodeHost<NodeDevice<A>> {
    spawn_device(NodeDevice { node, app }, bus)
}

/// Hosts any [`Device`] on `bus`.
pub fn spawn_device<D: Device>(device: D, bus: CanBus) -> NodeHost<D> {
    let (cmd, rx) = mpsc::unbounded_channel();
    let task = tokio::spawn(run(device, bus, rx));
    NodeHost { cmd, task }
}

/// Hosts several devices on one hub, each as its own participant. This is
/// what `drivebus serve` uses for 1..n drives on the socketcand hub.
pub fn spawn_on_hub<D: Device>(devices: impl IntoIterator<Item = D>, hub: &Hub) -> Vec<NodeHost<D>> {
    devices.into_iter().map(|d| spawn_device(d, hub.attach())).collect()
}

async fn flush(bus: &CanBus, out: &mut Vec<Frame>) -> bool {
    for f in out.drain(..) {
        if let Err(e) = bus.send(f).await {
            tracing::warn!(error = %e, "hosted device: bus send failed");
            return false;
        }
    }
    true
}

async fn run<D: Device>(mut dev: D, mut bus: CanBus, mut cmds: mpsc::UnboundedReceiver<Command<D>>) {
    let clock = Clock::new();
    let mut out = Vec::new();
    dev.boot(clock.now(), &mut out);
    let mut cmds_open = true;
    loop {
        // Poll after every step: a frame or a command may move the deadline
        // or make work due now (the contract allows early polls).
        let next = dev.poll(clock.now(), &mut out);
        if !flush(&bus, &mut out).await {
            return;
        }
        let sleep = tokio::time::sleep_until(next.map_or_else(far_future, |t| clock.at(t)));
        tokio::select! {
            // Frames first: a queued frame is handled before a deadline
            // that passed while this task was not scheduled.
            biased;
            r = bus.recv() => match r {
                Ok(f) => dev.handle_frame(&f, clock.now(), &mut out),
                Err(e) => {
                    tracing::info!(error = %e, "hosted device: bus closed");
                    return;
                }
            },
            () = sleep => {}
            c = cmds.recv(), if cmds_open => match c {
                Some(c) => c(&mut dev, clock.now(), &mut out),
                None => cmds_open = false,
            },
        }
        if !flush(&bus, &mut out).await {
            return;
        }
    }
}

fn far_future() -> tokio::time::Instant {
    tokio::time::Instant::now() + std::time::Duration::from_secs(3600)
}
