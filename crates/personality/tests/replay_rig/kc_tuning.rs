//! The bodies of the Kollmorgen tuning, motor and limit parameter tests
//! (KC1 §8.1.3, AKD §7.1.4 object tables; the float scale 1000:1 of the
//! §8.1.3 preamble): a parameter written by SDO changes what the motor
//! does on the virtual bus.

use super::Rig;
use super::kc_objects::{ID, emcy, emcys_after, enable, get, getu, operational, put, refused};
use drivebus_cia402::drive::Injection;
use drivebus_cia402::model::ModelInjection;
use drivebus_personality::Profile;

/// `profile` on a machine with a holding brake of 20 N·m, applied by
/// MOTOR.BRAKERLS 3450h = 2 whatever the drive does: the rotor is blocked.
fn braked(profile: Profile) -> Rig {
    let text =
        "[[node]]\nid = 3\n[node.brake]\nrelease_delay = 0.0\napply_delay = 0.0\nholding_torque = 20.0\n";
    let file = drivebus_personality::machine::MachineFile::parse(text).unwrap();
    let m = file.machine_for(profile, ID).unwrap();
    let (mut r, _) = Rig::with(profile.build_on(ID, &m).unwrap());
    r.send("000#0103");
    r.run_ms(5);
    put(&mut r, 0x3450, 0, &[2]);
    r
}

/// The model's true speed \[rad/s\].
fn speed(r: &Rig) -> f64 {
    r.pn().app.drive.model().velocity()
}

/// A 2-revolution pp move (72000 units, fast ramps) after `setup`; the
/// largest |demand − actual| seen, in position units.
fn pp_following_error(profile: Profile, setup: &[(u16, u8, u32)]) -> f64 {
    let mut r = operational(profile);
    for &(i, s, v) in setup {
        put(&mut r, i, s, &v.to_le_bytes());
    }
    put(&mut r, 0x6083, 0, &3_600_000u32.to_le_bytes());
    put(&mut r, 0x6084, 0, &3_600_000u32.to_le_bytes());
    put(&mut r, 0x6081, 0, &360_000u32.to_le_bytes());
    enable(&mut r, 1);
    put(&mut r, 0x607A, 0, &72_000i32.to_le_bytes());
    put(&mut r, 0x6040, 0, &0x1Fu16.to_le_bytes());
    let mut worst: f64 = 0.0;
    for _ in 0..800 {
        r.run_ms(1);
        let d = &r.pn().app.drive;
        worst = worst.max((d.demand_position() - d.position() as f64).abs());
    }
    assert!((r.position() - 72_000).abs() < 50, "arrived: {}", r.position());
    worst
}

/// PL.KP 3542h (1/s × 1000): a stiffer position loop follows closer
/// (velocity feed-forward off, VL.KVFF = 0.001, so the gain alone acts);
/// 0 restores the machine's gain.
pub fn position_gain(profile: Profile) {
    const NO_FF: (u16, u8, u32) = (0x354B, 0, 1);
    let soft = pp_following_error(profile, &[NO_FF, (0x3542, 0, 20_000)]);
    let stiff = pp_following_error(profile, &[NO_FF, (0x3542, 0, 300_000)]);
    assert!(stiff < soft / 5.0, "PL.KP 300/s: {stiff}, 20/s: {soft}");
    let own = pp_following_error(profile, &[NO_FF]);
    let back = pp_following_error(profile, &[NO_FF, (0x3542, 0, 20_000), (0x3542, 0, 0)]);
    assert_eq!(back, own, "PL.KP = 0 is the machine's gain");
}

/// VL.KVFF 354Bh and 3407h:2 (× 1000): the velocity feed-forward's share;
/// less of it lags more. Both objects are the one parameter.
pub fn velocity_feedforward(profile: Profile) {
    let full = pp_following_error(profile, &[]);
    let tenth = pp_following_error(profile, &[(0x354B, 0, 100)]);
    assert!(tenth > full * 3.0, "VL.KVFF 0.1: {tenth}, 1: {full}");
    let other = pp_following_error(profile, &[(0x3407, 2, 100)]);
    assert_eq!(other, tenth, "3407h:2 is VL.KVFF too");
    let mut r = operational(profile);
    put(&mut r, 0x3407, 2, &250u32.to_le_bytes());
    assert_eq!(get(&mut r, 0x354B, 0), 250, "354Bh follows 3407h:2");
    assert_eq!(refused(&mut r, 0x354B, 0, &(-1i32).to_le_bytes()), 0x0609_0032);
}

