//! The DDS6's rules as functions and constants of its manual (§4–§6),
//! apart from the behaviour that applies them (`super::Dds6`).

use drivebus_cia402::homing::{HomingRegistry, StandardMethod};
use drivebus_cia402::state_machine::State;
use drivebus_od::ObjectDictionary;

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
