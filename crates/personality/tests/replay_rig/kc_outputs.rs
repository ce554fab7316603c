//! The bodies of the Kollmorgen output tests (KC1 §8.1.3, AKD §7.1.4
//! object tables): the position limit switches, the drive-side brake
//! delays and the speed readings.

use super::Rig;
use super::kc_objects::{enable, operational, put};
use drivebus_personality::Profile;

/// 6064h and PLS.STATE 34A3h:4 as the drive published them last.
fn sample(r: &Rig) -> (i64, u16) {
    let od = r.node().od();
    (od.get_i64(0x6064, 0).unwrap(), od.get_u32(0x34A3, 4).unwrap() as u16)
}

/// A pp move to `target` at 1 revolution/s; every millisecond's sample.
fn move_to(r: &mut Rig, target: i32) -> Vec<(i64, u16)> {
    put(r, 0x607A, 0, &target.to_le_bytes());
    put(r, 0x6040, 0, &0x0Fu16.to_le_bytes());
    r.run_ms(2);
    put(r, 0x6040, 0, &0x1Fu16.to_le_bytes());
    let mut out = Vec::new();
    for _ in 0..2600 {
        r.run_ms(1);
        out.push(sample(r));
    }
    assert!((r.position() - target).abs() < 20, "arrived: {}", r.position());
    out
}

/// PLS (34A0h–34A3h): switch 1 is active exactly inside the window from
/// PLS.P1 to PLS.P1 + PLS.WIDTH1; switch 2 (PLS.MODE single-shot) triggers once until
/// PLS.RESET; switch 3 (PLS.T3 = 100 ms) stays active 100 ms from
/// entering its window; a switch not in PLS.EN stays off.
pub fn position_limit_switches(profile: Profile) {
    let mut r = operational(profile);
    for (sub, p, w) in [(1u8, 20_000i32, 10_000i32), (2, 40_000, 1_000), (3, 10_000, 100), (4, 0, 100_000)] {
        put(&mut r, 0x34A0, sub, &p.to_le_bytes());
        put(&mut r, 0x34A1, sub, &w.to_le_bytes());
    }
    put(&mut r, 0x34A2, 3, &100u16.to_le_bytes());
    put(&mut r, 0x34A3, 3, &0b10u16.to_le_bytes());
    put(&mut r, 0x34A3, 1, &0b111u16.to_le_bytes());
    put(&mut r, 0x6081, 0, &36_000u32.to_le_bytes());
    put(&mut r, 0x6083, 0, &360_000u32.to_le_bytes());
    put(&mut r, 0x6084, 0, &360_000u32.to_le_bytes());
    enable(&mut r, 1);
    let forth = move_to(&mut r, 72_000);
    for &(pos, state) in &forth {
        assert_eq!(state & 1 != 0, (20_000..=30_000).contains(&pos), "switch 1 at {pos}: {state:03b}");
        assert_eq!(state & 0b1000, 0, "switch 4 is not enabled");
    }
    let on =
        |s: &[(i64, u16)], bit: u16| s.iter().filter(|x| x.1 & bit != 0).map(|x| x.0).collect::<Vec<_>>();
    let two = on(&forth, 2);
    assert!(!two.is_empty() && two.iter().all(|p| (40_000..=41_000).contains(p)), "switch 2: {two:?}");
    // Timed: from 10000 on for 100 ms at 36000 units/s (≈ 3600 units).
    let three = on(&forth, 4);
    let (first, last) = (three[0], *three.last().unwrap());
    assert!(
        (10_000..10_100).contains(&first) && (13_000..14_200).contains(&last),
        "switch 3: {first}..{last}"
    );
    let back = move_to(&mut r, 0);
    assert!(on(&back, 2).is_empty(), "single-shot: no second trigger");
    assert!(!on(&back, 1).is_empty(), "continuous switch 1 again");
    put(&mut r, 0x34A3, 2, &0b10u16.to_le_bytes());
    let again = move_to(&mut r, 72_000);
    assert!(!on(&again, 2).is_empty(), "re-armed by PLS.RESET");
}

