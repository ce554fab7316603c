//! The real-time host: runs any sans-IO [`Device`] on an async [`CanBus`]
//! (a real bus, a socketcand server, the in-process [`Hub`]).
//!
//! A hosted device is one task: it starts the device, then loops
//! `select! { frame = bus.recv() => handle_frame, sleep_until(deadline) =>
//! poll, command => run it }`, polling after every step and sending what
//! the device emitted. `now` is the time since the host started, from
//! `tokio::time` (monotonic), so the device keeps its own timing on the
//! bus: heartbeats, event timers, EMCY inhibit times, SYNC-driven PDOs as
//! the SYNCs arrive. Each device is its own bus participant (its own
//! [`CanBus`]), as separate stations on a real bus: devices hear each other.
//!
//! ```no_run
//! # async fn demo() {
//! use drivebus_node::{Node, NodeConfig, NodeDevice};
//! use drivebus_od::NoHooks;
//! let hub = drivebus_transport::Hub::default();
//! let dev = NodeDevice::new(Node::new(NodeConfig::new(5)), NoHooks);
//! let host = drivebus_transport::host::spawn(dev, hub.attach());
//! // ... later, reach into the device from outside, between two frames:
//! host.with(|d, now| d.node.raise_emcy(0x2310, [0; 5], now)).await;
//! # }
//! ```
//!
//! The same device runs on the virtual bus (`drivebus_bus::Bus::attach`)
//! with the same frames; only the clock differs.

use drivebus_can::{Device, Frame, Instant, LinkState, TxSink};
use std::time::Duration;
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use crate::clock::TokioClock;
use crate::{CanBus, Hub};

type Command<D> = Box<dyn FnOnce(&mut D, Instant, &mut Vec<Frame>) + Send>;

/// A device running in its own task. Dropping the handle does not stop
/// the device (a `serve` command spawns and forgets); use
/// [`DeviceHost::stop`].
pub struct DeviceHost<D> {
    cmd: mpsc::UnboundedSender<Command<D>>,
    task: JoinHandle<()>,
}

impl<D: Device + Send + 'static> DeviceHost<D> {
    /// Runs `f` on the device inside its task (between two frames) and
    /// returns its result; the device is polled right after, so what `f`
    /// changed (an EMCY raised, a value written) takes effect at once.
    /// `None` if the host has stopped.
    pub async fn with<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut D, Instant) -> R + Send + 'static,
    ) -> Option<R> {
        self.with_out(move |d, now, _| f(d, now)).await
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

/// Hosts `device` on `bus`: starts it, then runs it in real time until the
/// bus closes or the host is stopped.
pub fn spawn<D: Device + Send + 'static>(device: D, bus: CanBus) -> DeviceHost<D> {
    let (cmd, rx) = mpsc::unbounded_channel();
    let task = tokio::spawn(run(device, bus, rx));
    DeviceHost { cmd, task }
}

/// Hosts several devices on one hub, each as its own participant (what
/// `drivebus serve` does with its drives).
pub fn spawn_on_hub<D: Device + Send + 'static>(
    devices: impl IntoIterator<Item = D>,
    hub: &Hub,
) -> Vec<DeviceHost<D>> {
    devices.into_iter().map(|d| spawn(d, hub.attach())).collect()
}

/// Connects `hub` to `bus` (a real bus): what one sends reaches the other,
/// so devices hosted on the hub sit on the real bus next to its other
/// stations. Ends when either side closes.
pub fn bridge(hub: &Hub, bus: CanBus) -> JoinHandle<()> {
    let (port_tx, mut port_rx) = hub.attach().split();
    let (bus_tx, mut bus_rx) = bus.split();
    tokio::spawn(async move {
        let inbound = async {
            while let Ok(f) = bus_rx.recv().await {
                if port_tx.send(f).await.is_err() {
                    break;
                }
            }
        };
        let outbound = async {
            while let Ok(f) = port_rx.recv().await {
                if let Err(e) = bus_tx.send(f).await {
                    tracing::warn!(error = %e, "bridge: sending on the bus failed");
                    break;
                }
            }
        };
        tokio::select! {
            () = inbound => tracing::info!("bridge: the bus closed"),
            () = outbound => tracing::info!("bridge: the hub side closed"),
        }
    })
}

