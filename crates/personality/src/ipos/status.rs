//! The iPOS status objects that mirror the drive (§4.4, §4.5): the fault
//! bits of the motion error register 2000h, the outputs status 2045h, the
//! 8-bit input and output images 208Fh / 2090h, the brake status 2102h,
//! the auxiliary encoder 208Dh; the outputs the iPOS360x has.

/// OUT0..OUT3 as 60FEh bits: the outputs of the emulated iPOS360x VX-CAT
/// ("the actual number of available digital outputs is product
/// dependent", §4.5.3; the manual names OUT0, OUT1, Error/OUT2 and
/// Ready/OUT3 for this family, §3.2.3, §4.5.3.1; OUT5 "may not be
/// available", §4.9.5).
pub const AVAILABLE_OUTPUTS: u32 = 0x000F_0000;

/// Full scale of the analogue inputs \[V\]: 0…65520 IU (§4.5.7, §4.5.8) is
/// unipolar; the iPOS360x's span is not in the manual, 0…5 V is our
/// reading (docs/personalities.md).
pub const ANALOG_FULL_SCALE_V: f64 = 5.0;

/// EMCY FF05h "specified digital I/O line not available" (§4.5.3).
pub const EMCY_IO_NOT_AVAILABLE: u16 = 0xFF05;

use super::*;
use drivebus_cia402::drive::{DriveView, ErrorReaction};
use drivebus_cia402::state_machine::Reaction;

/// 2000h bits this module keeps (Table 4.4.2): 3 control error, 4
/// communication error, 5 feedback error, 8 over-current, 10 motor
/// over-temperature, 12 over-voltage, 13 under-voltage. Bits 0, 6, 7 and
/// 14 are kept where their conditions are watched (ESM, limit switches,
/// command error).
const FAULT_BITS: u16 = 1 << 3 | 1 << 4 | 1 << 5 | 1 << 8 | 1 << 10 | 1 << 12 | 1 << 13;

/// The 2000h fault bits of the drive's present faults: "set when the
/// protection is triggered, reset by a Reset Fault command" (Table 4.4.2).
fn fault_bits(cx: &Context<'_>, view: DriveView, error_code: u16) -> u16 {
    let f = cx.drive.model().faults();
    // A protection taken without action (605Eh −1, 2113h) shows while its
    // condition lasts.
    let ignored =
        cx.drive.ignored_fault().and_then(|c| PROTECTIONS.iter().find(|p| p.0 == c)).map_or(0, |p| 1 << p.1);
    let mut bits = ignored
        | u16::from(f.over_current) << 8
        | u16::from(f.over_temperature) << 10
        | u16::from(f.over_voltage) << 12
        | u16::from(f.under_voltage) << 13
        | u16::from(f.encoder) << 5;
    if matches!(view.state, State::Fault | State::FaultReactionActive) {
        bits |= match error_code {
            // Control error: the following error fault (Table 3.1.3 8611h).
            0x8611 => 1 << 3,
            // Communication error (node guarding / NMT, 7500h).
            0x7500 | 0x8130 => 1 << 4,
            _ => 0,
        };
    }
    bits
}

