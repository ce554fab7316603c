//! Touch probe trigger sources (CiA 402-2 60B8h bits 3–2 / 11–10): 00
//! touch probe input (wired per `IoConfig::probe_inputs`), 01 zero impulse,
//! 10 source per 60D0h. Captures are checked against switch positions
//! placed in the axis (units 0.001°, 1 increment ≈ 0.00034°).

mod drive_rig;
use drive_rig::*;
use drivebus_cia402::drive::{DriveConfig, IoConfig, ProbeInput};
use drivebus_cia402::model::DriveParams;

/// Home switch [100°, 300°], positive limit from 500°, negative limit up
/// to −500°, index pulse at 0.3 rad (17.188 733 9°) of every revolution.
const HOME: (f64, f64) = (100.0, 300.0);
const POS_LIMIT: f64 = 500.0;
const NEG_LIMIT: f64 = -500.0;
const INDEX_DEG: f64 = 0.3 * 180.0 / core::f64::consts::PI;

fn rig(inputs: [ProbeInput; 2], source_object: bool) -> Rig {
    let mut p = DriveParams::servo_small();
    p.encoder.index_angle = 0.3;
    p.axis.home_switch = Some(HOME);
    p.axis.positive_limit = Some(POS_LIMIT);
    p.axis.negative_limit = Some(NEG_LIMIT);
    let mut cfg = DriveConfig::servo(p);
    cfg.io = IoConfig { probe_inputs: inputs, probe_source_object: source_object, ..cfg.io };
    let mut r = Rig::with_config(cfg);
    r.write(0x6060, 0, &[3]); // pv
    r
}

/// Runs at `v` \[0.001°/s\] for `ms`.
fn jog(r: &mut Rig, v: i32, ms: f64) {
    r.write(0x60FF, 0, &v.to_le_bytes());
    r.run_ms(ms);
}

fn near(got: u32, deg: f64) -> bool {
    (f64::from(got as i32) - deg * 1000.0).abs() <= 1.0
}

#[test]
fn default_wiring_is_the_home_switch_for_both_probes() {
    let mut r = rig([ProbeInput::HomeSwitch; 2], true);
    // Probe 1 and 2: enable, first event, touch probe input, both edges.
    r.write(0x60B8, 0, &0x3131u16.to_le_bytes());
    r.enable();
    jog(&mut r, 360_000, 1000.0); // 0 → ~360°: across [100°, 300°]
    assert_eq!(r.read(0x60B9, 0), 0x0707);
    for (idx, deg) in [(0x60BA, HOME.0), (0x60BB, HOME.1), (0x60BC, HOME.0), (0x60BD, HOME.1)] {
        let got = r.read(idx, 0);
        assert!(near(got, deg), "{idx:04X}: {} vs {deg}°", got as i32);
    }
}

#[test]
fn limit_switches_as_probe_inputs() {
    // Touch probe input 1 = positive limit, input 2 = negative limit.
    let mut r = rig([ProbeInput::PositiveLimit, ProbeInput::NegativeLimit], true);
    r.write(0x60B8, 0, &0x3131u16.to_le_bytes());
    r.enable();
    // Positive: the limit stops the axis past 500°; rising edge at 500°.
    jog(&mut r, 360_000, 2000.0);
    assert_eq!(r.read(0x60B9, 0) & 0x0007, 0x0003, "probe 1 rising only");
    assert!(near(r.read(0x60BA, 0), POS_LIMIT), "{}", r.read(0x60BA, 0) as i32);
    // Back and beyond −500°: falling edge of the positive limit, then the
    // negative limit rises for probe 2.
    jog(&mut r, -720_000, 2500.0);
    assert_eq!(r.read(0x60B9, 0), 0x0307);
    assert!(near(r.read(0x60BB, 0), POS_LIMIT), "{}", r.read(0x60BB, 0) as i32);
    assert!(near(r.read(0x60BC, 0), NEG_LIMIT), "{}", r.read(0x60BC, 0) as i32);
}

