//! The checks and applies several of the drive's objects share (see
//! `table.rs`, where each object names its own).

use super::Drive;
use super::config::DriveConfig;
use super::mode::op;
use super::objects::{Arg, How, range, record, sub};
use crate::state_machine::Options;
use drivebus_od::{Access, DataType as T, Object, ObjectDictionary, SdoAbort, Value, WriteOutcome};

use Access::Rw;
use Value::{U16, U32};

/// Sets option code `index` (605Ah–605Eh, 6007h) in `o`; the abort of an
/// unsupported code.
pub(super) fn set_option(o: &mut Options, index: u16, v: i16) -> Result<(), SdoAbort> {
    let r = match index {
        0x6007 => o.set_abort_connection(v),
        0x605A => o.set_quick_stop(v),
        0x605B => o.set_shutdown(v),
        0x605C => o.set_disable_operation(v),
        0x605D => o.set_halt(v),
        _ => o.set_fault_reaction(v),
    };
    r.map_err(|_| {
        // Reserved and manufacturer-specific codes are not supported:
        // 0609 0031 above the range, 0609 0032 below.
        let lo = match index {
            0x6007 => i16::MIN,
            0x605D => 1,
            _ => 0,
        };
        if v < lo { SdoAbort::VALUE_TOO_LOW } else { SdoAbort::VALUE_TOO_HIGH }
    })
}

pub(super) fn option_check(
    d: &mut Drive,
    _: &mut ObjectDictionary,
    a: Arg,
) -> Result<WriteOutcome, SdoAbort> {
    let Arg { index: i, v, .. } = a;
    // On a copy: nothing changes before the store.
    let mut o = *d.sm.options();
    set_option(&mut o, i, v.i16()).map(|()| WriteOutcome::Store)
}

pub(super) fn option_apply(d: &mut Drive, _: &mut ObjectDictionary, a: Arg) {
    let Arg { index: i, v, .. } = a;
    // Checked on writes; a stored value passed the check once.
    let _ = set_option(d.sm.options_mut(), i, v.i16());
}

/// A positive u32 (a zero rate or ratio would never get anywhere).
pub(super) fn positive(_: &mut Drive, _: &mut ObjectDictionary, a: Arg) -> Result<WriteOutcome, SdoAbort> {
    let Arg { v, .. } = a;
    range(v.u as i64, 1, i64::from(u32::MAX)).map(|()| WriteOutcome::Store)
}

/// Ramps 6083h, 6084h, 6085h, 60C5h, 60C6h, 609Ah: positive; drives whose
/// range includes 0 take it for 6083h/6084h/609Ah and refuse motion instead.
pub(super) fn ramp_check(d: &mut Drive, _: &mut ObjectDictionary, a: Arg) -> Result<WriteOutcome, SdoAbort> {
    let Arg { index: i, v, .. } = a;
    let zero_ok =
        d.cfg.zero_ramp != super::config::ZeroRamp::Refused && matches!(i, 0x6083 | 0x6084 | 0x609A);
    range(v.u as i64, if zero_ok { 0 } else { 1 }, i64::from(u32::MAX)).map(|()| WriteOutcome::Store)
}

pub(super) fn ramp_apply(d: &mut Drive, _: &mut ObjectDictionary, a: Arg) {
    let Arg { index: i, v, .. } = a;
    let v = d.cfg.zero_ramp.effective(i, v.u32());
    let p = &mut d.params;
    match i {
        0x6083 => p.profile_acceleration = v,
        0x6084 => p.profile_deceleration = v,
        0x6085 => p.quick_stop_deceleration = v,
        0x60C5 => p.max_acceleration = v,
        0x60C6 => p.max_deceleration = v,
        _ => p.homing_acceleration = v,
    }
}

/// A min/max pair (607Bh, 607Dh, 6046h): min must not exceed max (CiA
/// 402-2 §6.6: 0609 0036).
pub(super) fn min_max_check(
    d: &mut Drive,
    _: &mut ObjectDictionary,
    a: Arg,
) -> Result<WriteOutcome, SdoAbort> {
    let Arg { index: i, sub: s, v, .. } = a;
    let (mut lo, mut hi) = match i {
        0x607B => (i64::from(d.params.position_range.0), i64::from(d.params.position_range.1)),
        0x607D => (i64::from(d.params.software_limits.0), i64::from(d.params.software_limits.1)),
        _ => (i64::from(d.extra.vl_min), i64::from(d.extra.vl_max)),
    };
    let x = if i == 0x6046 { v.u32() as i64 } else { i64::from(v.i32()) };
    if s == 1 {
        lo = x;
    } else {
        hi = x;
    }
    if lo > hi { Err(SdoAbort::MAX_LESS_THAN_MIN) } else { Ok(WriteOutcome::Store) }
}

