//! `VirtualBus`: a participant of a named in-process virtual CAN bus,
//! optionally hosting drive twins on it.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use drivebus_can::{CanId, Frame, LinkState};
use drivebus_personality::machine::{Machine, MachineFile, MachineFileError};
use drivebus_personality::{PersonalityDevice, Profile};
use drivebus_transport::host::{self, Controller, DeviceHost};
use drivebus_transport::{CanRx, CanTx, Hub, TrySendError};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use tokio::sync::watch;

use crate::control::{self, Action};
use crate::runtime;
use crate::state::{DriveState, Owner};

/// A received frame: identifier, extended, remote, DLC, data.
pub(crate) type Received = (u32, bool, bool, u8, Vec<u8>);

/// A drive built for hosting: what `drivebus serve --drive` builds, and
/// what it is built from (to build it again at power-on).
pub(crate) struct Built {
    pub(crate) profile: Profile,
    pub(crate) node: u8,
    pub(crate) machine: Machine,
    pub(crate) dev: PersonalityDevice,
}

/// The real-time host of one drive: behind a CAN controller whose link
/// the owner sets, as `drivebus serve` hosts it.
type DriveHost = DeviceHost<Controller<PersonalityDevice>>;

/// One drive hosted in real time (by a `VirtualBus` or a `Server`).
struct Hosted {
    profile: Profile,
    node: u8,
    machine: Machine,
    /// `None` while its power is off.
    host: Mutex<Option<Arc<DriveHost>>>,
}

impl Hosted {
    /// `akd:1`.
    fn spec(&self) -> String {
        format!("{}:{}", self.profile, self.node)
    }

    /// The running host, `None` while the power is off.
    fn running(&self) -> Option<Arc<DriveHost>> {
        self.host.lock().ok().and_then(|h| h.clone())
    }
}

/// The drives of a `VirtualBus` or a `Server` on their hub.
pub(crate) struct HostedDrives {
    hub: Hub,
    drives: Vec<Hosted>,
}

impl HostedDrives {
    /// Starts the drives `built` as participants of `hub` (inside the runtime).
    pub(crate) fn spawn_all(built: Vec<Built>, hub: &Hub) -> HostedDrives {
        let drives = built
            .into_iter()
            .map(|b| Hosted {
                profile: b.profile,
                node: b.node,
                machine: b.machine,
                host: Mutex::new(Some(Arc::new(host::spawn(Controller::new(b.dev), hub.attach())))),
            })
            .collect();
        HostedDrives { hub: hub.clone(), drives }
    }

    /// `["akd:1", ...]`.
    pub(crate) fn specs(&self) -> Vec<String> {
        self.drives.iter().map(Hosted::spec).collect()
    }

    /// The state of the drives that have power, read now, with the GIL released.
    pub(crate) fn states(&self, py: Python<'_>) -> PyResult<Vec<DriveState>> {
        let rt = runtime()?;
        py.detach(|| {
            let mut states = Vec::with_capacity(self.drives.len());
            for h in &self.drives {
                let Some(host) = h.running() else { continue };
                let s = rt.block_on(host.with(|d, _| DriveState::of(&d.device)));
                states
                    .push(s.ok_or_else(|| PyOSError::new_err(format!("drive {} is not running", h.spec())))?);
            }
            Ok(states)
        })
    }

    /// Stops every drive (they fall silent, like a power cut).
    pub(crate) fn stop(&self) {
        for h in &self.drives {
            if let Some(host) = h.running() {
                host.stop();
            }
        }
    }

