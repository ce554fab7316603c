//! pp with 6086h = 3 (jerk-limited ramp, CiA 402-2 motion profile type)
//! on the virtual bus: 60A4h profile jerk, analytic S-curve duration,
//! sampled limits, change set immediately on an S-curve, the iPOS-style
//! refusal of bit 5 (`scurve_forbids_change_immediately`), and the opt-in
//! configuration personalities use.

mod drive_rig;
use drive_rig::*;
use drivebus_cia402::drive::{DriveConfig, ProfileJerk, profile_type};

const V: u32 = 360_000; // 360°/s in 0.001°/s
const A: u32 = 3_600_000; // 3600°/s²
const J: u32 = 72_000_000; // 72 000°/s³: 50 ms to full acceleration
const SW_ACK: u16 = 1 << 12;
const SW_REACHED: u16 = 1 << 10;
const SW_WARNING: u16 = 1 << 7;

/// Rest-to-rest S-curve with a = d and one jerk j, long enough to reach
/// v and a: T = D/v + v/a + a/j (written out, not the planner's code).
fn s_curve_time(dist: f64, v: f64, a: f64, j: f64) -> f64 {
    assert!(dist >= v * (v / a + a / j) && v * j >= a * a, "test case must cruise");
    dist / v + v / a + a / j
}

fn configure(r: &mut Rig) {
    r.write(0x6081, 0, &V.to_le_bytes());
    r.write(0x6083, 0, &A.to_le_bytes());
    r.write(0x6084, 0, &A.to_le_bytes());
    r.write(0x60A4, 1, &J.to_le_bytes());
    r.write(0x60A4, 2, &J.to_le_bytes());
    r.write(0x6086, 0, &3i16.to_le_bytes());
    r.write(0x6067, 0, &360u32.to_le_bytes());
    r.write(0x6068, 0, &0u16.to_le_bytes());
    r.enable();
    r.run_ms(1.0);
}

fn rig() -> Rig {
    let mut r = Rig::generic();
    configure(&mut r);
    r
}

fn sw(r: &Rig) -> u16 {
    r.drive().statusword()
}

#[test]
fn objects_and_write_validation() {
    let mut r = Rig::generic();
    assert_eq!(r.read(0x60A4, 0), 2, "60A4h sub 0");
    r.write_aborts(0x60A4, 1, &0u32.to_le_bytes(), 0x0609_0032);
    r.write(0x60A4, 2, &u32::MAX.to_le_bytes());
    r.write(0x6086, 0, &3i16.to_le_bytes());
    assert_eq!(r.read(0x6086, 0), 3);
    for bad in [2i16, 4, -1, i16::MIN, i16::MAX] {
        r.write_aborts(0x6086, 0, &bad.to_le_bytes(), 0x0609_0030);
    }
    r.write(0x6086, 0, &0i16.to_le_bytes());
}

#[test]
fn scurve_move_duration_and_limits() {
    let mut r = rig();
    let dist: i32 = 720_000; // 720°
    r.write(0x607A, 0, &dist.to_le_bytes());
    r.controlword(0x1F);
    let dt = r.drive().control_period();
    let (mut v_prev, mut a_prev) = (0.0f64, 0.0f64);
    let (mut a_max, mut j_max, mut v_max) = (0.0f64, 0.0f64, 0.0f64);
    let mut steps = 0u32;
    let mut started = None;
    let mut done = None;
    while steps < 40_000 {
        r.run_us(125);
        steps += 1;
        if sw(&r) & SW_ACK != 0 {
            r.controlword(0x0F);
        }
        let (p, v) = (r.drive().demand_position(), r.drive().demand_velocity());
        if started.is_none() && p != 0.0 {
            started = Some(steps - 1);
        }
        let a = (v - v_prev) / dt;
        v_max = v_max.max(v.abs());
        a_max = a_max.max(a.abs());
        if steps > 1 {
            j_max = j_max.max((a - a_prev).abs() / dt);
        }
        (v_prev, a_prev) = (v, a);
        if done.is_none() && p == f64::from(dist) {
            done = Some(steps);
            break;
        }
    }
    let t = f64::from(done.expect("target") - started.expect("moved")) * dt;
    let expect = s_curve_time(f64::from(dist), f64::from(V), f64::from(A), f64::from(J));
    eprintln!("S-curve 720°: {t:.6} s, analytic {expect:.6} s");
    assert!((t - expect).abs() <= 2.0 * dt, "{t} vs {expect}");
    // Per-period differences of the demand: mean values, so within limits.
    assert!(v_max <= f64::from(V) * (1.0 + 1e-9), "v {v_max}");
    assert!(a_max <= f64::from(A) * (1.0 + 1e-6), "a {a_max}");
    assert!(j_max <= f64::from(J) * (1.0 + 1e-3), "j {j_max}");
    let reached = r.run_until(125, 200.0, |r| sw(r) & SW_REACHED != 0);
    assert!(reached.is_some(), "target reached");
    let pos = r.read(0x6064, 0) as i32;
    assert!((pos - dist).abs() <= 2, "6064h {pos}");
    // The same move with the linear ramp is shorter by a/j (= 50 ms).
    let lin = f64::from(dist) / f64::from(V) + f64::from(V) / f64::from(A);
    assert!((expect - lin - f64::from(A) / f64::from(J)).abs() < 1e-12);
}

