//! The drive's CiA 402 objects, one entry each (CiA 402-2 §6 object
//! descriptions): the definition with its power-on value, the check of a
//! write, and how the drive takes the value — after a stored write and when
//! the node reloads stored parameters. Adding an object is adding an entry.
//!
//! An entry's position is its owner tag (`Owner::app(position)`), so a
//! write reaches its entry in one step. Entries without `check` and `apply`
//! are plain values the drive only publishes (statusword, actual values).

use super::checks::{
    factor_apply, factor_check, handler_check, min_max_apply, min_max_check, option_apply, option_check,
    positive, ramp_apply, ramp_check, vl, vl_ramp, vl_ramp_apply, vl_ramp_check,
};
use super::config::{DriveConfig, ZeroMeansOff, profile_type};
use super::mode::op;
use super::objects::{How, Raw, array, pair_of, range, record, sub, supported_homing_methods, var};
use super::{Drive, ProfileJerk};
use drivebus_od::{Access, DataType as T, Object, ObjectDictionary, SdoAbort, Value, WriteOutcome};

/// The definition: the object with its power-on values (`u32`: 6502h, the
/// modes the drive runs), `None` when this drive lacks the object.
pub(crate) type Def = fn(&DriveConfig, u32) -> Option<Object>;
/// The check of a write of `(index, sub)` (type, length and OD limits
/// already passed); changes nothing but what a `Handled` write applies.
pub(crate) type Check = fn(&mut Drive, &mut ObjectDictionary, u16, u8, Raw) -> Result<WriteOutcome, SdoAbort>;
/// Taking the value of `(index, sub)`.
pub(crate) type Apply = fn(&mut Drive, &mut ObjectDictionary, u16, u8, Raw, How);

/// One object of the drive.
pub(crate) struct Param {
    pub index: u16,
    pub def: Def,
    pub check: Option<Check>,
    pub apply: Option<Apply>,
    /// A mode handler shows its present values before a read (60C4h).
    pub live: bool,
}

impl Param {
    /// The drive owns the object's writable sub-objects.
    pub(crate) fn owned(&self) -> bool {
        self.check.is_some() || self.apply.is_some() || self.live
    }
}

const fn plain(index: u16, def: Def) -> Param {
    Param { index, def, check: None, apply: None, live: false }
}
const fn taken(index: u16, def: Def, apply: Apply) -> Param {
    Param { index, def, check: None, apply: Some(apply), live: false }
}
const fn checked(index: u16, def: Def, check: Check, apply: Apply) -> Param {
    Param { index, def, check: Some(check), apply: Some(apply), live: false }
}

use Access::{Ro, Rw, Rww};
use Value::{I8, I16, I32, U8, U16, U32};

