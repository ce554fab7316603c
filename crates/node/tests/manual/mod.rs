//! Shared pieces of the manual-trace replays (`manual_*.rs`): building a
//! drive-like node and replaying a printed frame sequence.
#![allow(dead_code)]

pub mod kollmorgen;

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

/// Give a communication parameter a drive's own default (value and reset
/// value), e.g. a PDO disabled by default.
pub fn default_u32(n: &mut Node, index: u16, sub: u8, v: u32) {
    default_raw(n, index, sub, &v.to_le_bytes());
}

/// As [`default_u32`], for any width (`data` is the little-endian value).
pub fn default_raw(n: &mut Node, index: u16, sub: u8, data: &[u8]) {
    let od = n.od_mut();
    od.get_mut(index, sub).expect("entry").default = data.to_vec();
    let e = od.find(index, sub).expect("entry");
    od.set_raw(e, data);
    let o = n.od().object(index).expect("object").clone();
    n.insert_object(o);
}

/// A drive's default mapping of one PDO (1600h.. / 1A00h..): entries as
/// printed in the manual (`0x6040_0010` = 6040h sub 0, 16 bits).
pub fn default_mapping(n: &mut Node, map: u16, entries: &[u32]) {
    let od = n.od_mut();
    for (i, e) in entries.iter().enumerate() {
        let sub = i as u8 + 1;
        od.get_mut(map, sub).expect("mapping entry").default = e.to_le_bytes().to_vec();
        od.set_value(map, sub, &Value::U32(*e)).expect("value");
    }
    let k = entries.len() as u8;
    od.get_mut(map, 0).expect("sub 0").default = vec![k];
    od.set_value(map, 0, &Value::U8(k)).expect("count");
    let o = n.od().object(map).expect("object").clone();
    n.insert_object(o);
}

/// The default mappings both Kollmorgen (KC1 §7.3.1.3/§7.3.2.3, AKD) and the
/// SSD 630 (§7) list: RPDO1..4 and TPDO1..4 built around 6040h / 6041h.
pub fn kollmorgen_default_mappings(n: &mut Node, rpdo4_second: u32) {
    default_mapping(n, 0x1600, &[0x6040_0010]);
    default_mapping(n, 0x1601, &[0x6040_0010, 0x6060_0008]);
    default_mapping(n, 0x1602, &[0x6040_0010, 0x607A_0020]);
    default_mapping(n, 0x1603, &[0x6040_0010, rpdo4_second]);
    default_mapping(n, 0x1A00, &[0x6041_0010]);
    default_mapping(n, 0x1A01, &[0x6041_0010, 0x6061_0008]);
    default_mapping(n, 0x1A02, &[0x6041_0010, 0x6064_0020]);
    default_mapping(n, 0x1A03, &[0x6041_0010, 0x606C_0020]);
}

