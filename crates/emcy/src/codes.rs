//! Emergency error codes (CiA 301 §7.2.7 table 21, CiA 402 error codes)
//! and the error register bits of 1001h (CiA 301 §7.5.2).

/// Bits of the error register 1001h (CiA 301 §7.5.2).
#[derive(Clone, Copy, Debug)]
pub struct ErrorRegister;

impl ErrorRegister {
    /// Bit 0: generic error; set whenever any error is active.
    pub const GENERIC: u8 = 1 << 0;
    /// Bit 1: current.
    pub const CURRENT: u8 = 1 << 1;
    /// Bit 2: voltage.
    pub const VOLTAGE: u8 = 1 << 2;
    /// Bit 3: temperature.
    pub const TEMPERATURE: u8 = 1 << 3;
    /// Bit 4: communication error (overrun, error state).
    pub const COMMUNICATION: u8 = 1 << 4;
    /// Bit 5: device profile specific.
    pub const DEVICE_PROFILE: u8 = 1 << 5;
    /// Bit 6: reserved, always 0.
    pub const RESERVED: u8 = 1 << 6;
    /// Bit 7: manufacturer specific.
    pub const MANUFACTURER: u8 = 1 << 7;
}

/// The 1001h bit a standard error code implies, besides the generic bit 0
/// (which the producer always sets while an error is active).
///
/// From the code classes of CiA 301 table 21: 2xxxh current, 3xxxh voltage,
/// 4xxxh temperature, 81xxh communication and 82xxh protocol error
/// (both bit 4), FFxxh device specific (bit 7). The CiA 402 monitoring
/// classes 83xxh..8Fxxh (torque, velocity, position, positioning, sync,
/// winding controller, process data, control) are device-profile errors
/// (bit 5), which is what e.g. the SSD 630 reports for 8611h (register 21h,
/// seed003 §9 table 1). Classes without a register bit (00xxh, 1xxxh, 5xxxh,
/// 6xxxh, 7xxxh, 80xxh, 9xxxh, F0xxh) give 0: only the generic bit.
pub const fn register_bit_for(code: u16) -> u8 {
    match code >> 8 {
        0x20..=0x2F => ErrorRegister::CURRENT,
        0x30..=0x3F => ErrorRegister::VOLTAGE,
        0x40..=0x4F => ErrorRegister::TEMPERATURE,
        0x81 | 0x82 => ErrorRegister::COMMUNICATION,
        0x83..=0x8F => ErrorRegister::DEVICE_PROFILE,
        0xFF => ErrorRegister::MANUFACTURER,
        _ => 0,
    }
}

/// The meaning of an emergency error code, or `None` for a code outside
/// every class CiA 301 and CiA 402 define (e.g. A000h..EFFFh).
///
/// Exact codes are looked up first; otherwise the answer is the name of
/// the code's class (the `xx` groups of CiA 301 table 21), so every
/// manufacturer refinement (e.g. 4380h) still gets its class name.
pub fn describe(code: u16) -> Option<&'static str> {
    exact(code).or_else(|| class(code))
}

