//! Replays of the Kollmorgen AKD CANopen manual (seed001, edition R
//! 09/2016) against the real personality: `Profile::Akd.build(node)` — EDS
//! dictionary, CiA 402 drive, AKD behaviour — on the virtual bus. Sections
//! follow `seed001-akd-examples.md` (manual §6.3, §7.2.1.x, §7.2.2.1).
//!
//! Ported from `crates/node/tests/manual_akd.rs` (hand-configured node,
//! values preset): here nothing is preset; statuswords, TPDOs and motion are
//! the drive's. The AKD examples invalidate a PDO before remapping it, so
//! the CiA 301 §7.5.2.36 procedure is replayed as printed. The printed
//! frames (with the typo corrections) are read from
//! `crates/personality/traces/akd_s*.txt` — sections 1, 3, 4, 5 and 10 from
//! the byte-identical KC1 files `kc1_ex*.txt` (frame numbers there) — shared
//! with the CiA 301 replays; frames marked `form` are checked in form
//! (COB-ID, length).

mod replay_rig;

use drivebus_node::MemoryStorage;
use drivebus_od::Value;
use drivebus_personality::{Profile, build_on_machine};
use replay_rig::kollmorgen::*;
use replay_rig::trace::akd as trace;
use replay_rig::*;

/// An AKD as node `id`, booted: the only power-on frame is the boot-up
/// message (§7.2.1.7: `703 00`).
fn akd(id: u8) -> Rig {
    booted(Profile::Akd, id)
}

fn node() -> Rig {
    akd(3)
}

/// §0: the store / restore signatures of §6.2.1.12/13 as SDO frames (derived
/// in the examples file from the printed payloads), and the 1000h value.
#[test]
fn akd_s0_store_restore_and_device_type() {
    let mut r = akd(1);
    replay(&mut r, &trace(0).steps(1, 4));
}

/// §6.3 (section 1): free mapping of TPDO1, node 1 — requests only in print;
/// the confirmations are CiA 301's.
#[test]
fn akd_s1_free_mapping_of_tpdo1() {
    let mut r = akd(1);
    replay(&mut r, &trace(1).steps(1, 5));
    assert_eq!(r.node().od().get_u32(0x1800, 1), Some(0xC000_0181));
}

/// §7.2.1.2 (section 3): state machine by SDO.
#[test]
fn akd_s3_state_machine_by_sdo() {
    let mut r = node();
    state_machine_by_sdo(&mut r, &trace(3));
}

/// §7.2.1.3 (section 4): jog by SDO.
#[test]
fn akd_s4_jog_mode_by_sdo() {
    let t = trace(4);
    let mut r = node();
    jog_by_sdo_start(&mut r, &t);
    jog_by_sdo_halt(&mut r, &t);
}

/// §7.2.1.4 (section 5): torque by SDO.
#[test]
fn akd_s5_torque_mode_by_sdo() {
    let t = trace(5);
    let mut r = node();
    torque_by_sdo_start(&mut r, &t);
    replay(&mut r, &t.steps(13, 14));
}

/// §7.2.1.5 (section 6): jog by PDO — RPDO1 → 60FFh, TPDO1 → 6064h + 606Ch
/// on every SYNC.
#[test]
fn akd_s6_jog_mode_by_pdo() {
    let t = trace(6);
    let mut r = node();
    // Lines 5573–5598: the remapping; 5599–5613: TPDO2..4, RPDO2..4 disabled;
    // 5614: NMT start; 5615–5620: enable.
    replay(&mut r, &t.steps(5573, 5620));
    // Line 5621 prints the RPDO1 with 4 bytes (`00 40 00 00`); this replay
    // sends 2 of them, as the KC1's `203 00 40`: the AKD takes the short RPDO
    // as well (set-point 4000h).
    r.exchange("203#00 40", &[]);
    assert_eq!(value(&r, 0x60FF, 0), Some(Value::I32(0x4000)));
    // TPDO1 at the SYNC, in form: the printed values are the manual's running
    // axis; here it runs 1 s first (velocity at the set-point, position ≈ 1 s
    // of it).
    let f = after_sync(&mut r, 1000, t.frame(5622));
    assert_jog_tpdo1(&f[0], t.line(5623));
    replay(&mut r, &t.steps(5624, 5625));
}

