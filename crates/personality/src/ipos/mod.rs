//! Technosoft iPOS behaviour (*iPOS CoE Programming* P091.064.UM.0524,
//! seed002): the CiA 402 over EtherCAT object dictionary, served as a
//! CANopen personality (SDOs on 600h/580h + node-ID, PDOs with CiA 301
//! COB-IDs: the EtherCAT mailbox and state machine have no CAN equivalent).
//!
//! What a master sees that differs from a plain CiA 301/402 device:
//!
//! * mode −1 electronic gearing (§11) follows the master position (201Eh
//!   online, or the machine's master encoder on the second encoder input)
//!   × 2013h on the drive's csp; −2 electronic camming (§12) runs the cam
//!   table of §18.4.1 from the drive memory 2064h–206Ah (`cam.rs`);
//! * the factor group of §5.2 (6093h, 6094h, 210Fh; `factor.rs`) scales
//!   the user's units to the internal ones;
//! * ip (7): CiA 402 linear interpolation with 208Eh bit 8 = 1, the legacy
//!   PT / PVT sub-modes 60C0h = 0 / −1 with bit 8 = 0: packed 60C1h:01/02
//!   points, integrity counter, 2072h–207Ah, EMCY FF01h (§9); csp, csv, cst;
//! * 6071h/6074h/6077h/6078h are ‰ of 6075h, the motor rated *current*
//!   (§8.2.1): the drive's torque reference is kept at kₜ × 6075h;
//! * 606Ch is the speed per 1 ms slow-loop sample (§10);
//! * limit switches send EMCY 5443h / 5442h and 0000h on release (§4.3.1);
//! * a PDO mapping of more than 64 bits is not taken: "When the drive will
//!   be re-initialized with the new settings, it will send an emergency
//!   message that ignored the PDO mapping" (§1.6.3.1). On CAN the
//!   re-initialisation is the write of mapping sub 0 that activates it: the
//!   write is confirmed (the master's tool sees success, as in TwinCAT),
//!   EMCY 8220h "PDO length exceeded" is sent and the mapping keeps its
//!   previous count. 8210h "PDO not processed due to length error" is
//!   what a received RPDO shorter than its mapping raises (CiA 301; the
//!   node does it). The manual gives no finer rule for the two codes;
//! * the error register uses only bits 0 and 4 (§3.1.3 / 1001h);
//! * no 1010h/1011h: 2076h saves, 2080h resets (§4.9.6, §4.9.8);
//! * the status objects (2000h, 2002h, 2045h, 208Fh, 2102h, …) mirror the
//!   drive and the machine (`status.rs`); what every object does is
//!   `ledger.tsv`.

mod emcy;
mod facts;

pub use facts::INFO;

/// The EDS file (`crates/personality/eds/ipos.eds`).
pub const EDS: &str = include_str!("../../eds/ipos.eds");

use crate::Profile;
use crate::build::{Behaviour, Context, EmcyFrame, Verdict};
use drivebus_cia402::drive::{DriveConfig, FactorGroup, ProbeInput, ProfileJerk, Scaling, profile_type};
use drivebus_cia402::homing::HomingMethod;
use drivebus_cia402::interp::{IpMode, IpMonitor};
use drivebus_cia402::state_machine::State;

mod cam;
pub mod ecat;
mod factor;
pub mod foe;
mod gearing;
mod homing;
mod interp;
mod refs;
mod status;
mod supervise;

pub use cam::{CamTable, Memory};
use drivebus_node::{NodeConfig, NodeEvent, Request};
use drivebus_od::{ObjectDictionary, SdoAbort};
use gearing::Gear;
pub use gearing::{MASTER_FULL_RANGE, master_increment};
pub use homing::MechanicalLimitHoming;
use interp::Legacy;
pub use interp::{AUX_LINEAR_IP, EMCY_IP_STATUS, IP_BUFFER_DEFAULT, IP_BUFFER_MAX, LegacyPoint, ip_status};
use refs::{Refs, i64_at, u32_at};
pub use status::{AVAILABLE_OUTPUTS, EMCY_IO_NOT_AVAILABLE};

