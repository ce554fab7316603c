//! The motion examples of the Technosoft iPOS CoE manual (seed002,
//! P091.064.UM.0524, `seed002-ipos-examples.md`) replayed with their
//! motion against the built `ipos` personality on the zero-time virtual bus.
//!
//! On the manual's EtherCAT drive the process data (controlword, modes of
//! operation, targets) travel in RxPDOs and the statusword in TxPDO1; here
//! the same objects travel in CAN PDOs (CiA 301 pre-defined connection set
//! for node 1: RPDO1 201h, RPDO2 301h, RPDO3 401h, RPDO4 501h, TPDO1 181h).
//! Where an example says "SDO" the object is written by an expedited SDO
//! download to 601h and confirmed on 581h.
//!
//! EtherCAT → CAN, step by step:
//! * "Start remote node / Pre-Op / Safe-Op / Op" → NMT Start (`000#01 01`);
//! * "mapped in RPDO1/RPDO2" → the mapping the example relies on is written
//!   by SDO before the start (unprinted, derived: the examples say
//!   "Control Word / Modes of Operation mapped in RPDO1", "Target position
//!   mapped in RPDO2"; §2.3's defaults map 6040h + 607Ah in RxPDO1 and
//!   leave 6060h out, seed002-ipos.md §2.3 note);
//! * assigning a PDO in the Sync Manager (1C12h/1C13h) → making it valid on
//!   CAN (1400h+n:1 bit 31 := 0): on CAN a PDO is used when its COB-ID is
//!   valid, and every iPOS RPDO but RPDO1 is invalid after power-on
//!   (§2.3.10, `ipos_pdo_validity.rs`);
//! * "Wait for bit 10 in Status Word" → the statusword of TPDO1 (6041h +
//!   6064h + 6077h, valid by default, §2.3 / §2.3.11), sent on change,
//!   with a bounded wait;
//! * the cyclic modes' SYNC0 → the CAN SYNC (`080#`), the targets sent in
//!   their RPDO before each SYNC.
//!
//! Units are the manual's (§1.3/§5): positions in encoder counts, speeds in
//! counts per 1 ms sample in 16.16 fixed point, accelerations in counts per
//! sample² in 16.16. The examples' motor has "a 500 lines incremental
//! encoder" (§6.4, §7.3: 2000 counts per revolution); the drive is built on
//! that machine (`build_custom`, [`manual_motor`]), so the rotations the
//! manual counts are the model's motor revolutions. Every expected value
//! is computed here from the example's numbers, not read from the drive.

mod ipos_rig;

use ipos_rig::*;

/// E05 (§1.6.1): profile position with CoE commands — the default PDO
/// variables (RxPDO1 = controlword + target position, §2.3), 6060h and
/// 6081h by SDO. 80000 counts at 9 IU, then back to 40000.
#[test]
fn e05_profile_position_default_rxpdo1() {
    let mut r = Rig::new();
    // Default RxPDO1 (§2.3): 6040h + 607Ah, valid (assigned in 1C12h).
    assert_eq!(r.upload(0x1600, 1, 4) as u32, 0x6040_0010);
    assert_eq!(r.upload(0x1600, 2, 4) as u32, 0x607A_0020);
    r.start_remote_node();
    let rpdo1 = |r: &mut Rig, cw: u16, target: i32| {
        let t = target.to_le_bytes();
        let c = cw.to_le_bytes();
        r.send(Frame::new(0x201, &[c[0], c[1], t[0], t[1], t[2], t[3]]));
    };
    // Step 3: 6060h := 1 by SDO.
    r.sdo(0x6060, 0, &[1]);
    // Steps 5–6: controlword 06h, 07h.
    rpdo1(&mut r, 0x06, 0);
    r.wait_sw("ready to switch on", 0x6F, 0x21, 100);
    rpdo1(&mut r, 0x07, 0);
    r.wait_sw("switched on", 0x6F, 0x23, 100);
    // Step 7: target position 80000 in the same RxPDO1.
    rpdo1(&mut r, 0x07, 80_000);
    // Step 8: 6081h := 0009_0000h = 9.0 IU.
    r.sdo(0x6081, 0, &0x0009_0000u32.to_le_bytes());
    // Step 9: 0Fh, the motor holds its position.
    rpdo1(&mut r, 0x0F, 80_000);
    r.wait_sw("operation enabled", 0x6F, 0x27, 100);
    let v = iu_to_counts_s(f64::from(0x0009_0000));
    assert_eq!(v, 9000.0, "9 counts/ms");
    let bound = move_bound_ms(&mut r, 80_000.0, v);
    // Step 10: 1Fh starts the move; step 12: "After reaching 80000 counts,
    // the motor will stop and hold its position".
    rpdo1(&mut r, 0x1F, 80_000);
    r.run_ms(2);
    assert_eq!(r.sw.unwrap() & (SW_ACK | SW_TARGET_REACHED), SW_ACK);
    let t = r.wait_sw("80000 reached", SW_TARGET_REACHED, SW_TARGET_REACHED, bound);
    // At 9 counts/ms the cruise alone takes 80000 / 9 ms.
    assert!(t as f64 >= 80_000.0 / 9.0 * 0.95, "80000 counts at 9 counts/ms take ≥ 8.9 s, took {t} ms");
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 80_000).abs() <= FEW_COUNTS, "6064h {p}");
    // Steps 13–15: bit 4 reset, target 40000, bit 4 set: back to 40000.
    rpdo1(&mut r, 0x0F, 80_000);
    rpdo1(&mut r, 0x0F, 40_000);
    let bound = move_bound_ms(&mut r, 40_000.0, v);
    rpdo1(&mut r, 0x1F, 40_000);
    r.run_ms(2);
    r.wait_sw("40000 reached", SW_TARGET_REACHED, SW_TARGET_REACHED, bound);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 40_000).abs() <= FEW_COUNTS, "6064h {p}");
    assert!((r.motor_revs() - 40_000.0 / COUNTS_PER_REV).abs() < 0.01, "{} rev", r.motor_revs());
}

