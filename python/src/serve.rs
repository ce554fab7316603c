//! `Server`: drives on a socketcand server inside the Python process (what
//! `drivebus serve` runs), for code that must reach them over TCP.

use std::path::PathBuf;
use std::sync::Mutex;

use drivebus_transport::socketcand::{SocketcandConfig, SocketcandServer};
use drivebus_transport::{Hub, HubConfig};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

use crate::bus::HostedDrives;
use crate::control::{self, Action};
use crate::runtime;
use crate::state::{DriveState, Owner};

/// A socketcand server hosting drive twins, running until `close()` (or
/// the end of its `with` block).
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct Server {
    url: String,
    port: u16,
    server: Mutex<Option<SocketcandServer>>,
    drives: HostedDrives,
}

#[pymethods]
impl Server {
    /// Listens on `host`:`port` (port 0: a free one) for socketcand clients
    /// of bus `channel` and starts `drives` on that bus, as `drivebus serve
    /// --listen HOST:PORT --channel CHANNEL --drive ... [--machine FILE]`
    /// does. Raises `ValueError` with the CLI's message for a bad drive,
    /// machine file or channel, `OSError` when it cannot listen.
    #[new]
    #[pyo3(signature = (drives = Vec::new(), machine = None, host = "127.0.0.1", port = 0, channel = "can0"))]
    fn new(
        py: Python<'_>,
        drives: Vec<String>,
        machine: Option<PathBuf>,
        host: &str,
        port: u16,
        channel: &str,
    ) -> PyResult<Server> {
        if channel.is_empty() || channel.contains(char::is_whitespace) || channel.contains(['<', '>']) {
            return Err(PyValueError::new_err(format!(
                "bad --channel `{channel}`: a bus name without spaces or angle brackets"
            )));
        }
        let built = crate::bus::build_all(&drives, machine.as_deref())?;
        let rt = runtime()?;
        let cfg = SocketcandConfig::new(channel);
        let (server, addr, drives) = py
            .detach(|| {
                rt.block_on(async {
                    // As `drivebus serve`: the hub, its listener, then the drives.
                    let hub = Hub::new(HubConfig::default());
                    let (server, addr) = SocketcandServer::bind_with((host, port), cfg, hub.clone()).await?;
                    Ok::<_, std::io::Error>((server, addr, HostedDrives::spawn_all(built, &hub)))
                })
            })
            .map_err(|e| PyOSError::new_err(format!("cannot listen on {host}:{port}: {e}")))?;
        Ok(Server {
            url: format!("socketcand://{addr}/{channel}"),
            port: addr.port(),
            server: Mutex::new(Some(server)),
            drives,
        })
    }

    /// `socketcand://HOST:PORT/CHANNEL`, as `drivebus --bus` and python-can's
    /// `socketcand` interface (`host`, `port`, `channel`) take it.
    #[getter]
    fn url(&self) -> &str {
        &self.url
    }

    /// The port it listens on.
    #[getter]
    fn port(&self) -> u16 {
        self.port
    }

    /// True once `close()` was called.
    #[getter]
    fn closed(&self) -> bool {
        self.server.lock().map_or(true, |s| s.is_none())
    }

    /// The hosted drives' state, read now, in the order they were given.
    /// Raises `OSError` once closed.
    #[getter]
    pub(crate) fn drives(slf: &Bound<'_, Self>) -> PyResult<Vec<DriveState>> {
        let server = slf.get();
        server.check_open()?;
        let states = server.drives.states(slf.py())?;
        Ok(states.into_iter().map(|s| s.owned_by(Owner::Server(slf.clone().unbind()))).collect())
    }

    /// Sets a machine input of drive `node` now, as `drivebus control
    /// input` does to a running `serve` (see `VirtualBus.input`).
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

    /// Starts (or with `"clear"` ends) a machine fault of drive `node`, as
    /// `drivebus control fault` (see `VirtualBus.fault`).
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

    /// Drive `node`'s CAN controller goes bus-off (`drivebus control bus off`).
    fn bus_off(&self, py: Python<'_>, node: u8) -> PyResult<()> {
        self.act(py, node, Action::BusOff(true))
    }

    /// Drive `node` is back on the bus (`drivebus control bus on`).
    fn bus_on(&self, py: Python<'_>, node: u8) -> PyResult<()> {
        self.act(py, node, Action::BusOff(false))
    }

    /// Cuts or restores drive `node`'s power (`drivebus control power`).
    fn power(&self, py: Python<'_>, node: u8, on: bool) -> PyResult<()> {
        self.act(py, node, Action::Power(on))
    }

    /// Stops the drives and the server; the port is closed when it returns
    /// (clients lose their connection). Closing twice is harmless.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        self.drives.stop();
        let server = self.server.lock().ok().and_then(|mut s| s.take());
        if let Some(server) = server {
            let rt = runtime()?;
            py.detach(|| rt.block_on(server.close()));
        }
        Ok(())
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
        let drives = self.drives.specs();
        format!("Server(url={:?}, drives={:?})", self.url, drives)
    }
}

impl Server {
    /// Carries out `action` on drive `node` (the methods above and a
    /// drive's own, `DriveState.fault`, ...).
    pub(crate) fn act(&self, py: Python<'_>, node: u8, action: Action) -> PyResult<()> {
        self.check_open()?;
        self.drives.apply(py, node, action)
    }

    fn check_open(&self) -> PyResult<()> {
        if self.closed() { Err(PyOSError::new_err("the socketcand server is closed")) } else { Ok(()) }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.drives.stop();
        // Dropping the server closes its listener on the runtime.
    }
}