/// EMCY 8220h "PDO length exceeded" (Table 3.1.3).
pub const EMCY_PDO_LENGTH_EXCEEDED: u16 = 0x8220;
/// EMCY 8210h "PDO not processed due to length error" (Table 3.1.3).
pub const EMCY_PDO_LENGTH_ERROR: u16 = 0x8210;
/// Bits of data one PDO carries at most (§1.6.3.1).
pub const MAX_PDO_BITS: u32 = 64;

/// Encoder increments per motor revolution of the emulated axis: 608Fh:1
/// default 2000 (§5.2.3), the "2000 counts per revolution" of the motion
/// examples (§6.4, §7.3).
pub const COUNTS_PER_REV: u32 = 2000;

/// The slow loop (position/speed control) sample \[s\]: 1 ms (§1.3, §6.4
/// "1ms sample rate for position/speed control").
pub const SLOW_LOOP_S: f64 = 1e-3;

/// Time constant of the speed measurement filter \[s\]: one slow-loop
/// sample (§10: 606Ch is increments per 1 ms sample; the emulation's
/// encoder is differentiated every 0.125 ms control period). A first-order
/// lag, so one 606Ch reading is within about one increment per sample of
/// the speed; it filters the speed loop's feedback too.
pub const SPEED_FILTER_S: f64 = 1e-3;

/// Sum of the lengths (bits) of mapping entries 1..=n of a mapping object.
pub fn mapped_bits(od: &ObjectDictionary, map: u16, n: u8) -> u32 {
    (1..=n).map(|s| od.get_u32(map, s).unwrap_or(0) & 0xFF).sum()
}

/// The 1001h value the iPOS sends with a code: bit 0 always, bit 4 for
/// communication errors (§3.1.3: only bits 0 and 4 are used).
pub fn error_register(code: u16) -> u8 {
    match code {
        0x0000..=0x00FF => 0,
        0x1000 | 0x7500 | 0x8100..=0x82FF => 0x11,
        _ => 0x01,
    }
}

/// EMCY 9000h "command error" (§7.1.2: a set-point with controlword bit 5
/// while 6086h = 3; Table 3.1.3).
pub const EMCY_COMMAND_ERROR: u16 = 0x9000;
/// EMCY 5443h "positive limit switch active" (§4.3.1, Table 3.1.3).
pub const EMCY_LSP: u16 = 0x5443;
/// EMCY 5442h "negative limit switch active" (§4.3.1, Table 3.1.3).
pub const EMCY_LSN: u16 = 0x5442;
/// EMCY FF06h "positive software position limit triggered" (§4.3.2).
pub const EMCY_SOFT_LIMIT_POSITIVE: u16 = 0xFF06;
/// EMCY FF07h "negative software position limit triggered" (§4.3.2).
pub const EMCY_SOFT_LIMIT_NEGATIVE: u16 = 0xFF07;

/// The iPOS quirks around the CiA 402 drive.
#[derive(Debug, Clone, Default)]
pub struct Ipos {
    /// The ip buffer fill, shared with the drive's ip handler.
    ip: IpMonitor,
    legacy: Legacy,
    gear: Gear,
    /// The master encoder count (second encoder input) last taken by
    /// gearing.
    second_taken: Option<i64>,
    /// Limit switches as last seen (LSN, LSP).
    limits: (bool, bool),
    /// Software limit passed as last seen (−1, 0, +1; §4.3.2).
    soft_limit: i8,
    /// 6061h as shown: it takes 6060h only in Operation enabled (§4.2.4).
    mode_shown: i8,
    /// Profile velocity ran (enabled) at the last step (§10.1 remark 2).
    in_pv: bool,
    /// Since when the speed error has been beyond 60F8h \[ns\] (§10.2.8).
    slipping_since: Option<u64>,
    /// Power-on work of the first step done.
    started: bool,
    /// Handles of the objects every step reads.
    refs: Refs,
    /// The drive memory behind 2064h–2069h (§17.2).
    memory: cam::Memory,
    /// Electronic camming (§12).
    cam: cam::Camming,
    /// Internal velocity units per velocity unit (6094h in force).
    velocity_iu: (u32, u32),
}

impl Ipos {
    /// The iPOS.
    pub fn new() -> Self {
        Ipos { legacy: Legacy { counter: 1, ..Legacy::default() }, velocity_iu: (1, 1), ..Ipos::default() }
    }

