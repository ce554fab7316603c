//! Shared fixtures: an object dictionary with CiA 402-like objects and a
//! node-like SDO write path (check, store, reconfigure).
#![allow(dead_code, missing_docs)]

use drivebus_can::{Frame, Instant};
use drivebus_od::{
    Access, DataType, NoHooks, Object, ObjectDictionary, ObjectHooks, SdoAbort, SubObject, Target, Value,
    WriteOutcome,
};
use drivebus_pdo::{Pdo, PdoConfig, classify, install};

pub fn var(index: u16, dt: DataType, access: Access, v: Value) -> Object {
    let name = "obj";
    Object::var(index, name, dt, access, v.clone())
        .with_sub(SubObject::new(0, name, dt, access, v).mappable())
}

/// Application objects used by the tests (and the seed examples).
pub fn app_od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    od.insert(Object::var(0x1000, "Device type", DataType::Unsigned32, Access::Ro, Value::U32(0x0002_0192)));
    od.insert(var(0x1002, DataType::Unsigned32, Access::Ro, Value::U32(0)));
    od.insert(var(0x2100, DataType::Unsigned32, Access::Rw, Value::U32(0)));
    od.insert(var(0x6040, DataType::Unsigned16, Access::Rww, Value::U16(0)));
    od.insert(var(0x6041, DataType::Unsigned16, Access::Ro, Value::U16(0)));
    od.insert(var(0x6064, DataType::Integer32, Access::Ro, Value::I32(0)));
    od.insert(var(0x606C, DataType::Integer32, Access::Ro, Value::I32(0)));
    od.insert(var(0x6071, DataType::Integer16, Access::Rww, Value::I16(0)));
    od.insert(var(0x6077, DataType::Integer16, Access::Ro, Value::I16(0)));
    od.insert(var(0x607A, DataType::Integer32, Access::Rww, Value::I32(0)));
    od.insert(var(0x60FF, DataType::Integer32, Access::Rww, Value::I32(0)));
    od.insert(
        Object::record(0x2000, "Test record")
            .with_sub(SubObject::new(1, "b1", DataType::Boolean, Access::Rw, Value::Bool(false)).mappable())
            .with_sub(SubObject::new(2, "b2", DataType::Boolean, Access::Rw, Value::Bool(false)).mappable())
            .with_sub(SubObject::new(3, "u8", DataType::Unsigned8, Access::Rw, Value::U8(0)).mappable())
            .with_sub(SubObject::new(4, "u16", DataType::Unsigned16, Access::Rw, Value::U16(0)).mappable())
            .with_sub(SubObject::new(5, "u64", DataType::Unsigned64, Access::Rw, Value::U64(0)).mappable())
            .with_sub(
                SubObject::new(6, "str", DataType::VisibleString, Access::Rw, Value::Str("x".into()))
                    .mappable(),
            )
            .with_sub(SubObject::new(7, "not mappable", DataType::Unsigned8, Access::Rw, Value::U8(0)))
            .with_sub(
                SubObject::new(8, "hooked", DataType::Unsigned16, Access::Rw, Value::U16(0))
                    .mappable()
                    .hooked(),
            )
            .with_sub(
                SubObject::new(9, "limited", DataType::Unsigned8, Access::Rw, Value::U8(0))
                    .limits(Value::U8(0), Value::U8(100))
                    .mappable(),
            )
            .with_sub(SubObject::new(10, "u32", DataType::Unsigned32, Access::Rw, Value::U32(0)).mappable()),
    );
    od
}

pub fn setup(cfg: &PdoConfig) -> (ObjectDictionary, Pdo) {
    let mut od = app_od();
    install(&mut od, cfg);
    let pdo = Pdo::new(cfg, &od);
    (od, pdo)
}

/// What the node does for a hooked PDO object: check, store, reconfigure.
pub struct NodeHooks<'a> {
    pub pdo: &'a mut Pdo,
}

impl ObjectHooks for NodeHooks<'_> {
    fn check_write(
        &mut self,
        od: &mut ObjectDictionary,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        if classify(self.pdo.config(), at.index).is_some() {
            self.pdo.check_write(od, at.index, at.sub, data)?;
        }
        Ok(WriteOutcome::Store)
    }
    fn apply_write(&mut self, od: &mut ObjectDictionary, at: &Target) {
        if classify(self.pdo.config(), at.index).is_some() {
            self.pdo.reconfigure(od, at.index, at.sub);
        }
    }
}

/// An SDO download as the node performs it.
pub fn sdo(
    od: &mut ObjectDictionary,
    pdo: &mut Pdo,
    index: u16,
    sub: u8,
    data: &[u8],
) -> Result<(), SdoAbort> {
    od.write(&mut NodeHooks { pdo }, index, sub, data)
}

pub fn sdo32(od: &mut ObjectDictionary, pdo: &mut Pdo, index: u16, sub: u8, v: u32) -> Result<(), SdoAbort> {
    sdo(od, pdo, index, sub, &v.to_le_bytes())
}
pub fn sdo16(od: &mut ObjectDictionary, pdo: &mut Pdo, index: u16, sub: u8, v: u16) -> Result<(), SdoAbort> {
    sdo(od, pdo, index, sub, &v.to_le_bytes())
}
pub fn sdo8(od: &mut ObjectDictionary, pdo: &mut Pdo, index: u16, sub: u8, v: u8) -> Result<(), SdoAbort> {
    sdo(od, pdo, index, sub, &[v])
}

/// The CiA 301 mapping procedure: invalidate, sub 0 = 0, entries, sub 0 = n,
/// set the transmission type, validate with `cob`.
pub fn remap(od: &mut ObjectDictionary, pdo: &mut Pdo, comm: u16, cob: u32, tt: u8, entries: &[u32]) {
    let map = comm + 0x200;
    sdo32(od, pdo, comm, 1, cob | 0x8000_0000).unwrap();
    sdo8(od, pdo, map, 0, 0).unwrap();
    for (i, &e) in entries.iter().enumerate() {
        sdo32(od, pdo, map, i as u8 + 1, e).unwrap();
    }
    sdo8(od, pdo, map, 0, entries.len() as u8).unwrap();
    sdo8(od, pdo, comm, 2, tt).unwrap();
    sdo32(od, pdo, comm, 1, cob).unwrap();
}

pub fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}
pub fn us(v: u64) -> Instant {
    Instant::from_micros(v)
}

pub fn set(od: &mut ObjectDictionary, index: u16, sub: u8, v: Value) {
    od.set_value(index, sub, &v).unwrap();
}

pub fn rx(
    pdo: &mut Pdo,
    od: &mut ObjectDictionary,
    f: Frame,
    now: Instant,
) -> (drivebus_pdo::PdoRx, Vec<Frame>) {
    let mut out = Vec::new();
    let r = pdo.handle_frame(&f, now, od, &mut NoHooks, &mut out);
    (r, out)
}

pub fn sync(pdo: &mut Pdo, od: &mut ObjectDictionary, counter: Option<u8>, now: Instant) -> Vec<Frame> {
    let mut out = Vec::new();
    pdo.on_sync(counter, now, od, &mut NoHooks, &mut out);
    out
}

pub fn poll(pdo: &mut Pdo, od: &mut ObjectDictionary, now: Instant) -> (Vec<Frame>, Option<Instant>) {
    let mut out = Vec::new();
    let d = pdo.poll(now, od, &mut NoHooks, &mut out);
    (out, d)
}

pub fn events(pdo: &mut Pdo) -> Vec<drivebus_pdo::PdoEvent> {
    std::iter::from_fn(|| pdo.pop_event()).collect()
}
