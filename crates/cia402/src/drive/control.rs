//! The control period: device control, the operating modes, stopping
//! reactions and the published values (supervision: `supervise.rs`).

use super::mode::{ModeCommand, ModeIo, op};
use super::pp::{PpIn, wrap};
use super::profile::{Limits, Ramp};
use super::{Drive, EmcyRequest};
use crate::model::Demand;
use crate::state_machine::{DriveFunction, Outcome, Reaction, State};
use core::f64::consts::PI;
use drivebus_od::ObjectDictionary;

/// A stopping reaction in progress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Stop {
    ramp: Ramp,
}

/// Error codes (CiA 402-2 / IEC 61800-7-201 Annex error code table).
pub(crate) mod code {
    /// Following error.
    pub const FOLLOWING_ERROR: u16 = 0x8611;
    /// Reference limit (limit switch reached, fault reaction configured).
    pub const LIMIT_SWITCH: u16 = 0x8612;
    /// Sync controller error (SYNC lost in a cyclic mode).
    pub const SYNC_LOST: u16 = 0x8700;
    /// Heartbeat / life guarding (CiA 301): raised by the node itself.
    pub const GUARDING: u16 = 0x8130;
}

/// The cyclic modes (a SYNC loss faults in them).
pub(super) const CYCLIC: [i8; 4] = [op::IP, op::CSP, op::CSV, op::CST];

impl Drive {
    /// A controlword arrived (SDO or RPDO): device control and the
    /// mode-specific edges, effective at once.
    pub(crate) fn controlword(&mut self, od: &mut ObjectDictionary, cw: u16) {
        if cw & 0x80 != 0 && self.cw & 0x80 == 0 {
            // Fault reset also resets a latched command error (iPOS: the
            // latched bits of 2000h are reset by Fault Reset), in any state.
            if let Some(c) = self.command_error.take() {
                self.emcy.push(EmcyRequest::Clear(c));
            }
        }
        self.cw = cw;
        self.pp.controlword(cw);
        let out = self.sm.controlword(cw);
        if out.fault_reset {
            self.fault_reset();
        }
        self.after_transition(out);
        self.publish(od);
    }

    /// 6060h written: CiA 402-2 §6.3 — a new mode takes effect at once,
    /// also while the drive function is enabled; 6061h follows.
    pub(crate) fn request_mode(&mut self, od: &mut ObjectDictionary, m: i8) {
        if m == self.mode {
            return;
        }
        if self.mode_active {
            self.exit_mode();
            self.mode = m;
            self.enter_mode(false);
        } else {
            self.mode = m;
        }
        self.publish(od);
    }

    /// Bookkeeping after any state machine input.
    pub(crate) fn after_transition(&mut self, out: Outcome) {
        if out.took(13) {
            let c = self.sm.fault_code();
            // 8130h belongs to the node's error control (it raised it).
            if c != code::GUARDING && c != 0 && !self.raised.contains(&c) {
                self.raised.push(c);
                self.emcy.push(EmcyRequest::Raise(c));
            }
        }
        if out.took(4) || out.took(16) {
            // Enabled again: the errors that only stopped the motor
            // (ErrorReaction::QuickStop) are over; a new stop reports anew.
            let actions = &self.fault_actions;
            let stopped =
                |c: &u16| actions.iter().any(|&(r, a)| r == *c && a == super::ErrorReaction::QuickStop);
            let emcy = &mut self.emcy;
            self.raised.retain(|c| {
                let keep = !stopped(c);
                if !keep {
                    emcy.push(EmcyRequest::Clear(*c));
                }
                keep
            });
        }
        if self.sm.drive_function() != DriveFunction::Enabled {
            // Target reached / acknowledge belong to the running mode.
            self.status_bits &= !(1 << 10 | 1 << 12);
        }
        self.sync_mode_activity();
    }

    fn sync_mode_activity(&mut self) {
        let enabled = self.sm.drive_function() == DriveFunction::Enabled;
        if enabled && !self.mode_active {
            self.enter_mode(true);
        } else if !enabled && self.mode_active {
            self.exit_mode();
        }
    }

