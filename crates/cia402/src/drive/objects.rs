//! The CiA 402 objects the drive installs (CiA 402-2 §6 object
//! descriptions: types, access, PDO mapping) and the handles of the live
//! values it pushes every control period.

use super::config::DriveConfig;
use super::mode::op;
use alloc::format;
use drivebus_od::{Access, DataType as T, EntryRef, Object, ObjectCode, ObjectDictionary, SubObject, Value};

/// Sub-object flags: PDO-mappable, routed through the drive's hooks.
#[derive(Clone, Copy)]
struct F {
    map: bool,
    hook: bool,
}
const PLAIN: F = F { map: false, hook: false };
const HOOK: F = F { map: false, hook: true };
const MAP: F = F { map: true, hook: false };
const MAP_HOOK: F = F { map: true, hook: true };

fn sub(s: u8, name: &'static str, t: T, a: Access, v: Value, f: F) -> SubObject {
    let mut x = SubObject::new(s, name, t, a, v);
    x.pdo_mappable = f.map;
    x.hooked = f.hook;
    x
}

fn var(index: u16, name: &'static str, t: T, a: Access, v: Value, f: F) -> Object {
    Object::with_code(index, ObjectCode::Var, name).with_sub(sub(0, name, t, a, v, f))
}

/// An ARRAY whose entries have their own defaults.
fn array(index: u16, name: &'static str, t: T, a: Access, values: &[Value], f: F) -> Object {
    let mut o = Object::with_code(index, ObjectCode::Array, name).with_sub(SubObject::new(
        0,
        "Highest sub-index supported",
        T::Unsigned8,
        Access::Const,
        Value::U8(values.len() as u8),
    ));
    for (i, v) in values.iter().enumerate() {
        let mut s = SubObject::new(i as u8 + 1, format!("{name} {}", i + 1), t, a, v.clone());
        s.pdo_mappable = f.map;
        s.hooked = f.hook;
        o = o.with_sub(s);
    }
    o
}

fn record(index: u16, name: &'static str, subs: impl IntoIterator<Item = SubObject>) -> Object {
    subs.into_iter().fold(Object::record(index, name), Object::with_sub)
}

/// 60E3h supported homing methods, sub 1..n (CiA 402-2 homing mode).
pub(crate) fn supported_homing_methods(methods: &[i8]) -> Object {
    let values: alloc::vec::Vec<Value> = methods.iter().map(|&m| Value::I8(m)).collect();
    array(0x60E3, "Supported homing methods", T::Integer8, Access::Ro, &values, PLAIN)
}

