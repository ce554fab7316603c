//! `drivebus.ethercat.serve(iface, drives)`: the EtherCAT slave line of
//! `drivebus ethercat serve --iface IFACE --drive ...` in this process,
//! built and served by the same library calls the CLI makes
//! (`described::devices`, `Host::line` on the real clock,
//! `server::RawSocket` and `server::serve_socket` on a thread of its own).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use drivebus_ethercat::described::{self, Member};
use drivebus_ethercat::server::{self, ServerStats};
use drivebus_ethercat::{Clock, Host, drive};
use pyo3::exceptions::{PyOSError, PyValueError};

use crate::control::{self, Action};
use pyo3::prelude::*;

/// A line of drive twins served on a network interface while it is open.
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct EthercatServer {
    iface: String,
    /// The line, shared with the server thread.
    host: Host,
    drives: Vec<String>,
    stop: Arc<AtomicBool>,
    thread: Mutex<Option<JoinHandle<std::io::Result<ServerStats>>>>,
}

/// The members and slaves of a line of `drives` (personalities with an EtherCAT face,
/// in line order); `ValueError` with the CLI's message for a bad name or
/// an empty list. The server and the simulation build their lines here.
pub(crate) fn line_devices(drives: &[String]) -> PyResult<(Vec<Member>, Vec<drivebus_ethercat::BoxDevice>)> {
    if drives.is_empty() {
        return Err(PyValueError::new_err("give at least one drive (drives=[\"ipos\"])"));
    }
    let members = drives
        .iter()
        .map(|p| drive::profile(p).map(Member::Drive).map_err(|e| PyValueError::new_err(e.to_string())))
        .collect::<PyResult<Vec<_>>>()?;
    let devices = described::devices(&members, None).map_err(PyValueError::new_err)?;
    Ok((members, devices))
}

#[pymethods]
impl EthercatServer {
    /// Serves `drives` (personalities with an EtherCAT face: `"ipos"`,
    /// `"generic"`, in line order) on `iface`, as `drivebus ethercat serve
    /// --iface IFACE --drive ...`. Raises `ValueError` with the CLI's
    /// message for a bad drive, `OSError` when the AF_PACKET socket cannot
    /// be opened (needs root or CAP_NET_RAW, and the interface up).
    #[new]
    #[pyo3(signature = (iface, drives = Vec::new()))]
    fn new(iface: &str, drives: Vec<String>) -> PyResult<EthercatServer> {
        let (members, devices) = line_devices(&drives)?;
        let host = Host::line(devices, Clock::real());
        // Bound before it returns: a master's first frame is not lost.
        let sock = server::RawSocket::open(iface).map_err(|e| {
            PyOSError::new_err(format!(
                "cannot open an AF_PACKET socket on {iface} (needs root or CAP_NET_RAW, and the interface up): {e}"
            ))
        })?;
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (stop, host) = (stop.clone(), host.clone());
            std::thread::Builder::new()
                .name("drivebus-ecat".into())
                .spawn(move || server::serve_socket(&sock, &host, &stop))
                .map_err(|e| PyOSError::new_err(format!("cannot start the EtherCAT server thread: {e}")))?
        };
        Ok(EthercatServer {
            iface: iface.to_owned(),
            host,
            drives: members.iter().map(name).collect(),
            stop,
            thread: Mutex::new(Some(thread)),
        })
    }

    /// The interface it serves on.
    #[getter]
    fn iface(&self) -> &str {
        &self.iface
    }

    /// The line's drives in order (`["ipos", "generic"]`).
    #[getter]
    fn drives(&self) -> Vec<String> {
        self.drives.clone()
    }

    /// True once `close()` was called.
    #[getter]
    fn closed(&self) -> bool {
        self.stop.load(Ordering::Acquire)
    }

    /// Stops serving (the line falls silent) and returns when the socket is
    /// closed; raises `OSError` when serving had failed. Closing twice is
    /// harmless.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        self.stop.store(true, Ordering::Release);
        let thread = self.thread.lock().ok().and_then(|mut t| t.take());
        let Some(thread) = thread else { return Ok(()) };
        let r = py.detach(|| thread.join());
        match r {
            Ok(Ok(_)) => Ok(()),
            Ok(Err(e)) => Err(PyOSError::new_err(format!("serving on {}: {e}", self.iface))),
            Err(_) => Err(PyOSError::new_err("the EtherCAT server thread panicked")),
        }
    }

    /// Sets a machine input of the drive at `slave` (its position from 1),
    /// as `drivebus control input` does to `drivebus ethercat serve`
    /// (see `VirtualBus.input`). Raises `ValueError` with the control
    /// interface's message, `OSError` when the slave is powered off.
    #[pyo3(signature = (slave, input, value, line = None, duration = None))]
    fn input(
        &self,
        slave: u8,
        input: &str,
        value: f64,
        line: Option<u8>,
        duration: Option<f64>,
    ) -> PyResult<()> {
        self.apply(slave, control::input(input, line, value, duration)?)
    }

    /// Starts (`"clear"`: ends) a machine fault of the drive at `slave`,
    /// as `drivebus control fault` (see `VirtualBus.fault`).
    #[pyo3(signature = (slave, kind, switch = None, duration = None))]
    fn fault(&self, slave: u8, kind: &str, switch: Option<&str>, duration: Option<f64>) -> PyResult<()> {
        self.apply(slave, control::fault(kind, switch, duration)?)
    }

    /// Cuts (`on=False`) or restores the power of the slave at `slave`, as
    /// `drivebus control power`: off it neither executes nor forwards
    /// frames; on, its ESC starts from its reset values in INIT.
    fn power(&self, slave: u8, on: bool) -> PyResult<()> {
        self.apply(slave, Action::Power(on))
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }

    fn __repr__(&self) -> String {
        format!("EthercatServer(iface={:?}, drives={:?})", self.iface, self.drives)
    }
}

