//! `DriveConfig::zero_means_off`: drives whose manual gives 0 a special
//! meaning — Kollmorgen 6065h = 0 "following error monitoring off"
//! (KC1 §7.8.2.3), Technosoft iPOS 6080h = 0 "no speed limit" (§15.2.3).
//! Without the switch 0 keeps its CiA 402-2 meaning (a zero window, a zero
//! limit).

mod drive_rig;
use drive_rig::*;
use drivebus_cia402::drive::{DriveConfig, Injection, ZeroMeansOff};
use drivebus_cia402::model::ModelInjection as M;

/// Enabled in pp with a load above the peak torque dragging the axis away;
/// returns whether the following error fault (8611h) was raised.
fn blocked_load_faults(cfg: DriveConfig, window: u32) -> bool {
    let mut r = Rig::with_config(cfg);
    r.start();
    r.write(0x6065, 0, &window.to_le_bytes());
    r.write(0x6066, 0, &20u16.to_le_bytes());
    r.enable();
    r.run_ms(2.0);
    r.take();
    r.drive_mut().inject(Injection::Model(M::LoadTorqueStep(3.0)));
    r.run_ms(100.0);
    // The dictionary keeps what the master wrote.
    assert_eq!(r.read(0x6065, 0), window);
    r.emcys().contains(&emcy(0x8611, 0x21))
}

#[test]
fn following_window_zero_is_off_when_the_drive_says_so() {
    let cfg = DriveConfig {
        zero_means_off: ZeroMeansOff { following_error_window: true, ..ZeroMeansOff::default() },
        ..DriveConfig::default()
    };
    assert!(!blocked_load_faults(cfg.clone(), 0), "6065h = 0: monitoring off");
    assert!(blocked_load_faults(cfg, 1000), "6065h = 1000: monitored");
    // CiA 402-2 meaning: a zero window faults at once.
    assert!(blocked_load_faults(DriveConfig::default(), 0));
}

#[test]
fn following_window_zero_at_power_on_is_off() {
    let mut cfg = DriveConfig {
        zero_means_off: ZeroMeansOff { following_error_window: true, ..ZeroMeansOff::default() },
        ..DriveConfig::default()
    };
    cfg.profile.following_error_window = 0;
    let mut r = Rig::with_config(cfg);
    r.start();
    r.enable();
    r.run_ms(2.0);
    r.take();
    r.drive_mut().inject(Injection::Model(M::LoadTorqueStep(3.0)));
    r.run_ms(100.0);
    assert_eq!(r.read(0x6065, 0), 0);
    assert!(!r.emcys().contains(&emcy(0x8611, 0x21)));
}

/// pv at `target` velocity with 6080h = `max`; the actual velocity after
/// 300 ms.
fn pv_speed(cfg: DriveConfig, max: u32, target: i32) -> i64 {
    let mut r = Rig::with_config(cfg);
    r.start();
    r.write(0x6060, 0, &[3]);
    r.write(0x6080, 0, &max.to_le_bytes());
    r.write(0x60FF, 0, &target.to_le_bytes());
    r.enable();
    r.run_ms(300.0);
    assert_eq!(r.read(0x6080, 0), max);
    i64::from(r.read(0x606C, 0) as i32)
}

#[test]
fn max_motor_speed_zero_is_no_limit_when_the_drive_says_so() {
    let cfg = DriveConfig {
        zero_means_off: ZeroMeansOff { max_motor_speed: true, ..ZeroMeansOff::default() },
        ..DriveConfig::default()
    };
    let v = pv_speed(cfg.clone(), 0, 360_000);
    assert!((v - 360_000).abs() < 20_000, "6080h = 0: no limit, {v}");
    let v = pv_speed(cfg, 100_000, 360_000);
    assert!((v - 100_000).abs() < 20_000, "6080h limits, {v}");
    // CiA 402-2 meaning: a zero limit holds the motor.
    let v = pv_speed(DriveConfig::default(), 0, 360_000);
    assert!(v.abs() < 20_000, "6080h = 0 limits to 0, {v}");
}

/// 6073h max current 0 limits nothing where the drive says so
/// (Kollmorgen), and blocks the torque where it does not.
#[test]
fn max_current_zero_is_no_limit_when_the_drive_says_so() {
    let demand = |zero_off: bool| {
        let cfg = DriveConfig {
            zero_means_off: ZeroMeansOff { max_current: zero_off, ..ZeroMeansOff::default() },
            ..DriveConfig::default()
        };
        let mut r = Rig::with_config(cfg);
        r.write(0x6060, 0, &[4]);
        r.write(0x6073, 0, &0u16.to_le_bytes());
        r.write(0x6087, 0, &100_000u32.to_le_bytes());
        r.enable();
        r.write(0x6071, 0, &100i16.to_le_bytes());
        r.run_ms(5.0);
        r.read(0x6074, 0) as i16
    };
    assert_eq!(demand(true), 100);
    assert_eq!(demand(false), 0);
}