/// The homing machine of E18: the positive limit switch LSP, active from
/// 3 motor revolutions (6000 counts) up. The manual's operator "presses
/// for 5 s the LSP button" (§6.4 step 12) while the motor runs towards
/// it; here the switch is placed on the axis, where method 18 finds it.
const E18_LSP_COUNTS: f64 = 6000.0;

/// E18 (§6.4): homing method 18 (positive limit switch), 600 rpm search
/// for the switch, 150 rpm search for zero, 5 rot/s², home offset 1
/// rotation.
#[test]
fn e18_homing_method_18() {
    let mut r = Rig::on(|c| c.params.axis.positive_limit = Some(deg(E18_LSP_COUNTS)));
    map_examples_rpdos(&mut r);
    // Step 1: start remote node; steps 2–4: 06h, 07h, 0Fh in RPDO1.
    r.start_remote_node();
    r.enable();
    // Steps 5–9, each value computed as the text does.
    let zero = rpm_to_iu(150.0);
    let switch = rpm_to_iu(600.0);
    let acc = 5.0 * COUNTS_PER_REV * SAMPLE_S * SAMPLE_S * FIX; // 5 rot/s²
    assert_eq!(zero, f64::from(0x0005_0000));
    assert_eq!(switch, f64::from(0x0014_0000));
    assert_eq!(acc.round(), f64::from(0x028F));
    assert_eq!(COUNTS_PER_REV, f64::from(0x07D0));
    r.sdo(0x6099, 2, &0x0005_0000u32.to_le_bytes());
    r.sdo(0x6099, 1, &0x0014_0000u32.to_le_bytes());
    r.sdo(0x609A, 0, &0x0000_028Fu32.to_le_bytes());
    r.sdo(0x607C, 0, &0x0000_07D0i32.to_le_bytes());
    r.sdo(0x6098, 0, &[0x12]);
    // Step 10: homing mode in RPDO1; step 11: 001Fh starts the homing.
    // Method 18 (§6.2.8): LSP inactive → move positive, reverse on LSP,
    // home where LSP becomes inactive moving negative. TYPO (§6.2.8):
    // "rightward (negative sense)" — rightward is the positive sense.
    r.modes_of_operation(6);
    r.run_ms(2);
    r.controlword(0x1F);
    r.run_ms(2);
    assert_eq!(r.sw.unwrap() & 0x3400, 0, "homing in progress");
    // Step 13: "When Status Word (object 6040h) bit13=0, bit12=1 and
    // bit10=1, means homing procedure is completed successfully".
    // TYPO (§6.4 step 13): "Status Word (object 6040h)" — 6041h.
    // Bound: reach the switch, brake from at most 600 rpm, come back at
    // 150 rpm, brake: all at 5 rot/s² — a few seconds; 20 s allowed.
    r.wait_sw("homing completed", SW_BIT13 | SW_ACK | SW_TARGET_REACHED, SW_ACK | SW_TARGET_REACHED, 20_000);
    // Step 14: 6064h by SDO. "6064h = 607Ch ± a few counts": the drive
    // braked past the home position (at 5 rot/s² from 150 rpm,
    // (5 counts/ms)² / (2 × 0.01 counts/ms²) = 1250 counts) and moved back.
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 2000).abs() <= FEW_COUNTS, "6064h {p} = 607Ch 2000 ± a few counts");
    // CiA 402 method 18: the home position is where LSP becomes inactive
    // moving negative; there the position became 607Ch = 2000, so the
    // shaft now stands at that edge (the switch placed on the model's axis).
    let from_edge = r.motor_revs() * COUNTS_PER_REV - E18_LSP_COUNTS;
    assert!((p as f64 - from_edge - 2000.0).abs() <= 2.0, "home at the LSP edge: {from_edge:.1} counts off");
    let v = iu_to_counts_s(zero);
    let a = iu_to_counts_s2(f64::from(0x028F));
    assert!((v * v / (2.0 * a) - 1250.0).abs() < 1.0, "the braking the return makes up for");
}

