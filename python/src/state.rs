//! What Python sees of a hosted drive: its state when it was read, and
//! the run-time changes of `drivebus control` as methods, carried out by
//! the bus, server or simulation that hosts it (the same calls as theirs).

use drivebus_cia402::codes::State;
use drivebus_personality::PersonalityDevice;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::bus::VirtualBus;
use crate::control::{self, Action};
use crate::serve::Server;
use crate::sim::Simulation;

/// What hosts a drive: where its methods act.
#[derive(Debug)]
pub(crate) enum Owner {
    Bus(Py<VirtualBus>),
    Server(Py<Server>),
    Sim(Py<Simulation>),
}

/// One hosted drive (`bus.drives`): its state when it was read, and
/// methods that change it now.
#[pyclass(frozen, module = "drivebus._drivebus")]
#[derive(Debug)]
pub struct DriveState {
    /// The personality (`"akd"`).
    #[pyo3(get)]
    pub profile: String,
    /// The node-ID.
    #[pyo3(get)]
    pub node: u8,
    /// The NMT state (`"pre-operational"`, `"operational"`, ...).
    #[pyo3(get)]
    pub nmt: String,
    /// The CiA 402 state from the statusword (`"switch on disabled"`,
    /// `"operation enabled"`, ...); `"unknown"` for a pattern CiA 402 does
    /// not define.
    #[pyo3(get)]
    pub state: String,
    /// 6041h, the statusword.
    #[pyo3(get)]
    pub statusword: u16,
    /// 6061h, the mode of operation in force.
    #[pyo3(get)]
    pub mode: i8,
    /// 6064h, the position actual value in position units.
    #[pyo3(get)]
    pub position: i64,
    /// Where it is hosted (set when `drives` hands it to Python).
    pub(crate) owner: Option<Owner>,
}

impl DriveState {
    /// Reads the state out of the device (between two of its frames).
    pub fn of(d: &PersonalityDevice) -> DriveState {
        let od = d.node.od();
        let statusword = od.get_u64(0x6041, 0).and_then(|v| u16::try_from(v).ok()).unwrap_or(0);
        DriveState {
            profile: d.app.profile().name().to_owned(),
            node: d.node.node_id(),
            nmt: d.node.nmt_state().name().to_owned(),
            state: State::from_statusword(statusword).map_or("unknown", State::name).to_owned(),
            statusword,
            mode: od.get_i64(0x6061, 0).and_then(|v| i8::try_from(v).ok()).unwrap_or(0),
            position: od.get_i64(0x6064, 0).unwrap_or(0),
            owner: None,
        }
    }
}

impl DriveState {
    /// The state hosted by `owner`.
    pub(crate) fn owned_by(mut self, owner: Owner) -> DriveState {
        self.owner = Some(owner);
        self
    }

    /// Carries out `action` on this drive through its host.
    fn act(&self, py: Python<'_>, action: Action) -> PyResult<()> {
        match &self.owner {
            Some(Owner::Bus(b)) => b.get().act(py, self.node, action),
            Some(Owner::Server(s)) => s.get().act(py, self.node, action),
            Some(Owner::Sim(s)) => s.get().act(py, self.node, action),
            None => Err(PyRuntimeError::new_err(format!("node {}: not a hosted drive", self.node))),
        }
    }
}

#[pymethods]
impl DriveState {
    /// The drive's state read now (a new object). Raises `OSError` when it
    /// is powered off or its bus is closed.
    fn refresh(&self, py: Python<'_>) -> PyResult<DriveState> {
        let states = match &self.owner {
            Some(Owner::Bus(b)) => VirtualBus::drives(b.bind(py))?,
            Some(Owner::Server(s)) => Server::drives(s.bind(py))?,
            Some(Owner::Sim(s)) => Simulation::drives(s.bind(py))?,
            None => return Err(PyRuntimeError::new_err(format!("node {}: not a hosted drive", self.node))),
        };
        states.into_iter().find(|d| d.node == self.node).ok_or_else(|| control::powered_off(self.node))
    }

    /// Sets machine input `input` of this drive now (`"digital"` with
    /// `line` 1..16 and value 0/1, `"analog"` with `line` 1..4 in volts,
    /// `"master_velocity"`, `"master_position"`, `"motor_temperature"`,
    /// `"brake"`), for `duration` seconds if given, as `drivebus control
    /// input`. Raises `ValueError` with the control interface's message,
    /// `OSError` when the drive is powered off.
    #[pyo3(signature = (input, value, line = None, duration = None))]
    fn set_input(
        &self,
        py: Python<'_>,
        input: &str,
        value: f64,
        line: Option<u8>,
        duration: Option<f64>,
    ) -> PyResult<()> {
        self.act(py, control::input(input, line, value, duration)?)
    }

    /// Starts machine fault `kind` of this drive now (`"encoder"`,
    /// `"over_current"`, `"over_temperature"`, `"over_voltage"`,
    /// `"under_voltage"`, `"trip"` / `"wire_break"` with `switch`), for
    /// `duration` seconds if given, as `drivebus control fault`.
    #[pyo3(signature = (kind, switch = None, duration = None))]
    fn fault(&self, py: Python<'_>, kind: &str, switch: Option<&str>, duration: Option<f64>) -> PyResult<()> {
        self.act(py, control::fault(kind, switch, duration)?)
    }

    /// Ends every machine fault of this drive that is on (`drivebus control
    /// fault NODE clear`); a latched drive fault stays until the master's
    /// fault reset.
    fn clear_fault(&self, py: Python<'_>) -> PyResult<()> {
        self.act(py, control::fault("clear", None, None)?)
    }

    /// This drive's CAN controller goes bus-off (`drivebus control bus off`).
    fn bus_off(&self, py: Python<'_>) -> PyResult<()> {
        self.act(py, Action::BusOff(true))
    }

    /// This drive is back on the bus (`drivebus control bus on`).
    fn bus_on(&self, py: Python<'_>) -> PyResult<()> {
        self.act(py, Action::BusOff(false))
    }

    /// Cuts (`on=False`) or restores this drive's power (`drivebus control
    /// power`): off it is silent and leaves `drives`; on it boots again.
    fn power(&self, py: Python<'_>, on: bool) -> PyResult<()> {
        self.act(py, Action::Power(on))
    }

    fn __repr__(&self) -> String {
        format!(
            "DriveState(profile={:?}, node={}, nmt={:?}, state={:?}, statusword=0x{:04X}, mode={}, position={})",
            self.profile, self.node, self.nmt, self.state, self.statusword, self.mode, self.position
        )
    }
}