pub(super) fn min_max_apply(d: &mut Drive, od: &mut ObjectDictionary, a: Arg) {
    let Arg { index: i, sub: s, v, how, .. } = a;
    let x = if i == 0x6046 { v.u as i64 } else { v.s };
    // A write keeps the other bound as the dictionary holds it; a reload
    // takes the stored bounds one sub-index after the other.
    let (mut lo, mut hi) = match i {
        0x607B => (i64::from(d.params.position_range.0), i64::from(d.params.position_range.1)),
        0x607D => (i64::from(d.params.software_limits.0), i64::from(d.params.software_limits.1)),
        _ => (i64::from(d.extra.vl_min), i64::from(d.extra.vl_max)),
    };
    if how == How::Write {
        let get = |s: u8| od.get_i64(i, s).unwrap_or(0);
        (lo, hi) = (get(1), get(2));
    }
    if s == 1 {
        lo = x;
    } else {
        hi = x;
    }
    match i {
        0x607B => d.params.position_range = (lo as i32, hi as i32),
        0x607D => d.params.software_limits = (lo as i32, hi as i32),
        _ => (d.extra.vl_min, d.extra.vl_max) = (lo as u32, hi as u32),
    }
}

/// The factor group's ratio behind `i` (6091h gear, 6092h feed, 6096h
/// velocity, 6097h acceleration factor).
pub(super) fn factor_slot(f: &mut super::FactorGroup, i: u16) -> &mut (u32, u32) {
    match i {
        0x6091 => &mut f.gear,
        0x6092 => &mut f.feed,
        0x6096 => &mut f.velocity_factor,
        _ => &mut f.acceleration_factor,
    }
}

/// 6091h/6092h/6096h/6097h: positive, and the units they make must stay
/// exact (0609 0030 otherwise); stored set-up parameters only while
/// scaling objects are in force ([`super::FactorGroup::scaling`]).
pub(super) fn factor_check(
    d: &mut Drive,
    _: &mut ObjectDictionary,
    a: Arg,
) -> Result<WriteOutcome, SdoAbort> {
    let Arg { index: i, sub: s, v, .. } = a;
    range(v.u as i64, 1, i64::from(u32::MAX))?;
    if d.factor.scaling.is_none() {
        let mut f = d.factor;
        let slot = factor_slot(&mut f, i);
        if s == 1 {
            slot.0 = v.u32();
        } else {
            slot.1 = v.u32();
        }
        super::Units::new(&f).ok_or(SdoAbort::INVALID_VALUE)?;
    }
    Ok(WriteOutcome::Store)
}

pub(super) fn factor_apply(d: &mut Drive, _: &mut ObjectDictionary, a: Arg) {
    let Arg { index: i, sub: s, v, how, .. } = a;
    let slot = factor_slot(&mut d.factor, i);
    if s == 1 {
        slot.0 = v.u32();
    } else {
        slot.1 = v.u32();
    }
    // On a reload the units are derived once, after every factor; under
    // scaling objects the chain is kept but not in force.
    if how == How::Write && d.factor.scaling.is_none() {
        d.retune_units();
    }
}

/// Mode handler objects (60C0h, 60C1h, 60C4h, 6098h): the owning handler
/// validates and takes the value; the drive keeps its copy (apply).
pub(super) fn handler_check(
    d: &mut Drive,
    _: &mut ObjectDictionary,
    a: Arg,
) -> Result<WriteOutcome, SdoAbort> {
    let Arg { index: i, sub: s, v, .. } = a;
    let units = d.units;
    let data = v.bytes();
    for h in d.handlers.iter_mut() {
        if h.write_object(i, s, &data[..v.len()], &units)? {
            break;
        }
    }
    Ok(WriteOutcome::Store)
}

/// The drive runs vl.
pub(super) fn vl(modes: u32) -> bool {
    modes & op::supported_bit(op::VL) != 0
}

pub(super) fn vl_ramp(index: u16, name: &'static str, c: &DriveConfig) -> Object {
    record(
        index,
        name,
        [
            sub(1, "Delta speed", T::Unsigned32, Rw, U32(c.vl_rpm()), false),
            sub(2, "Delta time", T::Unsigned16, Rw, U16(1), false),
        ],
    )
}

pub(super) fn vl_ramp_check(
    _: &mut Drive,
    _: &mut ObjectDictionary,
    a: Arg,
) -> Result<WriteOutcome, SdoAbort> {
    let Arg { sub: s, v, .. } = a;
    if s == 2 {
        range(v.u as i64, 1, 65535)?;
    }
    Ok(WriteOutcome::Store)
}

pub(super) fn vl_ramp_apply(d: &mut Drive, _: &mut ObjectDictionary, a: Arg) {
    let Arg { index: i, sub: s, v, .. } = a;
    let r = if i == 0x6048 { &mut d.extra.vl_acc } else { &mut d.extra.vl_dec };
    match s {
        1 => r.0 = v.u32(),
        // A stored 0 would divide by zero.
        2 => r.1 = v.u16().max(1),
        _ => {}
    }
}