/// E19 (§7.3.1): relative trapezoidal profile, 20 rotations then 200
/// rotations at 500 rpm; "the motor should rotate 220 times".
///
/// TYPO (§7.3.1 intro): "Execute an absolute trapezoidal profile … 4
/// rotations … 16 rotations" is §7.3.2's sentence; the steps are the
/// relative 20 + 200 rotations.
#[test]
fn e19_relative_trapezoidal() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Step 2: position mode in RPDO1; steps 3–5: 06h, 07h, 0Fh.
    r.modes_of_operation(1);
    r.enable();
    // Step 6: target 20 rotations = 20 × 2000 = 9C40h counts, in RPDO2.
    assert_eq!(20.0 * COUNTS_PER_REV, f64::from(0x9C40));
    r.target_position_rpdo2(0x0000_9C40);
    // Step 7: 500 rpm = 16.667 counts/ms = 10AAABh (rounded); the manual
    // prints 10AAACh (1 LSB more) — sent as printed.
    assert_eq!(rpm_to_iu(500.0).round(), f64::from(0x0010_AAAB));
    r.sdo(0x6081, 0, &0x0010_AAACu32.to_le_bytes());
    let v = iu_to_counts_s(f64::from(0x0010_AAAC));
    // Steps 8–9: 005Fh (bit 6 relative), wait for bit 10.
    let bound = move_bound_ms(&mut r, 40_000.0, v);
    start_and_wait(&mut r, 0x5F, bound);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 40_000).abs() <= FEW_COUNTS, "after the first move 6064h {p}");
    // Step 10: 000Fh resets the set-point.
    r.controlword(0x0F);
    // Step 11: target 200 rotations = 61A80h, by SDO. On EtherCAT a
    // PDO-mapped 607Ah would be overwritten by the next cycle (§1.6.1
    // remark); a CAN RPDO is used only when received, so the SDO value
    // stays until an RPDO2 comes.
    assert_eq!(200.0 * COUNTS_PER_REV, f64::from(0x0006_1A80));
    r.sdo(0x607A, 0, &0x0006_1A80i32.to_le_bytes());
    // Steps 12–13.
    let bound = move_bound_ms(&mut r, 400_000.0, v);
    let t = start_and_wait(&mut r, 0x5F, bound);
    assert!(t as f64 >= 400_000.0 / v * 1000.0 * 0.99, "200 rotations at 500 rpm last ≥ 24 s ({t} ms)");
    // Steps 14–15: 6064h and 6062h by SDO.
    let actual = r.upload(0x6064, 0, 4);
    let demand = r.upload(0x6062, 0, 4);
    let expected = (20 + 200) * COUNTS_PER_REV as i64;
    assert_eq!(demand, expected, "6062h = 20 + 200 rotations");
    assert!((actual - demand).abs() <= FEW_COUNTS, "6064h {actual} = 6062h {demand} ± a few counts");
    assert!((r.motor_revs() - 220.0).abs() < 0.01, "rotated {} times", r.motor_revs());
}

/// E20 (§7.3.2): absolute trapezoidal profile to 4 rotations, then to 16
/// rotations; "the motor should rotate 16 times".
#[test]
fn e20_absolute_trapezoidal() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    // Step 21: 4 rotations = 1F40h in RPDO2; step 22: 500 rpm.
    assert_eq!(4.0 * COUNTS_PER_REV, f64::from(0x1F40));
    r.target_position_rpdo2(0x0000_1F40);
    r.sdo(0x6081, 0, &0x0010_AAACu32.to_le_bytes());
    let v = iu_to_counts_s(f64::from(0x0010_AAAC));
    // Steps 23–24: 001Fh (absolute), wait for bit 10.
    let bound = move_bound_ms(&mut r, 8000.0, v);
    start_and_wait(&mut r, 0x1F, bound);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 8000).abs() <= FEW_COUNTS, "6064h {p}");
    // Steps 25–28: 000Fh, 607Ah := 16 rotations = 7D00h by SDO, 001Fh, wait.
    r.controlword(0x0F);
    assert_eq!(16.0 * COUNTS_PER_REV, f64::from(0x7D00));
    r.sdo(0x607A, 0, &0x0000_7D00i32.to_le_bytes());
    let bound = move_bound_ms(&mut r, 24_000.0, v);
    start_and_wait(&mut r, 0x1F, bound);
    // Steps 29–30.
    let actual = r.upload(0x6064, 0, 4);
    let demand = r.upload(0x6062, 0, 4);
    assert_eq!(demand, 16 * COUNTS_PER_REV as i64);
    assert!((actual - demand).abs() <= FEW_COUNTS, "6064h {actual} = 6062h {demand} ± a few counts");
    assert!((r.motor_revs() - 16.0).abs() < 0.01, "rotated {} times", r.motor_revs());
}

