//! Factor group (CiA 402-2 §6.4) exactness, digital inputs 60FDh, limit
//! switches, touch probe 60B8h–60BDh, and the ModeHandler plug-in.

mod drive_rig;
use drive_rig::*;
use drivebus_cia402::drive::{
    Carry, DriveConfig, FactorGroup, ModeCommand, ModeHandler, ModeIo, ModeOutput, Ratio, Units,
    generic_drive_with, op,
};
use drivebus_cia402::model::DriveParams;

/// Deterministic pseudo-random moves (64-bit LCG, Knuth's constants).
fn moves(n: usize, seed: u64) -> Vec<i64> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((x >> 33) as i64 % 2_000_000) - 1_000_000
        })
        .collect()
}

#[test]
fn ten_thousand_random_moves_have_zero_drift() {
    // 2^20 increments per 360 000 units, gear 7:3, feed 1000:1 — a
    // non-integer ratio: 2^20·7 / (3·360 000·1000)... reduced.
    let f = FactorGroup { gear: (7, 3), feed: (360_000, 1), ..FactorGroup::increments(1 << 20) };
    let u = Units::new(&f).unwrap();
    let r = u.position_ratio();
    // Analytic reduced ratio: 2^20·7 / (3·360000) = 7340032 / 1080000 = 114688 / 16875.
    assert_eq!(r, Ratio { num: 114_688, den: 16_875 });
    let ms = moves(10_000, 42);
    let mut carry = Carry::default();
    let mut inc: i128 = 0;
    let mut units: i128 = 0;
    for &m in &ms {
        inc += i128::from(carry.delta_to_inc(r, m));
        units += i128::from(m);
        // Absolute conversion of the running sum agrees at every step.
        assert_eq!(inc, (units * 114_688).div_euclid(16_875));
    }
    // And back: the reverse moves return to exactly 0 increments.
    for &m in ms.iter().rev() {
        inc += i128::from(carry.delta_to_inc(r, -m));
    }
    assert_eq!(inc, 0);
    assert_eq!(carry.remainder(), 0);
    // Absolute positions round-trip exactly (increments finer than units).
    for &m in &ms {
        assert_eq!(u.inc_to_pos(u.pos_to_inc(m)), m);
    }
}

#[test]
fn relative_moves_on_the_drive_do_not_drift() {
    let mut r = Rig::generic();
    r.write(0x6081, 0, &36_000_000u32.to_le_bytes());
    r.write(0x6083, 0, &3_600_000_000u32.to_le_bytes());
    r.write(0x6084, 0, &3_600_000_000u32.to_le_bytes());
    r.write(0x6067, 0, &u32::MAX.to_le_bytes()); // window off: reached = profile done
    r.enable();
    let ms = moves(40, 7);
    for &m in ms.iter().chain(ms.iter()) {
        let m = (m / 10) as i32;
        r.write(0x607A, 0, &m.to_le_bytes());
        r.controlword(0x5F);
        r.run_until(25, 10.0, |r| r.drive().statusword() & (1 << 12) != 0).unwrap();
        r.controlword(0x4F);
        r.run_until(125, 2000.0, |r| r.drive().statusword() & (1 << 10) != 0).unwrap();
    }
    let sum: i64 = ms.iter().map(|m| 2 * (m / 10)).sum();
    assert_eq!(r.read(0x6062, 0) as i32 as i64, sum, "demand is the exact sum");
    r.run_ms(50.0);
    let p = r.read(0x6064, 0) as i32 as i64;
    // The servo settles within a few increments (friction, P position loop).
    assert!((p - sum).abs() <= 10, "actual {p} vs {sum}");
}

fn switch_rig() -> Rig {
    let mut p = DriveParams::servo_small();
    p.axis.positive_limit = Some(90.0);
    p.axis.negative_limit = Some(-90.0);
    p.axis.home_switch = Some((45.0, 50.0));
    Rig::with_config(DriveConfig::servo(p))
}

