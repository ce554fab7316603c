//! `VirtualBus`: a participant of a named in-process virtual CAN bus,
//! optionally hosting drive twins on it.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;

use drivebus_can::{CanId, Frame};
use drivebus_personality::machine::{Machine, MachineFile, MachineFileError};
use drivebus_personality::{PersonalityDevice, Profile};
use drivebus_transport::host::{self, DeviceHost};
use drivebus_transport::{CanRx, CanTx, Hub, TrySendError};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use tokio::sync::watch;

use crate::runtime;
use crate::state::DriveState;

/// A received frame: identifier, extended, remote, DLC, data.
pub(crate) type Received = (u32, bool, bool, u8, Vec<u8>);

/// One drive hosted in real time (by a `VirtualBus` or a `Server`).
pub(crate) struct Hosted {
    profile: Profile,
    node: u8,
    host: DeviceHost<PersonalityDevice>,
}

impl Hosted {
    /// Starts the drives `built` as participants of `hub` (inside the runtime).
    pub(crate) fn spawn_all(built: Vec<(Profile, u8, PersonalityDevice)>, hub: &Hub) -> Vec<Hosted> {
        built
            .into_iter()
            .map(|(profile, node, dev)| Hosted { profile, node, host: host::spawn(dev, hub.attach()) })
            .collect()
    }

    /// `akd:1`.
    pub(crate) fn spec(&self) -> String {
        format!("{}:{}", self.profile, self.node)
    }

    /// The drives' state, read now, with the GIL released.
    pub(crate) fn states(py: Python<'_>, drives: &[Hosted]) -> PyResult<Vec<DriveState>> {
        let rt = runtime()?;
        py.detach(|| {
            drives
                .iter()
                .map(|h| {
                    rt.block_on(h.host.with(|d, _| DriveState::of(d)))
                        .ok_or_else(|| PyOSError::new_err(format!("drive {} is not running", h.spec())))
                })
                .collect()
        })
    }

    /// Stops the drive (it falls silent, like a power cut).
    pub(crate) fn stop(&self) {
        self.host.stop();
    }
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
    drives: Vec<Hosted>,
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
        let drives = Hosted::spawn_all(built, &hub);
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
    fn drives(&self, py: Python<'_>) -> PyResult<Vec<DriveState>> {
        // Stopping a drive's task takes effect at its next await: a read
        // right after `close` could still be answered.
        self.check_open()?;
        Hosted::states(py, &self.drives)
    }

    /// Stops the hosted drives (they fall silent, like a power cut) and
    /// leaves the bus; a blocked `recv` returns with `OSError`. Closing
    /// twice is harmless.
    fn close(&self) {
        self.closed.send_replace(true);
        for h in &self.drives {
            h.stop();
        }
    }

    fn __repr__(&self) -> String {
        let drives: Vec<String> = self.drives.iter().map(Hosted::spec).collect();
        format!("VirtualBus(channel={:?}, drives={:?})", self.channel, drives)
    }
}

impl VirtualBus {
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
pub(crate) fn build_all(
    drives: &[String],
    machine_file: Option<&Path>,
) -> PyResult<Vec<(Profile, u8, PersonalityDevice)>> {
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
        built.push((profile, node, dev));
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