/// Duration \[s\] of a rest-to-rest jerk-limited move of `d` counts with
/// speed limit `v`, acceleration (= deceleration) `a` and jerk `a / tj`
/// (§7.2.5): the textbook seven-segment S-curve, written out here.
fn s_curve_s(d: f64, v: f64, a: f64, tj: f64) -> f64 {
    let j = a / tj;
    // Time and distance to reach speed `w` from rest (and to stop from it).
    let ramp = |w: f64| {
        let t = if w * j >= a * a { w / a + a / j } else { 2.0 * (w / j).sqrt() };
        (t, w * t / 2.0)
    };
    let (t_ramp, d_ramp) = ramp(v);
    if 2.0 * d_ramp <= d {
        return 2.0 * t_ramp + (d - 2.0 * d_ramp) / v;
    }
    // No cruise: the peak speed w with 2 · d_ramp(w) = d.
    let jerk_only = (d * j.sqrt() / 2.0).powf(2.0 / 3.0);
    let w = if jerk_only * j < a * a {
        jerk_only
    } else {
        (-a / j + (a * a / (j * j) + 4.0 * d / a).sqrt()) * a / 2.0
    };
    2.0 * ramp(w).0
}

/// E21 (§7.3.3) relative and E22 (§7.3.4) absolute jerk-limited (S-curve)
/// profiles: 6086h = 3 with the jerk time 2023h (§7.2.5: the time to
/// reach the profile acceleration, so jerk = 6083h / 2023h). Asserted: the
/// end positions, "6064h = 6062h ± few counts" (the manual), and each
/// move's duration against the S-curve computed here ([`s_curve_s`]),
/// which the trapezoid of the same limits would miss by far.
///
/// TYPO (§7.3.3 intro): "Execute an absolute Jerk-limited ramp profile" —
/// §7.3.3 is the relative one (controlword 005Fh).
#[test]
fn e21_e22_jerk_limited_profiles() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    // E21 step 6: 6086h := 3; step 7: 10 rotations = 4E20h in RPDO2;
    // step 8: 450 rpm = 15 counts/ms = F0000h; step 9: 2023h := 1F4Bh.
    r.sdo(0x6086, 0, &3i16.to_le_bytes());
    assert_eq!(10.0 * COUNTS_PER_REV, f64::from(0x4E20));
    r.target_position_rpdo2(0x0000_4E20);
    assert_eq!(rpm_to_iu(450.0), f64::from(0x000F_0000));
    r.sdo(0x6081, 0, &0x000F_0000u32.to_le_bytes());
    r.sdo(0x2023, 0, &0x1F4Bu16.to_le_bytes());
    // Steps 10–11: 005Fh relative, wait for bit 10.
    let v = iu_to_counts_s(f64::from(0x000F_0000));
    let a = iu_to_counts_s2(r.upload(0x6083, 0, 4) as u32 as f64);
    let bound = move_bound_ms(&mut r, 20_000.0, v) + 8_011;
    let t = start_and_wait(&mut r, 0x5F, bound) as f64 * 1e-3 + 2e-3;
    let (want, trapezoid) = (s_curve_s(20_000.0, v, a, 8.011), 20_000.0 / v + v / a);
    assert!((t - want).abs() <= 0.01 * want + 2e-3, "E21: {t} s, S-curve {want} s (trapezoid {trapezoid} s)");
    // Steps 12–13.
    let actual = r.upload(0x6064, 0, 4);
    let demand = r.upload(0x6062, 0, 4);
    assert_eq!(demand, 20_000);
    assert!((actual - demand).abs() <= FEW_COUNTS, "E21: 6064h {actual} = 6062h {demand}");
    assert_eq!(r.upload(0x6086, 0, 2), 3, "6086h kept");
    // E22 on the same drive (its steps 14–18 repeat the start and enable;
    // the drive is already enabled in pp): reset bit 4 first.
    r.controlword(0x0F);
    // Step 19: 6086h := 3; step 20: 5 rotations = 2710h in RPDO2; step
    // 21: 150 rpm = 5 counts/ms = 50000h; step 22: 2023h := 013Bh.
    r.sdo(0x6086, 0, &3i16.to_le_bytes());
    assert_eq!(5.0 * COUNTS_PER_REV, f64::from(0x2710));
    r.target_position_rpdo2(0x0000_2710);
    assert_eq!(rpm_to_iu(150.0), f64::from(0x0005_0000));
    r.sdo(0x6081, 0, &0x0005_0000u32.to_le_bytes());
    r.sdo(0x2023, 0, &0x013Bu16.to_le_bytes());
    // Steps 23–24: 001Fh absolute, wait for bit 10.
    let v = iu_to_counts_s(f64::from(0x0005_0000));
    let bound = move_bound_ms(&mut r, 10_000.0, v) + 315;
    let t = start_and_wait(&mut r, 0x1F, bound) as f64 * 1e-3 + 2e-3;
    let want = s_curve_s(10_000.0, v, a, 0.315);
    assert!((t - want).abs() <= 0.01 * want + 2e-3, "E22: {t} s, S-curve {want} s");
    // Steps 25–26.
    let actual = r.upload(0x6064, 0, 4);
    let demand = r.upload(0x6062, 0, 4);
    assert_eq!(demand, 10_000);
    assert!((actual - demand).abs() <= FEW_COUNTS, "E22: 6064h {actual} = 6062h {demand}");
    assert!((r.motor_revs() - 5.0).abs() < 0.01, "at 5 rotations: {}", r.motor_revs());
}

