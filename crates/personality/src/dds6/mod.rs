//! LAM Technologies DDS6 behaviour (user manual HW 1.00 / FW 0.22, seed004).
//!
//! What a master sees that differs from a plain CiA 301/402 device:
//!
//! * 1010h/1011h are refused while the motor is enabled or NMT is
//!   operational (§4.2, §6.3.10: "an error code answer is received"; the
//!   manual lists no abort codes, so the CiA 301 code for "because of the
//!   present device state", `0800 0022h`, is used);
//! * NMT Stop / Reset Communication / Reset Node while the motor is enabled
//!   raise EMCY 82C2h with sub-code 0901h / 0902h / 0903h, class 4: quick
//!   stop, then Fault (§5);
//! * statusword bit 12 in profile velocity is "speed is equal 0": set when
//!   |velocity| < 606Fh for 6070h ms (§4.4.2, §6.5.3 table);
//! * fixed units: position 1/10000 rev, velocity 0.1 rpm, acceleration
//!   rpm/s, no factor group (§4.4, C.11 of the inventory);
//! * EMCY bytes 3–7 carry a 16-bit sub-code (§5; byte position not given:
//!   bytes 3–4, little-endian like every CANopen number);
//! * error classes decide the reaction (§5): 0 warning, 2 quick stop,
//!   4 quick stop then fault, 6 disable then fault, 8 fault until power
//!   cycle (`classes`; 8611h by 2480h:01, 82B2h by 3080h:02); limit
//!   switches raise 8612h, a failed homing 8613h, with sub-codes;
//! * the Sync Guard 3080h (`sync_guard`), the digital / analog I/O and the
//!   holding brake on the machine's lines and brake (`io`, `brake`,
//!   `live`); the behaviour ledger is `ledger.tsv`;
//! * homing methods 1–14, 17–30, 33, 34, 37 (no 35, no manufacturer methods,
//!   §4.4.4) on the 6083h ramps; modes pp, pv, tq, hm, ip (§6.5.4; no
//!   csp/csv/cst in FW 0.22);
//! * TPDO type FFh sends on a statusword change only (§6.3.21);
//! * "target reached" on the actual value alone, a set of set-points
//!   advancing there (the §4.4.1/§4.4.2 traces);
//! * enabling takes 16 ms open loop, ~515 ms with the closed loop
//!   (2410h:01, encoder timing); profile torque needs the closed loop
//!   (EMCY 63A0h / 0701h otherwise, §4.4.3);
//! * ip has no set-point buffer (§4.4.5).
//!
//! The §4.4 traces replay against this behaviour in
//! `tests/replay_dds6.rs` / `tests/replay_dds6_ip.rs`.

pub mod brake;
pub mod classes;
mod emcy;
mod facts;
pub mod io;
mod live;
mod rules;
pub mod sync_guard;

pub use rules::*;

pub use facts::INFO;

/// The EDS file (`crates/personality/eds/dds6.eds`).
pub const EDS: &str = include_str!("../../eds/dds6.eds");

// ---------------------------------------------------------------------------
// The behaviour.

use crate::Profile;
use crate::build::{Behaviour, Context, EmcyFrame, FilterOutcome, Verdict};
use drivebus_can::Frame;
use drivebus_cia402::drive::units::round;
use drivebus_cia402::drive::{DriveConfig, FactorGroup, Injection, TargetReached};
use drivebus_cia402::interp::IpMode;
use drivebus_cia402::model::DriveParams;
use drivebus_cia402::state_machine::State;
use drivebus_node::Node;
use drivebus_node::{NmtState, NodeEvent, Request};
use drivebus_od::{EntryRef, ObjectDictionary, SdoAbort, le_i64, le_u64};

/// The objects the DDS6 reads and writes after every control period,
/// resolved once per dictionary layout (`objects`: the object count they
/// were resolved at).
#[derive(Debug, Clone, Copy, Default)]
struct Handles {
    objects: usize,
    statusword: Option<EntryRef>,
    target_velocity: Option<EntryRef>,
    target_torque: Option<EntryRef>,
    velocity_window: Option<EntryRef>,
    velocity_demand: Option<EntryRef>,
    velocity_actual: Option<EntryRef>,
    torque_actual: Option<EntryRef>,
}

