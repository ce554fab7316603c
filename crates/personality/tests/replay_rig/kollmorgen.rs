//! The test bodies the Kollmorgen KC1 (seed000, `replay_kc1.rs`) and AKD
//! (seed001, `replay_akd.rs`) replays share: the two manuals print the same
//! examples (KC1 chapter 8 = AKD chapter 7), the AKD edition with other line
//! numbers and section numbers. Each function takes the trace and the frame
//! keys that differ; section citations stay in the callers' comments.

use super::trace::{Line, Trace, every_2nd_and_3rd};
use super::{Rig, assert_form, frs, replay};
use drivebus_can::Frame;
use drivebus_od::Value;
use drivebus_personality::{PersonalityDevice, Profile};

/// `profile` as node `id`, booted: the only power-on frame is the boot-up
/// message (KC1 §8.2.1.7 frame 1, AKD §7.2.1.7: `703 00` for node 3).
pub fn booted(profile: Profile, id: u8) -> Rig {
    let (r, boot) = Rig::new(profile, id);
    assert_eq!(boot, frs(&[&format!("{:03X}#00", 0x700 + u16::from(id))]), "boot-up");
    r
}

/// A node built for a test (machine or behaviour of its own) as node `id`,
/// booted: boot-up message only.
pub fn booted_with(pn: PersonalityDevice, id: u8) -> Rig {
    let (r, boot) = Rig::with(pn);
    assert_eq!(boot, frs(&[&format!("{:03X}#00", 0x700 + u16::from(id))]));
    r
}

/// A dictionary value of the node under test.
pub fn value(r: &Rig, index: u16, sub: u8) -> Option<Value> {
    r.node().od().get_value(index, sub)
}

/// KC1 example 3 / AKD section 3 (the same frames): statusword, shutdown
/// and switch on by SDO, the statusword read again after 1 ms.
pub fn state_machine_by_sdo(r: &mut Rig, t: &Trace) {
    replay(r, &t.steps(1, 6));
    r.run_ms(1);
    replay(r, &t.steps(7, 8));
}

/// KC1 example 4 / AKD section 4, frames 1–12: jog by SDO; after 500 ms
/// the axis turns at the set-point 4100h within 5 %.
pub fn jog_by_sdo_start(r: &mut Rig, t: &Trace) {
    replay(r, &t.steps(1, 12));
    r.run_ms(500);
    let v = r.velocity();
    assert!((v - 0x4100).abs() < 0x4100 / 20, "jog velocity {v}");
}

/// Frames 13–14 of the same example: halt; the axis stands after 500 ms.
pub fn jog_by_sdo_halt(r: &mut Rig, t: &Trace) {
    replay(r, &t.steps(13, 14));
    r.run_ms(500);
    assert_eq!(r.velocity(), 0, "halted");
}

/// KC1 example 5 / AKD section 5, frames 1–12: torque by SDO; after 20 ms
/// the unloaded axis has accelerated.
pub fn torque_by_sdo_start(r: &mut Rig, t: &Trace) {
    replay(r, &t.steps(1, 12));
    r.run_ms(20);
    assert!(r.velocity() > 0, "torque accelerates the axis");
}

/// Let `ms` pass, drop what went out, send the SYNC `sync`: the frames it
/// brings.
pub fn after_sync(r: &mut Rig, ms: u64, sync: &str) -> Vec<Frame> {
    r.run_ms(ms);
    r.take();
    r.send(sync);
    r.take()
}

/// Jog by PDO: TPDO1 (6064h + 606Ch) in the form of the printed `l`,
/// carrying this axis' motion after 1 s at 4000h: velocity within 5 %,
/// position between 0.8 and 1 s of it.
pub fn assert_jog_tpdo1(f: &Frame, l: Line) {
    assert_form(f, l);
    let d = f.data();
    let pos = i32::from_le_bytes([d[0], d[1], d[2], d[3]]);
    let vel = i32::from_le_bytes([d[4], d[5], d[6], d[7]]);
    assert!((vel - 0x4000).abs() < 0x4000 / 20, "velocity {vel}");
    assert!(pos > 0x4000 * 8 / 10 && pos < 0x4000, "position {pos}");
}

/// Torque by PDO: TPDO1 (6077h) in the form of the printed `l`, the torque
/// actual within 5 % of `demand`.
pub fn assert_torque_tpdo1(f: &Frame, l: Line, demand: i32) {
    assert_form(f, l);
    let tq = i16::from_le_bytes([f.data()[0], f.data()[1]]);
    assert!((i32::from(tq) - demand).abs() < demand / 20, "torque actual {tq}");
}

/// Profile position (KC1 example 9 / AKD section 9) up to homing: the PDO
/// set-up `setup`, NMT start with the event-driven TPDO1 `nmt`, the SDO
/// downloads incl. the 6099h:1 abort `sdo`, and the state machine `states`,
/// each step answered by TPDO1 within 1 ms.
pub fn pp_setup(
    r: &mut Rig,
    t: &Trace,
    setup: (u32, u32),
    nmt: (u32, u32),
    sdo: (u32, u32),
    states: (u32, u32),
) {
    replay(r, &t.steps(setup.0, setup.1));
    replay(r, &t.steps(nmt.0, nmt.1));
    replay(r, &t.steps(sdo.0, sdo.1));
    for (req, resp) in t.steps(states.0, states.1) {
        r.exchange_ms(req, 1, resp);
    }
}

