//! The CiA 402 drive: object dictionary binding, device control, profile
//! modes, units, I/O and faults.
//!
//! [`Drive::install`] inserts the CiA 402 objects (one entry each in
//! `table.rs`: definition, write check, apply) into a [`Node`]'s
//! dictionary, each writable sub-object owned by its entry; the drive is
//! then the node's [`Application`]: the node hands it the writes of the
//! objects it owns, it steps the [`DriveModel`] at its control rate in
//! [`Application::poll`] and pushes the live values (statusword, actual
//! values) with `set_le` through handles resolved once. Its EMCY requests
//! go to the node as [`drivebus_node::Request`]s.
//! `drivebus_node::NodeDevice<Drive>` is node and drive as one device.
//!
//! ```
//! use drivebus_cia402::drive::{Drive, generic_drive};
//! use drivebus_bus::{Bus, BusConfig};
//! use drivebus_can::Duration;
//! use drivebus_node::NodeDevice;
//!
//! let mut bus = Bus::new(BusConfig::zero_time());
//! let id = bus.attach(generic_drive(3));
//! bus.run_for(Duration::from_millis(1));
//! let dn = bus.node::<NodeDevice<Drive>>(id).unwrap();
//! assert_eq!(dn.app.statusword() & 0x4F, 0x40); // switch on disabled
//! ```

mod brake;
mod checks;
mod config;
mod control;
mod fieldbus;
mod generic;
pub mod mode;
mod objects;
mod pp;
pub mod profile;
mod settings;
mod supervise;
mod table;
mod tuning;
pub mod units;

#[cfg(test)]
mod tests;

pub use brake::BrakeControl;
pub use config::{
    BrakeDelays, DriveConfig, IoConfig, LimitSwitchReaction, ProbeInput, ProfileDefaults, ProfileJerk,
    TargetReached, ZeroMeansOff, ZeroRamp, profile_type,
};
pub use generic::{default_pdo_mapping, generic_drive, generic_drive_with};
pub use mode::{ModeCommand, ModeHandler, ModeIo, ModeOutput, ModeParams, op};
pub use units::{Carry, FactorGroup, Ratio, Scaling, Units};

use crate::model::{DriveModel, ParamError, StepEvents};
use crate::state_machine::StateMachine;
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_can::{Duration, Instant, LinkState};
use drivebus_node::{AppContext, Application, Node, NodeEvent, Request};
use drivebus_od::{ObjectDictionary, SdoAbort, Target, WriteOutcome};
use objects::Refs;
use profile::{Ramp, Shape};

/// Fault injections on the drive (test and demo scenarios).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Injection {
    /// A model-level condition (over-current, temperature, DC link, encoder,
    /// load torque step, clear).
    Model(crate::model::ModelInjection),
    /// A following error: the next control periods see the window exceeded
    /// (as if the load blocked), raising 8611h after 6066h.
    FollowingError,
    /// A fault with an arbitrary error code (603Fh / EMCY).
    Fault(u16),
    /// Connection to the master lost: executes 6007h (as on a heartbeat loss).
    ConnectionLost,
}

/// What the drive does on a fault of one code instead of 605Eh's (or
/// 6007h's) reaction: a manufacturer's per-error option code (Technosoft
/// iPOS 2113h/2114h, 605Eh −1 "no action" for its non-fatal errors).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorReaction {
    /// Signal it (EMCY while the condition lasts) and go on.
    NoAction,
    /// EMCY and statusword bit 7 (warning) until a fault reset; the motion
    /// goes on (LAM DDS6 §5 class 0).
    Warning,
    /// EMCY and a quick stop from Operation enabled (605Ah decides where it
    /// ends), no fault; over when Operation enabled is entered again or at
    /// a fault reset (LAM DDS6 §5 class 2).
    QuickStop,
    /// Fault with this reaction.
    React(crate::state_machine::Reaction),
}

/// An EMCY the drive asks for (603Fh codes); [`Drive::flush_emcy`] turns
/// them into the node's [`Request`]s at the end of every callback.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EmcyRequest {
    /// Raise an error code (1001h, 1003h, EMCY frame).
    Raise(u16),
    /// The error went away.
    Clear(u16),
}

