//! Machine inputs, machine faults, bus-off and power of hosted drives at
//! run time: what `drivebus control` does to a running `serve`
//! (docs/control.md), through the same library calls. An input or a
//! fault is an entry due now on the drive's machine schedule
//! (`Change::input` / `Change::fault` parsed as the control interface
//! parses them, applied by `change_machine` between two frames, through
//! the node so the application is polled right after); bus-off is the
//! station's link state (`Controller::set_link` on the real-time hub,
//! `Bus::set_bus_off` / `recover` on the simulated bus); power off stops
//! the drive, power on builds it again on its machine.

use std::collections::BTreeMap;

use drivebus_personality::machine::{Change, MachineError};
use pyo3::PyResult;
use pyo3::exceptions::{PyOSError, PyValueError};

/// One run-time change of a hosted drive.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Action {
    /// A machine input or fault for `duration` seconds (`None`: until changed).
    Machine(Change, Option<f64>),
    /// Bus-off (`true`) or back on the bus (`false`).
    BusOff(bool),
    /// Power on (`true`) or off.
    Power(bool),
}

/// `drivebus control input NODE INPUT [LINE] VALUE [--for SECONDS]`.
pub(crate) fn input(input: &str, line: Option<u8>, value: f64, duration: Option<f64>) -> PyResult<Action> {
    let c = Change::input(input, line, value).map_err(|e| PyValueError::new_err(format!("input: {e}")))?;
    Ok(Action::Machine(c, duration))
}

/// `drivebus control fault NODE KIND [SWITCH] [--for SECONDS]`; `kind`
/// `"clear"` ends every machine fault that is on.
pub(crate) fn fault(kind: &str, switch: Option<&str>, duration: Option<f64>) -> PyResult<Action> {
    let c = Change::fault(kind, switch).map_err(|e| PyValueError::new_err(format!("fault: {e}")))?;
    Ok(Action::Machine(c, duration))
}

/// The error of a refused machine change, as the control interface words it.
pub(crate) fn refused(node: u8, e: MachineError) -> pyo3::PyErr {
    PyValueError::new_err(format!("node {node}: {e}"))
}

/// No drive with node-ID `node` is hosted.
pub(crate) fn no_node<V>(nodes: &BTreeMap<u8, V>, node: u8) -> pyo3::PyErr {
    let list = nodes.keys().map(u8::to_string).collect::<Vec<_>>().join(", ");
    PyValueError::new_err(format!("no node with node-ID {node} is served: use one of {list}"))
}

/// The drive is powered off and cannot take the change.
pub(crate) fn powered_off(node: u8) -> pyo3::PyErr {
    PyOSError::new_err(format!("node {node} is powered off: power it on first (power({node}, True))"))
}