#[test]
fn limit_switch_stops_and_flags_internal_limit() {
    let mut r = switch_rig();
    r.write(0x6060, 0, &[3]);
    r.enable();
    r.write(0x60FF, 0, &360_000i32.to_le_bytes()); // 360°/s
    r.run_ms(400.0);
    let sw = r.drive().statusword();
    // Bit 11 internal limit active, bit 7 warning; 60FDh bit 1.
    assert_eq!(sw & 0x0880, 0x0880, "{sw:04X}");
    assert_eq!(r.read(0x60FD, 0) & 0x7, 0b010);
    let p = r.read(0x6064, 0) as i32;
    assert!((90_000..95_000).contains(&p), "stopped just past the switch: {p}");
    assert!(r.drive().model().velocity().abs() < 1.0);
    // Away from the switch is allowed.
    r.write(0x60FF, 0, &(-360_000i32).to_le_bytes());
    r.run_ms(100.0);
    assert!((r.read(0x6064, 0) as i32) < 80_000);
    assert_eq!(r.drive().statusword() & 0x0880, 0);
}

/// With the limit-switch function off (`Drive::set_limit_switches`) the
/// input still shows in 60FDh, but the motor runs on through it and bits
/// 7/11 stay clear; switched on again, the next approach stops.
#[test]
fn limit_switch_function_can_be_switched_off() {
    let mut r = switch_rig();
    r.drive_mut().set_limit_switches(false);
    r.write(0x6060, 0, &[3]);
    r.enable();
    r.write(0x60FF, 0, &360_000i32.to_le_bytes()); // 360°/s
    r.run_ms(300.0);
    assert_eq!(r.read(0x60FD, 0) & 0x2, 0b010, "the input is read");
    assert_eq!(r.drive().statusword() & 0x0880, 0, "no warning, no internal limit");
    let p = r.read(0x6064, 0) as i32;
    assert!(p > 95_000, "ran through the switch at 90°: {p}");
    r.write(0x60FF, 0, &0i32.to_le_bytes());
    r.run_ms(100.0);
    r.write(0x60FF, 0, &(-360_000i32).to_le_bytes());
    r.run_ms(100.0);
    r.drive_mut().set_limit_switches(true);
    r.write(0x60FF, 0, &360_000i32.to_le_bytes());
    r.run_ms(400.0);
    assert_eq!(r.drive().statusword() & 0x0880, 0x0880, "stops again");
    assert!(r.drive().model().velocity().abs() < 1.0);
}

#[test]
fn limit_switch_fault_option() {
    let mut p = DriveParams::servo_small();
    p.axis.positive_limit = Some(90.0);
    let mut cfg = DriveConfig::servo(p);
    cfg.io.limit_switch = drivebus_cia402::drive::LimitSwitchReaction::Fault;
    let mut r = Rig::with_config(cfg);
    r.start();
    r.write(0x6060, 0, &[3]);
    r.enable();
    r.write(0x60FF, 0, &360_000i32.to_le_bytes());
    r.run_ms(400.0);
    assert_eq!(r.emcys(), vec![emcy(0x8612, 0x21)]);
    assert_eq!(r.read(0x603F, 0), 0x8612);
}

#[test]
fn touch_probe_latches_home_switch_edges() {
    let mut r = switch_rig();
    r.write(0x6060, 0, &[3]);
    // Probe 1: enable, first event, home switch input, rising + falling.
    r.write(0x60B8, 0, &0x0031u16.to_le_bytes());
    assert_eq!(r.read(0x60B9, 0), 0x0001);
    r.enable();
    r.write(0x60FF, 0, &90_000i32.to_le_bytes()); // 90°/s
    r.run_ms(800.0);
    assert_eq!(r.read(0x60B9, 0), 0x0007);
    // Switch at [45°, 50°]: the interpolated edges, 1 increment ≈ 0.00034°.
    let rise = r.read(0x60BA, 0) as i32;
    let fall = r.read(0x60BB, 0) as i32;
    assert!((rise - 45_000).abs() <= 1, "rising edge {rise}");
    assert!((fall - 50_000).abs() <= 1, "falling edge {fall}");
    // Re-arming by disabling and enabling clears the stored bits.
    r.write(0x60B8, 0, &0u16.to_le_bytes());
    assert_eq!(r.read(0x60B9, 0), 0);
}