impl Handles {
    fn get(&mut self, od: &ObjectDictionary) -> Handles {
        if self.objects != od.objects().len() {
            let f = |i: u16| od.find(i, 0).ok();
            *self = Handles {
                objects: od.objects().len(),
                statusword: f(0x6041),
                target_velocity: f(0x60FF),
                target_torque: f(0x6071),
                velocity_window: f(0x606D),
                velocity_demand: f(0x606B),
                velocity_actual: f(0x606C),
                torque_actual: f(0x6077),
            };
        }
        *self
    }
}

/// `get_i64` through a handle: the value sign-extended, `None` if absent.
fn signed(od: &ObjectDictionary, r: Option<EntryRef>) -> Option<i64> {
    r.map(|r| le_i64(od.bytes(r)))
}

/// `get_u32` through a handle.
fn unsigned(od: &ObjectDictionary, r: Option<EntryRef>) -> Option<u32> {
    r.map(|r| le_u64(od.bytes(r)) as u32)
}

/// The DDS6 quirks around the CiA 402 drive.
#[derive(Debug, Clone, Default)]
pub struct Dds6 {
    /// The objects read and written every control period, resolved once.
    handles: Handles,
    nmt_operational: bool,
    /// An NMT request refused while the motor was enabled (sub-code), to be
    /// raised at the next step.
    pending_nmt_error: Option<u16>,
    /// The 82C2h sub-code of the last refusal (EMCY bytes 3–4).
    last_sub: u16,
    speed_zero: SpeedZero,
    speed_zero_bit: bool,
    target_velocity: i32,
    velocity_window: u16,
    /// The velocity demand is zero.
    at_rest: bool,
    /// The machine the motor drives (switches, stops), when not the bare
    /// shaft of [`DriveParams::stepper`].
    axis: Option<drivebus_cia402::model::AxisParams>,
    /// Enable operation requested: the drive enters Operation enabled at
    /// this time (motor enabling sequence).
    enable_at: Option<drivebus_can::Instant>,
    /// The enabling sequence has energised the motor (last part of it).
    power_stage_on: bool,
    /// 606Ch as the DDS6 shows it in open loop \[0.1 rpm\].
    shown_velocity: f64,
    /// pv statusword bit 10 from [`Dds6::shown_velocity`].
    velocity_reached: bool,
    /// 2410h:01 Feedback_MTNSTP as written (bit 0 closed loop, bit 3
    /// encoder timing at every enable).
    feedback: u8,
    /// The closed-loop encoder timing (rotor alignment) has run since
    /// power-on.
    aligned: bool,
    /// A homing completed since power-on (hm bit 12 while disabled).
    homed: bool,
    /// Operation enabled was entered in this control period, before the
    /// drive evaluated the mode's bits: the DDS6 shows them at once (tq
    /// 0637h, hm 0637h / 1637h straight after 0233h in §4.4.3–§4.4.4).
    just_enabled: bool,
    torque_target: i64,
    torque_demand: i64,
    /// 2480h:01, the class of 8611h.
    following_error_class: u8,
    /// 3080h:02, the class of 82B2h.
    sync_class: u8,
    /// A class 8 error is in force: fault reset refused until power-on.
    power_cycle: bool,
    /// The limit switches (60FDh bits 0/1) at the last step.
    limits: u32,
    /// A movement towards an active limit switch was reported.
    toward_limit: bool,
    /// 3080h.
    guard: sync_guard::SyncGuard,
    /// The I/O, voltage and current published every step.
    live: live::Live,
    /// The statusword as last published.
    last_sw: u16,
    /// Time the pv speed has been off the target by more than 60F8h \[s\].
    slip_s: f64,
    /// pv statusword bit 13 "max slippage error" (§6.4.23, §6.5.35).
    slipping: bool,
    /// hm statusword bit 13 (homing error) at the last step.
    homing_failed: bool,
}

/// 2310h:0Bh Max_Speed_MTRDT "can never be exceeded and prevails over any
/// other setting, whatever the chosen operating mode" (§6.4.1): the drive's
/// max motor speed, in the same 0.1 rpm.
fn max_speed(cx: &mut Context<'_>, od: &mut ObjectDictionary) {
    let v = od.get_u32(0x2310, 0x0B).unwrap_or(30_000);
    let _ = cx.drive.on_write(od, 0x6080, 0, &v.to_le_bytes());
}

