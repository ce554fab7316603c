//! Shared harness: the homing engine driving a `DriveModel` directly, in
//! degrees (the servo_small rotary axis: 360 units per motor revolution).
#![allow(dead_code)]

use drivebus_cia402::homing::{
    Homing, HomingCommand, HomingConfig, HomingEvent, HomingEvents, HomingInput, HomingRegistry, HomingState,
};
use drivebus_cia402::model::{AxisParams, Demand, DriveModel, DriveParams};

pub const DT: f64 = 1.0 / 8000.0;
/// Index pulse angle \[rad\] → 0.3 rad = 17.188 733 853 924 7°.
pub const INDEX_RAD: f64 = 0.3;
pub const INDEX_DEG: f64 = INDEX_RAD * 180.0 / core::f64::consts::PI;
/// One encoder count in degrees.
pub const COUNT_DEG: f64 = 360.0 / (1u64 << 20) as f64;
pub const HOME_OFFSET: f64 = 12.5;

/// Index pulses sit at INDEX_DEG + 360·k degrees.
pub fn index_right_of(x: f64) -> f64 {
    let k = ((x - INDEX_DEG) / 360.0).floor() + 1.0;
    INDEX_DEG + 360.0 * k
}

pub fn index_left_of(x: f64) -> f64 {
    let k = ((x - INDEX_DEG) / 360.0).ceil() - 1.0;
    INDEX_DEG + 360.0 * k
}

pub fn axis(
    neg: Option<f64>,
    pos: Option<f64>,
    home: Option<(f64, f64)>,
    stops: (Option<f64>, Option<f64>),
    start: f64,
) -> DriveParams {
    let mut p = DriveParams::servo_small();
    p.encoder.index_angle = INDEX_RAD;
    p.axis = AxisParams {
        negative_limit: neg,
        positive_limit: pos,
        home_switch: home,
        negative_stop: stops.0,
        positive_stop: stops.1,
        initial_position: start,
        ..AxisParams::rotary_degrees(1.6e-5)
    };
    p
}

pub fn config(method: i8) -> HomingConfig {
    HomingConfig {
        method,
        switch_speed: 1800.0,
        zero_speed: 180.0,
        acceleration: 36_000.0,
        home_offset: HOME_OFFSET,
        units_per_rev: 360.0,
    }
}

/// The engine on a model, tracking the actual-position frame like a drive.
pub struct Rig {
    pub model: DriveModel,
    pub homing: Homing,
    pub config: HomingConfig,
    /// actual position = raw measured degrees + offset.
    pub offset: f64,
    pub controlword: u16,
    /// Distinct consecutive status values (bits 10/12/13).
    pub statuses: Vec<u16>,
    pub resets: usize,
    pub steps: usize,
}

impl Rig {
    pub fn new(params: DriveParams, config: HomingConfig) -> Self {
        Self::with_registry(params, config, HomingRegistry::standard())
    }

    pub fn with_registry(params: DriveParams, config: HomingConfig, registry: HomingRegistry) -> Self {
        let model = DriveModel::new(params).unwrap();
        let mut homing = Homing::new(registry);
        let p = model.rad_to_units(model.position_measured());
        homing.enter(p, 0x0F);
        let status = homing.status();
        Rig {
            model,
            homing,
            config,
            offset: 0.0,
            controlword: 0x0F,
            statuses: vec![status],
            resets: 0,
            steps: 0,
        }
    }

    pub fn actual(&self) -> f64 {
        self.model.rad_to_units(self.model.position_measured()) + self.offset
    }

    pub fn step(&mut self) -> u16 {
        let m = &self.model;
        let mut events = HomingEvents::default();
        for e in m.events().iter() {
            events.push(HomingEvent {
                kind: e.kind,
                active: e.active,
                position: m.rad_to_units(e.position) + self.offset,
                positive_direction: e.positive_direction,
            });
        }
        let input = HomingInput {
            position: self.actual(),
            velocity: m.rad_to_units(m.velocity_measured()),
            torque: 0.0,
            switches: m.switches(),
            events: events.as_slice(),
        };
        let out = self.homing.step(self.controlword, &self.config, &input, DT);
        if let Some(r) = out.position_reset {
            self.offset = r - self.model.rad_to_units(self.model.position_measured());
            self.resets += 1;
        }
        let cmd = match out.command {
            HomingCommand::Position { position, velocity, acceleration } => Demand::Position {
                position: self.model.units_to_rad(position - self.offset),
                velocity: self.model.units_to_rad(velocity),
                acceleration: self.model.units_to_rad(acceleration),
            },
            HomingCommand::Torque(t) => Demand::Torque(t / 1000.0 * 0.64),
        };
        assert!(self.model.set_demand(cmd), "invalid command {cmd:?}");
        self.model.step(DT);
        self.steps += 1;
        if self.statuses.last() != Some(&out.status) {
            self.statuses.push(out.status);
        }
        out.status
    }

    /// Raises bit 4 and runs until the engine stops running and the status
    /// has bit 10 (at rest), or `max_s` simulated seconds.
    pub fn run(&mut self, max_s: f64) -> u16 {
        self.controlword = 0x1F;
        let mut status = 0;
        for _ in 0..(max_s / DT) as usize {
            status = self.step();
            if self.homing.state() != HomingState::Running && status & 0x0400 != 0 {
                break;
            }
        }
        status
    }

    /// Raw (pre-homing) position of the home position found: the raw
    /// position whose actual value is the home offset.
    pub fn reference_raw(&self) -> f64 {
        HOME_OFFSET - self.offset
    }
}