/// Profile and I/O parameters the drive keeps besides [`ModeParams`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Extra {
    pub profile_velocity: u32,
    pub end_velocity: u32,
    pub profile_type: i16,
    pub torque_slope: u32,
    pub velocity_window: u16,
    pub velocity_window_time: u16,
    pub velocity_threshold: u16,
    pub velocity_threshold_time: u16,
    pub max_current: u16,
    pub rated_current: u32,
    pub rated_torque: u32,
    pub probe_function: u16,
    pub outputs: u32,
    pub output_mask: u32,
    pub vl_target: i16,
    pub vl_min: u32,
    pub vl_max: u32,
    pub vl_acc: (u32, u16),
    pub vl_dec: (u32, u16),
}

/// The set-point state shared by the modes (position units).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Demand {
    pub pos: f64,
    pub vel: f64,
    pub acc: f64,
    /// Torque demand \[per mille of rated torque\].
    pub torque: f64,
}

/// A CiA 402 drive: device control, pp/pv/tq/vl, factor group, I/O, touch
/// probe, faults, and plug-in modes through [`ModeHandler`].
pub struct Drive {
    cfg: DriveConfig,
    model: DriveModel,
    sm: StateMachine,
    units: Units,
    factor: FactorGroup,
    params: ModeParams,
    extra: Extra,
    refs: Option<Refs>,
    /// The drive's objects the device does not have ([`Drive::withdraw_object`]):
    /// their parameters keep the drive's own values here.
    withdrawn: ObjectDictionary,
    handlers: Vec<Box<dyn ModeHandler + Send>>,
    modes: u32,
    // time
    dt: f64,
    period: Duration,
    next: Option<Instant>,
    steps: u64,
    // control
    cw: u16,
    mode: i8,
    mode_active: bool,
    dem: Demand,
    inc_offset: i64,
    /// The part of an increment the reference shift adds beyond
    /// `inc_offset`, as `Units::pos_to_inc_exact` gives it: a home position
    /// is exact in position units finer than an increment.
    inc_frac: i128,
    pp: pp::Pp,
    vel_ramp: Ramp,
    torque_ramp: Ramp,
    stop: Option<control::Stop>,
    window_timer: f64,
    threshold_timer: f64,
    status_bits: u16,
    warning: bool,
    limit_active: bool,
    /// The manufacturer mode selected (negative 6060h) and its stand-in.
    manufacturer: Option<(i8, i8)>,
    // supervision
    sup: supervise::Supervision,
    emcy: Vec<EmcyRequest>,
    raised: Vec<u16>,
    probe: supervise::Probe,
    events: StepEvents,
    interlock: bool,
    /// The limit-switch function is off (inputs still read in 60FDh).
    limit_switches_off: bool,
    /// 60F2h rado: how pp reaches a target on a modulo axis.
    rado: pp::Rado,
    /// Per-code fault actions ([`Drive::set_fault_action`]).
    fault_actions: Vec<(u16, ErrorReaction)>,
    /// A fault taken with [`ErrorReaction::NoAction`] whose condition lasts.
    ignored_fault: Option<u16>,
    /// NMT operational (for [`DriveView::operational`]).
    operational: bool,
    /// The active handler's warning (statusword bit 7).
    mode_warning: bool,
    /// EMCY codes the active handler raised, cleared with its warning.
    mode_emcy: Vec<u16>,
    /// The jerk of the jerk-limited ramp in force.
    jerk: ProfileJerk,
    /// A pp set-point refused by
    /// [`DriveConfig::scurve_forbids_change_immediately`]: its EMCY code,
    /// latched (statusword bit 7) until a fault reset.
    command_error: Option<u16>,
    /// A fault with [`ErrorReaction::Warning`] was raised (statusword bit 7
    /// until a fault reset).
    error_warning: bool,
    /// Who commands the holding brake.
    brake_control: BrakeControl,
    /// Output lines a personality's objects set.
    app_outputs: u16,
}

impl Drive {
    /// Builds the drive, inserts its objects into `node` and resolves the
    /// handles of its live values. Fails on invalid model parameters (or a
    /// control rate outside 4–16 kHz).
    pub fn install(node: &mut Node, cfg: DriveConfig) -> Result<Drive, ParamError> {
        Drive::install_with(node, cfg, Vec::new())
    }

