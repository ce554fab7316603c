//! `sim.master()`: the master of `drivebus_master` (the `drivebus` tool's)
//! on a `Simulation`'s bus, its procedures run in simulated time
//! (`SimBus::block_on`). Objects are named as the tool names them
//! (`drivebus_master::dict`: hex or CiA 301/402 names, and each hosted
//! drive's EDS); errors carry the tool's messages.

use std::future::Future;
use std::sync::Arc;
use std::time::Duration;

use drivebus_master::dict::Dict;
use drivebus_master::drive::mode;
use drivebus_master::{
    DataType, DriveError as RustDriveError, Master as RustMaster, MotionReport, NmtCommand, ScanOptions,
    SdoError as RustSdoError, SdoFailure, Stalled, Value,
};
use drivebus_personality::Profile;
use pyo3::IntoPyObjectExt;
use pyo3::exceptions::{PyTimeoutError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::lss::Lss;
use crate::pdo::Pdos;
use crate::sim::{Link, Sim};

pyo3::create_exception!(
    drivebus,
    DrivebusError,
    pyo3::exceptions::PyException,
    "A CANopen operation failed on the bus."
);
pyo3::create_exception!(
    drivebus,
    SdoError,
    DrivebusError,
    "An SDO transfer failed (aborted by the device, timed out, ...), with the `drivebus sdo` message."
);
pyo3::create_exception!(
    drivebus,
    DriveError,
    DrivebusError,
    "A CiA 402 drive command failed (fault, a move stopped short, a timeout), with the `drivebus drive` message."
);

/// Registers the exception types on the module.
pub(crate) fn add_exceptions(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("DrivebusError", py.get_type::<DrivebusError>())?;
    m.add("SdoError", py.get_type::<SdoError>())?;
    m.add("DriveError", py.get_type::<DriveError>())?;
    Ok(())
}

/// The longest a single master call may take in simulated time.
const MAX_SECONDS: f64 = 365.0 * 86_400.0;

/// The CANopen master on a `Simulation`'s bus (`sim.master()`).
#[pyclass(frozen, module = "drivebus._drivebus")]
#[derive(Clone)]
pub struct Master {
    link: Arc<Link>,
    /// How each hosted drive names its objects (its EDS, then CiA 301/402).
    dicts: Arc<Vec<(u8, Dict)>>,
    /// Names of nodes without a hosted drive: the standard objects.
    standard: Arc<Dict>,
}

impl Master {
    /// The master of the simulation behind `link`, hosting `drives`.
    pub(crate) fn new(link: Arc<Link>, drives: &[(u8, Profile)]) -> Master {
        let dicts = drives.iter().map(|(n, p)| (*n, Dict { eds: Some(p.eds().eds.clone()) })).collect();
        Master { link, dicts: Arc::new(dicts), standard: Arc::new(Dict::default()) }
    }

    /// How node `node` names its objects.
    pub(crate) fn dict(&self, node: u8) -> &Dict {
        self.dicts.iter().find(|(n, _)| *n == node).map_or(&*self.standard, |(_, d)| d)
    }

    /// Runs the master future `f` in simulated time on the bus thread.
    pub(crate) fn block_on<T, F>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(RustMaster) -> F + Send + 'static,
    ) -> PyResult<T>
    where
        T: Send + 'static,
        F: Future<Output = T>,
    {
        let r = self.link.run(py, move |s: &mut Sim| {
            let m = s.sim.master().clone();
            s.sim.block_on(f(m))
        })?;
        r.map_err(stalled)
    }
}

/// A node-ID of a command to one node.
pub(crate) fn node_id(node: i64) -> PyResult<u8> {
    u8::try_from(node)
        .ok()
        .filter(|n| (1..=127).contains(n))
        .ok_or_else(|| PyValueError::new_err(format!("node-ID `{node}` is not in 1..127")))
}

/// An object or sub-index as the user gave it: text as the tool takes it,
/// a number as hex text.
fn object_text(o: &Bound<'_, PyAny>, what: &str) -> PyResult<String> {
    if let Ok(n) = o.extract::<i64>() {
        return Ok(if n < 0 { n.to_string() } else { format!("0x{n:X}") });
    }
    o.extract::<String>().map_err(|_| PyValueError::new_err(format!("{what} must be an int or a str")))
}

