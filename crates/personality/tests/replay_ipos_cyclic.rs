//! The cyclic and interpolated examples of the Technosoft iPOS CoE manual
//! (seed002, `seed002-ipos-examples.md`): E06/E38 (csp), E39 (csv), E40
//! (cst), E25 (linear ip), E24/E26–E28 (PT/PVT records), E31/E32
//! (electronic gearing), replayed with their motion against the built
//! `ipos` personality on the zero-time virtual bus. The EtherCAT → CAN
//! translation and the units are those of `replay_ipos_motion.rs`; the
//! examples' SYNC0 is the CAN SYNC, each cycle's target sent in its RPDO
//! before the SYNC that latches it.

mod ipos_rig;

use ipos_rig::*;

/// E06 (§1.6.2): cyclic synchronous position by hand — the default
/// RxPDO1 (controlword + target position), 6060h := 8 by SDO, small
/// target steps ("Maximum 20-200 encoder counts"), each reached "within
/// that communication cycle time value". The free-run 1 ms cycle of E04
/// becomes a 1 ms CAN SYNC; 60C2h keeps its stated default 1 × 10⁻³ s.
#[test]
fn e06_csp_manual_commands() {
    let mut r = Rig::new();
    assert_eq!(r.upload(0x1600, 1, 4) as u32, 0x6040_0010);
    assert_eq!(r.upload(0x1600, 2, 4) as u32, 0x607A_0020);
    // 60C2h default (§13.2.1): 1, −3 = 1 ms, the free-run cycle of E04.
    assert_eq!((r.upload(0x60C2, 1, 1), r.upload(0x60C2, 2, 1)), (1, -3));
    r.start_remote_node();
    let rpdo1 = |cw: u16, t: i64| {
        let (c, p) = (cw.to_le_bytes(), (t as i32).to_le_bytes());
        Frame::new(0x201, &[c[0], c[1], p[0], p[1], p[2], p[3]])
    };
    // "6060h should already be set to the value 08 if the XML file is
    // loaded. If it is not 08, then modify … 6060h value 08 via SDO".
    r.sdo(0x6060, 0, &[8]);
    for (cw, state) in [(0x06u16, 0x21u16), (0x07, 0x23), (0x0F, 0x27)] {
        sync_cycle(&mut r, rpdo1(cw, 0), 1, 0x6062);
        r.wait_sw("enable", 0x6F, state, 100);
    }
    for _ in 0..5 {
        sync_cycle(&mut r, rpdo1(0x0F, 0), 1, 0x6062);
    }
    // Steps of 20…200 counts, one per 1 ms cycle, some held: the demand
    // reaches each within the cycle after the SYNC that latched it.
    let targets = [20, 60, 120, 200, 200, 400, 400, 380, 300, 100, 0, 0];
    follow(&mut r, 1, |t| rpdo1(0x0F, t), 0x6062, 0, &targets, 2.0);
    for _ in 0..50 {
        sync_cycle(&mut r, rpdo1(0x0F, 0), 1, 0x6062);
    }
    let p = r.upload(0x6064, 0, 4);
    assert!(p.abs() <= FEW_COUNTS, "back at 0: 6064h {p}");
}

/// One SYNC cycle of `period_ms`: the SYNC, then `rpdo` (the target for
/// the *next* SYNC) 1 ms before the next one; returns the values of
/// `index` 1, 2, … `period_ms` ms after the SYNC.
fn sync_cycle(r: &mut Rig, rpdo: Frame, period_ms: u64, index: u16) -> Vec<i64> {
    r.bus.send_from(r.probe, Frame::new(0x080, &[]));
    let mut v = Vec::new();
    for k in 1..=period_ms {
        if k == period_ms {
            r.bus.send_from(r.probe, rpdo);
        }
        r.run_us(1000);
        v.push(r.od_i64(index, 0));
    }
    v
}

/// Sends `targets` one per cycle of `period` ms (each in its RPDO,
/// `frame`, latched at the next SYNC), then one more cycle, and checks
/// that `index` heads linearly for each latched target over its cycle:
/// `j` ms after the SYNC it is `from + (to − from)·j/period` (±`tol`),
/// `from` the target latched before (`start` for the first), allowing
/// the value to lag by up to 0.2 ms (one control period of the drive's
/// loop, whose output is published after the period). Every cycle is
/// checked.
fn follow(
    r: &mut Rig,
    period: u64,
    frame: impl Fn(i64) -> Frame,
    index: u16,
    start: i64,
    targets: &[i64],
    tol: f64,
) {
    let last = *targets.last().unwrap();
    for k in 0..=targets.len() {
        let v = sync_cycle(r, frame(targets.get(k).copied().unwrap_or(last)), period, index);
        if k == 0 {
            // This SYNC latched `start`, sent before.
            continue;
        }
        let to = targets[k - 1];
        let from = if k >= 2 { targets[k - 2] } else { start };
        for (j, got) in v.iter().enumerate() {
            let slope = (to - from) as f64 / period as f64;
            let want = from as f64 + slope * (j as f64 + 1.0);
            assert!(
                (*got as f64 - want).abs() <= tol + 0.2 * slope.abs(),
                "{index:04X}h at SYNC {k} + {} ms: {got}, heading {from} → {to}: {want}",
                j + 1
            );
        }
    }
}