#[test]
fn touch_probe_on_index_pulse() {
    let mut r = Rig::generic();
    r.write(0x6060, 0, &[3]);
    // Probe 2: enable, continuous, index pulse, rising edge.
    r.write(0x60B8, 0, &0x1700u16.to_le_bytes());
    r.enable();
    r.write(0x60FF, 0, &360_000i32.to_le_bytes());
    r.run_ms(1600.0);
    assert_eq!(r.read(0x60B9, 0) & 0x0700, 0x0300);
    let p = r.read(0x60BC, 0) as i32;
    // Index at angle 0 of every revolution: a multiple of 360°.
    assert!(p > 0 && (p % 360_000 <= 1 || p % 360_000 >= 359_999), "index at {p}");
}

/// A minimal handler for csv (mode 9): velocity from 60FFh, homing-like
/// position reset on controlword bit 4.
struct TestCsv;

impl ModeHandler for TestCsv {
    fn supported_modes(&self) -> u32 {
        op::supported_bit(op::CSV)
    }
    fn enter(&mut self, _mode: i8, _io: &ModeIo<'_>) {}
    fn step(&mut self, _mode: i8, io: &ModeIo<'_>, _dt: f64) -> ModeOutput {
        let v = io.units.velocity_to_frame(f64::from(io.params.target_velocity));
        let mut out = ModeOutput::new(ModeCommand::Velocity { velocity: v, acceleration: 0.0 }, 1 << 12);
        if io.cw_bit(4) {
            out.position_reset = Some(1234);
        }
        out
    }
}

#[test]
fn mode_handler_plugs_in() {
    let dn = generic_drive_with(ID, DriveConfig::default(), vec![Box::new(TestCsv)]);
    let mut r = Rig::with(dn);
    assert_eq!(r.read(0x6502, 0), 0b1111 | 1 << 8);
    r.write(0x6060, 0, &[9]);
    r.enable();
    r.write(0x60FF, 0, &36_000i32.to_le_bytes());
    r.run_ms(100.0);
    assert_ne!(r.drive().statusword() & (1 << 12), 0);
    assert!(r.drive().position() > 0);
    r.write(0x60FF, 0, &0i32.to_le_bytes());
    r.controlword(0x1F);
    r.run_ms(1.0);
    r.controlword(0x0F);
    r.run_ms(1.0);
    let p = r.read(0x6064, 0) as i32;
    assert!((p - 1234).abs() <= 40, "position reset to 1234: {p}");
}

#[test]
fn digital_outputs_follow_the_mask() {
    let mut r = Rig::generic();
    // Default mask 0xFFFF0000: the upper 16 bits are settable.
    r.write(0x60FE, 1, &0x1234_5678u32.to_le_bytes());
    assert_eq!(r.read(0x60FE, 1), 0x1234_0000);
    assert_eq!(r.drive().digital_outputs(), 0x1234_0000);
    r.write(0x60FE, 2, &0xFFFF_FFFFu32.to_le_bytes());
    r.write(0x60FE, 1, &0x1234_5678u32.to_le_bytes());
    assert_eq!(r.read(0x60FE, 1), 0x1234_5678);
}

/// A follower for csp (mode 8): the position is the machine's master
/// encoder, one count per position unit (the plainest electronic gearing).
struct Follower;

impl ModeHandler for Follower {
    fn supported_modes(&self) -> u32 {
        op::supported_bit(op::CSP)
    }
    fn enter(&mut self, _mode: i8, _io: &ModeIo<'_>) {}
    fn step(&mut self, _mode: i8, io: &ModeIo<'_>, _dt: f64) -> ModeOutput {
        let cmd = ModeCommand::Position {
            position: io.master_position as f64,
            velocity: io.master_velocity,
            acceleration: 0.0,
        };
        ModeOutput::new(cmd, 1 << 12)
    }
}

/// Mode handlers see the machine's master encoder (position and speed).
#[test]
fn mode_handlers_see_the_master_encoder() {
    let mut p = DriveParams::servo_small();
    p.io.master_velocity = 36_000.0; // counts/s: 36°/s as followed here
    let dn = generic_drive_with(ID, DriveConfig::servo(p), vec![Box::new(Follower)]);
    let mut r = Rig::with(dn);
    r.write(0x6060, 0, &[8]);
    r.enable();
    r.run_ms(500.0);
    let (master, pos) = (r.drive().model().master_position(), r.read(0x6064, 0) as i32);
    assert!((i64::from(pos) - master).abs() <= 200, "following the master: {pos} vs {master}");
    assert!(master > 17_000, "the master ran: {master}");
}