fn seconds(what: &str, s: f64) -> PyResult<Duration> {
    if s.is_finite() && (0.0..=MAX_SECONDS).contains(&s) {
        Ok(Duration::from_secs_f64(s))
    } else {
        Err(PyValueError::new_err(format!("{what}: give a number of seconds from 0 to a year, not {s}")))
    }
}

fn data_type(t: Option<&str>) -> PyResult<Option<DataType>> {
    t.map(|t| {
        DataType::from_name(t).ok_or_else(|| {
            PyValueError::new_err(format!("unknown type `{t}` (use u8, u16, u32, u64, i8, i16, i32, i64, f32, f64, bool, str, bytes or a CiA name like UNSIGNED16)"))
        })
    })
    .transpose()
}

fn stalled(e: Stalled) -> PyErr {
    PyTimeoutError::new_err(e.to_string())
}

/// An SDO failure with the tool's message.
pub(crate) fn sdo_error(
    node: u8,
    index: u16,
    sub: u8,
    write: bool,
    timeout: Duration,
) -> impl FnOnce(RustSdoError) -> PyErr {
    move |error| SdoError::new_err(SdoFailure { node, index, sub, write, error, timeout }.to_string())
}

fn drive_error(node: u8) -> impl Fn(RustDriveError) -> PyErr {
    move |e| match e {
        RustDriveError::Sdo(e) => SdoError::new_err(format!("node {node}: {e}")),
        e => DriveError::new_err(format!("node {node}: {e}")),
    }
}

/// A value as Python gets it.
fn to_py(py: Python<'_>, v: Value) -> PyResult<Py<PyAny>> {
    match v {
        Value::Bool(b) => b.into_py_any(py),
        Value::I8(x) => x.into_py_any(py),
        Value::I16(x) => x.into_py_any(py),
        Value::I32(x) => x.into_py_any(py),
        Value::I64(x) => x.into_py_any(py),
        Value::U8(x) => x.into_py_any(py),
        Value::U16(x) => x.into_py_any(py),
        Value::U32(x) => x.into_py_any(py),
        Value::U64(x) => x.into_py_any(py),
        Value::F32(x) => f64::from(x).into_py_any(py),
        Value::F64(x) => x.into_py_any(py),
        Value::Str(s) => s.into_py_any(py),
        Value::Bytes(b) => pyo3::types::PyBytes::new(py, &b).into_py_any(py),
        Value::Unicode(u) => String::from_utf16_lossy(&u).into_py_any(py),
        Value::Time { ms, days } => (ms, days).into_py_any(py),
    }
}

/// How a motion ended, as a dict.
fn report(py: Python<'_>, r: &MotionReport) -> PyResult<Py<PyAny>> {
    let d = PyDict::new(py);
    d.set_item("end", r.end.code())?;
    d.set_item("position", r.position)?;
    d.set_item("target", r.target)?;
    d.set_item("statusword", r.statusword)?;
    d.set_item("duration", r.duration.as_secs_f64())?;
    d.into_py_any(py)
}

#[pymethods]
impl Master {
    /// Active scan of node-IDs 1..127 (`drivebus scan`): SDO upload of
    /// 1000h from each, then 1018h from those that answered. A list of
    /// dicts `node`, `device_type`, `vendor_id`, `product_code`,
    /// `revision`, `serial` (the identity parts `None` when 1018h was not
    /// readable), sorted by node-ID.
    #[pyo3(signature = (timeout = 0.1))]
    fn scan(&self, py: Python<'_>, timeout: f64) -> PyResult<Vec<Py<PyAny>>> {
        let timeout = seconds("timeout", timeout)?;
        let found = self.block_on(py, move |m| async move {
            m.scan_with(ScanOptions { timeout, ..ScanOptions::default() }).await
        })?;
        found
            .into_iter()
            .map(|n| {
                let d = PyDict::new(py);
                d.set_item("node", n.node)?;
                d.set_item("device_type", n.device_type)?;
                d.set_item("vendor_id", n.identity.map(|i| i.vendor_id))?;
                d.set_item("product_code", n.identity.map(|i| i.product_code))?;
                d.set_item("revision", n.identity.map(|i| i.revision))?;
                d.set_item("serial", n.identity.map(|i| i.serial))?;
                d.into_py_any(py)
            })
            .collect()
    }

