//! `drivebus.ethercat.Simulation`: the in-process EtherCAT line of
//! `drivebus demo --ethercat` with the same master, in simulated time.
//!
//! The line is `Host::line` of the drives `described::devices` builds (as
//! `drivebus ethercat serve` and `drivebus.ethercat.serve()`) on a
//! simulated `Clock`; the master is `drivebus_ethercat::master` (ethercrab)
//! on that host (`LineMaster::on_host`), its waits moving the host's time, so
//! a run depends only on the calls made. The master and the drive under
//! control (`CyclicDrive`, which borrows the master) live on a thread of
//! their own; the Python object hands it jobs and waits with the GIL
//! released. Dropping it ends that thread; ethercrab's link thread and
//! frame storage (about 18 kB) stay parked for the process, as in the CLI
//! (only the unsafe `MainDevice::release_all` would end them).

use std::io::Write;
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use drivebus_can::Instant;
use drivebus_ethercat::master::drive::{CyclicDrive, Feedback};
use drivebus_ethercat::master::{LineMaster, PduFrames, PreOpGroup, SlaveInfo, block_on};
use drivebus_ethercat::{Clock, Host};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::master::{DriveError, DrivebusError};

/// One cycle of the process-data log: simulated seconds, statusword,
/// position actual value (6064h), following error (60F4h, when mapped).
type Sample = (f64, u16, i32, Option<i32>);

/// The longest wait or timeout of one call: a day of simulated time.
const MAX_SECONDS: f64 = 86_400.0;

/// The master's side of the line, on its thread.
struct Line<'m> {
    m: &'m LineMaster,
    clock: Clock,
    /// The line as `scan` left it (PRE-OP), until `start` takes it to OP.
    group: Option<PreOpGroup>,
    /// The drive under control once the line is in OP.
    drive: Option<CyclicDrive<'m>>,
    log: Vec<Sample>,
}

impl<'m> Line<'m> {
    fn seconds(&self) -> f64 {
        self.clock.now().as_nanos() as f64 / 1e9
    }

    /// The drive under control and the log, or why there is none.
    fn op(&mut self) -> PyResult<(&mut CyclicDrive<'m>, Logger<'_>)> {
        let clock = &self.clock;
        match self.drive.as_mut() {
            Some(d) => Ok((d, Logger { clock, log: &mut self.log })),
            None => Err(DrivebusError::new_err("the line is not in OP: call start() first")),
        }
    }
}

/// Appends each cycle's feedback to the log.
struct Logger<'a> {
    clock: &'a Clock,
    log: &'a mut Vec<Sample>,
}

impl Logger<'_> {
    fn push(&mut self, fb: &Feedback) {
        let t = self.clock.now().as_nanos() as f64 / 1e9;
        self.log.push((t, fb.statusword, fb.position, fb.following));
    }
}

/// Work for the master's thread.
type Job = Box<dyn for<'m> FnOnce(&mut Line<'m>) + Send>;

/// The pcapng capture of every frame, shared with the host.
#[derive(Clone, Default)]
struct SharedCapture(Arc<Mutex<Vec<u8>>>);