#[test]
fn zero_impulse_and_60d0_sources() {
    let mut r = rig([ProbeInput::HomeSwitch; 2], true);
    assert_eq!(r.read(0x60D0, 0), 2);
    assert_eq!(r.read(0x60D0, 1), 1);
    r.write_aborts(0x60D0, 1, &3i16.to_le_bytes(), 0x0609_0030);
    r.write_aborts(0x60D0, 2, &(-1i16).to_le_bytes(), 0x0609_0030);
    r.write_aborts(0x60D0, 2, &4i16.to_le_bytes(), 0x0609_0030);
    // Probe 1: 60D0h:1 = 5 (zero impulse) via bits 3–2 = 10b; probe 2:
    // bits 11–10 = 01b (zero impulse) directly. Rising edge, first event.
    r.write(0x60D0, 1, &5i16.to_le_bytes());
    r.write(0x60B8, 0, &(0x0019u16 | 0x1500).to_le_bytes());
    r.enable();
    jog(&mut r, 90_000, 400.0); // 0 → 36°: index at 17.19°
    assert_eq!(r.read(0x60B9, 0), 0x0303);
    assert!(near(r.read(0x60BA, 0), INDEX_DEG), "{}", r.read(0x60BA, 0) as i32);
    assert!(near(r.read(0x60BC, 0), INDEX_DEG), "{}", r.read(0x60BC, 0) as i32);
    // 60D0h:2 = 1: probe 2 (10b) takes touch probe input 1 (home switch).
    r.write(0x60D0, 2, &1i16.to_le_bytes());
    r.write(0x60B8, 0, &0u16.to_le_bytes());
    r.write(0x60B8, 0, &0x3900u16.to_le_bytes());
    jog(&mut r, 360_000, 1000.0);
    assert_eq!(r.read(0x60B9, 0) & 0x0700, 0x0700);
    assert!(near(r.read(0x60BC, 0), HOME.0) && near(r.read(0x60BD, 0), HOME.1));
}

#[test]
fn without_60d0_selection_10b_captures_nothing() {
    // The personality default: no 60D0h from the drive.
    let mut r = rig([ProbeInput::HomeSwitch; 2], false);
    let f = r.sdo_write(0x60D0, 1, &1i16.to_le_bytes());
    assert_eq!(f.data()[0], 0x80, "no 60D0h: {f:?}");
    r.write(0x60B8, 0, &0x0039u16.to_le_bytes());
    r.enable();
    jog(&mut r, 360_000, 1000.0);
    assert_eq!(r.read(0x60B9, 0), 0x0001, "armed, nothing stored");
}

#[test]
fn dedicated_probe_input() {
    let mut r = rig([ProbeInput::Dedicated, ProbeInput::HomeSwitch], true);
    r.write(0x60B8, 0, &0x0033u16.to_le_bytes()); // continuous, both edges
    r.enable();
    jog(&mut r, 90_000, 100.0);
    // The edge is seen at the next control period: the capture is the
    // position then, within one period of motion (90°/s · 125 µs).
    r.drive_mut().set_probe_input(0, true);
    let before = r.drive().position();
    r.run_us(125);
    let after = r.drive().position();
    let got = i64::from(r.read(0x60BA, 0) as i32);
    assert!(got >= before && got <= after + 1, "{before} ≤ {got} ≤ {after}");
    r.run_ms(10.0);
    r.drive_mut().set_probe_input(0, false);
    r.run_us(125);
    let fall = i64::from(r.read(0x60BB, 0) as i32);
    assert!(fall > got, "falling edge later: {fall}");
    assert_eq!(r.read(0x60B9, 0) & 0x7, 0x7);
    // The home switch never reaches probe 1 while it is wired elsewhere.
    r.drive_mut().set_probe_input(5, true); // out of range: ignored
    jog(&mut r, 360_000, 1000.0);
    assert_eq!(r.read(0x60BA, 0) as i32 as i64, got);
}
