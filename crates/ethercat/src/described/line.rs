//! A line of drive twins and described devices in one order, as
//! `drivebus ethercat serve --drive … --device …` gives them.

use super::{Described, Loopback, slave};
use crate::drive::{self, DriveLine, DriveSlaveSpec};
use crate::host::BoxDevice;
use drivebus_personality::Profile;
use std::path::Path;

/// One slave of a mixed line.
#[derive(Debug, Clone)]
pub enum Member {
    /// A drive twin of a personality (`ipos`, `generic`).
    Drive(Profile),
    /// A device from its SII image or ESI file.
    Device(Box<Described>),
}

/// The slaves of `members` in line order; serial numbers are the 1-based
/// positions (an EEPROM image keeps its own), drives keep their state
/// under `state_dir` as [`DriveLine::state_dir`] does. Described devices
/// loop their outputs back as inputs ([`Loopback`]).
pub fn devices(members: &[Member], state_dir: Option<&Path>) -> Result<Vec<BoxDevice>, String> {
    members
        .iter()
        .enumerate()
        .map(|(i, m)| match m {
            Member::Drive(p) => {
                let spec = DriveSlaveSpec {
                    state_dir: state_dir.map(|d| DriveLine::slave_dir(d, i, *p)),
                    ..DriveSlaveSpec::new(*p, i as u32 + 1)
                };
                drive::slave(&spec).map(|s| Box::new(s) as BoxDevice).map_err(|e| e.to_string())
            }
            Member::Device(d) => slave(d, i as u32 + 1, Box::new(Loopback))
                .map(|s| Box::new(s) as BoxDevice)
                .map_err(|e| e.to_string()),
        })
        .collect()
}

/// Runs `f` on the described slave at `position` of `host`'s segment.
pub fn with_device<R>(
    host: &crate::Host,
    position: usize,
    f: impl FnOnce(&mut super::DescribedSlave) -> R,
) -> Option<R> {
    host.with_segment(|s| {
        let d = s.device_mut(position)?.as_any_mut()?.downcast_mut::<super::DescribedSlave>()?;
        Some(f(d))
    })
}
