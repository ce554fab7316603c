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
//!   4 quick stop then fault, 6 disable then fault, 8 fault until power cycle;
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

pub mod classes;
mod emcy;
mod facts;
pub mod io;
pub mod sync_guard;

pub use facts::INFO;

/// The EDS file (`crates/personality/eds/dds6.eds`).
pub const EDS: &str = include_str!("../../eds/dds6.eds");

use drivebus_cia402::homing::{HomingRegistry, StandardMethod};

/// The SDO abort for a store/restore the device state forbids.
pub const STORE_REFUSED: u32 = 0x0800_0022;

/// EMCY 82C2h "Error in the execution of the requested NMT service" (§5).
pub const EMCY_NMT_WHILE_ENABLED: u16 = 0x82C2;

/// The NMT services §5 names for 82C2h.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NmtRequest {
    /// cs 02h.
    Stop,
    /// cs 82h.
    ResetCommunication,
    /// cs 81h.
    ResetNode,
}

impl NmtRequest {
    /// The NMT command specifier → request (the ones §5 lists).
    pub fn from_cs(cs: u8) -> Option<Self> {
        match cs {
            0x02 => Some(NmtRequest::Stop),
            0x82 => Some(NmtRequest::ResetCommunication),
            0x81 => Some(NmtRequest::ResetNode),
            _ => None,
        }
    }

    /// The 82C2h sub-code (§5: 0901h stop, 0902h reset communication,
    /// 0903h node reset, "with motor enabled").
    pub fn sub_code(self) -> u16 {
        match self {
            NmtRequest::Stop => 0x0901,
            NmtRequest::ResetCommunication => 0x0902,
            NmtRequest::ResetNode => 0x0903,
        }
    }
}

/// Whether 1010h/1011h may run (§4.2: "only with the motor disabled or in
/// the NMT status Stopped or Pre-operational. Trying the operation with the
/// motor enabled or in the NMT Operational status an error code answer is
/// received"). The second sentence is the operative one: refused when
/// either holds.
pub fn store_allowed(motor_enabled: bool, nmt_operational: bool) -> Result<(), u32> {
    if motor_enabled || nmt_operational { Err(STORE_REFUSED) } else { Ok(()) }
}

/// The manufacturer bytes 3–7 of an EMCY with sub-code `sub` (§5).
pub fn emcy_sub_code_bytes(sub: u16) -> [u8; 5] {
    let b = sub.to_le_bytes();
    [b[0], b[1], 0, 0, 0]
}

/// Error class of an EMCY code (§5 table; 8611h: the table's class 2 —
/// "expresses the default value" — is used, the 2480h:01 object default 6
/// contradicts it and the table is the more specific statement).
pub fn error_class(code: u16) -> Option<u8> {
    Some(match code {
        0x2310 | 0x23A0 | 0x23B2 | 0x3210 | 0x3220 => 6,
        0x4210 | 0x82C2 => 4,
        0x5592 | 0x5594 | 0x55A0 | 0x55A2 | 0x6200 | 0x63A0 | 0x7282 => 8,
        0x8110 | 0x8120 | 0x8130 | 0x8140 | 0x8200 | 0x8210 | 0x8220 | 0x8240 | 0x8250 | 0x82A1 | 0x82A2
        | 0x82A3 | 0x82A4 | 0x82B2 | 0x8611 | 0x8612 | 0x8613 => 2,
        _ => return None,
    })
}

/// Statusword bit 12 in pv: "speed is equal 0" (§6.5.3: 1 = motor halted,
/// abs(v) < 606Fh for 6070h ms). Keeps the time the speed has been below
/// the threshold.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpeedZero {
    below_s: f64,
}

impl SpeedZero {
    /// One period: `|v|` and the threshold in velocity units (0.1 rpm),
    /// the threshold time in ms; returns the bit.
    pub fn update(&mut self, velocity: f64, threshold: u16, time_ms: u16, dt: f64) -> bool {
        if velocity.abs() >= f64::from(threshold) {
            self.below_s = 0.0;
            return false;
        }
        self.below_s += dt;
        self.below_s * 1000.0 + 1e-9 >= f64::from(time_ms)
    }
}

/// The DDS6 homing methods (§4.4.4): every standard method but 35 (37 is
/// used for "homing at the actual position").
pub fn homing_registry() -> HomingRegistry {
    let mut r = HomingRegistry::empty();
    for code in StandardMethod::CODES {
        if code == 35 {
            continue;
        }
        if let Some(m) = StandardMethod::new(code) {
            r.register(Box::new(m));
        }
    }
    r
}