/// 2310h:08 Rated_Current_MTRDT (10 mArms) is what 6078h counts in 0.1 %
/// of (§6.5.20): the drive's rated current (mA).
fn rated_values(cx: &mut Context<'_>, od: &mut ObjectDictionary) {
    if let Some(v) = od.get_u32(0x2310, 0x08).filter(|v| *v > 0) {
        let _ = cx.drive.on_write(od, 0x6075, 0, &(v * 10).to_le_bytes());
    }
}

impl Dds6 {
    /// The DDS6 as it powers up.
    pub fn new() -> Self {
        Self::default()
    }

    /// The statusword as the DDS6 shows it, from the drive's.
    fn statusword(&self, drive_sw: u16, state: State, mode: i8) -> u16 {
        let mut sw = drive_sw;
        match state {
            State::OperationEnabled | State::QuickStopActive if mode == 3 => {
                sw = (sw & !(1 << 13 | 1 << 12 | 1 << 10))
                    | (u16::from(self.slipping) << 13)
                    | (u16::from(self.speed_zero_bit) << 12)
                    | (u16::from(self.velocity_reached) << 10);
            }
            State::OperationEnabled if self.just_enabled && matches!(mode, 4 | 6) => {
                // tq: reached when the demand is the target (both 0 here);
                // hm: "not started" (bit 10), attained kept when homed.
                let tq_reached = self.torque_target == self.torque_demand;
                let bits = match mode {
                    4 => u16::from(tq_reached) << 10,
                    _ => 0x0400 | u16::from(self.homed) << 12,
                };
                sw = (sw & !0x3400) | bits;
            }
            State::OperationEnabled
                if matches!(mode, 1 | 7) && self.at_rest && (mode == 7 || sw & (1 << 12) == 0) =>
            {
                // pp / ip at standstill report "target reached": 0637h right
                // after enabling (§4.4.1 EX1), 1716h in ip while the
                // set-points stand still (§4.4.5 EX9). In pp only without a
                // set-point being acknowledged. (EX9 also shows 1716h around
                // the turning points, where the real axis is within a few
                // units of the set-point; the rule behind it — probably the
                // 3490h micro-interpolator's lag against 6067h — is not
                // documented, so it is not emulated.)
                sw |= 1 << 10;
            }
            State::SwitchOnDisabled | State::ReadyToSwitchOn | State::SwitchedOn => {
                // Voltage bit 4 set, quick-stop bit 5 clear in Switch on
                // disabled (0250h), mode bits as observed.
                if state == State::SwitchOnDisabled {
                    sw = (sw | 0x10) & !0x20;
                }
                let tv = self.target_velocity.unsigned_abs();
                let in_window = self.power_stage_on && tv < u32::from(self.velocity_window);
                sw = (sw & !0x3C00) | disabled_mode_bits(mode, state, in_window, self.homed);
            }
            _ => {}
        }
        sw
    }

    fn publish(&mut self, cx: &Context<'_>, od: &mut ObjectDictionary) {
        self.power_stage_on = self
            .enable_at
            .is_some_and(|t| cx.now + drivebus_can::Duration::from_millis(POWER_STAGE_LEAD_MS) >= t);
        self.at_rest = cx.drive.demand_velocity().abs() < 1e-6;
        let h = self.handles.get(od);
        self.target_velocity = signed(od, h.target_velocity).unwrap_or(0) as i32;
        self.torque_target = signed(od, h.target_torque).unwrap_or(0);
        // The DDS6 has no 6074h (§6.5): the drive's demand itself.
        self.torque_demand = round(cx.drive.demand_torque()) as i64;
        self.velocity_window = unsigned(od, h.velocity_window).unwrap_or(100) as u16;
        let drive_sw = cx.drive.statusword();
        if cx.drive.mode() == 6 && drive_sw & 0x6F == 0x27 && !self.just_enabled {
            // Completed (bits 12 + 10) or restarted (bit 12 cleared).
            self.homed = drive_sw & 0x3400 == 0x1400 || (self.homed && drive_sw & 0x1000 != 0);
        }
        let sw = self.statusword(drive_sw, cx.drive.state_machine().state(), cx.drive.mode());
        self.last_sw = sw;
        if let Some(r) = h.statusword {
            od.set_le(r, &sw.to_le_bytes());
        }
    }