/// MOTOR.TBRAKERLS 366Fh / MOTOR.TBRAKEAPP 366Eh (ms) on a machine whose
/// brake releases in 50 ms and applies in 40 ms: the drive waits its own
/// times instead (the mode starts TBRAKERLS after the enable, the power
/// stage holds TBRAKEAPP after a disable); 0 waits for the brake.
pub fn brake_times(profile: Profile) {
    use drivebus_cia402::model::Demand;
    let run = |times: &[(u16, i32)]| {
        let mut r = super::kc_objects::with_brake(profile);
        for &(i, v) in times {
            put(&mut r, i, 0, &v.to_le_bytes());
        }
        put(&mut r, 0x6083, 0, &36_000_000u32.to_le_bytes());
        put(&mut r, 0x6084, 0, &36_000_000u32.to_le_bytes());
        enable(&mut r, 3);
        put(&mut r, 0x60FF, 0, &600_000i32.to_le_bytes());
        let mut moved = None;
        for ms in 0..400 {
            r.run_ms(1);
            if moved.is_none() && r.pn().app.drive.model().velocity().abs() > 1.0 {
                moved = Some(ms);
            }
        }
        put(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
        r.run_ms(100);
        put(&mut r, 0x6040, 0, &0x07u16.to_le_bytes());
        let mut held = 0;
        for _ in 0..400 {
            r.run_ms(1);
            if matches!(r.pn().app.drive.model().demand(), Demand::Position { .. }) {
                held += 1;
            }
        }
        (moved.expect("the axis moved"), held)
    };
    let (moved, held) = run(&[]);
    assert!((48..=60).contains(&moved), "the brake's 50 ms: {moved}");
    assert!((38..=45).contains(&held), "the brake's 40 ms: {held}");
    let (moved, held) = run(&[(0x366F, 200), (0x366E, 150)]);
    assert!((198..=210).contains(&moved), "TBRAKERLS 200 ms: {moved}");
    assert!((148..=155).contains(&held), "TBRAKEAPP 150 ms: {held}");
}

/// VL.FBFILTER 3407h:1 (rpm × 1000): the speed through a 10 Hz low-pass:
/// at a steady speed the speed, after a quick stop still most of it
/// (τ = 1/(2π·10 Hz) ≈ 16 ms).
pub fn filtered_speed(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x6083, 0, &36_000_000u32.to_le_bytes());
    put(&mut r, 0x6084, 0, &360_000_000u32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &600_000i32.to_le_bytes());
    r.run_ms(500);
    let rpm = r.pn().app.drive.model().velocity_measured() * 30.0 / core::f64::consts::PI;
    let f = |r: &Rig| r.node().od().get_i64(0x3407, 1).unwrap() as f64 / 1000.0;
    assert!((f(&r) - rpm).abs() < rpm * 0.01, "steady: {} vs {rpm} rpm", f(&r));
    put(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    r.run_ms(10);
    let now = r.pn().app.drive.model().velocity_measured().abs() * 30.0 / core::f64::consts::PI;
    assert!(now < rpm * 0.2, "stopped: {now} rpm");
    assert!(f(&r) > rpm * 0.45 && f(&r) < rpm * 0.8, "filtered: {} of {rpm} rpm", f(&r));
}

/// AOUT.VALUEU 3470h:3 (V × 1000) sets the drive's analog output, which
/// the machine sees and AOUT.VALUE 3470h:2 reads (mV).
pub fn analog_output(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x3470, 3, &(-2500i16).to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.pn().app.drive.model().analog_output(), -2.5);
    assert_eq!(super::kc_objects::get(&mut r, 0x3470, 2), -2500);
}

/// AIN.CUTOFF 5000h (Hz): AIN.VALUE 3509h reads the analog input through
/// a first-order low-pass; 0 reads it as it is.
pub fn analog_input_cutoff(profile: Profile) {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Plant;
    let step = |cutoff: u32| {
        let mut r = operational(profile);
        put(&mut r, 0x5000, 0, &cutoff.to_le_bytes());
        r.run_ms(5);
        r.pn_mut().app.inject(Injection::Model(Plant::AnalogInput { channel: 1, volts: 5.0 }));
        r.run_ms(16);
        let at_tau = super::kc_objects::get(&mut r, 0x3509, 0);
        r.run_ms(200);
        (at_tau, super::kc_objects::get(&mut r, 0x3509, 0))
    };
    assert_eq!(step(0), (5000, 5000), "no filter");
    // τ = 1/(2π·10 Hz) ≈ 15.9 ms: 63 % after 16 ms.
    let (at_tau, settled) = step(10);
    assert!((3000..=3400).contains(&at_tau), "10 Hz after 16 ms: {at_tau} mV");
    assert_eq!(settled, 5000);
}

/// HOME.SET 35F0h: the axis is homed where it stands: 6064h reads the
/// home offset 607Ch (HOME.P) and 1002h bit 1 (homed) is set; nothing
/// moves.
pub fn home_set(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x6083, 0, &3_600_000u32.to_le_bytes());
    put(&mut r, 0x6084, 0, &3_600_000u32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &600_000i32.to_le_bytes());
    r.run_ms(100);
    put(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    r.run_ms(300);
    let angle = r.pn().app.drive.model().position();
    assert!(r.position() > 1000, "moved: {}", r.position());
    assert_eq!(super::kc_objects::getu(&mut r, 0x1002, 0) & 2, 0, "not homed");
    put(&mut r, 0x607C, 0, &1234i32.to_le_bytes());
    put(&mut r, 0x35F0, 0, &0i32.to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.position(), 1234, "6064h = HOME.P");
    assert_ne!(super::kc_objects::getu(&mut r, 0x1002, 0) & 2, 0, "1002h bit 1 homed");
    assert!((r.pn().app.drive.model().position() - angle).abs() < 1e-3, "nothing moved");
}

/// FB1.OFFSET 3490h (position units): 6064h reads the feedback plus the
/// offset; a new offset replaces the old one; nothing moves.
pub fn position_offset(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x6083, 0, &3_600_000u32.to_le_bytes());
    put(&mut r, 0x6084, 0, &3_600_000u32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &600_000i32.to_le_bytes());
    r.run_ms(100);
    put(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    r.run_ms(300);
    let p = r.position();
    put(&mut r, 0x3490, 0, &5000i32.to_le_bytes());
    r.run_ms(2);
    assert!((r.position() - (p + 5000)).abs() <= 1, "{} vs {p} + 5000", r.position());
    put(&mut r, 0x3490, 0, &(-2000i32).to_le_bytes());
    r.run_ms(2);
    assert!((r.position() - (p - 2000)).abs() <= 1, "{} vs {p} − 2000", r.position());
    assert_eq!(r.pn().app.drive.model().velocity(), 0.0, "nothing moves");
}