/// Profile position, homing: `start` (method 12 on the machine's home
/// switch) answered by `start + 1`; after 20 s the TPDO1 statuswords on 183h
/// end in 1637h (homing attained); the printed `start + 2` (0637h) is
/// `form`.
pub fn pp_homing(r: &mut Rig, t: &Trace, start: u32) {
    r.exchange(t.frame(start), &[t.frame(start + 1)]);
    r.run_ms(20_000);
    let sws: Vec<u16> = r
        .take()
        .into_iter()
        .filter(|f| f.std_id() == Some(0x183))
        .map(|f| u16::from_le_bytes([f.data()[0], f.data()[1]]))
        .collect();
    assert!(t.line(start + 2).form());
    assert_eq!(sws.last(), Some(&0x1637), "homing attained: {sws:04X?}");
}

/// Profile position, parameters: the controlword `cw` by RPDO1 (bit 4
/// cleared), the SDO downloads `sdo`, then RPDO2 `rpdo2`: target 36000
/// (8CA0h), profile velocity 20000 (4E20h).
pub fn pp_parameters(r: &mut Rig, t: &Trace, cw: u32, sdo: (u32, u32), rpdo2: u32) {
    r.send(t.frame(cw));
    r.run_ms(1);
    r.take();
    replay(r, &t.steps(sdo.0, sdo.1));
    r.run_ms(1);
    r.take();
    replay(r, &t.steps(rpdo2, rpdo2));
    assert_eq!(value(r, 0x607A, 0), Some(Value::I32(36_000)));
    assert_eq!(value(r, 0x6081, 0), Some(Value::U32(20_000)));
}

/// Profile position, the move: the set-point handshake by RPDO1 (`new_sp`
/// → `ack`, `cw` → `sw`), then 60 s for the move (6083h/6084h = 50 taken as
/// acceleration units: ≈ 54 s for 36000 units). Returns what went out.
pub fn pp_move(r: &mut Rig, t: &Trace, (new_sp, ack): (u32, u32), (cw, sw): (u32, u32)) -> Vec<Frame> {
    r.exchange_ms(t.frame(new_sp), 1, &[t.frame(ack)]);
    r.exchange_ms(t.frame(cw), 1, &[t.frame(sw)]);
    r.run_ms(60_000);
    r.take()
}

/// Profile position, the last SYNC `sync`: TPDO2 in the form of `tpdo2`,
/// the position at the target 36000 (8CA0h) within 2.
pub fn pp_final_position(r: &mut Rig, t: &Trace, sync: u32, tpdo2: u32) {
    r.send(t.frame(sync));
    let f = r.take();
    assert_form(&f[0], t.line(tpdo2));
    let pos = i32::from_le_bytes([f[0].data()[0], f[0].data()[1], f[0].data()[2], f[0].data()[3]]);
    assert!((pos - 36_000).abs() <= 2, "position {pos}");
}

/// KC1 example 11 / AKD section 11: after the set-up `setup`, NMT start
/// (not printed; PDOs need it, TPDO3/4 go out on entering operational),
/// then the SYNC `sync` and the pattern of its comment on 183h/283h: axis
/// at rest, position 0, statusword 0240h, 1002h 0.
pub fn sync_every_nth(r: &mut Rig, t: &Trace, setup: (u32, u32), sync: u32) {
    replay(r, &t.steps(setup.0, setup.1));
    r.send("000#01 03");
    r.run_ms(1);
    r.take();
    let sync = t.frame(sync);
    let tpdo1 = "183#00 00 00 00";
    let tpdo2 = "283#40 02 00 00 00 00";
    for (sync, tpdos) in every_2nd_and_3rd(sync, tpdo1, tpdo2) {
        r.exchange(sync, &tpdos);
    }
}

/// A drive fault 4310h on node 1: the Kollmorgen EMCY `emcy` (register 08h
/// without the generic bit, category 01h) within 1 ms.
pub fn emcy_fault(r: &mut Rig, emcy: &str) {
    r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Fault(0x4310));
    r.run_ms(1);
    assert_eq!(r.take(), frs(&[emcy]));
}

/// Fault reset (controlword bit 7) on node 1: the SDO confirmation and the
/// error-reset EMCY, register 00h (no error left).
pub fn emcy_reset(r: &mut Rig) {
    r.exchange_ms(
        "601#2B 40 60 00 80 00 00 00",
        1,
        &["581#60 40 60 00 00 00 00 00", "081#00 00 00 00 00 00 00 00"],
    );
}

/// KC1 example 12 / AKD section 13, axis 1 (node 1) up to the set-points:
/// the set-up `setup` (requests to 601h), NMT start `nmt` with the
/// event-driven TPDO1 (0240h, not printed there), the state machine
/// `states` by RPDO1, each answered by TPDO1 within 1 ms.
pub fn ip_axis1_start(r: &mut Rig, t: &Trace, setup: (u32, u32), nmt: u32, states: (u32, u32)) {
    replay(r, &t.steps_on(setup.0, setup.1, "601"));
    r.exchange(t.frame(nmt), &["181#40 02"]);
    for (req, resp) in t.steps(states.0, states.1) {
        r.exchange_ms(req, 1, resp);
    }
}

/// Axis 1 follows: the set-point RPDO2 `rpdo2` and the SYNC `sync` every
/// 1 ms for 200 ms; 100 ms later the axis is at 500 within 2.
pub fn ip_axis1_follows(r: &mut Rig, t: &Trace, rpdo2: u32, sync: u32) {
    for _ in 0..200 {
        r.run_ms(1);
        r.send(t.frame(rpdo2));
        r.send(t.frame(sync));
    }
    r.run_ms(100);
    let p = r.position();
    assert!((p - 500).abs() <= 2, "ip position {p}");
}