impl EthercatServer {
    /// Carries out `action` on the slave at `slave` (from 1) between two
    /// frames, as the CLI's control interface does on a line.
    fn apply(&self, slave: u8, action: Action) -> PyResult<()> {
        let slaves = self.host.with_segment(|s| s.len());
        if slave == 0 || usize::from(slave) > slaves {
            return Err(PyValueError::new_err(format!(
                "no slave {slave} on the line: use 1..{slaves} (positions from 1, as drivebus ethercat scan lists them)"
            )));
        }
        let i = usize::from(slave) - 1;
        match action {
            Action::Power(on) => {
                self.host.with_segment(|s| if on { s.power_on(i) } else { s.power_off(i) });
                Ok(())
            }
            Action::BusOff(_) => Err(PyValueError::new_err(
                "an EtherCAT slave has no bus-off: cut its power (power(slave, False))",
            )),
            Action::Machine(change, duration) => {
                if !self.host.with_segment(|s| s.is_powered(i)) {
                    return Err(PyOSError::new_err(format!(
                        "slave {slave} is powered off: power it on first (power({slave}, True))"
                    )));
                }
                let now = self.host.clock().now();
                drive::with_drive(&self.host, i, |d| d.app_mut().change_machine(now, change, duration))
                    .ok_or_else(|| PyValueError::new_err(format!("slave {slave}: not a drive twin")))?
                    .map_err(|e| PyValueError::new_err(format!("slave {slave}: {e}")))
            }
        }
    }
}

impl Drop for EthercatServer {
    fn drop(&mut self) {
        // The thread sees it within its longest wait and ends.
        self.stop.store(true, Ordering::Release);
    }
}

/// The slave's name as the CLI's ready line gives it.
fn name(m: &Member) -> String {
    match m {
        Member::Drive(p) => p.to_string(),
        Member::Device(d) => d.type_name().to_owned(),
    }
}