impl Ipos {
    /// Per step: 2000h fault bits, 2045h, 208Fh.
    pub(super) fn publish_status(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        refs: Refs,
        view: DriveView,
    ) {
        if let Some(r) = refs.motion_errors {
            let code = u32_at(od, refs.error_code).unwrap_or(0) as u16;
            let mer = u32_at(od, Some(r)).unwrap_or(0) as u16;
            let n = (mer & !FAULT_BITS) | fault_bits(cx, view, code);
            if n != mer {
                od.set_le(r, &n.to_le_bytes());
            }
        }
        // §7.2.17: 60FCh, the demand in increments.
        if let Some(r) = refs.demand_internal {
            let u = cx.drive.units();
            let inc = u.pos_to_inc_f(cx.drive.demand_position()).round();
            let inc = inc.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
            if i64_at(od, Some(r)) != Some(i64::from(inc)) {
                od.set_le(r, &inc.to_le_bytes());
            }
        }
        // §10.2.1: 6069h, the speed read from the encoder in internal
        // units (65536 = 1 increment per sample): 606Ch through 6094h.
        if let (Some(r), Some(v)) = (refs.velocity_sensor, i64_at(od, refs.velocity_actual)) {
            let (num, den) = self.velocity_iu;
            let iu = (i128::from(v) * i128::from(num) / i128::from(den.max(1)))
                .clamp(i128::from(i32::MIN), i128::from(i32::MAX)) as i32;
            if i64_at(od, Some(r)) != Some(i64::from(iu)) {
                od.set_le(r, &iu.to_le_bytes());
            }
        }
        // §4.5.5: OUTn status = the output lines as the drive drives them,
        // with the outputs the position triggers control (§4.9.5).
        let lines = cx.drive.output_lines() & (AVAILABLE_OUTPUTS >> 16) as u16;
        let out = Self::triggered(od, refs, lines);
        if let Some(r) = refs.outputs_status
            && u32_at(od, Some(r)) != Some(u32::from(out))
        {
            od.set_le(r, &out.to_le_bytes());
        }
        // §4.5.2: "the same data as 60FDh": sub 1 bits 0-3 (limit
        // switches, home, interlock), sub 2 IN0..IN7 (60FDh bits 16-23).
        // §4.5.1: the device profile inputs are mapped on the manufacturer
        // inputs as well: the home switch is IN0 (§6.1).
        let di = view.digital_inputs;
        let di = di | (di >> 2 & 1) << 16;
        if let Some(r) = refs.inputs
            && u32_at(od, Some(r)) != Some(di)
        {
            od.set_le(r, &di.to_le_bytes());
        }
        // §4.5.6: 2102h = 1 while the brake output holds the brake.
        let b = cx.drive.model().brake();
        let brake = u8::from(b.fitted && b.engaged);
        if let Some(r) = refs.brake
            && od.bytes(r).first() != Some(&brake)
        {
            od.set_le(r, &[brake]);
        }
        // §4.5.7 / §4.5.8: the reference (machine channel 1) and feedback
        // (channel 2) analogue inputs, 0…65520 over the input's span.
        for (k, r) in refs.analog.into_iter().enumerate() {
            let Some(r) = r else { continue };
            let v = cx.drive.model().analog_input(k as u8 + 1) / ANALOG_FULL_SCALE_V * 65520.0;
            let iu = v.round().clamp(0.0, 65520.0) as u16;
            if u32_at(od, Some(r)) != Some(u32::from(iu)) {
                od.set_le(r, &iu.to_le_bytes());
            }
        }
        // §7.2.21: the auxiliary encoder = the second encoder input, where
        // the machine's master encoder is wired (§11.3).
        if let Some(r) = refs.aux_encoder {
            let m = cx.drive.model().master_position() as i32;
            if i64_at(od, Some(r)) != Some(i64::from(m)) {
                od.set_le(r, &m.to_le_bytes());
            }
        }
        for (r, v) in refs.inputs8.into_iter().zip([(di & 0x0F) as u8, (di >> 16) as u8]) {
            if let Some(r) = r
                && od.bytes(r).first() != Some(&v)
            {
                od.set_le(r, &[v]);
            }
        }
    }

    /// §4.9.4 / §4.9.5: position trigger n is 1 once 6064h has reached
    /// 2075h:n (the TML status register bits SRH.1-4 are not objects; the
    /// exact value is passed within one control period, so "is the value"
    /// reads as reached); 2085h bits 0/1/3 give OUT0/OUT1/OUT5 to triggers
    /// 1/2/4, bits 8/9/11 their polarity (0: the output is 1 while the
    /// trigger is 0).
    fn triggered(od: &ObjectDictionary, refs: Refs, out: u16) -> u16 {
        let cfg = u32_at(od, refs.triggered_outputs).unwrap_or(0) as u16;
        if cfg & 0x0B == 0 {
            return out;
        }
        let pos = i64_at(od, refs.position_actual).unwrap_or(0);
        let mut out = out;
        for (enable, trigger, output) in [(0u16, 0usize, 0u16), (1, 1, 1), (3, 3, 5)] {
            if cfg & 1 << enable == 0 {
                continue;
            }
            let reached = i64_at(od, refs.triggers[trigger]).is_some_and(|t| pos >= t);
            let high = reached == (cfg & 1 << (8 + enable) != 0);
            out = if high { out | 1 << output } else { out & !(1 << output) };
        }
        out
    }