/// §7.1.2: "when the jerk-limited ramp is selected, controlword bit 5
/// (change set immediately) must be 0, otherwise a command error is
/// issued": the set-point is not taken (no acknowledge, no motion), EMCY
/// 9000h, statusword bit 7 (warning), 2000h bit 14 and 2002h bit 9 until a
/// fault reset.
#[test]
fn s_curve_with_change_immediately_is_a_command_error() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    r.sdo(0x6086, 0, &3i16.to_le_bytes());
    r.sdo(0x2023, 0, &100u16.to_le_bytes());
    r.target_position_rpdo2(4000);
    r.emcy.clear();
    r.controlword(0x3F);
    r.run_ms(50);
    let sw = r.sw.unwrap();
    assert_eq!(sw & SW_ACK, 0, "not acknowledged: {sw:04X}h");
    assert_ne!(sw & 0x80, 0, "warning bit 7: {sw:04X}h");
    assert_eq!(r.upload(0x6062, 0, 4), 0, "no motion");
    assert!(r.emcy.iter().any(|f| f.data()[..2] == [0x00, 0x90]), "EMCY 9000h in {:?}", r.emcy);
    // Table 4.4.2: 2000h bit 14 command error; 2002h bit 9 "update ignored
    // for S-curve".
    assert_ne!(r.upload(0x2000, 0, 2) & 1 << 14, 0);
    assert_ne!(r.upload(0x2002, 0, 2) & 1 << 9, 0);
    // Fault reset (bit 7 rising) clears the latch.
    r.controlword(0x8F);
    r.run_ms(5);
    r.controlword(0x0F);
    r.run_ms(5);
    assert_eq!(r.sw.unwrap() & 0x80, 0, "warning gone");
    assert_eq!(r.upload(0x2000, 0, 2) & 1 << 14, 0);
    // Without bit 5 the same set-point runs.
    r.controlword(0x0F);
    r.run_ms(2);
    let bound = move_bound_ms(&mut r, 4000.0, 33_000.0) + 200;
    start_and_wait(&mut r, 0x1F, bound);
    assert_eq!(r.upload(0x6062, 0, 4), 4000);
}