/// pv at 1000 rpm, a load torque step of −0.3 N·m: the largest speed
/// drop \[rad/s\] in 100 ms after `setup`.
fn speed_sag(profile: Profile, setup: &[(u16, u32)]) -> f64 {
    let mut r = operational(profile);
    for &(i, v) in setup {
        put(&mut r, i, 0, &v.to_le_bytes());
    }
    put(&mut r, 0x6083, 0, &3_600_000u32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &600_000i32.to_le_bytes());
    r.run_ms(300);
    let v0 = speed(&r);
    assert!(v0 > 50.0, "running: {v0} rad/s");
    r.pn_mut().app.inject(Injection::Model(ModelInjection::LoadTorqueStep(-0.3)));
    let mut worst: f64 = 0.0;
    for _ in 0..100 {
        r.run_ms(1);
        worst = worst.max(v0 - speed(&r));
    }
    worst
}

/// VL.KP 3548h (A/(rad/s) × 1000): a stiffer velocity loop sags less
/// under a load step.
pub fn velocity_gain(profile: Profile) {
    let soft = speed_sag(profile, &[(0x3548, 20)]);
    let stiff = speed_sag(profile, &[(0x3548, 200)]);
    assert!(stiff < soft / 3.0, "VL.KP 0.2: {stiff}, 0.02: {soft}");
}

/// VL.KI 354Dh (Hz × 1000): the integral removes the speed error of a
/// load step; a low corner frequency leaves it standing longer.
pub fn velocity_integral(profile: Profile) {
    let error_after = |ki: u32| {
        let mut r = operational(profile);
        put(&mut r, 0x354D, 0, &ki.to_le_bytes());
        put(&mut r, 0x6083, 0, &3_600_000u32.to_le_bytes());
        enable(&mut r, 3);
        put(&mut r, 0x60FF, 0, &600_000i32.to_le_bytes());
        r.run_ms(300);
        let v0 = speed(&r);
        r.pn_mut().app.inject(Injection::Model(ModelInjection::LoadTorqueStep(-0.3)));
        r.run_ms(60);
        v0 - speed(&r)
    };
    let (slow, fast) = (error_after(1_000), error_after(100_000));
    assert!(fast < slow / 5.0, "VL.KI 100 Hz: {fast} rad/s, 1 Hz: {slow} rad/s");
}

/// tq at `torque` ‰ for 20 ms after `setup`: the model's speed \[rad/s\]
/// (the torque ramps at 6087h, 10000 ‰/s by default).
fn torque_run(profile: Profile, setup: &[(u16, u32)], torque: i16) -> (Rig, f64) {
    let mut r = operational(profile);
    for &(i, v) in setup {
        put(&mut r, i, 0, &v.to_le_bytes());
    }
    enable(&mut r, 4);
    put(&mut r, 0x6071, 0, &torque.to_le_bytes());
    r.run_ms(20);
    let v = speed(&r);
    (r, v)
}

/// MOTOR.INERTIA 35ABh (kg·cm² × 1000) and LOAD.INERTIA 525Fh (kg·cm²):
/// more inertia accelerates slower at the same current.
pub fn inertia(profile: Profile) {
    let (r, light) = torque_run(profile, &[], 200);
    let rotor = r.pn().app.drive.config().params.motor.rotor_inertia;
    let total = r.pn().app.drive.model().inertia();
    // Four times the rotor's inertia (kg·m² = 10⁴ kg·cm²).
    let obj = (4.0 * rotor * 1e4 * 1000.0).round() as u32;
    let (_, heavy) = torque_run(profile, &[(0x35AB, obj)], 200);
    let expect = (total + 3.0 * rotor) / total;
    assert!((light / heavy / expect - 1.0).abs() < 0.05, "{light} / {heavy} vs {expect}");
    let (r, loaded) = torque_run(profile, &[(0x525F, 1)], 200);
    let j = r.pn().app.drive.model().inertia();
    assert!((j - (rotor + 1e-4)).abs() < 1e-9, "1 kg·cm² of load: {j}");
    assert!(loaded < light / 2.0, "{loaded} vs {light}");
}