    /// Reads an object (`drivebus sdo read`): `index` as an int, or as the
    /// tool takes it (`"6041"`, `"1018:01"`, `"statusword"`,
    /// `"identity/vendor-id"`, a name of the drive's EDS); `sub` an int or
    /// hex text. Decoded by `type` (`"u16"`, ...), else by the EDS or
    /// standard type; `bytes` when the type is unknown. A record or array
    /// without a sub-index reads as a dict of its entries. Raises
    /// `SdoError` with the tool's message.
    #[pyo3(signature = (node, index, sub = None, *, r#type = None))]
    fn sdo_read(
        &self,
        py: Python<'_>,
        node: i64,
        index: &Bound<'_, PyAny>,
        sub: Option<&Bound<'_, PyAny>>,
        r#type: Option<&str>,
    ) -> PyResult<Py<PyAny>> {
        let node = node_id(node)?;
        let forced = data_type(r#type)?;
        let dict = self.dict(node);
        let (index, sub) = resolve(dict, index, sub)?;
        let subs: Option<Vec<u8>> = match sub {
            Some(s) => Some(vec![s]),
            None => dict.entries(index),
        };
        let timeout = sdo_timeout();
        let Some(all) = subs else {
            let data = self.upload(py, node, index, 0, timeout)?;
            return decode(py, node, index, 0, forced.or_else(|| dict.data_type(index, 0)), data);
        };
        if sub.is_some() {
            let s = all[0];
            let data = self.upload(py, node, index, s, timeout)?;
            return decode(py, node, index, s, forced.or_else(|| dict.data_type(index, s)), data);
        }
        // A whole record/array: sub 0 says how many entries exist.
        let count = self.upload(py, node, index, 0, timeout)?.first().copied().unwrap_or(0);
        let out = PyDict::new(py);
        for s in all.into_iter().filter(|&s| s <= count) {
            let data = match self.upload(py, node, index, s, timeout) {
                // A record may skip sub-indices.
                Err(e) if s > 0 && e.is_instance_of::<SdoError>(py) => continue,
                r => r?,
            };
            out.set_item(s, decode(py, node, index, s, forced.or_else(|| dict.data_type(index, s)), data)?)?;
        }
        out.into_py_any(py)
    }

    /// Writes an object (`drivebus sdo write OBJECT [SUB] VALUE`):
    /// `sdo_write(node, index, value)` or `sdo_write(node, index, sub,
    /// value)`, the object as `sdo_read` takes it; the value encoded by
    /// `type`, else the EDS or standard type (`bytes` are written as they
    /// are). Raises `SdoError` with the tool's message.
    #[pyo3(signature = (node, index, *args, r#type = None))]
    fn sdo_write(
        &self,
        py: Python<'_>,
        node: i64,
        index: &Bound<'_, PyAny>,
        args: &Bound<'_, PyTuple>,
        r#type: Option<&str>,
    ) -> PyResult<()> {
        let node = node_id(node)?;
        let (sub, value) = match args.len() {
            1 => (None, args.get_item(0)?),
            2 => (Some(args.get_item(0)?), args.get_item(1)?),
            _ => return Err(PyValueError::new_err("give OBJECT [SUB] VALUE")),
        };
        let dict = self.dict(node);
        let (index, sub) = resolve(dict, index, sub.as_ref())?;
        let sub = sub.unwrap_or(0);
        let forced = data_type(r#type)?;
        let bytes = if let Ok(b) = value.cast::<pyo3::types::PyBytes>() {
            b.as_bytes().to_vec()
        } else {
            let dt = forced.or_else(|| dict.data_type(index, sub)).ok_or_else(|| {
                PyValueError::new_err(format!("the data type of {index:04X}h:{sub:02X} is unknown: give type= (u8, u16, u32, i32, str, ...)"))
            })?;
            let text = if value.is_instance_of::<pyo3::types::PyBool>() {
                if value.is_truthy()? { "1".to_owned() } else { "0".to_owned() }
            } else {
                value.str()?.to_string()
            };
            let v = Value::parse(dt, &text)
                .map_err(|e| PyValueError::new_err(format!("bad value `{text}`: {e}")))?;
            v.encode(dt).map_err(|e| {
                PyValueError::new_err(format!("value `{text}` does not fit {}: {e}", dt.name()))
            })?
        };
        let timeout = sdo_timeout();
        let r = self.block_on(py, move |m| async move { m.sdo(node).download(index, sub, &bytes).await })?;
        r.map_err(sdo_error(node, index, sub, true, timeout))
    }

    /// Sends an NMT command (`drivebus nmt`): `start`, `stop`, `preop`,
    /// `reset`, `reset-comm` to `node` (0: all nodes). A reset returns once
    /// the node's boot-up came; the others once the command reached the bus.
    fn nmt(&self, py: Python<'_>, node: i64, command: &str) -> PyResult<()> {
        let target = u8::try_from(node).ok().filter(|n| *n <= 127).ok_or_else(|| {
            PyValueError::new_err(format!("node-ID `{node}` is not in 0..127 (0: all nodes)"))
        })?;
        let cmd = match command {
            "start" => NmtCommand::Start,
            "stop" => NmtCommand::Stop,
            "preop" => NmtCommand::EnterPreOperational,
            "reset" => NmtCommand::ResetNode,
            "reset-comm" => NmtCommand::ResetCommunication,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "invalid NMT command `{command}` [possible values: start, stop, preop, reset, reset-comm]"
                )));
            }
        };
        let boot_wait = Duration::from_millis(500);
        let r = self.block_on(py, move |m| async move {
            match cmd {
                NmtCommand::ResetNode if target != 0 => {
                    m.reset_node(target, boot_wait).await.map_err(|e| e.to_string())
                }
                NmtCommand::ResetCommunication if target != 0 => {
                    m.reset_communication(target, boot_wait).await.map_err(|e| e.to_string())
                }
                _ => {
                    m.nmt(target, cmd).await.map_err(|e| e.to_string())?;
                    // On the bus and taken by the node: a frame takes well under 1 ms.
                    m.sleep(Duration::from_millis(1)).await;
                    Ok(())
                }
            }
        })?;
        r.map_err(|e| DrivebusError::new_err(format!("node {target}: {e}")))
    }

    /// The CiA 402 drive at `node` (`drivebus drive`).
    fn drive(&self, node: i64) -> PyResult<Drive> {
        Ok(Drive { master: self.clone(), node: node_id(node)? })
    }

    /// PDO configuration (`drivebus pdo show|map`): `pdo.read`,
    /// `pdo.show`, `pdo.map`.
    #[getter]
    fn pdo(&self) -> Pdos {
        Pdos { master: self.clone() }
    }

    /// The LSS services (`drivebus lss`), each answer awaited 100 ms of
    /// simulated time (the tool's default).
    #[getter]
    fn lss(&self) -> Lss {
        Lss { master: self.clone(), timeout: Duration::from_millis(100) }
    }

    /// Starts producing SYNC every `period` seconds of simulated time
    /// (`counter`: the counter overflow value, 0 for SYNC without a
    /// counter), as `drivebus sync` does.
    #[pyo3(signature = (period = 0.001, counter = 0))]
    fn start_sync(&self, py: Python<'_>, period: f64, counter: u8) -> PyResult<()> {
        let p = seconds("period", period)?;
        if p < Duration::from_micros(100) {
            return Err(PyValueError::new_err(format!("period: at least 0.0001 s, not {period}")));
        }
        self.block_on(py, move |m| async move { m.start_sync(p, counter) })
    }

    /// Stops producing SYNC.
    fn stop_sync(&self, py: Python<'_>) -> PyResult<()> {
        self.block_on(py, |m| async move { m.stop_sync() })
    }

    /// Reads `index`/`sub` of `node` by SDO every `period` seconds for
    /// `seconds` of simulated time: `(times, values)`, the simulated time
    /// of each reading and its value (decoded as `sdo_read` does). The
    /// readings' SDO frames are on the bus like any other.
    #[pyo3(signature = (node, index, sub = None, *, seconds = 1.0, period = 0.01))]
    fn sample(
        &self,
        py: Python<'_>,
        node: i64,
        index: &Bound<'_, PyAny>,
        sub: Option<&Bound<'_, PyAny>>,
        seconds: f64,
        period: f64,
    ) -> PyResult<(Vec<f64>, Vec<Py<PyAny>>)> {
        let node = node_id(node)?;
        let total = self::seconds("seconds", seconds)?;
        let step = self::seconds("period", period)?;
        if step.is_zero() {
            return Err(PyValueError::new_err("period must be above 0 seconds"));
        }
        let dict = self.dict(node);
        let (index, sub) = resolve(dict, index, sub)?;
        let sub = sub.unwrap_or(0);
        let dt = dict.data_type(index, sub);
        let got = self.block_on(py, move |m| async move {
            let end = m.now() + total;
            let mut out = Vec::new();
            loop {
                let at = m.now();
                let r = m.sdo(node).upload(index, sub).await;
                out.push((at.as_nanos() as f64 / 1e9, r));
                if m.now() + step > end {
                    return out;
                }
                m.sleep(step.saturating_sub(m.now().saturating_duration_since(at))).await;
            }
        })?;
        let timeout = sdo_timeout();
        let mut times = Vec::with_capacity(got.len());
        let mut values = Vec::with_capacity(got.len());
        for (t, r) in got {
            let data = r.map_err(sdo_error(node, index, sub, false, timeout))?;
            times.push(t);
            values.push(decode(py, node, index, sub, dt, data)?);
        }
        Ok((times, values))
    }
}