    /// [`Drive::install`] with mode handlers for hm, ip, csp, csv, cst;
    /// their modes are added to 6502h.
    pub fn install_with(
        node: &mut Node,
        mut cfg: DriveConfig,
        handlers: Vec<Box<dyn ModeHandler + Send>>,
    ) -> Result<Drive, ParamError> {
        if !(4000.0..=16000.0).contains(&cfg.control_rate_hz) {
            return Err(ParamError { field: "control_rate_hz", reason: "outside 4–16 kHz" });
        }
        cfg.params.control.control_rate_hz = cfg.control_rate_hz;
        // 608Fh:1 is the physical encoder (read-only): the model's counts.
        cfg.factor.encoder = (cfg.params.encoder.counts_per_rev, 1);
        let model = DriveModel::new(cfg.params)?;
        let units = Units::new(&cfg.factor).ok_or(ParamError { field: "factor", reason: "zero ratio" })?;
        let own = cfg.modes
            & (op::supported_bit(op::PP)
                | op::supported_bit(op::VL)
                | op::supported_bit(op::PV)
                | op::supported_bit(op::TQ));
        let modes = handlers.iter().fold(own, |m, h| m | h.supported_modes());
        node.insert_objects(objects::objects(&cfg, modes));
        let dt = 1.0 / cfg.control_rate_hz;
        let period = Duration::from_nanos((1e9 / cfg.control_rate_hz) as u64);
        let mut d = Drive {
            sm: StateMachine::new(cfg.options),
            factor: cfg.factor,
            model,
            units,
            params: ModeParams::default(),
            extra: Extra::default(),
            refs: None,
            withdrawn: ObjectDictionary::new(),
            handlers,
            modes,
            dt,
            period,
            next: None,
            steps: 0,
            cw: 0,
            mode: 0,
            mode_active: false,
            manufacturer: None,
            dem: Demand::default(),
            inc_offset: 0,
            inc_frac: 0,
            pp: pp::Pp::default(),
            vel_ramp: Ramp::default(),
            torque_ramp: Ramp::default(),
            stop: None,
            window_timer: 0.0,
            threshold_timer: 0.0,
            status_bits: 0,
            warning: false,
            limit_active: false,
            sup: supervise::Supervision::default(),
            emcy: Vec::with_capacity(8),
            raised: Vec::with_capacity(8),
            probe: supervise::Probe::new(cfg.io.probe_inputs, cfg.io.probe_source_object),
            events: StepEvents::default(),
            interlock: false,
            limit_switches_off: false,
            rado: pp::Rado::Shortest,
            fault_actions: Vec::new(),
            ignored_fault: None,
            operational: false,
            mode_warning: false,
            mode_emcy: Vec::with_capacity(4),
            jerk: cfg.profile_jerk,
            command_error: None,
            error_warning: false,
            brake_control: BrakeControl::Auto,
            app_outputs: 0,
            cfg,
        };
        d.reload(node.od_mut());
        d.refresh_handler_objects(node.od_mut());
        if let Some(o) = node.od().object(0x60E3).cloned() {
            // Through the node so its services re-resolve their handles.
            node.insert_object(o);
        }
        d.sm.self_test_passed();
        d.publish(node.od_mut());
        Ok(d)
    }

    /// Takes the drive's object `index` out of the dictionary because the
    /// device has no such object (a personality whose manual does not list
    /// it): SDO and PDO no longer reach it, and the drive keeps working
    /// with the parameter's value — the power-on value, or what
    /// [`Drive::on_write`] sets from the application side. Live values it published are no longer
    /// published. Returns whether the object was there. The caller
    /// re-resolves the node's services (`Node::insert_object`).
    pub fn withdraw_object(&mut self, od: &mut ObjectDictionary, index: u16) -> bool {
        let Some(o) = od.remove(index) else { return false };
        self.withdrawn.insert(o);
        self.refs = Refs::resolve(od);
        true
    }

    /// Whether [`Drive::withdraw_object`] took `index` out.
    pub fn is_withdrawn(&self, index: u16) -> bool {
        self.withdrawn.object(index).is_some()
    }

    /// The configuration.
    pub fn config(&self) -> &DriveConfig {
        &self.cfg
    }
    /// The motor and axis model.
    pub fn model(&self) -> &DriveModel {
        &self.model
    }
    /// The device control state machine.
    pub fn state_machine(&self) -> &StateMachine {
        &self.sm
    }
    /// The factor group conversions in force.
    pub fn units(&self) -> &Units {
        &self.units
    }
    /// The mode parameters (as the handlers see them).
    pub fn mode_params(&self) -> &ModeParams {
        &self.params
    }
    /// 6502h: supported drive modes.
    pub fn supported_modes(&self) -> u32 {
        self.modes
    }
    /// The active mode (6061h).
    pub fn mode(&self) -> i8 {
        self.mode
    }
    /// The control period \[s\].
    pub fn control_period(&self) -> f64 {
        self.dt
    }
    /// Control periods stepped so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }
    /// The statusword as last published.
    pub fn statusword(&self) -> u16 {
        self.statusword_value()
    }
    /// The latched command error (an S-curve set-point with "change set
    /// immediately", [`DriveConfig::scurve_forbids_change_immediately`])
    /// until the next fault reset: its EMCY code.
    pub fn command_error(&self) -> Option<u16> {
        self.command_error
    }
    /// Position demand \[position units\] (6062h, unrounded).
    pub fn demand_position(&self) -> f64 {
        self.dem.pos
    }
    /// Velocity demand \[position units/s\].
    pub fn demand_velocity(&self) -> f64 {
        self.dem.vel
    }
    /// Torque demand \[per mille\] (6074h, unrounded).
    pub fn demand_torque(&self) -> f64 {
        self.dem.torque
    }
    /// Position actual internal value \[increments\] (6063h).
    pub fn position_increments(&self) -> i64 {
        self.model.position_counts().saturating_add(self.inc_offset)
    }
    /// Position actual value \[position units\] (6064h before range wrap).
    pub fn position(&self) -> i64 {
        self.units.inc_frac_to_pos(self.position_increments(), self.inc_frac)
    }