    /// A DDS6 driving `axis` (limit and home switches on DI6/DI7/DI5 as
    /// 2810h:03..05 assign them by default, §6.4.8).
    pub fn with_axis(axis: drivebus_cia402::model::AxisParams) -> Self {
        Dds6 { axis: Some(axis), ..Self::default() }
    }

    /// Takes the class and Sync Guard settings from the dictionary (boot,
    /// values restored) and tells the drive the reactions.
    fn load_settings(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        self.following_error_class = od.get_u32(0x2480, 1).unwrap_or(6) as u8;
        self.sync_class = od.get_u32(0x3080, 2).unwrap_or(2) as u8;
        classes::install(cx.drive, self.following_error_class, self.sync_class);
        max_speed(cx, od);
        rated_values(cx, od);
        let g = &mut self.guard;
        g.expected_us = od.get_u32(0x3080, 4).unwrap_or(1000);
        g.jitter_us = od.get_u32(0x3080, 5).unwrap_or(200) as u16;
        g.threshold = od.get_u32(0x3080, 6).unwrap_or(15) as u8;
        g.write_options(od.get_u32(0x3080, 1).unwrap_or(0) as u8);
        self.live.load(od);
    }

    /// 3080h:03/07/08 as the guard counts.
    fn publish_guard(&self, od: &mut ObjectDictionary) {
        let g = &self.guard;
        for (sub, v) in [(3u8, g.count), (7, u32::from(g.peak)), (8, u32::from(g.out_of_sync))] {
            if let Ok(r) = od.find(0x3080, sub) {
                let b = v.to_le_bytes();
                let n = if sub == 3 { 4 } else { 1 };
                od.set_le(r, &b[..n]);
            }
        }
    }

    /// Limit switches (§5 8612h, class 2): one becoming active while the
    /// motor is enabled (0801h positive, 0802h negative), or a movement
    /// towards an active one (0803h / 0804h). Homing searches them.
    fn supervise_limits(&mut self, cx: &mut Context<'_>, od: &ObjectDictionary) {
        let switches = cx.drive.view().digital_inputs & 3;
        let rising = switches & !self.limits;
        self.limits = switches;
        let state = cx.drive.state_machine().state();
        let mode = cx.drive.mode();
        if state != State::OperationEnabled || mode == 6 {
            self.toward_limit = false;
            return;
        }
        // pv: the target velocity (the drive holds a blocked target at 0);
        // otherwise the demand.
        let direction = if mode == 3 {
            od.get_i64(0x60FF, 0).unwrap_or(0).signum()
        } else {
            let v = cx.drive.demand_velocity();
            if v > 0.0 {
                1
            } else if v < 0.0 {
                -1
            } else {
                0
            }
        };
        let toward = (switches & 2 != 0 && direction > 0) || (switches & 1 != 0 && direction < 0);
        let sub = if rising & 2 != 0 {
            Some(0x0801)
        } else if rising & 1 != 0 {
            Some(0x0802)
        } else if toward && !self.toward_limit {
            Some(if direction > 0 { 0x0803 } else { 0x0804 })
        } else {
            None
        };
        self.toward_limit = toward;
        if let Some(sub) = sub {
            self.last_sub = sub;
            cx.drive.inject(Injection::Fault(classes::EMCY_LIMIT_SWITCH));
        }
    }

    /// §5 8613h "Homing error" (class 2) when a homing fails (the
    /// handler's statusword bit 13): sub-code 0602h / 0603h with the
    /// clockwise / counter-clockwise limit switch active, 0601h "Unfound
    /// index" otherwise.
    fn supervise_homing(&mut self, cx: &mut Context<'_>) {
        let failed = cx.drive.mode() == 6
            && cx.drive.state_machine().state() == State::OperationEnabled
            && cx.drive.statusword() & 0x2000 != 0;
        if failed && !self.homing_failed {
            let switches = cx.drive.view().digital_inputs;
            self.last_sub = if switches & 2 != 0 {
                0x0602
            } else if switches & 1 != 0 {
                0x0603
            } else {
                0x0601
            };
            cx.drive.inject(Injection::Fault(classes::EMCY_HOMING));
        }
        self.homing_failed = failed;
    }

