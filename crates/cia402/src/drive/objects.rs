//! Installing the drive's objects ([`super::table`]), dispatching a write
//! to its entry by owner tag, reloading, and the handles of the live
//! values the drive pushes every control period.

use super::config::DriveConfig;
use super::table::PARAMS;
use super::{Drive, Units};
use alloc::format;
use alloc::vec::Vec;
use drivebus_od::{
    Access, DataType as T, EntryRef, Object, ObjectCode, ObjectDictionary, Owner, SdoAbort, SubObject,
    Target, Value, WriteOutcome, le_i64, le_u64,
};

/// Why an entry's apply runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum How {
    /// A write was checked (and stored, unless forwarded by a wrapper).
    Write,
    /// The node restored or loaded stored values behind the write path.
    Reload,
}

/// What an entry's check or apply is handed: which sub-object, its value,
/// and why the apply runs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Arg {
    pub index: u16,
    pub sub: u8,
    pub v: Raw,
    pub how: How,
}

/// A written or stored value, little-endian, up to 8 bytes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Raw {
    /// Zero-extended.
    pub u: u64,
    /// Sign-extended.
    pub s: i64,
    len: u8,
}

impl Raw {
    pub(crate) fn of(b: &[u8]) -> Raw {
        Raw { u: le_u64(b), s: le_i64(b), len: b.len().min(8) as u8 }
    }
    pub(crate) fn u32(self) -> u32 {
        self.u as u32
    }
    pub(crate) fn u16(self) -> u16 {
        self.u as u16
    }
    pub(crate) fn u8(self) -> u8 {
        self.u as u8
    }
    pub(crate) fn i32(self) -> i32 {
        self.s as i32
    }
    pub(crate) fn i16(self) -> i16 {
        self.s as i16
    }
    pub(crate) fn i8(self) -> i8 {
        self.s as i8
    }
    /// The bytes as written.
    pub(crate) fn bytes(self) -> [u8; 8] {
        self.u.to_le_bytes()
    }
    pub(crate) fn len(self) -> usize {
        usize::from(self.len)
    }
}

/// Inclusive range check with the CiA 301 abort for each side.
pub(crate) fn range(v: i64, lo: i64, hi: i64) -> Result<(), SdoAbort> {
    if v < lo {
        Err(SdoAbort::VALUE_TOO_LOW)
    } else if v > hi {
        Err(SdoAbort::VALUE_TOO_HIGH)
    } else {
        Ok(())
    }
}

/// Sub 1 and sub 2 of a 2-entry array or record as u32s (1 when absent).
pub(crate) fn pair_of(od: &ObjectDictionary, index: u16) -> (u32, u32) {
    (od.get_u32(index, 1).unwrap_or(1), od.get_u32(index, 2).unwrap_or(1))
}

pub(crate) fn sub(s: u8, name: &'static str, t: T, a: Access, v: Value, map: bool) -> SubObject {
    let mut x = SubObject::new(s, name, t, a, v);
    x.pdo_mappable = map;
    x
}

pub(crate) fn var(index: u16, name: &'static str, t: T, a: Access, v: Value, map: bool) -> Object {
    Object::with_code(index, ObjectCode::Var, name).with_sub(sub(0, name, t, a, v, map))
}

/// An ARRAY whose entries have their own defaults.
pub(crate) fn array(index: u16, name: &'static str, t: T, a: Access, values: &[Value], map: bool) -> Object {
    let mut o = Object::with_code(index, ObjectCode::Array, name).with_sub(SubObject::new(
        0,
        "Highest sub-index supported",
        T::Unsigned8,
        Access::Const,
        Value::U8(values.len() as u8),
    ));
    for (i, v) in values.iter().enumerate() {
        let mut s = SubObject::new(i as u8 + 1, format!("{name} {}", i + 1), t, a, v.clone());
        s.pdo_mappable = map;
        o = o.with_sub(s);
    }
    o
}

pub(crate) fn record(index: u16, name: &'static str, subs: impl IntoIterator<Item = SubObject>) -> Object {
    subs.into_iter().fold(Object::record(index, name), Object::with_sub)
}

/// 60E3h supported homing methods, sub 1..n (CiA 402-2 homing mode).
pub(crate) fn supported_homing_methods(methods: &[i8]) -> Object {
    let values: Vec<Value> = methods.iter().map(|&m| Value::I8(m)).collect();
    array(0x60E3, "Supported homing methods", T::Integer8, Access::Ro, &values, false)
}

/// The table entry a drive tag names.
fn param_of(owner: Owner) -> Option<(usize, &'static super::table::Param)> {
    let k = usize::from(owner.app_tag()?);
    PARAMS.get(k).map(|p| (k, p))
}

/// The table entry of an index.
fn param_at(index: u16) -> Option<&'static super::table::Param> {
    PARAMS.iter().find(|p| p.index == index)
}

/// Every object of the drive with power-on values from `cfg` (`modes` is
/// 6502h), its writable sub-objects owned by their table entry.
pub(crate) fn objects(cfg: &DriveConfig, modes: u32) -> Vec<Object> {
    let mut v = Vec::with_capacity(PARAMS.len());
    for (k, p) in PARAMS.iter().enumerate() {
        let Some(mut o) = p.object(cfg, modes) else { continue };
        if p.owned() {
            let tag = Owner::app(k as u8);
            for s in o.subs_mut() {
                if s.access.writable() {
                    s.owner = tag;
                }
                if p.live && s.sub != 0 {
                    s.owner = tag;
                    s.live = true;
                }
            }
        }
        v.push(o);
    }
    v
}

