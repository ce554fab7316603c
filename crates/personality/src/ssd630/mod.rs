//! SSD Drives 630 series behaviour (*CANopen-630* manual V0904, seed003).
//!
//! What a master sees that differs from a plain CiA 301/402 device:
//!
//! * an unknown index is answered `0601 0000h`, not `0602 0000h` (§14.1);
//! * after initialisation (power-on and NMT reset node) an EMCY 0000h "no
//!   error" carries the firmware version as ASCII "Vxxxx" in bytes 3–7 (§9
//!   transition 0, Table 1);
//! * the state machine follows the controlword only while the "Controller
//!   Active" input X10.7 is at 24 V: statusword bit 9 "remote" shows it and
//!   Shutdown is not accepted without it (§10.2); dropping the input goes
//!   to Switch on disabled or, with 2019h = 1, to Fault (§10.2, §11 2019h);
//! * node guarding is answered but 100Ch/100Dh are not evaluated and stay 0
//!   (§8): writes are accepted and ignored; there is no heartbeat (§8, B.8);
//! * homing methods are the drive's own modes 0..23 written as −24..−1 in
//!   6098h, 0 = no homing, 6099h:2 unused (§12 6098h/6099h, §14.10);
//! * PDO mappings may be changed in pre-operational while the PDO is valid:
//!   writing sub 0 checks and activates the mapping (§7); in operational
//!   the write is refused with `0800 0022h` (§5 "due to the actual device
//!   state (… PDO not activated …)");
//! * EMCY error register per code as in §9 Table 1 (03h, 05h, 09h, 21h, 81h);
//! * 60FFh must be 0 before leaving profile velocity (§14.15 note): a mode
//!   change with 60FFh ≠ 0 while in pv is refused with `0800 0022h`;
//! * with transmission type 254 only the bits the masks 2014h–2017h select
//!   trigger a TPDO (§7, §11); configuration mode 5 (4804h:05) ignores the
//!   controlword (§1.4); the behaviour ledger is `ledger.tsv`;
//! * 2018h = 1 "NMT state (operational after power on)" (§11): after the
//!   boot-up message the drive goes operational by itself (value as
//!   loaded from storage at power-on). NMT Reset Node, which CiA 301
//!   §7.3.2.1 defines as the application's power-on reset, does the same;
//!   Reset Communication does not (it is no power-on).

mod emcy;
mod facts;

pub use facts::INFO;

/// The EDS file (`crates/personality/eds/ssd630.eds`).
pub const EDS: &str = include_str!("../../eds/ssd630.eds");

use drivebus_cia402::homing::{
    HomingConfig, HomingContext, HomingMethod, HomingRegistry, MethodStep, StandardMethod,
};

/// The firmware version the "no error" EMCY carries (§9 Table 1: "Vxxxx",
/// xxxx = firmware version, the manual's example "819d").
pub const FIRMWARE_TAG: [u8; 5] = *b"V819d";

/// The abort for a missing object (§14.1: `80 34 12 00 00 00 01 06`).
pub const MISSING_OBJECT_ABORT: u32 = 0x0601_0000;

/// The abort for a write the present device state forbids (§5 0800 0022h).
pub const STATE_ABORT: u32 = 0x0800_0022;

/// The error register (1001h) the 630 sends with each EMCY code
/// (§9 Table 1, column "630 Error register nr."). `None` for codes the
/// table does not list.
pub fn error_register(code: u16) -> Option<u8> {
    Some(match code {
        0x0000 => 0x00,
        0x2230 | 0x2311 | 0x2312 => 0x03,
        0x3210 | 0x3220 | 0x5110 => 0x05,
        0x4210 | 0x4310 | 0x7113 => 0x09,
        0x5441 | 0x5442 | 0x5443 | 0x5530 | 0x6010 | 0x6100 | 0x6200 | 0x7300 => 0x81,
        0x8400 | 0x8611 | 0x8612 | 0x8700 => 0x21,
        _ => return None,
    })
}