    /// Per step: limit switch EMCYs (§4.3.1), the PVT stop on an empty
    /// buffer and 2072h (§9.2.3).
    fn watch(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, refs: Refs) {
        let view = cx.drive.view();
        let lsn = view.digital_inputs & 1 != 0;
        let lsp = view.digital_inputs & 2 != 0;
        // §4.3.1: 60B8h bit 6 = 1 disables the limit switch EMCYs.
        let silent = u32_at(od, refs.limit_config).unwrap_or(0) & 0x40 != 0;
        for (now, was, code, bit) in [(lsp, self.limits.1, EMCY_LSP, 6u16), (lsn, self.limits.0, EMCY_LSN, 7)]
        {
            if now != was {
                let mer = u32_at(od, refs.motion_errors).unwrap_or(0) as u16;
                let mer = if now { mer | 1 << bit } else { mer & !(1 << bit) };
                if let Some(r) = refs.motion_errors {
                    od.set_le(r, &mer.to_le_bytes());
                }
                if now && !silent {
                    cx.request(
                        EmcyFrame { code, register: Some(error_register(code)), bytes: [0; 5] }.raise(),
                    );
                } else if !now {
                    // §4.3.1: "the emergency error code 0x0000 will be sent".
                    cx.request(Request::ClearEmcy(code));
                }
            }
        }
        self.limits = (lsn, lsp);
        // §4.3.2: the software limits act as limit switches (the drive
        // stops); FF06h / FF07h and 2002h bits 6 / 7 while one is passed,
        // 0000h when it is left.
        let soft = view.software_limit;
        if soft != self.soft_limit {
            for (side, code, bit) in
                [(1i8, EMCY_SOFT_LIMIT_POSITIVE, 6u16), (-1, EMCY_SOFT_LIMIT_NEGATIVE, 7)]
            {
                let (now, was) = (soft == side, self.soft_limit == side);
                if now == was {
                    continue;
                }
                let der = u32_at(od, refs.detailed_errors).unwrap_or(0) as u16;
                let der = if now { der | 1 << bit } else { der & !(1 << bit) };
                if let Some(r) = refs.detailed_errors {
                    od.set_le(r, &der.to_le_bytes());
                }
                cx.request(if now {
                    EmcyFrame { code, register: Some(error_register(code)), bytes: [0; 5] }.raise()
                } else {
                    Request::ClearEmcy(code)
                });
            }
            self.soft_limit = soft;
        }
        // §9.2.3 bit 11: PVT with the buffer run empty after a point whose
        // velocity is not 0: quick stop.
        if Self::legacy_of(u32_at(od, refs.aux_settings), i64_at(od, refs.sub_mode)) == Some(true)
            && Self::ip_active(cx)
            && self.ip.underflow()
            && self.legacy.last_velocity != 0
            && !self.legacy.quick_stopped
        {
            self.legacy.quick_stopped = true;
            let cw = (view.controlword & !0x0004) | 0x0002;
            let _ = cx.drive.on_write(od, 0x6040, 0, &cw.to_le_bytes());
        }
        self.publish_ip_status(cx, od, false);
    }
}

impl Behaviour for Ipos {
    fn profile(&self) -> Profile {
        Profile::Ipos
    }