/// The application objects the Kollmorgen KC1 / AKD examples read, write or
/// map, with the types, access and mappability of the seed000/seed001 tsv.
pub fn kollmorgen_objects(n: &mut Node) {
    use Access::{Ro, Rw, Wo};
    use DataType::{Integer8, Integer16, Integer32, Unsigned8, Unsigned16, Unsigned32, VisibleString};
    n.insert_object(pvar(0x1002, "Manufacturer status register", Unsigned32, Ro, Value::U32(0)));
    n.insert_object(record(
        0x2026,
        "ASCII channel",
        &[
            (VisibleString, Wo, false, Value::Str("    ".into())),
            (VisibleString, Ro, false, Value::Str("    ".into())),
        ],
    ));
    // §8.2.2.1: manufacturer dummy object used as a 4-byte placeholder.
    n.insert_object(pvar(0x2100, "Dummy mapping entry", Unsigned32, Rw, Value::U32(0)));
    n.insert_object(record(
        0x204C,
        "pv scaling factor",
        &[(Integer32, Rw, false, Value::I32(1)), (Integer32, Rw, false, Value::I32(1))],
    ));
    n.insert_object(pvar(0x6040, "Controlword", Unsigned16, Rw, Value::U16(0)));
    n.insert_object(pvar(0x6041, "Statusword", Unsigned16, Ro, Value::U16(0)));
    n.insert_object(pvar(0x6060, "Modes of operation", Integer8, Rw, Value::I8(0)));
    n.insert_object(pvar(0x6061, "Modes of operation display", Integer8, Ro, Value::I8(0)));
    n.insert_object(pvar(0x6063, "Position actual value (increments)", Integer32, Ro, Value::I32(0)));
    n.insert_object(pvar(0x6064, "Position actual value", Integer32, Ro, Value::I32(0)));
    n.insert_object(pvar(0x606C, "Velocity actual value", Integer32, Ro, Value::I32(0)));
    n.insert_object(pvar(0x6071, "Target torque", Integer16, Rw, Value::I16(0)));
    n.insert_object(pvar(0x6077, "Torque actual value", Integer16, Ro, Value::I16(0)));
    n.insert_object(pvar(0x607A, "Target position", Integer32, Rw, Value::I32(0)));
    n.insert_object(var(0x607C, "Reference offset", Integer32, Rw, Value::I32(0)));
    n.insert_object(pvar(0x6081, "Profile velocity", Unsigned32, Rw, Value::U32(10)));
    n.insert_object(pvar(0x6083, "Profile acceleration", Unsigned32, Rw, Value::U32(0)));
    n.insert_object(pvar(0x6084, "Profile deceleration", Unsigned32, Rw, Value::U32(0)));
    n.insert_object(record(
        0x608F,
        "Position encoder resolution",
        &[(Unsigned32, Rw, false, Value::U32(1 << 20)), (Unsigned32, Rw, false, Value::U32(1))],
    ));
    n.insert_object(record(
        0x6093,
        "Gearing factors",
        &[(Unsigned32, Rw, false, Value::U32(1)), (Unsigned32, Rw, false, Value::U32(1))],
    ));
    n.insert_object(var(0x6098, "Homing method", Integer8, Rw, Value::I8(0)));
    n.insert_object(record(
        0x6099,
        "Homing speeds",
        &[(Unsigned32, Rw, false, Value::U32(0)), (Unsigned32, Rw, false, Value::U32(0))],
    ));
    n.insert_object(var(0x609A, "Homing acceleration", Unsigned32, Rw, Value::U32(0)));
    n.insert_object(var(0x60C0, "Interpolation submode select", Integer16, Rw, Value::I16(0)));
    n.insert_object(record(
        0x60C1,
        "Interpolation data record",
        &[
            (Integer32, Rw, true, Value::I32(0)),
            (Unsigned32, Rw, true, Value::U32(0)),
            (Integer32, Rw, true, Value::I32(0)),
        ],
    ));
    // 60C2h sub 2: the manual's tables say INTEGER16, its §8.2.2.1 frame
    // writes one byte; CiA 402 defines the time index as INTEGER8.
    n.insert_object(record(
        0x60C2,
        "Interpolation time period",
        &[(Unsigned8, Rw, false, Value::U8(1)), (Integer8, Rw, false, Value::I8(-3))],
    ));
    n.insert_object(record(
        0x60C4,
        "Interpolation data configuration",
        &[
            (Unsigned32, Ro, false, Value::U32(10)),
            (Unsigned32, Ro, true, Value::U32(9)),
            (Unsigned8, Rw, false, Value::U8(0)),
            (Unsigned16, Rw, false, Value::U16(0)),
            (Unsigned8, Wo, false, Value::U8(1)),
            (Unsigned8, Wo, false, Value::U8(0)),
        ],
    ));
    n.insert_object(pvar(0x60FF, "Target velocity", Integer32, Rw, Value::I32(0)));
}

/// Put the values a printed drive frame carries into the dictionary before
/// the frame is due, as the drive's application would have: an expedited
/// SDO upload reply sets the object read, a TPDO sets its mapped objects.
/// Returns false for frames that carry no application value.
pub fn preset_from(r: &mut Rig, f: &drivebus_can::Frame) -> bool {
    let Some(id) = f.std_id() else { return false };
    let d = f.data().to_vec();
    let node_id = r.node().node_id() as u16;
    let od = r.node_mut().od_mut();
    if id == 0x580 + node_id {
        if d.len() == 8 && d[0] & 0xF3 == 0x43 {
            let n = 4 - ((d[0] >> 2) & 3) as usize;
            let (index, sub) = (u16::from_le_bytes([d[1], d[2]]), d[3]);
            let e = od.find(index, sub).expect("object of an upload reply");
            od.set_raw(e, &d[4..4 + n]);
            return true;
        }
        return false;
    }
    for n in 0..512u16 {
        let Some(cob) = od.get_u32(0x1800 + n, 1) else { break };
        if cob & 0x8000_0000 != 0 || cob & 0x7FF != u32::from(id) {
            continue;
        }
        let count = od.get_u64(0x1A00 + n, 0).unwrap_or(0) as u8;
        let mut at = 0;
        for i in 1..=count {
            let m = od.get_u32(0x1A00 + n, i).expect("mapping entry");
            let (index, sub, bytes) = ((m >> 16) as u16, (m >> 8) as u8, (m & 0xFF) as usize / 8);
            let e = od.find(index, sub).expect("mapped object");
            od.set_raw(e, &d[at..at + bytes]);
            at += bytes;
        }
        assert_eq!(at, d.len(), "TPDO {id:03X}: printed length differs from the mapping");
        return true;
    }
    false
}