    /// Carries out `action` on drive `node` between two of its frames, as
    /// `drivebus serve --control` does (crate::control).
    pub(crate) fn apply(&self, py: Python<'_>, node: u8, action: Action) -> PyResult<()> {
        let Some(h) = self.drives.iter().find(|h| h.node == node) else {
            let nodes = self.drives.iter().map(|h| (h.node, ())).collect();
            return Err(control::no_node(&nodes, node));
        };
        let rt = runtime()?;
        match action {
            Action::Power(on) => {
                let mut slot =
                    h.host.lock().map_err(|_| PyOSError::new_err("the drive's host is poisoned"))?;
                match (on, slot.take()) {
                    (false, Some(host)) => host.stop(),
                    (true, None) => {
                        let dev = h
                            .profile
                            .build_on(h.node, &h.machine)
                            .map_err(|e| PyValueError::new_err(format!("cannot build {}: {e}", h.spec())))?;
                        let _in_runtime = rt.enter();
                        *slot = Some(Arc::new(host::spawn(Controller::new(dev), self.hub.attach())));
                    }
                    // Already as asked: nothing changes.
                    (_, host) => *slot = host,
                }
                Ok(())
            }
            Action::Machine(change, duration) => {
                let host = h.running().ok_or_else(|| control::powered_off(node))?;
                let done = py.detach(|| {
                    rt.block_on(host.with_out(move |d, now, out| {
                        let dev = &mut d.device;
                        dev.node.with_app(now, &mut dev.app, out, |app, _| {
                            app.change_machine(now, change, duration)
                        })
                    }))
                });
                done.ok_or_else(|| stopped(node))?.map_err(|e| control::refused(node, e))
            }
            Action::BusOff(off) => {
                let host = h.running().ok_or_else(|| control::powered_off(node))?;
                let state = if off { LinkState::BusOff { recover_at: None } } else { LinkState::Active };
                let done =
                    py.detach(|| rt.block_on(host.with_out(move |d, now, out| d.set_link(state, now, out))));
                done.ok_or_else(|| stopped(node))
            }
        }
    }
}

/// The drive's task ended although it has power.
fn stopped(node: u8) -> PyErr {
    PyOSError::new_err(format!("node {node} has stopped running"))
}

/// A connection to the in-process virtual CAN bus `channel` (every
/// `VirtualBus` of the process with the same channel is on the same bus),
/// hosting the drives `drives` (`"akd:1"`) on it in real time while it is
/// open. Frames it sends reach every other participant, never itself.
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct VirtualBus {
    channel: String,
    tx: CanTx,
    rx: Mutex<CanRx>,
    closed: watch::Sender<bool>,
    drives: HostedDrives,
}

#[pymethods]
impl VirtualBus {
    /// Joins `channel` and starts `drives` on it, each on its machine
    /// (`machine`: a machine file, as `drivebus serve --machine` takes it;
    /// else the profile's default). Raises `ValueError` with the message
    /// of `drivebus serve` for a bad drive or machine file.
    #[new]
    #[pyo3(signature = (channel = "virtual", drives = Vec::new(), machine = None))]
    fn new(channel: &str, drives: Vec<String>, machine: Option<PathBuf>) -> PyResult<VirtualBus> {
        let built = build_all(&drives, machine.as_deref())?;
        let rt = runtime()?;
        let _in_runtime = rt.enter();
        let hub = drivebus_transport::hub::virtual_hub(channel);
        // Joined before the drives start: their boot-ups reach this bus.
        let (tx, rx) = hub.attach().split();
        let drives = HostedDrives::spawn_all(built, &hub);
        Ok(VirtualBus {
            channel: channel.to_owned(),
            tx,
            rx: Mutex::new(rx),
            closed: watch::channel(false).0,
            drives,
        })
    }

    /// The channel (the bus's name).
    #[getter]
    fn channel(&self) -> &str {
        &self.channel
    }

    /// True once `close()` was called.
    #[getter]
    fn closed(&self) -> bool {
        *self.closed.borrow()
    }

    /// Sends a classic CAN frame. `dlc` is the length of a remote frame
    /// (default 0). Raises `ValueError` for a frame CAN cannot carry and
    /// `OSError` once the bus is closed.
    #[pyo3(signature = (arbitration_id, data, is_extended_id = false, is_remote_frame = false, dlc = None))]
    fn send(
        &self,
        py: Python<'_>,
        arbitration_id: u32,
        data: &[u8],
        is_extended_id: bool,
        is_remote_frame: bool,
        dlc: Option<u8>,
    ) -> PyResult<()> {
        self.check_open()?;
        let frame = frame(arbitration_id, data, is_extended_id, is_remote_frame, dlc)?;
        match self.tx.try_send(frame) {
            Ok(()) => Ok(()),
            Err(TrySendError::Busy(frame)) => {
                let rt = runtime()?;
                py.detach(|| rt.block_on(self.tx.send(frame))).map_err(|e| PyOSError::new_err(e.to_string()))
            }
            Err(TrySendError::Failed(e)) => Err(PyOSError::new_err(e.to_string())),
        }
    }