    fn adjust_node_config(&self, cfg: &mut NodeConfig) {
        // §4.9.6 / inventory B.5: 1010h/1011h are not documented; 2076h saves.
        cfg.store_restore = false;
        cfg.heartbeat_consumers = 0;
        cfg.error_classes = 0;
        // CAN-only objects the manual does not have (no CoE meaning).
        cfg.sync_window = false;
        cfg.sync_counter = false;
        cfg.sdo_server_param = false;
    }

    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        cfg.params.encoder.counts_per_rev = COUNTS_PER_REV;
        // §10 / §1.3: the iPOS speed (606Ch) is increments per slow-loop
        // sample (1 ms): the encoder difference over one sample, not one
        // control period. A first-order lag of one sample on the measured
        // speed gives that resolution (one count per sample = 1 IU).
        cfg.params.control.velocity_filter = SPEED_FILTER_S;
        // Internal units (§1.3, §5): position = increments; velocity =
        // increments per slow-loop sample (1 ms) in 16.16 fixed point;
        // acceleration = increments per sample² in 16.16. The scaling
        // objects 6093h/6094h/210Fh (§5.2) convert to them, default 1/1;
        // 6091h/6092h/6096h/6097h are stored set-up parameters (factor.rs).
        cfg.factor = FactorGroup {
            scaling: Some(Scaling::unit(factor::VELOCITY_IU, factor::ACCELERATION_IU)),
            ..FactorGroup::increments(COUNTS_PER_REV)
        };
        cfg.initial_mode = 0;
        let p = &mut cfg.profile;
        // 133 IU = 133 increments per 1 ms sample = 4000 rpm at 2000
        // increments per revolution.
        p.max_profile_velocity = 133 << 16;
        p.profile_velocity = 33 << 16;
        p.profile_acceleration = 1 << 16;
        p.profile_deceleration = 1 << 16;
        p.quick_stop_deceleration = 4 << 16;
        p.following_error_window = COUNTS_PER_REV;
        p.position_window = 10;
        p.position_window_time = 0;
        p.velocity_window = 0xFFFF;
        p.velocity_threshold = 0xFFFF;
        // 6087h default 0 (§8.2.3). The manual does not say what 0 does:
        // the drive refuses torque motion (tq demand 0) until the master
        // sets a slope, as the §8.3 example does with 6075h and 6087h.
        p.torque_slope = 0;
        // 6080h default 0 = no speed limit (§15.2.3).
        cfg.zero_means_off.max_motor_speed = true;
        // 60A8h default 00B50100h (IU = increments), 60A9h/60AAh 0 (§5.2.1,
        // §5.2.6, §5.2.9: informative only).
        cfg.si_units = [0x00B5_0100, 0, 0, 0];
        // 60FEh:2 bit mask default 0 (§4.5.3); sub 1 keeps the command, the
        // outputs change when the mask is written.
        cfg.io.output_mask = 0;
        cfg.io.keep_unmasked_command = true;
        // §16: touch probe 1's own input is LSP, touch probe 2's LSN.
        cfg.io.probe_inputs = [ProbeInput::PositiveLimit, ProbeInput::NegativeLimit];
        // §7.2.6: 6086h = 0 trapezoidal or 3 jerk-limited (S-curve, jerk
        // time 2023h); 1 and 2 are reserved. §7.1.2: with the S-curve a
        // set-point with controlword bit 5 is a command error (EMCY 9000h).
        cfg.motion_profile_types = profile_type::LINEAR | profile_type::JERK_LIMITED;
        cfg.scurve_forbids_change_immediately = Some(EMCY_COMMAND_ERROR);
        // §6 / E18: "6064h = 607Ch" at the end of a homing: the drive
        // moves back to the home position after braking.
        cfg.homing_return_to_home = true;
        cfg.remote = true;
        // §4.3.2: 607Dh works like LSP/LSN in every mode.
        cfg.io.software_limit_switches = true;
        // §4.5.1 / §4.5.3: 60FDh bits 16–31 are IN0..IN15, 60FEh bits
        // 16–31 OUT0..OUT15: the machine's lines 1–16 (status.rs keeps the
        // outputs the iPOS360x has).
        cfg.io.input_lines = true;
        cfg.io.output_lines = true;
    }

    fn finish(&mut self, node: &mut drivebus_node::Node) {
        use crate::build::set_default;
        use drivebus_od::Value;
        let od = node.od_mut();
        // §8.2.2: 6075h motor rated current default 0 (set by the master,
        // as in the §8.3 example; the drive computes with at least 1 mA).
        set_default(od, 0x6075, 0, &Value::U32(0));
        // §4.6.1: 607Dh defaults 80000000h / 7FFFFFFFh = check disabled.
        set_default(od, 0x607D, 1, &Value::I32(i32::MIN));
        set_default(od, 0x607D, 2, &Value::I32(i32::MAX));
        // §15.2.3: 6080h default 0 (no limit, `zero_means_off`).
        set_default(od, 0x6080, 0, &Value::U32(0));
        // §6.3.5 / §6.3.6: homing speeds 1.0 IU (00010000h), homing
        // acceleration 0.1 IU (0000199Ah).
        set_default(od, 0x6099, 1, &Value::U32(0x0001_0000));
        set_default(od, 0x6099, 2, &Value::U32(0x0001_0000));
        set_default(od, 0x609A, 0, &Value::U32(0x0000_199A));
        // §5.2.5, §5.2.8, §5.2.11: feed constant, velocity and acceleration
        // factors 1/1 (set-up values; the scaling objects are in force).
        for index in [0x6092, 0x6096, 0x6097] {
            for sub in [1, 2] {
                set_default(od, index, sub, &Value::U32(1));
            }
        }
    }

    fn homing_methods(&self) -> Vec<Box<dyn HomingMethod + Send>> {
        (-4..=-1)
            .filter_map(MechanicalLimitHoming::new)
            .map(|m| Box::new(m) as Box<dyn HomingMethod + Send>)
            .collect()
    }

    fn manufacturer_mode(&self, mode: i8) -> Option<i8> {
        match mode {
            // −1 gearing (§11): the drive runs csp with the reference the
            // behaviour computes from the master position 201Eh (online).
            -1 => Some(8),
            // −2 camming (§12): the drive runs csp with the reference the
            // behaviour computes from the cam table (cam.rs).
            -2 => Some(8),
            _ => None,
        }
    }

    fn ip_mode(&self) -> IpMode {
        // §9.2.4: up to 000Fh points; the buffer state is 2072h and EMCY
        // FF01h (§9.2.3), not the drive's generic buffer warnings.
        IpMode::new(usize::from(IP_BUFFER_MAX)).with_monitor(self.ip.clone()).without_buffer_warnings()
    }

    fn hooked_objects(&self) -> &'static [u16] {
        &[
            0x1600, 0x1601, 0x1602, 0x1603, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x6086, 0x6075, 0x60C0, 0x60C1,
            0x2073, 0x2074, 0x208E, 0x201E, 0x2013, 0x2023, 0x60B8, 0x6093, 0x6094, 0x210F, 0x2110, 0x6097,
            0x608E, 0x2076, 0x2080, 0x2081, 0x2090, 0x2065, 0x2066, 0x2067, 0x2069, 0x2019, 0x2006, 0x2077,
            0x6040, 0x6060, 0x6066, 0x6068, 0x2070, 0x2071, 0x210B, 0x60FE, 0x60F2, 0x605E, 0x2113, 0x2114,
        ]
    }

    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        let le = |d: &[u8]| drivebus_od::le_u64(d);
        if factor::refuses_zero(index, sub) && le(data) == 0 {
            return Err(SdoAbort::VALUE_TOO_LOW);
        }
        // §3.2.6: with 2112h ≠ 0 the TML program has priority: 6060h and
        // 6040h are not written (local control).
        // (A handle: the controlword comes with every cycle's process data.)
        if matches!(index, 0x6040 | 0x6060) && u32_at(od, self.refs.fresh(od).tml_priority).unwrap_or(0) != 0
        {
            return Err(SdoAbort::LOCAL_CONTROL);
        }
        if let Some(v) = self.object_write(cx, od, index, sub, le(data)) {
            return v;
        }
        match (index, sub) {
            (0x6075, 0) => {
                // §8.2.2: default 0, set by the master; the drive computes
                // with at least 1 mA (the generic drive refuses 0).
                let ma = (le(data) as u32).max(1);
                cx.drive.on_write(od, 0x6075, 0, &ma.to_le_bytes())?;
                return Ok(Verdict::Store);
            }
            (0x60C0, 0) => {
                let v = le(data) as i16;
                let aux = od.get_u32(0x208E, 0).unwrap_or(u32::from(AUX_LINEAR_IP)) as u16;
                let old = od.get_i64(0x60C0, 0).unwrap_or(0) as i16;
                Self::drive_sub_mode(v, aux).ok_or(SdoAbort::INVALID_VALUE)?;
                if v != old {
                    // §9.2.1: changed only while interpolation is inactive;
                    // each change resets the buffer.
                    if Self::ip_active(cx) {
                        return Err(SdoAbort::DEVICE_STATE);
                    }
                    Self::sync_sub_mode(cx, od, v, aux)?;
                    self.clear_buffer(cx, od);
                }
                return Ok(Verdict::Store);
            }
            (0x208E, 0) => {
                let aux = le(data) as u16;
                let old = od.get_u32(0x208E, 0).unwrap_or(0) as u16;
                if (aux ^ old) & AUX_LINEAR_IP != 0 {
                    if Self::ip_active(cx) {
                        return Err(SdoAbort::DEVICE_STATE);
                    }
                    Self::sync_sub_mode(cx, od, od.get_i64(0x60C0, 0).unwrap_or(0) as i16, aux)?;
                    self.clear_buffer(cx, od);
                }
                return Ok(Verdict::Pass);
            }
            (0x60C1, 1 | 2) => {
                let Some(pvt) = Self::legacy_mode(od) else { return Ok(Verdict::Pass) };
                // X1 is kept until its X2 completes the point (the
                // integrity counter is in X2).
                if sub == 2 {
                    self.load_point(cx, od, pvt, le(data) as u32)?;
                }
                return Ok(Verdict::Store);
            }
            (0x2073, 0) => {
                // §9.2.4: a new length resets the buffer; 0 is not allowed.
                let n = le(data);
                if n == 0 {
                    return Err(SdoAbort::VALUE_TOO_LOW);
                }
                if n > u64::from(IP_BUFFER_MAX) {
                    return Err(SdoAbort::VALUE_TOO_HIGH);
                }
                cx.drive.on_write(od, 0x60C4, 2, &n.to_le_bytes())?;
                self.clear_buffer(cx, od);
                self.publish_ip_status(cx, od, false);
                return Ok(Verdict::Store);
            }
            (0x2074, 0) => {
                // Table 9.2.2.
                let v = le(data) as u16;
                let l = &mut self.legacy;
                l.unchecked = v & 1 << 14 != 0;
                l.from_demand = v & 1 << 12 != 0;
                if v & 1 << 13 != 0 {
                    l.counter = (v & 0x7F) as u8;
                    l.integrity_error = false;
                }
                if v & 1 << 7 != 0 {
                    l.low = (v >> 8) & 0xF;
                }
                if v & 1 << 15 != 0 {
                    self.clear_buffer(cx, od);
                }
                self.publish_ip_status(cx, od, false);
                return Ok(Verdict::Store);
            }
            _ => {}
        }
        if matches!(index, 0x1600..=0x1603 | 0x1A00..=0x1A03) && sub == 0 {
            let n = data.first().copied().unwrap_or(0);
            if n > 0 && mapped_bits(od, index, n) > MAX_PDO_BITS {
                // §1.6.3.1: the drive sends an EMCY and ignores the mapping.
                let reg = error_register(EMCY_PDO_LENGTH_EXCEEDED);
                cx.request(
                    EmcyFrame { code: EMCY_PDO_LENGTH_EXCEEDED, register: Some(reg), bytes: [0; 5] }.raw(),
                );
                return Ok(Verdict::Handled);
            }
        }
        Ok(Verdict::Pass)
    }

    fn after_write(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, sub: u8) {
        match (index, sub) {
            (0x6075, 0) => Self::sync_torque_reference(cx, od),
            // §7.2.19: the motor position := the value, in increments (not
            // scaled); 6063h, 6064h and 6062h follow.
            (0x2081, 0) => cx.drive.set_position_increments(od.get_i64(0x2081, 0).unwrap_or(0)),
            (0x2090, 1 | 2) => Self::digital_outputs_8bit(cx, od, sub),
            // §17.2.5 checksum; §12.2.1 cam table copy.
            (0x2069 | 0x2019, 0) => {
                let v = od.get_u32(index, 0).unwrap_or(0);
                let _ = self.memory_write(od, index, v);
            }
            (i, _) if factor::OBJECTS.contains(&i) => self.sync_scaling(cx, od),
            (0x2070 | 0x2071, _) => Self::sync_times(cx, od),
            (0x210B | 0x60F2, 0) => Self::sync_asr2(cx, od),
            (0x605E | 0x2113 | 0x2114, _) => Self::sync_fault_actions(cx, od),
            (0x2023, 0) => Self::sync_jerk(cx, od),
            // §16 / §4.3.1: 60B8h bit 6 = 1 frees LSP/LSN for the probes.
            (0x60B8, 0) => cx.drive.set_limit_switches(od.get_u32(0x60B8, 0).unwrap_or(0) & 0x40 == 0),
            (0x2013, 2) => {
                // §11.2.3: the ratio is computed when sub 2 is written; a
                // denominator 0 leaves the ratio as it was.
                let num = od.get_i64(0x2013, 1).unwrap_or(1) as i16;
                let den = od.get_u32(0x2013, 2).unwrap_or(1) as u16;
                if den != 0 {
                    self.gear.ratio = f64::from(num) / f64::from(den);
                }
            }
            // §11.2.6: 201Dh = 1, the master position comes online.
            (0x201E, 0) if od.get_u32(0x201D, 0) == Some(1) => {
                let m = od.get_i64(0x201E, 0).unwrap_or(0);
                self.gear_update(cx, od, m);
            }
            _ => {}
        }
    }

    fn on_event(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, event: &NodeEvent) {
        match event {
            NodeEvent::ResetApplication => {
                self.legacy = Legacy { counter: 1, ..Legacy::default() };
                self.gear = Gear::default();
                // The node forgot its errors: an active switch is reported
                // again, as at power-on.
                self.limits = (false, false);
                self.soft_limit = 0;
                self.mode_shown = 0;
                self.started = false;
            }
            NodeEvent::NmtState { .. } => {
                // The drive re-reads 60C0h and its rated torque (stored
                // parameters): give them the iPOS meaning again.
                let aux = od.get_u32(0x208E, 0).unwrap_or(u32::from(AUX_LINEAR_IP)) as u16;
                let _ = Self::sync_sub_mode(cx, od, od.get_i64(0x60C0, 0).unwrap_or(0) as i16, aux);
                Self::sync_torque_reference(cx, od);
                Self::sync_times(cx, od);
                Self::sync_asr2(cx, od);
                Self::sync_fault_actions(cx, od);
                self.sync_scaling(cx, od);
                if self.gear.active {
                    Self::gear_target(cx, od, self.gear.reference);
                }
            }
            _ => {}
        }
    }

    fn after_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        if !self.started {
            self.started = true;
            // Power-on: 2073h default 7 points (§9.2.4), the torque
            // reference of the power-on 6075h.
            let _ = cx.drive.on_write(od, 0x60C4, 2, &u64::from(IP_BUFFER_DEFAULT).to_le_bytes());
            Self::sync_torque_reference(cx, od);
            Self::sync_jerk(cx, od);
            self.sync_scaling(cx, od);
            Self::sync_asr2(cx, od);
            Self::sync_fault_actions(cx, od);
            // §4.9.7: 208Ah bit 0 = 1, a save (2076h) may be started; a
            // save completes at once.
            if let Ok(r) = od.find(0x208A, 0) {
                od.set_le(r, &1u16.to_le_bytes());
            }
        }
        // §11.2.6: 201Dh = 3, the master is the digital reference: the
        // machine's master encoder on the second encoder input (§11.3).
        let refs = self.refs.fresh(od);
        let m = cx.drive.model().master_position();
        if u32_at(od, refs.master_source) == Some(3) && self.second_taken != Some(m) {
            self.second_taken = Some(m);
            self.gear_update(cx, od, m);
        }
        // One snapshot for the rules below (the step is a hot path).
        let view = cx.drive.view();
        self.show_mode(cx, od, refs, view);
        self.enter_pv(cx, od, view);
        self.watch_slippage(cx, od, refs, view);
        self.gear_step(cx, od, refs);
        self.watch(cx, od, refs);
        self.publish_status(cx, od, refs, view);
        // §7.1.2 / Table 4.4.2: a command error sets 2000h bit 14, and the
        // S-curve update refused 2002h bit 9, until the fault reset.
        let err = cx.drive.command_error().is_some();
        for (r, bit) in [(refs.motion_errors, 14u16), (refs.detailed_errors, 9)] {
            let v = u32_at(od, r).unwrap_or(0) as u16;
            let n = if err { v | 1 << bit } else { v & !(1 << bit) };
            if n != v
                && let Some(r) = r
            {
                od.set_le(r, &n.to_le_bytes());
            }
        }
    }

    fn on_read(
        &mut self,
        _cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        _sub: u8,
    ) -> Result<(), SdoAbort> {
        // §17.2.3: each read of 2066h moves data from the memory.
        if index == 0x2066 {
            self.memory_read(od)?;
        }
        Ok(())
    }

    fn emcy(&self, code: u16) -> EmcyFrame {
        EmcyFrame { code, register: Some(error_register(code)), bytes: [0; 5] }
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod facts_tests {
    use super::*;
    use drivebus_cia402::homing::{HomingConfig, HomingContext, HomingEvent, MethodStep};
    use drivebus_cia402::model::EventKind;

    #[test]
    fn mechanical_limit_minus_3_travels_the_offset() {
        // §6: −3 runs negative into the limit, reverses and travels 607Ch.
        let cfg = HomingConfig {
            method: -3,
            switch_speed: 100.0,
            zero_speed: 10.0,
            acceleration: 1000.0,
            home_offset: 50.0,
            units_per_rev: f64::from(COUNTS_PER_REV),
        };
        let ctx = |position: f64, events: &'static [HomingEvent]| HomingContext {
            config: &cfg,
            position,
            velocity: 0.0,
            switches: Default::default(),
            events,
            torque: 0.0,
        };
        let mut m = MechanicalLimitHoming::new(-3).unwrap();
        assert_eq!(m.begin(&ctx(0.0, &[])), MethodStep::Move(-100.0));
        assert_eq!(m.update(&ctx(-10.0, &[])), MethodStep::Move(-100.0));
        static STOP: [HomingEvent; 1] = [HomingEvent {
            kind: EventKind::HardStop,
            active: false,
            position: -200.0,
            positive_direction: false,
        }];
        assert_eq!(m.update(&ctx(-200.0, &STOP)), MethodStep::Move(10.0));
        assert_eq!(m.update(&ctx(-170.0, &[])), MethodStep::Move(10.0));
        assert_eq!(m.update(&ctx(-150.0, &[])), MethodStep::Found(-150.0));
        assert!(MechanicalLimitHoming::new(-5).is_none());
    }

    #[test]
    fn master_increment_wraps_a_cyclic_master() {
        assert_eq!(master_increment(1990, 10, 2000), 20);
        assert_eq!(master_increment(10, 1990, 2000), -20);
        assert_eq!(master_increment(0, 500, 2000), 500);
        assert_eq!(master_increment(i64::from(i32::MAX), i64::from(i32::MIN), MASTER_FULL_RANGE), 1);
        assert_eq!(master_increment(5, 3, 0), -2);
    }

    #[test]
    fn legacy_points_decode_as_the_examples_pack_them() {
        // E26 point 2: 30000 counts, 2000 samples, IC 2.
        assert_eq!(
            LegacyPoint::pt(0x0000_7530, 0x0400_07D0),
            LegacyPoint { position: 30_000, velocity_16_8: 0, time: 2000, counter: 2 }
        );
        // E27 point 9: −1686 counts, −13.33 IU (FFF2ABh), 360 samples, IC 9.
        assert_eq!(
            LegacyPoint::pvt(0xFFAB_F96A, 0x1368_FFF2),
            LegacyPoint { position: -1686, velocity_16_8: -0xD55, time: 360, counter: 9 }
        );
        // IC 127 and the 9-bit time's top bit.
        assert_eq!(LegacyPoint::pvt(0, 0xFFFF_0000).counter, 127);
        assert_eq!(LegacyPoint::pvt(0, 0xFFFF_0000).time, 511);
    }

    #[test]
    fn sub_modes() {
        assert_eq!(Ipos::drive_sub_mode(0, AUX_LINEAR_IP), Some(0));
        assert_eq!(Ipos::drive_sub_mode(0, 0), Some(-1));
        assert_eq!(Ipos::drive_sub_mode(-1, 0), Some(-2));
        assert_eq!(Ipos::drive_sub_mode(1, 0), None);
        assert_eq!(Ipos::drive_sub_mode(-2, 0), None);
    }

    #[test]
    fn registers_use_bits_0_and_4() {
        assert_eq!(error_register(0x8220), 0x11);
        assert_eq!(error_register(0x8210), 0x11);
        assert_eq!(error_register(0x2310), 0x01);
        assert_eq!(error_register(0x0000), 0x00);
        for e in crate::Profile::Ipos.info().emcy {
            assert_eq!(error_register(e.code) & !0x11, 0);
        }
    }
}