/// §7.2.1.6 (section 7): torque by PDO — RPDO1 → 6071h, TPDO1 → 6077h on SYNC.
#[test]
fn akd_s7_torque_mode_by_pdo() {
    let t = trace(7);
    let mut r = node();
    replay(&mut r, &t.steps(5633, 5679));
    assert_eq!(value(&r, 0x6071, 0), Some(Value::I16(530)));
    // TPDO1 at the SYNC, in form: 6077h follows the 530 ‰ demand (printed 537).
    let f = after_sync(&mut r, 60, t.frame(5680));
    assert_torque_tpdo1(&f[0], t.line(5681), 530);
    replay(&mut r, &t.steps(5682, 5683));
}

/// §7.2.1.7 (section 8): boot-up (`703 00`, checked by the rig), homing
/// parameters and start by SDO. The last statusword response is printed
/// incomplete (`60` only) and is not replayed.
#[test]
fn akd_s8_homing_by_sdo() {
    let t = trace(8);
    let mut r = node();
    replay(&mut r, &t.steps(5708, 5732));
    r.run_ms(1);
    replay(&mut r, &t.steps(5733, 5738));
}

/// An AKD on a machine with a home switch over −20°..−5° (homing method 12).
fn home_switch_machine(id: u8) -> Rig {
    let pn = build_on_machine(Profile::Akd, id, Box::new(MemoryStorage::new()), |c| {
        c.params.axis.home_switch = Some((-20.0, -5.0));
    })
    .unwrap();
    booted_with(pn, id)
}

/// §7.2.1.8 (section 9): profile position, every frame in order — PDO
/// set-up (9a–9e), NMT start with the event-driven TPDO1 (9f), homing with
/// the 6099h:1 abort and the TPDO1 statuswords (9g), RPDO1 (9h), pp
/// parameters (9i), RPDO2 + SYNC → TPDO2 (9j), the set-point handshake and
/// the move to 36000 (9k).
#[test]
fn akd_s9_profile_position() {
    let t = trace(9);
    let mut r = home_switch_machine(3);
    // Lines 5756–5835: PDO set-up; 9f (5840/5841): NMT start, TPDO1
    // (event-driven) sends the statusword at once; lines 5847–5852, incl.
    // the 0609 0031 abort of 6099h:1; lines 5853–5861: the state machine,
    // each step answered by TPDO1.
    pp_setup(&mut r, &t, (5756, 5835), (5840, 5841), (5847, 5852), (5853, 5861));
    // Lines 5862–5865: homing (method 12 on the machine's home switch) ends
    // with 1637h (homing attained); 5864 (0637h) in form: the sequence is
    // checked to end in 1637h.
    pp_homing(&mut r, &t, 5862);
    // 9h: controlword by RPDO1 (default mapping 6040h), bit 4 cleared; 9i
    // (5876–5881) and RPDO2 (5886).
    pp_parameters(&mut r, &t, 5870, (5876, 5881), 5886);
    // 9j: TPDO2 at SYNC, in form (printed with 4 of its 8 bytes).
    r.send(t.frame(5887));
    let f = r.take();
    assert_form(&f[0], t.line(5888));
    // 9k: set-point handshake by RPDO1, then target reached (6083h/6084h = 50
    // taken as acceleration units: ≈ 54 s for one revolution).
    let last =
        pp_move(&mut r, &t, (5893, 5898), (5903, 5904)).into_iter().rfind(|f| f.std_id() == Some(0x183));
    assert_eq!(last, Some(fr(t.frame(5909))), "target reached");
    pp_final_position(&mut r, &t, 5910, 5911);
}