/// Fixed units (§4.4): position units per motor revolution.
pub const POSITION_UNITS_PER_REV: u32 = 10_000;

#[cfg(test)]
mod facts_tests {
    use super::*;

    #[test]
    fn store_refusal() {
        // §4.2 / §6.3.10.
        assert_eq!(store_allowed(false, false), Ok(()));
        assert_eq!(store_allowed(true, false), Err(0x0800_0022));
        assert_eq!(store_allowed(false, true), Err(0x0800_0022));
    }

    #[test]
    fn nmt_sub_codes() {
        // §5 82C2h sub-codes.
        assert_eq!(NmtRequest::from_cs(2).map(NmtRequest::sub_code), Some(0x0901));
        assert_eq!(NmtRequest::from_cs(0x82).map(NmtRequest::sub_code), Some(0x0902));
        assert_eq!(NmtRequest::from_cs(0x81).map(NmtRequest::sub_code), Some(0x0903));
        assert_eq!(NmtRequest::from_cs(1), None);
        assert_eq!(NmtRequest::from_cs(0x80), None);
        assert_eq!(emcy_sub_code_bytes(0x0903), [0x03, 0x09, 0, 0, 0]);
    }

    #[test]
    fn classes() {
        assert_eq!(error_class(0x82C2), Some(4));
        assert_eq!(error_class(0x8130), Some(2));
        assert_eq!(error_class(0x2310), Some(6));
        assert_eq!(error_class(0x6200), Some(8));
        for e in crate::Profile::Dds6.info().emcy {
            if e.code != 0 {
                assert!(error_class(e.code).is_some(), "{:04X}", e.code);
            }
        }
    }

    #[test]
    fn speed_zero_needs_threshold_time() {
        // 606Fh default 60 (6 rpm), 6070h 10 ms, 1 ms periods.
        let mut s = SpeedZero::default();
        let mut bit = false;
        for _ in 0..9 {
            bit = s.update(0.0, 60, 10, 0.001);
        }
        assert!(!bit);
        assert!(s.update(0.0, 60, 10, 0.001) || s.update(0.0, 60, 10, 0.001));
        assert!(!s.update(600.0, 60, 10, 0.001));
        // 6070h = 0 (the DDS6 default): the bit follows the speed at once.
        let mut s = SpeedZero::default();
        assert!(!s.update(300.0, 60, 0, 0.001));
        assert!(s.update(59.0, 60, 0, 0.001));
        assert!(!s.update(60.0, 60, 0, 0.001));
    }

    #[test]
    fn homing_methods() {
        // §4.4.4: 31 methods, 37 instead of 35.
        let codes: Vec<i8> = homing_registry().codes().collect();
        assert_eq!(codes, crate::Profile::Dds6.info().homing_methods);
    }
}

// ---------------------------------------------------------------------------
// The behaviour.

use crate::Profile;
use crate::build::{Behaviour, Context, EmcyFrame, FilterOutcome, Verdict};
use drivebus_can::Frame;
use drivebus_cia402::drive::{DriveConfig, FactorGroup, Injection, TargetReached};
use drivebus_cia402::interp::IpMode;
use drivebus_cia402::model::DriveParams;
use drivebus_cia402::state_machine::State;
use drivebus_node::Node;
use drivebus_node::{NmtState, NodeEvent, Request};
use drivebus_od::{ObjectDictionary, SdoAbort};

/// Mode-specific statusword bits 10/12/13 the DDS6 shows while the drive
/// function is disabled (inventory G.5, observed in every §4.4 trace:
/// Switch on disabled 2650h in pp/ip, 3250h in pv, 0650h in hm, 0250h in
/// tq; Ready to switch on 2631h / 3231h / 0631h; Switched on 2633h / 3633h
/// / 0633h).
///
/// In pv, Switched on shows bit 10 "target reached" once the enabling
/// sequence has energised the motor and the target velocity 60FFh is
/// within the velocity window of the (zero) speed: 3233h polled 7 ms after
/// 000Fh (§4.4.2 EX3), 3633h just before 1637h (EX4). In hm, bit 12
/// "homing attained" stays once a homing completed (1633h in §4.4.4 EX7,
/// captured on a homed axis; 0633h in EX8 from power-on).
pub fn disabled_mode_bits(mode: i8, state: State, target_velocity_in_window: bool, homed: bool) -> u16 {
    match (mode, state) {
        (1 | 7, _) => 0x2400,
        (3, State::SwitchedOn) if target_velocity_in_window => 0x3400,
        (3, _) => 0x3000,
        (6, _) if homed => 0x1400,
        (6, _) => 0x0400,
        _ => 0,
    }
}