/// Every object of the drive, with power-on values from `cfg`; `modes` is
/// 6502h.
pub(crate) fn objects(cfg: &DriveConfig, modes: u32) -> alloc::vec::Vec<Object> {
    use Access::{Ro, Rw, Rww};
    use Value::*;
    let p = &cfg.profile;
    let f = &cfg.factor;
    let o = &cfg.options;
    let m = &cfg.params.motor;
    let rated_torque_mnm = (m.kt * m.rated_current * 1000.0).clamp(1.0, 4e9) as u32;
    let rated_current_ma = (m.rated_current * 1000.0).clamp(1.0, 4e9) as u32;
    let max_torque = (m.max_current / m.rated_current * 1000.0).clamp(0.0, 65535.0) as u16;
    let max_motor_speed = p.max_profile_velocity;
    let pair = |v: (u32, u32)| [U32(v.0), U32(v.1)];
    let power_on_mode = if op::supported_bit(cfg.initial_mode) & modes != 0 { cfg.initial_mode } else { 0 };
    let dc_link_mv = (cfg.params.bus.nominal_voltage * 1000.0).clamp(0.0, 4e9) as u32;
    let mut v = alloc::vec![
        var(0x6007, "Abort connection option code", T::Integer16, Rw, I16(o.abort_connection()), HOOK),
        var(0x603F, "Error code", T::Unsigned16, Ro, U16(0), MAP),
        var(0x6040, "Controlword", T::Unsigned16, Rww, U16(0), MAP_HOOK),
        var(0x6041, "Statusword", T::Unsigned16, Ro, U16(0), MAP),
        var(0x605A, "Quick stop option code", T::Integer16, Rw, I16(o.quick_stop()), HOOK),
        var(0x605B, "Shutdown option code", T::Integer16, Rw, I16(o.shutdown()), HOOK),
        var(0x605C, "Disable operation option code", T::Integer16, Rw, I16(o.disable_operation()), HOOK),
        var(0x605D, "Halt option code", T::Integer16, Rw, I16(o.halt()), HOOK),
        var(0x605E, "Fault reaction option code", T::Integer16, Rw, I16(o.fault_reaction()), HOOK),
        var(0x6060, "Modes of operation", T::Integer8, Rww, I8(cfg.initial_mode), MAP_HOOK),
        // The display starts with the power-on mode the drive enters.
        var(0x6061, "Modes of operation display", T::Integer8, Ro, I8(power_on_mode), MAP),
        var(0x6062, "Position demand value", T::Integer32, Ro, I32(0), MAP),
        var(0x6063, "Position actual internal value", T::Integer32, Ro, I32(0), MAP),
        var(0x6064, "Position actual value", T::Integer32, Ro, I32(0), MAP),
        var(0x6065, "Following error window", T::Unsigned32, Rw, U32(p.following_error_window), MAP_HOOK),
        var(0x6066, "Following error time out", T::Unsigned16, Rw, U16(p.following_error_timeout), MAP_HOOK),
        var(0x6067, "Position window", T::Unsigned32, Rw, U32(p.position_window), MAP_HOOK),
        var(0x6068, "Position window time", T::Unsigned16, Rw, U16(p.position_window_time), MAP_HOOK),
        var(0x606B, "Velocity demand value", T::Integer32, Ro, I32(0), MAP),
        var(0x606C, "Velocity actual value", T::Integer32, Ro, I32(0), MAP),
        var(0x606D, "Velocity window", T::Unsigned16, Rw, U16(p.velocity_window), MAP_HOOK),
        var(0x606E, "Velocity window time", T::Unsigned16, Rw, U16(p.velocity_window_time), MAP_HOOK),
        var(0x606F, "Velocity threshold", T::Unsigned16, Rw, U16(p.velocity_threshold), MAP_HOOK),
        var(0x6070, "Velocity threshold time", T::Unsigned16, Rw, U16(p.velocity_threshold_time), MAP_HOOK),
        var(0x6071, "Target torque", T::Integer16, Rww, I16(0), MAP_HOOK),
        var(0x6072, "Max torque", T::Unsigned16, Rw, U16(max_torque), MAP_HOOK),
        var(0x6073, "Max current", T::Unsigned16, Rw, U16(max_torque), HOOK),
        var(0x6074, "Torque demand", T::Integer16, Ro, I16(0), MAP),
        var(0x6075, "Motor rated current", T::Unsigned32, Rw, U32(rated_current_ma), HOOK),
        var(0x6076, "Motor rated torque", T::Unsigned32, Rw, U32(rated_torque_mnm), HOOK),
        var(0x6077, "Torque actual value", T::Integer16, Ro, I16(0), MAP),
        var(0x6078, "Current actual value", T::Integer16, Ro, I16(0), MAP),
        // mV; the bus starts at its nominal voltage.
        var(0x6079, "DC link circuit voltage", T::Unsigned32, Ro, U32(dc_link_mv), MAP),
        var(0x607A, "Target position", T::Integer32, Rww, I32(0), MAP_HOOK),
        array(0x607B, "Position range limit", T::Integer32, Rw, &[I32(0), I32(0)], HOOK),
        var(0x607C, "Home offset", T::Integer32, Rw, I32(0), MAP_HOOK),
        array(0x607D, "Software position limit", T::Integer32, Rw, &[I32(0), I32(0)], HOOK),
        var(0x607E, "Polarity", T::Unsigned8, Rw, U8(f.polarity), HOOK),
        var(0x607F, "Max profile velocity", T::Unsigned32, Rw, U32(p.max_profile_velocity), MAP_HOOK),
        var(0x6080, "Max motor speed", T::Unsigned32, Rw, U32(max_motor_speed), MAP_HOOK),
        var(0x6081, "Profile velocity", T::Unsigned32, Rw, U32(p.profile_velocity), MAP_HOOK),
        var(0x6082, "End velocity", T::Unsigned32, Rw, U32(0), MAP_HOOK),
        var(0x6083, "Profile acceleration", T::Unsigned32, Rw, U32(p.profile_acceleration), MAP_HOOK),
        var(0x6084, "Profile deceleration", T::Unsigned32, Rw, U32(p.profile_deceleration), MAP_HOOK),
        var(0x6085, "Quick stop deceleration", T::Unsigned32, Rw, U32(p.quick_stop_deceleration), MAP_HOOK),
        var(0x6086, "Motion profile type", T::Integer16, Rw, I16(0), MAP_HOOK),
        var(0x6087, "Torque slope", T::Unsigned32, Rw, U32(p.torque_slope), MAP_HOOK),
        var(0x6088, "Torque profile type", T::Integer16, Rw, I16(0), MAP_HOOK),
        array(0x608F, "Position encoder resolution", T::Unsigned32, Ro, &pair(f.encoder), PLAIN),
        array(0x6090, "Velocity encoder resolution", T::Unsigned32, Ro, &pair(f.velocity_encoder), PLAIN),
        array(0x6091, "Gear ratio", T::Unsigned32, Rw, &pair(f.gear), HOOK),
        array(0x6092, "Feed constant", T::Unsigned32, Rw, &pair(f.feed), HOOK),
        array(0x6096, "Velocity factor", T::Unsigned32, Rw, &pair(f.velocity_factor), HOOK),
        array(0x6097, "Acceleration factor", T::Unsigned32, Rw, &pair(f.acceleration_factor), HOOK),
        // Homing (behaviour: crate::homing through a ModeHandler).
        var(0x6098, "Homing method", T::Integer8, Rw, I8(0), MAP_HOOK),
        array(
            0x6099,
            "Homing speeds",
            T::Unsigned32,
            Rw,
            &[U32(p.profile_velocity / 4), U32(p.profile_velocity / 40)],
            MAP_HOOK
        ),
        var(0x609A, "Homing acceleration", T::Unsigned32, Rw, U32(p.profile_acceleration), MAP_HOOK),
        var(0x60A8, "SI unit position", T::Unsigned32, Rw, U32(cfg.si_units[0]), PLAIN),
        var(0x60A9, "SI unit velocity", T::Unsigned32, Rw, U32(cfg.si_units[1]), PLAIN),
        var(0x60AA, "SI unit acceleration", T::Unsigned32, Rw, U32(cfg.si_units[2]), PLAIN),
        var(0x60AB, "SI unit jerk", T::Unsigned32, Rw, U32(cfg.si_units[3]), PLAIN),
        // Offsets and interpolation (behaviour: crate::interp).
        var(0x60B0, "Position offset", T::Integer32, Rww, I32(0), MAP_HOOK),
        var(0x60B1, "Velocity offset", T::Integer32, Rww, I32(0), MAP_HOOK),
        var(0x60B2, "Torque offset", T::Integer16, Rww, I16(0), MAP_HOOK),
        var(0x60B8, "Touch probe function", T::Unsigned16, Rww, U16(0), MAP_HOOK),
        var(0x60B9, "Touch probe status", T::Unsigned16, Ro, U16(0), MAP),
        var(0x60BA, "Touch probe 1 positive edge", T::Integer32, Ro, I32(0), MAP),
        var(0x60BB, "Touch probe 1 negative edge", T::Integer32, Ro, I32(0), MAP),
        var(0x60BC, "Touch probe 2 positive edge", T::Integer32, Ro, I32(0), MAP),
        var(0x60BD, "Touch probe 2 negative edge", T::Integer32, Ro, I32(0), MAP),
        var(0x60C0, "Interpolation sub mode select", T::Integer16, Rw, I16(0), MAP_HOOK),
        // Sub 1 position; subs 2 (velocity, PVT) and 3 (segment time in ms,
        // PT/PVT) for the manufacturer sub-modes of `IpMode`.
        array(0x60C1, "Interpolation data record", T::Integer32, Rww, &[I32(0), I32(0), I32(0)], MAP_HOOK),
        record(
            0x60C2,
            "Interpolation time period",
            [
                sub(1, "Interpolation time period value", T::Unsigned8, Rw, U8(1), MAP_HOOK),
                sub(2, "Interpolation time index", T::Integer8, Rw, I8(-3), MAP_HOOK),
            ]
        ),
        array(0x60C3, "Interpolation sync definition", T::Unsigned8, Rw, &[U8(0), U8(1)], PLAIN),
        record(
            0x60C4,
            "Interpolation data configuration",
            [
                sub(1, "Maximum buffer size", T::Unsigned32, Ro, U32(1), HOOK),
                sub(2, "Actual buffer size", T::Unsigned32, Rw, U32(1), HOOK),
                sub(3, "Buffer organization", T::Unsigned8, Rw, U8(0), HOOK),
                sub(4, "Buffer position", T::Unsigned16, Rw, U16(1), HOOK),
                sub(5, "Size of data record", T::Unsigned8, Rw, U8(4), HOOK),
                sub(6, "Buffer clear", T::Unsigned8, Rw, U8(0), HOOK),
            ]
        ),
        var(0x60C5, "Max acceleration", T::Unsigned32, Rw, U32(p.max_acceleration), MAP_HOOK),
        var(0x60C6, "Max deceleration", T::Unsigned32, Rw, U32(p.max_acceleration), MAP_HOOK),
        var(0x60F4, "Following error actual value", T::Integer32, Ro, I32(0), MAP),
        var(0x60FD, "Digital inputs", T::Unsigned32, Ro, U32(0), MAP),
        array(0x60FE, "Digital outputs", T::Unsigned32, Rww, &[U32(0), U32(cfg.io.output_mask)], MAP_HOOK),
        var(0x60FF, "Target velocity", T::Integer32, Rww, I32(0), MAP_HOOK),
        var(0x6502, "Supported drive modes", T::Unsigned32, Ro, U32(modes), PLAIN),
    ];
    if cfg.profile_jerk_object {
        // CiA 402-2 60A4h profile jerk (ARRAY, up to 6 entries): this drive
        // uses two, sub 1 while the speed rises, sub 2 while it falls.
        let (ja, jd) = cfg.profile_jerk_rates();
        v.push(array(0x60A4, "Profile jerk", T::Unsigned32, Rw, &[U32(ja), U32(jd)], MAP_HOOK));
    }
    if cfg.io.probe_source_object {
        // 60D0h touch probe source (ARRAY of INTEGER16), used with 60B8h
        // trigger selection 10b.
        v.push(array(0x60D0, "Touch probe source", T::Integer16, Rw, &[I16(1), I16(2)], HOOK));
    }
    if modes & op::supported_bit(op::HM) != 0 {
        // 60E3h: the standard methods (CiA 402-2 §6.7.x: 1–14, 17–30, 33–35, 37).
        // A handler with a registry replaces it (`refresh_handler_objects`).
        let methods: alloc::vec::Vec<i8> =
            (1..=37i8).filter(|m| !matches!(m, 15 | 16 | 31 | 32 | 36)).collect();
        v.push(supported_homing_methods(&methods));
    }
    if modes & op::supported_bit(op::VL) != 0 {
        // vl (CiA 402-2 §6.5): speeds in rpm of the motor shaft.
        let rpm = (m.max_speed * 60.0 / (2.0 * core::f64::consts::PI)).clamp(1.0, 32767.0) as u32;
        v.extend([
            var(0x6042, "vl target velocity", T::Integer16, Rww, I16(0), MAP_HOOK),
            var(0x6043, "vl velocity demand", T::Integer16, Ro, I16(0), MAP),
            var(0x6044, "vl velocity actual value", T::Integer16, Ro, I16(0), MAP),
            array(0x6046, "vl velocity min max amount", T::Unsigned32, Rw, &[U32(0), U32(rpm)], HOOK),
            record(
                0x6048,
                "vl velocity acceleration",
                [
                    sub(1, "Delta speed", T::Unsigned32, Rw, U32(rpm), HOOK),
                    sub(2, "Delta time", T::Unsigned16, Rw, U16(1), HOOK),
                ],
            ),
            record(
                0x6049,
                "vl velocity deceleration",
                [
                    sub(1, "Delta speed", T::Unsigned32, Rw, U32(rpm), HOOK),
                    sub(2, "Delta time", T::Unsigned16, Rw, U16(1), HOOK),
                ],
            ),
        ]);
    }
    v
}

