//! `Simulation`: drive twins on the virtual bus in simulated time
//! (`drivebus_bus::Bus`), as fast as the CPU allows and deterministic.
//!
//! The bus (its devices are not `Send`) lives on a thread of its own; the
//! Python object sends it requests and waits for the answers with the GIL
//! released, so any Python thread may use a `Simulation`, one call at a
//! time, and others run meanwhile.

use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::mpsc;
use std::time::Duration;

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Frame, Instant};
use drivebus_personality::PersonalityDevice;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::bus::{Received, frame, received};
use crate::state::DriveState;

/// One frame of the log: simulated time in seconds, then as `recv`.
type Logged = (f64, u32, bool, bool, u8, Vec<u8>);

/// The longest `advance` in one call: a year of simulated time.
const MAX_ADVANCE_S: f64 = 365.0 * 86_400.0;

/// Drive twins on a virtual CAN bus in simulated time. Nothing moves
/// between calls: `advance(seconds)` runs the bus and the drives; the same
/// calls give the same frame log, byte for byte.
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct Simulation {
    to_bus: Mutex<mpsc::Sender<Request>>,
}

/// What the bus thread is asked to do.
enum Request {
    Advance(Duration, mpsc::Sender<()>),
    Send(Frame),
    Received(mpsc::Sender<Vec<Received>>),
    Log(mpsc::Sender<Vec<Logged>>),
    LogLines(mpsc::Sender<Vec<String>>),
    Drives(mpsc::Sender<Vec<DriveState>>),
    Now(mpsc::Sender<f64>),
}

/// The bus and the host's station, on the bus thread.
struct Sim {
    bus: Bus,
    probe: ProbeId,
    drives: Vec<NodeId>,
}

impl Sim {
    /// Answers requests until the `Simulation` is dropped.
    fn serve(mut self, requests: mpsc::Receiver<Request>) {
        // A send fails only when the caller gave up waiting: nothing to do.
        for r in requests {
            match r {
                Request::Advance(d, done) => {
                    self.bus.run_for(d);
                    let _ = done.send(());
                }
                Request::Send(f) => {
                    self.bus.send_from(self.probe, f);
                }
                Request::Received(out) => {
                    let _ = out.send(self.bus.take_received(self.probe).iter().map(received).collect());
                }
                Request::Log(out) => {
                    let log = self.bus.log().iter().map(|e| {
                        let (id, ext, rtr, dlc, data) = received(&e.frame);
                        (seconds(e.time), id, ext, rtr, dlc, data)
                    });
                    let _ = out.send(log.collect());
                }
                Request::LogLines(out) => {
                    let _ = out.send(self.bus.log_lines());
                }
                Request::Drives(out) => {
                    let drives = self.drives.iter().filter_map(|&id| self.bus.node::<PersonalityDevice>(id));
                    let _ = out.send(drives.map(DriveState::of).collect());
                }
                Request::Now(out) => {
                    let _ = out.send(seconds(self.bus.now()));
                }
            }
        }
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
        let built: Vec<_> =
            crate::bus::build_all(&drives, machine.as_deref())?.into_iter().map(|(_, _, d)| d).collect();
        let (to_bus, requests) = mpsc::channel();
        std::thread::Builder::new()
            .name("drivebus-sim".into())
            .spawn(move || {
                let mut bus = Bus::new(BusConfig { bitrate, ..BusConfig::default() });
                // The host's station, before the drives: it hears their boot-ups.
                let probe = bus.attach_probe();
                let drives = built.into_iter().map(|d| bus.attach(d)).collect();
                Sim { bus, probe, drives }.serve(requests);
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start the simulation thread: {e}")))?;
        Ok(Simulation { to_bus: Mutex::new(to_bus) })
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

    /// The log as candump lines (`(0.001234) can0 701#00`).
    fn log_lines(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        self.ask(py, Request::LogLines)
    }

    /// The drives' state now, in the order they were given.
    #[getter]
    fn drives(&self, py: Python<'_>) -> PyResult<Vec<DriveState>> {
        self.ask(py, Request::Drives)
    }
}

impl Simulation {
    /// Hands `r` to the bus thread.
    fn request(&self, r: Request) -> PyResult<()> {
        let to_bus = self.to_bus.lock().map_err(|_| stopped())?;
        to_bus.send(r).map_err(|_| stopped())
    }

    /// Asks the bus thread and waits for the answer, the GIL released.
    fn ask<T: Send>(&self, py: Python<'_>, r: impl FnOnce(mpsc::Sender<T>) -> Request) -> PyResult<T> {
        let (tx, rx) = mpsc::channel();
        self.request(r(tx))?;
        py.detach(move || rx.recv()).map_err(|_| stopped())
    }
}

/// The bus thread ended (only a bug in a device makes it end early).
fn stopped() -> PyErr {
    PyRuntimeError::new_err("the simulation has stopped")
}

fn seconds(t: Instant) -> f64 {
    t.as_nanos() as f64 / 1e9
}