impl Master {
    fn upload(&self, py: Python<'_>, node: u8, index: u16, sub: u8, timeout: Duration) -> PyResult<Vec<u8>> {
        let r = self.block_on(py, move |m| async move { m.sdo(node).upload(index, sub).await })?;
        r.map_err(sdo_error(node, index, sub, false, timeout))
    }
}

/// The SDO timeout of the simulation's master (`MasterConfig::default`).
pub(crate) fn sdo_timeout() -> Duration {
    drivebus_master::MasterConfig::default().sdo_timeout
}

fn resolve(
    dict: &Dict,
    index: &Bound<'_, PyAny>,
    sub: Option<&Bound<'_, PyAny>>,
) -> PyResult<(u16, Option<u8>)> {
    let o = object_text(index, "index")?;
    let s = sub.filter(|s| !s.is_none()).map(|s| object_text(s, "sub")).transpose()?;
    dict.resolve(&o, s.as_deref()).map_err(|e| PyValueError::new_err(e.to_string()))
}

fn decode(
    py: Python<'_>,
    node: u8,
    index: u16,
    sub: u8,
    dt: Option<DataType>,
    data: Vec<u8>,
) -> PyResult<Py<PyAny>> {
    match dt {
        None => pyo3::types::PyBytes::new(py, &data).into_py_any(py),
        Some(dt) => {
            let v = Value::decode(dt, &data).map_err(|e| {
                SdoError::new_err(format!(
                    "node {node}: {index:04X}h:{sub:02X}: {} bytes do not decode as {}: {e}",
                    data.len(),
                    dt.name()
                ))
            })?;
            to_py(py, v)
        }
    }
}