    /// Fault reset (rising edge of controlword bit 7, transition 15):
    /// clears latched faults and their EMCYs; a persisting condition faults
    /// again at the next period.
    pub(crate) fn fault_reset(&mut self) {
        self.model.clear_faults();
        self.sup.fe_timer = 0.0;
        self.sup.fe_active = false;
        self.sup.force_following_error = false;
        self.sup.pending_fault = None;
        self.sup.sync_lost = false;
        self.error_warning = false;
        for c in self.raised.drain(..) {
            self.emcy.push(EmcyRequest::Clear(c));
        }
    }

    pub(super) fn actual_pos_f(&self) -> f64 {
        self.units.inc_to_pos_f(self.model.position_counts() as f64 + self.inc_offset_f())
    }

    fn actual_vel_frame(&self) -> f64 {
        self.units.inc_to_pos_f(self.units.rad_to_inc(self.model.velocity_measured()))
    }

    /// The torque demand's limit \[‰\]: 6072h max torque and 6073h max
    /// current (‰ of rated current, the torque's share of it).
    fn torque_limit(&self) -> f64 {
        f64::from(self.params.max_torque.min(self.extra.max_current))
    }

    fn torque_per_mille(&self, nm: f64) -> f64 {
        nm / (f64::from(self.extra.rated_torque) / 1000.0) * 1000.0
    }

    pub(crate) fn enter_mode(&mut self, from_disabled: bool) {
        if from_disabled {
            self.dem.pos = self.actual_pos_f();
            self.dem.vel = 0.0;
            self.dem.acc = 0.0;
        }
        self.stop = None;
        self.pp.reset(self.dem.pos);
        self.vel_ramp = Ramp { value: self.dem.vel, rate: 0.0 };
        self.torque_ramp = Ramp { value: self.torque_per_mille(self.model.torque()), rate: 0.0 };
        self.window_timer = 0.0;
        self.threshold_timer = 0.0;
        self.mode_active = true;
        let mode = self.mode;
        self.with_handler(|h, io| h.enter(mode, io));
    }

    pub(crate) fn exit_mode(&mut self) {
        self.mode_active = false;
        let mode = self.mode;
        let bit = op::supported_bit(mode);
        if let Some(h) = self.handlers.iter_mut().find(|h| h.supported_modes() & bit != 0) {
            h.exit(mode);
        }
        self.clear_mode_warning();
    }

    /// The handler's warning is over (or its mode left): bit 7 drops and
    /// the EMCYs it raised are cleared (CiA 301 error reset).
    fn clear_mode_warning(&mut self) {
        self.mode_warning = false;
        for c in self.mode_emcy.drain(..) {
            self.emcy.push(EmcyRequest::Clear(c));
        }
    }