/// The drive's objects, in reload order (6060h last: entering the mode
/// needs every other parameter).
pub(crate) static PARAMS: &[Param] = &[
    checked(
        0x6007,
        |c, _| {
            Some(var(
                0x6007,
                "Abort connection option code",
                T::Integer16,
                Rw,
                I16(c.options.abort_connection()),
                false,
            ))
        },
        option_check,
        option_apply,
    ),
    plain(0x603F, |_, _| Some(var(0x603F, "Error code", T::Unsigned16, Ro, U16(0), true))),
    Param {
        index: 0x6040,
        def: |_, _| Some(var(0x6040, "Controlword", T::Unsigned16, Rww, U16(0), true)),
        check: None,
        // A controlword acts when written, never again on a reload.
        apply: Some(|d, od, _, _, v, how| {
            if how == How::Write {
                d.controlword(od, v.u16());
            }
        }),
        live: false,
    },
    plain(0x6041, |_, _| Some(var(0x6041, "Statusword", T::Unsigned16, Ro, U16(0), true))),
    checked(
        0x605A,
        |c, _| {
            Some(var(0x605A, "Quick stop option code", T::Integer16, Rw, I16(c.options.quick_stop()), false))
        },
        option_check,
        option_apply,
    ),
    checked(
        0x605B,
        |c, _| Some(var(0x605B, "Shutdown option code", T::Integer16, Rw, I16(c.options.shutdown()), false)),
        option_check,
        option_apply,
    ),
    checked(
        0x605C,
        |c, _| {
            let v = I16(c.options.disable_operation());
            Some(var(0x605C, "Disable operation option code", T::Integer16, Rw, v, false))
        },
        option_check,
        option_apply,
    ),
    checked(
        0x605D,
        |c, _| Some(var(0x605D, "Halt option code", T::Integer16, Rw, I16(c.options.halt()), false)),
        option_check,
        option_apply,
    ),
    checked(
        0x605E,
        |c, _| {
            Some(var(
                0x605E,
                "Fault reaction option code",
                T::Integer16,
                Rw,
                I16(c.options.fault_reaction()),
                false,
            ))
        },
        option_check,
        option_apply,
    ),
    // The display starts with the power-on mode the drive enters.
    plain(0x6061, |c, modes| {
        let m = if op::supported_bit(c.initial_mode) & modes != 0 { c.initial_mode } else { 0 };
        Some(var(0x6061, "Modes of operation display", T::Integer8, Ro, I8(m), true))
    }),
    plain(0x6062, |_, _| Some(var(0x6062, "Position demand value", T::Integer32, Ro, I32(0), true))),
    plain(0x6063, |_, _| Some(var(0x6063, "Position actual internal value", T::Integer32, Ro, I32(0), true))),
    plain(0x6064, |_, _| Some(var(0x6064, "Position actual value", T::Integer32, Ro, I32(0), true))),
    taken(
        0x6065,
        |c, _| {
            Some(var(
                0x6065,
                "Following error window",
                T::Unsigned32,
                Rw,
                U32(c.profile.following_error_window),
                true,
            ))
        },
        |d, _, _, _, v, _| {
            let off = d.cfg.zero_means_off.following_error_window;
            d.params.following_error_window = ZeroMeansOff::effective(off, v.u32());
        },
    ),
    taken(
        0x6066,
        |c, _| {
            Some(var(
                0x6066,
                "Following error time out",
                T::Unsigned16,
                Rw,
                U16(c.profile.following_error_timeout),
                true,
            ))
        },
        |d, _, _, _, v, _| d.params.following_error_timeout = v.u16(),
    ),
    taken(
        0x6067,
        |c, _| Some(var(0x6067, "Position window", T::Unsigned32, Rw, U32(c.profile.position_window), true)),
        |d, _, _, _, v, _| d.params.position_window = v.u32(),
    ),
    taken(
        0x6068,
        |c, _| {
            Some(var(
                0x6068,
                "Position window time",
                T::Unsigned16,
                Rw,
                U16(c.profile.position_window_time),
                true,
            ))
        },
        |d, _, _, _, v, _| d.params.position_window_time = v.u16(),
    ),
    plain(0x606B, |_, _| Some(var(0x606B, "Velocity demand value", T::Integer32, Ro, I32(0), true))),
    plain(0x606C, |_, _| Some(var(0x606C, "Velocity actual value", T::Integer32, Ro, I32(0), true))),
    taken(
        0x606D,
        |c, _| Some(var(0x606D, "Velocity window", T::Unsigned16, Rw, U16(c.profile.velocity_window), true)),
        |d, _, _, _, v, _| d.extra.velocity_window = v.u16(),
    ),
    taken(
        0x606E,
        |c, _| {
            Some(var(
                0x606E,
                "Velocity window time",
                T::Unsigned16,
                Rw,
                U16(c.profile.velocity_window_time),
                true,
            ))
        },
        |d, _, _, _, v, _| d.extra.velocity_window_time = v.u16(),
    ),
    taken(
        0x606F,
        |c, _| {
            Some(var(
                0x606F,
                "Velocity threshold",
                T::Unsigned16,
                Rw,
                U16(c.profile.velocity_threshold),
                true,
            ))
        },
        |d, _, _, _, v, _| d.extra.velocity_threshold = v.u16(),
    ),
    taken(
        0x6070,
        |c, _| {
            let v = U16(c.profile.velocity_threshold_time);
            Some(var(0x6070, "Velocity threshold time", T::Unsigned16, Rw, v, true))
        },
        |d, _, _, _, v, _| d.extra.velocity_threshold_time = v.u16(),
    ),
    taken(
        0x6071,
        |_, _| Some(var(0x6071, "Target torque", T::Integer16, Rww, I16(0), true)),
        |d, _, _, _, v, _| d.params.target_torque = v.i16(),
    ),
    taken(
        0x6072,
        |c, _| Some(var(0x6072, "Max torque", T::Unsigned16, Rw, U16(c.max_torque_per_mille()), true)),
        |d, _, _, _, v, _| d.params.max_torque = v.u16(),
    ),
    taken(
        0x6073,
        |c, _| Some(var(0x6073, "Max current", T::Unsigned16, Rw, U16(c.max_torque_per_mille()), false)),
        |d, _, _, _, v, _| d.extra.max_current = v.u16(),
    ),
    plain(0x6074, |_, _| Some(var(0x6074, "Torque demand", T::Integer16, Ro, I16(0), true))),
    checked(
        0x6075,
        |c, _| Some(var(0x6075, "Motor rated current", T::Unsigned32, Rw, U32(c.rated_current_ma()), false)),
        positive,
        |d, _, _, _, v, _| d.extra.rated_current = v.u32().max(1),
    ),
    checked(
        0x6076,
        |c, _| Some(var(0x6076, "Motor rated torque", T::Unsigned32, Rw, U32(c.rated_torque_mnm()), false)),
        positive,
        |d, _, _, _, v, _| d.extra.rated_torque = v.u32().max(1),
    ),
    plain(0x6077, |_, _| Some(var(0x6077, "Torque actual value", T::Integer16, Ro, I16(0), true))),
    plain(0x6078, |_, _| Some(var(0x6078, "Current actual value", T::Integer16, Ro, I16(0), true))),
    // mV; the bus starts at its nominal voltage.
    plain(0x6079, |c, _| {
        let mv = (c.params.bus.nominal_voltage * 1000.0).clamp(0.0, 4e9) as u32;
        Some(var(0x6079, "DC link circuit voltage", T::Unsigned32, Ro, U32(mv), true))
    }),
    taken(
        0x607A,
        |_, _| Some(var(0x607A, "Target position", T::Integer32, Rww, I32(0), true)),
        |d, _, _, _, v, _| d.params.target_position = v.i32(),
    ),
    checked(
        0x607B,
        |_, _| Some(array(0x607B, "Position range limit", T::Integer32, Rw, &[I32(0), I32(0)], false)),
        min_max_check,
        min_max_apply,
    ),
    taken(
        0x607C,
        |_, _| Some(var(0x607C, "Home offset", T::Integer32, Rw, I32(0), true)),
        |d, _, _, _, v, _| d.params.home_offset = v.i32(),
    ),
    checked(
        0x607D,
        |_, _| Some(array(0x607D, "Software position limit", T::Integer32, Rw, &[I32(0), I32(0)], false)),
        min_max_check,
        min_max_apply,
    ),
    checked(
        0x607E,
        |c, _| Some(var(0x607E, "Polarity", T::Unsigned8, Rw, U8(c.factor.polarity), false)),
        // Only bit 7 (position) and bit 6 (velocity) are defined.
        |_, _, _, _, v| if v.u & !0xC0 != 0 { Err(SdoAbort::INVALID_VALUE) } else { Ok(WriteOutcome::Store) },
        |d, _, _, _, v, how| {
            d.factor.polarity = v.u8();
            if how == How::Write {
                d.retune_units();
            }
        },
    ),
    taken(
        0x607F,
        |c, _| {
            Some(var(
                0x607F,
                "Max profile velocity",
                T::Unsigned32,
                Rw,
                U32(c.profile.max_profile_velocity),
                true,
            ))
        },
        |d, _, _, _, v, _| d.params.max_profile_velocity = v.u32(),
    ),
    taken(
        0x6080,
        |c, _| {
            Some(var(0x6080, "Max motor speed", T::Unsigned32, Rw, U32(c.profile.max_profile_velocity), true))
        },
        |d, _, _, _, v, _| {
            d.params.max_motor_speed = ZeroMeansOff::effective(d.cfg.zero_means_off.max_motor_speed, v.u32())
        },
    ),
    taken(
        0x6081,
        |c, _| {
            Some(var(0x6081, "Profile velocity", T::Unsigned32, Rw, U32(c.profile.profile_velocity), true))
        },
        |d, _, _, _, v, _| d.extra.profile_velocity = v.u32(),
    ),
    taken(
        0x6082,
        |_, _| Some(var(0x6082, "End velocity", T::Unsigned32, Rw, U32(0), true)),
        |d, _, _, _, v, _| d.extra.end_velocity = v.u32(),
    ),
    checked(
        0x6083,
        |c, _| {
            Some(var(
                0x6083,
                "Profile acceleration",
                T::Unsigned32,
                Rw,
                U32(c.profile.profile_acceleration),
                true,
            ))
        },
        ramp_check,
        ramp_apply,
    ),
    checked(
        0x6084,
        |c, _| {
            Some(var(
                0x6084,
                "Profile deceleration",
                T::Unsigned32,
                Rw,
                U32(c.profile.profile_deceleration),
                true,
            ))
        },
        ramp_check,
        ramp_apply,
    ),
    checked(
        0x6085,
        |c, _| {
            let v = U32(c.profile.quick_stop_deceleration);
            Some(var(0x6085, "Quick stop deceleration", T::Unsigned32, Rw, v, true))
        },
        ramp_check,
        ramp_apply,
    ),
    checked(
        0x6086,
        |_, _| Some(var(0x6086, "Motion profile type", T::Integer16, Rw, I16(0), true)),
        // 0 linear ramp, 1 sin² ramp, 3 jerk-limited ramp (CiA 402-2
        // §6.7.x), as far as this drive offers them.
        |d, _, _, _, v| {
            let types = d.cfg.motion_profile_types & profile_type::IMPLEMENTED;
            if !(0..32).contains(&v.s) || types & (1u32 << v.s) == 0 {
                return Err(SdoAbort::INVALID_VALUE);
            }
            Ok(WriteOutcome::Store)
        },
        |d, _, _, _, v, _| d.extra.profile_type = v.i16(),
    ),
    taken(
        0x6087,
        |c, _| Some(var(0x6087, "Torque slope", T::Unsigned32, Rw, U32(c.profile.torque_slope), true)),
        |d, _, _, _, v, _| d.extra.torque_slope = v.u32(),
    ),
    checked(
        0x6088,
        |_, _| Some(var(0x6088, "Torque profile type", T::Integer16, Rw, I16(0), true)),
        // Only 0 (linear torque ramp) is implemented.
        |_, _, _, _, v| if v.s != 0 { Err(SdoAbort::INVALID_VALUE) } else { Ok(WriteOutcome::Store) },
        |_, _, _, _, _, _| {},
    ),
    plain(0x608F, |c, _| {
        let e = c.factor.encoder;
        Some(array(0x608F, "Position encoder resolution", T::Unsigned32, Ro, &[U32(e.0), U32(e.1)], false))
    }),
    plain(0x6090, |c, _| {
        let e = c.factor.velocity_encoder;
        Some(array(0x6090, "Velocity encoder resolution", T::Unsigned32, Ro, &[U32(e.0), U32(e.1)], false))
    }),
    checked(
        0x6091,
        |c, _| {
            Some(array(
                0x6091,
                "Gear ratio",
                T::Unsigned32,
                Rw,
                &[U32(c.factor.gear.0), U32(c.factor.gear.1)],
                false,
            ))
        },
        factor_check,
        factor_apply,
    ),
    checked(
        0x6092,
        |c, _| {
            Some(array(
                0x6092,
                "Feed constant",
                T::Unsigned32,
                Rw,
                &[U32(c.factor.feed.0), U32(c.factor.feed.1)],
                false,
            ))
        },
        factor_check,
        factor_apply,
    ),
    checked(
        0x6096,
        |c, _| {
            let f = c.factor.velocity_factor;
            Some(array(0x6096, "Velocity factor", T::Unsigned32, Rw, &[U32(f.0), U32(f.1)], false))
        },
        factor_check,
        factor_apply,
    ),
    checked(
        0x6097,
        |c, _| {
            let f = c.factor.acceleration_factor;
            Some(array(0x6097, "Acceleration factor", T::Unsigned32, Rw, &[U32(f.0), U32(f.1)], false))
        },
        factor_check,
        factor_apply,
    ),
    // Homing (behaviour: crate::homing through a ModeHandler).
    checked(
        0x6098,
        |_, _| Some(var(0x6098, "Homing method", T::Integer8, Rw, I8(0), true)),
        handler_check,
        |d, _, _, _, v, _| d.params.homing_method = v.i8(),
    ),
    taken(
        0x6099,
        |c, _| {
            let v = c.profile.profile_velocity;
            Some(array(0x6099, "Homing speeds", T::Unsigned32, Rw, &[U32(v / 4), U32(v / 40)], true))
        },
        |d, _, _, s, v, _| match s {
            1 => d.params.homing_speed_switch = v.u32(),
            2 => d.params.homing_speed_zero = v.u32(),
            _ => {}
        },
    ),
    checked(
        0x609A,
        |c, _| {
            Some(var(
                0x609A,
                "Homing acceleration",
                T::Unsigned32,
                Rw,
                U32(c.profile.profile_acceleration),
                true,
            ))
        },
        ramp_check,
        ramp_apply,
    ),
    // CiA 402-2 60A4h profile jerk (ARRAY, up to 6 entries): this drive
    // uses two, sub 1 while the speed rises, sub 2 while it falls.
    checked(
        0x60A4,
        |c, _| {
            let (ja, jd) = c.profile_jerk_rates();
            c.profile_jerk_object
                .then(|| array(0x60A4, "Profile jerk", T::Unsigned32, Rw, &[U32(ja), U32(jd)], true))
        },
        // A jerk of 0 would never build up any acceleration.
        positive,
        |d, od, _, s, v, how| {
            let (a, b) = match (how, d.jerk) {
                (How::Write, _) => pair_of(od, 0x60A4),
                (How::Reload, ProfileJerk::Rate { acceleration, deceleration }) => {
                    (acceleration, deceleration)
                }
                // Stored rates replace rates; a jerk time (configured or set
                // by the personality) stays until 60A4h itself is written.
                (How::Reload, ProfileJerk::Time(_)) => return,
            };
            let (acceleration, deceleration) = if s == 1 { (v.u32(), b) } else { (a, v.u32()) };
            d.jerk = ProfileJerk::Rate { acceleration, deceleration };
        },
    ),
    plain(0x60A8, |c, _| Some(var(0x60A8, "SI unit position", T::Unsigned32, Rw, U32(c.si_units[0]), false))),
    plain(0x60A9, |c, _| Some(var(0x60A9, "SI unit velocity", T::Unsigned32, Rw, U32(c.si_units[1]), false))),
    plain(0x60AA, |c, _| {
        Some(var(0x60AA, "SI unit acceleration", T::Unsigned32, Rw, U32(c.si_units[2]), false))
    }),
    plain(0x60AB, |c, _| Some(var(0x60AB, "SI unit jerk", T::Unsigned32, Rw, U32(c.si_units[3]), false))),
    // Offsets and interpolation (behaviour: crate::interp).
    taken(
        0x60B0,
        |_, _| Some(var(0x60B0, "Position offset", T::Integer32, Rww, I32(0), true)),
        |d, _, _, _, v, _| d.params.position_offset = v.i32(),
    ),
    taken(
        0x60B1,
        |_, _| Some(var(0x60B1, "Velocity offset", T::Integer32, Rww, I32(0), true)),
        |d, _, _, _, v, _| d.params.velocity_offset = v.i32(),
    ),
    taken(
        0x60B2,
        |_, _| Some(var(0x60B2, "Torque offset", T::Integer16, Rww, I16(0), true)),
        |d, _, _, _, v, _| d.params.torque_offset = v.i16(),
    ),
    taken(
        0x60B8,
        |_, _| Some(var(0x60B8, "Touch probe function", T::Unsigned16, Rww, U16(0), true)),
        |d, _, _, _, v, _| {
            d.extra.probe_function = v.u16();
            d.probe.configure(v.u16());
        },
    ),
    plain(0x60B9, |_, _| Some(var(0x60B9, "Touch probe status", T::Unsigned16, Ro, U16(0), true))),
    plain(0x60BA, |_, _| Some(var(0x60BA, "Touch probe 1 positive edge", T::Integer32, Ro, I32(0), true))),
    plain(0x60BB, |_, _| Some(var(0x60BB, "Touch probe 1 negative edge", T::Integer32, Ro, I32(0), true))),
    plain(0x60BC, |_, _| Some(var(0x60BC, "Touch probe 2 positive edge", T::Integer32, Ro, I32(0), true))),
    plain(0x60BD, |_, _| Some(var(0x60BD, "Touch probe 2 negative edge", T::Integer32, Ro, I32(0), true))),
    checked(
        0x60C0,
        |_, _| Some(var(0x60C0, "Interpolation sub mode select", T::Integer16, Rw, I16(0), true)),
        handler_check,
        |d, _, _, _, v, _| d.params.interpolation_sub_mode = v.i16(),
    ),
    // Sub 1 position; subs 2 (velocity, PVT) and 3 (segment time in ms,
    // PT/PVT) for the manufacturer sub-modes of `IpMode`.
    checked(
        0x60C1,
        |_, _| {
            Some(array(
                0x60C1,
                "Interpolation data record",
                T::Integer32,
                Rww,
                &[I32(0), I32(0), I32(0)],
                true,
            ))
        },
        handler_check,
        |d, _, _, s, v, _| {
            if s == 1 {
                d.params.interpolation_data = v.i32();
            }
        },
    ),
    checked(
        0x60C2,
        |_, _| {
            Some(record(
                0x60C2,
                "Interpolation time period",
                [
                    sub(1, "Interpolation time period value", T::Unsigned8, Rw, U8(1), true),
                    sub(2, "Interpolation time index", T::Integer8, Rw, I8(-3), true),
                ],
            ))
        },
        // 10^index s: microseconds to seconds are meaningful.
        |_, _, _, s, v| {
            if s == 2 { range(v.s, -6, 0).map(|()| WriteOutcome::Store) } else { Ok(WriteOutcome::Store) }
        },
        |d, _, _, s, v, _| match s {
            1 => d.params.interpolation_period_value = v.u8(),
            2 => d.params.interpolation_period_index = v.i8(),
            _ => {}
        },
    ),
    plain(0x60C3, |_, _| {
        Some(array(0x60C3, "Interpolation sync definition", T::Unsigned8, Rw, &[U8(0), U8(1)], false))
    }),
    Param {
        index: 0x60C4,
        def: |_, _| {
            Some(record(
                0x60C4,
                "Interpolation data configuration",
                [
                    sub(1, "Maximum buffer size", T::Unsigned32, Ro, U32(1), false),
                    sub(2, "Actual buffer size", T::Unsigned32, Rw, U32(1), false),
                    sub(3, "Buffer organization", T::Unsigned8, Rw, U8(0), false),
                    sub(4, "Buffer position", T::Unsigned16, Rw, U16(1), false),
                    sub(5, "Size of data record", T::Unsigned8, Rw, U8(4), false),
                    sub(6, "Buffer clear", T::Unsigned8, Rw, U8(0), false),
                ],
            ))
        },
        check: Some(handler_check),
        apply: None,
        live: true,
    },
    checked(
        0x60C5,
        |c, _| {
            Some(var(0x60C5, "Max acceleration", T::Unsigned32, Rw, U32(c.profile.max_acceleration), true))
        },
        ramp_check,
        ramp_apply,
    ),
    checked(
        0x60C6,
        |c, _| {
            Some(var(0x60C6, "Max deceleration", T::Unsigned32, Rw, U32(c.profile.max_acceleration), true))
        },
        ramp_check,
        ramp_apply,
    ),
    // 60D0h touch probe source (ARRAY of INTEGER16), used with 60B8h
    // trigger selection 10b: 1 / 2 touch probe input 1 / 2, 5 hardware and
    // 6 software zero impulse of the position encoder (the same index
    // here); 3 / 4 and manufacturer codes are not wired (CiA 402-2 /
    // ETG.6010 coding, e.g. Beckhoff AX8000 60D0h:01).
    checked(
        0x60D0,
        |c, _| {
            c.io.probe_source_object
                .then(|| array(0x60D0, "Touch probe source", T::Integer16, Rw, &[I16(1), I16(2)], false))
        },
        |_, _, _, _, v| {
            if matches!(v.s, 1 | 2 | 5 | 6) { Ok(WriteOutcome::Store) } else { Err(SdoAbort::INVALID_VALUE) }
        },
        |d, _, _, s, v, _| {
            if let Some(x) = d.probe.source.get_mut(usize::from(s).wrapping_sub(1)) {
                // A stored code the drive does not wire is off.
                *x = if matches!(v.s, 1 | 2 | 5 | 6) { v.i16() } else { 0 };
            }
        },
    ),
    // 60E3h: the standard methods (CiA 402-2 §6.7.x: 1–14, 17–30, 33–35,
    // 37); a handler with a registry replaces it.
    plain(0x60E3, |_, modes| {
        (modes & op::supported_bit(op::HM) != 0).then(|| {
            let methods: alloc::vec::Vec<i8> =
                (1..=37i8).filter(|m| !matches!(m, 15 | 16 | 31 | 32 | 36)).collect();
            supported_homing_methods(&methods)
        })
    }),
    plain(0x60F4, |_, _| Some(var(0x60F4, "Following error actual value", T::Integer32, Ro, I32(0), true))),
    plain(0x60FD, |_, _| Some(var(0x60FD, "Digital inputs", T::Unsigned32, Ro, U32(0), true))),
    checked(
        0x60FE,
        |c, _| {
            Some(array(0x60FE, "Digital outputs", T::Unsigned32, Rww, &[U32(0), U32(c.io.output_mask)], true))
        },
        |d, od, _, s, v| {
            if s == 1 && !d.cfg.io.keep_unmasked_command {
                // Only the outputs enabled in the bit mask (sub 2) follow,
                // and the object shows what was set.
                d.extra.outputs = v.u32() & d.extra.output_mask;
                if let Ok(r) = od.find(0x60FE, 1) {
                    od.set_le(r, &d.extra.outputs.to_le_bytes());
                }
                return Ok(WriteOutcome::Handled);
            }
            Ok(WriteOutcome::Store)
        },
        |d, od, _, s, v, how| {
            let x = &mut d.extra;
            match (how, s) {
                // Sub 1 (the command) comes before sub 2 (the mask).
                (How::Reload, 1) => x.outputs = v.u32(),
                (How::Reload, _) => {
                    x.output_mask = v.u32();
                    x.outputs &= x.output_mask;
                }
                (How::Write, 1) => x.outputs = v.u32() & x.output_mask,
                (How::Write, _) => {
                    x.output_mask = v.u32();
                    if d.cfg.io.keep_unmasked_command {
                        // The stored command takes effect through the new mask.
                        x.outputs = od.get_u32(0x60FE, 1).unwrap_or(0) & x.output_mask;
                    }
                }
            }
        },
    ),
    taken(
        0x60FF,
        |_, _| Some(var(0x60FF, "Target velocity", T::Integer32, Rww, I32(0), true)),
        |d, _, _, _, v, _| d.params.target_velocity = v.i32(),
    ),
    plain(0x6502, |_, modes| {
        Some(var(0x6502, "Supported drive modes", T::Unsigned32, Ro, U32(modes), false))
    }),
    // vl (CiA 402-2 §6.5): speeds in rpm of the motor shaft.
    taken(
        0x6042,
        |_, modes| vl(modes).then(|| var(0x6042, "vl target velocity", T::Integer16, Rww, I16(0), true)),
        |d, _, _, _, v, _| d.extra.vl_target = v.i16(),
    ),
    plain(0x6043, |_, modes| {
        vl(modes).then(|| var(0x6043, "vl velocity demand", T::Integer16, Ro, I16(0), true))
    }),
    plain(0x6044, |_, modes| {
        vl(modes).then(|| var(0x6044, "vl velocity actual value", T::Integer16, Ro, I16(0), true))
    }),
    checked(
        0x6046,
        |c, modes| {
            vl(modes).then(|| {
                let v = [U32(0), U32(c.vl_rpm())];
                array(0x6046, "vl velocity min max amount", T::Unsigned32, Rw, &v, false)
            })
        },
        min_max_check,
        min_max_apply,
    ),
    checked(
        0x6048,
        |c, modes| vl(modes).then(|| vl_ramp(0x6048, "vl velocity acceleration", c)),
        vl_ramp_check,
        vl_ramp_apply,
    ),
    checked(
        0x6049,
        |c, modes| vl(modes).then(|| vl_ramp(0x6049, "vl velocity deceleration", c)),
        vl_ramp_check,
        vl_ramp_apply,
    ),
    // Last: the mode is entered with every other parameter in place.
    Param {
        index: 0x6060,
        def: |c, _| Some(var(0x6060, "Modes of operation", T::Integer8, Rww, I8(c.initial_mode), true)),
        check: Some(|d, _, _, _, v| {
            // CiA 402-2 §6.3.2: a mode the drive does not run is refused
            // (a manufacturer mode runs on its stand-in); 0 is "no mode
            // change" (the power-on value of a drive without a default
            // mode): stored, the mode in force stays.
            if v.i8() != 0 && d.stand_in(v.i8()).is_none() {
                return Err(SdoAbort::INVALID_VALUE);
            }
            Ok(WriteOutcome::Store)
        }),
        apply: Some(|d, od, _, _, v, _| d.select_mode(od, v.i8())),
        live: false,
    },
];