/// A CiA 402 drive of a simulation (`master.drive(node)`): each call runs
/// the master's procedure (the `drivebus drive` command's) in simulated time.
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct Drive {
    master: Master,
    node: u8,
}

impl Drive {
    /// Runs `f` on this node's drive handle.
    fn run<T, F>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(drivebus_master::RemoteDrive) -> F + Send + 'static,
    ) -> PyResult<T>
    where
        T: Send + 'static,
        F: Future<Output = Result<T, RustDriveError>>,
    {
        let node = self.node;
        let r = self.master.block_on(py, move |m| async move {
            let d = m.drive(node).await?;
            f(d).await
        })?;
        r.map_err(drive_error(node))
    }
}

#[pymethods]
impl Drive {
    /// The node-ID.
    #[getter]
    fn node(&self) -> u8 {
        self.node
    }

    /// The CiA 402 state from the statusword (`"operation enabled"`, ...).
    #[getter]
    fn state(&self, py: Python<'_>) -> PyResult<String> {
        self.run(py, |d| async move { d.state().await.map(|s| s.name().to_owned()) })
    }

    /// 6064h, the position actual value (`None` when unreadable).
    #[getter]
    fn position(&self, py: Python<'_>) -> PyResult<Option<i32>> {
        self.run(py, |d| async move { Ok(d.position().await) })
    }