/// The DDS6 quirks around the CiA 402 drive.
#[derive(Debug, Clone, Default)]
pub struct Dds6 {
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
    /// 3230h:01 bits of the outputs configured as General Purpose.
    general_outputs: u16,
    /// The limit switches (60FDh bits 0/1) at the last step.
    limits: u32,
    /// A movement towards an active limit switch was reported.
    toward_limit: bool,
    /// 3080h.
    guard: sync_guard::SyncGuard,
    refs: Option<Refs>,
}

/// Handles of the manufacturer values published every step, resolved once
/// (again when objects were inserted).
#[derive(Debug, Clone, Copy)]
struct Refs {
    objects: usize,
    inputs: Option<drivebus_od::EntryRef>,
    outputs: Option<drivebus_od::EntryRef>,
}

impl Refs {
    fn get(refs: &mut Option<Refs>, od: &ObjectDictionary) -> Refs {
        match *refs {
            Some(r) if r.objects == od.objects().len() => r,
            _ => {
                let r = Refs {
                    objects: od.objects().len(),
                    inputs: od.find(0x3210, 1).ok(),
                    outputs: od.find(0x3230, 1).ok(),
                };
                *refs = Some(r);
                r
            }
        }
    }
}

/// The 63A0h "Conflicts in the configuration" sub-code an Enable operation
/// meets (§5, class 8): 0704h closed loop (2410h:01 bit 0) without an
/// encoder (2330h:01 = 0 or 2330h:02 = 0 disable the input, §6.4.2),
/// 0702h load-proportional current (23A0h:01 = 1) without the closed loop,
/// 0701h profile torque without it (§4.4.3).
pub fn configuration_conflict(od: &ObjectDictionary, closed: bool, mode: i8) -> Option<u16> {
    let encoder = od.get_u32(0x2330, 1).unwrap_or(0) != 0 && od.get_u32(0x2330, 2).unwrap_or(0) != 0;
    if closed && !encoder {
        Some(0x0704)
    } else if !closed && od.get_u32(0x23A0, 1) == Some(1) {
        Some(0x0702)
    } else if !closed && mode == 4 {
        Some(0x0701)
    } else {
        None
    }
}

/// The closed-loop enable with its "encoder timing" (rotor alignment,
/// §4.4 / C.14): 000Fh → Operation enabled in ~515 ms (§4.4.3 EX6 517 ms,
/// EX5 between 480 and 548 ms, §4.4.4 EX8 517 ms).
pub const ENCODER_TIMING_MS: u64 = 515;

/// EMCY 63A0h "configuration conflict" (class 8), sub-code 0701h: profile
/// torque without closed loop (§4.4.3).
pub const EMCY_CONFIGURATION: u16 = 0x63A0;

/// Open loop the DDS6 has no speed sensor in the loop: 606Ch follows the
/// commanded speed with a short lag, ~1.8 ms in the §4.4.2 EX4 trace (68
/// at 8.6 ms and 208 at 22.6 ms of a 10 000 (0.1 rpm)/s ramp), smooth
/// enough that bit 10 sets once and stays.
pub const VELOCITY_LAG_S: f64 = 0.0018;

/// Switched on → Operation enabled takes the current enable ramp
/// (2410h:02, default 10 ms) plus the drive's own settling: 16 ms observed
/// in the open-loop traces (§4.4.2 EX4: 3633h at 71.5 ms, 1637h 16 ms later;
/// §4.4.1 EX1: 2633h polled at 46.6 ms); closed loop see
/// [`ENCODER_TIMING_MS`].
pub const ENABLE_DELAY_MS: u64 = 16;

/// 2310h:0Bh Max_Speed_MTRDT "can never be exceeded and prevails over any
/// other setting, whatever the chosen operating mode" (§6.4.1): the drive's
/// max motor speed, in the same 0.1 rpm.
fn max_speed(cx: &mut Context<'_>, od: &mut ObjectDictionary) {
    let v = od.get_u32(0x2310, 0x0B).unwrap_or(30_000);
    let _ = cx.drive.on_write(od, 0x6080, 0, &v.to_le_bytes());
}