/// MOTOR.KT 3593h (N·m/A × 1000): the same current makes more torque;
/// the rated torque (the unit of 6071h/6077h) follows.
pub fn torque_constant(profile: Profile) {
    let (r, _) = torque_run(profile, &[], 200);
    let (t1, i1) = (r.pn().app.drive.model().torque(), r.pn().app.drive.model().current());
    let kt = r.pn().app.drive.config().params.motor.kt;
    let obj = (2.0 * kt * 1000.0).round() as u32;
    let (mut r, _) = torque_run(profile, &[(0x3593, obj)], 200);
    let (t2, i2) = (r.pn().app.drive.model().torque(), r.pn().app.drive.model().current());
    assert!((t2 / t1 - 2.0).abs() < 0.01, "twice the torque: {t2} vs {t1} N·m");
    assert!((i2 / i1 - 1.0).abs() < 0.01, "at the same current: {i2} vs {i1} A");
    // The rated torque doubled with it: 6077h reads the same ‰.
    assert!((get(&mut r, 0x6077, 0) - 200).abs() <= 2, "6077h: {}", get(&mut r, 0x6077, 0));
}

/// MOTOR.R 3456h (Ω × 1000): the winding heats with R·i².
pub fn winding_resistance(profile: Profile) {
    let heat = |setup: &[(u16, u32)]| {
        let (mut r, _) = torque_run(profile, setup, 50);
        r.run_ms(200);
        let m = r.pn().app.drive.model();
        m.temperature() - m.params().motor.ambient_temperature
    };
    let (r, _) = torque_run(profile, &[], 0);
    let ohm = r.pn().app.drive.config().params.motor.resistance;
    let base = heat(&[]);
    let hot = heat(&[(0x3456, (4.0 * ohm * 1000.0).round() as u32)]);
    assert!(base > 0.0 && (hot / base - 4.0).abs() < 0.2, "R×4: {hot} vs {base} K");
}

/// MOTOR.KE 5260h (V/krpm): more back-EMF, the bus voltage runs out at a
/// lower speed.
pub fn back_emf(profile: Profile) {
    let top = |setup: &[(u16, u32)]| {
        let mut r = operational(profile);
        for &(i, v) in setup {
            put(&mut r, i, 0, &v.to_le_bytes());
        }
        put(&mut r, 0x6083, 0, &36_000_000u32.to_le_bytes());
        enable(&mut r, 3);
        put(&mut r, 0x60FF, 0, &100_000_000i32.to_le_bytes());
        r.run_ms(500);
        speed(&r)
    };
    let (own, strong) = (top(&[]), top(&[(0x5260, 100)]));
    let (r, _) = torque_run(profile, &[], 0);
    let bus = r.pn().app.drive.model().bus_voltage();
    let limit = bus / (100.0 / (1000.0 * core::f64::consts::PI / 30.0));
    assert!(
        strong < limit * 1.02 && strong < own * 0.8,
        "KE 100 V/krpm: {strong} rad/s (≤ {limit}), own {own}"
    );
}

/// IL.LIMITP 356Eh / IL.LIMITN 356Fh (A × 1000): the current per
/// direction; AKD 60E0h/60E1h read them in ‰ of the rated current.
pub fn current_limits(profile: Profile) {
    let mut r = braked(profile);
    let rated = r.pn().app.drive.config().params.motor.rated_current;
    put(&mut r, 0x356E, 0, &1000i32.to_le_bytes());
    put(&mut r, 0x356F, 0, &(-500i32).to_le_bytes());
    enable(&mut r, 4);
    put(&mut r, 0x6071, 0, &3000i16.to_le_bytes());
    r.run_ms(400);
    let i = r.pn().app.drive.model().current();
    assert!((i - 1.0).abs() < 0.01, "positive: {i} A");
    put(&mut r, 0x6071, 0, &(-3000i16).to_le_bytes());
    r.run_ms(700);
    let i = r.pn().app.drive.model().current();
    assert!((i + 0.5).abs() < 0.01, "negative: {i} A");
    if r.node().od().get(0x60E0, 0).is_some() {
        assert_eq!(getu(&mut r, 0x60E0, 0), (1000.0 / rated).round() as u64, "60E0h ‰");
        assert_eq!(getu(&mut r, 0x60E1, 0), (500.0 / rated).round() as u64, "60E1h ‰");
    }
}

