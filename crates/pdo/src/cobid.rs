//! PDO COB-ID entries (CiA 301 7.5.2.35 / 7.5.2.37, sub-index 01h).

use drivebus_can::CanId;

/// Bit 31: the PDO does not exist (is invalid).
pub const COB_INVALID: u32 = 1 << 31;
/// Bit 30: no RTR allowed on this PDO (TPDO only).
pub const COB_NO_RTR: u32 = 1 << 30;
/// Bit 29: 29-bit (extended) CAN-ID.
pub const COB_EXTENDED: u32 = 1 << 29;
/// Bits that may not change while the PDO is valid (CiA 301: bits 0..29).
pub const COB_ID_BITS: u32 = 0x3FFF_FFFF;

/// True for 11-bit CAN-IDs CiA 301 §7.3.5 (Table 36) reserves for other
/// services (NMT, SYNC/EMCY/TIME base range, SDO, LSS, heartbeat...).
pub const fn restricted_id(id: u16) -> bool {
    drivebus_can::cob::is_restricted(id)
}

/// The CAN identifier a COB-ID entry names, or `None` if it is malformed
/// (an 11-bit id with bits 11..28 set) or restricted.
pub fn can_id(cob: u32) -> Option<CanId> {
    if cob & COB_EXTENDED != 0 {
        CanId::extended(cob & 0x1FFF_FFFF)
    } else {
        let raw = cob & 0x1FFF_FFFF;
        if raw > 0x7FF || restricted_id(raw as u16) {
            return None;
        }
        CanId::standard(raw as u16)
    }
}

/// True when the COB-ID entry marks the PDO valid (bit 31 clear).
#[inline]
pub const fn is_valid(cob: u32) -> bool {
    cob & COB_INVALID == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restricted_ranges() {
        assert!(restricted_id(0x000) && restricted_id(0x07F) && restricted_id(0x180));
        assert!(!restricted_id(0x181) && !restricted_id(0x100) && !restricted_id(0x580));
        assert!(restricted_id(0x5FF) && restricted_id(0x67F) && !restricted_id(0x680));
        assert!(restricted_id(0x6E0) && restricted_id(0x701) && !restricted_id(0x700));
        assert_eq!(can_id(0x4000_0181), Some(CanId::Standard(0x181)));
        assert_eq!(can_id(0x0000_0801), None);
        assert_eq!(can_id(0x2000_0801), Some(CanId::Extended(0x801)));
    }
}