/// E23 (§8.3): profile torque, rated current 1000 mA, slope 1000 ‰/s,
/// +50.0 % then −120.0 %. The machine: the motor shaft between two end
/// stops 2 revolutions either side (the manual gives no load; unloaded, a
/// torque set-point only runs the motor into its speed limit), so the
/// torque is held once the motor "moves positive" / "moves negative".
#[test]
fn e23_torque_profile() {
    let mut r = Rig::on(|c| {
        c.params.axis.positive_stop = Some(deg(2.0 * COUNTS_PER_REV));
        c.params.axis.negative_stop = Some(deg(-2.0 * COUNTS_PER_REV));
    });
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Step 2: mode 04h in RPDO1. TYPO (§8.3 step 2): "Select position
    // mode" — 04h is profile torque.
    r.modes_of_operation(4);
    r.enable();
    // Steps 6–7: 6075h := 1000 mA, 6087h := 1000 ‰/s. TYPO (§8.3 step 7):
    // the slope is printed "1000mA"; its unit is ‰ of 6075h per second
    // (§8.2.3), here 1000 mA/s.
    r.sdo(0x6075, 0, &0x03E8u32.to_le_bytes());
    r.sdo(0x6087, 0, &0x03E8u32.to_le_bytes());
    let slope = 1000.0; // ‰ per second
    // Step 8: 6071h := 01F4h = 500 = 50.0 %. The demand follows the slope:
    // 500 ‰ after 500 / 1000 s.
    r.sdo(0x6071, 0, &0x01F4i16.to_le_bytes());
    let t0 = 0.0005; // the SDO exchange (500 µs) after the write
    for ms in [100u64, 250, 400] {
        r.run_ms(if ms == 100 { 100 } else { 150 });
        let want = (slope * (ms as f64 / 1000.0 + t0)).min(500.0);
        let got = r.od_i64(0x6074, 0) as f64;
        assert!((got - want).abs() <= 3.0, "6074h {got} ‰ at {ms} ms, slope gives {want:.1}");
    }
    r.run_ms(200);
    assert_eq!(r.od_i64(0x6074, 0), 500, "target 50.0 % reached");
    assert!(r.motor_revs() > 1.9, "moved positive to the stop: {} rev", r.motor_revs());
    let tq = r.upload(0x6077, 0, 2);
    assert!((tq - 500).abs() <= 10, "6077h {tq} ‰ held against the stop");
    assert_ne!(r.sw.unwrap() & SW_TARGET_REACHED, 0, "bit 10: target torque reached");
    // Step 8: "reach a current of 50.0% of the motor rated current
    // (500mA)" (§8.2.1: ‰ of 6075h): the motor's own current (the iPOS
    // has no 6078h, Appendix A).
    let rated_ma = 1000.0;
    let ma = 500.0 / 1000.0 * rated_ma;
    let amps = r.dn().drive.model().current();
    assert!((amps * 1000.0 - ma).abs() <= 10.0, "motor current {amps} A, 500 mA expected");
    // Step 9: 6071h := FB50h = −1200 = −120.0 %: 1700 ‰ at 1000 ‰/s.
    assert_eq!(0xFB50u16 as i16, -1200);
    r.sdo(0x6071, 0, &0xFB50u16.to_le_bytes());
    r.run_ms(1000);
    let want = 500.0 - slope * (1.0 + t0);
    let got = r.od_i64(0x6074, 0) as f64;
    assert!((got - want).abs() <= 3.0, "6074h {got} ‰ 1 s after, slope gives {want:.1}");
    r.run_ms(800);
    assert_eq!(r.od_i64(0x6074, 0), -1200, "target −120.0 % reached after 1.7 s");
    r.run_ms(500);
    assert!(r.motor_revs() < -1.9, "moved negative to the stop: {} rev", r.motor_revs());
    let tq = r.upload(0x6077, 0, 2);
    assert!((tq + 1200).abs() <= 20, "6077h {tq} ‰ held against the stop");
    // "reach a current of -120.0% of the motor rated current (-1200mA)".
    let amps = r.dn().drive.model().current();
    assert!((amps * 1000.0 + 1200.0).abs() <= 20.0, "motor current {amps} A, −1200 mA expected");
}

/// E29 (§10.3): profile velocity, 600 rpm = 20.0 IU = 140000h.
#[test]
fn e29_speed_profile_600_rpm() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Step 2: speed mode in RPDO1; steps 3–5.
    r.modes_of_operation(3);
    r.enable();
    // Step 6: 600 rpm × 2000 counts / 60 s × 1 ms = 20.0 IU.
    let iu = rpm_to_iu(600.0);
    assert_eq!(iu, f64::from(0x0014_0000));
    r.sdo(0x60FF, 0, &0x0014_0000i32.to_le_bytes());
    let bound = ramp_bound_ms(&mut r, iu_to_counts_s(iu));
    r.run_ms(bound);
    // Step 7: "It should rotate with 600 rpm. Read … 606Ch".
    let v = r.upload(0x606C, 0, 4) as f64;
    assert!((v - iu).abs() <= ONE_READING_IU, "606Ch {v} IU, 600 rpm = {iu} IU");
    // Not one lucky reading: every slow-loop sample for 100 ms.
    for ms in 0..100 {
        r.run_us(1000);
        let v = r.od_i64(0x606C, 0) as f64;
        assert!((v - iu).abs() <= ONE_READING_IU, "606Ch {v} IU at +{ms} ms, 600 rpm = {iu} IU");
    }
    let (speed, rpm) = speed_over_1s(&mut r);
    assert!((speed - iu).abs() <= iu * 0.005, "{speed:.0} IU over 1 s, 600 rpm = {iu} IU");
    assert!((rpm - 600.0).abs() <= 3.0, "{rpm} rpm");
}

