//! `Simulation`: drive twins on the virtual bus in simulated time
//! (`drivebus_bus::Bus`), as fast as the CPU allows and deterministic.

use std::time::Duration;

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::Instant;
use drivebus_personality::{PersonalityDevice, Profile};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::bus::{Received, frame, received};
use crate::state::DriveState;

/// One frame of the log: simulated time in seconds, then as `recv`.
type Logged = (f64, u32, bool, bool, u8, Vec<u8>);

/// The longest `advance` in one call: a year of simulated time.
const MAX_ADVANCE_S: f64 = 365.0 * 86_400.0;

/// Drive twins on a virtual CAN bus in simulated time. Nothing moves
/// between calls: `advance(seconds)` runs the bus and the drives; the same
/// calls give the same frame log, byte for byte. Belongs to the thread
/// that made it.
#[pyclass(unsendable, module = "drivebus._drivebus")]
pub struct Simulation {
    bus: Bus,
    probe: ProbeId,
    drives: Vec<(Profile, u8, NodeId)>,
}

#[pymethods]
impl Simulation {
    /// Builds `drives` (`"akd:1"`) on a bus at `bitrate` bit/s (`None`:
    /// frames take no time). Raises `ValueError` with the CLI's message
    /// for a bad drive, and for a bitrate of 0.
    #[new]
    #[pyo3(signature = (drives = Vec::new(), bitrate = Some(1_000_000)))]
    fn new(drives: Vec<String>, bitrate: Option<u32>) -> PyResult<Simulation> {
        if bitrate == Some(0) {
            return Err(PyValueError::new_err("bitrate must be positive (None: frames take no time)"));
        }
        let specs = drivebus_personality::drive_specs(&drives).map_err(PyValueError::new_err)?;
        let cfg = BusConfig { bitrate, ..BusConfig::default() };
        let mut bus = Bus::new(cfg);
        // The host's station, before the drives: it hears their boot-ups.
        let probe = bus.attach_probe();
        let mut hosted = Vec::with_capacity(specs.len());
        for (profile, node) in specs {
            let dev = crate::bus::build(profile, node)?;
            hosted.push((profile, node, bus.attach(dev)));
        }
        Ok(Simulation { bus, probe, drives: hosted })
    }

    /// Simulated time in seconds since the start.
    #[getter]
    fn now(&self) -> f64 {
        seconds(self.bus.now())
    }

    /// Runs the bus and the drives for `seconds` of simulated time.
    fn advance(&mut self, seconds: f64) -> PyResult<()> {
        if !(seconds.is_finite() && (0.0..=MAX_ADVANCE_S).contains(&seconds)) {
            return Err(PyValueError::new_err(format!(
                "seconds must be a number from 0 to {MAX_ADVANCE_S}, not {seconds}"
            )));
        }
        self.bus.run_for(Duration::from_secs_f64(seconds));
        Ok(())
    }

    /// Queues a classic CAN frame from the host's station at the current
    /// simulated time (it goes on the bus during the next `advance`).
    /// Raises `ValueError` for a frame CAN cannot carry.
    #[pyo3(signature = (arbitration_id, data, is_extended_id = false, is_remote_frame = false, dlc = None))]
    fn send(
        &mut self,
        arbitration_id: u32,
        data: &[u8],
        is_extended_id: bool,
        is_remote_frame: bool,
        dlc: Option<u8>,
    ) -> PyResult<()> {
        let f = frame(arbitration_id, data, is_extended_id, is_remote_frame, dlc)?;
        self.bus.send_from(self.probe, f);
        Ok(())
    }

    /// The frames the host's station received since the last call, as
    /// `recv` gives them, oldest first.
    fn received(&mut self) -> Vec<Received> {
        self.bus.take_received(self.probe).iter().map(received).collect()
    }

    /// Every frame the bus delivered so far: `(seconds, arbitration_id,
    /// is_extended_id, is_remote_frame, dlc, data)`, in bus order.
    fn log(&self) -> Vec<Logged> {
        self.bus
            .log()
            .iter()
            .map(|e| {
                let (id, ext, rtr, dlc, data) = received(&e.frame);
                (seconds(e.time), id, ext, rtr, dlc, data)
            })
            .collect()
    }

    /// The log as candump lines (`(0.001234) can0 701#00`).
    fn log_lines(&self) -> Vec<String> {
        self.bus.log_lines()
    }

    /// The drives' state now, in the order they were given.
    #[getter]
    fn drives(&self) -> Vec<DriveState> {
        self.drives
            .iter()
            .filter_map(|&(_, _, id)| self.bus.node::<PersonalityDevice>(id).map(DriveState::of))
            .collect()
    }
}

fn seconds(t: Instant) -> f64 {
    t.as_nanos() as f64 / 1e9
}
