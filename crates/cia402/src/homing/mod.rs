//! Homing (CiA 402 hm mode, CiA 402-2 "Homing mode", objects 6098h–609Ah, 607Ch, 60E3h): every standard method and
//! pluggable manufacturer methods.
//!
//! [`Homing`] is the mode engine: it starts a run on the rising edge of
//! controlword bit 4, interrupts it on halt (bit 8) or on the falling edge of
//! bit 4, moves the axis on a velocity profile with the homing acceleration
//! 609Ah at the speeds 6099h:1/2 asked for by the [`HomingMethod`] (from a
//! [`HomingRegistry`]), and once the method reports the home position makes
//! it the home offset 607Ch ("position actual := home offset") and brings the
//! axis to rest. It works in position units and is driven either by the
//! drive through [`HomingMode`] (the `ModeHandler` adapter) or directly on
//! a [`crate::model::DriveModel`] (see the tests).
//!
//! Statusword bits 10 / 12 / 13 (CiA 402-2 homing mode, table "Definition of bit
//! 10, bit 12 and bit 13"; [`status`]):
//!
//! | bit 13 | bit 12 | bit 10 | meaning |
//! |---|---|---|---|
//! | 0 | 0 | 0 | homing in progress (also: halted, still decelerating) |
//! | 0 | 0 | 1 | homing interrupted or not started |
//! | 0 | 1 | 0 | homing attained, but target not reached (decelerating) |
//! | 0 | 1 | 1 | homing completed |
//! | 1 | 0 | 0 | homing error, velocity ≠ 0 |
//! | 1 | 0 | 1 | homing error, velocity = 0 |
//!
//! Interruption aborts the run; a new rising edge of bit 4 starts it again
//! from the beginning (the method's search direction follows the switch
//! states then).
//!
//! **Return to home** ([`Homing::set_return_to_home`], off by default):
//! without it the axis comes to rest wherever the homing acceleration stops
//! it after the reference, i.e. 607Ch plus the braking distance in the
//! final direction. With it, once at rest the engine moves back to the home
//! position (607Ch in the new coordinates) on a trapezoid with the zero
//! search speed 6099h:2 and the homing acceleration 609Ah. Bit 12 (homing
//! attained) is set when the reference is taken, bit 10 (target reached)
//! only when the axis is at rest at the home position. A halt or bit 4
//! dropped during the return stops the axis and reports "interrupted"
//! (the new coordinates stay in force).

mod adapter;
pub mod method;
pub mod standard;

pub use adapter::HomingMode;
pub use method::{
    HomingConfig, HomingContext, HomingError, HomingEvent, HomingEvents, HomingMethod, HomingRegistry,
    MethodStep,
};
pub use standard::StandardMethod;

use crate::drive::profile::{Limits, Shape, Trajectory};
use crate::model::Switches;

/// Statusword 6041h bits of the homing mode.
pub mod status {
    /// Bit 10: target reached (home position reached / axis at rest).
    pub const TARGET_REACHED: u16 = 1 << 10;
    /// Bit 12: homing attained.
    pub const ATTAINED: u16 = 1 << 12;
    /// Bit 13: homing error.
    pub const ERROR: u16 = 1 << 13;
    /// The three bits.
    pub const MASK: u16 = TARGET_REACHED | ATTAINED | ERROR;
}

/// Controlword 6040h bit 4 in hm: homing operation start.
const CW_START: u16 = 1 << 4;
/// Controlword bit 8: halt.
const CW_HALT: u16 = 1 << 8;

/// Where the homing engine is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HomingState {
    /// Never started since the mode was entered.
    Idle,
    /// A method is running.
    Running,
    /// Halted or bit 4 dropped; decelerating or at rest.
    Interrupted,
    /// Home position found; decelerating (attained) or at rest (completed).
    Attained,
    /// Failed; decelerating or at rest.
    Error(HomingError),
}