#[test]
fn change_immediately_replans_continuously() {
    // CiA 402-2 pp bit 5 with the S-curve: the new target is planned from
    // the present position, velocity and acceleration.
    let mut r = rig();
    r.write(0x607A, 0, &3_600_000i32.to_le_bytes());
    r.controlword(0x1F);
    r.run_until(25, 5.0, |r| sw(r) & SW_ACK != 0).expect("ack");
    r.controlword(0x0F);
    r.run_ms(300.0);
    let dt = r.drive().control_period();
    r.write(0x607A, 0, &(-100_000i32).to_le_bytes());
    r.controlword(0x3F);
    let mut v_prev = r.drive().demand_velocity();
    let mut a_prev: Option<f64> = None;
    let mut acked = false;
    for _ in 0..40_000 {
        r.run_us(125);
        if !acked && sw(&r) & SW_ACK != 0 {
            r.controlword(0x2F);
            acked = true;
        }
        let v = r.drive().demand_velocity();
        let a = (v - v_prev) / dt;
        assert!(a.abs() <= f64::from(A) * (1.0 + 1e-6), "acceleration {a}");
        if let Some(ap) = a_prev {
            assert!((a - ap).abs() / dt <= f64::from(J) * (1.0 + 1e-3), "jerk {}", (a - ap) / dt);
        }
        (v_prev, a_prev) = (v, Some(a));
        if r.drive().demand_position() == -100_000.0 && v == 0.0 {
            break;
        }
    }
    assert!(acked);
    assert_eq!(r.drive().demand_position(), -100_000.0);
}

#[test]
fn ipos_rule_refuses_bit5_with_scurve() {
    let cfg = DriveConfig { scurve_forbids_change_immediately: Some(0x9000), ..DriveConfig::default() };
    let mut r = Rig::with_config(cfg);
    configure(&mut r);
    r.take();
    r.write(0x607A, 0, &100_000i32.to_le_bytes());
    r.controlword(0x3F);
    r.run_ms(5.0);
    assert_eq!(sw(&r) & SW_ACK, 0, "not acknowledged");
    assert_ne!(sw(&r) & SW_WARNING, 0, "warning");
    assert_eq!(r.drive().demand_position(), 0.0, "no motion");
    assert_eq!(r.emcys(), vec![emcy(0x9000, 0x01)]);
    // Fault reset clears the latched command error.
    r.controlword(0x0F);
    r.controlword(0x8F);
    r.controlword(0x0F);
    assert_eq!(sw(&r) & SW_WARNING, 0);
    // Bit 5 = 0 is fine; with the linear ramp bit 5 is fine too.
    r.controlword(0x1F);
    r.run_until(25, 5.0, |r| sw(r) & SW_ACK != 0).expect("ack");
    r.controlword(0x0F);
    r.write(0x6086, 0, &0i16.to_le_bytes());
    r.run_ms(2.0);
    r.write(0x607A, 0, &0i32.to_le_bytes());
    r.controlword(0x3F);
    r.run_until(25, 5.0, |r| sw(r) & SW_ACK != 0).expect("ack with the linear ramp");
}

