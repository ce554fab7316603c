//! The drive's CiA 402 objects, one entry each (CiA 402-2 §6 object
//! descriptions): the definition with its power-on value, the check of a
//! write, and how the drive takes the value — after a stored write and when
//! the node reloads stored parameters. Adding an object is adding an entry.
//!
//! An entry's position is its owner tag (`Owner::app(position)`), so a
//! write reaches its entry in one step. Entries without `check` and `apply`
//! are plain values: the live values the drive publishes (statusword,
//! actual values) and parameters it does not act on.

use super::checks::{
    factor_apply, factor_check, handler_check, min_max_apply, min_max_check, option_apply, option_check,
    positive, ramp_apply, ramp_check, vl, vl_ramp, vl_ramp_apply, vl_ramp_check,
};
use super::config::{DriveConfig, ZeroMeansOff, profile_type};
use super::mode::op;
use super::objects::{Arg, How, array, pair_of, range, record, sub, supported_homing_methods, var};
use super::{Drive, ProfileJerk};
use drivebus_od::{Access, DataType as T, Object, ObjectDictionary, SdoAbort, Value, WriteOutcome};

/// How an object is made, with its power-on values from the configuration.
#[derive(Clone, Copy)]
pub(crate) enum Def {
    /// A VAR: name, type, access, PDO-mappable, power-on value.
    Var(&'static str, T, Access, bool, fn(&DriveConfig) -> i64),
    /// An ARRAY of two entries (sub 1, sub 2), each like a VAR.
    Pair(&'static str, T, Access, bool, fn(&DriveConfig) -> (i64, i64)),
    /// Anything else; `u32` is 6502h (the modes the drive runs).
    With(fn(&DriveConfig, u32) -> Object),
}

/// The check of a write (type, length and OD limits already passed);
/// changes nothing but what a `Handled` write applies.
pub(crate) type Check = fn(&mut Drive, &mut ObjectDictionary, Arg) -> Result<WriteOutcome, SdoAbort>;
/// Taking a value (after a stored write, or on a reload: [`Arg::how`]).
pub(crate) type Apply = fn(&mut Drive, &mut ObjectDictionary, Arg);

/// One object of the drive.
#[derive(Clone, Copy)]
pub(crate) struct Param {
    pub index: u16,
    pub def: Def,
    /// Whether this drive has the object (configuration, 6502h).
    pub when: fn(&DriveConfig, u32) -> bool,
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

    /// The object with its power-on values, `None` when this drive lacks it.
    pub(crate) fn object(&self, c: &DriveConfig, modes: u32) -> Option<Object> {
        if !(self.when)(c, modes) {
            return None;
        }
        Some(match self.def {
            Def::Var(name, t, a, map, init) => var(self.index, name, t, a, value(t, init(c)), map),
            Def::Pair(name, t, a, map, init) => {
                let (x, y) = init(c);
                array(self.index, name, t, a, &[value(t, x), value(t, y)], map)
            }
            Def::With(f) => f(c, modes),
        })
    }

    const fn check(mut self, f: Check) -> Param {
        self.check = Some(f);
        self
    }
    const fn apply(mut self, f: Apply) -> Param {
        self.apply = Some(f);
        self
    }
    const fn live(mut self) -> Param {
        self.live = true;
        self
    }
    const fn when(mut self, f: fn(&DriveConfig, u32) -> bool) -> Param {
        self.when = f;
        self
    }
}

/// A value of a numeric type from its integer.
fn value(t: T, x: i64) -> Value {
    match t {
        T::Integer8 => Value::I8(x as i8),
        T::Integer16 => Value::I16(x as i16),
        T::Integer32 => Value::I32(x as i32),
        T::Unsigned8 => Value::U8(x as u8),
        T::Unsigned16 => Value::U16(x as u16),
        _ => Value::U32(x as u32),
    }
}

const fn always(_: &DriveConfig, _: u32) -> bool {
    true
}
const fn def(index: u16, def: Def) -> Param {
    Param { index, def, when: always, check: None, apply: None, live: false }
}
/// A VAR (`map`: PDO-mappable).
const fn v(
    index: u16,
    name: &'static str,
    t: T,
    a: Access,
    map: bool,
    init: fn(&DriveConfig) -> i64,
) -> Param {
    def(index, Def::Var(name, t, a, map, init))
}
/// A live value the drive publishes: read-only, mappable, 0 at power-on.
const fn live(index: u16, name: &'static str, t: T) -> Param {
    v(index, name, t, Ro, MAP, |_| 0)
}
/// A two-entry ARRAY.
const fn pair(
    index: u16,
    name: &'static str,
    t: T,
    a: Access,
    map: bool,
    init: fn(&DriveConfig) -> (i64, i64),
) -> Param {
    def(index, Def::Pair(name, t, a, map, init))
}
const fn with(index: u16, f: fn(&DriveConfig, u32) -> Object) -> Param {
    def(index, Def::With(f))
}

/// The drive runs vl (CiA 402-2 §6.5): the vl objects exist.
fn vl_on(_: &DriveConfig, modes: u32) -> bool {
    vl(modes)
}

const MAP: bool = true;
const NO_MAP: bool = false;
const INT8: T = T::Integer8;
const INT16: T = T::Integer16;
const INT32: T = T::Integer32;
const UNS8: T = T::Unsigned8;
const UNS16: T = T::Unsigned16;
const UNS32: T = T::Unsigned32;
use Access::{Ro, Rw, Rww};

/// The drive's objects, in reload order (6060h last: entering the mode
/// needs every other parameter).
pub(crate) static PARAMS: &[Param] = &[
    v(0x6007, "Abort connection option code", INT16, Rw, NO_MAP, |c| c.options.abort_connection().into())
        .check(option_check)
        .apply(option_apply),
    live(0x603F, "Error code", UNS16),
    // A controlword acts when written, never again on a reload.
    v(0x6040, "Controlword", UNS16, Rww, MAP, |_| 0).apply(|d, od, a| {
        if a.how == How::Write {
            d.controlword(od, a.v.u16());
        }
    }),
    live(0x6041, "Statusword", UNS16),
    v(0x605A, "Quick stop option code", INT16, Rw, NO_MAP, |c| c.options.quick_stop().into())
        .check(option_check)
        .apply(option_apply),
    v(0x605B, "Shutdown option code", INT16, Rw, NO_MAP, |c| c.options.shutdown().into())
        .check(option_check)
        .apply(option_apply),
    v(0x605C, "Disable operation option code", INT16, Rw, NO_MAP, |c| c.options.disable_operation().into())
        .check(option_check)
        .apply(option_apply),
    v(0x605D, "Halt option code", INT16, Rw, NO_MAP, |c| c.options.halt().into())
        .check(option_check)
        .apply(option_apply),
    v(0x605E, "Fault reaction option code", INT16, Rw, NO_MAP, |c| c.options.fault_reaction().into())
        .check(option_check)
        .apply(option_apply),
    // The display starts with the power-on mode the drive enters.
    with(0x6061, |c, modes| {
        let m = if op::supported_bit(c.initial_mode) & modes != 0 { c.initial_mode } else { 0 };
        var(0x6061, "Modes of operation display", INT8, Ro, Value::I8(m), MAP)
    }),
    live(0x6062, "Position demand value", INT32),
    live(0x6063, "Position actual internal value", INT32),
    live(0x6064, "Position actual value", INT32),
    v(0x6065, "Following error window", UNS32, Rw, MAP, |c| c.profile.following_error_window.into()).apply(
        |d, _, a| {
            let off = d.cfg.zero_means_off.following_error_window;
            d.params.following_error_window = ZeroMeansOff::effective(off, a.v.u32());
        },
    ),
    v(0x6066, "Following error time out", UNS16, Rw, MAP, |c| c.profile.following_error_timeout.into())
        .apply(|d, _, a| d.params.following_error_timeout = a.v.u16()),
    v(0x6067, "Position window", UNS32, Rw, MAP, |c| c.profile.position_window.into())
        .apply(|d, _, a| d.params.position_window = a.v.u32()),
    v(0x6068, "Position window time", UNS16, Rw, MAP, |c| c.profile.position_window_time.into())
        .apply(|d, _, a| d.params.position_window_time = a.v.u16()),
    live(0x606B, "Velocity demand value", INT32),
    live(0x606C, "Velocity actual value", INT32),
    v(0x606D, "Velocity window", UNS16, Rw, MAP, |c| c.profile.velocity_window.into())
        .apply(|d, _, a| d.extra.velocity_window = a.v.u16()),
    v(0x606E, "Velocity window time", UNS16, Rw, MAP, |c| c.profile.velocity_window_time.into())
        .apply(|d, _, a| d.extra.velocity_window_time = a.v.u16()),
    v(0x606F, "Velocity threshold", UNS16, Rw, MAP, |c| c.profile.velocity_threshold.into())
        .apply(|d, _, a| d.extra.velocity_threshold = a.v.u16()),
    v(0x6070, "Velocity threshold time", UNS16, Rw, MAP, |c| c.profile.velocity_threshold_time.into())
        .apply(|d, _, a| d.extra.velocity_threshold_time = a.v.u16()),
    v(0x6071, "Target torque", INT16, Rww, MAP, |_| 0).apply(|d, _, a| d.params.target_torque = a.v.i16()),
    v(0x6072, "Max torque", UNS16, Rw, MAP, |c| c.max_torque_per_mille().into())
        .apply(|d, _, a| d.params.max_torque = a.v.u16()),
    v(0x6073, "Max current", UNS16, Rw, NO_MAP, |c| c.max_torque_per_mille().into()).apply(|d, _, a| {
        let off = d.cfg.zero_means_off.max_current && a.v.u16() == 0;
        d.extra.max_current = if off { u16::MAX } else { a.v.u16() };
    }),
    live(0x6074, "Torque demand", INT16),
    v(0x6075, "Motor rated current", UNS32, Rw, NO_MAP, |c| c.rated_current_ma().into())
        .check(positive)
        .apply(|d, _, a| d.extra.rated_current = a.v.u32().max(1)),
    v(0x6076, "Motor rated torque", UNS32, Rw, NO_MAP, |c| c.rated_torque_mnm().into())
        .check(positive)
        .apply(|d, _, a| d.extra.rated_torque = a.v.u32().max(1)),
    live(0x6077, "Torque actual value", INT16),
    live(0x6078, "Current actual value", INT16),
    // mV; the bus starts at its nominal voltage.
    v(0x6079, "DC link circuit voltage", UNS32, Ro, MAP, |c| {
        (c.params.bus.nominal_voltage * 1000.0).clamp(0.0, 4e9) as i64
    }),
    v(0x607A, "Target position", INT32, Rww, MAP, |_| 0)
        .apply(|d, _, a| d.params.target_position = a.v.i32()),
    pair(0x607B, "Position range limit", INT32, Rw, NO_MAP, |_| (0, 0))
        .check(min_max_check)
        .apply(min_max_apply),
    v(0x607C, "Home offset", INT32, Rw, MAP, |_| 0).apply(|d, _, a| d.params.home_offset = a.v.i32()),
    pair(0x607D, "Software position limit", INT32, Rw, NO_MAP, |_| (0, 0))
        .check(min_max_check)
        .apply(min_max_apply),
    v(0x607E, "Polarity", UNS8, Rw, NO_MAP, |c| c.factor.polarity.into())
        // Only bit 7 (position) and bit 6 (velocity) are defined.
        .check(
            |_, _, a| if a.v.u & !0xC0 != 0 { Err(SdoAbort::INVALID_VALUE) } else { Ok(WriteOutcome::Store) },
        )
        .apply(|d, _, a| {
            d.factor.polarity = a.v.u8();
            if a.how == How::Write {
                d.retune_units();
            }
        }),
    v(0x607F, "Max profile velocity", UNS32, Rw, MAP, |c| c.profile.max_profile_velocity.into())
        .apply(|d, _, a| d.params.max_profile_velocity = a.v.u32()),
    v(0x6080, "Max motor speed", UNS32, Rw, MAP, |c| c.profile.max_profile_velocity.into()).apply(
        |d, _, a| {
            d.params.max_motor_speed =
                ZeroMeansOff::effective(d.cfg.zero_means_off.max_motor_speed, a.v.u32())
        },
    ),
    v(0x6081, "Profile velocity", UNS32, Rw, MAP, |c| c.profile.profile_velocity.into())
        .apply(|d, _, a| d.extra.profile_velocity = a.v.u32()),
    v(0x6082, "End velocity", UNS32, Rw, MAP, |_| 0).apply(|d, _, a| d.extra.end_velocity = a.v.u32()),
    v(0x6083, "Profile acceleration", UNS32, Rw, MAP, |c| c.profile.profile_acceleration.into())
        .check(ramp_check)
        .apply(ramp_apply),
    v(0x6084, "Profile deceleration", UNS32, Rw, MAP, |c| c.profile.profile_deceleration.into())
        .check(ramp_check)
        .apply(ramp_apply),
    v(0x6085, "Quick stop deceleration", UNS32, Rw, MAP, |c| c.profile.quick_stop_deceleration.into())
        .check(ramp_check)
        .apply(ramp_apply),
    v(0x6086, "Motion profile type", INT16, Rw, MAP, |_| 0)
        // 0 linear ramp, 1 sin² ramp, 3 jerk-limited ramp (CiA 402-2
        // §6.7.x), as far as this drive offers them.
        .check(|d, _, a| {
            let types = d.cfg.motion_profile_types & profile_type::IMPLEMENTED;
            if !(0..32).contains(&a.v.s) || types & (1u32 << a.v.s) == 0 {
                return Err(SdoAbort::INVALID_VALUE);
            }
            Ok(WriteOutcome::Store)
        })
        .apply(|d, _, a| d.extra.profile_type = a.v.i16()),
    v(0x6087, "Torque slope", UNS32, Rw, MAP, |c| c.profile.torque_slope.into())
        .apply(|d, _, a| d.extra.torque_slope = a.v.u32()),
    // Only 0 (linear torque ramp) is implemented.
    v(0x6088, "Torque profile type", INT16, Rw, MAP, |_| 0)
        .check(|_, _, a| if a.v.s != 0 { Err(SdoAbort::INVALID_VALUE) } else { Ok(WriteOutcome::Store) }),
    pair(0x608F, "Position encoder resolution", UNS32, Ro, NO_MAP, |c| wide(c.factor.encoder)),
    pair(0x6090, "Velocity encoder resolution", UNS32, Ro, NO_MAP, |c| wide(c.factor.velocity_encoder)),
    pair(0x6091, "Gear ratio", UNS32, Rw, NO_MAP, |c| wide(c.factor.gear))
        .check(factor_check)
        .apply(factor_apply),
    pair(0x6092, "Feed constant", UNS32, Rw, NO_MAP, |c| wide(c.factor.feed))
        .check(factor_check)
        .apply(factor_apply),
    pair(0x6096, "Velocity factor", UNS32, Rw, NO_MAP, |c| wide(c.factor.velocity_factor))
        .check(factor_check)
        .apply(factor_apply),
    pair(0x6097, "Acceleration factor", UNS32, Rw, NO_MAP, |c| wide(c.factor.acceleration_factor))
        .check(factor_check)
        .apply(factor_apply),
    // Homing (behaviour: crate::homing through a ModeHandler).
    v(0x6098, "Homing method", INT8, Rw, MAP, |_| 0)
        .check(handler_check)
        .apply(|d, _, a| d.params.homing_method = a.v.i8()),
    pair(0x6099, "Homing speeds", UNS32, Rw, MAP, |c| {
        let v = i64::from(c.profile.profile_velocity);
        (v / 4, v / 40)
    })
    .apply(|d, _, a| match a.sub {
        1 => d.params.homing_speed_switch = a.v.u32(),
        2 => d.params.homing_speed_zero = a.v.u32(),
        _ => {}
    }),
    v(0x609A, "Homing acceleration", UNS32, Rw, MAP, |c| c.profile.profile_acceleration.into())
        .check(ramp_check)
        .apply(ramp_apply),
    // CiA 402-2 60A4h profile jerk (ARRAY, up to 6 entries): this drive
    // uses two, sub 1 while the speed rises, sub 2 while it falls. A jerk of
    // 0 would never build up any acceleration.
    pair(0x60A4, "Profile jerk", UNS32, Rw, MAP, |c| wide(c.profile_jerk_rates()))
        .when(|c, _| c.profile_jerk_object)
        .check(positive)
        .apply(|d, od, a| {
            let (x, y) = match (a.how, d.jerk) {
                (How::Write, _) => pair_of(od, 0x60A4),
                (How::Reload, ProfileJerk::Rate { acceleration, deceleration }) => {
                    (acceleration, deceleration)
                }
                // Stored rates replace rates; a jerk time (configured or set
                // by the personality) stays until 60A4h itself is written.
                (How::Reload, ProfileJerk::Time(_)) => return,
            };
            let (acceleration, deceleration) = if a.sub == 1 { (a.v.u32(), y) } else { (x, a.v.u32()) };
            d.jerk = ProfileJerk::Rate { acceleration, deceleration };
        }),
    v(0x60A8, "SI unit position", UNS32, Rw, NO_MAP, |c| c.si_units[0].into()),
    v(0x60A9, "SI unit velocity", UNS32, Rw, NO_MAP, |c| c.si_units[1].into()),
    v(0x60AA, "SI unit acceleration", UNS32, Rw, NO_MAP, |c| c.si_units[2].into()),
    v(0x60AB, "SI unit jerk", UNS32, Rw, NO_MAP, |c| c.si_units[3].into()),
    // Offsets and interpolation (behaviour: crate::interp).
    v(0x60B0, "Position offset", INT32, Rww, MAP, |_| 0)
        .apply(|d, _, a| d.params.position_offset = a.v.i32()),
    v(0x60B1, "Velocity offset", INT32, Rww, MAP, |_| 0)
        .apply(|d, _, a| d.params.velocity_offset = a.v.i32()),
    v(0x60B2, "Torque offset", INT16, Rww, MAP, |_| 0).apply(|d, _, a| d.params.torque_offset = a.v.i16()),
    v(0x60B8, "Touch probe function", UNS16, Rww, MAP, |_| 0).apply(|d, _, a| {
        d.extra.probe_function = a.v.u16();
        d.probe.configure(a.v.u16());
    }),
    live(0x60B9, "Touch probe status", UNS16),
    live(0x60BA, "Touch probe 1 positive edge", INT32),
    live(0x60BB, "Touch probe 1 negative edge", INT32),
    live(0x60BC, "Touch probe 2 positive edge", INT32),
    live(0x60BD, "Touch probe 2 negative edge", INT32),
    v(0x60C0, "Interpolation sub mode select", INT16, Rw, MAP, |_| 0)
        .check(handler_check)
        .apply(|d, _, a| d.params.interpolation_sub_mode = a.v.i16()),
    // Sub 1 position; subs 2 (velocity, PVT) and 3 (segment time in ms,
    // PT/PVT) for the manufacturer sub-modes of `IpMode`.
    with(0x60C1, |_, _| {
        let zero = [Value::I32(0), Value::I32(0), Value::I32(0)];
        array(0x60C1, "Interpolation data record", INT32, Rww, &zero, MAP)
    })
    .check(handler_check)
    .apply(|d, _, a| {
        if a.sub == 1 {
            d.params.interpolation_data = a.v.i32();
        }
    }),
    with(0x60C2, |_, _| {
        record(
            0x60C2,
            "Interpolation time period",
            [
                sub(1, "Interpolation time period value", UNS8, Rw, Value::U8(1), MAP),
                sub(2, "Interpolation time index", INT8, Rw, Value::I8(-3), MAP),
            ],
        )
    })
    // 10^index s: microseconds to seconds are meaningful.
    .check(|_, _, a| {
        if a.sub == 2 { range(a.v.s, -6, 0).map(|()| WriteOutcome::Store) } else { Ok(WriteOutcome::Store) }
    })
    .apply(|d, _, a| match a.sub {
        1 => d.params.interpolation_period_value = a.v.u8(),
        2 => d.params.interpolation_period_index = a.v.i8(),
        _ => {}
    }),
    pair(0x60C3, "Interpolation sync definition", UNS8, Rw, NO_MAP, |_| (0, 1)),
    with(0x60C4, |_, _| {
        record(
            0x60C4,
            "Interpolation data configuration",
            [
                sub(1, "Maximum buffer size", UNS32, Ro, Value::U32(1), NO_MAP),
                sub(2, "Actual buffer size", UNS32, Rw, Value::U32(1), NO_MAP),
                sub(3, "Buffer organization", UNS8, Rw, Value::U8(0), NO_MAP),
                sub(4, "Buffer position", UNS16, Rw, Value::U16(1), NO_MAP),
                sub(5, "Size of data record", UNS8, Rw, Value::U8(4), NO_MAP),
                sub(6, "Buffer clear", UNS8, Rw, Value::U8(0), NO_MAP),
            ],
        )
    })
    .check(handler_check)
    .live(),
    v(0x60C5, "Max acceleration", UNS32, Rw, MAP, |c| c.profile.max_acceleration.into())
        .check(ramp_check)
        .apply(ramp_apply),
    v(0x60C6, "Max deceleration", UNS32, Rw, MAP, |c| c.profile.max_acceleration.into())
        .check(ramp_check)
        .apply(ramp_apply),
    // 60D0h touch probe source (ARRAY of INTEGER16), used with 60B8h
    // trigger selection 10b: 1 / 2 touch probe input 1 / 2, 5 hardware and
    // 6 software zero impulse of the position encoder (the same index
    // here); 3 / 4 and manufacturer codes are not wired (CiA 402-2 /
    // ETG.6010 coding, e.g. Beckhoff AX8000 60D0h:01).
    pair(0x60D0, "Touch probe source", INT16, Rw, NO_MAP, |_| (1, 2))
        .when(|c, _| c.io.probe_source_object)
        .check(|_, _, a| {
            if matches!(a.v.s, 1 | 2 | 5 | 6) {
                Ok(WriteOutcome::Store)
            } else {
                Err(SdoAbort::INVALID_VALUE)
            }
        })
        .apply(|d, _, a| {
            if let Some(x) = d.probe.source.get_mut(usize::from(a.sub).wrapping_sub(1)) {
                // A stored code the drive does not wire is off.
                *x = if matches!(a.v.s, 1 | 2 | 5 | 6) { a.v.i16() } else { 0 };
            }
        }),
    // 60E3h: the standard methods (CiA 402-2 §6.7.x: 1–14, 17–30, 33–35,
    // 37); a handler with a registry replaces it.
    with(0x60E3, |_, _| {
        let methods: alloc::vec::Vec<i8> =
            (1..=37i8).filter(|m| !matches!(m, 15 | 16 | 31 | 32 | 36)).collect();
        supported_homing_methods(&methods)
    })
    .when(|_, modes| modes & op::supported_bit(op::HM) != 0),
    live(0x60F4, "Following error actual value", INT32),
    live(0x60FD, "Digital inputs", UNS32),
    pair(0x60FE, "Digital outputs", UNS32, Rww, MAP, |c| (0, c.io.output_mask.into()))
        .check(|d, od, a| {
            if a.sub == 1 && !d.cfg.io.keep_unmasked_command {
                // Only the outputs enabled in the bit mask (sub 2) follow,
                // and the object shows what was set.
                d.extra.outputs = a.v.u32() & d.extra.output_mask;
                if let Ok(r) = od.find(0x60FE, 1) {
                    od.set_le(r, &d.extra.outputs.to_le_bytes());
                }
                d.sync_outputs();
                return Ok(WriteOutcome::Handled);
            }
            Ok(WriteOutcome::Store)
        })
        .apply(|d, od, a| {
            let x = &mut d.extra;
            match (a.how, a.sub) {
                // Sub 1 (the command) comes before sub 2 (the mask).
                (How::Reload, 1) => x.outputs = a.v.u32(),
                (How::Reload, _) => {
                    x.output_mask = a.v.u32();
                    x.outputs &= x.output_mask;
                }
                (How::Write, 1) => x.outputs = a.v.u32() & x.output_mask,
                (How::Write, _) => {
                    x.output_mask = a.v.u32();
                    if d.cfg.io.keep_unmasked_command {
                        // The stored command takes effect through the new mask.
                        x.outputs = od.get_u32(0x60FE, 1).unwrap_or(0) & x.output_mask;
                    }
                }
            }
            d.sync_outputs();
        }),
    v(0x60FF, "Target velocity", INT32, Rww, MAP, |_| 0)
        .apply(|d, _, a| d.params.target_velocity = a.v.i32()),
    with(0x6502, |_, modes| var(0x6502, "Supported drive modes", UNS32, Ro, Value::U32(modes), NO_MAP)),
    // vl (CiA 402-2 §6.5): speeds in rpm of the motor shaft.
    v(0x6042, "vl target velocity", INT16, Rww, MAP, |_| 0)
        .when(vl_on)
        .apply(|d, _, a| d.extra.vl_target = a.v.i16()),
    live(0x6043, "vl velocity demand", INT16).when(vl_on),
    live(0x6044, "vl velocity actual value", INT16).when(vl_on),
    pair(0x6046, "vl velocity min max amount", UNS32, Rw, NO_MAP, |c| (0, c.vl_rpm().into()))
        .when(vl_on)
        .check(min_max_check)
        .apply(min_max_apply),
    with(0x6048, |c, _| vl_ramp(0x6048, "vl velocity acceleration", c))
        .when(vl_on)
        .check(vl_ramp_check)
        .apply(vl_ramp_apply),
    with(0x6049, |c, _| vl_ramp(0x6049, "vl velocity deceleration", c))
        .when(vl_on)
        .check(vl_ramp_check)
        .apply(vl_ramp_apply),
    // Last: the mode is entered with every other parameter in place.
    v(0x6060, "Modes of operation", INT8, Rww, MAP, |c| c.initial_mode.into())
        // CiA 402-2 §6.3.2: a mode the drive does not run is refused (a
        // manufacturer mode runs on its stand-in); 0 is "no mode change"
        // (the power-on value of a drive without a default mode): stored,
        // the mode in force stays.
        .check(|d, _, a| {
            if a.v.i8() != 0 && d.stand_in(a.v.i8()).is_none() {
                return Err(SdoAbort::INVALID_VALUE);
            }
            Ok(WriteOutcome::Store)
        })
        .apply(|d, od, a| d.select_mode(od, a.v.i8())),
];

/// A ratio's two `u32`s as the pair's values.
fn wide((x, y): (u32, u32)) -> (i64, i64) {
    (x.into(), y.into())
}