/// Actual values for one control period, in position units.
#[derive(Debug, Clone, Copy)]
pub struct HomingInput<'a> {
    /// Position actual \[units\].
    pub position: f64,
    /// Velocity actual \[units/s\].
    pub velocity: f64,
    /// Torque actual \[per mille\].
    pub torque: f64,
    /// Switch levels.
    pub switches: Switches,
    /// Events of the last period, earliest first.
    pub events: &'a [HomingEvent],
}

/// The set-point homing produces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HomingCommand {
    /// Follow a position with velocity / acceleration feed-forward \[units\].
    Position {
        /// Position demand \[units\].
        position: f64,
        /// Velocity feed-forward \[units/s\].
        velocity: f64,
        /// Acceleration feed-forward \[units/s²\].
        acceleration: f64,
    },
    /// A torque demand from a manufacturer method \[per mille\].
    Torque(f64),
}

/// Output of one control period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomingOutput {
    /// The set-point.
    pub command: HomingCommand,
    /// Statusword bits 10, 12, 13.
    pub status: u16,
    /// The home position was found in this period: the actual position now
    /// becomes this value \[units\] (home offset + distance travelled past
    /// the home position). The command above is already in the new frame.
    pub position_reset: Option<f64>,
}

/// Velocity profile with a symmetric acceleration limit.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Profile {
    position: f64,
    velocity: f64,
    target: f64,
}

impl Profile {
    fn step(&mut self, accel: f64, dt: f64) -> HomingCommand {
        if dt <= 0.0 {
            return HomingCommand::Position {
                position: self.position,
                velocity: self.velocity,
                acceleration: 0.0,
            };
        }
        let v0 = self.velocity;
        let dv = accel * dt;
        let diff = self.target - v0;
        self.velocity = if diff.abs() <= dv { self.target } else { v0 + dv.copysign(diff) };
        self.position += 0.5 * (v0 + self.velocity) * dt;
        HomingCommand::Position {
            position: self.position,
            velocity: self.velocity,
            acceleration: (self.velocity - v0) / dt,
        }
    }

    fn at_rest(&self) -> bool {
        self.velocity == 0.0 && self.target == 0.0
    }
}

/// The homing mode engine (see the module docs).
#[derive(Debug)]
pub struct Homing {
    registry: HomingRegistry,
    state: HomingState,
    bit4: bool,
    profile: Profile,
    torque: Option<f64>,
    method: i8,
    /// Move back to the home position after the stop.
    return_to_home: bool,
    /// The return is still due (reference taken with `return_to_home`).
    return_pending: bool,
    /// The return move and the time into it \[s\].
    ret: Option<(Trajectory, f64)>,
    /// The reference does not reset the position (Technosoft iPOS 210Bh
    /// bit 12): the counter keeps its value, a return goes to the point
    /// found.
    keep_position: bool,
    /// Where the return goes (the home offset, or the point found).
    return_target: f64,
}

impl Homing {
    /// An idle engine offering the methods of `registry`.
    pub fn new(registry: HomingRegistry) -> Self {
        Homing {
            registry,
            state: HomingState::Idle,
            bit4: false,
            profile: Profile { position: 0.0, velocity: 0.0, target: 0.0 },
            torque: None,
            method: 0,
            return_to_home: false,
            return_pending: false,
            ret: None,
            keep_position: false,
            return_target: 0.0,
        }
    }

    /// The reference found keeps the position as it is instead of setting
    /// it to the home offset (no position reset); applies from the next
    /// reference found.
    pub fn set_keep_position(&mut self, on: bool) {
        self.keep_position = on;
    }

    /// After the reference is taken and the axis has stopped, move back to
    /// the home position before reporting homing completed (see the module
    /// docs). Applies from the next reference found.
    pub fn set_return_to_home(&mut self, on: bool) {
        self.return_to_home = on;
    }

    /// Whether the engine returns to the home position.
    pub fn return_to_home(&self) -> bool {
        self.return_to_home
    }

