//! `sim.master().lss`: the CiA 305 layer setting services of the master
//! library (`LssMaster`), as `drivebus lss` uses them, in simulated time.

use std::time::Duration;

use drivebus_master::{Identity, LssError, LssMaster, LssMode, OnlySlave};
use pyo3::IntoPyObjectExt;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::master::{DrivebusError, Master};

/// The LSS master on a simulation's bus (`master.lss`); each question
/// waits `timeout` seconds of simulated time for its answer.
#[pyclass(frozen, module = "drivebus._drivebus")]
pub struct Lss {
    pub(crate) master: Master,
    pub(crate) timeout: Duration,
}

fn lss_error(e: LssError) -> PyErr {
    DrivebusError::new_err(e.to_string())
}

fn identity_dict(py: Python<'_>, a: &Identity) -> PyResult<Py<PyAny>> {
    let d = PyDict::new(py);
    d.set_item("vendor_id", a.vendor_id)?;
    d.set_item("product_code", a.product_code)?;
    d.set_item("revision", a.revision)?;
    d.set_item("serial", a.serial)?;
    d.into_py_any(py)
}

fn configurable(node_id: u8) -> PyResult<u8> {
    if (1..=127).contains(&node_id) {
        Ok(node_id)
    } else {
        Err(PyValueError::new_err(format!("node-ID `{node_id}` is not in 1..127")))
    }
}

impl Lss {
    /// Runs `f` on the LSS master in simulated time.
    fn run<T, F>(&self, py: Python<'_>, f: impl FnOnce(LssMaster) -> F + Send + 'static) -> PyResult<T>
    where
        T: Send + 'static,
        F: std::future::Future<Output = Result<T, LssError>>,
    {
        let timeout = self.timeout;
        self.master
            .block_on(py, move |m| async move { f(m.lss().timeout(timeout)).await })?
            .map_err(lss_error)
    }
}

#[pymethods]
impl Lss {
    /// Switch state global: `"configuration"` (every LSS slave takes
    /// configuration services: use it with one slave on the bus) or
    /// `"waiting"`.
    fn switch_global(&self, py: Python<'_>, mode: &str) -> PyResult<()> {
        let mode = match mode {
            "configuration" => LssMode::Configuration,
            "waiting" => LssMode::Waiting,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "bad LSS mode `{mode}`: use \"configuration\" or \"waiting\""
                )));
            }
        };
        self.run(py, move |l| async move { l.switch_global(mode).await })
    }

    /// Switch state selective: the slave with this LSS address (1018h:1..4)
    /// goes to configuration. Raises `DrivebusError` (`LSS: no answer`)
    /// when none answers.
    fn switch_selective(
        &self,
        py: Python<'_>,
        vendor_id: u32,
        product_code: u32,
        revision: u32,
        serial: u32,
    ) -> PyResult<()> {
        let a = Identity { vendor_id, product_code, revision, serial };
        self.run(py, move |l| async move { l.switch_selective(&a).await })
    }

    /// Inquire the LSS address of the slave in configuration: a dict
    /// `vendor_id`, `product_code`, `revision`, `serial`.
    fn inquire_identity(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let a = self.run(py, |l| async move { l.inquire_identity().await })?;
        identity_dict(py, &a)
    }

    /// Inquire the node-ID of the slave in configuration (FFh: none).
    fn inquire_node_id(&self, py: Python<'_>) -> PyResult<u8> {
        self.run(py, |l| async move { l.inquire_node_id().await })
    }

    /// Configure node-ID `node_id` on the slave in configuration; it takes
    /// effect at the slave's next NMT reset communication (CiA 305).
    fn configure_node_id(&self, py: Python<'_>, node_id: u8) -> PyResult<()> {
        let n = configurable(node_id)?;
        self.run(py, move |l| async move { l.configure_node_id(n).await })
    }

    /// Store the configuration of the slave in configuration.
    fn store(&self, py: Python<'_>) -> PyResult<()> {
        self.run(py, |l| async move { l.store().await })
    }

    /// `drivebus lss set-node-id N --vendor ...`: switch selective on the
    /// address, configure `node_id`, store when `store`, back to waiting.
    #[pyo3(signature = (node_id, vendor_id, product_code, revision, serial, store = false))]
    #[allow(clippy::too_many_arguments)]
    fn configure_selected(
        &self,
        py: Python<'_>,
        node_id: u8,
        vendor_id: u32,
        product_code: u32,
        revision: u32,
        serial: u32,
        store: bool,
    ) -> PyResult<()> {
        let n = configurable(node_id)?;
        let a = Identity { vendor_id, product_code, revision, serial };
        self.run(py, move |l| async move { l.configure_selected(&a, n, store).await })
    }

    /// `drivebus lss scan`: the non-configured slave with the lowest LSS
    /// address (fastscan), as a dict with `more` (whether others answer),
    /// or `None`. Every slave is left as it was.
    fn scan(&self, py: Python<'_>) -> PyResult<Option<Py<PyAny>>> {
        let found = self.run(py, |l| async move { l.probe_unconfigured().await })?;
        found
            .map(|(a, more)| {
                let d = identity_dict(py, &a)?;
                d.bind(py).set_item("more", more)?;
                Ok(d)
            })
            .transpose()
    }

    /// Gives `node_id` to the only non-configured slave (store when
    /// `store`): its address, or `None` when there is none; raises
    /// `DrivebusError` and changes nothing when several answer.
    #[pyo3(signature = (node_id, store = false))]
    fn configure_only_slave(&self, py: Python<'_>, node_id: u8, store: bool) -> PyResult<Option<Py<PyAny>>> {
        let n = configurable(node_id)?;
        match self.run(py, move |l| async move { l.configure_only_slave(n, store).await })? {
            OnlySlave::Configured(a) => identity_dict(py, &a).map(Some),
            OnlySlave::NoneFound => Ok(None),
            OnlySlave::Several(a) => Err(DrivebusError::new_err(format!(
                "LSS: more than one non-configured slave answers (the lowest: vendor 0x{:08X} serial 0x{:08X}): configure them by address",
                a.vendor_id, a.serial
            ))),
        }
    }

    fn __repr__(&self) -> String {
        format!("Lss(timeout={})", self.timeout.as_secs_f64())
    }
}
