//! Shared pieces of the manual-trace replays (`manual_*.rs`): building a
//! drive-like node and replaying a printed frame sequence.
#![allow(dead_code)]

use crate::common::Rig;
use drivebus_node::{Identity, Node, NodeConfig};
use drivebus_od::{Access, DataType, Object, SubObject, Value};

/// One printed step: a request into the device and the responses the
/// manual shows, in bus order (empty: the device stays silent).
pub type Step<'a> = (&'a str, &'a [&'a str]);

/// Replay `steps` exactly, in order.
pub fn replay(r: &mut Rig, steps: &[Step<'_>]) {
    for (req, resp) in steps {
        r.exchange(req, resp);
    }
}

/// A 402 drive's communication config: device type 0002_0192h, identity,
/// device name.
pub fn drive_config(node_id: u8, identity: Identity, name: &str) -> NodeConfig {
    let mut c = NodeConfig::new(node_id);
    c.device_type = 0x0002_0192;
    c.identity = identity;
    c.device_name = Some(name.into());
    c
}

/// A VAR application object.
pub fn var(index: u16, name: &'static str, dt: DataType, access: Access, default: Value) -> Object {
    Object::var(index, name, dt, access, default)
}

/// A PDO-mappable VAR application object.
pub fn pvar(index: u16, name: &'static str, dt: DataType, access: Access, default: Value) -> Object {
    let mut o = Object::var(index, name, dt, access, default);
    if let Some(s) = o.last_sub_mut() {
        s.pdo_mappable = true;
    }
    o
}

/// A RECORD whose subs 1.. are given as (type, access, mappable, default).
pub fn record(index: u16, name: &'static str, subs: &[(DataType, Access, bool, Value)]) -> Object {
    let mut o = Object::record(index, name);
    for (i, (dt, acc, map, def)) in subs.iter().enumerate() {
        let mut s = SubObject::new(i as u8 + 1, name, *dt, *acc, def.clone());
        s.pdo_mappable = *map;
        o = o.with_sub(s);
    }
    o
}

/// Set the value an object has at the time of the trace (what the drive's
/// application would have pushed).
pub fn set(r: &mut Rig, index: u16, sub: u8, v: Value) {
    r.node_mut().od_mut().set_value(index, sub, &v).expect("set_value");
}

/// Boot `node` on a fresh rig.
pub fn rig(node: Node) -> Rig {
    Rig::with_node(node)
}

/// Send an EMCY outside the CiA 301 error bookkeeping (a personality's own
/// register value) and let it go out.
pub fn raw_emcy(r: &mut Rig, code: u16, register: u8, bytes: [u8; 5]) {
    let now = r.now();
    r.node_mut().send_raw_emcy(code, register, bytes, now);
    r.bus.wake(r.dut);
    r.run_for(drivebus_can::Duration::from_nanos(1));
}