/// E30 (§10.4): profile velocity of a stepper in open loop, 200 steps ×
/// 512 µsteps, 300 rpm = 512 IU = 200_0000h. The machine: the NEMA 23
/// stepper model with 512 µsteps, position IU = µsteps ("1 IU is
/// equivalent to 1 µstep per slow loop": 102 400 per revolution).
#[test]
fn e30_stepper_open_loop_300_rpm() {
    const USTEPS: u32 = 200 * 512;
    let mut r = Rig::on(|c| {
        let mut p = drivebus_cia402::model::DriveParams::stepper();
        if let drivebus_cia402::model::MotorKind::Stepper(s) = &mut p.motor.kind {
            s.microsteps = 512;
        }
        p.encoder.counts_per_rev = USTEPS;
        p.control.control_rate_hz = c.control_rate_hz;
        // The personality's speed filter (one slow-loop sample) stays.
        p.control.velocity_filter = c.params.control.velocity_filter;
        c.params = p;
        c.factor.encoder = (USTEPS, 1);
        c.factor.velocity_encoder = (USTEPS, 1);
        c.factor.feed = (USTEPS, 1);
    });
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(3);
    r.enable();
    // Step 6: 300 rpm = 5 rev/s = 512 000 µsteps/s = 512 µsteps per 1 ms
    // sample; × 65536 = 200_0000h.
    let iu = 300.0 / 60.0 * f64::from(USTEPS) * SAMPLE_S * FIX;
    assert_eq!(iu, f64::from(0x0200_0000));
    // TYPO (§10.4 step 6): the message prints "32-bit value 00140000h"
    // (E29's 600 rpm value); the text computes 2000000h, which is sent.
    r.sdo(0x60FF, 0, &0x0200_0000i32.to_le_bytes());
    let bound = ramp_bound_ms(&mut r, iu_to_counts_s(iu));
    r.run_ms(bound);
    let v = r.upload(0x606C, 0, 4) as f64;
    assert!((v - iu).abs() <= ONE_READING_IU, "606Ch {v} IU, 300 rpm = {iu} IU");
    let (speed, rpm) = speed_over_1s(&mut r);
    assert!((speed - iu).abs() <= iu * 0.005, "{speed:.0} IU over 1 s, 300 rpm = {iu} IU");
    assert!((rpm - 300.0).abs() <= 1.5, "{rpm} rpm");
}

/// The machine of E41: LSP active from 1.5 revolutions (3000 counts) up,
/// inside the 4-rotation move.
const E41_LSP_COUNTS: f64 = 3000.0;

/// Differential travel of the placed limit switches: 5 counts (a real
/// switch releases a little inside the point where it closed).
const SWITCH_HYSTERESIS_COUNTS: f64 = 5.0;

/// E41 (§16.3): touch probe 1 on the LSP rising edge during a pp move at
/// 2 IU/ms; the LSP stops the motor. Replayed: set-up, 60B9h = 0001h
/// before the event, the move, the stop at the LSP, the capture (60B9h =
/// 0003h, 60BAh at the LSP: touch probe 1's input is the LSP, §16).
#[test]
fn e41_touch_probe_move_and_lsp_stop() {
    let mut r = Rig::on(|c| {
        c.params.axis.positive_limit = Some(deg(E41_LSP_COUNTS));
        c.params.axis.limit_hysteresis = deg(SWITCH_HYSTERESIS_COUNTS);
    });
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    // Step 6: 4 rotations = 1F40h in RPDO2; step 7: 2 IU/ms.
    assert_eq!(4.0 * COUNTS_PER_REV, f64::from(0x1F40));
    r.target_position_rpdo2(0x0000_1F40);
    r.sdo(0x6081, 0, &0x0002_0000u32.to_le_bytes());
    // Step 8: 60B8h := 0011h; step 9: 60B9h = 0001h — TYPO (§16.3 step
    // 9): the text reads it as "a capture was detected (bit1=1)"; 0001h
    // is "enabled, nothing stored" (Table 16.2.2).
    r.sdo(0x60B8, 0, &0x0011u16.to_le_bytes());
    assert_eq!(r.upload(0x60B9, 0, 2), 0x0001);
    // Step 10 "while the motor is moving": the example gives no start
    // command; 001Fh inserted (unprinted, derived).
    r.controlword(0x1F);
    r.run_ms(2);
    assert_eq!(r.sw.unwrap() & (SW_ACK | SW_TARGET_REACHED), SW_ACK, "moving");
    // At 2 counts/ms the LSP (3000 counts) comes after ~1.5 s: "The motor
    // should stop".
    let v = iu_to_counts_s(f64::from(0x0002_0000));
    let bound = move_bound_ms(&mut r, E41_LSP_COUNTS, v);
    r.wait_sw("LSP: internal limit active", 1 << 11, 1 << 11, bound);
    // Step 11: 60B9h = 0003h. TYPO (§16.3 step 11): 0003h is read as "no
    // capture was detected (bit1=0)"; it is "enabled, positive edge
    // stored in 60BAh" (bit 1 = 1). Step 12: 60BAh, the position of the
    // LSP's rising edge.
    r.run_ms(500);
    assert_eq!(r.upload(0x60B9, 0, 2), 0x0003);
    let captured = r.upload(0x60BA, 0, 4);
    assert!((captured as f64 - E41_LSP_COUNTS).abs() <= 1.0, "60BAh {captured} at the LSP edge");
    let p = r.upload(0x6064, 0, 4);
    assert!(p as f64 >= E41_LSP_COUNTS - 1.0 && p < 8000, "stopped at the LSP, short of 8000: 6064h {p}");
    let before = r.upload(0x6064, 0, 4);
    r.run_ms(100);
    assert_eq!(r.upload(0x6064, 0, 4), before, "at rest");
    // §4.3.1: the limit switch stop keeps Operation enabled (no Quick stop
    // active, 605Ah has no effect).
    assert_eq!(r.sw.unwrap() & 0x6F, 0x27, "Operation enabled: {:04X?}", r.sw);
    // §4.3.1: "If the positive limit switch is activated, the emergency
    // error code 0x5443 will be sent automatically and object 2000h bit 6
    // will be 1" (60B8h bit 6 = 0: limit switch functions on).
    let codes = |r: &Rig| r.emcy.iter().map(|f| (f.data()[0], f.data()[1], f.data()[2])).collect::<Vec<_>>();
    assert_eq!(codes(&r), [(0x43, 0x54, 0x01)], "one EMCY 5443h");
    assert_eq!(r.upload(0x2000, 0, 2) & 0xC0, 0x40, "2000h bit 6 on the LSP");
    r.emcy.clear();
    // Back off the switch (not in the example): target 0, new set-point.
    // "When a limit switch becomes inactive, the emergency error code
    // 0x0000 will be sent automatically and object 2000h bit 6 … 0".
    r.controlword(0x0F);
    r.target_position_rpdo2(0);
    r.controlword(0x1F);
    let bound = move_bound_ms(&mut r, E41_LSP_COUNTS, v);
    r.wait_sw("back at 0", SW_TARGET_REACHED, SW_TARGET_REACHED, bound);
    assert_eq!(codes(&r), [(0x00, 0x00, 0x00)], "one EMCY 0000h, error register clear");
    assert_eq!(r.upload(0x2000, 0, 2) & 0xC0, 0, "2000h bit 6 reset");
}