impl Write for SharedCapture {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut v = self.0.lock().map_err(|_| std::io::Error::other("the capture is poisoned"))?;
        v.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// An EtherCAT line of drive twins and the `drivebus` master, in simulated
/// time (`drivebus.ethercat.Simulation`).
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct EthercatSimulation {
    to_line: Mutex<mpsc::Sender<Job>>,
    drives: Vec<String>,
    capture: Option<SharedCapture>,
}

fn drive_err(e: drivebus_ethercat::master::drive::CyclicDriveError) -> PyErr {
    DriveError::new_err(e.to_string())
}

fn master_err(e: drivebus_ethercat::master::MasterError) -> PyErr {
    DrivebusError::new_err(e.to_string())
}

/// `seconds` as a duration, or `ValueError` naming `what`.
fn duration(what: &str, seconds: f64) -> PyResult<Duration> {
    if seconds.is_finite() && seconds > 0.0 && seconds <= MAX_SECONDS {
        Ok(Duration::from_secs_f64(seconds))
    } else {
        Err(PyValueError::new_err(format!(
            "{what} must be a positive number of seconds up to {MAX_SECONDS}, not {seconds}"
        )))
    }
}

#[pymethods]
impl EthercatSimulation {
    /// Builds the line `drives` (personalities with an EtherCAT face:
    /// `"ipos"`, `"generic"`, in line order) on a simulated clock with the
    /// master on it. With `capture` every frame is recorded (`capture()`).
    /// Raises `ValueError` with the CLI's message for a bad drive.
    #[new]
    #[pyo3(signature = (drives = vec!["ipos".to_owned()], capture = true))]
    fn new(drives: Vec<String>, capture: bool) -> PyResult<EthercatSimulation> {
        let (_, devices) = crate::ethercat::line_devices(&drives)?;
        // As `drivebus demo --ethercat`: simulated time from 1 ms.
        let clock = Clock::simulated(Instant::from_millis(1));
        let host = Host::line(devices, clock.clone());
        let shared = capture.then(SharedCapture::default);
        if let Some(c) = &shared {
            host.set_capture(Box::new(c.clone()), "drivebus")
                .map_err(|e| PyRuntimeError::new_err(format!("cannot start the capture: {e}")))?;
        }
        let (to_line, jobs) = mpsc::channel::<Job>();
        let (ready, started) = mpsc::channel::<Result<(), String>>();
        std::thread::Builder::new()
            .name("drivebus-ecat-sim".into())
            .spawn(move || {
                // ethercrab splits its frame storage once: one per line,
                // kept for the process (16 frames of 1100 bytes).
                let storage: &'static PduFrames = Box::leak(Box::new(PduFrames::new()));
                let m = match LineMaster::on_host(storage, host) {
                    Ok(m) => m,
                    Err(e) => {
                        let _ = ready.send(Err(e.to_string()));
                        return;
                    }
                };
                let _ = ready.send(Ok(()));
                let mut line = Line { m: &m, clock, group: None, drive: None, log: Vec::new() };
                for job in jobs {
                    job(&mut line);
                }
            })
            .map_err(|e| {
                PyRuntimeError::new_err(format!("cannot start the EtherCAT simulation thread: {e}"))
            })?;
        started
            .recv()
            .map_err(|_| stopped())?
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start the master: {e}")))?;
        Ok(EthercatSimulation { to_line: Mutex::new(to_line), drives, capture: shared })
    }

    /// The line's drives in order (`["ipos"]`).
    #[getter]
    fn drives(&self) -> Vec<String> {
        self.drives.clone()
    }

    /// Simulated time in seconds.
    #[getter]
    fn now(&self, py: Python<'_>) -> PyResult<f64> {
        self.run(py, |l| l.seconds())
    }

    /// Scans the line (SII and 1018h over CoE, as `drivebus ethercat scan`)
    /// and leaves it in PRE-OP: one dict per slave with `position`, `name`,
    /// `vendor_id`, `product_code`, `revision`, `serial`,
    /// `coe_identity_matches`, `dc`. Raises `DrivebusError` if the line
    /// does not answer or is in OP already.
    fn scan(&self, py: Python<'_>) -> PyResult<Vec<Py<PyAny>>> {
        let found = self.run(py, |l| {
            if l.drive.is_some() {
                return Err(DrivebusError::new_err("the line is in OP: call stop() first"));
            }
            let (found, group) = block_on(l.m.scan_group()).map_err(master_err)?;
            l.group = Some(group);
            Ok(found)
        })??;
        found.iter().map(|s| slave_dict(py, s)).collect()
    }