/// Replay a printed bus trace in order. `>ID#DATA` goes into the device,
/// `<ID#DATA` is what it must send; an optional `T|` prefix gives the
/// frame's time in ms from the start of the trace (the device must stay
/// silent until then). A run of inputs must produce the outputs printed
/// after it, up to the first repeated COB-ID; later outputs of the same run
/// are spontaneous (the drive's own events) and are checked one by one. The
/// values such outputs carry (statusword, positions, upload replies) are
/// preset from the printed frames — the drive behaviour behind them is
/// CiA 402's, not under test here.
pub fn play(r: &mut Rig, trace: &[&str]) {
    use drivebus_can::{Duration, Frame};
    struct Line {
        input: bool,
        at_ns: Option<u64>,
        frame: Frame,
    }
    let lines: Vec<Line> = trace
        .iter()
        .map(|s| {
            let (at_ns, f) = match s.split_once('|') {
                Some((t, f)) => (Some((t.parse::<f64>().expect("time in ms") * 1e6).round() as u64), f),
                None => (None, *s),
            };
            Line { input: f.starts_with('>'), at_ns, frame: crate::common::fr(&f[1..]) }
        })
        .collect();
    let t0 = r.now();
    // Let simulated time reach a printed timestamp. With `quiet`, nothing may
    // have been sent meanwhile (inside a run of inputs, the answers to the
    // earlier inputs of the run are collected at its end instead).
    let wait = |r: &mut Rig, l: &Line, what: &str, quiet: bool| {
        if let Some(ns) = l.at_ns {
            let now = (r.now() - t0).as_nanos() as u64;
            if ns > now {
                r.run_for(Duration::from_nanos(ns - now - 1));
                if quiet {
                    assert_eq!(r.take(), Vec::<Frame>::new(), "unexpected frames before {what}");
                }
                r.run_for(Duration::from_nanos(1));
            }
        }
    };
    let mut i = 0;
    r.take();
    while i < lines.len() {
        let start = i;
        while i < lines.len() && lines[i].input {
            i += 1;
        }
        let out_start = i;
        while i < lines.len() && !lines[i].input {
            i += 1;
        }
        let outputs: Vec<Frame> = lines[out_start..i].iter().map(|l| l.frame).collect();
        // Outputs answered by the inputs: up to the first repeated COB-ID.
        let mut k = 0;
        while k < outputs.len() && !outputs[..k].iter().any(|o| o.id() == outputs[k].id()) {
            k += 1;
        }
        if start == out_start {
            k = 0;
        }
        for o in &outputs[..k] {
            preset_from(r, o);
        }
        for (j, l) in lines[start..out_start].iter().enumerate() {
            wait(r, l, trace[start + j], j == 0);
            r.bus.send_from(r.probe, l.frame);
            r.run_for(Duration::from_micros(1));
        }
        assert_eq!(r.take(), outputs[..k].to_vec(), "after inputs {:?}", &trace[start..out_start]);
        for (j, l) in lines[out_start + k..i].iter().enumerate() {
            let what = trace[out_start + k + j];
            wait(r, l, what, true);
            preset_from(r, &l.frame);
            r.bus.wake(r.dut);
            r.run_for(Duration::from_micros(1));
            assert_eq!(r.take(), vec![l.frame], "spontaneous frame {what}");
        }
    }
}