/// The power stage is on this long before Operation enabled: pv shows bit
/// 10 in Switched on for that last millisecond (§4.4.2 EX4: 3633h at
/// 71.5 ms, 1637h at 72.0 ms; EX3 polls 3233h 7 ms after 000Fh).
pub const POWER_STAGE_LEAD_MS: u64 = 1;

/// TPDO change-of-state mask for a mapping: the bits of 6041h (§6.3.21:
/// transmission type FFh is "triggered by Statusword change").
pub fn statusword_mask(od: &ObjectDictionary, mapping: u16) -> [u8; 8] {
    let mut mask = [0u8; 8];
    let count = od.get_u32(mapping, 0).unwrap_or(0).min(64) as u8;
    let mut bit = 0usize;
    for i in 1..=count {
        let e = od.get_u32(mapping, i).unwrap_or(0);
        let len = (e & 0xFF) as usize;
        if e >> 16 == 0x6041 {
            for b in bit..(bit + len).min(64) {
                mask[b / 8] |= 1 << (b % 8);
            }
        }
        bit += len;
    }
    mask
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
                sw = (sw & !(1 << 12 | 1 << 10))
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
        self.target_velocity = od.get_i64(0x60FF, 0).unwrap_or(0) as i32;
        self.torque_target = od.get_i64(0x6071, 0).unwrap_or(0);
        // The DDS6 has no 6074h (§6.5): the drive's demand itself.
        self.torque_demand = cx.drive.demand_torque().round() as i64;
        self.velocity_window = od.get_u32(0x606D, 0).unwrap_or(100) as u16;
        let drive_sw = cx.drive.statusword();
        if cx.drive.mode() == 6 && drive_sw & 0x6F == 0x27 && !self.just_enabled {
            // Completed (bits 12 + 10) or restarted (bit 12 cleared).
            self.homed = drive_sw & 0x3400 == 0x1400 || (self.homed && drive_sw & 0x1000 != 0);
        }
        let sw = self.statusword(drive_sw, cx.drive.state_machine().state(), cx.drive.mode());
        if let Ok(r) = od.find(0x6041, 0) {
            od.set_le(r, &sw.to_le_bytes());
        }
    }

    /// A DDS6 driving `axis` (limit and home switches on DI6/DI7/DI5 as
    /// 2810h:03..05 assign them by default, §6.4.8).
    pub fn with_axis(axis: drivebus_cia402::model::AxisParams) -> Self {
        Dds6 { axis: Some(axis), ..Self::default() }
    }

    /// The output sources 2830h–2832h:01.
    fn output_sources(od: &ObjectDictionary) -> [u16; 3] {
        [0u16, 1, 2].map(|n| od.get_u32(0x2830 + n, 1).unwrap_or(0) as u16)
    }

    /// Takes the class and Sync Guard settings from the dictionary (boot,
    /// values restored) and tells the drive the reactions.
    fn load_settings(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        self.following_error_class = od.get_u32(0x2480, 1).unwrap_or(6) as u8;
        self.sync_class = od.get_u32(0x3080, 2).unwrap_or(2) as u8;
        classes::install(cx.drive, self.following_error_class, self.sync_class);
        max_speed(cx, od);
        let g = &mut self.guard;
        g.expected_us = od.get_u32(0x3080, 4).unwrap_or(1000);
        g.jitter_us = od.get_u32(0x3080, 5).unwrap_or(200) as u16;
        g.threshold = od.get_u32(0x3080, 6).unwrap_or(15) as u8;
        g.write_options(od.get_u32(0x3080, 1).unwrap_or(0) as u8);
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
            if v > 0.0 { 1 } else if v < 0.0 { -1 } else { 0 }
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

    /// 3210h:01 and 3230h:01 from the machine's switches and the output
    /// sources.
    fn publish_io(&mut self, cx: &Context<'_>, od: &mut ObjectDictionary) {
        let refs = Refs::get(&mut self.refs, od);
        let di = io::inputs(cx.drive.view().digital_inputs, 0);
        let sw = od.get_u32(0x6041, 0).unwrap_or(0) as u16;
        let v = cx.drive.demand_velocity();
        let signals = io::Signals { statusword: sw, brake: false, positive: v > 0.0, negative: v < 0.0 };
        let out = io::outputs(Self::output_sources(od), self.general_outputs, &signals);
        if let Some(r) = refs.inputs {
            od.set_le(r, &di.to_le_bytes());
        }
        if let Some(r) = refs.outputs {
            od.set_le(r, &out.to_le_bytes());
        }
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
                cx.drive.set_error_reaction(classes::EMCY_FOLLOWING_ERROR, r);
            }
            (0x3080, 2) => {
                self.sync_class = od.get_u32(0x3080, 2).unwrap_or(2) as u8;
                cx.drive.set_error_reaction(classes::EMCY_SYNC_BREACH, classes::reaction(self.sync_class));
            }
            (0x3080, 1) => {
                self.guard.write_options(od.get_u32(0x3080, 1).unwrap_or(0) as u8);
                self.publish_guard(od);
            }
            (0x3080, 4..=6) => self.load_settings(cx, od),
            (0x3230, 2) => self.publish_io(cx, od),
            (0x2310, 0x0B) => max_speed(cx, od),
            _ => {}
        }
        if (0x1A00..=0x1A03).contains(&index) {
            let mask = statusword_mask(od, index);
            cx.request(Request::TpdoChangeMask { tpdo: index - 0x1A00, mask: Some(mask) });
        }
    }

    fn hooked_objects(&self) -> &'static [u16] {
        &[
            0x1010, 0x1011, 0x2410, 0x6040, 0x6083, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x2480, 0x3080, 0x3230, 0x2310,
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
            (0x3230, 1) => {
                // §6.4.15: only the General Purpose outputs take the bits.
                let sources = Self::output_sources(od);
                self.general_outputs = io::write_outputs(sources, self.general_outputs, value as u16);
                self.publish_io(cx, od);
                return Ok(Verdict::Handled);
            }
            (0x3230, 2) => {
                let sources = Self::output_sources(od);
                self.general_outputs = io::set_output(sources, self.general_outputs, value as u8);
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
                let ms = if timing { ENCODER_TIMING_MS } else { ramp + ENABLE_DELAY_MS - 10 };
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
            self.general_outputs = 0;
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
            self.power_cycle |= classes::class_of(code, self.following_error_class, self.sync_class) == Some(8);
        }
        self.supervise_limits(cx, od);
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
        if enabled && cx.drive.mode() != 4 {
            let demand = od.get_i64(0x606B, 0).unwrap_or(0) as f64;
            self.shown_velocity += (demand - self.shown_velocity) * dt / (VELOCITY_LAG_S + dt);
            if let Ok(r) = od.find(0x606C, 0) {
                od.set_le(r, &(self.shown_velocity.round() as i32).to_le_bytes());
            }
        } else {
            self.shown_velocity = od.get_i64(0x606C, 0).unwrap_or(0) as f64;
        }
        if enabled && cx.drive.mode() == 4 && self.feedback & 1 != 0 {
            // Closed loop the current loop follows the ramped demand: 6077h
            // shows the torque demand (§4.4.3 EX6: C8h after the 400 ms
            // ramp, F301h one step into the ramp down). The stepper model
            // itself has no torque loop.
            if let Ok(a) = od.find(0x6077, 0) {
                let v = cx.drive.demand_torque().round().clamp(-32768.0, 32767.0) as i16;
                od.set_le(a, &v.to_le_bytes());
            }
        }
        // §6.5.14: bit 10 in pv, |606Ch − 60FFh| within 606Dh (606Eh = 0).
        let target = od.get_i64(0x60FF, 0).unwrap_or(0) as f64;
        let window = f64::from(od.get_u32(0x606D, 0).unwrap_or(100));
        self.velocity_reached = (self.shown_velocity.round() - target).abs() <= window;
        if enabled && cx.drive.mode() == 3 {
            // §6.5.3 pv bit 12 "speed is equal 0".
            let v = od.get_i64(0x606C, 0).unwrap_or(0) as f64;
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
        let with_sub = matches!(code, EMCY_NMT_WHILE_ENABLED | EMCY_CONFIGURATION | classes::EMCY_LIMIT_SWITCH);
        let bytes = if with_sub { emcy_sub_code_bytes(self.last_sub) } else { [0; 5] };
        EmcyFrame { code, register: None, bytes }
    }
}