    /// Brings the line to OP with the drive at line `position` (from 1)
    /// under control: process data every `cycle` seconds, DC SYNC0 at that
    /// period when `dc` and every slave supports it (else free run), as
    /// `drivebus ethercat drive` does. Scans first if `scan()` was not
    /// called. Raises `DrivebusError` / `DriveError` with the CLI's message.
    #[pyo3(signature = (position = 1, cycle = 0.001, dc = true))]
    fn start(&self, py: Python<'_>, position: usize, cycle: f64, dc: bool) -> PyResult<()> {
        let cycle = duration("cycle", cycle)?;
        if position == 0 || position > self.drives.len() {
            return Err(PyValueError::new_err(format!(
                "position must be 1..{} (the line's slaves), not {position}",
                self.drives.len()
            )));
        }
        self.run(py, move |l| {
            if l.drive.is_some() {
                return Err(DrivebusError::new_err("the line is in OP already"));
            }
            let group = match l.group.take() {
                Some(g) => g,
                None => block_on(l.m.scan_group()).map_err(master_err)?.1,
            };
            let d = block_on(CyclicDrive::start(l.m, group, position, cycle, dc, None)).map_err(drive_err)?;
            l.drive = Some(d);
            Ok(())
        })?
    }

    /// Whether the line is in OP with distributed clocks (SYNC0).
    #[getter]
    fn dc(&self, py: Python<'_>) -> PyResult<bool> {
        self.run(py, |l| l.drive.as_ref().is_some_and(|d| d.dc()))
    }

    /// Runs `n` process-data cycles with the outputs as they are; returns
    /// the last feedback `(statusword, position, following)`.
    #[pyo3(signature = (n = 1))]
    fn cycle(&self, py: Python<'_>, n: u64) -> PyResult<(u16, i32, Option<i32>)> {
        if n > 86_400_000 {
            return Err(PyValueError::new_err(format!("n must be at most 86400000 cycles, not {n}")));
        }
        self.run(py, move |l| {
            let (d, mut log) = l.op()?;
            for _ in 0..n {
                let fb = block_on(d.cycle()).map_err(drive_err)?;
                log.push(&fb);
            }
            Ok((d.fb.statusword, d.fb.position, d.fb.following))
        })?
    }

    /// Enables the drive (CiA 402 state machine to Operation enabled over
    /// the process data) within `timeout` seconds.
    #[pyo3(signature = (timeout = 2.0))]
    fn enable(&self, py: Python<'_>, timeout: f64) -> PyResult<()> {
        let t = duration("timeout", timeout)?;
        self.run(py, move |l| block_on(l.op()?.0.enable(t)).map_err(drive_err))?
    }

    /// Disables the drive (to Switch on disabled) within `timeout` seconds.
    #[pyo3(signature = (timeout = 2.0))]
    fn disable(&self, py: Python<'_>, timeout: f64) -> PyResult<()> {
        let t = duration("timeout", timeout)?;
        self.run(py, move |l| block_on(l.op()?.0.disable(t)).map_err(drive_err))?
    }

    /// Homes with `method` (6098h) in homing mode; returns the position
    /// when homing is attained. Raises `DriveError` on a fault, a homing
    /// error or a timeout, with the CLI's message.
    #[pyo3(signature = (method = 35, timeout = 10.0))]
    fn home(&self, py: Python<'_>, method: i8, timeout: f64) -> PyResult<i32> {
        let t = duration("timeout", timeout)?;
        self.run(py, move |l| {
            let (d, mut log) = l.op()?;
            block_on(d.home(method, t, |fb| log.push(fb))).map_err(drive_err)
        })?
    }

    /// A profile-position move to `target` (absolute, or `relative`), at
    /// `velocity` (6081h) if given; returns the position at target reached.
    #[pyo3(signature = (target, velocity = None, relative = false, timeout = 20.0))]
    fn move_to(
        &self,
        py: Python<'_>,
        target: i32,
        velocity: Option<u32>,
        relative: bool,
        timeout: f64,
    ) -> PyResult<i32> {
        let t = duration("timeout", timeout)?;
        self.run(py, move |l| {
            let (d, mut log) = l.op()?;
            block_on(d.move_to(target, relative, velocity, t, |fb| log.push(fb))).map_err(drive_err)
        })?
    }