    /// Abandons a pending return: the axis decelerates from where it is.
    fn cancel_return(&mut self) {
        if self.return_pending {
            self.return_pending = false;
            self.ret = None;
            if self.state == HomingState::Attained {
                self.state = HomingState::Interrupted;
            }
        }
    }

    /// The methods offered (60E3h).
    pub fn registry(&self) -> &HomingRegistry {
        &self.registry
    }

    /// The methods offered, to register manufacturer methods.
    pub fn registry_mut(&mut self) -> &mut HomingRegistry {
        &mut self.registry
    }

    /// Where the engine is.
    pub fn state(&self) -> HomingState {
        self.state
    }

    /// The mode became active: hold `demand_position` \[units\] bumplessly;
    /// a run in progress is abandoned (interrupted). `controlword` is the
    /// present one, so a bit 4 already set does not count as a rising edge.
    pub fn enter(&mut self, demand_position: f64, controlword: u16) {
        let p = if demand_position.is_finite() { demand_position } else { 0.0 };
        self.profile = Profile { position: p, velocity: 0.0, target: 0.0 };
        self.torque = None;
        self.bit4 = controlword & CW_START != 0;
        if self.state == HomingState::Running {
            self.state = HomingState::Interrupted;
        }
        self.cancel_return();
    }

    /// The mode was left or the drive disabled: a run in progress is
    /// interrupted (the profile stops; the drive no longer follows it).
    pub fn interrupt(&mut self) {
        if self.state == HomingState::Running {
            self.state = HomingState::Interrupted;
        }
        self.cancel_return();
        self.profile.target = 0.0;
        self.profile.velocity = 0.0;
        self.torque = None;
    }

    /// The status bits 10 / 12 / 13 now.
    pub fn status(&self) -> u16 {
        use status::*;
        let rest = self.profile.at_rest() && self.torque.is_none() && !self.return_pending;
        let tr = if rest { TARGET_REACHED } else { 0 };
        match self.state {
            HomingState::Idle => TARGET_REACHED,
            HomingState::Running => 0,
            HomingState::Interrupted => tr,
            HomingState::Attained => ATTAINED | tr,
            HomingState::Error(_) => ERROR | tr,
        }
    }

    /// One control period of `dt` seconds with controlword `controlword`.
    pub fn step(
        &mut self,
        controlword: u16,
        config: &HomingConfig,
        input: &HomingInput<'_>,
        dt: f64,
    ) -> HomingOutput {
        let bit4 = controlword & CW_START != 0;
        let halt = controlword & CW_HALT != 0;
        let (rising, falling) = (bit4 && !self.bit4, !bit4 && self.bit4);
        self.bit4 = bit4;
        let ctx = HomingContext {
            config,
            position: input.position,
            velocity: input.velocity,
            switches: input.switches,
            events: input.events,
            torque: input.torque,
        };
        let mut reset = None;
        if self.return_pending && (halt || falling) {
            // Halt / bit 4 1→0 during the return: stop on the homing
            // acceleration from the present motion.
            self.cancel_return();
        }
        let request = if self.state == HomingState::Running {
            if halt || falling {
                // Halt in hm: "stop axis with homing acceleration" (CiA 402-2 homing
                // mode, controlword bit 8); bit 4 1→0: "interrupt homing".
                self.state = HomingState::Interrupted;
                None
            } else {
                match self.registry.get_mut(self.method) {
                    Some(m) => Some(m.update(&ctx)),
                    // Unregistered during the run.
                    None => Some(MethodStep::Failed(HomingError::UnsupportedMethod)),
                }
            }
        } else if rising && !halt {
            self.start(config, &ctx)
        } else {
            None
        };
        if let Some(req) = request {
            reset = self.apply(req, config, &ctx);
        }
        if self.state != HomingState::Running {
            self.profile.target = 0.0;
            if self.torque.take().is_some() {
                self.sync(input.position);
            }
        }
        let accel = if config.acceleration.is_finite() && config.acceleration > 0.0 {
            config.acceleration
        } else {
            // Unusable 609Ah: stop at once rather than never.
            f64::MAX
        };
        // A bad period does not advance the profile.
        let dt = if dt.is_finite() && dt > 0.0 { dt } else { 0.0 };
        let command = match self.torque {
            Some(t) => HomingCommand::Torque(t),
            None => self.profile_step(config, accel, dt),
        };
        HomingOutput { command, status: self.status(), position_reset: reset }
    }