/// §7.2.1.9 (section 10): ASCII channel 2026h, node 1; the reply is the
/// drive's own answer to `DRV.FAULTS`.
#[test]
fn akd_s10_ascii_channel() {
    let mut r = akd(1);
    replay(&mut r, &trace(10).steps(1, 16));
}

/// §7.2.1.10 (section 11): TPDO1 (6064h) every 2nd SYNC, TPDO2 (6041h +
/// 1002h) every 3rd SYNC; RPDO2 → 607Ah + 6081h.
#[test]
fn akd_s11_sync_every_nth() {
    let mut r = node();
    // Lines 5948–5986; TPDO3/4 are still valid and event-driven: they go out
    // when the node becomes operational (no NMT start is printed; PDOs need
    // it). Line 5991 (SYNC) and the pattern of its comment, on 183h/283h.
    // Axis at rest: position 0, statusword 0240h, 1002h 0.
    sync_every_nth(&mut r, &trace(11), (5948, 5986), 5991);
}

/// Sections 11b and 13k: a drive fault raises the AKD EMCY: code, error
/// register without the generic bit (08h for 4310h), category 01h (13k's
/// 8-byte form; 11b prints 7 bytes, the category column lost); the fault
/// reset sends the error-reset EMCY (register of what is still active: 00h;
/// the printed reset frames, lines 6000 and 6191, in form).
#[test]
fn akd_s11_s13_emcy_frames() {
    let (t11, t13) = (trace(11), trace(13));
    let mut r = akd(1);
    emcy_fault(&mut r, t13.frame(6190));
    assert!(t11.line(6000).form() && t13.line(6191).form());
    emcy_reset(&mut r);
}

/// §7.2.2.1 (section 13), axis 1 (node 1): RPDO2 → 60C1h:1 + dummy 2100h,
/// TPDO2 → 6063h + 1002h, both on every SYNC; TPDO3/4 off; IP mode, period.
#[test]
fn akd_s13_ip_axis1() {
    let t = trace(13);
    let mut r = akd_ip_axis(1);
    // Lines 6038–6133 (to 601h). 13h: NMT start of node 1. The event-driven
    // TPDO1 goes out on entering operational with 0240h (as printed in 9f;
    // 13h prints no frame). 13i (lines 6151–6158): controlwords by RPDO1,
    // answered by TPDO1.
    ip_axis1_start(&mut r, &t, (6038, 6133), 6146, (6151, 6158));
    // 13j: the set-points are applied at the SYNC (synchronous RPDO2).
    replay(&mut r, &t.steps(6167, 6167));
    assert_eq!(value(&r, 0x60C1, 1), Some(Value::I32(0)));
    // Line 6181 in form (printed on 181h, see the trace; its values are the
    // manual's axis, this one starts at 0).
    r.send(t.frame(6177));
    let f = r.take();
    assert_form(&f[0], t.line(6181));
    assert_eq!(value(&r, 0x60C1, 1), Some(Value::I32(500)));
    ip_axis1_follows(&mut r, &t, 6167, 6177);
}

