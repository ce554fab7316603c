//! The iPOS factor group (§5): which objects scale the user's values into
//! the drive's internal units.
//!
//! The twin is FA00G firmware, so the CiA 402-2 factor group of §5.2
//! applies: "the user-defined units are translated to internal units (IU)
//! by the factor / scaling objects 6093h (position factor), 6094h
//! (velocity encoder factor), 210Fh (acceleration encoder factor) and
//! 2110h (jerk encoder factor)", each IU = user value × sub 1 / sub 2.
//! 608Fh, 6091h, 6092h, 6096h, 6097h and 60A2h are what EasyMotion Studio
//! computes those from (§1.3.2, §5.2.2, §5.2.7, §5.2.10): the drive keeps
//! them as set-up values — their defaults (608Fh 2000/1 with 6093h 1/1,
//! 6094h 1/1 with T × 2¹⁶) are not related by the formulas, so the drive
//! does not evaluate them.
//!
//! The obsolete group of §5.1 is in the object table too: there a
//! non-zero dimension index validates its factor (§5.1: "writing a
//! non-zero value into the respective dimension index objects validates
//! these factors"). Its position and velocity factors are the same
//! objects; its acceleration factor is 6097h (§5.1.12): with 608Eh ≠ 0
//! the drive scales accelerations by 6097h instead of 210Fh. No object of
//! the dictionary is in jerk units (60A4h is not listed), so 2110h scales
//! nothing; 2023h is a time. Its time factor 2071h, validated by a
//! non-zero time dimension index 2070h (§5.1.13), scales the times the
//! drive takes in slow-loop samples (1 ms): 6066h, 6068h, 2023h (2005h
//! and 2051h belong to protections the model does not have).

use drivebus_cia402::drive::Scaling;
use drivebus_od::ObjectDictionary;

/// Increments/s per internal velocity unit: 1/65536 increment per 1 ms
/// slow-loop sample (§1.3; §5.2.7 "× T × 2¹⁶").
pub const VELOCITY_IU: (u32, u32) = (125, 8192);

/// Increments/s² per internal acceleration unit: 1/65536 increment per
/// sample² (§1.3; §5.2.10).
pub const ACCELERATION_IU: (u32, u32) = (15_625, 1024);

/// The objects whose writes change the scaling in force.
pub(super) const OBJECTS: [u16; 5] = [0x6093, 0x6094, 0x210F, 0x6097, 0x608E];

/// The time objects 2071h scales (§5.1.13) that the drive uses.
pub(super) const TIMES: [u16; 2] = [0x6066, 0x6068];

/// Time internal units (1 ms samples) per time unit: 2071h when 2070h ≠ 0
/// validates it (§5.1.13), else 1/1.
pub(super) fn time_factor(od: &ObjectDictionary) -> (u64, u64) {
    if od.get_u32(0x2070, 0).unwrap_or(0) == 0 {
        return (1, 1);
    }
    match (od.get_u32(0x2071, 1), od.get_u32(0x2071, 2)) {
        (Some(n), Some(d)) if n != 0 && d != 0 => (u64::from(n), u64::from(d)),
        _ => (1, 1),
    }
}

/// `t` time units in internal units (ms), rounded, saturating at `max`.
pub(super) fn time_iu(od: &ObjectDictionary, t: u64, max: u64) -> u64 {
    let (n, d) = time_factor(od);
    ((u128::from(t) * u128::from(n) + u128::from(d) / 2) / u128::from(d)).min(u128::from(max)) as u64
}

/// Scaling objects a zero sub-index would make meaningless (a 0 factor
/// maps every value to 0 or divides by 0): refused.
pub(super) fn refuses_zero(index: u16, sub: u8) -> bool {
    matches!(index, 0x6093 | 0x6094 | 0x210F | 0x2110 | 0x2071) && matches!(sub, 1 | 2)
}

/// The scaling in force as the dictionary holds it; `None` while an
/// object is missing or a term is 0 (the units then stay as they were).
pub(super) fn scaling(od: &ObjectDictionary) -> Option<Scaling> {
    let pair = |i: u16| Some((od.get_u32(i, 1)?, od.get_u32(i, 2)?));
    let legacy_acceleration = od.get_u32(0x608E, 0).unwrap_or(0) != 0;
    let acceleration = if legacy_acceleration { pair(0x6097)? } else { pair(0x210F)? };
    Some(Scaling {
        position: pair(0x6093)?,
        velocity: pair(0x6094)?,
        acceleration,
        velocity_unit: VELOCITY_IU,
        acceleration_unit: ACCELERATION_IU,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_cia402::drive::{FactorGroup, Units};

    #[test]
    fn internal_units_are_increments_per_sample_in_16_16() {
        let s = Scaling::unit(VELOCITY_IU, ACCELERATION_IU);
        let u = Units::new(&FactorGroup { scaling: Some(s), ..FactorGroup::increments(2000) }).unwrap();
        // 00010000h = 1 increment per 1 ms sample = 1000 increments/s.
        assert_eq!(u.vel_to_pos(65536.0), 1000.0);
        assert_eq!(u.acc_to_pos(65536.0), 1e6);
    }
}