/// Individually defined codes (CiA 301 table 21 and the CiA 402 drive codes).
fn exact(code: u16) -> Option<&'static str> {
    Some(match code {
        0x0000 => "Error reset or no error",
        0x1000 => "Generic error",
        // Current (CiA 402)
        0x2110 => "Short circuit/earth leakage (input)",
        0x2120 => "Earth leakage (input)",
        0x2121 => "Earth leakage phase L1",
        0x2122 => "Earth leakage phase L2",
        0x2123 => "Earth leakage phase L3",
        0x2130 => "Short circuit (input)",
        0x2131 => "Short circuit phases L1-L2",
        0x2132 => "Short circuit phases L2-L3",
        0x2133 => "Short circuit phases L3-L1",
        0x2211 => "Internal current no. 1",
        0x2212 => "Internal current no. 2",
        0x2213 => "Over-current in ramp function",
        0x2214 => "Over-current in the sequence",
        0x2220 => "Continuous over-current (device internal)",
        0x2221 => "Continuous over-current no. 1 (device internal)",
        0x2222 => "Continuous over-current no. 2 (device internal)",
        0x2230 => "Short circuit/earth leakage (device internal)",
        0x2240 => "Earth leakage (device internal)",
        0x2250 => "Short circuit (device internal)",
        0x2310 => "Continuous over-current",
        0x2311 => "Continuous over-current no. 1",
        0x2312 => "Continuous over-current no. 2",
        0x2320 => "Short circuit/earth leakage (motor side)",
        0x2330 => "Earth leakage (motor side)",
        0x2331 => "Earth leakage phase U",
        0x2332 => "Earth leakage phase V",
        0x2333 => "Earth leakage phase W",
        0x2340 => "Short circuit (motor side)",
        0x2341 => "Short circuit phases U-V",
        0x2342 => "Short circuit phases V-W",
        0x2343 => "Short circuit phases W-U",
        // Voltage
        0x3110 => "Mains over-voltage",
        0x3120 => "Mains under-voltage",
        0x3130 => "Phase failure",
        0x3140 => "Mains frequency",
        0x3210 => "DC link over-voltage",
        0x3220 => "DC link under-voltage",
        0x3230 => "Load error",
        0x3310 => "Output over-voltage",
        0x3320 => "Armature circuit",
        0x3330 => "Field circuit",
        // Temperature
        0x4110 => "Excess ambient temperature",
        0x4120 => "Too low ambient temperature",
        0x4130 => "Temperature supply air",
        0x4140 => "Temperature air outlet",
        0x4210 => "Excess temperature device",
        0x4220 => "Too low temperature device",
        0x4300 => "Drive temperature",
        0x4310 => "Excess temperature drive",
        0x4320 => "Too low temperature drive",
        0x4400 => "Temperature supply",
        0x4410 => "Excess temperature supply",
        0x4420 => "Too low temperature supply",
        // Device hardware
        0x5100 => "Supply",
        0x5110 => "Supply low voltage",
        0x5111 => "Supply low voltage U1 (+/-15 V)",
        0x5112 => "Supply low voltage U2 (+24 V)",
        0x5113 => "Supply low voltage U3 (+5 V)",
        0x5120 => "Supply intermediate circuit",
        0x5200 => "Control",
        0x5210 => "Measurement circuit",
        0x5220 => "Computing circuit",
        0x5300 => "Operating unit",
        0x5400 => "Power section",
        0x5410 => "Output stages",
        0x5420 => "Chopper",
        0x5430 => "Input stages",
        0x5440 => "Contacts",
        0x5441 => "Contact 1",
        0x5442 => "Contact 2",
        0x5443 => "Contact 3",
        0x5444 => "Contact 4",
        0x5445 => "Contact 5",
        0x5450 => "Fuses",
        0x5500 => "Hardware memory",
        0x5510 => "RAM",
        0x5520 => "Program memory",
        0x5530 => "Non-volatile data memory",
        // Device software
        0x6010 => "Software reset (watchdog)",
        0x6100 => "Internal software",
        0x6200 => "User software",
        0x6300 => "Data set",
        0x6310 => "Loss of parameters",
        0x6320 => "Parameter error",
        // Additional modules
        0x7100 => "Power",
        0x7110 => "Brake chopper",
        0x7111 => "Failure brake chopper",
        0x7112 => "Over-current brake chopper",
        0x7113 => "Protective circuit brake chopper",
        0x7120 => "Motor",
        0x7121 => "Motor blocked",
        0x7122 => "Motor error or commutation malfunction",
        0x7123 => "Motor tilted",
        0x7200 => "Measurement circuit",
        0x7300 => "Sensor",
        0x7301 => "Tacho fault",
        0x7302 => "Tacho wrong polarity",
        0x7303 => "Resolver 1 fault",
        0x7304 => "Resolver 2 fault",
        0x7305 => "Incremental encoder 1 fault",
        0x7306 => "Incremental encoder 2 fault",
        0x7307 => "Incremental encoder 3 fault",
        0x7310 => "Speed",
        0x7320 => "Position",
        0x7400 => "Computation circuit",
        0x7500 => "Communication",
        0x7510 => "Serial interface no. 1",
        0x7520 => "Serial interface no. 2",
        0x7600 => "Data storage (external)",
        // Monitoring: communication (CiA 301)
        0x8100 => "Communication",
        0x8110 => "CAN overrun (objects lost)",
        0x8120 => "CAN in error passive mode",
        0x8130 => "Life guard error or heartbeat error",
        0x8140 => "Recovered from bus off",
        0x8150 => "CAN-ID collision",
        // Monitoring: protocol error (CiA 301)
        0x8200 => "Protocol error",
        0x8210 => "PDO not processed due to length error",
        0x8220 => "PDO length exceeded",
        0x8230 => "DAM MPDO not processed, destination object not available",
        0x8240 => "Unexpected SYNC data length",
        0x8250 => "RPDO timeout",
        // Monitoring: drive control loops (CiA 402)
        0x8300 => "Torque control",
        0x8311 => "Excess torque",
        0x8312 => "Difficult start up",
        0x8313 => "Standstill torque",
        0x8321 => "Insufficient torque",
        0x8331 => "Torque fault",
        0x8400 => "Velocity speed controller",
        0x8500 => "Position controller",
        0x8600 => "Positioning controller",
        0x8611 => "Following error",
        0x8612 => "Reference limit",
        0x8700 => "Sync controller",
        0x8800 => "Winding controller",
        0x8900 => "Process data monitoring",
        0x8A00 => "Control",
        0x9000 => "External error",
        // Additional functions (CiA 402)
        0xF000 => "Additional functions",
        0xF001 => "Deceleration",
        0xF002 => "Sub-synchronous run",
        0xF003 => "Stroke operation",
        0xF004 => "Control",
        0xFF00 => "Device specific",
        _ => return None,
    })
}