    /// The next frame another participant sent, as `(arbitration_id,
    /// is_extended_id, is_remote_frame, dlc, data)`; `None` when `timeout`
    /// seconds pass first (`None`: wait until a frame comes or the bus is
    /// closed). Raises `OSError` once the bus is closed.
    #[pyo3(signature = (timeout = None))]
    fn recv(&self, py: Python<'_>, timeout: Option<f64>) -> PyResult<Option<Received>> {
        let wait = match timeout {
            None => None,
            Some(t) if t.is_finite() && t >= 0.0 => Some(Duration::from_secs_f64(t.min(1e9))),
            Some(t) => {
                return Err(PyValueError::new_err(format!(
                    "timeout must be a non-negative number of seconds, not {t}"
                )));
            }
        };
        self.check_open()?;
        let rt = runtime()?;
        let mut closed = self.closed.subscribe();
        let got = py.detach(|| {
            let Ok(mut rx) = self.rx.lock() else {
                return Err(std::io::Error::other("the receiver is poisoned"));
            };
            rt.block_on(async {
                let next = async {
                    match wait {
                        Some(d) => tokio::time::timeout(d, rx.recv()).await.ok(),
                        None => Some(rx.recv().await),
                    }
                };
                tokio::select! {
                    r = next => r.transpose(),
                    _ = closed.wait_for(|c| *c) => Err(std::io::Error::other(closed_message())),
                }
            })
        });
        let frame = got.map_err(|e| PyOSError::new_err(e.to_string()))?;
        Ok(frame.as_ref().map(received))
    }

    /// The hosted drives' state, read now, in the order they were given.
    /// Raises `OSError` once the bus is closed.
    #[getter]
    pub(crate) fn drives(slf: &Bound<'_, Self>) -> PyResult<Vec<DriveState>> {
        // Stopping a drive's task takes effect at its next await: a read
        // right after `close` could still be answered.
        let bus = slf.get();
        bus.check_open()?;
        let states = bus.drives.states(slf.py())?;
        Ok(states.into_iter().map(|s| s.owned_by(Owner::Bus(slf.clone().unbind()))).collect())
    }

    /// Sets machine input `input` of drive `node` to `value`, as `drivebus
    /// control input NODE INPUT [LINE] VALUE [--for SECONDS]`: `"digital"`
    /// (`line` 1..16, value 0/1), `"analog"` (`line` 1..4, volts),
    /// `"master_velocity"`, `"master_position"`, `"motor_temperature"`,
    /// `"brake"`; for `duration` seconds, then back to the machine's value.
    /// It shows in the drive's objects (60FDh, a TPDO) at its next control
    /// period. Raises `ValueError` with the control interface's message.
    #[pyo3(signature = (node, input, value, line = None, duration = None))]
    fn input(
        &self,
        py: Python<'_>,
        node: u8,
        input: &str,
        value: f64,
        line: Option<u8>,
        duration: Option<f64>,
    ) -> PyResult<()> {
        self.act(py, node, control::input(input, line, value, duration)?)
    }

    /// Starts machine fault `kind` of drive `node` (`"encoder"`,
    /// `"over_current"`, `"over_temperature"`, `"over_voltage"`,
    /// `"under_voltage"`, `"trip"` / `"wire_break"` with `switch`
    /// `"negative_limit"`, `"positive_limit"` or `"home_switch"`), as
    /// `drivebus control fault`; `"clear"` ends every machine fault that is
    /// on (a latched drive fault stays until the master's fault reset).
    #[pyo3(signature = (node, kind, switch = None, duration = None))]
    fn fault(
        &self,
        py: Python<'_>,
        node: u8,
        kind: &str,
        switch: Option<&str>,
        duration: Option<f64>,
    ) -> PyResult<()> {
        self.act(py, node, control::fault(kind, switch, duration)?)
    }

    /// Drive `node`'s CAN controller goes bus-off: it hears nothing and what
    /// it sends is lost (`drivebus control bus off NODE`).
    fn bus_off(&self, py: Python<'_>, node: u8) -> PyResult<()> {
        self.act(py, node, Action::BusOff(true))
    }