/// E37 (§13.2.1) as used by E38–E40: 60C2h = 4 × 10⁻³ s.
fn four_ms_cycle(r: &mut Rig) {
    r.sdo(0x60C2, 1, &[4]);
    r.sdo(0x60C2, 2, &[(-3i8) as u8]);
}

/// E38 (§13.3): cyclic synchronous position, 4 ms cycle; "If actual
/// position = 0 and the new target position is 40, then the motor will
/// move 10 increments in 1 ms".
#[test]
fn e38_csp_basic() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Step 2: 60C2h = 4, −3.
    four_ms_cycle(&mut r);
    // Step 3: mode 08h in RPDO1; steps 4–6.
    r.modes_of_operation(8);
    r.enable();
    assert_eq!(r.upload(0x6064, 0, 4), 0, "actual position = 0");
    // SYNC running, target 0 held.
    for _ in 0..5 {
        sync_cycle(&mut r, Frame::new(0x301, &0i32.to_le_bytes()), 4, 0x6062);
    }
    // Step 7: a new 607Ah in RPDO2 every cycle: 40, 80, … (10 counts/ms).
    // The target latched at a SYNC is reached linearly over the 4 ms
    // cycle: at SYNC + j ms the demand 6062h is 10·j counts on (the
    // printed value lags by less than one control period: ±2 counts).
    let rpdo2 = |t: i64| Frame::new(0x301, &(t as i32).to_le_bytes());
    let targets: Vec<i64> = (1..=50).map(|k| 40 * k).collect();
    follow(&mut r, 4, rpdo2, 0x6062, 0, &targets, 2.0);
    // Hold the last target: the axis follows to it.
    for _ in 0..50 {
        sync_cycle(&mut r, Frame::new(0x301, &2000i32.to_le_bytes()), 4, 0x6062);
    }
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 2000).abs() <= FEW_COUNTS, "6064h {p} at the last target 2000");
    let sw = r.sw.unwrap();
    assert_eq!(sw & 0x6F, 0x27, "still operation enabled: {sw:04X}h");
}

/// E25 (§9.3): linear interpolation — "identical with the Cyclic
/// Synchronous Position Mode basic example" (E38) with 6060h = 7 and
/// 60C1h:01 instead of 607Ah (208Eh bit 8 = 1, its default: not written).
/// RPDO2 carries 60C1h:01. Inserted (unprinted, derived): controlword
/// 001Fh — in ip bit 4 is "enable ip mode" (§9.1), which E38's 000Fh
/// leaves off.
#[test]
fn e25_linear_interpolation() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.sdo(0x1401, 1, &0x8000_0301u32.to_le_bytes());
    r.sdo(0x1601, 0, &[0]);
    r.sdo(0x1601, 1, &0x60C1_0120u32.to_le_bytes());
    r.sdo(0x1601, 0, &[1]);
    r.sdo(0x1401, 1, &0x0000_0301u32.to_le_bytes());
    r.start_remote_node();
    four_ms_cycle(&mut r);
    r.modes_of_operation(7);
    r.enable();
    let rpdo2 = |t: i64| Frame::new(0x301, &(t as i32).to_le_bytes());
    r.controlword(0x1F);
    for _ in 0..5 {
        sync_cycle(&mut r, rpdo2(0), 4, 0x6062);
    }
    assert_eq!(r.sw.unwrap() & SW_ACK, SW_ACK, "ip mode active");
    let targets: Vec<i64> = (1..=50).map(|k| 40 * k).collect();
    follow(&mut r, 4, rpdo2, 0x6062, 0, &targets, 2.0);
}