    /// The velocity profile, or the return to the home position once the
    /// axis has stopped after the reference.
    fn profile_step(&mut self, config: &HomingConfig, accel: f64, dt: f64) -> HomingCommand {
        if self.return_pending && self.ret.is_none() && self.profile.at_rest() {
            let lim = Limits { velocity: config.zero_speed, acceleration: accel, deceleration: accel };
            if lim.valid() && self.return_target.is_finite() {
                let traj =
                    Trajectory::plan(self.profile.position, 0.0, self.return_target, lim, Shape::Linear);
                self.ret = Some((traj, 0.0));
            } else {
                // Parameters changed to unusable ones: stay where we are.
                self.return_pending = false;
            }
        }
        let Some((traj, t)) = &mut self.ret else { return self.profile.step(accel, dt) };
        *t += dt;
        let (position, velocity, acceleration) = traj.at(*t);
        if *t >= traj.duration() {
            self.ret = None;
            self.return_pending = false;
        }
        // Keep the velocity profile in step, so a halt decelerates from here.
        self.profile.position = position;
        self.profile.velocity = velocity;
        HomingCommand::Position { position, velocity, acceleration }
    }

    fn start(&mut self, config: &HomingConfig, ctx: &HomingContext<'_>) -> Option<MethodStep> {
        self.method = config.method;
        self.return_pending = false;
        self.ret = None;
        if !config.is_valid() {
            self.state = HomingState::Error(HomingError::InvalidParameters);
            return None;
        }
        match self.registry.get_mut(config.method) {
            Some(m) => {
                self.state = HomingState::Running;
                Some(m.begin(ctx))
            }
            None => {
                self.state = HomingState::Error(HomingError::UnsupportedMethod);
                None
            }
        }
    }

    fn sync(&mut self, position: f64) {
        if position.is_finite() {
            self.profile.position = position;
        }
        self.profile.velocity = 0.0;
    }

    fn apply(&mut self, req: MethodStep, config: &HomingConfig, ctx: &HomingContext<'_>) -> Option<f64> {
        match req {
            MethodStep::Move(v) => {
                if self.torque.take().is_some() {
                    self.sync(ctx.position);
                }
                self.profile.target = if v.is_finite() { v } else { 0.0 };
                None
            }
            MethodStep::Torque(t) => {
                self.torque = Some(if t.is_finite() { t } else { 0.0 });
                self.profile.position = ctx.position;
                self.profile.velocity = 0.0;
                None
            }
            MethodStep::Found(reference) if reference.is_finite() => {
                self.state = HomingState::Attained;
                self.return_pending = self.return_to_home;
                if self.keep_position {
                    self.return_target = reference;
                    return None;
                }
                // CiA 402-2 homing mode: the home position gets the home offset,
                // so everything shifts by home offset − reference.
                let shift = config.home_offset - reference;
                self.profile.position += shift;
                self.return_target = config.home_offset;
                Some(ctx.position + shift)
            }
            MethodStep::Found(_) => {
                self.state = HomingState::Error(HomingError::InvalidParameters);
                None
            }
            MethodStep::Failed(e) => {
                self.state = HomingState::Error(e);
                if matches!(e, HomingError::SwitchNotFound | HomingError::IndexNotFound) {
                    // Blocked: stop demanding motion into the obstacle.
                    self.sync(ctx.position);
                }
                None
            }
        }
    }
}
