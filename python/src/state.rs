//! What Python sees of a hosted drive: a snapshot of its state.

use drivebus_cia402::codes::State;
use drivebus_personality::PersonalityDevice;
use pyo3::prelude::*;

/// The state of one hosted drive when it was read (`bus.drives`).
#[pyclass(frozen, get_all, module = "drivebus._drivebus")]
#[derive(Clone, Debug)]
pub struct DriveState {
    /// The personality (`"akd"`).
    pub profile: String,
    /// The node-ID.
    pub node: u8,
    /// The NMT state (`"pre-operational"`, `"operational"`, ...).
    pub nmt: String,
    /// The CiA 402 state from the statusword (`"switch on disabled"`,
    /// `"operation enabled"`, ...); `"unknown"` for a pattern CiA 402 does
    /// not define.
    pub state: String,
    /// 6041h, the statusword.
    pub statusword: u16,
    /// 6061h, the mode of operation in force.
    pub mode: i8,
    /// 6064h, the position actual value in position units.
    pub position: i64,
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
        }
    }
}

#[pymethods]
impl DriveState {
    fn __repr__(&self) -> String {
        format!(
            "DriveState(profile={:?}, node={}, nmt={:?}, state={:?}, statusword=0x{:04X}, mode={}, position={})",
            self.profile, self.node, self.nmt, self.state, self.statusword, self.mode, self.position
        )
    }
}