    /// The reference shift in increments, its fraction included.
    pub(crate) fn inc_offset_f(&self) -> f64 {
        self.inc_offset as f64 + self.units.frac_to_inc_f(self.inc_frac)
    }

    /// Hands the queued EMCY requests to the node, each as `map` turns the
    /// drive's code into an EMCY (a personality's own codes and register
    /// bits); the drive's own callbacks use the CiA 301 bookkeeping.
    pub fn flush_emcy(&mut self, cx: &mut AppContext<'_>, map: impl Fn(u16) -> Request) {
        for r in self.emcy.drain(..) {
            match r {
                EmcyRequest::Raise(c) => cx.request(map(c)),
                EmcyRequest::Clear(c) => match map(c) {
                    Request::RaiseEmcy { code, .. } => cx.clear_emcy(code),
                    _ => cx.clear_emcy(c),
                },
            }
        }
    }

    /// Registers a mode handler after installation (adds its modes to 6502h,
    /// shows its 60C4h values; 60E3h is rebuilt from its homing registry if
    /// the drive was installed with hm, else pass hm handlers to
    /// [`Drive::install_with`]).
    pub fn add_handler(&mut self, od: &mut ObjectDictionary, h: Box<dyn ModeHandler + Send>) {
        self.modes |= h.supported_modes();
        self.handlers.push(h);
        if let Ok(r) = od.find(0x6502, 0) {
            od.set_le(r, &self.modes.to_le_bytes());
        }
        self.refresh_handler_objects(od);
    }

    /// Steps the drive to `now`: whole control periods on simulated time
    /// (the first call starts the clock). Returns the next step instant.
    fn advance(&mut self, od: &mut ObjectDictionary, now: Instant) -> Instant {
        let mut next = *self.next.get_or_insert(now);
        // Catch up in fixed steps; bounded so a huge jump cannot stall.
        let mut budget = 1_000_000u32;
        while next <= now && budget > 0 {
            self.control_step(od);
            next += self.period;
            budget -= 1;
        }
        if next <= now {
            next = now + self.period;
        }
        self.next = Some(next);
        self.publish(od);
        next
    }

    /// Runs `n` control periods at once, without a node clock (numeric tests,
    /// benchmarks).
    pub fn step_n(&mut self, od: &mut ObjectDictionary, n: u32) {
        for _ in 0..n {
            self.control_step(od);
        }
        self.publish(od);
    }

    fn connection_lost(&mut self, code: u16) {
        // CiA 402-2 6007h: the reaction applies in Operation enabled.
        if self.sm.state() == crate::state_machine::State::OperationEnabled {
            if self.sm.options().abort_connection() == 1
                && let Some(a) = self.fault_action(code)
            {
                self.take_fault(code, a);
                return;
            }
            let out = self.sm.connection_lost(code);
            self.after_transition(out);
        }
    }
}

/// What the drive does for each node callback, without handing over its
/// EMCY requests: the parts a wrapping application (a personality) calls
/// before its own behaviour, then [`Drive::flush_emcy`].
impl Drive {
    /// A SYNC: cyclic set-points latch, SYNC supervision resets.
    pub fn sync(&mut self, od: &mut ObjectDictionary) {
        self.sup.sync_lost = false;
        self.handler_sync(od);
    }