/// VL.LIMITP 3622h / VL.LIMITN 3623h (rpm): the speed per direction.
pub fn velocity_limits(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x3622, 0, &1000i32.to_le_bytes());
    put(&mut r, 0x3623, 0, &(-500i32).to_le_bytes());
    put(&mut r, 0x6083, 0, &36_000_000u32.to_le_bytes());
    put(&mut r, 0x6084, 0, &36_000_000u32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &100_000_000i32.to_le_bytes());
    r.run_ms(300);
    let rpm = speed(&r) * 30.0 / core::f64::consts::PI;
    assert!((rpm - 1000.0).abs() < 20.0, "positive: {rpm} rpm");
    put(&mut r, 0x60FF, 0, &(-100_000_000i32).to_le_bytes());
    r.run_ms(300);
    let rpm = speed(&r) * 30.0 / core::f64::consts::PI;
    assert!((rpm + 500.0).abs() < 20.0, "negative: {rpm} rpm");
}

/// The blocked rotor pushed at three times the rated torque (tq):
/// with MOTOR.CTF0 3454h giving a 0.1 s coil time constant the foldback
/// (IL.IFOLD 3425h, IL.MIFOLD 35A4h, mA) falls to the continuous current
/// (MOTOR.ICONT); IL.MI2T 3427h:3 reads the I²t load (%); below
/// IL.FOLDWTHRESH 355Ah warning n304 (EMCY 8381h), below IL.FOLDFTHRESHU
/// 3421h fault F304 (EMCY 8311h).
pub fn foldback(profile: Profile) {
    let held = |ctf0: u32| {
        let mut r = braked(profile);
        if ctf0 > 0 {
            put(&mut r, 0x3454, 0, &ctf0.to_le_bytes());
        }
        enable(&mut r, 4);
        put(&mut r, 0x6071, 0, &3000i16.to_le_bytes());
        r
    };
    // 1/(2π·0.1 s) = 1.5915 Hz = 1591.5 mHz, × 1000.
    const CTF0: u32 = 1_591_549;
    let mut r = held(0);
    r.run_ms(500);
    let peak = r.pn().app.drive.config().params.motor.max_current;
    assert_eq!(
        getu(&mut r, 0x3425, 0),
        (peak * 1000.0).round() as u64,
        "the machine's coil: no foldback yet"
    );
    let mut r = held(CTF0);
    put(&mut r, 0x355A, 0, &3000i32.to_le_bytes());
    let e = emcys_after(&mut r, 1000);
    let icont = r.pn().app.drive.config().params.motor.rated_current;
    let ifold = getu(&mut r, 0x3425, 0) as f64 / 1000.0;
    assert!((ifold - icont).abs() < 0.1, "IL.IFOLD {ifold} A → MOTOR.ICONT {icont} A");
    assert_eq!(getu(&mut r, 0x35A4, 0) as f64 / 1000.0, ifold, "IL.MIFOLD");
    assert!(getu(&mut r, 0x3427, 3) >= 100, "IL.MI2T at or above the continuous rating");
    let i = r.pn().app.drive.model().current().abs();
    assert!(i < icont * 1.1, "the current folded back: {i} A");
    assert!(e.contains(&emcy(0x8381, 0x80)), "n304: {e:?}");
    assert_eq!(getu(&mut r, 0x2000, 1), 304, "2000h:1");
    assert_eq!(r.statusword() & 0x6F, 0x27, "a warning only");
    put(&mut r, 0x3421, 0, &2000u32.to_le_bytes());
    let e = emcys_after(&mut r, 5);
    assert!(e.contains(&emcy(0x8311, 0x80)), "F304: {e:?}");
    assert_eq!(getu(&mut r, 0x2001, 1), 304, "2001h:1");
}