/// Handles of the values the drive pushes every period; `None` where the
/// device does not have the object (`Drive::withdraw_object`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Refs {
    pub statusword: Option<EntryRef>,
    pub error_code: Option<EntryRef>,
    pub mode_display: Option<EntryRef>,
    pub pos_demand: Option<EntryRef>,
    pub pos_internal: Option<EntryRef>,
    pub pos_actual: Option<EntryRef>,
    pub vel_demand: Option<EntryRef>,
    pub vel_actual: Option<EntryRef>,
    pub torque_demand: Option<EntryRef>,
    pub torque_actual: Option<EntryRef>,
    pub current_actual: Option<EntryRef>,
    pub dc_link: Option<EntryRef>,
    pub following_error: Option<EntryRef>,
    pub inputs: Option<EntryRef>,
    pub probe_status: Option<EntryRef>,
    pub probe_pos: [Option<EntryRef>; 4],
    pub vl_demand: Option<EntryRef>,
    pub vl_actual: Option<EntryRef>,
    /// Number of objects when resolved: inserting an object moves handles.
    pub objects: usize,
}

impl Refs {
    /// Resolves every handle; `None` without a statusword (not a drive's
    /// dictionary).
    pub fn resolve(od: &ObjectDictionary) -> Option<Refs> {
        let f = |i: u16| od.find(i, 0).ok();
        Some(Refs {
            statusword: Some(f(0x6041)?),
            error_code: f(0x603F),
            mode_display: f(0x6061),
            pos_demand: f(0x6062),
            pos_internal: f(0x6063),
            pos_actual: f(0x6064),
            vel_demand: f(0x606B),
            vel_actual: f(0x606C),
            torque_demand: f(0x6074),
            torque_actual: f(0x6077),
            current_actual: f(0x6078),
            dc_link: f(0x6079),
            following_error: f(0x60F4),
            inputs: f(0x60FD),
            probe_status: f(0x60B9),
            probe_pos: [f(0x60BA), f(0x60BB), f(0x60BC), f(0x60BD)],
            vl_demand: f(0x6043),
            vl_actual: f(0x6044),
            objects: od.objects().len(),
        })
    }
}
