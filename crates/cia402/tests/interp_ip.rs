//! Interpolated position mode (CiA 402-2 ip, 60C0h–60C4h) on the motor
//! model: linear ip of a ramp, buffer underflow / overflow, ring buffer,
//! buffer configuration, PT and PVT (cubic Hermite) sub-modes, halt.

use drivebus_cia402::interp::ip::{IP_ACTIVE, IP_OVERFLOW_CODE, IP_UNDERFLOW_CODE, TARGET_REACHED, WARNING};
use drivebus_cia402::interp::{Ip, IpBufferError, IpConfig, IpRecord, Organisation, SubMode};
use drivebus_cia402::model::{Demand, DriveModel, DriveParams};

const DT: f64 = 1.0 / 8000.0;
/// 1 kHz SYNC at 8 kHz control: 8 periods per SYNC.
const PER_SYNC: usize = 8;

fn config(sub_mode: SubMode) -> IpConfig {
    IpConfig { sub_mode, period: 1e-3, halt_deceleration: 36_000.0 }
}

/// The ip engine on a servo, in degrees.
struct Rig {
    model: DriveModel,
    ip: Ip,
    cw: u16,
    emcy: Vec<u16>,
    last_status: u16,
}

impl Rig {
    fn new(buffer: usize) -> Self {
        let model = DriveModel::new(DriveParams::servo_small()).unwrap();
        let mut ip = Ip::new(buffer);
        ip.enter(0.0, 0x0F);
        Rig { model, ip, cw: 0x1F, emcy: Vec::new(), last_status: 0 }
    }

    /// One control period; returns the position demand.
    fn step(&mut self, c: &IpConfig) -> f64 {
        let out = self.ip.step(self.cw, c, DT);
        self.emcy.extend(out.emcy);
        self.last_status = out.status;
        let m = &mut self.model;
        let cmd = Demand::Position {
            position: m.units_to_rad(out.position),
            velocity: m.units_to_rad(out.velocity),
            acceleration: m.units_to_rad(out.acceleration),
        };
        assert!(m.set_demand(cmd));
        m.step(DT);
        out.position
    }

    /// A SYNC period: optional record written before the SYNC (the RPDO),
    /// then SYNC, then 8 control periods; returns the demands.
    fn sync_period(&mut self, record: Option<f64>, c: &IpConfig) -> [f64; PER_SYNC] {
        if let Some(p) = record {
            self.ip.write_data(1, p).unwrap();
        }
        self.ip.on_sync(self.cw, c);
        core::array::from_fn(|_| self.step(c))
    }
}

#[test]
fn linear_ip_of_a_ramp_hits_the_points_at_the_sync_instants() {
    let c = config(SubMode::Linear);
    let mut rig = Rig::new(1);
    // A ramp at 720°/s: 0.72° per 1 ms record.
    let points: Vec<f64> = (1..=300).map(|k| 0.72 * k as f64).collect();
    let mut prev = 0.0;
    for (k, &p) in points.iter().enumerate() {
        let d = rig.sync_period(Some(p), &c);
        // The record written before SYNC k is the demand at SYNC k+1 (one
        // period of interpolation); so at SYNC k the demand is the previous
        // point, and in between it runs on the straight line.
        for (i, &x) in d.iter().enumerate() {
            let want = prev + (p - prev) * i as f64 / PER_SYNC as f64;
            assert!((x - want).abs() < 1e-9, "record {k} period {i}: {x} vs {want}");
        }
        assert_eq!(rig.last_status & (IP_ACTIVE | WARNING), IP_ACTIVE);
        prev = p;
    }
    assert!(rig.emcy.is_empty());
    // The servo follows the ramp with a small lag (velocity feed-forward).
    let actual = rig.model.rad_to_units(rig.model.position());
    assert!((actual - 216.0).abs() < 0.5, "{actual}");
}

#[test]
fn underflow_holds_and_warns_once() {
    let c = config(SubMode::Linear);
    let mut rig = Rig::new(4);
    for k in 1..=10 {
        rig.sync_period(Some(k as f64), &c);
    }
    assert!(rig.emcy.is_empty());
    // The master stops writing: SYNCs find the buffer empty.
    let d = rig.sync_period(None, &c);
    assert!(d.iter().all(|&x| (x - 10.0).abs() < 1e-9), "holds the last point");
    assert_eq!(
        rig.last_status & (WARNING | TARGET_REACHED | IP_ACTIVE),
        WARNING | TARGET_REACHED | IP_ACTIVE
    );
    for _ in 0..5 {
        rig.sync_period(None, &c);
    }
    assert_eq!(rig.emcy, [IP_UNDERFLOW_CODE]);
    assert!(rig.ip.underflow());
    // Data again: the warning goes.
    rig.sync_period(Some(11.0), &c);
    assert_eq!(rig.last_status & WARNING, 0);
    assert!(!rig.ip.underflow());
}

#[test]
fn fifo_overflow_drops_the_record_and_warns() {
    let c = config(SubMode::Linear);
    let mut rig = Rig::new(4);
    // Disabled ip (bit 4 = 0): records are buffered, not consumed.
    rig.cw = 0x0F;
    for k in 1..=4 {
        rig.ip.write_data(1, k as f64).unwrap();
    }
    assert_eq!(rig.ip.buffer().len(), 4);
    assert_eq!(rig.ip.write_data(1, 5.0), Err(IpBufferError::Overflow));
    rig.ip.on_sync(rig.cw, &c);
    rig.step(&c);
    assert_eq!(rig.last_status & (WARNING | IP_ACTIVE), WARNING);
    assert_eq!(rig.emcy, [IP_OVERFLOW_CODE]);
    assert_eq!(rig.ip.buffer().len(), 4, "nothing consumed while bit 4 = 0");
    // Enable: the buffered records 1..4 play out, 5 was lost.
    rig.cw = 0x1F;
    let mut at_sync = Vec::new();
    for _ in 0..5 {
        at_sync.push(rig.sync_period(None, &c)[0]);
    }
    assert_eq!(at_sync, [0.0, 1.0, 2.0, 3.0, 4.0]);
    assert!(!rig.ip.overflow(), "consuming clears the overflow warning");
    // The fifth SYNC found the buffer empty: now an underflow warning.
    assert_eq!(rig.emcy, [IP_OVERFLOW_CODE, IP_UNDERFLOW_CODE]);
    assert_eq!(rig.last_status & WARNING, WARNING);
}