/// A device behind a CAN controller whose link state the host's owner
/// sets (a bus-off injected at run time, `drivebus serve --control`):
/// off the bus it hears nothing and what it sends is lost, as on the
/// simulated bus's stations. A bus-off with a `recover_at` ends by itself
/// then (the controller's automatic recovery), as on the simulated bus.
pub struct Controller<D> {
    /// The device.
    pub device: D,
    link: LinkState,
}

impl<D: Device> Controller<D> {
    /// `device` on an active link.
    pub fn new(device: D) -> Self {
        Controller { device, link: LinkState::Active }
    }

    /// The controller's link state.
    pub fn link(&self) -> LinkState {
        self.link
    }

    /// Changes the link state and tells the device
    /// ([`Device::link_changed`]).
    pub fn set_link(&mut self, state: LinkState, now: Instant, out: &mut dyn TxSink) {
        self.link = state;
        if state.is_on_bus() {
            self.device.link_changed(state, now, out);
        } else {
            self.device.link_changed(state, now, &mut Lost);
        }
    }
}

/// What a controller off the bus sends.
struct Lost;

impl TxSink for Lost {
    fn send(&mut self, _: Frame) {}
}

impl<D: Device + 'static> Device for Controller<D> {
    fn start(&mut self, now: Instant, out: &mut dyn TxSink) {
        self.device.start(now, out);
    }
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut dyn TxSink) {
        if self.link.is_on_bus() {
            self.device.handle_frame(frame, now, out);
        }
    }
    fn poll(&mut self, now: Instant, out: &mut dyn TxSink) -> Option<Instant> {
        if let LinkState::BusOff { recover_at: Some(r) } = self.link
            && r <= now
        {
            self.set_link(LinkState::Active, now, out);
        }
        let next =
            if self.link.is_on_bus() { self.device.poll(now, out) } else { self.device.poll(now, &mut Lost) };
        match self.link {
            LinkState::BusOff { recover_at } => drivebus_can::earliest(next, recover_at),
            _ => next,
        }
    }
    fn link_changed(&mut self, state: LinkState, now: Instant, out: &mut dyn TxSink) {
        self.set_link(state, now, out);
    }
    fn handle_error_frame(&mut self, now: Instant, out: &mut dyn TxSink) {
        if self.link.is_on_bus() {
            self.device.handle_error_frame(now, out);
        }
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
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
    let clock = TokioClock::start();
    let mut out: Vec<Frame> = Vec::new();
    dev.start(clock.now(), &mut out);
    let mut cmds_open = true;
    loop {
        // Poll after every step: a frame or a command may move the deadline
        // or make work due now (the contract allows early polls).
        let next = dev.poll(clock.now(), &mut out);
        if !flush(&bus, &mut out).await {
            return;
        }
        let far = tokio::time::Instant::now() + Duration::from_secs(3600);
        let sleep = tokio::time::sleep_until(next.map_or(far, |t| clock.at(t)));
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

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_node::{Node, NodeConfig, NodeDevice};
    use drivebus_od::NoHooks;

    #[test]
    fn a_bus_off_with_a_recovery_time_ends_by_itself_with_8140h() {
        let mut c = Controller::new(NodeDevice::new(Node::new(NodeConfig::new(5)), NoHooks));
        let mut out: Vec<Frame> = Vec::new();
        c.start(Instant::ZERO, &mut out);
        c.poll(Instant::ZERO, &mut out);
        out.clear();
        let back = Instant::from_micros(11_264);
        c.set_link(LinkState::BusOff { recover_at: Some(back) }, Instant::ZERO, &mut out);
        let next = c.poll(Instant::from_micros(10), &mut out);
        assert!(next.is_some_and(|t| t <= back), "polled again at the recovery: {next:?}");
        assert!(out.is_empty());
        assert!(matches!(c.link(), LinkState::BusOff { .. }));
        c.poll(back, &mut out);
        assert_eq!(c.link(), LinkState::Active);
        assert_eq!(out, [Frame::new(0x85, &[0x40, 0x81, 0x11, 0, 0, 0, 0, 0]), Frame::new(0x85, &[0; 8])]);
    }
}