/// §7.2.2.1, axis 2 (node 2): RPDO2 on 301h with the set-point in bytes 4–7.
#[test]
fn akd_s13_ip_axis2() {
    let t = trace(13);
    let mut r = akd_ip_axis(2);
    replay(&mut r, &t.steps_on(6038, 6133, "602"));
    // "The same procedure must be carried out for axis 2" (13c, 13e): TPDO2 →
    // 6063h + 1002h, TPDO3/4 off — not printed for node 2, done here so the
    // printed axis-2 answer of 13j can be checked.
    for (idx, sub, v) in
        [(0x1801u16, 1u8, 0xC000_0282u32), (0x1A01, 0, 0), (0x1A01, 1, 0x6063_0020), (0x1A01, 2, 0x1002_0020)]
    {
        let b = v.to_le_bytes();
        let data = if idx == 0x1A01 && sub == 0 { &b[..1] } else { &b[..] };
        Rig::assert_written(r.sdo_write(2, idx, sub, data), 2, idx, sub);
    }
    Rig::assert_written(r.sdo_write(2, 0x1A01, 0, &[2]), 2, 0x1A01, 0);
    for (idx, v) in [(0x1801u16, 0x282u32), (0x1802, 0xC000_0382), (0x1803, 0xC000_0482)] {
        Rig::assert_written(r.sdo_write(2, idx, 1, &v.to_le_bytes()), 2, idx, 1);
    }
    // 13h starts node 1 only (INCONSISTENT with "all axes"); node 2 started
    // here (its TPDO1 on entering operational is not printed, not asserted).
    r.send("000#01 02");
    r.run_ms(1);
    r.take();
    replay(&mut r, &t.steps(6167, 6167));
    // Line 6182 in form (printed on 182h, see the trace).
    r.send(t.frame(6177));
    let f = r.take();
    assert_form(&f[0], t.line(6182));
    assert_eq!(value(&r, 0x60C1, 1), Some(Value::I32(1000)));
}

/// Section 13's drives: the DC bus is charged before switch on (TPDO1
/// `31 02` after shutdown, line 6152; §9 shows 0221h — both forms appear).
fn akd_ip_axis(id: u8) -> Rig {
    use drivebus_personality::akd::Akd;
    let pn = drivebus_personality::build_with(
        Profile::Akd,
        id,
        Box::new(MemoryStorage::new()),
        Box::new(Akd::new().with_dc_bus_before_switch_on(true)),
    )
    .unwrap();
    booted_with(pn, id)
}

/// §7.2.1.5 lines 5585–5596: the AKD has no RTR on TPDOs yet acknowledges
/// re-enabling TPDO1 as 0x0000_0183 (bit 30 clear, inventory B.4).
#[test]
fn akd_rtr_unsupported_tpdo_cob_id_with_bit30_clear() {
    let mut r = node();
    replay(&mut r, &trace(6).steps(5585, 5596));
    // A remote frame on 183h is never answered.
    r.exchange("183#R0", &[]);
}

/// Identity and modes against the manual: 1000h 0002_0192h (§6.2.1.1),
/// vendor-ID 6Ah (§6.2.1.18), 6502h E5h (§6.2.3.10: the tq bit and the
/// negative modes not shown), 6060h values of §6.4.2.4 incl. −1 analog
/// current, −2 analog velocity, −3 electronic gearing, shown in 6061h.
#[test]
fn akd_identity_and_modes() {
    let mut r = node();
    assert_eq!(r.read_u32(3, 0x1000, 0), 0x0002_0192);
    assert_eq!(r.read_u32(3, 0x1018, 1), 0x6A);
    assert_eq!(r.read_u32(3, 0x6502, 0), 0xE5);
    for m in [-3i8, -2, -1, 1, 3, 4, 6, 7, 8] {
        Rig::assert_written(r.sdo_write(3, 0x6060, 0, &[m as u8]), 3, 0x6060, 0);
        r.run_ms(1);
        assert_eq!(r.node().od().get_i64(0x6061, 0), Some(i64::from(m)), "6061h shows {m}");
    }
    for m in [-4i8, 2, 5, 9, 10] {
        Rig::assert_abort(r.sdo_write(3, 0x6060, 0, &[m as u8]), 3, 0x6060, 0, 0x0609_0030);
    }
}