/// The class of a code (CiA 301 table 21), by high byte then high nibble.
fn class(code: u16) -> Option<&'static str> {
    let by_byte = match code >> 8 {
        0x00 => Some("Error reset or no error"),
        0x21 => Some("Current, device input side"),
        0x22 => Some("Current inside the device"),
        0x23 => Some("Current, device output side"),
        0x31 => Some("Mains voltage"),
        0x32 => Some("Voltage inside the device"),
        0x33 => Some("Output voltage"),
        0x41 => Some("Ambient temperature"),
        0x42 => Some("Device temperature"),
        0x43 => Some("Drive temperature"),
        0x44 => Some("Supply temperature"),
        0x61 => Some("Internal software"),
        0x62 => Some("User software"),
        0x63 => Some("Data set"),
        0x81 => Some("Communication"),
        0x82 => Some("Protocol error"),
        0x83 => Some("Torque control"),
        0x84 => Some("Velocity speed controller"),
        0x85 => Some("Position controller"),
        0x86 => Some("Positioning controller"),
        0x87 => Some("Sync controller"),
        0x88 => Some("Winding controller"),
        0x89 => Some("Process data monitoring"),
        0x8A => Some("Control"),
        0xF0 => Some("Additional functions"),
        0xFF => Some("Device specific"),
        _ => None,
    };
    by_byte.or(match code >> 12 {
        0x1 => Some("Generic error"),
        0x2 => Some("Current"),
        0x3 => Some("Voltage"),
        0x4 => Some("Temperature"),
        0x5 => Some("Device hardware"),
        0x6 => Some("Device software"),
        0x7 => Some("Additional modules"),
        0x8 => Some("Monitoring"),
        0x9 => Some("External error"),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn register_bits_by_class() {
        assert_eq!(register_bit_for(0x2310), ErrorRegister::CURRENT);
        assert_eq!(register_bit_for(0x3210), ErrorRegister::VOLTAGE);
        assert_eq!(register_bit_for(0x4310), ErrorRegister::TEMPERATURE);
        assert_eq!(register_bit_for(0x8130), ErrorRegister::COMMUNICATION);
        assert_eq!(register_bit_for(0x8240), ErrorRegister::COMMUNICATION);
        assert_eq!(register_bit_for(0x8611), ErrorRegister::DEVICE_PROFILE);
        assert_eq!(register_bit_for(0xFF01), ErrorRegister::MANUFACTURER);
        assert_eq!(register_bit_for(0x1000), 0);
        assert_eq!(register_bit_for(0x6010), 0);
        assert_eq!(register_bit_for(0x9000), 0);
        assert_eq!(register_bit_for(0x0000), 0);
    }

    /// Register values the SSD 630 manual prints (seed003 §9 table 1) where
    /// they follow the CiA 301 classes: generic bit + class bit.
    #[test]
    fn ssd630_register_values_match_classes() {
        for (code, reg) in [
            (0x2230, 0x03),
            (0x2311, 0x03),
            (0x2312, 0x03),
            (0x3210, 0x05),
            (0x3220, 0x05),
            (0x4210, 0x09),
            (0x4310, 0x09),
            (0x8400, 0x21),
            (0x8611, 0x21),
            (0x8612, 0x21),
            (0x8700, 0x21),
        ] {
            assert_eq!(ErrorRegister::GENERIC | register_bit_for(code), reg, "{code:04X}");
        }
    }

    #[test]
    fn descriptions() {
        assert_eq!(describe(0x0000), Some("Error reset or no error"));
        assert_eq!(describe(0x8130), Some("Life guard error or heartbeat error"));
        assert_eq!(describe(0x8240), Some("Unexpected SYNC data length"));
        assert_eq!(describe(0x8611), Some("Following error"));
        // Class fallbacks for manufacturer refinements.
        assert_eq!(describe(0x4380), Some("Drive temperature"));
        assert_eq!(describe(0x82B2), Some("Protocol error"));
        assert_eq!(describe(0x5592), Some("Device hardware"));
        assert_eq!(describe(0xFF05), Some("Device specific"));
        assert_eq!(describe(0x0012), Some("Error reset or no error"));
        // Outside every class.
        assert_eq!(describe(0xA000), None);
        assert_eq!(describe(0xF100), None);
        // Every code that has text must be in a class with text too.
        for code in 0..=u16::MAX {
            if exact(code).is_some() {
                assert!(class(code).is_some(), "{code:04X}");
            }
        }
    }
}
