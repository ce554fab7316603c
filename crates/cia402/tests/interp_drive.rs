//! csp and ip end to end: the mode handlers plugged into the CiA 402 drive
//! on the virtual bus; targets written by SDO, SYNC frames at 1 kHz.
//! Position units: 0.001° (the generic servo's factor group).

#[path = "drive_rig/mod.rs"]
mod drive_rig;

use drive_rig::{ID, Rig};
use drivebus_can::Frame;
use drivebus_cia402::drive::{DriveConfig, ModeHandler, generic_drive_with};
use drivebus_cia402::interp::{CspMode, CstMode, CsvMode, IpMode};
use drivebus_cia402::model::DriveParams;

fn rig(mode: u8) -> Rig {
    let handlers: Vec<Box<dyn ModeHandler + Send>> = vec![
        Box::new(IpMode::default()),
        Box::new(CspMode::new()),
        Box::new(CsvMode::new()),
        Box::new(CstMode::new()),
    ];
    let cfg = DriveConfig::servo(DriveParams::servo_small());
    let mut rig = Rig::with(generic_drive_with(ID, cfg, handlers));
    rig.start();
    rig.write(0x60C2, 1, &[1]);
    rig.write(0x60C2, 2, &[(-3i8) as u8]); // 1 ms
    rig.write(0x6060, 0, &[mode]);
    rig.enable();
    rig.run_ms(2.0);
    rig
}

/// Writes the set-point, then SYNC, then runs to just before the next SYNC.
fn cycle(rig: &mut Rig, index: u16, sub: u8, value: i32) {
    rig.write(index, sub, &value.to_le_bytes());
    rig.send(Frame::new(0x080, &[]));
    // `write` and `send` each advance 1 µs.
    rig.run_us(997);
}

#[test]
fn csp_ramp_is_followed_with_bit12() {
    let mut rig = rig(8);
    // 90°/s: 90 units (0.001°) per 1 ms cycle, for 0.5 s.
    for k in 1..=500 {
        cycle(&mut rig, 0x607A, 0, 90 * k);
        if k > 5 {
            assert_eq!(rig.drive().statusword() & 0x3000, 0x1000, "follows, no following error");
        }
    }
    let pos = rig.read(0x6064, 0) as i32;
    // Target 45 000; the drive is one cycle behind (44 910) at worst.
    assert!((44_850..=45_010).contains(&pos), "6064h {pos}");
    assert!(rig.emcys().is_empty());
}

#[test]
fn ip_linear_consumes_60c1_at_sync() {
    let mut rig = rig(7);
    rig.controlword(0x1F); // enable ip
    for k in 1..=300 {
        cycle(&mut rig, 0x60C1, 1, 100 * k);
        if k > 2 {
            assert_eq!(rig.drive().statusword() & 0x1000, 0x1000, "ip mode active");
        }
    }
    let pos = rig.read(0x6064, 0) as i32;
    assert!((29_750..=30_010).contains(&pos), "6064h {pos}");
}

/// 60C2h: the linear interpolation spreads each 60C1h step over the
/// interpolation period (4 ms here), not over one control period.
#[test]
fn ip_interpolates_over_the_60c2_period() {
    let mut rig = rig(7);
    rig.write(0x60C2, 1, &[4]); // 4 × 10^-3 s
    rig.controlword(0x1F);
    rig.write(0x60C1, 1, &4000i32.to_le_bytes());
    rig.send(Frame::new(0x080, &[]));
    rig.run_us(2000);
    let half = rig.drive().demand_position();
    assert!((half - 2000.0).abs() < 300.0, "half-way after 2 of 4 ms: {half}");
    rig.run_us(1990);
    let end = rig.drive().demand_position();
    assert!((end - 4000.0).abs() <= 125.0, "at the point after 4 ms (one control period): {end}");
}