    /// Brings the drive to operation enabled (fault reset first when
    /// faulted), as `drivebus drive enable`. Raises `DriveError`.
    fn enable(&self, py: Python<'_>) -> PyResult<()> {
        self.run(py, |d| async move { d.enable().await })
    }

    /// Operation disabled (ready to switch on).
    fn disable(&self, py: Python<'_>) -> PyResult<()> {
        self.run(py, |d| async move { d.disable().await })
    }

    /// Homing with `method` (default: the drive's 6098h), as `drivebus
    /// drive home`; waits up to `timeout` seconds of simulated time.
    /// Returns the report (`end`, `position`, `target`, `statusword`,
    /// `duration` in simulated seconds); raises `DriveError` when homing
    /// did not attain.
    #[pyo3(signature = (method = None, timeout = 60.0))]
    fn home(&self, py: Python<'_>, method: Option<i8>, timeout: f64) -> PyResult<Py<PyAny>> {
        let wait = seconds("timeout", timeout)?.max(Duration::from_millis(10));
        let r = self.run(py, move |d| async move {
            let method = match method {
                Some(m) => m,
                None => d.read_raw(0x6098, 0).await?.first().map_or(0, |b| *b as i8),
            };
            d.home(method, wait).await
        })?;
        report(py, &r)
    }

    /// A profile-position move to `position` (relative to where the axis
    /// is with `relative=True`), at `velocity` (6081h) and `acceleration`
    /// (6083h/6084h) when given, as `drivebus drive move`; waits up to
    /// `timeout` seconds of simulated time. Returns the report (`end`,
    /// `position`, `target`, `statusword`, `duration` in simulated
    /// seconds); raises `DriveError` when the move stopped anywhere but the
    /// target.
    #[pyo3(signature = (position, relative = false, velocity = None, acceleration = None, timeout = 60.0))]
    fn move_to(
        &self,
        py: Python<'_>,
        position: i32,
        relative: bool,
        velocity: Option<u32>,
        acceleration: Option<u32>,
        timeout: f64,
    ) -> PyResult<Py<PyAny>> {
        let wait = seconds("timeout", timeout)?.max(Duration::from_millis(10));
        let r = self.run(py, move |d| async move {
            d.set_mode(mode::PP).await?;
            if let Some(v) = velocity {
                d.write_raw(0x6081, 0, &v.to_le_bytes()).await?;
            }
            if let Some(a) = acceleration {
                d.write_raw(0x6083, 0, &a.to_le_bytes()).await?;
                d.write_raw(0x6084, 0, &a.to_le_bytes()).await?;
            }
            d.move_to(position, relative, None::<drivebus_master::MoveProfile>, wait).await
        })?;
        report(py, &r)
    }

    /// Cyclic synchronous position (`drivebus drive csp`): mode 8, then the
    /// target positions 607Ah, one right after each SYNC (by an RPDO
    /// mapping 607Ah when there is one, else SDO); returns how many were
    /// sent. Needs SYNC (`master.start_sync`) and the drive enabled;
    /// raises `DriveError` otherwise.
    fn csp(&self, py: Python<'_>, positions: Vec<i32>) -> PyResult<usize> {
        self.run(py, move |d| async move {
            d.set_mode(mode::CSP).await?;
            d.stream_csp(positions).await
        })
    }

    fn __repr__(&self) -> String {
        format!("Drive(node={})", self.node)
    }
}