/// E39 (§14.2): cyclic synchronous velocity with 60FFh in RxPDO4.
#[test]
fn e39_csv_basic() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    // Steps 2–7 (pre-operational): 1C12h:00 := 0 … 1C12h:03 := 1603h,
    // 1C12h:00 := 3 — on CAN: RPDO4 invalid while mapped (it is invalid
    // after power-on, §2.3.10), then valid. TYPO (§14.2): "PRDO4" — RPDO4.
    r.sdo(0x1403, 1, &0x8000_0501u32.to_le_bytes());
    r.sdo(0x1403, 2, &[0xFF]);
    r.sdo(0x1603, 0, &[0]);
    r.sdo(0x1603, 1, &0x60FF_0020u32.to_le_bytes());
    r.sdo(0x1603, 0, &[1]);
    r.sdo(0x1403, 1, &0x0000_0501u32.to_le_bytes());
    // Step 8: operational; step 9: 60C2h = 4 ms. TYPO (§14.2 step 9): "when
    // every new position command is received in object 607Ah" (copied
    // from §13.3) — in csv it is 60FFh.
    r.start_remote_node();
    four_ms_cycle(&mut r);
    // Step 10: mode 09h in RPDO1; steps 11–13.
    r.modes_of_operation(9);
    r.enable();
    let rpdo4 = |v: i32| Frame::new(0x501, &v.to_le_bytes());
    for _ in 0..5 {
        sync_cycle(&mut r, rpdo4(0), 4, 0x606B);
    }
    // Step 14: a new 60FFh (16.16 IU) every cycle: 0 → 20.0 IU (600 rpm)
    // in steps of 2.0 IU, then held.
    let top = rpm_to_iu(600.0) as i64;
    let targets: Vec<i64> = (1..=10).map(|k| top * k / 10).collect();
    follow(&mut r, 4, |v| rpdo4(v as i32), 0x606B, 0, &targets, 0.01 * top as f64);
    for _ in 0..50 {
        sync_cycle(&mut r, rpdo4(top as i32), 4, 0x606B);
    }
    let v = r.upload(0x606C, 0, 4) as f64;
    assert!((v - top as f64).abs() <= ONE_READING_IU, "606Ch {v} IU, 600 rpm = {top} IU");
    // SYNC keeps coming: a second of cycles, the speed measured over it.
    let (c0, p0) = (r.od_i64(0x6064, 0), r.motor_revs());
    for _ in 0..250 {
        sync_cycle(&mut r, rpdo4(top as i32), 4, 0x606C);
    }
    let speed = (r.od_i64(0x6064, 0) - c0) as f64 / 1000.0 * FIX;
    let rpm = (r.motor_revs() - p0) * 60.0;
    assert!((speed - top as f64).abs() <= top as f64 * 0.005, "{speed:.0} IU over 1 s, 600 rpm = {top} IU");
    assert!((rpm - 600.0).abs() <= 3.0, "{rpm} rpm");
}

/// E40 (§15.3): cyclic synchronous torque with the default RxPDO3
/// (6060h + 6071h, §2.3 — "The RPDO3 has mapped by default, the object
/// 6071h").
#[test]
fn e40_cst_basic() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    assert_eq!(r.upload(0x1602, 0, 1), 2);
    assert_eq!(r.upload(0x1602, 1, 4) as u32, 0x6060_0008, "RxPDO3 default (§2.3)");
    assert_eq!(r.upload(0x1602, 2, 4) as u32, 0x6071_0010, "RxPDO3 default (§2.3)");
    // Steps 2–4: 1C12h:00 := 0, 1C12h:03 := 1602h, 1C12h:00 := 3 — on CAN
    // RPDO3 made valid.
    r.sdo(0x1402, 1, &0x8000_0401u32.to_le_bytes());
    r.sdo(0x1402, 2, &[0xFF]);
    r.sdo(0x1402, 1, &0x0000_0401u32.to_le_bytes());
    // Step 5: operational. 60C2h is not written by E40: the E37 4 ms
    // cycle of the preceding examples is used (unprinted, derived).
    r.start_remote_node();
    four_ms_cycle(&mut r);
    // The emulation's cst unit is ‰ of 6075h (the ASR4.0 = 1 variant,
    // docs/personalities.md), whose power-on value 0 leaves no torque:
    // 6075h := 1000 mA as in E23 (inserted, unprinted).
    r.sdo(0x6075, 0, &1000u32.to_le_bytes());
    // Steps 6–8, then step 9: mode 0Ah in RPDO1.
    r.enable();
    r.modes_of_operation(10);
    // RxPDO3 carries 6060h too: the process image keeps 0Ah there.
    let rpdo3 = |t: i16| {
        let b = t.to_le_bytes();
        Frame::new(0x401, &[0x0A, b[0], b[1]])
    };
    for _ in 0..5 {
        sync_cycle(&mut r, rpdo3(0), 4, 0x6074);
    }
    // Step 10: a new 6071h every cycle: 0 → 100 in steps of 10, then held.
    // The manual's CST unit is the current IU (65520·I / (2·Ipeak)) unless
    // ASR4.0 = 1 (‰ of 6075h); the emulation takes ‰ (report).
    let targets: Vec<i64> = (1..=10).map(|k| 10 * k).collect();
    follow(&mut r, 4, |t| rpdo3(t as i16), 0x6074, 0, &targets, 1.5);
    for _ in 0..3 {
        sync_cycle(&mut r, rpdo3(100), 4, 0x6074);
    }
    assert_eq!(r.od_i64(0x6074, 0), 100);
    let tq = r.upload(0x6077, 0, 2);
    assert!((tq - 100).abs() <= 5, "6077h {tq} ‰ follows");
    assert!(r.motor_rpm() > 0.0, "the motor turns positive");
    // "The drive applies the new current reference": 100 ‰ of 1000 mA.
    let amps = r.dn().app.drive.model().current();
    assert!((amps - 0.1).abs() <= 0.01, "motor current {amps} A, 100 mA expected");
}

/// E26–E28 steps 2–5: RPDO3 := 60C1h:01 (X1) + 60C1h:02 (X2). On CAN the
/// Sync Manager assignment 1C12h:03 := 1602h is RPDO3 made valid (401h).
fn map_interpolation_rpdo3(r: &mut Rig) {
    r.sdo(0x1402, 1, &0x8000_0401u32.to_le_bytes());
    r.sdo(0x1402, 2, &[0xFF]);
    r.sdo(0x1602, 0, &[0]);
    r.sdo(0x1602, 1, &0x60C1_0120u32.to_le_bytes());
    r.sdo(0x1602, 2, &0x60C1_0220u32.to_le_bytes());
    r.sdo(0x1602, 0, &[2]);
    r.sdo(0x1402, 1, &0x0000_0401u32.to_le_bytes());
}

