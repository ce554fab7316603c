//! COB-ID entries of the communication objects (CiA 301 §7.5.2): the
//! identifier bits, the frame-format bit, and the restricted identifiers.

use crate::CanId;

/// Bit 29 of a COB-ID entry: the identifier is 29 bits (extended).
pub const EXTENDED: u32 = 1 << 29;

/// The CAN identifier a COB-ID entry names (bits 0..28, format from bit
/// 29), or `None` for an 11-bit entry with bits set above bit 10.
/// Bits 30 and 31 (service-specific flags) are ignored.
#[inline]
pub const fn can_id(cob_id: u32) -> Option<CanId> {
    if cob_id & EXTENDED != 0 {
        CanId::extended(cob_id & 0x1FFF_FFFF)
    } else if cob_id & 0x1FFF_F800 == 0 {
        CanId::standard((cob_id & 0x7FF) as u16)
    } else {
        None
    }
}

/// CiA 301 §7.3.5: 11-bit identifiers reserved for NMT, SDO, NMT error
/// control and LSS, which no configurable COB-ID (PDO, SYNC, TIME, EMCY,
/// additional SDO) may use.
#[inline]
pub const fn is_restricted(id: u16) -> bool {
    matches!(id, 0x000..=0x07F | 0x101..=0x180 | 0x581..=0x5FF | 0x601..=0x67F | 0x6E0..=0x6FF | 0x701..=0x7FF)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restricted_ranges_edges() {
        for id in [0x000, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x6FF, 0x701, 0x7FF] {
            assert!(is_restricted(id), "{id:#x}");
        }
        for id in [0x080, 0x100, 0x181, 0x580, 0x600, 0x680, 0x6DF, 0x700] {
            assert!(!is_restricted(id), "{id:#x}");
        }
    }

    #[test]
    fn cob_id_decoding() {
        assert_eq!(can_id(0x4000_0181), Some(CanId::Standard(0x181)));
        assert_eq!(can_id(0x8000_0080), Some(CanId::Standard(0x080)));
        assert_eq!(can_id(0x0000_0801), None);
        assert_eq!(can_id(0x2000_0801), Some(CanId::Extended(0x801)));
    }
}
