//! The units CiA 301 and CiA 402 give their objects' values in, for tools
//! that show a value with its unit. Position, velocity and acceleration
//! units are the drive's user units (its factor group, 608Fh–60A2h); the
//! torque and current objects are per mille of the motor's rated values.

/// The unit of `index:sub`'s value where CiA 301 or CiA 402 defines one;
/// `None` for objects without a unit (words, codes, counts, identities)
/// and for those the standards leave to the manufacturer.
pub fn unit(index: u16, sub: u8) -> Option<&'static str> {
    const POS: &str = "position units";
    const VEL: &str = "velocity units";
    const ACC: &str = "acceleration units";
    Some(match (index, sub) {
        (0x1006 | 0x1007, 0) => "µs",
        (0x100C | 0x1017, 0) => "ms",
        (0x1015, 0) => "100 µs",
        // PDO communication parameters: inhibit time, event timer.
        (0x1800..=0x19FF, 3) => "100 µs",
        (0x1400..=0x15FF | 0x1800..=0x19FF, 5) => "ms",
        (0x6062 | 0x6064 | 0x6065 | 0x6067 | 0x607A | 0x607C | 0x60B0 | 0x60F4, 0) => POS,
        (0x607B | 0x607D, 1 | 2) => POS,
        (0x6063 | 0x60FC, 0) => "increments",
        (0x6066 | 0x6068 | 0x606E | 0x6070, 0) => "ms",
        (0x606B | 0x606C | 0x606D | 0x606F | 0x607F | 0x6081 | 0x6082 | 0x60B1 | 0x60F8 | 0x60FF, 0) => VEL,
        (0x6099, 1 | 2) => VEL,
        (0x6083 | 0x6084 | 0x6085 | 0x609A | 0x60C5 | 0x60C6, 0) => ACC,
        (0x6071 | 0x6072 | 0x6074 | 0x6077 | 0x60B2, 0) => "‰ of rated torque",
        (0x6073 | 0x6078, 0) => "‰ of rated current",
        (0x6087, 0) => "‰ of rated torque per s",
        (0x6075, 0) => "mA",
        (0x6076, 0) => "mN·m",
        (0x6079, 0) => "mV",
        (0x6080, 0) => "rpm",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::unit;

    #[test]
    fn units_of_the_standard_objects() {
        assert_eq!(unit(0x6064, 0), Some("position units"));
        assert_eq!(unit(0x607D, 2), Some("position units"));
        assert_eq!(unit(0x606C, 0), Some("velocity units"));
        assert_eq!(unit(0x6077, 0), Some("‰ of rated torque"));
        assert_eq!(unit(0x1017, 0), Some("ms"));
        assert_eq!(unit(0x1A00, 3), None, "a TPDO mapping entry is not an inhibit time");
        assert_eq!(unit(0x1800, 3), Some("100 µs"));
        assert_eq!(unit(0x1400, 5), Some("ms"));
        // No unit: words, modes, manufacturer objects, sub 0 of a record.
        for (i, s) in [(0x6040, 0), (0x6041, 0), (0x6060, 0), (0x2000, 0), (0x607D, 0), (0x1018, 1)] {
            assert_eq!(unit(i, s), None, "{i:04X}:{s}");
        }
    }
}