    /// The snapshot a handler sees now.
    fn mode_io(&self) -> ModeIo<'_> {
        ModeIo {
            controlword: self.cw,
            position: self.position(),
            position_inc: self.position_increments(),
            inc_offset: self.inc_offset,
            velocity: self.actual_vel_frame(),
            torque: self.torque_per_mille(self.model.torque()),
            demand_position: self.dem.pos,
            demand_velocity: self.dem.vel,
            events: &self.events,
            switches: self.model.switches(),
            master_position: self.model.master_position(),
            master_velocity: self.model.master_velocity(),
            params: &self.params,
            units: &self.units,
            dt: self.dt,
            time: self.steps as f64 * self.dt,
        }
    }

    /// Calls `f` with the handler of the active mode and the snapshot
    /// (`None` without one). The handlers are moved out for the call (no
    /// allocation) so the snapshot can borrow the drive.
    fn with_handler<R>(
        &mut self,
        f: impl FnOnce(&mut (dyn super::ModeHandler + Send), &ModeIo<'_>) -> R,
    ) -> Option<R> {
        let bit = op::supported_bit(self.mode);
        let mut hs = core::mem::take(&mut self.handlers);
        let r = match hs.iter_mut().find(|h| h.supported_modes() & bit != 0) {
            Some(h) => {
                let io = self.mode_io();
                Some(f(&mut **h, &io))
            }
            None => None,
        };
        self.handlers = hs;
        r
    }

    /// Whether the active mode's handler supervises the following error.
    pub(super) fn handler_owns_following_error(&self) -> bool {
        let bit = op::supported_bit(self.mode);
        self.handlers
            .iter()
            .find(|h| h.supported_modes() & bit != 0)
            .is_some_and(|h| h.owns_following_error(self.mode))
    }

    /// SYNC: let a cyclic handler latch its set-points.
    pub(crate) fn handler_sync(&mut self, od: &mut ObjectDictionary) {
        let _ = od;
        if !self.mode_active {
            return;
        }
        let mode = self.mode;
        self.with_handler(|h, io| h.on_sync(mode, io));
    }

    /// Position-frame demand → model command.
    pub(super) fn position_command(&self, p: f64, v: f64, a: f64) -> Demand {
        let u = &self.units;
        Demand::Position {
            position: u.inc_to_rad(u.pos_to_inc_f(p) - self.inc_offset_f()),
            velocity: u.pos_to_rad(v),
            acceleration: u.pos_to_rad(a),
        }
    }

    fn velocity_command(&self, v: f64, a: f64) -> Demand {
        Demand::Velocity { velocity: self.units.pos_to_rad(v), acceleration: self.units.pos_to_rad(a) }
    }

    /// Profile limits in position units: 6081h ≤ 607Fh ≤ 6080h, ramps ≤ 60C5h/60C6h.
    fn pp_limits(&self) -> Limits {
        let p = &self.params;
        let u = &self.units;
        let v = self.extra.profile_velocity.min(p.max_profile_velocity).min(p.max_motor_speed);
        Limits {
            velocity: u.vel_to_pos(f64::from(v)),
            acceleration: u.acc_to_pos(f64::from(p.profile_acceleration.min(p.max_acceleration))),
            deceleration: u.acc_to_pos(f64::from(p.profile_deceleration.min(p.max_deceleration))),
        }
    }

    /// The jerk of the jerk-limited ramp in position units/s³ for the
    /// limits `lim` in force; `None` (linear ramp) for a zero jerk.
    fn pp_jerk(&self, lim: &Limits) -> Option<super::profile::Jerk> {
        let j = match self.jerk {
            super::ProfileJerk::Rate { acceleration, deceleration } => super::profile::Jerk {
                acceleration: self.units.acc_to_pos(f64::from(acceleration)),
                deceleration: self.units.acc_to_pos(f64::from(deceleration)),
            },
            super::ProfileJerk::Time(t) => super::profile::Jerk {
                acceleration: lim.acceleration / t,
                deceleration: lim.deceleration / t,
            },
        };
        j.valid().then_some(j)
    }

    /// A pp set-point was refused (S-curve with change set immediately):
    /// warning bit 7 and the configured EMCY, latched until a fault reset.
    fn command_error_raised(&mut self) {
        if let Some(c) = self.cfg.scurve_forbids_change_immediately
            && self.command_error.is_none()
        {
            self.command_error = Some(c);
            self.emcy.push(EmcyRequest::Raise(c));
        }
    }

    fn halt_deceleration(&self) -> f64 {
        let p = &self.params;
        let dec = match self.sm.options().halt_reaction() {
            Reaction::SlowDownRamp => p.profile_deceleration,
            // 605Dh 2–4: the quick-stop ramp (current/voltage limit braking
            // is approximated by it in the halt function).
            _ => p.quick_stop_deceleration,
        };
        // A zero 6084h cannot stop the axis: the quick-stop ramp does.
        let dec = if dec == 0 { p.quick_stop_deceleration } else { dec };
        self.units.acc_to_pos(f64::from(dec))
    }

    /// One control period.
    pub(crate) fn control_step(&mut self, od: &mut ObjectDictionary) {
        let _ = od;
        self.steps = self.steps.wrapping_add(1);
        self.sync_mode_activity();
        let f = self.sm.drive_function();
        self.command_brake(f);
        let cmd = match self.brake_hold(f) {
            Some(hold) => hold,
            None => self.function_command(f),
        };
        self.model.set_demand(cmd);
        self.model.step(self.dt);
        self.events.clone_from(self.model.events());
        for i in 0..self.events.len() {
            let e = self.events.as_slice()[i];
            let inc = e.counts.saturating_add(self.inc_offset);
            self.probe.on_event(&e, self.units.inc_frac_to_pos(inc, self.inc_frac));
        }
        if self.probe.dedicated_pending() {
            self.probe.sample_dedicated(self.position());
        }
        self.supervise();
        if let DriveFunction::Stopping(_) = self.sm.drive_function() {
            let still = self.model.velocity().abs() < 0.01 * self.model.params().motor.max_speed;
            let ramp_done = self.stop.is_none_or(|s| s.ramp.value == 0.0);
            if still && ramp_done {
                let out = self.sm.motion_stopped();
                self.after_transition(out);
            }
        }
    }

    /// The power stage's command for the drive function.
    fn function_command(&mut self, f: DriveFunction) -> Demand {
        match f {
            DriveFunction::Disabled => {
                self.stop = None;
                self.dem.pos = self.actual_pos_f();
                self.dem.vel = self.actual_vel_frame();
                self.dem.acc = 0.0;
                self.dem.torque = 0.0;
                self.status_bits = 0;
                Demand::Off
            }
            DriveFunction::Enabled => self.mode_step(),
            DriveFunction::Stopping(r) => self.stop_step(r),
            DriveFunction::Holding => {
                // CiA 402-2 statusword bit 10: with quick stop option codes
                // 5–8 "target reached" is set once the drive has stopped.
                self.status_bits |= 1 << 10;
                self.dem.vel = 0.0;
                self.position_command(self.dem.pos, 0.0, 0.0)
            }
        }
    }

    fn mode_step(&mut self) -> Demand {
        let dt = self.dt;
        self.stop = None;
        let mode = self.mode;
        let actual_vel = self.actual_vel_frame();
        let torque_now = self.torque_per_mille(self.model.torque());
        match mode {
            op::PP => {
                let by_window = self.cfg.target_reached == super::TargetReached::ActualInWindow;
                let running_reached = by_window
                    && self.pp.moving
                    && (self.actual_pos_f() - self.pp.target).abs() <= f64::from(self.params.position_window);
                let shape = self.shape();
                let lim = self.pp_limits();
                let pin = PpIn {
                    running_reached,
                    cw: self.cw,
                    target_raw: self.params.target_position,
                    lim,
                    shape,
                    acc: self.dem.acc,
                    // Only the S-curve needs the jerk (linear path untouched).
                    jerk: if shape == super::profile::Shape::JerkLimited { self.pp_jerk(&lim) } else { None },
                    forbid_change_immediately: self.cfg.scurve_forbids_change_immediately.is_some(),
                    halt_dec: self.halt_deceleration(),
                    soft_limits: self.params.software_limits,
                    range: self.params.position_range,
                    rado: self.rado,
                    dt,
                };
                let (p, v, a) = self.pp.step(&pin, self.dem.pos, self.dem.vel);
                if self.pp.rejected {
                    self.pp.rejected = false;
                    self.command_error_raised();
                }
                (self.dem.pos, self.dem.vel, self.dem.acc) = (p, v, a);
                self.dem.torque = torque_now;
                let reached = if self.pp.halted {
                    v == 0.0
                } else if by_window && self.pp.buffered.is_none() {
                    self.in_window(self.pp.target)
                } else if self.pp.moving || self.pp.buffered.is_some() {
                    self.window_timer = 0.0;
                    false
                } else {
                    self.in_window(self.pp.target)
                };
                self.status_bits = u16::from(reached) << 10
                    | u16::from(self.pp.limited) << 11
                    | u16::from(self.pp.ack) << 12
                    | u16::from(self.sup.fe_active) << 13;
                self.position_command(p, v, a)
            }
            op::PV => {
                let u = self.units;
                let p = &self.params;
                let vmax = u.vel_to_pos(f64::from(p.max_motor_speed));
                let mut target = u.velocity_to_frame(f64::from(p.target_velocity)).clamp(-vmax, vmax);
                let halted = self.cw & 0x100 != 0;
                let blocked = self.sup.limit_block != 0 && target * f64::from(self.sup.limit_block) > 0.0;
                if halted || blocked {
                    target = 0.0;
                }
                // A zero 6083h/6084h refuses the motion: the target is 0,
                // reached on the quick-stop ramp.
                let zero_ramp = p.profile_acceleration == 0 || p.profile_deceleration == 0;
                if zero_ramp {
                    target = 0.0;
                }
                let (up, down) = if halted || blocked || zero_ramp {
                    let d = if blocked || (zero_ramp && !halted) {
                        u.acc_to_pos(f64::from(p.quick_stop_deceleration))
                    } else {
                        self.halt_deceleration()
                    };
                    (d, d)
                } else {
                    (
                        u.acc_to_pos(f64::from(p.profile_acceleration)),
                        u.acc_to_pos(f64::from(p.profile_deceleration)),
                    )
                };
                let v = self.vel_ramp.step(target, up, down, dt);
                self.dem.vel = v;
                self.dem.acc = self.vel_ramp.rate;
                self.dem.pos = self.actual_pos_f();
                self.dem.torque = torque_now;
                // Bit 10: |v_actual − v_target| ≤ 606Dh for 606Eh (halt: v = 0).
                let win = u.vel_to_pos(f64::from(self.extra.velocity_window));
                let profile_done =
                    v == target || self.cfg.target_reached == super::TargetReached::ActualInWindow;
                let reached = if (actual_vel - target).abs() <= win && profile_done {
                    self.window_timer += dt;
                    self.window_timer * 1000.0 + 1e-9 >= f64::from(self.extra.velocity_window_time)
                } else {
                    self.window_timer = 0.0;
                    false
                };
                // Bit 12: speed = 0, |v_actual| ≤ 606Fh for 6070h (CiA 402-2 §6.9).
                let thr = u.vel_to_pos(f64::from(self.extra.velocity_threshold));
                let zero = if actual_vel.abs() <= thr {
                    self.threshold_timer += dt;
                    self.threshold_timer * 1000.0 + 1e-9 >= f64::from(self.extra.velocity_threshold_time)
                } else {
                    self.threshold_timer = 0.0;
                    false
                };
                self.status_bits = u16::from(reached) << 10 | u16::from(zero) << 12;
                self.velocity_command(v, self.dem.acc)
            }
            op::TQ => {
                let p = &self.params;
                let lim = self.torque_limit();
                // A zero 6087h refuses torque motion (as a zero ramp does in
                // pp/pv): the demand is 0.
                let refused = self.extra.torque_slope == 0;
                let target = if self.cw & 0x100 != 0 || refused {
                    0.0
                } else {
                    f64::from(p.target_torque).clamp(-lim, lim)
                };
                let slope = f64::from(self.extra.torque_slope);
                let t = self.torque_ramp.step(target, slope, slope, dt);
                self.dem.torque = t;
                self.dem.pos = self.actual_pos_f();
                self.dem.vel = actual_vel;
                self.status_bits = u16::from(t == target) << 10;
                Demand::Torque(t / 1000.0 * f64::from(self.extra.rated_torque) / 1000.0)
            }
            op::VL => {
                let x = &self.extra;
                let mut target = f64::from(x.vl_target);
                if target != 0.0 {
                    // 6046h: the amount is held between min and max.
                    let a = target.abs().clamp(f64::from(x.vl_min), f64::from(x.vl_max.max(x.vl_min)));
                    target = a.copysign(target);
                }
                if self.cw & 0x100 != 0 {
                    target = 0.0;
                }
                let up = f64::from(x.vl_acc.0) / f64::from(x.vl_acc.1.max(1));
                let down = f64::from(x.vl_dec.0) / f64::from(x.vl_dec.1.max(1));
                let rpm = self.vel_ramp.step(target, up, down, dt);
                let rad = rpm * 2.0 * PI / 60.0;
                self.dem.vel = self.units.rad_to_pos(rad);
                self.dem.pos = self.actual_pos_f();
                self.dem.torque = torque_now;
                self.status_bits = 0;
                Demand::Velocity { velocity: rad, acceleration: self.vel_ramp.rate * 2.0 * PI / 60.0 }
            }
            _ => self.handler_step(),
        }
    }

    /// Position window 6067h/6068h around `target` → bit 10.
    fn in_window(&mut self, target: f64) -> bool {
        let w = self.params.position_window;
        if w == u32::MAX {
            return true;
        }
        if (self.actual_pos_f() - target).abs() > f64::from(w) {
            self.window_timer = 0.0;
            return false;
        }
        self.window_timer += self.dt;
        self.window_timer * 1000.0 + 1e-9 >= f64::from(self.params.position_window_time)
    }

    fn handler_step(&mut self) -> Demand {
        let mode = self.mode;
        let (pos, inc) = (self.position(), self.position_increments());
        let vel = self.actual_vel_frame();
        let torque = self.torque_per_mille(self.model.torque());
        let dt = self.dt;
        let Some(mut out) = self.with_handler(|h, io| h.step(mode, io, dt)) else {
            self.status_bits = 0;
            self.dem.vel = 0.0;
            return self.position_command(self.dem.pos, 0.0, 0.0);
        };
        let finite = match out.command {
            ModeCommand::Position { position, velocity, acceleration } => {
                position.is_finite() && velocity.is_finite() && acceleration.is_finite()
            }
            ModeCommand::Velocity { velocity, acceleration } => {
                velocity.is_finite() && acceleration.is_finite()
            }
            ModeCommand::Torque(t) => t.is_finite(),
            ModeCommand::Hold => true,
        };
        if !finite {
            // A broken set-point never reaches the motor: hold instead.
            out.command = ModeCommand::Hold;
        }
        if let Some(r) = out.position_reset {
            // Shift the reference so the actual position reads `r`; the
            // demand moves with it (no motion). The shift keeps its part of
            // an increment: `r` is exact even in units finer than the
            // encoder (CiA 402-2 homing: home position = 607Ch).
            let (want, frac) = self.units.pos_to_inc_exact(r);
            let delta_pos = r as f64 - pos as f64;
            self.inc_offset = self.inc_offset.saturating_add(want.saturating_sub(inc));
            self.inc_frac = frac;
            self.dem.pos += delta_pos;
        }
        if let Some(c) = out.fault {
            self.sup.pending_fault = Some(c);
        }
        // CiA 402-2 §6.2.2: bits 10–13 are the mode's; the drive adds
        // nothing of its own here (its following error shows as the fault).
        self.status_bits = out.status & super::ModeOutput::STATUS_MASK;
        if let Some(c) = out.emcy
            && !self.mode_emcy.contains(&c)
        {
            self.mode_emcy.push(c);
            self.emcy.push(EmcyRequest::Raise(c));
        }
        if out.warning {
            self.mode_warning = true;
        } else if self.mode_warning || !self.mode_emcy.is_empty() {
            self.clear_mode_warning();
        }
        // 60B2h torque offset as feed-forward: the acceleration that takes
        // that torque on the total inertia (the loops add J·a / kₜ).
        let t_ff = if out.torque_offset.is_finite() { out.torque_offset } else { 0.0 };
        let acc_ff_rad = t_ff / 1000.0 * f64::from(self.extra.rated_torque) / 1000.0 / self.model.inertia();
        match out.command {
            ModeCommand::Position { position, velocity, acceleration } => {
                (self.dem.pos, self.dem.vel, self.dem.acc) = (position, velocity, acceleration);
                self.dem.torque = torque;
                let mut c = self.position_command(position, velocity, acceleration);
                if let Demand::Position { acceleration, .. } = &mut c {
                    *acceleration += acc_ff_rad;
                }
                c
            }
            ModeCommand::Velocity { velocity, acceleration } => {
                self.dem.vel = velocity;
                self.dem.acc = acceleration;
                self.dem.pos = self.actual_pos_f();
                self.dem.torque = torque;
                let mut c = self.velocity_command(velocity, acceleration);
                if let Demand::Velocity { acceleration, .. } = &mut c {
                    *acceleration += acc_ff_rad;
                }
                c
            }
            ModeCommand::Torque(t) => {
                let lim = self.torque_limit();
                let t = if t.is_finite() { t.clamp(-lim, lim) } else { 0.0 };
                self.dem.torque = t;
                self.dem.pos = self.actual_pos_f();
                self.dem.vel = vel;
                Demand::Torque(t / 1000.0 * f64::from(self.extra.rated_torque) / 1000.0)
            }
            ModeCommand::Hold => {
                self.dem.vel = 0.0;
                self.dem.acc = 0.0;
                self.position_command(self.dem.pos, 0.0, 0.0)
            }
        }
    }

    /// Executes a stopping reaction (CiA 402-2 §6.2: 605Ah–605Eh codings).
    fn stop_step(&mut self, r: Reaction) -> Demand {
        if self.stop.is_none() {
            // Position-controlled modes ramp from their demand; velocity and
            // torque modes from the measured speed.
            let v0 = if matches!(self.mode, op::PP | op::HM | op::IP | op::CSP) {
                self.dem.vel
            } else {
                self.dem.pos = self.actual_pos_f();
                self.actual_vel_frame()
            };
            self.stop = Some(Stop { ramp: Ramp { value: v0, rate: 0.0 } });
        }
        self.status_bits &= !(1 << 10 | 1 << 12);
        let p = &self.params;
        let dec = match r {
            Reaction::SlowDownRamp => p.profile_deceleration,
            Reaction::QuickStopRamp => p.quick_stop_deceleration,
            Reaction::CurrentLimit => {
                self.dem.pos = self.actual_pos_f();
                self.dem.vel = 0.0;
                if let Some(s) = &mut self.stop {
                    s.ramp.value = 0.0;
                }
                return Demand::Velocity { velocity: 0.0, acceleration: 0.0 };
            }
            Reaction::VoltageLimit => {
                self.dem.pos = self.actual_pos_f();
                self.dem.vel = 0.0;
                if let Some(s) = &mut self.stop {
                    s.ramp.value = 0.0;
                }
                return Demand::ShortCircuit;
            }
            Reaction::DisableDrive => return Demand::Off,
        };
        let dec = self.units.acc_to_pos(f64::from(dec));
        let dt = self.dt;
        let Some(s) = &mut self.stop else { return Demand::Off };
        let v0 = s.ramp.value;
        let v = s.ramp.step(0.0, dec, dec, dt);
        self.dem.pos += (v0 + v) / 2.0 * dt;
        self.dem.vel = v;
        self.dem.acc = s.ramp.rate;
        self.position_command(self.dem.pos, v, self.dem.acc)
    }

    /// Statusword 6041h (CiA 402-2 §6.2.2); a personality patches the
    /// manufacturer bits 8/14/15 after each step.
    pub(crate) fn statusword_value(&self) -> u16 {
        self.base_statusword()
    }

    /// 60FDh digital inputs as published.
    pub(crate) fn digital_inputs(&self) -> u32 {
        self.model.switches().digital_inputs() | u32::from(self.interlock) << 3 | self.input_lines()
    }

    /// The statusword as the drive computes it.
    pub(crate) fn base_statusword(&self) -> u16 {
        let mut sw = self.sm.statusword();
        let warned = self.warning || self.mode_warning || self.error_warning;
        sw |= u16::from(warned || self.command_error.is_some()) << 7;
        sw |= u16::from(self.cfg.remote) << 9;
        if matches!(self.sm.state(), State::OperationEnabled | State::QuickStopActive) {
            sw |= self.status_bits & 0x3C00;
        }
        sw |= u16::from(self.limit_active) << 11;
        sw
    }

    /// Pushes the live values into the dictionary.
    pub(crate) fn publish(&mut self, od: &mut ObjectDictionary) {
        if self.refs.is_none_or(|r| r.objects != od.objects().len()) {
            // An object was inserted after install: handles moved.
            self.refs = super::objects::Refs::resolve(od);
        }
        if self.refs.is_none() {
            return;
        }
        // 6061h shows a manufacturer mode while its stand-in runs.
        let shown = self.mode_shown();
        let Some(r) = &self.refs else { return };
        let sw = self.statusword_value();
        let inc = self.position_increments();
        let pos = self.units.inc_frac_to_pos(inc, self.inc_frac);
        let (lo, hi) = self.params.position_range;
        let pos_shown = if lo < hi { wrap(pos as f64, lo, hi) as i64 } else { pos };
        let vel_act = self.units.frame_to_velocity(self.actual_vel_frame());
        let vel_dem = self.units.frame_to_velocity(self.dem.vel);
        let rated_i = f64::from(self.extra.rated_current) / 1000.0;
        let i32s = |x: f64| {
            if x.is_finite() {
                super::units::round(x).clamp(i32::MIN as f64, i32::MAX as f64) as i32
            } else {
                0
            }
        };
        let i16s =
            |x: f64| if x.is_finite() { super::units::round(x).clamp(-32768.0, 32767.0) as i16 } else { 0 };
        // Objects the device lacks are not published (`withdraw_object`).
        let put = |od: &mut ObjectDictionary, r: Option<drivebus_od::EntryRef>, b: &[u8]| {
            if let Some(r) = r {
                od.set_le(r, b);
            }
        };
        put(od, r.statusword, &sw.to_le_bytes());
        put(od, r.error_code, &self.sm.fault_code().to_le_bytes());
        put(od, r.mode_display, &shown.to_le_bytes());
        put(od, r.pos_demand, &i32s(self.dem.pos).to_le_bytes());
        put(od, r.pos_internal, &(inc as i32).to_le_bytes());
        put(od, r.pos_actual, &(pos_shown as i32).to_le_bytes());
        put(od, r.vel_demand, &i32s(vel_dem).to_le_bytes());
        put(od, r.vel_actual, &i32s(vel_act).to_le_bytes());
        put(od, r.torque_demand, &i16s(self.dem.torque).to_le_bytes());
        put(od, r.torque_actual, &i16s(self.torque_per_mille(self.model.torque())).to_le_bytes());
        put(od, r.current_actual, &i16s(self.model.current() / rated_i * 1000.0).to_le_bytes());
        let mv = (self.model.bus_voltage() * 1000.0).clamp(0.0, f64::from(u32::MAX)) as u32;
        put(od, r.dc_link, &mv.to_le_bytes());
        put(od, r.following_error, &i32s(self.dem.pos - pos as f64).to_le_bytes());
        let di = self.digital_inputs();
        put(od, r.inputs, &di.to_le_bytes());
        put(od, r.probe_status, &self.probe.status.to_le_bytes());
        for k in 0..4 {
            put(od, r.probe_pos[k], &self.probe.pos[k].to_le_bytes());
        }
        if let (Some(d), Some(a)) = (r.vl_demand, r.vl_actual) {
            let rpm_act = self.model.velocity_measured() * 60.0 / (2.0 * PI);
            let rpm_dem = if self.mode == op::VL { self.vel_ramp.value } else { 0.0 };
            od.set_le(d, &i16s(rpm_dem).to_le_bytes());
            od.set_le(a, &i16s(rpm_act).to_le_bytes());
        }
    }
}
