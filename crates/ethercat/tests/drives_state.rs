//! A line of drives keeps its state: per-slave state directories (1010h
//! stores survive a restart, as with `drivebus serve --state-dir`), and
//! the drives run with no master on the line.

use drivebus_can::{Duration, Instant};
use drivebus_ethercat::Clock;
use drivebus_ethercat::drive::{DriveLine, with_drive};
use drivebus_personality::Profile;

#[test]
fn stores_survive_a_restart_of_the_line() {
    let dir = std::env::temp_dir().join(format!("drivebus-ecat-state-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let line = DriveLine::new().drive(Profile::Ipos).drive(Profile::Generic).state_dir(&dir);
    let host = line.host(Clock::simulated(Instant::ZERO)).unwrap();
    host.advance(Duration::from_millis(5));
    let stored = with_drive(&host, 1, |d| {
        let t = Instant::from_millis(5);
        let mut out = Vec::new();
        let dev = d.app_mut().device_mut();
        dev.write_object(0x6081, 0, &123_456u32.to_le_bytes(), t, &mut out).unwrap();
        // CiA 301 §7.5.2.13: "save" to 1010h:01 stores every parameter.
        dev.write_object(0x1010, 1, b"save", t, &mut out)
    })
    .unwrap();
    assert_eq!(stored, Ok(()));
    drop(host);
    assert!(DriveLine::slave_dir(&dir, 1, Profile::Generic).is_dir());
    let host = line.host(Clock::simulated(Instant::ZERO)).unwrap();
    host.advance(Duration::from_millis(5));
    let v = with_drive(&host, 1, |d| d.app().device().node.od().get_u32(0x6081, 0)).unwrap();
    assert_eq!(v, Some(123_456), "restored at power-on");
    // The iPOS (no 1010h) keeps its power-on value.
    let v = with_drive(&host, 0, |d| d.app().device().node.od().get_u32(0x6081, 0)).unwrap();
    assert_eq!(v, Some(0x0021_0000));
    let _ = std::fs::remove_dir_all(&dir);
}

/// iPOS §4.9.6: 2076h "save current configuration" (the iPOS has no
/// 1010h) stores into the slave's state directory like 1010h:01.
#[test]
fn ipos_2076h_saves_into_the_state_directory() {
    let dir = std::env::temp_dir().join(format!("drivebus-ecat-2076-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let line = DriveLine::new().drive(Profile::Ipos).state_dir(&dir);
    let host = line.host(Clock::simulated(Instant::ZERO)).unwrap();
    host.advance(Duration::from_millis(5));
    let saved = with_drive(&host, 0, |d| {
        let t = Instant::from_millis(5);
        let mut out = Vec::new();
        let dev = d.app_mut().device_mut();
        dev.write_object(0x6081, 0, &0x0005_0000u32.to_le_bytes(), t, &mut out).unwrap();
        dev.write_object(0x2076, 0, &1u16.to_le_bytes(), t, &mut out)
    })
    .unwrap();
    assert_eq!(saved, Ok(()));
    drop(host);
    let host = line.host(Clock::simulated(Instant::ZERO)).unwrap();
    host.advance(Duration::from_millis(5));
    let v = with_drive(&host, 0, |d| d.app().device().node.od().get_u32(0x6081, 0)).unwrap();
    assert_eq!(v, Some(0x0005_0000), "restored at power-on");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn drives_run_without_a_master() {
    let host = DriveLine::new().drive(Profile::Ipos).host(Clock::simulated(Instant::ZERO)).unwrap();
    host.advance(Duration::from_millis(10));
    let before = with_drive(&host, 0, |d| d.app().device().app.drive.steps()).unwrap();
    host.advance(Duration::from_secs(1));
    let after = with_drive(&host, 0, |d| d.app().device().app.drive.steps()).unwrap();
    let period = with_drive(&host, 0, |d| d.app().device().app.drive.control_period()).unwrap();
    // One second of control periods, give or take the last partial one.
    let expected = (1.0 / period).round() as u64;
    assert!(
        after - before >= expected - 1 && after - before <= expected + 1,
        "{before} → {after}, {expected}"
    );
}