    /// pv statusword bit 13 "max slippage error": the speed differs from
    /// 60FFh by more than 60F8h for 3450h:01 ms (§6.4.23: "The drive is
    /// able to know the actual motor speed only if the motor is provided
    /// with encoder and the drive is configured in closed loop mode").
    fn supervise_slippage(&mut self, cx: &Context<'_>, od: &ObjectDictionary, enabled: bool, dt: f64) {
        if !(enabled && cx.drive.mode() == 3 && self.feedback & 1 != 0) {
            self.slip_s = 0.0;
            self.slipping = false;
            return;
        }
        // The encoder's speed in 0.1 rpm.
        let v = cx.drive.model().velocity_measured() * 600.0 / core::f64::consts::TAU;
        let target = od.get_i64(0x60FF, 0).unwrap_or(0) as f64;
        let window = f64::from(od.get_u32(0x60F8, 0).unwrap_or(1000));
        self.slip_s = if (v - target).abs() > window { self.slip_s + dt } else { 0.0 };
        let timeout = f64::from(od.get_u32(0x3450, 1).unwrap_or(0) as u16);
        self.slipping = self.slip_s > 0.0 && self.slip_s * 1000.0 + 1e-9 >= timeout;
    }

    /// The values published every step (`live`).
    fn publish_io(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let (sw, enabling) = (self.last_sw, self.enable_at.is_some());
        let dt = cx.drive.control_period();
        self.live.publish(cx.drive, sw, enabling, od, dt);
    }

    fn motor_enabled(sw: u16) -> bool {
        // Operation enabled or Quick stop active (§3.1: "motor enabled").
        sw & 0x6F == 0x27 || sw & 0x6F == 0x07
    }
}

impl Behaviour for Dds6 {
    fn profile(&self) -> Profile {
        Profile::Dds6
    }