/// §7, §11 2014h–2017h: with transmission type 254 only the bits set in
/// TPDO `n`'s mask (sub 1 bytes 0–3, sub 2 bytes 4–7) trigger it ("Only
/// valid in transmission type 254"); any other type, or all bits set (the
/// default, "all bits are event driven"), sends on any change.
pub fn tpdo_change_mask(od: &ObjectDictionary, n: u16) -> Option<[u8; 8]> {
    if od.get_u32(0x1800 + n, 2) != Some(254) {
        return None;
    }
    let lo = od.get_u32(0x2014 + n, 1).unwrap_or(u32::MAX);
    let hi = od.get_u32(0x2014 + n, 2).unwrap_or(u32::MAX);
    if lo == u32::MAX && hi == u32::MAX {
        return None;
    }
    let mut m = [0u8; 8];
    m[..4].copy_from_slice(&lo.to_le_bytes());
    m[4..].copy_from_slice(&hi.to_le_bytes());
    Some(m)
}

fn tpdo_mask_request(od: &ObjectDictionary, n: u16) -> Request {
    Request::TpdoChangeMask { tpdo: n, mask: tpdo_change_mask(od, n) }
}

/// The EMCY "no error" frame data sent after initialisation (§9, 0.):
/// code 0000h, error register 00h, "Vxxxx".
pub fn boot_emcy_data() -> [u8; 8] {
    let t = FIRMWARE_TAG;
    [0, 0, 0, t[0], t[1], t[2], t[3], t[4]]
}

/// The CiA 402 method each SSD homing mode is emulated with, indexed by
/// the SSD mode 0..23 (6098h = mode − 24).
///
/// The manual describes only mode 0 ("reference to the next zero pulse in
/// positive direction", §14.10: method −24 = E8h); the descriptions of the
/// others are behind a lost link ("refer to homing method"). So that every
/// accepted code homes plausibly, modes 1..23 are assigned to the standard
/// methods using the sensors a 630 has (limit switches, reference switch,
/// zero pulse): this assignment is drivebus's, not the manual's
/// (docs/personalities.md says so).
pub const HOMING_EQUIVALENT: [i8; 24] =
    [34, 33, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 17, 18, 19, 20, 21, 22, 23, 35];

/// The 6098h code of SSD homing mode `mode` (0..23 → −24..−1).
pub const fn homing_code(mode: u8) -> i8 {
    mode as i8 - 24
}

/// One SSD homing mode: a standard method under a negative code, with
/// 6099h:2 ignored (§12: "This value is unused with modes −24..−1") — the
/// zero-pulse search runs at 6099h:1 too.
pub struct SsdHoming {
    code: i8,
    inner: StandardMethod,
}

impl SsdHoming {
    /// SSD mode `mode` (0..23); `None` outside.
    pub fn new(mode: u8) -> Option<Self> {
        let std = *HOMING_EQUIVALENT.get(mode as usize)?;
        Some(SsdHoming { code: homing_code(mode), inner: StandardMethod::new(std)? })
    }

    fn ctx<'a>(cfg: &'a HomingConfig, ctx: &HomingContext<'a>) -> HomingContext<'a> {
        HomingContext { config: cfg, ..*ctx }
    }

    fn with_one_speed(ctx: &HomingContext<'_>) -> HomingConfig {
        HomingConfig { zero_speed: ctx.config.switch_speed, ..*ctx.config }
    }
}

impl HomingMethod for SsdHoming {
    fn code(&self) -> i8 {
        self.code
    }

    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        let cfg = Self::with_one_speed(ctx);
        self.inner.begin(&Self::ctx(&cfg, ctx))
    }

    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        let cfg = Self::with_one_speed(ctx);
        self.inner.update(&Self::ctx(&cfg, ctx))
    }
}

/// The 630's homing methods: −24..−1 only (§12 6098h; standard positive
/// methods are not mentioned, so not offered: faithful by default).
pub fn homing_registry() -> HomingRegistry {
    let mut r = HomingRegistry::empty();
    for mode in 0..24 {
        if let Some(m) = SsdHoming::new(mode) {
            r.register(Box::new(m));
        }
    }
    r
}

#[cfg(test)]
mod facts_tests {
    use super::*;

    #[test]
    fn homing_codes_are_minus_24_to_minus_1() {
        // §12 6098h: "The homing modes 0..23 must appear as values -24..-1".
        let r = homing_registry();
        let codes: Vec<i8> = r.codes().collect();
        assert_eq!(codes, (-24..=-1).collect::<Vec<i8>>());
        assert!(!r.is_supported(0) && !r.is_supported(1) && !r.is_supported(34));
        // §14.10: −24 (E8h) is the next zero pulse in positive direction.
        assert_eq!(homing_code(0), -24);
        assert_eq!(-24i8 as u8, 0xE8);
        assert_eq!(HOMING_EQUIVALENT[0], 34);
    }