/// §6.4.2.4: in −2 (analog velocity) the set-point is the analog input —
/// the virtual drive has none (0 V): the axis stays at rest even when
/// 60FFh is written, and 6061h shows −2 while enabled.
#[test]
fn akd_manufacturer_mode_analog_velocity_ignores_bus_setpoint() {
    let mut r = node();
    Rig::assert_written(r.sdo_write(3, 0x6060, 0, &[(-2i8) as u8]), 3, 0x6060, 0);
    for cw in [6u16, 7, 0xF] {
        Rig::assert_written(r.sdo_write(3, 0x6040, 0, &cw.to_le_bytes()), 3, 0x6040, 0);
        r.run_ms(1);
    }
    assert_eq!(r.statusword() & 0x6F, 0x27);
    Rig::assert_written(r.sdo_write(3, 0x60FF, 0, &0x4000i32.to_le_bytes()), 3, 0x60FF, 0);
    r.run_ms(200);
    assert_eq!(r.velocity(), 0);
    assert_eq!(r.node().od().get_i64(0x6061, 0), Some(-2));
    // Back to pv (3): the bus set-point acts again.
    Rig::assert_written(r.sdo_write(3, 0x6060, 0, &[3]), 3, 0x6060, 0);
    Rig::assert_written(r.sdo_write(3, 0x60FF, 0, &0x4000i32.to_le_bytes()), 3, 0x60FF, 0);
    r.run_ms(500);
    assert!(r.velocity() > 0x4000 * 9 / 10);
}

/// §6.10.2.2 (edition R): 6098h takes −7..−3 besides the standard methods
/// (the AKD has no 60E3h: its object list §7.1.5 does not have it); −5
/// "set reference here" homes at once (position := 607Ch); −4 searches the
/// reference switch positive and references on it without index.
#[test]
fn akd_manufacturer_homing_methods() {
    let pn = build_on_machine(Profile::Akd, 3, Box::new(MemoryStorage::new()), |c| {
        c.params.axis.home_switch = Some((10.0, 1000.0));
    })
    .unwrap();
    let (mut r, _) = Rig::with(pn);
    Rig::assert_abort(r.sdo_read(3, 0x60E3, 0), 3, 0x60E3, 0, 0x0602_0000);
    for m in -7i8..=-3 {
        Rig::assert_written(r.sdo_write(3, 0x6098, 0, &[m as u8]), 3, 0x6098, 0);
    }
    Rig::assert_abort(r.sdo_write(3, 0x6098, 0, &[(-8i8) as u8]), 3, 0x6098, 0, 0x0609_0030);
    Rig::assert_written(r.sdo_write(3, 0x6060, 0, &[6]), 3, 0x6060, 0);
    Rig::assert_written(r.sdo_write(3, 0x607C, 0, &1234i32.to_le_bytes()), 3, 0x607C, 0);
    Rig::assert_written(r.sdo_write(3, 0x6098, 0, &[(-5i8) as u8]), 3, 0x6098, 0);
    for cw in [6u16, 7, 0xF, 0x1F] {
        Rig::assert_written(r.sdo_write(3, 0x6040, 0, &cw.to_le_bytes()), 3, 0x6040, 0);
        r.run_ms(1);
    }
    r.run_ms(10);
    assert_eq!(r.statusword() & 0x3400, 0x1400, "homing attained");
    assert_eq!(r.position(), 1234);
    // −4 on a fresh drive: positive search for the switch at +10° (1000
    // units), no index.
    let pn = build_on_machine(Profile::Akd, 3, Box::new(MemoryStorage::new()), |c| {
        c.params.axis.home_switch = Some((10.0, 1000.0));
    })
    .unwrap();
    let (mut r, _) = Rig::with(pn);
    Rig::assert_written(r.sdo_write(3, 0x6060, 0, &[6]), 3, 0x6060, 0);
    Rig::assert_written(r.sdo_write(3, 0x6098, 0, &[(-4i8) as u8]), 3, 0x6098, 0);
    for cw in [6u16, 7, 0xF, 0x1F] {
        Rig::assert_written(r.sdo_write(3, 0x6040, 0, &cw.to_le_bytes()), 3, 0x6040, 0);
        r.run_ms(1);
    }
    r.run_ms(5000);
    assert_eq!(r.statusword() & 0x3400, 0x1400, "homing attained: {:04X}", r.statusword());
    assert!(r.position().abs() < 200, "at the switch edge: {}", r.position());
}
