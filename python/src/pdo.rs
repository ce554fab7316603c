//! `sim.master().pdo`: PDO configuration as `drivebus pdo show|map` does
//! it (`Master::read_pdo`, `Master::try_write_pdo`: the CiA 301
//! invalidate / map / validate procedure, the previous mapping restored
//! when the device refuses), in simulated time.

use drivebus_master::{ConfigError, PdoDir, PdoMapEntry, PdoRecord, SdoAbort, SdoError as RustSdoError};
use pyo3::IntoPyObjectExt;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::master::{Master, SdoError, node_id, sdo_error, sdo_timeout};

/// The PDO configuration of the nodes on a simulation's bus (`master.pdo`).
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct Pdos {
    pub(crate) master: Master,
}

/// `"rpdo"` / `"tpdo"` (also `"rx"` / `"tx"`).
fn dir(d: &str) -> PyResult<PdoDir> {
    match d.to_ascii_lowercase().as_str() {
        "rpdo" | "rx" => Ok(PdoDir::Rx),
        "tpdo" | "tx" => Ok(PdoDir::Tx),
        _ => Err(PyValueError::new_err(format!("bad PDO direction `{d}`: use \"rpdo\" or \"tpdo\""))),
    }
}

fn dir_name(d: PdoDir) -> &'static str {
    if d == PdoDir::Rx { "RPDO" } else { "TPDO" }
}

fn number(n: i64) -> PyResult<u16> {
    u16::try_from(n)
        .ok()
        .filter(|n| (1..=512).contains(n))
        .ok_or_else(|| PyValueError::new_err(format!("PDO number `{n}` is not in 1..512")))
}

impl Pdos {
    /// A PDO as `drivebus pdo show --json` gives it.
    fn record(&self, py: Python<'_>, node: u8, d: PdoDir, num: u16, p: &PdoRecord) -> PyResult<Py<PyAny>> {
        let dict = self.master.dict(node);
        let out = PyDict::new(py);
        out.set_item("dir", dir_name(d))?;
        out.set_item("number", num)?;
        out.set_item("cob_id", p.cob_id & 0x1FFF_FFFF)?;
        out.set_item("valid", p.valid())?;
        out.set_item("transmission_type", p.transmission_type)?;
        out.set_item("inhibit_time", p.inhibit_time)?;
        out.set_item("event_timer_ms", p.event_timer)?;
        out.set_item("sync_start", p.sync_start)?;
        let mapping = p
            .mapping
            .iter()
            .map(|e| {
                let m = PyDict::new(py);
                m.set_item("index", e.index)?;
                m.set_item("sub", e.sub)?;
                m.set_item("bits", e.bits)?;
                m.set_item("name", dict.name(e.index, e.sub).unwrap_or_default())?;
                Ok(m)
            })
            .collect::<PyResult<Vec<_>>>()?;
        out.set_item("mapping", mapping)?;
        out.into_py_any(py)
    }

    /// A mapping entry: `(index, sub, bits)`, `"INDEX:SUB:BITS"` (hex,
    /// hex, decimal) or an object whose size the drive's EDS knows, as
    /// `drivebus pdo map` takes it.
    fn entry(&self, node: u8, e: &Bound<'_, PyAny>) -> PyResult<PdoMapEntry> {
        if let Ok(t) = e.cast::<PyTuple>() {
            let (index, sub, bits): (u16, u8, u8) = t.extract()?;
            if !(1..=64).contains(&bits) {
                return Err(PyValueError::new_err(format!("bad mapping entry {t}: bits must be 1..64")));
            }
            return Ok(PdoMapEntry::new(index, sub, bits));
        }
        let s: String = e.extract().map_err(|_| {
            PyValueError::new_err(
                "a mapping entry is (index, sub, bits), \"INDEX:SUB:BITS\" or an object name",
            )
        })?;
        let dict = self.master.dict(node);
        let parts: Vec<&str> = s.split(':').collect();
        if let [i, sub, bits] = parts[..] {
            let (index, sub) =
                dict.resolve(i, Some(sub)).map_err(|e| PyValueError::new_err(e.to_string()))?;
            let bits: u8 = bits.trim().parse().ok().filter(|b| (1..=64).contains(b)).ok_or_else(|| {
                PyValueError::new_err(format!("bad mapping entry `{s}`: BITS must be 1..64 (decimal)"))
            })?;
            return Ok(PdoMapEntry::new(index, sub.unwrap_or(0), bits));
        }
        let (index, sub) = dict.resolve(&s, None).map_err(|e| {
            PyValueError::new_err(format!(
                "bad mapping entry `{s}`: expected INDEX:SUB:BITS, e.g. 6041:0:16, or an object ({e})"
            ))
        })?;
        let sub = sub.unwrap_or(0);
        let bytes = dict.data_type(index, sub).and_then(|t| t.fixed_size()).ok_or_else(|| {
            PyValueError::new_err(format!(
                "bad mapping entry `{s}`: its size is unknown; write INDEX:SUB:BITS, e.g. 6041:0:16"
            ))
        })?;
        Ok(PdoMapEntry::new(index, sub, (bytes * 8) as u8))
    }
}

