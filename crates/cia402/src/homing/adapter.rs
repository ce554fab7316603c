//! [`HomingMode`]: the homing engine as the drive's `ModeHandler` for hm (6).

use alloc::vec::Vec;

use super::{Homing, HomingCommand, HomingConfig, HomingEvent, HomingEvents, HomingInput, HomingRegistry};
use crate::drive::Units;
use crate::drive::mode::{ModeCommand, ModeHandler, ModeIo, ModeOutput, op};
use drivebus_od::SdoAbort;

/// Homing mode (6060h = 6) for the drive: converts the OD parameters
/// (6098h, 6099h, 609Ah, 607Ch) and the model events to position units and
/// runs [`Homing`].
///
/// Event positions (model radians, raw encoder frame) are placed in the
/// actual-position frame with [`ModeIo::event_position`], i.e. with the
/// drive's present reference shift [`ModeIo::inc_offset`], whoever caused it.
///
/// As the drive's handler it provides 60E3h from its registry
/// ([`ModeHandler::homing_methods`], manufacturer methods with negative codes
/// included) and refuses 6098h writes of methods not registered (0609 0030;
/// 0 "no homing method" is always accepted).
#[derive(Debug)]
pub struct HomingMode {
    engine: Homing,
    /// Return to the home position after the stop (besides
    /// [`ModeParams::homing_return_to_home`](crate::drive::ModeParams::homing_return_to_home)).
    return_to_home: bool,
}

impl Default for HomingMode {
    fn default() -> Self {
        Self::new(HomingRegistry::standard())
    }
}

impl HomingMode {
    /// hm offering `registry`'s methods.
    pub fn new(registry: HomingRegistry) -> Self {
        HomingMode { engine: Homing::new(registry), return_to_home: false }
    }

    /// After the reference is taken and the axis has braked, move back to
    /// the home position (607Ch in the new coordinates) with 6099h:2 and
    /// 609Ah, and only then report homing completed (bits 12 + 10). Also
    /// switched on for every hm handler by
    /// [`DriveConfig::homing_return_to_home`](crate::drive::DriveConfig::homing_return_to_home).
    pub fn with_return_to_home(mut self, on: bool) -> Self {
        self.return_to_home = on;
        self
    }

    /// The engine (state, registry).
    pub fn engine(&self) -> &Homing {
        &self.engine
    }

    /// The engine, e.g. to register manufacturer methods.
    pub fn engine_mut(&mut self) -> &mut Homing {
        &mut self.engine
    }

    /// 60E3h: supported homing methods, sub 1..n.
    pub fn supported_methods(&self) -> Vec<i8> {
        self.engine.registry().codes().collect()
    }

    /// Whether a 6098h write of `method` is acceptable (else abort 0609 0030).
    pub fn is_supported(&self, method: i8) -> bool {
        self.engine.registry().is_supported(method)
    }

    /// The status bits 10/12/13 now (for the statusword outside hm steps).
    pub fn status(&self) -> u16 {
        self.engine.status()
    }
}

fn config(io: &ModeIo<'_>) -> HomingConfig {
    let p = io.params;
    let u = io.units;
    HomingConfig {
        method: p.homing_method,
        switch_speed: u.vel_to_pos(f64::from(p.homing_speed_switch)),
        zero_speed: u.vel_to_pos(f64::from(p.homing_speed_zero)),
        acceleration: u.acc_to_pos(f64::from(p.homing_acceleration)),
        home_offset: f64::from(p.home_offset),
        units_per_rev: u.rad_to_pos(2.0 * core::f64::consts::PI).abs(),
    }
}

impl ModeHandler for HomingMode {
    fn supported_modes(&self) -> u32 {
        op::supported_bit(op::HM)
    }

    fn enter(&mut self, _mode: i8, io: &ModeIo<'_>) {
        self.engine.enter(io.demand_position, io.controlword);
    }

    fn step(&mut self, _mode: i8, io: &ModeIo<'_>, dt: f64) -> ModeOutput {
        let u = io.units;
        // 607Eh polarity may flip the direction in position units.
        let flip = u.rad_to_pos(1.0) < 0.0;
        let mut events = HomingEvents::default();
        for e in io.events.iter() {
            events.push(HomingEvent {
                kind: e.kind,
                active: e.active,
                position: io.event_position(e),
                positive_direction: e.positive_direction != flip,
            });
        }
        let input = HomingInput {
            position: io.position as f64,
            velocity: io.velocity,
            torque: io.torque,
            switches: io.switches,
            events: events.as_slice(),
        };
        self.engine.set_return_to_home(self.return_to_home || io.params.homing_return_to_home);
        self.engine.set_keep_position(io.params.homing_keeps_position);
        let out = self.engine.step(io.controlword, &config(io), &input, dt);
        let command = match out.command {
            HomingCommand::Position { position, velocity, acceleration } => {
                ModeCommand::Position { position, velocity, acceleration }
            }
            HomingCommand::Torque(t) => ModeCommand::Torque(t),
        };
        let position_reset = out.position_reset.map(|r| libm::round(r.clamp(-9.0e15, 9.0e15)) as i64);
        ModeOutput { command, status: out.status, position_reset, ..ModeOutput::default() }
    }

    fn exit(&mut self, _mode: i8) {
        self.engine.interrupt();
    }

    fn homing_methods(&self) -> Option<Vec<i8>> {
        Some(self.supported_methods())
    }

    fn write_object(&mut self, index: u16, sub: u8, data: &[u8], _units: &Units) -> Result<bool, SdoAbort> {
        if (index, sub) != (0x6098, 0) {
            return Ok(false);
        }
        let m = data.first().copied().unwrap_or(0) as i8;
        // CiA 402-2: 6098h = 0 means "no homing method assigned".
        if m == 0 || self.is_supported(m) { Ok(true) } else { Err(SdoAbort::INVALID_VALUE) }
    }
}
