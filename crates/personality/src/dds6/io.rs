//! Digital I/O (§6.4.8–6.4.11, §6.4.14–6.4.15): the outputs DO0..DO2 from
//! their sources 2830h–2832h (general purpose: 3230h), the inputs DI2..DI7
//! in 3210h:01.

/// What a digital output source (2830h–2832h:01) looks at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OutputConditions {
    /// The statusword as published.
    pub statusword: u16,
    /// The holding brake output (active = released, §4.3).
    pub brake: bool,
    /// The motor turns in the positive / negative direction.
    pub positive: bool,
    /// See `positive`.
    pub negative: bool,
}

/// The level of an output with source `source` (§6.4.9 table), `None` for
/// 0000h "General Purpose" (3230h:01 decides). Bit 15 of a source inverts
/// its condition (8040h "No Fault", 8060h–806Fh "statusword bit n = 0");
/// an unknown source keeps the output inactive.
pub fn source_level(source: u16, s: &OutputConditions) -> Option<bool> {
    let sw = s.statusword;
    let condition = match source & 0x7FFF {
        0x0000 if source == 0 => return None,
        0x0008 => true,
        // Fault: the FSA in Fault reaction active or Fault (bit 3).
        0x0040 => sw & 0x08 != 0,
        0x0041 => sw & 0x6F == 0x27,
        0x0042 => sw & 0x6F == 0x07,
        0x0044 => s.brake,
        0x0050 => s.positive,
        0x0051 => s.negative,
        n @ 0x0060..=0x006F => sw & (1 << (n - 0x60)) != 0,
        _ => return Some(false),
    };
    Some(condition != (source & 0x8000 != 0))
}

/// 3230h:01 from the sources of DO0..DO2 and the general-purpose bits the
/// master set.
pub fn outputs(sources: [u16; 3], general: u16, s: &OutputConditions) -> u16 {
    (0..3).fold(0, |acc, n| {
        let on = source_level(sources[n], s).unwrap_or(general & (1 << n) != 0);
        acc | u16::from(on) << n
    })
}

/// The general-purpose bits after a write of 3230h:01 (`value`): only the
/// bits of outputs configured as General Purpose change (§6.4.15: "any
/// attempt of that kind will be ignored").
pub fn write_outputs(sources: [u16; 3], general: u16, value: u16) -> u16 {
    (0..3).fold(general, |g, n| if sources[n] == 0 { (g & !(1 << n)) | (value & (1 << n)) } else { g })
}

/// The general-purpose bits after a write of 3230h:02 (`cmd`): bits 0–3
/// the bit number, bit 7 the level, 0 = set to 1, 1 = set to 0 (§6.4.15:
/// 81h clears bit 1, 01h sets it, 00h sets bit 0). A bit of an output with
/// an internal source, or beyond DO2, is ignored.
pub fn set_output(sources: [u16; 3], general: u16, cmd: u8) -> u16 {
    let n = usize::from(cmd & 0x0F);
    if n >= 3 || sources[n] != 0 {
        return general;
    }
    if cmd & 0x80 != 0 { general & !(1 << n) } else { general | 1 << n }
}

/// 3210h:01 (bits 2..7 = DI2..DI7) from the machine's switches as wired
/// by the 2810h defaults (§6.4.8): positive limit DI7, negative limit DI6,
/// home DI5 (`switches` in the 60FDh layout: bit 0 negative limit, bit 1
/// positive limit, bit 2 home), plus the inputs `others` sets (bits 2..7).
pub fn inputs(switches: u32, others: u16) -> u16 {
    let neg = u16::from(switches & 1 != 0) << 6;
    let pos = u16::from(switches & 2 != 0) << 7;
    let home = u16::from(switches & 4 != 0) << 5;
    (others & 0xFC) | neg | pos | home
}

/// Whether an input function assigned by a 2810h sub (`assign`: low byte
/// the input 2..7, high byte 0 always inactive, 1 always active, 2 active
/// input, 3 inactive input) is active with the inputs `di` (3210h:01).
pub fn function_active(assign: u16, di: u16) -> bool {
    let input = (assign & 0xFF) as u8;
    let level = (2..=7).contains(&input) && di & (1 << input) != 0;
    match assign >> 8 {
        1 => true,
        2 => level,
        3 => (2..=7).contains(&input) && !level,
        _ => false,
    }
}

/// A fault-reset input (2810h:02: high byte 4 rising edge, 5 falling edge)
/// fired between the inputs `before` and `now`.
pub fn edge_fired(assign: u16, before: u16, now: u16) -> bool {
    let input = (assign & 0xFF) as u8;
    if !(2..=7).contains(&input) {
        return false;
    }
    let (was, is) = (before & (1 << input) != 0, now & (1 << input) != 0);
    match assign >> 8 {
        4 => !was && is,
        5 => was && !is,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sig(sw: u16) -> OutputConditions {
        OutputConditions { statusword: sw, ..OutputConditions::default() }
    }

    #[test]
    fn sources_of_section_6_4_9() {
        // Defaults: DO0 8040h no fault, DO1 0041h operation enabled, DO2
        // 006Ah statusword bit 10.
        let disabled = sig(0x2650);
        assert_eq!(outputs([0x8040, 0x0041, 0x006A], 0, &disabled), 0b101);
        assert_eq!(outputs([0x8040, 0x0041, 0x006A], 0, &sig(0x0237)), 0b011);
        assert_eq!(outputs([0x8040, 0x0041, 0x006A], 0, &sig(0x0218)), 0b000);
        // 8067h: active while the warning bit 7 is 0.
        assert_eq!(source_level(0x8067, &sig(0x0080)), Some(false));
        assert_eq!(source_level(0x8067, &sig(0x0000)), Some(true));
        assert_eq!(source_level(0x0008, &sig(0)), Some(true));
        assert_eq!(source_level(0x8008, &sig(0)), Some(false));
        assert_eq!(source_level(0x0042, &sig(0x0207)), Some(true));
        assert_eq!(source_level(0x0000, &sig(0)), None);
        assert_eq!(source_level(0x1234, &sig(0)), Some(false));
        let moving = OutputConditions { positive: true, brake: true, ..sig(0) };
        assert_eq!(source_level(0x0050, &moving), Some(true));
        assert_eq!(source_level(0x8051, &moving), Some(true));
        assert_eq!(source_level(0x0044, &moving), Some(true));
    }

    #[test]
    fn general_purpose_bits() {
        let src = [0, 0x0041, 0];
        assert_eq!(set_output(src, 0, 0x00), 0b001);
        assert_eq!(set_output(src, 0b101, 0x82), 0b001);
        assert_eq!(set_output(src, 0, 0x01), 0, "DO1 has an internal source");
        assert_eq!(set_output(src, 0, 0x05), 0, "no DO5");
        assert_eq!(write_outputs(src, 0, 0b111), 0b101);
        assert_eq!(write_outputs(src, 0b101, 0), 0);
    }

    #[test]
    fn inputs_and_functions() {
        assert_eq!(inputs(0b010, 0), 0x80);
        assert_eq!(inputs(0b101, 0x04), 0x64);
        assert!(function_active(0x0207, 0x80));
        assert!(!function_active(0x0307, 0x80));
        assert!(function_active(0x0307, 0x00));
        assert!(function_active(0x0100, 0));
        assert!(!function_active(0x0007, 0x80));
        assert!(edge_fired(0x0502, 0x04, 0));
        assert!(!edge_fired(0x0502, 0, 0x04));
        assert!(edge_fired(0x0402, 0, 0x04));
    }
}