    #[test]
    fn emcy_registers_from_table_1() {
        // §9 Table 1.
        assert_eq!(error_register(0x2230), Some(0x03));
        assert_eq!(error_register(0x3220), Some(0x05));
        assert_eq!(error_register(0x4310), Some(0x09));
        assert_eq!(error_register(0x5441), Some(0x81));
        assert_eq!(error_register(0x8611), Some(0x21));
        assert_eq!(error_register(0x1234), None);
        // Every code of the transcribed table has a register.
        for e in crate::Profile::Ssd630.info().emcy {
            assert!(error_register(e.code).is_some(), "{:04X}", e.code);
        }
    }

    #[test]
    fn boot_emcy_carries_firmware() {
        // §9: 'V' + 4 characters of firmware version, e.g. 819d.
        assert_eq!(boot_emcy_data(), [0, 0, 0, b'V', b'8', b'1', b'9', b'd']);
    }
}

// ---------------------------------------------------------------------------
// The behaviour.

use crate::Profile;
use crate::build::{Behaviour, Context, EmcyFrame, Verdict};
use drivebus_cia402::drive::{DriveConfig, FactorGroup, Injection};
use drivebus_cia402::state_machine::State;
use drivebus_nmt::NmtCommand;
use drivebus_node::{NmtState, Node, NodeConfig, NodeEvent, Request};
use drivebus_od::{ObjectDictionary, SdoAbort, Value};

/// Encoder increments per motor revolution of the emulated 630 (the manual
/// gives none; 5C03h "encoder resolution" has no value): a 1024-line
/// encoder evaluated ×4. Position units are increments (§4: factor = 1).
pub const COUNTS_PER_REV: u32 = 4096;

/// The SSD 630 quirks around the CiA 402 drive.
#[derive(Debug, Clone)]
pub struct Ssd630 {
    /// X10.7 "Controller Active" input at 24 V (§10.2; §14.8 settings).
    enable_input: bool,
    /// NMT state as last reported (PDO definitions only in pre-operational, §7).
    nmt: NmtState,
    /// The statusword last shown.
    last: u16,
    /// An NMT Reset Node is under way: the next boot is a power-on (2018h).
    reset_node: bool,
}

impl Default for Ssd630 {
    fn default() -> Self {
        Ssd630 { enable_input: true, nmt: NmtState::PreOperational, last: 0, reset_node: false }
    }
}

impl Ssd630 {
    /// The 630 with the enable input wired to 24 V (as in every example).
    pub fn new() -> Self {
        Self::default()
    }

    /// The 630 with the enable input at `on` from power-on.
    pub fn with_enable_input(on: bool) -> Self {
        Ssd630 { enable_input: on, ..Self::default() }
    }

    /// Sets the X10.7 enable input. Dropping it while the drive is switched
    /// on takes the drive to Switch on disabled, or to Fault (EMCY 5441h
    /// "contact 1 = enable input") when 2019h = 1 (§10.2 transitions 13/14,
    /// §11 2019h); applied at the next control period.
    pub fn set_enable_input(&mut self, on: bool) {
        self.enable_input = on;
    }

    /// The enable input.
    pub fn enable_input(&self) -> bool {
        self.enable_input
    }

    /// The statusword as the 630 shows it, from the drive's CiA 402 one.
    ///
    /// * bit 9 "remote" = the enable input (§10.2: "If the conditions are
    ///   fulfilled, the remote bit in the statusword will be set");
    /// * bits 4/5 as printed in §14.8: Switch on disabled 0240h (bit 5
    ///   clear), Ready to switch on 0231h, Switched on 0233h, Operation
    ///   enabled 0627h (bit 4 clear);
    /// * bit 15 (manufacturer-specific): set in every printed statusword
    ///   with bit 12 (9227h, 9627h in §14.9–§14.11) and in none without it
    ///   (0627h): emulated as a copy of bit 12.
    pub fn statusword(&self, drive_sw: u16, state: State) -> u16 {
        let mut sw = drive_sw & !(1 << 9) & !(1 << 15);
        if self.enable_input {
            sw |= 1 << 9;
        }
        match state {
            State::SwitchOnDisabled => sw &= !0x30,
            State::OperationEnabled => sw &= !0x10,
            _ => {}
        }
        if matches!(state, State::OperationEnabled) && sw & (1 << 12) != 0 {
            sw |= 1 << 15;
            // §14.11 steps 7–8: a new set-point is first acknowledged with
            // "target reached" still set (9627h), the next status drops it
            // (9227h): the first statusword with bit 12 keeps bit 10.
            if self.last & (1 << 12) == 0 && self.last & (1 << 10) != 0 {
                sw |= 1 << 10;
            }
        }
        sw
    }

