//! `IpMode`, `CspMode`, `CsvMode`, `CstMode` through the drive's
//! `ModeHandler` interface (hand-built `ModeIo`, default units).

use drivebus_cia402::drive::{ModeCommand, ModeHandler, ModeIo, ModeParams, Units, op};
use drivebus_cia402::interp::{CspMode, CstMode, CsvMode, IpMode};
use drivebus_cia402::model::StepEvents;

const DT: f64 = 1.0 / 8000.0;

fn io<'a>(
    cw: u16,
    position: i64,
    params: &'a ModeParams,
    units: &'a Units,
    events: &'a StepEvents,
) -> ModeIo<'a> {
    ModeIo {
        controlword: cw,
        position,
        position_inc: position,
        inc_offset: 0,
        velocity: 0.0,
        torque: 0.0,
        demand_position: position as f64,
        demand_velocity: 0.0,
        events,
        switches: Default::default(),
        master_position: 0,
        master_velocity: 0.0,
        params,
        units,
        dt: DT,
        time: 0.0,
    }
}

fn params() -> ModeParams {
    ModeParams {
        interpolation_period_value: 1,
        interpolation_period_index: -3,
        following_error_window: 1000,
        following_error_timeout: 5,
        profile_deceleration: 1_000_000,
        ..ModeParams::default()
    }
}

#[test]
fn supported_mode_bits() {
    assert_eq!(IpMode::default().supported_modes(), 1 << 6);
    assert_eq!(CspMode::new().supported_modes(), 1 << 7);
    assert_eq!(CsvMode::new().supported_modes(), 1 << 8);
    assert_eq!(CstMode::new().supported_modes(), 1 << 9);
}

