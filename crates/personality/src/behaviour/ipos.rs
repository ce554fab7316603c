//! Technosoft iPOS behaviour (*iPOS CoE Programming* P091.064.UM.0524,
//! seed002): the CiA 402 over EtherCAT object dictionary, served as a
//! CANopen personality (SDOs on 600h/580h + node-ID, PDOs with CiA 301
//! COB-IDs: the EtherCAT mailbox and state machine have no CAN equivalent).
//!
//! What a master sees that differs from a plain CiA 301/402 device:
//!
//! * modes −1 electronic gearing and −2 electronic camming (§11, §12) are
//!   accepted in 6060h and shown in 6061h; gearing/camming objects
//!   (2012h–201Eh, 206Bh/206Ch …) are plain parameters;
//! * ip (7) with the PT / PVT sub-modes 60C0h = 0 / −1 (§9), csp, csv, cst;
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
//! * no 1010h/1011h: 2076h saves, 2080h resets (§4.9.6).

use crate::Profile;
use crate::build::{Action, Behaviour, Context, EmcyFrame, Verdict};
use drivebus_cia402::drive::{DriveConfig, FactorGroup};
use drivebus_cia402::homing::{HomingContext, HomingMethod, MethodStep};
use drivebus_cia402::model::EventKind;
use drivebus_node::NodeConfig;
use drivebus_od::{ObjectDictionary, SdoAbort};

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

/// The iPOS homing methods on a mechanical limit (§6): −1 / −2 run into the
/// negative / positive limit, then reverse at 6099h:2 to the first index
/// pulse; −3 / −4 run into the limit, then travel |607Ch| back, and that
/// point reports 607Ch (so the limit is 0). The limit is detected when the
/// axis hits its end stop or stalls (the manual's current threshold
/// 207Bh/207Ch, or the control error of an open-loop stepper, is what such
/// a contact produces on the real drive).
#[derive(Debug, Clone, Copy)]
pub struct MechanicalLimitHoming {
    code: i8,
    /// Where the limit was met (position units), once met.
    limit: Option<f64>,
}

impl MechanicalLimitHoming {
    /// Method −1..−4; `None` otherwise.
    pub fn new(code: i8) -> Option<Self> {
        (-4..=-1).contains(&code).then_some(MechanicalLimitHoming { code, limit: None })
    }

    fn towards_positive(&self) -> bool {
        matches!(self.code, -2 | -4)
    }

    fn with_index(&self) -> bool {
        matches!(self.code, -1 | -2)
    }
}

impl HomingMethod for MechanicalLimitHoming {
    fn code(&self) -> i8 {
        self.code
    }

    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        self.limit = None;
        let v = ctx.config.switch_speed;
        MethodStep::Move(if self.towards_positive() { v } else { -v })
    }

    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        let away = if self.towards_positive() { -1.0 } else { 1.0 };
        let slow = ctx.config.zero_speed * away;
        match self.limit {
            None => {
                if let Some(e) =
                    ctx.events.iter().find(|e| matches!(e.kind, EventKind::HardStop | EventKind::Stall))
                {
                    self.limit = Some(e.position);
                    return MethodStep::Move(slow);
                }
                let v = ctx.config.switch_speed;
                MethodStep::Move(if self.towards_positive() { v } else { -v })
            }
            Some(at) => {
                if self.with_index() {
                    if let Some(e) = ctx.events.iter().find(|e| e.kind == EventKind::Index) {
                        return MethodStep::Found(e.position);
                    }
                } else if (ctx.position - at).abs() >= ctx.config.home_offset.abs() {
                    return MethodStep::Found(ctx.position);
                }
                MethodStep::Move(slow)
            }
        }
    }
}

/// The iPOS quirks around the CiA 402 drive.
#[derive(Debug, Clone, Copy, Default)]
pub struct Ipos;

impl Ipos {
    /// The iPOS.
    pub fn new() -> Self {
        Ipos
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
        // Internal units (§1.3, §5): position = increments; velocity =
        // increments per slow-loop sample (1 ms) in 16.16 fixed point;
        // acceleration = increments per sample² in 16.16. Factors in
        // position units/s per velocity unit: 1000/65536, 10^6/65536.
        cfg.factor = FactorGroup {
            velocity_factor: (125, 8192),
            acceleration_factor: (15_625, 1024),
            ..FactorGroup::increments(COUNTS_PER_REV)
        };
        // §5.2.2: the conversion is the position factor 6093h (set by
        // EasyMotion Studio); 6091h/6092h/6096h/6097h are stored set-up
        // parameters, default 1/1 (§5.2.5, §5.2.8, §5.2.11).
        cfg.fixed_factor_group = true;
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
        cfg.remote = true;
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
        // factors 1/1 (stored; `fixed_factor_group` keeps internal units).
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
        // −1 gearing, −2 camming (§4.2.3): accepted and displayed; the drive
        // holds its position under profile position (the master-following
        // motion is not emulated, docs/personalities.md).
        matches!(mode, -1 | -2).then_some(1)
    }

    fn hooked_objects(&self) -> &'static [u16] {
        &[0x1600, 0x1601, 0x1602, 0x1603, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x6086]
    }

    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        if index == 0x6086 && data.first() == Some(&3) {
            // §7.3.3/§7.3.4 (E21/E22): 6086h = 3 selects the jerk-limited
            // S-curve (jerk time 2023h). Accepted and stored; the drive
            // keeps its own ramp shape (S-curve not emulated).
            return Ok(Verdict::Store);
        }
        if matches!(index, 0x1600..=0x1603 | 0x1A00..=0x1A03) && sub == 0 {
            let n = data.first().copied().unwrap_or(0);
            if n > 0 && mapped_bits(od, index, n) > MAX_PDO_BITS {
                // §1.6.3.1: the drive sends an EMCY and ignores the mapping.
                let reg = error_register(EMCY_PDO_LENGTH_EXCEEDED);
                cx.actions.push(Action::RawEmcy(EmcyFrame {
                    code: EMCY_PDO_LENGTH_EXCEEDED,
                    register: Some(reg),
                    bytes: [0; 5],
                }));
                return Ok(Verdict::Handled);
            }
        }
        Ok(Verdict::Pass)
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
    use drivebus_cia402::homing::{HomingConfig, HomingEvent};

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