#[test]
fn jerk_time_setter_and_personality_defaults() {
    // What a personality gets without opting in: no 60A4h, 6086h ∈ {0, 1}.
    let cfg = DriveConfig {
        motion_profile_types: profile_type::LINEAR | profile_type::SIN_SQUARED,
        profile_jerk_object: false,
        ..DriveConfig::default()
    };
    let mut r = Rig::with_config(cfg.clone());
    r.write_aborts(0x6086, 0, &3i16.to_le_bytes(), 0x0609_0030);
    let f = r.sdo_write(0x60A4, 1, &J.to_le_bytes());
    assert_eq!(f.data()[0], 0x80, "no 60A4h: {f:?}");
    // Opting into the S-curve without 60A4h: the jerk comes from the
    // personality (a jerk time, as iPOS 2023h).
    let cfg = DriveConfig { motion_profile_types: profile_type::IMPLEMENTED, ..cfg };
    let mut r = Rig::with_config(cfg);
    {
        let dn = r.dn_mut();
        dn.app.set_profile_jerk(dn.node.od_mut(), ProfileJerk::Time(0.05));
    }
    r.write(0x6081, 0, &V.to_le_bytes());
    r.write(0x6083, 0, &A.to_le_bytes());
    r.write(0x6084, 0, &A.to_le_bytes());
    r.write(0x6086, 0, &3i16.to_le_bytes());
    r.enable();
    r.run_ms(1.0);
    let dist: i32 = 720_000;
    r.write(0x607A, 0, &dist.to_le_bytes());
    r.controlword(0x1F);
    let t = r.run_until(125, 3000.0, |r| r.drive().demand_position() == f64::from(dist)).unwrap();
    // j = a / 50 ms = J: the same analytic duration.
    let expect = s_curve_time(f64::from(dist), f64::from(V), f64::from(A), f64::from(J));
    assert!((t - expect).abs() <= 3.0 * 125e-6, "{t} vs {expect}");
}

mod robustness {
    use drivebus_cia402::drive::{Drive, DriveConfig, ProfileJerk};
    use drivebus_node::{Node, NodeConfig};
    use proptest::prelude::*;

    const OBJECTS: [(u16, u8, usize); 11] = [
        (0x6086, 0, 2),
        (0x60A4, 1, 4),
        (0x60A4, 2, 4),
        (0x60B8, 0, 2),
        (0x60D0, 1, 2),
        (0x60D0, 2, 2),
        (0x607A, 0, 4),
        (0x6081, 0, 4),
        (0x6083, 0, 4),
        (0x6084, 0, 4),
        (0x6086, 0, 2),
    ];

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Any value written to the S-curve and probe objects is taken or
        /// refused with an abort; moves with any of them never panic and the
        /// demand stays finite.
        #[test]
        fn scurve_and_probe_writes_never_panic(
            forbid in any::<bool>(),
            jerk_time in prop_oneof![Just(None), (0.0f64..1.0).prop_map(Some), Just(Some(f64::NAN))],
            ops in proptest::collection::vec(
                (0usize..OBJECTS.len(), any::<u32>(), 0usize..8, 0u32..400), 1..40),
        ) {
            let mut node = Node::new(NodeConfig::new(1));
            let cfg = DriveConfig {
                scurve_forbids_change_immediately: forbid.then_some(0x9000),
                ..DriveConfig::default()
            };
            let mut d = Drive::install(&mut node, cfg).unwrap();
            if let Some(t) = jerk_time {
                d.set_profile_jerk(node.od_mut(), ProfileJerk::Time(t));
            }
            let _ = node.write_object(0x6086, 0, &3i16.to_le_bytes(), drivebus_can::Instant::ZERO, &mut d, &mut Vec::new());
            for (pick, value, cw_pick, steps) in ops {
                let (index, sub, size) = OBJECTS[pick];
                let bytes = value.to_le_bytes();
                let _ = node.write_object(index, sub, &bytes[..size], drivebus_can::Instant::ZERO, &mut d, &mut Vec::new());
                let cw = [0x06u16, 0x07, 0x0F, 0x1F, 0x3F, 0x5F, 0x8F, 0x21F][cw_pick];
                let _ = node.write_object(0x6040, 0, &cw.to_le_bytes(), drivebus_can::Instant::ZERO, &mut d, &mut Vec::new());
                d.step_n(node.od_mut(), steps);
                prop_assert!(d.demand_position().is_finite() && d.demand_velocity().is_finite());
            }
        }
    }
}