#[test]
fn ring_buffer_overwrites_the_oldest() {
    let mut ip = Ip::new(8);
    assert!(ip.buffer_mut().set_organisation(1));
    assert!(ip.buffer_mut().set_size(4));
    assert_eq!(ip.buffer().organisation(), Organisation::Ring);
    for k in 1..=6 {
        ip.push(IpRecord { position: k as f64, ..Default::default() }).unwrap();
    }
    assert!(!ip.overflow());
    assert_eq!(ip.buffer().position(), 2, "6 writes into 4 slots");
    let got: Vec<f64> = core::iter::from_fn(|| ip.buffer_mut().pop()).map(|r| r.position).collect();
    assert_eq!(got, [3.0, 4.0, 5.0, 6.0]);
}

#[test]
fn buffer_configuration_objects() {
    let mut ip = Ip::new(16);
    let b = ip.buffer_mut();
    assert_eq!(b.max_size(), 16);
    assert!(!b.set_size(17) && !b.set_size(0));
    assert!(b.set_size(2));
    assert!(!b.set_organisation(2));
    assert!(!b.set_position(1), "position only in a ring");
    // 60C4h:6 = 0: clear and disable access.
    b.push(IpRecord::default()).unwrap();
    assert!(b.set_clear(0));
    assert!(b.is_empty() && !b.access_enabled());
    assert_eq!(b.push(IpRecord::default()), Err(IpBufferError::Disabled));
    assert!(b.set_clear(1) && b.access_enabled());
    assert!(!b.set_clear(7));
    assert_eq!(SubMode::Linear.record_size(), 4);
    assert_eq!(SubMode::from_code(-2), Some(SubMode::Pvt));
    assert_eq!(SubMode::from_code(1), None);
    assert_eq!(SubMode::Pt.code(), -1);
}

#[test]
fn pvt_is_a_cubic_hermite_through_the_points() {
    // p(t) = 100·t³ − 50·t² (degrees, t in s) is a cubic: Hermite segments
    // with exact end positions and velocities reproduce it exactly.
    let p = |t: f64| 100.0 * t * t * t - 50.0 * t * t;
    let v = |t: f64| 300.0 * t * t - 100.0 * t;
    let c = config(SubMode::Pvt);
    let mut rig = Rig::new(64);
    // 10 ms segments (60C1h:3 in ms).
    for k in 1..=40 {
        let t = 0.01 * k as f64;
        rig.ip.write_data(2, v(t)).unwrap();
        rig.ip.write_data(3, 10.0).unwrap();
        rig.ip.write_data(1, p(t)).unwrap();
    }
    rig.ip.on_sync(rig.cw, &c);
    let mut worst: f64 = 0.0;
    for n in 0..3200 {
        let d = rig.step(&c);
        worst = worst.max((d - p(n as f64 * DT)).abs());
    }
    assert!(worst < 1e-9, "{worst}");
    // Then the buffer runs dry: hold at p(0.4) with an underflow warning.
    let d = rig.step(&c);
    assert!((d - p(0.4)).abs() < 1e-9);
    assert_eq!(rig.emcy, [IP_UNDERFLOW_CODE]);
}

#[test]
fn pt_segments_are_linear_over_their_time() {
    let c = config(SubMode::Pt);
    let mut rig = Rig::new(8);
    rig.ip.write_data(3, 4.0).unwrap();
    rig.ip.write_data(1, 8.0).unwrap(); // 8° in 4 ms
    rig.ip.write_data(3, 2.0).unwrap();
    rig.ip.write_data(1, 6.0).unwrap(); // back 2° in 2 ms
    let d: Vec<f64> = (0..48).map(|_| rig.step(&c)).collect();
    // 32 periods of 0.25° then 16 of −0.125°.
    for (i, &x) in d.iter().enumerate() {
        let n = i as f64;
        let want = if i < 32 { 0.25 * n } else { 8.0 - 0.125 * (n - 32.0) };
        assert!((x - want).abs() < 1e-9, "{i}: {x} vs {want}");
    }
}

#[test]
fn halt_ramps_to_rest_and_resumes_bumplessly() {
    let c = config(SubMode::Linear);
    let mut rig = Rig::new(1);
    let mut p = 0.0;
    for _ in 0..100 {
        p += 1.8; // 1800°/s
        rig.sync_period(Some(p), &c);
    }
    rig.cw = 0x11F;
    let mut steps = 0;
    while rig.last_status & TARGET_REACHED == 0 {
        rig.step(&c);
        steps += 1;
        assert!(steps < 1000);
    }
    // 1800°/s at 36 000°/s²: 50 ms = 400 periods.
    assert!((399..=401).contains(&steps), "{steps}");
    let stopped = rig.step(&c);
    rig.cw = 0x1F;
    let d = rig.sync_period(Some(stopped + 0.5), &c);
    assert!((d[0] - stopped).abs() < 0.1, "no jump on release");
}