#[pymethods]
impl Pdos {
    /// Reads PDO `number` (1-based) of `node`, `direction` `"rpdo"` or
    /// `"tpdo"`: a dict `dir`, `number`, `cob_id`, `valid`,
    /// `transmission_type`, `inhibit_time`, `event_timer_ms`, `sync_start`
    /// (`None` where the device lacks the entry), `mapping` (dicts
    /// `index`, `sub`, `bits`, `name`). Raises `SdoError`.
    fn read(&self, py: Python<'_>, node: i64, direction: &str, number: i64) -> PyResult<Py<PyAny>> {
        let (node, d, num) = (node_id(node)?, dir(direction)?, self::number(number)?);
        let r = self.master.block_on(py, move |m| async move { m.read_pdo(node, d, num).await })?;
        let p = r.map_err(sdo_error(node, d.comm_index(num), 1, false, sdo_timeout()))?;
        self.record(py, node, d, num, &p)
    }

    /// Every PDO of `node` (`drivebus pdo show`): the RPDOs, then the
    /// TPDOs, each up to the first one the device lacks.
    fn show(&self, py: Python<'_>, node: i64) -> PyResult<Vec<Py<PyAny>>> {
        let node = node_id(node)?;
        let r = self.master.block_on(py, move |m| async move {
            let mut pdos = Vec::new();
            for d in [PdoDir::Rx, PdoDir::Tx] {
                for num in 1..=512u16 {
                    match m.read_pdo(node, d, num).await {
                        Ok(r) => pdos.push((d, num, r)),
                        Err(RustSdoError::Abort { code, .. })
                            if code == SdoAbort::NO_OBJECT || code == SdoAbort::NO_SUB_INDEX =>
                        {
                            break;
                        }
                        Err(e) => return Err((d.comm_index(num), e)),
                    }
                }
            }
            Ok(pdos)
        })?;
        let pdos = r.map_err(|(index, e)| sdo_error(node, index, 1, false, sdo_timeout())(e))?;
        pdos.iter().map(|(d, n, p)| self.record(py, node, *d, *n, p)).collect()
    }

    /// Maps PDO `number` of `node` (`drivebus pdo map`): `entries` in
    /// order, each `(index, sub, bits)`, `"INDEX:SUB:BITS"` or an object of
    /// the drive's EDS (`"statusword"`); `cob_id`, `transmission`,
    /// `inhibit` (100 µs), `event_timer` (ms) when given, else the COB-ID
    /// and transmission type in force; the PDO is valid afterwards. When
    /// the device refuses a step, the previous mapping is written back;
    /// raises `SdoError` naming the refusal and whether the restore worked.
    #[pyo3(signature = (node, direction, number, entries, *, cob_id = None, transmission = None, inhibit = None, event_timer = None))]
    #[allow(clippy::too_many_arguments)]
    fn map(
        &self,
        py: Python<'_>,
        node: i64,
        direction: &str,
        number: i64,
        entries: Vec<Bound<'_, PyAny>>,
        cob_id: Option<u32>,
        transmission: Option<u8>,
        inhibit: Option<u16>,
        event_timer: Option<u16>,
    ) -> PyResult<()> {
        let (node, d, num) = (node_id(node)?, dir(direction)?, self::number(number)?);
        let mapping = entries.iter().map(|e| self.entry(node, e)).collect::<PyResult<Vec<_>>>()?;
        let r = self.master.block_on(py, move |m| async move {
            let current = m.read_pdo(node, d, num).await.map_err(Err)?;
            let rec = PdoRecord {
                cob_id: cob_id.unwrap_or(current.cob_id & !0x8000_0000) & !0x8000_0000,
                transmission_type: transmission.unwrap_or(current.transmission_type),
                inhibit_time: inhibit,
                event_timer,
                sync_start: None,
                mapping,
            };
            m.try_write_pdo(node, d, num, &rec).await.map_err(Ok)
        })?;
        let timeout = sdo_timeout();
        match r {
            Ok(()) => Ok(()),
            Err(Err(e)) => Err(sdo_error(node, d.comm_index(num), 1, false, timeout)(e)),
            Err(Ok(e)) => {
                let cause = match e.cause {
                    ConfigError::Sdo { index, sub, error } => {
                        sdo_error(node, index, sub, true, timeout)(error).value(py).to_string()
                    }
                    other => other.to_string(),
                };
                let outcome = match (&e.previous, &e.restored) {
                    (None, _) => "nothing was changed".to_owned(),
                    (Some(_), Ok(())) => {
                        format!("the previous mapping of {}{num} is in force again", dir_name(d))
                    }
                    (Some(_), Err(re)) => format!(
                        "restoring the previous mapping failed too ({re}): {}{num} may be invalid",
                        dir_name(d)
                    ),
                };
                Err(SdoError::new_err(format!(
                    "node {node}: {}{num} mapping refused; {outcome}: {cause}",
                    dir_name(d)
                )))
            }
        }
    }
}