impl Drive {
    /// Step 5 of the write path for one of the drive's objects: its
    /// entry's check. Another application's tag is not the drive's: stored.
    pub fn check_object(
        &mut self,
        od: &mut ObjectDictionary,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        match param_of(at.owner) {
            Some((_, p)) if p.index == at.index => match p.check {
                Some(check) => {
                    check(self, od, Arg { index: at.index, sub: at.sub, v: Raw::of(data), how: How::Write })
                }
                None => Ok(WriteOutcome::Store),
            },
            _ => Ok(WriteOutcome::Store),
        }
    }

    /// Step 7: the stored value taken by the object's entry.
    pub fn apply_object(&mut self, od: &mut ObjectDictionary, at: &Target) {
        if let Some((_, p)) = param_of(at.owner)
            && p.index == at.index
            && let Some(apply) = p.apply
        {
            let v = Raw::of(od.bytes(at.r));
            apply(self, od, Arg { index: at.index, sub: at.sub, v, how: How::Write });
        }
    }

    /// Before a read of a live object: the handlers' present values (60C4h).
    pub fn refresh_object(&mut self, od: &mut ObjectDictionary, at: &Target) {
        self.read_handler_object(od, at.index, at.sub);
    }

    /// A write forwarded by a wrapping application (a personality that
    /// translated it): the object's check, then its apply, by index. Nothing
    /// is stored; the caller stores what it wants. `Ok(Handled)`: the check
    /// applied it.
    pub fn on_write(
        &mut self,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let Some(p) = param_at(index) else { return Ok(WriteOutcome::Store) };
        let a = Arg { index, sub, v: Raw::of(data), how: How::Write };
        let outcome = match p.check {
            Some(check) => check(self, od, a)?,
            None => WriteOutcome::Store,
        };
        if outcome == WriteOutcome::Store {
            if let Some(apply) = p.apply {
                apply(self, od, a);
            }
            // A withdrawn object's value lives with the drive.
            if let Ok(e) = self.withdrawn.find(index, sub) {
                self.withdrawn.set_le(e, data);
            }
        }
        Ok(outcome)
    }

    /// Before a read by index (a wrapping application's own read path).
    pub fn on_read(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) {
        self.read_handler_object(od, index, sub);
    }

    /// Takes every stored parameter (after install, and after the node
    /// restored or loaded values behind the write path), entry by entry in
    /// table order, then derives the units and re-resolves the handles. A
    /// withdrawn object's values are the drive's own (`withdraw_object`).
    pub(crate) fn reload(&mut self, od: &mut ObjectDictionary) {
        for p in PARAMS {
            let Some(apply) = p.apply else { continue };
            let src = if self.withdrawn.object(p.index).is_some() { &self.withdrawn } else { &*od };
            let Some(o) = src.object(p.index) else { continue };
            let vals: Vec<(u8, Raw)> = o
                .subs()
                .iter()
                .filter(|s| s.access.writable())
                .map(|s| (s.sub, Raw::of(s.bytes())))
                .collect();
            for (s, v) in vals {
                apply(self, od, Arg { index: p.index, sub: s, v, how: How::Reload });
            }
        }
        // Configuration, not an object.
        self.params.homing_return_to_home = self.cfg.homing_return_to_home;
        if let Some(units) = Units::new(&self.factor) {
            self.units = units;
        }
        self.refs = Refs::resolve(od);
    }

    /// Shows the handlers' present values of the objects they own (60C4h)
    /// in the dictionary (before an SDO upload, after install).
    pub(crate) fn read_handler_object(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) {
        if index != 0x60C4 {
            return;
        }
        let Some(v) = self.handlers.iter().find_map(|h| h.read_object(index, sub)) else { return };
        if let Ok(r) = od.find(index, sub) {
            let n = od.bytes(r).len().min(8);
            od.set_le(r, &v.to_le_bytes()[..n]);
        }
    }

    /// After install or a new handler: 60C4h from the ip handler, 60E3h
    /// from the hm handler's method registry.
    pub(crate) fn refresh_handler_objects(&mut self, od: &mut ObjectDictionary) {
        for sub in 1..=6 {
            self.read_handler_object(od, 0x60C4, sub);
            // The handler's state now is the power-on value (1011h restores it).
            if let Some(s) = od.get_mut(0x60C4, sub) {
                s.default = s.bytes().to_vec();
            }
        }
        // Replaced in place only: inserting a new object would move the
        // handles the node's PDO service holds (a handler added after
        // install without hm at install keeps no 60E3h).
        let present = od.object(0x60E3).is_some();
        if let Some(methods) = self.handlers.iter().find_map(|h| h.homing_methods())
            && present
        {
            od.insert(supported_homing_methods(&methods));
            self.refs = Refs::resolve(od);
        }
    }

    /// Re-derives the unit conversions after a factor group write (checked
    /// exact by the entry), keeping the position where it is.
    pub(crate) fn retune_units(&mut self) {
        let Some(u) = Units::new(&self.factor) else { return };
        // The demand is in user units: keep it at the same increments.
        let inc = self.units.pos_to_inc_f(self.dem.pos);
        // The reference shift's fraction, over the new denominator.
        let frac = self.units.frac_to_inc_f(self.inc_frac) * u.position_ratio().den as f64;
        self.inc_frac = (libm::floor(frac) as i128).clamp(0, u.position_ratio().den as i128 - 1);
        self.units = u;
        self.dem.pos = self.units.inc_to_pos_f(inc);
        self.dem.vel = 0.0;
        self.pp.reset(self.dem.pos);
    }
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