    /// The 60FEh:2 mask the drive takes: only the outputs the iPOS360x
    /// has; selecting another sends EMCY FF05h (§4.5.3).
    pub(super) fn available_outputs(cx: &mut Context<'_>, mask: u32) -> u32 {
        if mask & 0xFFFF_0000 & !AVAILABLE_OUTPUTS != 0 {
            let code = EMCY_IO_NOT_AVAILABLE;
            cx.request(EmcyFrame { code, register: Some(error_register(code)), bytes: [0; 5] }.raw());
        }
        mask & (AVAILABLE_OUTPUTS | 0xFFFF)
    }

    /// §4.5.4: 2090h "has the same functionality as 60FEh", 8 bits: sub 1
    /// commands OUT0..OUT7 (60FEh:01 bits 16-23), sub 2 is their mask
    /// (60FEh:02 bits 16-23); 60FEh shows the result.
    pub(super) fn digital_outputs_8bit(cx: &mut Context<'_>, od: &mut ObjectDictionary, sub: u8) {
        let Some(v) = od.get_u32(0x2090, sub) else { return };
        let Ok(r) = od.find(0x60FE, sub) else { return };
        let old = u32_at(od, Some(r)).unwrap_or(0);
        let new = (old & !0x00FF_0000) | (v & 0xFF) << 16;
        od.set_le(r, &new.to_le_bytes());
        let take = if sub == 2 { Self::available_outputs(cx, new) } else { new };
        let _ = cx.drive.on_write(od, 0x60FE, sub, &take.to_le_bytes());
    }
}

/// The drive's fault codes by the 2000h bit (and 2113h sub-index) of the
/// protection they are (§4.4.2, §4.4.13, §4.4.14), and whether §4.4.11
/// counts them as non-fatal (605Eh decides their reaction).
const PROTECTIONS: [(u16, u16, u8, bool); 8] = [
    // (code, 2000h bit, 2113h sub-index, non-fatal)
    (0x8100, 0, 4, true),
    (0x8130, 0, 4, true),
    (0x8611, 3, 3, false),
    (0x7305, 5, 0, false),
    (0x2310, 8, 8, false),
    (0x4310, 10, 10, true),
    (0x3210, 12, 12, true),
    (0x3220, 13, 13, true),
];

/// The action for a fault of a protection (§4.4.11, §4.4.13, §4.4.14):
/// 2114h's bit set → 2113h's option (0 disable, 2 quick stop, −1 no action
/// in bits 0–7; bit 15, a TML interrupt, is not emulated); else a
/// non-fatal error follows 605Eh (−1 no action; 0 and 2 as the drive
/// does them), a fatal one disables the drive.
fn action(od: &ObjectDictionary, bit: u16, sub: u8, non_fatal: bool) -> Option<ErrorReaction> {
    let overridden = od.get_u32(0x2114, 0).unwrap_or(0x8000) & 1 << bit != 0;
    if overridden && sub != 0 {
        match od.get_u32(0x2113, sub).unwrap_or(0) as u8 as i8 {
            0 => return Some(ErrorReaction::React(Reaction::DisableDrive)),
            2 => return Some(ErrorReaction::React(Reaction::QuickStopRamp)),
            -1 => return Some(ErrorReaction::NoAction),
            _ => {}
        }
    }
    if !non_fatal {
        return Some(ErrorReaction::React(Reaction::DisableDrive));
    }
    (od.get_i64(0x605E, 0) == Some(-1)).then_some(ErrorReaction::NoAction)
}

impl Ipos {
    /// The fault actions of every protection the model raises, after
    /// 605Eh, 2113h or 2114h changed (and at power-on / reload).
    pub(super) fn sync_fault_actions(cx: &mut Context<'_>, od: &ObjectDictionary) {
        for (code, bit, sub, non_fatal) in PROTECTIONS {
            cx.drive.set_fault_action(code, action(od, bit, sub, non_fatal));
        }
    }
}