/// One interpolation point: X1 and X2 in RPDO3.
fn point(r: &mut Rig, x1: u32, x2: u32) {
    let (a, b) = (x1.to_le_bytes(), x2.to_le_bytes());
    r.send(Frame::new(0x401, &[a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]));
}

/// The PT X2 the examples print: time (bits 0–15), integrity counter in
/// byte 3 bits 1–7 (§9.2.2.2).
fn pt_x2(time: u16, ic: u8) -> u32 {
    u32::from(ic) << 25 | u32::from(time)
}

/// PVT X1/X2 from position, velocity (16.8 IU), time, counter (§9.2.2.3,
/// the layout every correctly printed E27/E28 point follows).
fn pvt_x(p: i32, v_16_8: i32, t: u16, ic: u8) -> (u32, u32) {
    let p = p as u32 & 0xFF_FFFF;
    let v = v_16_8 as u32 & 0xFF_FFFF;
    let t = u32::from(t) & 0x1FF;
    let x1 = (p >> 16) << 24 | (v & 0xFF) << 16 | (p & 0xFFFF);
    let x2 = u32::from(ic) << 25 | (t >> 8) << 24 | (t & 0xFF) << 16 | (v >> 8);
    (x1, x2)
}

/// EMCY FF01h frames received since the last call: their 2072h (bytes 3–4).
fn ip_status_emcys(r: &mut Rig) -> Vec<u16> {
    let v = r
        .emcy
        .iter()
        .filter(|f| f.data()[0..2] == [0x01, 0xFF])
        .map(|f| u16::from_le_bytes([f.data()[3], f.data()[4]]))
        .collect();
    r.emcy.clear();
    v
}

/// 2072h status bits (Table 9.2.1).
const IPS_EMPTY: u16 = 1 << 15;
const IPS_LOW: u16 = 1 << 14;
const IPS_INTEGRITY: u16 = 1 << 12;

/// Steps common to E26–E28 up to the buffer set-up: mapping, start,
/// 208Eh bit 8 := 0 (legacy interpolation; "must be 0 (default 1)": the
/// write is not printed, inserted by SDO), enable with `enable_cw`, mode 7.
fn legacy_ip_setup(r: &mut Rig, enable_cw: u16) {
    map_examples_rpdos(r);
    map_interpolation_rpdo3(r);
    r.start_remote_node();
    assert_eq!(r.upload(0x208E, 0, 2), 0x0100, "208Eh default: bit 8 = 1 (§4.9.11)");
    r.sdo(0x208E, 0, &0x0000u16.to_le_bytes());
    r.controlword(0x06);
    r.wait_sw("ready to switch on", 0x6F, 0x21, 100);
    r.controlword(0x07);
    r.wait_sw("switched on", 0x6F, 0x23, 100);
    r.controlword(enable_cw);
    r.wait_sw("operation enabled", 0x6F, 0x27, 100);
    r.modes_of_operation(7);
    r.run_ms(2);
    assert_eq!(r.upload(0x6061, 0, 1), 7);
}

/// Runs until `t_ms` after the start and checks 6062h against `want`
/// within the distance `slope` (counts/ms) covers in 2 ms, plus 2 counts.
fn demand_at(r: &mut Rig, now: &mut u64, t_ms: u64, want: f64, slope: f64) {
    r.run_ms(t_ms - *now);
    *now = t_ms;
    let got = r.od_i64(0x6062, 0) as f64;
    assert!(
        (got - want).abs() <= 2.0 * slope.abs() + 2.0,
        "6062h {got} at {t_ms} ms, the points give {want}"
    );
}