    /// The end of an initialisation (power-on, NMT reset node): the stored
    /// values are loaded by now (node boot before this).
    fn initialised(cx: &mut Context<'_>, od: &ObjectDictionary) {
        // §9 transition 0: "After the initialisation … the message 'no
        // error' is being sent", manufacturer field "Vxxxx".
        cx.request(EmcyFrame { code: 0, register: Some(0), bytes: FIRMWARE_TAG }.raw());
        for n in 0..4 {
            cx.request(tpdo_mask_request(od, n));
        }
        Self::autostart(cx, od);
    }

    /// §11 2018h: 1 = "NMT state (operational after power on)": the local
    /// Start that follows the boot-up message.
    fn autostart(cx: &mut Context<'_>, od: &ObjectDictionary) {
        if od.get_u32(0x2018, 0) == Some(1) {
            cx.request(Request::Nmt(NmtCommand::Start));
        }
    }

    fn pdo_comm_of(index: u16) -> Option<u16> {
        match index {
            0x1600..=0x1603 => Some(index - 0x200),
            0x1A00..=0x1A03 => Some(index - 0x200),
            _ => None,
        }
    }

    fn publish(&mut self, cx: &Context<'_>, od: &mut ObjectDictionary) {
        let sm = cx.drive.state_machine().state();
        let sw = self.statusword(cx.drive.statusword(), sm);
        self.last = sw;
        if let Ok(r) = od.find(0x6041, 0) {
            od.set_le(r, &sw.to_le_bytes());
        }
    }
}

impl Behaviour for Ssd630 {
    fn profile(&self) -> Profile {
        Profile::Ssd630
    }