    /// A node event (NMT state, guarding, resets, link).
    pub fn event(&mut self, od: &mut ObjectDictionary, event: NodeEvent) {
        match event {
            NodeEvent::HeartbeatTimeout { .. } | NodeEvent::LifeGuardingLost => {
                self.connection_lost(0x8130);
            }
            // CiA 402-2 6007h: bus-off (or a pulled cable) aborts the
            // connection; error passive still communicates.
            NodeEvent::Link(LinkState::BusOff { .. } | LinkState::Disconnected) => {
                self.connection_lost(0x8130);
            }
            NodeEvent::NmtState { from, to } => {
                use drivebus_node::NmtState;
                self.operational = to == NmtState::Operational;
                if from == NmtState::Operational && to != NmtState::Operational {
                    // CiA 402-2 6007h: NMT stopped / leaving operational
                    // counts as an abort of the connection.
                    self.connection_lost(0x8130);
                }
                if to == NmtState::PreOperational && from != NmtState::Operational {
                    // Stored parameters may have been loaded behind the write path.
                    self.reload(od);
                }
            }
            NodeEvent::ResetApplication => {
                // NMT reset node: the application restarts from power-on
                // (Not ready → Switch on disabled); the node restores the
                // parameters and the following boot reloads them.
                self.connection_lost(0x8130);
                if self.mode_active {
                    self.exit_mode();
                }
                self.fault_reset();
                self.emcy.clear();
                self.command_error = None;
                self.manufacturer = None;
                self.sm = StateMachine::new(*self.sm.options());
                self.sm.self_test_passed();
                self.cw = 0;
                // Withdrawn parameters restart at their power-on values.
                self.withdrawn.restore_defaults(|_, _| true);
                self.pp = pp::Pp::default();
                self.pp.reset(self.dem.pos);
            }
            NodeEvent::ResetCommunication => {
                self.connection_lost(0x8130);
            }
            NodeEvent::SyncTimeout => {
                self.sup.sync_lost = true;
            }
            _ => {}
        }
        self.publish(od);
    }

    /// Steps the drive to `now`; the next control period's instant.
    pub fn step_to(&mut self, od: &mut ObjectDictionary, now: Instant) -> Instant {
        self.advance(od, now)
    }
}

/// The drive's EMCY as CiA 301 bookkeeping (the drive on its own).
fn standard(code: u16) -> Request {
    Request::RaiseEmcy { code, register: None, manufacturer: [0; 5] }
}

impl Application for Drive {
    fn check_write(
        &mut self,
        cx: &mut AppContext<'_>,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let r = self.check_object(cx.od, at, data);
        self.flush_emcy(cx, standard);
        r
    }

    fn apply_write(&mut self, cx: &mut AppContext<'_>, at: &Target) {
        self.apply_object(cx.od, at);
        self.flush_emcy(cx, standard);
    }

    fn on_read(&mut self, cx: &mut AppContext<'_>, at: &Target) -> Result<(), SdoAbort> {
        self.refresh_object(cx.od, at);
        Ok(())
    }

    fn on_sync(&mut self, cx: &mut AppContext<'_>, counter: Option<u8>) {
        let _ = counter;
        self.sync(cx.od);
        self.flush_emcy(cx, standard);
    }

    fn on_event(&mut self, cx: &mut AppContext<'_>, event: NodeEvent) {
        self.event(cx.od, event);
        self.flush_emcy(cx, standard);
    }

    fn poll(&mut self, cx: &mut AppContext<'_>) -> Option<Instant> {
        let next = self.advance(cx.od, cx.now);
        self.flush_emcy(cx, standard);
        Some(next)
    }
}

/// A snapshot of the drive (see [`Drive::view`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriveView {
    /// The device control state (CiA 402-2 §6.2.1).
    pub state: crate::state_machine::State,
    /// The active mode of operation (6061h).
    pub mode: i8,
    /// The statusword the drive computed.
    pub statusword: u16,
    /// The last controlword received (6040h).
    pub controlword: u16,
    /// Digital inputs 60FDh as the drive publishes them.
    pub digital_inputs: u32,
    /// The node is NMT *Operational* (tracked from the node's events).
    pub operational: bool,
    /// Past the negative (−1) or positive (+1) software position limit
    /// acting as a limit switch (`IoConfig::software_limit_switches`), 0
    /// inside or without.
    pub software_limit: i8,
}

impl Drive {
    /// 6086h → ramp shape. A stored 3 the drive was not configured for
    /// (a personality that accepts it itself) keeps the linear ramp.
    fn shape(&self) -> Shape {
        match self.extra.profile_type {
            1 => Shape::SinSquared,
            3 if self.cfg.motion_profile_types & profile_type::JERK_LIMITED != 0 => Shape::JerkLimited,
            _ => Shape::Linear,
        }
    }
}