/// E26 (§9.4): absolute PT, 4 points, initial position 2079h = 1000.
#[test]
fn e26_pt_absolute() {
    let mut r = Rig::new();
    legacy_ip_setup(&mut r, 0x0F);
    // Steps 12–15.
    r.sdo(0x60C0, 0, &0i16.to_le_bytes());
    r.sdo(0x2073, 0, &0x000Cu16.to_le_bytes());
    r.sdo(0x2074, 0, &0xA001u16.to_le_bytes());
    r.sdo(0x2079, 0, &1000i32.to_le_bytes());
    r.emcy.clear();
    // Steps 17–20 as printed (X2 = IC << 25 | time).
    let points: [(i32, u16, u8, u32, u32); 4] = [
        (20_000, 1000, 1, 0x0000_4E20, 0x0200_03E8),
        (30_000, 2000, 2, 0x0000_7530, 0x0400_07D0),
        (2000, 1000, 3, 0x0000_07D0, 0x0600_03E8),
        (0, 500, 4, 0x0000_0000, 0x0800_01F4),
    ];
    for (k, &(p, t, ic, x1, x2)) in points.iter().enumerate() {
        assert_eq!((x1, x2), (p as u32, pt_x2(t, ic)), "point {} as printed", k + 1);
        point(&mut r, x1, x2);
        if k == 0 {
            // The buffer is no longer empty (nor low): EMCY FF01h with
            // 2072h (§9.2.3).
            let e = ip_status_emcys(&mut r);
            assert_eq!(e.len(), 1, "one FF01h EMCY: {e:04X?}");
            assert_eq!(e[0] & (IPS_EMPTY | IPS_LOW | IPS_INTEGRITY), 0, "2072h {:04X}h", e[0]);
        }
    }
    assert_eq!(r.od_i64(0x6062, 0), 0, "nothing moves before bit 4");
    // Step 21: 1Fh. "if the drive actual position before starting the
    // motion was 0, now it should be -1000 counts because of Step 15":
    // each point P is reached at P − 1000, linearly over its time.
    r.controlword(0x1F);
    let mut now = 0;
    let mut from = 0.0;
    let mut at = 0u64;
    for &(p, t, ..) in &points {
        let to = f64::from(p) - 1000.0;
        let slope = (to - from) / f64::from(t);
        demand_at(&mut r, &mut now, at + u64::from(t) / 2, (from + to) / 2.0, slope);
        demand_at(&mut r, &mut now, at + u64::from(t), to, slope);
        from = to;
        at += u64::from(t);
    }
    assert_eq!(at, 4500);
    r.run_ms(200);
    assert_eq!(r.od_i64(0x6062, 0), -1000);
    let p = r.upload(0x6064, 0, 4);
    assert!((p + 1000).abs() <= FEW_COUNTS, "6064h {p}, −1000 expected");
    // The buffer ran empty: FF01h with 2072h bit 15 (and low) set.
    let e = ip_status_emcys(&mut r);
    assert!(e.iter().any(|s| s & IPS_EMPTY != 0), "FF01h with buffer empty: {e:04X?}");
    assert_ne!(r.upload(0x2072, 0, 2) as u16 & IPS_EMPTY, 0);
}

/// E27 (§9.5): absolute PVT, 12 points, initial position = the position
/// demand (2074h = B001h).
#[test]
fn e27_pvt_absolute() {
    let mut r = Rig::new();
    legacy_ip_setup(&mut r, 0x0F);
    // Steps 12–14.
    r.sdo(0x60C0, 0, &(-1i16).to_le_bytes());
    r.sdo(0x2073, 0, &0x000Fu16.to_le_bytes());
    r.sdo(0x2074, 0, &0xB001u16.to_le_bytes());
    // Steps 16–27: (P, V in 16.8, T, printed X1, printed X2).
    // TYPO (§9.5 step 25): X2 printed "159AFF2" — the layout gives
    // 159AFFF2h. TYPO (step 26): X1 printed "FF990C2B" (P8's position
    // bytes) — P = −9135 = FFDC51h gives FF99DC51h. TYPO (step 27): X2
    // printed "18F0000" — 18F00000h; its velocity is printed "−7.4 IU
    // (0x00000)": the value sent is 0. The layout-derived values are sent.
    let pts: [(i32, i32, u16, u32, u32); 12] = [
        (88, 0x354, 55, 0x0054_0058, 0x0237_0003),
        (370, 0x6A8, 55, 0x00A8_0172, 0x0437_0006),
        (2982, 0x6A8, 390, 0x00A8_0BA6, 0x0786_0006),
        (5631, 0x6A8, 400, 0x00A8_15FF, 0x0990_0006),
        (5925, 0x300, 60, 0x0000_1725, 0x0A3C_0003),
        (6000, 0, 50, 0x0000_1770, 0x0C32_0000),
        (5127, -0x780, 240, 0x0080_1407, 0x0EF0_FFF8),
        (3115, -0xD55, 190, 0x00AB_0C2B, 0x10BE_FFF2),
        (-1686, -0xD55, 360, 0xFFAB_F96A, 0x1368_FFF2),
        (-7145, -0xD55, 410, 0xFFAB_E417, 0x159A_FFF2),
        (-9135, -0x767, 190, 0xFF99_DC51, 0x16BE_FFF8),
        (-10_000, 0, 240, 0xFF00_D8F0, 0x18F0_0000),
    ];
    for (k, &(p, v, t, x1, x2)) in pts.iter().enumerate() {
        assert_eq!(pvt_x(p, v, t, k as u8 + 1), (x1, x2), "point {}", k + 1);
        point(&mut r, x1, x2);
    }
    // 12 points in a 15-point buffer: neither full nor empty.
    assert_eq!(r.upload(0x2072, 0, 2) as u16 & (IPS_EMPTY | (1 << 13)), 0);
    // Step 28: 1Fh. The cubic passes through every point at its time.
    r.controlword(0x1F);
    let mut now = 0;
    let mut at = 0u64;
    let mut from = 0.0;
    let mut top = i64::MIN;
    for &(p, _, t, ..) in &pts {
        at += u64::from(t);
        let slope = (f64::from(p) - from) / f64::from(t);
        // Sample the way there for the extreme.
        while now + 10 < at {
            r.run_ms(10);
            now += 10;
            top = top.max(r.od_i64(0x6062, 0));
        }
        demand_at(&mut r, &mut now, at, f64::from(p), 2.0 * slope);
        top = top.max(r.od_i64(0x6062, 0));
        from = f64::from(p);
    }
    // "All points should be executed within 2.64s".
    assert_eq!(at, 2640);
    // "3 positive rotations and another 8 negatively": up to 6000 counts,
    // then down to −10000 (−5 rotations).
    assert!((top - 6000).abs() <= 5, "highest demand {top}, 3 rotations = 6000");
    r.run_ms(200);
    assert_eq!(r.od_i64(0x6062, 0), -10_000);
    let p = r.upload(0x6064, 0, 4);
    assert!((p + 10_000).abs() <= FEW_COUNTS, "6064h {p}, −10000 expected");
    assert!((r.motor_revs() + 5.0).abs() < 0.01, "{} rev, −5 expected", r.motor_revs());
    // The last velocity was 0: no quick stop (2072h bit 11), still enabled.
    assert_eq!(r.upload(0x2072, 0, 2) as u16 & (1 << 11), 0);
    assert_eq!(r.sw.unwrap() & 0x6F, 0x27);
}