#[test]
fn csp_latches_target_plus_offset_at_sync() {
    let (units, ev) = (Units::default(), StepEvents::default());
    let mut p = params();
    let mut m = CspMode::new();
    m.enter(op::CSP, &io(0x0F, 100, &p, &units, &ev));
    p.target_position = 900;
    p.position_offset = 20;
    m.on_sync(op::CSP, &io(0x0F, 100, &p, &units, &ev));
    let mut last = None;
    for _ in 0..9 {
        let out = m.step(op::CSP, &io(0x0F, 100, &p, &units, &ev), DT);
        assert_eq!(out.status & 0x3000, 0x1000, "bit 12: follows");
        last = Some(out.command);
    }
    // The demand of the period starting one cycle after the SYNC.
    match last {
        Some(ModeCommand::Position { position, .. }) => {
            assert!((position - 920.0).abs() < 1e-9, "{position}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn csp_following_error_raises_8611_once() {
    let (units, ev) = (Units::default(), StepEvents::default());
    let mut p = params();
    let mut m = CspMode::new();
    m.enter(op::CSP, &io(0x0F, 0, &p, &units, &ev));
    p.target_position = 5000;
    m.on_sync(op::CSP, &io(0x0F, 0, &p, &units, &ev));
    let mut faults = Vec::new();
    for _ in 0..200 {
        // The axis never moves: position actual stays 0.
        let out = m.step(op::CSP, &io(0x0F, 0, &p, &units, &ev), DT);
        faults.extend(out.fault);
    }
    assert_eq!(faults, [0x8611]);
    assert!(m.engine().following_error() > 1000.0);
    // 6065h = FFFF FFFFh: supervision off.
    let mut m = CspMode::new();
    p.following_error_window = u32::MAX;
    m.enter(op::CSP, &io(0x0F, 0, &p, &units, &ev));
    m.on_sync(op::CSP, &io(0x0F, 0, &p, &units, &ev));
    for _ in 0..200 {
        assert_eq!(m.step(op::CSP, &io(0x0F, 0, &p, &units, &ev), DT).fault, None);
    }
}

#[test]
fn csv_and_cst_commands() {
    let (units, ev) = (Units::default(), StepEvents::default());
    let mut p = params();
    p.target_velocity = 8000;
    p.velocity_offset = 800;
    p.target_torque = 300;
    p.torque_offset = -50;
    let mut v = CsvMode::new();
    v.enter(op::CSV, &io(0x0F, 0, &p, &units, &ev));
    v.on_sync(op::CSV, &io(0x0F, 0, &p, &units, &ev));
    let mut t = CstMode::new();
    t.enter(op::CST, &io(0x0F, 0, &p, &units, &ev));
    t.on_sync(op::CST, &io(0x0F, 0, &p, &units, &ev));
    let (mut vc, mut tc) = (None, None);
    for _ in 0..8 {
        vc = Some(v.step(op::CSV, &io(0x0F, 0, &p, &units, &ev), DT).command);
        tc = Some(t.step(op::CST, &io(0x0F, 0, &p, &units, &ev), DT).command);
    }
    v.on_sync(op::CSV, &io(0x0F, 0, &p, &units, &ev));
    t.on_sync(op::CST, &io(0x0F, 0, &p, &units, &ev));
    let vn = v.step(op::CSV, &io(0x0F, 0, &p, &units, &ev), DT).command;
    let tn = t.step(op::CST, &io(0x0F, 0, &p, &units, &ev), DT).command;
    assert!(matches!(vc, Some(ModeCommand::Velocity { .. })));
    assert!(matches!(tc, Some(ModeCommand::Torque(_))));
    assert_eq!(vn, ModeCommand::Velocity { velocity: 8800.0, acceleration: 0.0 });
    assert_eq!(tn, ModeCommand::Torque(250.0));
}

#[test]
fn ip_auto_push_consumes_60c1_at_each_sync() {
    let (units, ev) = (Units::default(), StepEvents::default());
    let mut p = params();
    let mut m = IpMode::default();
    m.enter(op::IP, &io(0x0F, 0, &p, &units, &ev));
    let mut positions = Vec::new();
    for k in 1..=4 {
        p.interpolation_data = 100 * k;
        m.on_sync(op::IP, &io(0x1F, 0, &p, &units, &ev));
        let out = m.step(op::IP, &io(0x1F, 0, &p, &units, &ev), DT);
        assert_eq!(out.status & 0x1000, 0x1000, "ip mode active");
        if let ModeCommand::Position { position, .. } = out.command {
            positions.push(position);
        }
        for _ in 1..8 {
            m.step(op::IP, &io(0x1F, 0, &p, &units, &ev), DT);
        }
    }
    // At each SYNC the demand is the record of the SYNC before.
    assert_eq!(positions, [0.0, 100.0, 200.0, 300.0]);
    assert!(!m.engine().underflow() && !m.engine().overflow());
}

/// A drive without a set-point buffer (`IpMode::latest_only`, e.g. the
/// DDS6): forwarded 60C1h writes are left to the dictionary (the drive
/// stores them), the value in force at each SYNC is taken, several writes
/// between two SYNCs count once, and a missing write is no underflow.
#[test]
fn ip_latest_only_takes_the_value_in_force() {
    let (units, ev) = (Units::default(), StepEvents::default());
    let mut p = params();
    let mut m = IpMode::latest_only();
    let bytes = 500i32.to_le_bytes();
    assert_eq!(m.write_object(0x60C1, 1, &bytes, &units), Ok(false), "stored by the drive");
    m.enter(op::IP, &io(0x0F, 0, &p, &units, &ev));
    let mut positions = Vec::new();
    // Two writes before the first SYNC (the first one is overwritten),
    // then none for two periods.
    for (k, data) in [(1, 300), (2, 400), (3, 400), (4, 400)] {
        if k == 1 {
            p.interpolation_data = 200;
        }
        p.interpolation_data = data;
        m.on_sync(op::IP, &io(0x1F, 0, &p, &units, &ev));
        let out = m.step(op::IP, &io(0x1F, 0, &p, &units, &ev), DT);
        if let ModeCommand::Position { position, .. } = out.command {
            positions.push(position);
        }
        for _ in 1..8 {
            m.step(op::IP, &io(0x1F, 0, &p, &units, &ev), DT);
        }
    }
    assert_eq!(positions, [0.0, 300.0, 400.0, 400.0]);
    assert!(!m.engine().underflow() && !m.engine().overflow(), "no buffer, no buffer warnings");
}