    fn adjust_node_config(&self, cfg: &mut drivebus_node::NodeConfig) {
        // §6.3 lists neither 1007h nor 1019h (SYNC consumer only).
        cfg.sync_window = false;
        cfg.sync_counter = false;
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }

    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        // A two-phase stepper, open loop with encoder input (§1.1, C.14).
        let mut params = DriveParams::stepper();
        params.control.control_rate_hz = cfg.control_rate_hz;
        // The DDS6 reports a filtered speed (§4.4.2 traces: 606Ch settles
        // smoothly); the bare 4000-count encoder at 4 kHz is too coarse.
        params.control.velocity_filter = 0.02;
        if let Some(a) = self.axis {
            params.axis = a;
        }
        let cpr = params.encoder.counts_per_rev;
        cfg.params = params;
        // Fixed units (§4.4): position 1/10000 rev, velocity 0.1 rpm
        // (= 10000/600 position units/s), acceleration rpm/s (= 10000/60
        // position units/s²).
        cfg.factor = FactorGroup {
            feed: (POSITION_UNITS_PER_REV, 1),
            velocity_factor: (50, 3),
            acceleration_factor: (500, 3),
            ..FactorGroup::increments(cpr)
        };
        cfg.initial_mode = 1; // 6060h default 1 (§6.5.4)
        let p = &mut cfg.profile;
        // Object defaults of §6.5 (inventory C.6/C.7).
        p.max_profile_velocity = 30_000;
        p.profile_velocity = 600;
        p.profile_acceleration = 100;
        p.profile_deceleration = 300;
        p.quick_stop_deceleration = 5000;
        p.following_error_window = 10_000;
        p.following_error_timeout = 10;
        p.position_window = 10;
        p.position_window_time = 0;
        p.velocity_window = 100;
        p.velocity_window_time = 0;
        p.velocity_threshold = 60;
        p.velocity_threshold_time = 0;
        cfg.remote = true;
        // §5 class 2 "stop of the motor but not the transition to FAULT",
        // class 4 adds "successive motor disabling": a class-2 stop keeps
        // the motor enabled in Quick stop active (605Ah 6; §6.5.3 bit 5
        // "quick stop active/concluded"). A life guard / heartbeat loss
        // (8130h) is class 2: a quick stop (6007h 3).
        let _ = cfg.options.set_quick_stop(6);
        let _ = cfg.options.set_abort_connection(3);
        // §4.4.1/§4.4.2 traces: 0637h with the position still 9–10 units
        // short of the target (6067h = 10), the next set-point of a set
        // taken there; pv 0637h at 208 of 300 (606Dh = 100) while ramping.
        cfg.target_reached = TargetReached::ActualInWindow;
    }

    fn ip_mode(&self) -> IpMode {
        // No 60C4h: one set-point per period, the last one written (§4.4.5).
        IpMode::latest_only()
    }

    fn finish(&mut self, node: &mut Node) {
        // §6.5.31 homing speeds 600 / 60 (0.1 rpm).
        let od = node.od_mut();
        crate::build::set_default(od, 0x6099, 1, &drivebus_od::Value::U32(600));
        crate::build::set_default(od, 0x6099, 2, &drivebus_od::Value::U32(60));
        for n in 0..4u16 {
            let mask = statusword_mask(node.od(), 0x1A00 + n);
            node.set_tpdo_change_mask(n, Some(mask));
        }
    }

    fn after_write(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, sub: u8) {
        match (index, sub) {
            (0x2480, 1) => {
                self.following_error_class = od.get_u32(0x2480, 1).unwrap_or(6) as u8;
                let r = classes::reaction(self.following_error_class);
                cx.drive.set_fault_action(classes::EMCY_FOLLOWING_ERROR, r);
            }
            (0x3080, 2) => {
                self.sync_class = od.get_u32(0x3080, 2).unwrap_or(2) as u8;
                cx.drive.set_fault_action(classes::EMCY_SYNC_BREACH, classes::reaction(self.sync_class));
            }
            (0x3080, 1) => {
                self.guard.write_options(od.get_u32(0x3080, 1).unwrap_or(0) as u8);
                self.publish_guard(od);
            }
            (0x3080, 4..=6) => self.load_settings(cx, od),
            (0x3230, 2) => self.publish_io(cx, od),
            (0x2310, 0x0B) => max_speed(cx, od),
            (0x2310, 0x08) => {
                rated_values(cx, od);
                self.live.load(od);
            }
            (0x2310 | 0x2830..=0x2832 | 0x3310 | 0x23A0 | 0x2360 | 0x3360 | 0x2810, _) => self.live.load(od),
            _ => {}
        }
        if (0x1A00..=0x1A03).contains(&index) {
            let mask = statusword_mask(od, index);
            cx.request(Request::TpdoChangeMask { tpdo: index - 0x1A00, mask: Some(mask) });
        }
    }

    fn hooked_objects(&self) -> &'static [u16] {
        &[
            0x1010, 0x1011, 0x2410, 0x6040, 0x6083, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x2480, 0x3080, 0x3230,
            0x2310, 0x2830, 0x2831, 0x2832, 0x3310, 0x23A0, 0x60C2, 0x2360, 0x3360, 0x2810,
        ]
    }

    fn filter_rx(&mut self, od: &ObjectDictionary, node_id: u8, frame: &Frame) -> FilterOutcome {
        // §5 82C2h: NMT Stop / Reset Communication / Reset Node while the
        // motor is enabled is an "error in the execution of the requested
        // NMT service": the service is not carried out (read of the code's
        // name; the manual says nothing more), EMCY 82C2h with the sub-code,
        // class 4 (quick stop, then Fault).
        if frame.std_id() == Some(0) && frame.data().len() == 2 {
            let d = frame.data();
            if (d[1] == 0 || d[1] == node_id)
                && let Some(req) = NmtRequest::from_cs(d[0])
                && Self::motor_enabled(od.get_u32(0x6041, 0).unwrap_or(0) as u16)
            {
                self.pending_nmt_error = Some(req.sub_code());
                return FilterOutcome::Drop;
            }
        }
        FilterOutcome::Pass
    }

    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        let value = drivebus_od::le_u64(data) as u32;
        match (index, sub) {
            (0x2480, 1) if !classes::following_error_class_valid(value as u8) => {
                return Err(SdoAbort::INVALID_VALUE);
            }
            (0x3080, 2) if !classes::sync_class_valid(value as u8) => return Err(SdoAbort::INVALID_VALUE),
            (0x3080, _) => match self.guard.check(sub, value) {
                Err(sync_guard::Refusal::MonitoringEnabled) => return Err(SdoAbort(STORE_REFUSED)),
                Err(sync_guard::Refusal::JitterTooLarge) => return Err(SdoAbort::INVALID_VALUE),
                Ok(()) => {}
            },
            // §6.5.33: "can be modified only if the interpolation is not
            // active (bit ipa in the Statusword set to 0)".
            (0x60C2, _) if cx.drive.mode() == 7 && self.last_sw & 0x1000 != 0 => {
                return Err(SdoAbort(STORE_REFUSED));
            }
            (0x3230, 1) => {
                // §6.4.15: only the General Purpose outputs take the bits.
                let l = &mut self.live;
                l.general = io::write_outputs(l.sources, l.general, value as u16);
                self.publish_io(cx, od);
                return Ok(Verdict::Handled);
            }
            (0x3230, 2) => {
                let l = &mut self.live;
                l.general = io::set_output(l.sources, l.general, value as u8);
            }
            _ => {}
        }
        if index == 0x6040 {
            let mut cw =
                u16::from_le_bytes([data.first().copied().unwrap_or(0), data.get(1).copied().unwrap_or(0)]);
            if self.power_cycle {
                // §5 class 8: "can be reset only through a cycle of turning
                // off and on".
                cw &= !0x80;
            }
            let state = cx.drive.state_machine().state();
            let mut to_drive = cw;
            self.enable_at = None;
            if cw & 0x8F == 0x0F && matches!(state, State::ReadyToSwitchOn | State::SwitchedOn) {
                // Enable operation: switched on now, enabled after the
                // motor enabling sequence.
                to_drive = cw & !0x08;
                let closed = self.feedback & 1 != 0;
                if let Some(sub) = configuration_conflict(od, closed, cx.drive.mode()) {
                    self.last_sub = sub;
                    cx.drive.inject(Injection::Fault(EMCY_CONFIGURATION));
                }
                let timing = closed && (!self.aligned || self.feedback & 8 != 0);
                // §6.4.5 2410h:02: the current ramp to the rated current,
                // then the drive's own settling (16 ms with the default
                // 10 ms ramp, §4.4.2 EX4).
                let ramp = u64::from(od.get_u32(0x2410, 2).unwrap_or(10) as u16);
                let mut ms = if timing { ENCODER_TIMING_MS } else { ramp + ENABLE_DELAY_MS - 10 };
                if self.live.brake.automatic() {
                    // §4.3: "The transition to the operating state is
                    // delayed by the time the brake requires to completely
                    // disengage" (2360h:03).
                    ms = ms.max(u64::from(self.live.brake.release_ms));
                }
                self.enable_at = Some(cx.now + drivebus_can::Duration::from_millis(ms));
            }
            cx.drive.on_write(od, index, sub, &to_drive.to_le_bytes())?;
            self.publish(cx, od);
            return Ok(Verdict::Store);
        }
        if index == 0x2410 && sub == 1 {
            // C.14: the feedback is chosen with the motor disabled.
            if matches!(cx.drive.state_machine().state(), State::OperationEnabled | State::QuickStopActive) {
                return Err(SdoAbort(STORE_REFUSED));
            }
            self.feedback = data.first().copied().unwrap_or(0);
            self.aligned = false;
        }
        if index == 0x6083 {
            // C.9: homing runs on the profile acceleration (no 609Ah).
            cx.drive.on_write(od, 0x609A, 0, data)?;
        }
        if matches!(index, 0x1010 | 0x1011) {
            let enabled =
                matches!(cx.drive.state_machine().state(), State::OperationEnabled | State::QuickStopActive);
            store_allowed(enabled, self.nmt_operational).map_err(SdoAbort)?;
        }
        Ok(Verdict::Pass)
    }

    fn on_boot(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        self.load_settings(cx, od);
    }

    fn on_sync(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        if self.guard.on_sync(cx.now) {
            cx.drive.inject(Injection::Fault(classes::EMCY_SYNC_BREACH));
        }
        self.publish_guard(od);
    }

    fn on_event(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, event: &NodeEvent) {
        if let NodeEvent::ResetApplication = *event {
            // A restart of the drive (§4.2: like power-on).
            self.power_cycle = false;
            self.live.general = 0;
        }
        if let NodeEvent::NmtState { from, to } = *event {
            if from.is_initialisation() {
                // Restored / stored values are in the dictionary now.
                self.load_settings(cx, od);
            }
            self.nmt_operational = to == NmtState::Operational;
            // The drive reloads its parameters at boot: homing takes 6083h.
            if let Some(acc) = od.get_u32(0x6083, 0) {
                let _ = cx.drive.on_write(od, 0x609A, 0, &acc.to_le_bytes());
            }
        }
    }

    fn after_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        if let Some(sub) = self.pending_nmt_error.take() {
            self.last_sub = sub;
            cx.drive.inject(Injection::Fault(EMCY_NMT_WHILE_ENABLED));
        }
        if matches!(cx.drive.state_machine().state(), State::Fault | State::FaultReactionActive) {
            let code = cx.drive.state_machine().fault_code();
            self.power_cycle |=
                classes::class_of(code, self.following_error_class, self.sync_class) == Some(8);
        }
        self.supervise_limits(cx, od);
        self.supervise_homing(cx);
        if self.live.take_fault_reset() && !self.power_cycle {
            // §6.4.8 2810h:02: the input's edge resets a fault like
            // controlword bit 7 (a class 8 error excepted, §5).
            let cw = od.get_u32(0x6040, 0).unwrap_or(0) as u16 & !0x80;
            for c in [cw, cw | 0x80, cw] {
                let _ = cx.drive.on_write(od, 0x6040, 0, &c.to_le_bytes());
            }
        }
        if let Some(t) = self.enable_at
            && cx.now >= t
        {
            self.enable_at = None;
            let cw = od.get_u32(0x6040, 0).unwrap_or(0) as u16;
            if cw & 0x8F == 0x0F && cx.drive.state_machine().state() == State::SwitchedOn {
                let _ = cx.drive.on_write(od, 0x6040, 0, &cw.to_le_bytes());
                self.aligned |= self.feedback & 1 != 0;
                self.just_enabled = true;
            }
        } else {
            self.just_enabled = false;
        }
        let state = cx.drive.state_machine().state();
        let enabled = matches!(state, State::OperationEnabled | State::QuickStopActive);
        let dt = cx.drive.control_period();
        let h = self.handles.get(od);
        if enabled && cx.drive.mode() != 4 {
            let demand = signed(od, h.velocity_demand).unwrap_or(0) as f64;
            self.shown_velocity += (demand - self.shown_velocity) * dt / (VELOCITY_LAG_S + dt);
            if let Some(r) = h.velocity_actual {
                od.set_le(r, &(round(self.shown_velocity) as i32).to_le_bytes());
            }
        } else {
            self.shown_velocity = signed(od, h.velocity_actual).unwrap_or(0) as f64;
        }
        if enabled && cx.drive.mode() == 4 && self.feedback & 1 != 0 {
            // Closed loop the current loop follows the ramped demand: 6077h
            // shows the torque demand (§4.4.3 EX6: C8h after the 400 ms
            // ramp, F301h one step into the ramp down). The stepper model
            // itself has no torque loop.
            if let Some(a) = h.torque_actual {
                let v = round(cx.drive.demand_torque()).clamp(-32768.0, 32767.0) as i16;
                od.set_le(a, &v.to_le_bytes());
            }
        }
        // §6.5.14: bit 10 in pv, |606Ch − 60FFh| within 606Dh (606Eh = 0).
        let target = signed(od, h.target_velocity).unwrap_or(0) as f64;
        let window = f64::from(unsigned(od, h.velocity_window).unwrap_or(100));
        self.velocity_reached = (round(self.shown_velocity) - target).abs() <= window;
        self.supervise_slippage(cx, od, enabled, dt);
        if enabled && cx.drive.mode() == 3 {
            // §6.5.3 pv bit 12 "speed is equal 0".
            let v = signed(od, h.velocity_actual).unwrap_or(0) as f64;
            let thr = od.get_u32(0x606F, 0).unwrap_or(60) as u16;
            let t = od.get_u32(0x6070, 0).unwrap_or(0) as u16;
            self.speed_zero_bit = self.speed_zero.update(v, thr, t, dt);
        } else {
            self.speed_zero = SpeedZero::default();
            self.speed_zero_bit = true;
        }
        self.publish(cx, od);
        self.publish_io(cx, od);
    }

    fn emcy(&self, code: u16) -> EmcyFrame {
        let with_sub = matches!(
            code,
            EMCY_NMT_WHILE_ENABLED | EMCY_CONFIGURATION | classes::EMCY_LIMIT_SWITCH | classes::EMCY_HOMING
        );
        let bytes = if with_sub { emcy_sub_code_bytes(self.last_sub) } else { [0; 5] };
        EmcyFrame { code, register: None, bytes }
    }
}