/// E28 (§9.6): relative PVT, 6 points, controlword 4Fh/5Fh.
#[test]
fn e28_pvt_relative() {
    let mut r = Rig::new();
    // Step 10: 4Fh (enable operation, relative).
    legacy_ip_setup(&mut r, 0x4F);
    r.cw = 0x4F;
    r.sdo(0x60C0, 0, &(-1i16).to_le_bytes());
    r.sdo(0x2073, 0, &0x000Cu16.to_le_bytes());
    r.sdo(0x2074, 0, &0xA001u16.to_le_bytes());
    // Steps 16–21 (X1 printed with 7 digits, e.g. "00004D8").
    let pts: [(i32, i32, u32, u32); 6] = [
        (400, 0x300, 0x0000_0190, 0x02FA_0003),
        (1240, 0x600, 0x0000_04D8, 0x04FA_0006),
        (1674, 0x600, 0x0000_068A, 0x06FA_0006),
        (1666, 0x600, 0x0000_0682, 0x08FA_0006),
        (1240, 0x300, 0x0000_04D8, 0x0AFA_0003),
        (410, 0, 0x0000_019A, 0x0CFA_0000),
    ];
    for (k, &(p, v, x1, x2)) in pts.iter().enumerate() {
        assert_eq!(pvt_x(p, v, 250, k as u8 + 1), (x1, x2), "point {}", k + 1);
        point(&mut r, x1, x2);
    }
    // Step 22: 5Fh. Each point is a distance from the previous one.
    r.controlword(0x5F);
    let mut now = 0;
    let mut sum = 0.0;
    for (k, &(p, v, ..)) in pts.iter().enumerate() {
        sum += f64::from(p);
        // The speed there: the velocity of the point [counts/ms].
        let slope = f64::from(v) / 256.0 + f64::from(p) / 250.0;
        demand_at(&mut r, &mut now, 250 * (k as u64 + 1), sum, slope);
    }
    // "the final position should be 6630 IU (3.315 rotation …) All points
    // should be executed in 1.5s".
    assert_eq!(sum, 6630.0);
    r.run_ms(200);
    assert_eq!(r.od_i64(0x6062, 0), 6630);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 6630).abs() <= FEW_COUNTS, "6064h {p}");
    assert!((r.motor_revs() - 3.315).abs() < 0.005, "{} rev", r.motor_revs());
}

/// E24 (§9.2.8): the integrity counter. A point with a counter 2 ahead is
/// ignored with EMCY FF01h and 2072h bit 12; the same counter again is
/// ignored with EMCY FF01h; the right one is taken and clears bit 12.
/// Only the points taken are travelled.
#[test]
fn e24_integrity_counter() {
    let mut r = Rig::new();
    legacy_ip_setup(&mut r, 0x0F);
    r.sdo(0x60C0, 0, &0i16.to_le_bytes());
    r.sdo(0x2073, 0, &0x000Cu16.to_le_bytes());
    // Clear, counter := 1, initial position = the demand (B001h).
    r.sdo(0x2074, 0, &0xB001u16.to_le_bytes());
    point(&mut r, 1000, pt_x2(100, 1));
    ip_status_emcys(&mut r);
    // IC 3 instead of 2: ignored, integrity error.
    point(&mut r, 50_000, pt_x2(100, 3));
    let e = ip_status_emcys(&mut r);
    assert_eq!(e.len(), 1, "{e:04X?}");
    assert_ne!(e[0] & IPS_INTEGRITY, 0, "2072h {:04X}h: integrity counter error", e[0]);
    // IC 1 again (the same as the last taken): ignored with an EMCY.
    point(&mut r, 60_000, pt_x2(100, 1));
    assert_eq!(ip_status_emcys(&mut r).len(), 1);
    // IC 2: taken, the error goes away (EMCY FF01h with bit 12 clear).
    point(&mut r, 2000, pt_x2(100, 2));
    let e = ip_status_emcys(&mut r);
    assert!(e.iter().any(|s| s & IPS_INTEGRITY == 0), "{e:04X?}");
    assert_eq!(r.upload(0x2072, 0, 2) as u16 & IPS_INTEGRITY, 0);
    // Wrong counter with checking off (2074h bit 14): taken.
    r.sdo(0x2074, 0, &0x4000u16.to_le_bytes());
    point(&mut r, 3000, pt_x2(100, 77));
    r.controlword(0x1F);
    r.run_ms(100);
    assert!((r.od_i64(0x6062, 0) - 1000).abs() <= 20, "first point at 100 ms");
    r.run_ms(100);
    assert!((r.od_i64(0x6062, 0) - 2000).abs() <= 20, "the ignored points were not travelled");
    r.run_ms(300);
    assert_eq!(r.od_i64(0x6062, 0), 3000);
    // 2073h = 0 is not allowed (§9.2.4); above 000Fh neither (§9.4).
    r.sdo.clear();
    r.send(Frame::new(0x601, &[0x2B, 0x73, 0x20, 0, 0, 0, 0, 0]));
    assert_eq!(r.sdo.len(), 1);
    assert_eq!(r.sdo[0].data()[0], 0x80, "2073h := 0 aborted");
    r.sdo.clear();
}