/// IL.OFFSET 3423h (A × 1000): a constant current added to the command
/// (tq 0 on a blocked rotor drives it); IL.FRICTION 3422h (A × 1000): a
/// current in the direction the motor turns.
pub fn current_feedforward(profile: Profile) {
    let mut r = braked(profile);
    put(&mut r, 0x3423, 0, &(-500i32).to_le_bytes());
    enable(&mut r, 4);
    put(&mut r, 0x6071, 0, &0i16.to_le_bytes());
    r.run_ms(20);
    let i = r.pn().app.drive.model().current();
    assert!((i + 0.5).abs() < 0.01, "IL.OFFSET −0.5 A: {i} A");
    // Spinning at 1000 rpm, then tq 0: friction compensation only.
    let spin = |friction: u32| {
        let mut r = operational(profile);
        put(&mut r, 0x3422, 0, &friction.to_le_bytes());
        put(&mut r, 0x6083, 0, &36_000_000u32.to_le_bytes());
        enable(&mut r, 3);
        put(&mut r, 0x60FF, 0, &(-1_000_000i32).to_le_bytes());
        r.run_ms(300);
        put(&mut r, 0x6071, 0, &0i16.to_le_bytes());
        put(&mut r, 0x6060, 0, &[4]);
        r.run_ms(50);
        r.pn().app.drive.model().current()
    };
    let (none, comp) = (spin(0), spin(300));
    assert!(
        none.abs() < 0.02 && (comp + 0.3).abs() < 0.02,
        "IL.FRICTION 0.3 A turning negative: {comp} (none {none})"
    );
}

/// IL.KP 3598h (V/A × 1000) with MOTOR.LQLL 3455h (mH × 1000): the
/// current loop's time constant LQLL / IL.KP (5 ms here): the current of
/// a blocked rotor rises that slowly.
pub fn current_loop_gain(profile: Profile) {
    let rise = |setup: &[(u16, u32)]| {
        let mut r = braked(profile);
        for &(i, v) in setup {
            put(&mut r, i, 0, &v.to_le_bytes());
        }
        put(&mut r, 0x6083, 0, &3_600_000_000u32.to_le_bytes());
        enable(&mut r, 3);
        put(&mut r, 0x60FF, 0, &1_000_000i32.to_le_bytes());
        r.run_ms(2);
        r.pn().app.drive.model().current()
    };
    let peak = operational(profile).pn().app.drive.config().params.motor.max_current;
    let (fast, slow) = (rise(&[]), rise(&[(0x3455, 50_000), (0x3598, 10_000)]));
    assert!(fast > 0.95 * peak, "the machine's loop: {fast} A");
    assert!(slow < 0.5 * peak && slow > 0.1 * peak, "τ = 5 ms: {slow} A of {peak}");
    let only_kp = rise(&[(0x3598, 10_000)]);
    assert!(only_kp > 0.95 * peak, "IL.KP without MOTOR.LQLL: the machine's loop ({only_kp} A)");
}

/// MOTOR.VOLTMAX 3452h (V): the voltage the motor gets, so its speed ends
/// at VOLTMAX / kₑ.
pub fn motor_voltage(profile: Profile) {
    let mut r = operational(profile);
    let ke = r.pn().app.drive.config().params.motor.ke;
    put(&mut r, 0x3452, 0, &100u16.to_le_bytes());
    put(&mut r, 0x6083, 0, &36_000_000u32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &100_000_000i32.to_le_bytes());
    r.run_ms(500);
    let v = speed(&r);
    assert!(v < 100.0 / ke && v > 0.8 * 100.0 / ke, "{v} rad/s, 100 V / {ke}");
}

/// REGEN.POWER 3416h (W): braking a large inertia (LOAD.INERTIA 10
/// kg·cm²) from 3000 rpm charges the DC bus into the braking resistor,
/// whose power it reads; motoring it reads 0.
pub fn regen_power(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x525F, 0, &10u32.to_le_bytes());
    put(&mut r, 0x6083, 0, &3_600_000_000u32.to_le_bytes());
    put(&mut r, 0x6084, 0, &3_600_000_000u32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &3_000_000i32.to_le_bytes());
    r.run_ms(600);
    assert_eq!(getu(&mut r, 0x3416, 0), 0, "motoring");
    put(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    let mut peak = 0;
    for _ in 0..300 {
        r.run_ms(1);
        peak = peak.max(r.node().od().get_u32(0x3416, 0).unwrap());
    }
    assert!(peak > 50, "braking into the resistor: {peak} W");
}
