//! `Simulation`: drive twins on the virtual bus in simulated time
//! (`drivebus_bus::Bus`), as fast as the CPU allows and deterministic.
//!
//! The bus (its devices are not `Send`) lives on a thread of its own; the
//! Python object sends it requests and waits for the answers with the GIL
//! released, so any Python thread may use a `Simulation`, one call at a
//! time, and others run meanwhile. The master of `drivebus_master` is a
//! station of the same bus (`SimBus`); `sim.master()` ([`crate::master`])
//! runs its procedures there.

use std::path::PathBuf;
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Frame, Instant};
use drivebus_master::{MasterConfig, SimBus};
use drivebus_personality::machine::Machine;
use drivebus_personality::{PersonalityDevice, Profile};
use pyo3::IntoPyObjectExt;
use pyo3::exceptions::{PyImportError, PyRuntimeError, PyTimeoutError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::bus::{Received, frame, received};
use crate::control::{self, Action};
use crate::master::Master;
use crate::state::{DriveState, Owner};

/// One frame of the log: simulated time in seconds, then as `recv`.
type Logged = (f64, u32, bool, bool, u8, Vec<u8>);

/// The longest `advance` in one call: a year of simulated time.
const MAX_ADVANCE_S: f64 = 365.0 * 86_400.0;

/// Drive twins on a virtual CAN bus in simulated time. Nothing moves
/// between calls: `advance(seconds)` runs the bus and the drives; the same
/// calls give the same frame log, byte for byte.
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct Simulation {
    link: Arc<Link>,
    /// Each drive's node-ID and personality (its EDS names the objects).
    drives: Vec<(u8, Profile)>,
}

/// Work for the bus thread, with the simulation in hand.
pub(crate) type Job = Box<dyn FnOnce(&mut Sim) + Send>;

/// What the bus thread is asked to do.
enum Request {
    Advance(Duration, mpsc::Sender<()>),
    Send(Frame),
    Received(mpsc::Sender<Vec<Received>>),
    Log(mpsc::Sender<Vec<Logged>>),
    LogLines(mpsc::Sender<Vec<String>>),
    Drives(mpsc::Sender<Vec<DriveState>>),
    Now(mpsc::Sender<f64>),
    Run(Job),
}

/// The bus with the drives, the master (`drivebus_master::SimBus`: the
/// same master as the `drivebus` tool's, in simulated time) and the
/// host's station, on the bus thread.
pub(crate) struct Sim {
    /// The bus and the master.
    pub(crate) sim: SimBus,
    probe: ProbeId,
    /// Each drive's station and what it was built from (to build it again
    /// at power-on).
    drives: Vec<(NodeId, Profile, u8, Machine)>,
}

impl Sim {
    /// Carries out `action` on drive `node` now, through the library calls
    /// the control interface's in-code form names (docs/control.md).
    fn apply(&mut self, node: u8, action: Action) -> PyResult<()> {
        let Some((id, profile, _, machine)) = self.drives.iter().find(|d| d.2 == node) else {
            let nodes = self.drives.iter().map(|d| (d.2, ())).collect();
            return Err(control::no_node(&nodes, node));
        };
        let id = *id;
        let bus = self.sim.bus_mut();
        let powered = bus.node::<PersonalityDevice>(id).is_some();
        match action {
            Action::Power(false) => {
                bus.power_off(id);
            }
            Action::Power(true) if !powered => {
                let dev = profile
                    .build_on(node, machine)
                    .map_err(|e| PyValueError::new_err(format!("cannot build {profile}:{node}: {e}")))?;
                bus.power_on(id, dev);
            }
            Action::Power(true) => {}
            _ if !powered => return Err(control::powered_off(node)),
            Action::Machine(change, duration) => {
                let now = bus.now();
                let dev = bus.node_mut::<PersonalityDevice>(id).ok_or_else(|| control::powered_off(node))?;
                dev.app.change_machine(now, change, duration).map_err(|e| control::refused(node, e))?;
                // Applied at this poll, as a scheduled entry.
                bus.wake(id);
            }
            Action::BusOff(true) => bus.set_bus_off(id),
            Action::BusOff(false) => bus.recover(id),
        }
        Ok(())
    }

    /// Answers requests until the `Simulation` is dropped.
    fn serve(mut self, requests: mpsc::Receiver<Request>) {
        // A send fails only when the caller gave up waiting: nothing to do.
        for r in requests {
            match r {
                Request::Advance(d, done) => {
                    self.sim.run_for(d);
                    let _ = done.send(());
                }
                Request::Send(f) => {
                    self.sim.bus_mut().send_from(self.probe, f);
                }
                Request::Received(out) => {
                    let _ =
                        out.send(self.sim.bus_mut().take_received(self.probe).iter().map(received).collect());
                }
                Request::Log(out) => {
                    let log = self.sim.bus().log().iter().map(|e| {
                        let (id, ext, rtr, dlc, data) = received(&e.frame);
                        (seconds(e.time), id, ext, rtr, dlc, data)
                    });
                    let _ = out.send(log.collect());
                }
                Request::LogLines(out) => {
                    let _ = out.send(self.sim.bus().log_lines());
                }
                Request::Drives(out) => {
                    let bus = self.sim.bus();
                    let drives = self.drives.iter().filter_map(|d| bus.node::<PersonalityDevice>(d.0));
                    let _ = out.send(drives.map(DriveState::of).collect());
                }
                Request::Now(out) => {
                    let _ = out.send(seconds(self.sim.now()));
                }
                Request::Run(job) => job(&mut self),
            }
        }
    }
}

/// The way to the bus thread, shared by a `Simulation` and its masters.
pub(crate) struct Link(Mutex<mpsc::Sender<Request>>);

impl Link {
    /// Hands `r` to the bus thread.
    fn request(&self, r: Request) -> PyResult<()> {
        let to_bus = self.0.lock().map_err(|_| stopped())?;
        to_bus.send(r).map_err(|_| stopped())
    }

    /// Asks the bus thread and waits for the answer, the GIL released.
    fn ask<T: Send>(&self, py: Python<'_>, r: impl FnOnce(mpsc::Sender<T>) -> Request) -> PyResult<T> {
        let (tx, rx) = mpsc::channel();
        self.request(r(tx))?;
        py.detach(move || rx.recv()).map_err(|_| stopped())
    }

    /// Runs `f` on the bus thread and waits for its result, the GIL released.
    pub(crate) fn run<T: Send + 'static>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut Sim) -> T + Send + 'static,
    ) -> PyResult<T> {
        self.ask(py, |tx| {
            Request::Run(Box::new(move |s| {
                let _ = tx.send(f(s));
            }))
        })
    }
}