/// E32 (§11.4): electronic gearing through online communication. The
/// master position 201Eh comes in RPDO2 every 1 ms communication cycle
/// with the SYNC ("It is recommended to set the SYNC 0 time equal to the
/// communication cycle and slow loop"); master resolution 2000 (a
/// 500-line master encoder, cyclic).
#[test]
fn e32_gearing_online() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    // Step 1: 201Eh in an RPDO (RPDO2, instead of 607Ah).
    r.sdo(0x1401, 1, &0x8000_0301u32.to_le_bytes());
    r.sdo(0x1601, 0, &[0]);
    r.sdo(0x1601, 1, &0x201E_0020u32.to_le_bytes());
    r.sdo(0x1601, 0, &[1]);
    r.sdo(0x1401, 1, &0x0000_0301u32.to_le_bytes());
    // Step 2: operational; step 3: mode FFh; step 4: 06h, 07h, 0Fh.
    r.start_remote_node();
    r.modes_of_operation(-1);
    r.enable();
    assert_eq!(r.upload(0x6061, 0, 1), -1, "6061h shows gearing");
    // Steps 5–8.
    r.sdo(0x201D, 0, &1u16.to_le_bytes());
    r.sdo(0x2012, 0, &0x0000_07D0u32.to_le_bytes());
    r.sdo(0x2013, 1, &1i16.to_le_bytes());
    r.sdo(0x2013, 2, &1u16.to_le_bytes());
    let master = |m: i64| Frame::new(0x301, &((m.rem_euclid(2000)) as i32).to_le_bytes());
    // Step 9: the initial master position (1500); the slave holds.
    let mut m = 1500i64;
    for _ in 0..20 {
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    assert_eq!(r.od_i64(0x2017, 0), 1500, "2017h: master actual position");
    let start = r.od_i64(0x6064, 0);
    // A master move before bit 4: not followed.
    for _ in 0..20 {
        m += 10;
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    assert!((r.od_i64(0x6062, 0) - start).abs() <= 1, "not engaged: the slave holds");
    // Step 10: 1Fh starts gearing; step 11: the master moves 20 counts
    // per 1 ms cycle (20 IU), through its 2000-count roll-over.
    r.controlword(0x1F);
    let d0 = r.od_i64(0x6062, 0);
    let cycles = 1000i64;
    for _ in 0..cycles {
        m += 20;
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    assert_eq!(r.od_i64(0x2018, 0), 20, "2018h: master speed 20 increments/sample");
    // "Slave speed equals master position difference per slow loop": the
    // ratio 1/1 takes the master's 20000 counts (ten roll-overs) one for
    // one. The slave lags up to two cycles: the RPDO sent before a SYNC
    // is latched at that SYNC and interpolated over the next 1 ms.
    let lag = 2 * 20;
    let moved = r.od_i64(0x6062, 0) - d0;
    assert!((moved - 20 * cycles).abs() <= lag, "slave demand moved {moved}, master {}", 20 * cycles);
    let v = r.upload(0x606C, 0, 4) as f64;
    assert!((v - 20.0 * FIX).abs() <= ONE_READING_IU, "606Ch {v}, the master's 20 IU");
    // Statusword bit 10 is always 0 in gearing with Halt = 0 (Table
    // 11.1.2).
    assert_eq!(r.sw.unwrap() & (SW_TARGET_REACHED | 0x6F), 0x27, "{:04X?}", r.sw);
    // §11.2.3: 2013h:01 alone does not change the ratio; with 2013h:02
    // written after it, −1/2 reverses at half the master's speed.
    r.sdo(0x2013, 1, &(-1i16).to_le_bytes());
    let d1 = r.od_i64(0x6062, 0);
    for _ in 0..100 {
        m += 20;
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    let moved = r.od_i64(0x6062, 0) - d1;
    assert!((moved - 2000).abs() <= lag, "ratio still 1/1 before 2013h:02: moved {moved}");
    r.sdo(0x2013, 2, &2u16.to_le_bytes());
    let d2 = r.od_i64(0x6062, 0);
    for _ in 0..100 {
        m += 20;
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    let moved = r.od_i64(0x6062, 0) - d2;
    assert!((moved + 1000).abs() <= lag, "ratio −1/2: moved {moved}, −1000 expected");
    // The actual position follows the demand.
    for _ in 0..50 {
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    let p = r.upload(0x6064, 0, 4);
    let dem = r.upload(0x6062, 0, 4);
    assert!((p - dem).abs() <= FEW_COUNTS, "6064h {p}, 6062h {dem}");
}

/// §9.2.3 bit 11: PVT with the buffer run empty after a point whose
/// velocity is not 0 — the drive performs a quick stop and sets 2072h bit
/// 11 (EMCY FF01h); with a last velocity 0 (E27, E28) it stays enabled.
#[test]
fn pvt_empty_buffer_with_speed_quick_stops() {
    let mut r = Rig::new();
    legacy_ip_setup(&mut r, 0x0F);
    r.sdo(0x60C0, 0, &(-1i16).to_le_bytes());
    r.sdo(0x2074, 0, &0xB001u16.to_le_bytes());
    // 1000 counts in 200 ms, ending at 5 counts/ms: then nothing.
    let (x1, x2) = pvt_x(1000, 5 * 256, 200, 1);
    point(&mut r, x1, x2);
    r.emcy.clear();
    r.controlword(0x1F);
    r.run_ms(150);
    assert_eq!(r.sw.unwrap() & 0x6F, 0x27, "moving");
    assert_eq!(r.upload(0x2072, 0, 2) as u16 & (1 << 11), 0);
    r.run_ms(100);
    let st = r.upload(0x2072, 0, 2) as u16;
    assert_ne!(st & (1 << 11), 0, "2072h {st:04X}h: quick stop after buffer empty");
    assert!(ip_status_emcys(&mut r).iter().any(|s| s & (1 << 11) != 0), "FF01h with bit 11");
    // The quick stop left Operation enabled; 605Ah (quick stop option
    // code) decides where it ends: Quick stop active or, as here,
    // Switch on disabled.
    r.run_ms(100);
    let sw = r.sw.unwrap();
    assert!(matches!(sw & 0x6F, 0x07 | 0x40 | 0x60), "statusword {sw:04X}h after the quick stop");
    assert!(r.dn().app.drive.model().velocity().abs() < 1e-3, "at rest");
}

/// E31 (§11.3): electronic gearing through the second encoder input. The
/// master encoder (2000 counts/rev, the same 500-line encoder) is the
/// machine's master encoder (`master_position` of a machine file's
/// `[[node.inputs]]`, here set by the test); 208Dh shows it; the drive's
/// csp stand-in takes the reference at a 1 ms SYNC (the EtherCAT cycle of
/// the example's network).
#[test]
fn e31_gearing_second_encoder() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Steps 2–3: mode FFh, 06h, 07h, 0Fh.
    r.modes_of_operation(-1);
    r.enable();
    // Steps 4–7: 201Dh := 3 (digital: the 2nd encoder), 2012h := 7D0h,
    // 2013h := 1/1.
    r.sdo(0x201D, 0, &3u16.to_le_bytes());
    r.sdo(0x2012, 0, &0x0000_07D0u32.to_le_bytes());
    r.sdo(0x2013, 1, &1i16.to_le_bytes());
    r.sdo(0x2013, 2, &1u16.to_le_bytes());
    let enc = |r: &mut Rig, m: i64| {
        use drivebus_cia402::drive::Injection;
        use drivebus_cia402::model::ModelInjection as Model;
        let id = r.dut;
        let pn = r.bus.node_mut::<PersonalityDevice>(id).unwrap();
        pn.app.inject(Injection::Model(Model::MasterPosition(m.rem_euclid(2000) as f64)));
    };
    // Step 8 (201Eh) is not used with 201Dh = 3: an online master position
    // is ignored.
    r.sdo(0x201E, 0, &500i32.to_le_bytes());
    let mut m = 100i64;
    enc(&mut r, m);
    let sync = |r: &mut Rig| {
        r.bus.send_from(r.probe, Frame::new(0x080, &[]));
        r.run_us(1000);
    };
    for _ in 0..10 {
        sync(&mut r);
    }
    assert_eq!(r.od_i64(0x2017, 0), 100, "2017h: the encoder, not 201Eh");
    assert_eq!(r.upload(0x208D, 0, 4), 100, "208Dh: the auxiliary (second) encoder");
    // Step 9: 1Fh; step 10: the master turns 15 counts per ms for 1 s.
    r.controlword(0x1F);
    let d0 = r.od_i64(0x6062, 0);
    for _ in 0..1000 {
        m += 15;
        enc(&mut r, m);
        sync(&mut r);
    }
    let moved = r.od_i64(0x6062, 0) - d0;
    assert!((moved - 15_000).abs() <= 2 * 15, "slave demand moved {moved}, the master 15000");
    for _ in 0..50 {
        sync(&mut r);
    }
    let p = r.upload(0x6064, 0, 4);
    assert!((p - (d0 + 15_000)).abs() <= FEW_COUNTS, "6064h {p}, 1:1 from where it stood");
}
