//! One file per personality: the [`ProfileInfo`](crate::ProfileInfo) value,
//! each field citing the manual section it comes from.

pub mod akd;
pub mod dds6;
pub mod generic;
pub mod ipos;
pub mod kc1;
pub mod ssd630;

use crate::PdoDefault;

/// A CAN PDO default: valid unless `cob_id` has bit 31, transmission type 255.
pub(crate) const fn can(cob_id: u32, event_timer_ms: u16, mapping: &'static [u32]) -> PdoDefault {
    PdoDefault {
        cob_id: Some(cob_id),
        enabled: cob_id & 0x8000_0000 == 0,
        transmission_type: Some(0xFF),
        event_timer_ms,
        mapping,
    }
}

/// An EtherCAT (CoE) PDO default: no COB-ID, `enabled` = assigned in 1C12h/1C13h.
pub(crate) const fn coe(enabled: bool, mapping: &'static [u32]) -> PdoDefault {
    PdoDefault { cob_id: None, enabled, transmission_type: None, event_timer_ms: 0, mapping }
}

/// The CiA 402 default mappings the Kollmorgen drives and the SSD 630 use
/// (controlword/statusword first, then the mode's set-point or actual value).
pub(crate) mod maps {
    pub const CW: &[u32] = &[0x6040_0010];
    pub const CW_MODE: &[u32] = &[0x6040_0010, 0x6060_0008];
    pub const CW_POS: &[u32] = &[0x6040_0010, 0x607A_0020];
    pub const CW_VEL: &[u32] = &[0x6040_0010, 0x60FF_0020];
    pub const SW: &[u32] = &[0x6041_0010];
    pub const SW_MODE: &[u32] = &[0x6041_0010, 0x6061_0008];
    pub const SW_POS: &[u32] = &[0x6041_0010, 0x6064_0020];
    pub const SW_VEL: &[u32] = &[0x6041_0010, 0x606C_0020];
}