/// A LAM DDS6 (seed004 inventory) at node-ID `id`: device type 0044_0192h
/// (§6.3.1), vendor-ID 30Ch, product code 0060_4100h (DDS6041, §6.3.16),
/// 4+4 PDOs with 5 entries and the defaults of §6.3.19–6.3.22 (PDO1 valid,
/// PDO2..4 not, TPDO2/3 event timer 100 ms), the application objects its
/// chapter 4.4 examples use, with the types and defaults of the tsv.
pub fn dds6_node(id: u8) -> Node {
    use Access::{Ro, Rw};
    use DataType::{Integer8, Integer16, Integer32, Unsigned8, Unsigned16, Unsigned32};
    let ident = Identity { vendor_id: 0x30C, product_code: 0x0060_4100, revision: 0, serial: 0 };
    let mut cfg = drive_config(id, ident, "DDS6041");
    cfg.device_type = 0x0044_0192;
    cfg.pdo.max_entries = 5;
    let mut n = Node::new(cfg);
    n.insert_object(Object::record(0x2310, "Motor data").with_sub(SubObject::new(
        0x0B,
        "Max_Speed_MTRDT",
        Unsigned16,
        Rw,
        Value::U16(30000),
    )));
    n.insert_object(
        Object::record(0x2810, "Digital inputs action")
            .with_sub(SubObject::new(3, "Positive_Limit_DIA", Unsigned16, Rw, Value::U16(0x0207)))
            .with_sub(SubObject::new(4, "Negative_Limit_DIA", Unsigned16, Rw, Value::U16(0x0206)))
            .with_sub(SubObject::new(5, "Home_DIA", Unsigned16, Rw, Value::U16(0x0205))),
    );
    n.insert_object(pvar(0x6040, "Controlword", Unsigned16, Rw, Value::U16(0)));
    n.insert_object(pvar(0x6041, "Statusword", Unsigned16, Ro, Value::U16(0)));
    n.insert_object(pvar(0x6060, "Modes_of_Operation", Integer8, Rw, Value::I8(1)));
    n.insert_object(pvar(0x6061, "Modes_of_operation_display", Integer8, Ro, Value::I8(1)));
    n.insert_object(pvar(0x6064, "Position_actual_value", Integer32, Ro, Value::I32(0)));
    n.insert_object(pvar(0x606C, "Velocity_actual_value", Integer32, Ro, Value::I32(0)));
    n.insert_object(pvar(0x6071, "Target_Torque", Integer16, Rw, Value::I16(0)));
    n.insert_object(pvar(0x6077, "Torque_actual_value", Integer16, Ro, Value::I16(0)));
    n.insert_object(pvar(0x607A, "Target_position", Integer32, Rw, Value::I32(0)));
    n.insert_object(pvar(0x6081, "Profile_velocity", Unsigned32, Rw, Value::U32(600)));
    n.insert_object(pvar(0x6083, "Profile_acceleration", Unsigned32, Rw, Value::U32(100)));
    n.insert_object(pvar(0x6084, "Profile_deceleration", Unsigned32, Rw, Value::U32(300)));
    n.insert_object(pvar(0x6087, "Torque_slope", Unsigned32, Rw, Value::U32(0)));
    n.insert_object(pvar(0x6098, "Homing_method", Integer8, Rw, Value::I8(0)));
    n.insert_object(record(
        0x6099,
        "Homing speeds",
        &[(Unsigned32, Rw, true, Value::U32(600)), (Unsigned32, Rw, true, Value::U32(60))],
    ));
    n.insert_object(record(0x60C1, "Interpolation_data_record", &[(Integer32, Rw, true, Value::I32(0))]));
    n.insert_object(record(
        0x60C2,
        "Interpolation_time_period",
        &[(Unsigned8, Rw, true, Value::U8(1)), (Integer8, Rw, true, Value::I8(-3))],
    ));
    n.insert_object(pvar(0x60FF, "Target_velocity", Integer32, Rw, Value::I32(0)));
    default_mapping(&mut n, 0x1600, &[0x6040_0010]);
    default_mapping(&mut n, 0x1601, &[0x6040_0010, 0x607A_0020]);
    default_mapping(&mut n, 0x1602, &[0x6040_0010, 0x60FF_0020]);
    default_mapping(&mut n, 0x1603, &[0x607A_0020, 0x6081_0020]);
    default_mapping(&mut n, 0x1A00, &[0x6041_0010]);
    default_mapping(&mut n, 0x1A01, &[0x6041_0010, 0x6064_0020]);
    default_mapping(&mut n, 0x1A02, &[0x6041_0010, 0x606C_0020]);
    default_mapping(&mut n, 0x1A03, &[]);
    let id = u32::from(id);
    for (index, base) in [(0x1401, 0x300), (0x1402, 0x400), (0x1403, 0x500)] {
        default_u32(&mut n, index, 1, 0x8000_0000 | (base + id));
    }
    for (index, base) in [(0x1801, 0x280), (0x1802, 0x380), (0x1803, 0x480)] {
        default_u32(&mut n, index, 1, 0x8000_0000 | (base + id));
    }
    default_raw(&mut n, 0x1801, 5, &100u16.to_le_bytes());
    default_raw(&mut n, 0x1802, 5, &100u16.to_le_bytes());
    n
}