    fn adjust_node_config(&self, cfg: &mut NodeConfig) {
        // §14.7: a 631 answers "631_402".
        cfg.device_name = Some("631_402".into());
        // §8: node guarding only; 100Ch/100Dh not evaluated.
        cfg.nmt.heartbeat_supported = false;
        cfg.nmt.life_guarding_honoured = false;
        cfg.heartbeat_consumers = 0;
        cfg.error_classes = 0;
        // EX14.1: a missing index is answered with 0601 0000, not 0602 0000.
        cfg.sdo.missing_object = drivebus_od::SdoAbort::UNSUPPORTED_ACCESS;
        // §4's object list has no 1007h, 1019h or 1200h.
        cfg.sync_window = false;
        cfg.sync_counter = false;
        cfg.sdo_server_param = false;
    }

    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        cfg.params.encoder.counts_per_rev = COUNTS_PER_REV;
        // Position in increments (§4: "factor = 1"), velocities in min⁻¹
        // (§14.9: 6081h = 1000 is "1000 min⁻¹"; §14.10: 6099h:1 = 50 is
        // "50 min⁻¹"), accelerations in min⁻¹/s (unit not stated; chosen to
        // match). Velocity factor = increments/s per min⁻¹ = cpr / 60.
        cfg.factor = FactorGroup {
            velocity_factor: (COUNTS_PER_REV, 60),
            acceleration_factor: (COUNTS_PER_REV, 60),
            ..FactorGroup::increments(COUNTS_PER_REV)
        };
        // §10: after power-on always profile position.
        cfg.initial_mode = 1;
        let p = &mut cfg.profile;
        p.max_profile_velocity = 3000;
        p.profile_velocity = 1000;
        p.profile_acceleration = 10_000;
        p.profile_deceleration = 10_000;
        p.quick_stop_deceleration = 30_000;
        p.max_acceleration = u32::MAX;
        p.following_error_window = COUNTS_PER_REV;
        p.position_window = 10;
        p.position_window_time = 0;
        p.velocity_window = 10;
        p.velocity_threshold = 10;
        cfg.remote = true;
    }

    fn homing_methods(&self) -> Vec<Box<dyn HomingMethod + Send>> {
        (0..24u8)
            .filter_map(|m| SsdHoming::new(m).map(|h| Box::new(h) as Box<dyn HomingMethod + Send>))
            .collect()
    }

    fn hooked_objects(&self) -> &'static [u16] {
        &[
            0x100C, 0x100D, 0x1400, 0x1401, 0x1402, 0x1403, 0x1600, 0x1601, 0x1602, 0x1603, 0x1800, 0x1801,
            0x1802, 0x1803, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x6040, 0x6099, 0x1006, 0x6080, 0x2014, 0x2015,
            0x2016, 0x2017, 0x6060, 0x6048, 0x4803,
        ]
    }

    fn finish(&mut self, node: &mut Node) {
        let id = node.node_id();
        let od = node.od_mut();
        // §14.7 / §14.6: device name and the pre-DS301-v4 node-ID object.
        crate::build::set_default(od, 0x1008, 0, &Value::Str("631_402".into()));
        crate::build::set_default(od, 0x100B, 0, &Value::U32(u32::from(id)));
        // §8: guard time and life time factor are 0 after power-on.
        crate::build::set_default(od, 0x100C, 0, &Value::U16(0));
        crate::build::set_default(od, 0x100D, 0, &Value::U8(0));
    }

    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        match index {
            // §8: "not being evaluated by the controller and are always 0":
            // accepted (§4 lists them rw) and dropped.
            0x100C | 0x100D => Ok(Verdict::Handled),
            // §12: 6080h is an ARRAY, sub 1 the negative and sub 2 the
            // positive max motor speed (UNSIGNED16, min⁻¹). The drive
            // model limits both directions alike: with the lower one.
            0x6080 if sub == 1 || sub == 2 => {
                let other = od.get_u64(0x6080, 3 - sub).unwrap_or(0);
                let limit = drivebus_od::le_u64(data).min(other) as u32;
                cx.drive.on_write(od, 0x6080, 0, &limit.to_le_bytes())?;
                Ok(Verdict::Store)
            }
            // Writing back what a PDO object holds modifies nothing: taken
            // in any NMT state.
            0x1400..=0x1403 | 0x1600..=0x1603 | 0x1800..=0x1803 | 0x1A00..=0x1A03
                if od.get_u64(index, sub) == Some(drivebus_od::le_u64(data)) =>
            {
                Ok(Verdict::Handled)
            }
            0x1400..=0x1403 | 0x1600..=0x1603 | 0x1800..=0x1803 | 0x1A00..=0x1A03 => {
                // §7: "Modifications of the PDO definitions are permitted in
                // operating state Pre-operational only" — elsewhere §5's
                // 0800 0022h ("due to the actual device state").
                if self.nmt != NmtState::PreOperational {
                    return Err(SdoAbort(STATE_ABORT));
                }
                // §7: the mapping is checked and activated by writing sub 0
                // ("number_of_mapped_objects"); the COB-ID need not be
                // invalidated first (§14.12/§14.13 remap the valid PDO1).
                // The CiA 301 service insists on an invalid PDO: lift that
                // for this one write and put the COB-ID back afterwards.
                if let Some(comm) = Self::pdo_comm_of(index)
                    && let Some(cob) = od.get_u32(comm, 1)
                    && cob & 0x8000_0000 == 0
                {
                    if let Ok(r) = od.find(comm, 1) {
                        od.set_raw(r, &(cob | 0x8000_0000).to_le_bytes());
                    }
                    cx.request(Request::Restore {
                        index: comm,
                        sub: 1,
                        value: cob,
                        only_if: Some(cob | 0x8000_0000),
                    });
                }
                let _ = sub;
                Ok(Verdict::Pass)
            }
            // §14.15: "The object 60FFh must be set to 0 before the
            // operating mode is changed": leaving pv with a target velocity
            // is refused (§5 0800 0022h, "operating mode wrong").
            0x6060
                if cx.drive.mode() == 3
                    && data.first().is_some_and(|&m| m as i8 != 3)
                    && od.get_i64(0x60FF, 0).is_some_and(|v| v != 0) =>
            {
                Err(SdoAbort(STATE_ABORT))
            }
            0x6040 if !self.enable_input => {
                // §10.2: without the enable input the drive is not "remote"
                // and does not follow the controlword (Shutdown refused):
                // the value is stored, the state machine does not move.
                Ok(Verdict::Store)
            }
            // §1.4 configuration mode 5 (4804h:05) "CANopen configuration
            // DS301 + PDO mapping": "The control of the DS402 State-machine
            // is being ignored. 6040h, 6041h … are not being evaluated".
            0x6040 if od.get_u32(0x4804, 5) == Some(5) => Ok(Verdict::Store),
            0x6040 => {
                // The drive takes the controlword now; the statusword it
                // publishes is put in the 630's form before a TPDO samples it.
                cx.drive.on_write(od, index, sub, data)?;
                self.publish(cx, od);
                Ok(Verdict::Store)
            }
            0x6099 if sub == 1 => {
                // §12: 6099h:2 "is unused with modes -24..-1": the drive runs
                // the zero-pulse search at 6099h:1 as well (the SsdHoming
                // methods do), and 6099h:2 must not block the start.
                let _ = cx.drive.on_write(od, 0x6099, 2, data);
                Ok(Verdict::Pass)
            }
            _ => Ok(Verdict::Pass),
        }
    }

    fn after_write(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, sub: u8) {
        match index {
            0x2014..=0x2017 => cx.request(tpdo_mask_request(od, index - 0x2014)),
            0x1800..=0x1803 if sub == 2 => cx.request(tpdo_mask_request(od, index - 0x1800)),
            // §12: "acceleration and deceleration are calculated
            // symmetrically in velocity mode": 6048h is the deceleration too.
            0x6048 if sub > 0 => {
                if let Some(v) = od.get_u64(0x6048, sub) {
                    let b = v.to_le_bytes();
                    let n = if sub == 1 { 4 } else { 2 };
                    let _ = cx.drive.on_write(od, 0x6049, sub, &b[..n]);
                }
            }
            _ => {}
        }
        if index == 0x1006 {
            // §14.13: "interpolation time 5000 µs" is written to 1006h; the
            // 630 runs ip on that cycle. The drive's ip reads 60C2h, so the
            // period is carried over (value · 10^index s).
            let us = od.get_u32(0x1006, 0).unwrap_or(0);
            let (v, i): (u32, i8) = if us.is_multiple_of(1000) && us / 1000 <= 255 {
                (us / 1000, -3)
            } else if us <= 255 {
                (us, -6)
            } else {
                ((us / 1000).min(255), -3)
            };
            if v > 0 {
                for (sub, b) in [(1u8, v as u8), (2u8, i as u8)] {
                    if cx.drive.on_write(od, 0x60C2, sub, &[b]).is_ok()
                        && let Ok(r) = od.find(0x60C2, sub)
                    {
                        od.set_raw(r, &[b]);
                    }
                }
            }
        }
    }

    fn on_boot(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        Self::initialised(cx, od);
    }

    fn on_event(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, event: &NodeEvent) {
        match *event {
            // Reported before the stored values are reloaded: decide at
            // the end of the boot that follows.
            NodeEvent::ResetApplication => self.reset_node = true,
            NodeEvent::NmtState { from, to } => {
                self.nmt = to;
                if from.is_initialisation() && core::mem::take(&mut self.reset_node) {
                    Self::initialised(cx, od);
                }
            }
            _ => {}
        }
    }

    fn after_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        if !self.enable_input {
            let state = cx.drive.state_machine().state();
            if !matches!(state, State::SwitchOnDisabled | State::NotReadyToSwitchOn | State::Fault) {
                // §10.2 transitions 13/14 and §11 2019h: 0 = Switch on
                // disabled, 1 = FAULT (EMCY 5441h, Table 1).
                if od.get_u32(0x2019, 0).unwrap_or(0) == 1 {
                    if state != State::FaultReactionActive {
                        cx.drive.inject(Injection::Fault(0x5441));
                    }
                } else {
                    let _ = cx.drive.on_write(od, 0x6040, 0, &[0, 0]);
                }
            }
        }
        self.publish(cx, od);
    }

    fn on_read(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
    ) -> Result<(), SdoAbort> {
        // §13 4803h "Drive information" (units not given): 05h motor
        // temperature in °C, 06h the DC link Ucc in V, 07h the analog input
        // X10 in mV (two's complement), from the machine.
        let m = cx.drive.model();
        let v = match (index, sub) {
            (0x4803, 5) => m.temperature().round().clamp(0.0, 65535.0) as u16,
            (0x4803, 6) => m.bus_voltage().round().clamp(0.0, 65535.0) as u16,
            (0x4803, 7) => (m.analog_input(1) * 1000.0).round().clamp(-32768.0, 32767.0) as i16 as u16,
            _ => return Ok(()),
        };
        if let Ok(r) = od.find(index, sub) {
            od.set_le(r, &v.to_le_bytes());
        }
        Ok(())
    }

    fn emcy(&self, code: u16) -> EmcyFrame {
        // §9 Table 1: the register per code; manufacturer bytes all 00h.
        EmcyFrame { code, register: error_register(code), bytes: [0; 5] }
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }
}