    /// Drive `node` is back on the bus (`drivebus control bus on NODE`).
    fn bus_on(&self, py: Python<'_>, node: u8) -> PyResult<()> {
        self.act(py, node, Action::BusOff(false))
    }

    /// Cuts (`on=False`) or restores drive `node`'s power, as `drivebus
    /// control power NODE off|on`: off it is silent and forgets its state;
    /// on it boots again (a boot-up message) with its parameters at their
    /// power-on values.
    fn power(&self, py: Python<'_>, node: u8, on: bool) -> PyResult<()> {
        self.act(py, node, Action::Power(on))
    }

    /// Stops the hosted drives (they fall silent, like a power cut) and
    /// leaves the bus; a blocked `recv` returns with `OSError`. Closing
    /// twice is harmless.
    fn close(&self) {
        self.closed.send_replace(true);
        self.drives.stop();
    }

    fn __repr__(&self) -> String {
        let drives = self.drives.specs();
        format!("VirtualBus(channel={:?}, drives={:?})", self.channel, drives)
    }
}

impl VirtualBus {
    /// Carries out `action` on drive `node` (the methods above and a
    /// drive's own, `DriveState.fault`, ...).
    pub(crate) fn act(&self, py: Python<'_>, node: u8, action: Action) -> PyResult<()> {
        self.check_open()?;
        self.drives.apply(py, node, action)
    }

    fn check_open(&self) -> PyResult<()> {
        if *self.closed.borrow() { Err(PyOSError::new_err(closed_message())) } else { Ok(()) }
    }
}

impl Drop for VirtualBus {
    fn drop(&mut self) {
        self.close();
    }
}

fn closed_message() -> &'static str {
    "the virtual bus is closed"
}

/// The drives `drivebus serve --drive PROFILE:NODE [--machine FILE]`
/// hosts: each personality on its machine (from `machine_file`, else the
/// profile's default), parameters in memory. The errors are the CLI's.
pub(crate) fn build_all(drives: &[String], machine_file: Option<&Path>) -> PyResult<Vec<Built>> {
    let specs = drivebus_personality::drive_specs(drives).map_err(PyValueError::new_err)?;
    let file = match machine_file {
        None => None,
        Some(path) => {
            let at = |e: MachineFileError| PyValueError::new_err(format!("{}: {e}", path.display()));
            let f = MachineFile::read(path).map_err(at)?;
            f.check_nodes(&specs.iter().map(|s| s.1).collect::<Vec<_>>()).map_err(at)?;
            Some((f, at))
        }
    };
    let mut built = Vec::with_capacity(specs.len());
    for (profile, node) in specs {
        let machine = match &file {
            None => Machine::default_for(profile),
            Some((f, at)) => f.machine_for(profile, node).map_err(at)?,
        };
        let dev = profile
            .build_on(node, &machine)
            .map_err(|e| PyValueError::new_err(format!("cannot build {profile}:{node}: {e}")))?;
        built.push(Built { profile, node, machine, dev });
    }
    Ok(built)
}

/// A frame as Python gets it.
pub(crate) fn received(f: &Frame) -> Received {
    let data = if f.is_rtr() { Vec::new() } else { f.data().to_vec() };
    (f.id().raw(), f.id().is_extended(), f.is_rtr(), f.len() as u8, data)
}

/// The frame Python asked for, or why CAN cannot carry it.
pub(crate) fn frame(id: u32, data: &[u8], extended: bool, remote: bool, dlc: Option<u8>) -> PyResult<Frame> {
    let can_id =
        if extended { CanId::extended(id) } else { u16::try_from(id).ok().and_then(CanId::standard) };
    let bits = if extended { 29 } else { 11 };
    let can_id = can_id.ok_or_else(|| {
        PyValueError::new_err(format!("CAN identifier 0x{id:X} does not fit in {bits} bits"))
    })?;
    let built =
        if remote { Frame::try_remote(can_id, dlc.unwrap_or(0)) } else { Frame::try_new(can_id, data) };
    built.map_err(|e| PyValueError::new_err(format!("{e} (identifier 0x{id:X}, {} data bytes)", data.len())))
}