#[pymethods]
impl Simulation {
    /// Builds `drives` (`"akd:1"`, each on its machine from the machine
    /// file `machine`, else the profile's default) on a bus at `bitrate`
    /// bit/s (`None`: frames take no time). Raises `ValueError` with the
    /// CLI's message for a bad drive or machine file, and for a bitrate of 0.
    #[new]
    #[pyo3(signature = (drives = Vec::new(), bitrate = Some(1_000_000), machine = None))]
    fn new(drives: Vec<String>, bitrate: Option<u32>, machine: Option<PathBuf>) -> PyResult<Simulation> {
        if bitrate == Some(0) {
            return Err(PyValueError::new_err("bitrate must be positive (None: frames take no time)"));
        }
        let built = crate::bus::build_all(&drives, machine.as_deref())?;
        let specs = built.iter().map(|b| (b.node, b.profile)).collect();
        let (to_bus, requests) = mpsc::channel();
        std::thread::Builder::new()
            .name("drivebus-sim".into())
            .spawn(move || {
                let mut bus = Bus::new(BusConfig { bitrate, ..BusConfig::default() });
                // The host's station, before the drives: it hears their boot-ups.
                let probe = bus.attach_probe();
                let drives =
                    built.into_iter().map(|b| (bus.attach(b.dev), b.profile, b.node, b.machine)).collect();
                // The master's station joins last, as in `drivebus demo`.
                let sim = SimBus::with_config(bus, MasterConfig::default());
                Sim { sim, probe, drives }.serve(requests);
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start the simulation thread: {e}")))?;
        Ok(Simulation { link: Arc::new(Link(Mutex::new(to_bus))), drives: specs })
    }

    /// Simulated time in seconds since the start.
    #[getter]
    fn now(&self, py: Python<'_>) -> PyResult<f64> {
        self.ask(py, Request::Now)
    }

    /// Runs the bus and the drives for `seconds` of simulated time.
    fn advance(&self, py: Python<'_>, seconds: f64) -> PyResult<()> {
        if !(seconds.is_finite() && (0.0..=MAX_ADVANCE_S).contains(&seconds)) {
            return Err(PyValueError::new_err(format!(
                "seconds must be a number from 0 to {MAX_ADVANCE_S}, not {seconds}"
            )));
        }
        let d = Duration::from_secs_f64(seconds);
        self.ask(py, |done| Request::Advance(d, done))
    }

    /// Queues a classic CAN frame from the host's station at the current
    /// simulated time (it goes on the bus during the next `advance`).
    /// Raises `ValueError` for a frame CAN cannot carry.
    #[pyo3(signature = (arbitration_id, data, is_extended_id = false, is_remote_frame = false, dlc = None))]
    fn send(
        &self,
        arbitration_id: u32,
        data: &[u8],
        is_extended_id: bool,
        is_remote_frame: bool,
        dlc: Option<u8>,
    ) -> PyResult<()> {
        let f = frame(arbitration_id, data, is_extended_id, is_remote_frame, dlc)?;
        self.request(Request::Send(f))
    }

    /// The frames the host's station received since the last call, as
    /// `recv` gives them, oldest first.
    fn received(&self, py: Python<'_>) -> PyResult<Vec<Received>> {
        self.ask(py, Request::Received)
    }

    /// Every frame the bus delivered so far: `(seconds, arbitration_id,
    /// is_extended_id, is_remote_frame, dlc, data)`, in bus order.
    fn log(&self, py: Python<'_>) -> PyResult<Vec<Logged>> {
        self.ask(py, Request::Log)
    }

    /// The frame log for analysis: with `columns=True` (the default) a
    /// dict of equal-length lists `time` (simulated seconds), `id`,
    /// `extended`, `remote`, `dlc`, `data` (bytes), which
    /// `pandas.DataFrame(...)` takes as it is; with `columns=False` a list
    /// of dicts with those keys, one per frame; with `numpy=True` a numpy
    /// structured array with those fields (`data` as 8 `uint8`, zero
    /// padded). Raises `ImportError` naming the package when numpy is
    /// asked for and not installed.
    #[pyo3(signature = (columns = true, numpy = false))]
    fn frame_log(&self, py: Python<'_>, columns: bool, numpy: bool) -> PyResult<Py<PyAny>> {
        let log = self.ask(py, Request::Log)?;
        if numpy {
            return numpy_log(py, &log);
        }
        if !columns {
            let rows = log
                .iter()
                .map(|(t, id, ext, rtr, dlc, data)| {
                    let d = PyDict::new(py);
                    d.set_item("time", t)?;
                    d.set_item("id", id)?;
                    d.set_item("extended", ext)?;
                    d.set_item("remote", rtr)?;
                    d.set_item("dlc", dlc)?;
                    d.set_item("data", PyBytes::new(py, data))?;
                    Ok(d)
                })
                .collect::<PyResult<Vec<_>>>()?;
            return rows.into_py_any(py);
        }
        let d = PyDict::new(py);
        d.set_item("time", log.iter().map(|e| e.0).collect::<Vec<_>>())?;
        d.set_item("id", log.iter().map(|e| e.1).collect::<Vec<_>>())?;
        d.set_item("extended", log.iter().map(|e| e.2).collect::<Vec<_>>())?;
        d.set_item("remote", log.iter().map(|e| e.3).collect::<Vec<_>>())?;
        d.set_item("dlc", log.iter().map(|e| e.4).collect::<Vec<_>>())?;
        d.set_item("data", log.iter().map(|e| PyBytes::new(py, &e.5)).collect::<Vec<_>>())?;
        d.into_py_any(py)
    }

    /// The log as candump lines (`(0.001234) can0 701#00`).
    fn log_lines(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        self.ask(py, Request::LogLines)
    }

    /// The drives' state now, in the order they were given.
    #[getter]
    pub(crate) fn drives(slf: &Bound<'_, Self>) -> PyResult<Vec<DriveState>> {
        let states = slf.get().ask(slf.py(), Request::Drives)?;
        Ok(states.into_iter().map(|s| s.owned_by(Owner::Sim(slf.clone().unbind()))).collect())
    }

    /// Sets machine input `input` of drive `node` to `value` now, as
    /// `drivebus control input` does to a running `serve` (see
    /// `VirtualBus.input`); it shows in the drive's objects at its next
    /// control period. Raises `ValueError` with the control interface's
    /// message, `OSError` when the drive is powered off.
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

    /// Starts machine fault `kind` of drive `node` now (`"clear"`: every
    /// machine fault that is on ends), as `drivebus control fault` (see
    /// `VirtualBus.fault`).
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

    /// Drive `node`'s CAN controller goes bus-off now (`drivebus control bus off`).
    fn bus_off(&self, py: Python<'_>, node: u8) -> PyResult<()> {
        self.act(py, node, Action::BusOff(true))
    }

    /// Drive `node` is back on the bus now (`drivebus control bus on`).
    fn bus_on(&self, py: Python<'_>, node: u8) -> PyResult<()> {
        self.act(py, node, Action::BusOff(false))
    }

    /// Cuts (`on=False`) or restores drive `node`'s power now (`drivebus
    /// control power`): off it is silent and its state is gone (it leaves
    /// `drives`); on it boots again from its machine.
    fn power(&self, py: Python<'_>, node: u8, on: bool) -> PyResult<()> {
        self.act(py, node, Action::Power(on))
    }

    /// The CANopen master on this bus (the `drivebus` tool's), whose calls
    /// run in simulated time: each returns when its work is done on the
    /// simulated bus, however long that took there.
    fn master(&self) -> Master {
        Master::new(self.link.clone(), &self.drives)
    }

    /// Advances simulated time in steps of `step` seconds until
    /// `predicate()` is true, and returns the simulated time then. Raises
    /// `TimeoutError` naming the simulated time reached when `timeout`
    /// seconds of simulated time pass first.
    #[pyo3(signature = (predicate, timeout, step = 0.001))]
    fn run_until(
        &self,
        py: Python<'_>,
        predicate: &Bound<'_, PyAny>,
        timeout: f64,
        step: f64,
    ) -> PyResult<f64> {
        if !(timeout.is_finite() && (0.0..=MAX_ADVANCE_S).contains(&timeout)) {
            return Err(PyValueError::new_err(format!(
                "timeout must be a number of seconds from 0 to {MAX_ADVANCE_S}, not {timeout}"
            )));
        }
        if !(step.is_finite() && step > 0.0 && step <= MAX_ADVANCE_S) {
            return Err(PyValueError::new_err(format!(
                "step must be a positive number of seconds up to {MAX_ADVANCE_S}, not {step}"
            )));
        }
        let start = self.now(py)?;
        let end = start + timeout;
        loop {
            if predicate.call0()?.is_truthy()? {
                return self.now(py);
            }
            let now = self.now(py)?;
            if now >= end {
                return Err(PyTimeoutError::new_err(format!(
                    "the condition was still false after {timeout} s of simulated time (simulated time {now:.6} s)"
                )));
            }
            let d = Duration::from_secs_f64(step.min(end - now).max(1e-9));
            self.ask(py, |done| Request::Advance(d, done))?;
        }
    }
}

impl Simulation {
    /// Carries out `action` on drive `node` now (the methods above and a
    /// drive's own, `DriveState.fault`, ...).
    pub(crate) fn act(&self, py: Python<'_>, node: u8, action: Action) -> PyResult<()> {
        self.link.run(py, move |s| s.apply(node, action))?
    }

    fn request(&self, r: Request) -> PyResult<()> {
        self.link.request(r)
    }

    fn ask<T: Send>(&self, py: Python<'_>, r: impl FnOnce(mpsc::Sender<T>) -> Request) -> PyResult<T> {
        self.link.ask(py, r)
    }
}

/// The bus thread ended (only a bug in a device makes it end early).
fn stopped() -> PyErr {
    PyRuntimeError::new_err("the simulation has stopped")
}

/// The log as a numpy structured array, or why not.
fn numpy_log(py: Python<'_>, log: &[Logged]) -> PyResult<Py<PyAny>> {
    let np = py.import("numpy").map_err(|e| {
        PyImportError::new_err(format!("frame_log(numpy=True) needs numpy ({e}): pip install numpy"))
    })?;
    let dtype = vec![
        ("time", "f8").into_py_any(py)?,
        ("id", "u4").into_py_any(py)?,
        ("extended", "?").into_py_any(py)?,
        ("remote", "?").into_py_any(py)?,
        ("dlc", "u1").into_py_any(py)?,
        ("data", "u1", (8,)).into_py_any(py)?,
    ];
    let rows = log
        .iter()
        .map(|(t, id, ext, rtr, dlc, data)| {
            // As numbers: a `Vec<u8>` would reach Python as bytes.
            let mut padded = [0u8; 8];
            padded[..data.len().min(8)].copy_from_slice(&data[..data.len().min(8)]);
            (*t, *id, *ext, *rtr, *dlc, padded.map(u16::from).to_vec()).into_py_any(py)
        })
        .collect::<PyResult<Vec<_>>>()?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", dtype)?;
    np.getattr("array")?.call((rows,), Some(&kwargs))?.into_py_any(py)
}

fn seconds(t: Instant) -> f64 {
    t.as_nanos() as f64 / 1e9
}