/// §4.3.1: the negative limit switch sends EMCY 5442h (2000h bit 7) and
/// 0000h when released; with 60B8h bit 6 = 1 (limit switch functions
/// off) no EMCY is sent.
#[test]
fn lsn_emcy_and_60b8_bit6() {
    let lsn = -E41_LSP_COUNTS;
    let mut r = Rig::on(|c| {
        c.params.axis.negative_limit = Some(deg(lsn));
        c.params.axis.limit_hysteresis = deg(SWITCH_HYSTERESIS_COUNTS);
    });
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    r.sdo(0x6081, 0, &0x0002_0000u32.to_le_bytes());
    let v = iu_to_counts_s(f64::from(0x0002_0000));
    let bound = move_bound_ms(&mut r, -lsn, v);
    r.target_position_rpdo2(-8000);
    r.controlword(0x1F);
    r.wait_sw("LSN: internal limit active", 1 << 11, 1 << 11, bound);
    r.run_ms(10);
    let codes = |r: &Rig| r.emcy.iter().map(|f| (f.data()[0], f.data()[1], f.data()[2])).collect::<Vec<_>>();
    assert_eq!(codes(&r), [(0x42, 0x54, 0x01)], "one EMCY 5442h");
    assert_eq!(r.upload(0x2000, 0, 2) & 0xC0, 0x80, "2000h bit 7 on the LSN");
    r.emcy.clear();
    r.controlword(0x0F);
    r.target_position_rpdo2(0);
    r.controlword(0x1F);
    r.wait_sw("back at 0", SW_TARGET_REACHED, SW_TARGET_REACHED, bound);
    assert_eq!(codes(&r), [(0x00, 0x00, 0x00)], "one EMCY 0000h");
    assert_eq!(r.upload(0x2000, 0, 2) & 0xC0, 0, "2000h bit 7 reset");
    r.emcy.clear();
    // 60B8h bit 6 = 1 disables the limit-switch function (§16, §4.3.1):
    // no EMCY, no stop, no statusword bit 11 — the move runs through.
    r.sdo(0x60B8, 0, &0x0040u16.to_le_bytes());
    r.controlword(0x0F);
    r.target_position_rpdo2(-8000);
    r.controlword(0x1F);
    r.wait_sw("at −8000, through the LSN", SW_TARGET_REACHED, SW_TARGET_REACHED, 2 * bound);
    assert!(r.dn().drive.view().digital_inputs & 1 != 0, "on the LSN");
    assert_eq!(r.sw.unwrap() & (1 << 11), 0, "no internal limit");
    assert!((r.upload(0x6064, 0, 4) + 8000).abs() <= FEW_COUNTS, "at −8000");
    assert!(codes(&r).is_empty(), "no EMCY with 60B8h bit 6 = 1: {:?}", codes(&r));
}