    /// Cyclic synchronous position: one of `targets` per cycle; returns
    /// the cycles run.
    fn csp(&self, py: Python<'_>, targets: Vec<i32>) -> PyResult<u64> {
        self.run(py, move |l| {
            let (d, mut log) = l.op()?;
            block_on(d.csp(targets, |_, fb| log.push(fb))).map_err(drive_err)
        })?
    }

    /// Reads object `index`:`sub` of the drive under control over CoE
    /// (SDO upload), as a signed integer.
    fn sdo_read(&self, py: Python<'_>, index: u16, sub: u8) -> PyResult<i64> {
        self.run(py, move |l| block_on(l.op()?.0.read(index, sub)).map_err(drive_err))?
    }

    /// Writes `data` (little-endian bytes) to object `index`:`sub` of the
    /// drive under control over CoE (SDO download).
    fn sdo_write(&self, py: Python<'_>, index: u16, sub: u8, data: Vec<u8>) -> PyResult<()> {
        self.run(py, move |l| block_on(l.op()?.0.write(index, sub, &data)).map_err(drive_err))?
    }

    /// Leaves OP for SAFE-OP (the drive reacts as its 6007h says); `scan()`
    /// or `start()` begin again.
    fn stop(&self, py: Python<'_>) -> PyResult<()> {
        self.run(py, |l| match l.drive.take() {
            Some(d) => block_on(d.stop()).map_err(drive_err),
            None => Err(DrivebusError::new_err("the line is not in OP")),
        })?
    }

    /// Counters of the cyclic exchange: `(cycles, bad_wkc, lost)`.
    fn counters(&self, py: Python<'_>) -> PyResult<(u64, u64, u64)> {
        self.run(py, |l| l.drive.as_ref().map_or((0, 0, 0), |d| (d.cycles, d.bad_wkc, d.lost)))
    }

    /// The process-data log: one `(seconds, statusword, position,
    /// following)` per cycle of `cycle`, `home`, `move_to` and `csp`
    /// (`following` is `None` where 60F4h is not mapped).
    fn log(&self, py: Python<'_>) -> PyResult<Vec<Sample>> {
        self.run(py, |l| l.log.clone())
    }

    /// Every frame so far as pcapng bytes (Wireshark opens them; simulated
    /// timestamps from 2000-01-01), `None` when built with `capture=False`.
    fn capture<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyBytes>>> {
        let Some(c) = &self.capture else { return Ok(None) };
        let bytes = c.0.lock().map_err(|_| PyRuntimeError::new_err("the capture is poisoned"))?.clone();
        Ok(Some(PyBytes::new(py, &bytes)))
    }

    fn __repr__(&self) -> String {
        format!("drivebus.ethercat.Simulation(drives={:?})", self.drives)
    }
}

impl EthercatSimulation {
    /// Runs `f` on the master's thread and waits, the GIL released.
    fn run<T: Send + 'static>(
        &self,
        py: Python<'_>,
        f: impl for<'m> FnOnce(&mut Line<'m>) -> T + Send + 'static,
    ) -> PyResult<T> {
        let (tx, rx) = mpsc::channel();
        let job: Job = Box::new(move |l| {
            let _ = tx.send(f(l));
        });
        self.to_line.lock().map_err(|_| stopped())?.send(job).map_err(|_| stopped())?;
        py.detach(move || rx.recv()).map_err(|_| stopped())
    }
}

/// The master's thread ended (only a bug makes it end early).
fn stopped() -> PyErr {
    PyRuntimeError::new_err("the EtherCAT simulation has stopped")
}

/// A slave of `scan` as a dict.
fn slave_dict(py: Python<'_>, s: &SlaveInfo) -> PyResult<Py<PyAny>> {
    let d = pyo3::types::PyDict::new(py);
    d.set_item("position", s.position)?;
    d.set_item("name", &s.name)?;
    d.set_item("vendor_id", s.identity[0])?;
    d.set_item("product_code", s.identity[1])?;
    d.set_item("revision", s.identity[2])?;
    d.set_item("serial", s.identity[3])?;
    d.set_item("coe_identity_matches", s.coe_identity == Some(s.identity))?;
    d.set_item("dc", s.dc)?;
    Ok(d.into_any().unbind())
}
