//! The drive and its plug-in mode handlers together (CiA 402-2 §6.2.2
//! statusword ownership, ip buffer 60C1h/60C4h, 60E3h/6098h from the homing
//! registry, the homing event frame, following error ownership, 60B1h/60B2h
//! feed-forward in csp/csv). Position units: 0.001° of the motor shaft.

#[path = "drive_rig/mod.rs"]
mod drive_rig;

use drive_rig::{ID, Rig};
use drivebus_can::Frame;
use drivebus_cia402::drive::{
    DriveConfig, ModeCommand, ModeHandler, ModeIo, ModeOutput, generic_drive_with, op,
};
use drivebus_cia402::homing::{HomingContext, HomingMethod, HomingMode, HomingRegistry, MethodStep};
use drivebus_cia402::interp::{CspMode, CstMode, CsvMode, IpMode};
use drivebus_cia402::model::DriveParams;
use drivebus_cia402::state_machine::State;

fn boxed(v: Vec<Box<dyn ModeHandler + Send>>) -> Vec<Box<dyn ModeHandler + Send>> {
    v
}

fn rig_with(params: DriveParams, handlers: Vec<Box<dyn ModeHandler + Send>>) -> Rig {
    Rig::with(generic_drive_with(ID, DriveConfig::servo(params), handlers))
}

fn interp_rig() -> Rig {
    rig_with(
        DriveParams::servo_small(),
        boxed(vec![
            Box::new(IpMode::new(16)),
            Box::new(CspMode::new()),
            Box::new(CsvMode::new()),
            Box::new(CstMode::new()),
        ]),
    )
}

fn sync(rig: &mut Rig) {
    rig.send(Frame::new(0x080, &[]));
}

/// EMCY frames of `code` among `frames`.
fn count_emcy(frames: &[Frame], code: u16) -> usize {
    frames
        .iter()
        .filter(|f| f.std_id() == Some(0x80 + ID as u16) && f.data()[..2] == code.to_le_bytes())
        .count()
}

// ---------------------------------------------------------------- item 3

/// ip with a 16-record buffer: 8 records by SDO and 8 by RPDO (60C1h:1),
/// consumed one per SYNC in order (CiA 402-2 interpolated position mode,
/// 60C4h FIFO).
#[test]
fn ip_buffer_of_16_filled_by_sdo_and_rpdo_consumed_at_sync() {
    let mut rig = interp_rig();
    // RPDO1 → 60C1h:1, asynchronous (255): applied on reception.
    rig.write(0x1400, 1, &(0x8000_0200u32 + u32::from(ID)).to_le_bytes());
    rig.write(0x1400, 2, &[255]);
    rig.write(0x1600, 0, &[0]);
    rig.write(0x1600, 1, &0x60C1_0120u32.to_le_bytes());
    rig.write(0x1600, 0, &[1]);
    rig.write(0x1400, 1, &(0x200u32 + u32::from(ID)).to_le_bytes());
    rig.start();
    // 60C4h: max 16 records, actual 16, FIFO, access enabled.
    assert_eq!(rig.read(0x60C4, 1), 16);
    assert_eq!(rig.read(0x60C4, 2), 16);
    assert_eq!(rig.read(0x60C4, 3), 0);
    assert_eq!(rig.read(0x60C4, 6), 1);
    rig.write(0x60C2, 1, &[1]);
    rig.write(0x60C2, 2, &[(-3i8) as u8]); // 1 ms
    rig.write(0x6060, 0, &[7]);
    rig.enable();
    rig.run_ms(2.0);
    let r0 = rig.drive().demand_position();
    // Distinct, non-linear records: r_k = r0 + 50·k².
    let rec = |k: i32| r0 as i32 + 50 * k * k;
    for k in 1..=8 {
        rig.write(0x60C1, 1, &rec(k).to_le_bytes());
    }
    for k in 9..=16 {
        rig.send(Frame::new(0x200 + ID as u16, &rec(k).to_le_bytes()));
    }
    // Nothing consumed yet: bit 4 is off.
    assert_eq!(rig.drive().demand_position(), r0);
    rig.controlword(0x1F);
    let mut prev = r0;
    for k in 1..=16 {
        sync(&mut rig);
        rig.run_us(990);
        // Between SYNC k and k+1 the demand heads from r_{k-1} to r_k.
        let (lo, hi) = (prev, f64::from(rec(k)));
        let d = rig.drive().demand_position();
        assert!(d >= lo + 0.6 * (hi - lo) && d <= hi + 1e-6, "SYNC {k}: demand {d}, want → {hi} from {lo}");
        prev = hi;
        assert_eq!(rig.drive().statusword() & 0x1080, 0x1000, "ip active, no warning");
    }
    assert!(rig.emcys().is_empty());
}

/// 60C4h writes reach the ip handler with the right aborts.
#[test]
fn ip_buffer_configuration_aborts() {
    let mut rig = interp_rig();
    rig.write_aborts(0x60C4, 2, &17u32.to_le_bytes(), 0x0609_0031);
    rig.write_aborts(0x60C4, 2, &0u32.to_le_bytes(), 0x0609_0032);
    rig.write(0x60C4, 2, &4u32.to_le_bytes());
    assert_eq!(rig.read(0x60C4, 2), 4);
    rig.write_aborts(0x60C4, 3, &[2], 0x0609_0030);
    // FIFO: no writable buffer position.
    rig.write_aborts(0x60C4, 4, &1u16.to_le_bytes(), 0x0609_0030);
    rig.write(0x60C4, 3, &[1]); // ring
    rig.write(0x60C4, 4, &2u16.to_le_bytes());
    assert_eq!(rig.read(0x60C4, 4), 2);
    rig.write_aborts(0x60C4, 4, &4u16.to_le_bytes(), 0x0609_0031);
    rig.write_aborts(0x60C4, 5, &[3], 0x0609_0030);
    rig.write_aborts(0x60C4, 6, &[2], 0x0609_0030);
    // Buffer clear: 0 clears and disables access, 1 enables it again.
    rig.write(0x60C4, 6, &[0]);
    assert_eq!(rig.read(0x60C4, 6), 0);
    rig.write_aborts(0x60C1, 1, &5i32.to_le_bytes(), 0x0800_0022);
    rig.write(0x60C4, 6, &[1]);
    rig.write(0x60C1, 1, &5i32.to_le_bytes());
    // 60C0h: 0, −1, −2 are offered; 1 is not.
    rig.write_aborts(0x60C0, 0, &1i16.to_le_bytes(), 0x0609_0030);
    rig.write(0x60C0, 0, &(-2i16).to_le_bytes());
}

// ---------------------------------------------------------------- item 2

/// ip buffer overflow and underflow: statusword bit 7 and EMCY FF02h /
/// FF01h through the drive's EMCY queue; cleared when the condition ends.
#[test]
fn ip_buffer_warnings_set_bit7_and_emcy() {
    let mut rig = interp_rig();
    rig.start();
    rig.write(0x60C4, 2, &2u32.to_le_bytes()); // two records deep
    rig.write(0x6060, 0, &[7]);
    rig.enable();
    rig.run_ms(2.0);
    rig.take();
    for v in [10i32, 20, 30] {
        rig.write(0x60C1, 1, &v.to_le_bytes());
    }
    rig.run_ms(1.0);
    let frames = rig.take();
    assert_eq!(count_emcy(&frames, 0xFF02), 1, "overflow EMCY: {frames:?}");
    assert_eq!(rig.statusword() & 0x0080, 0x0080, "warning");
    // Enable ip; the SYNCs consume the two records (overflow over), the
    // third SYNC finds the buffer empty: underflow.
    rig.controlword(0x1F);
    sync(&mut rig);
    rig.run_ms(1.0);
    assert_eq!(rig.statusword() & 0x0080, 0, "overflow cleared by consumption");
    let frames = rig.take();
    assert_eq!(count_emcy(&frames, 0x0000), 1, "error reset EMCY: {frames:?}");
    sync(&mut rig);
    rig.run_ms(1.0);
    sync(&mut rig);
    rig.run_ms(1.0);
    let frames = rig.take();
    assert_eq!(count_emcy(&frames, 0xFF01), 1, "underflow EMCY: {frames:?}");
    assert_eq!(rig.statusword() & 0x0080, 0x0080);
    assert_eq!(rig.drive().state_machine().state(), State::OperationEnabled);
    // A new record ends the underflow.
    rig.write(0x60C1, 1, &40i32.to_le_bytes());
    rig.run_ms(1.0);
    assert_eq!(rig.statusword() & 0x0080, 0);
}

// ---------------------------------------------------------------- item 4

/// A manufacturer method: found at once where it stands.
struct HereMethod;

impl HomingMethod for HereMethod {
    fn code(&self) -> i8 {
        -3
    }
    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        MethodStep::Found(ctx.position)
    }
    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        MethodStep::Found(ctx.position)
    }
}

#[test]
fn supported_homing_methods_come_from_the_registry() {
    let mut reg = HomingRegistry::standard();
    reg.register(Box::new(HereMethod));
    let want: Vec<i8> = reg.codes().collect();
    let mut rig = rig_with(DriveParams::servo_small(), boxed(vec![Box::new(HomingMode::new(reg))]));
    assert_eq!(rig.read(0x60E3, 0) as usize, want.len());
    for (i, m) in want.iter().enumerate() {
        assert_eq!(rig.read(0x60E3, i as u8 + 1) as u8 as i8, *m, "60E3h:{}", i + 1);
    }
    assert!(want.contains(&-3));
    // 6098h: registered methods and 0 are accepted, others refused.
    rig.write(0x6098, 0, &[(-3i8) as u8]);
    rig.write(0x6098, 0, &[0]);
    rig.write(0x6098, 0, &[35]);
    rig.write_aborts(0x6098, 0, &[15], 0x0609_0030);
    rig.write_aborts(0x6098, 0, &[(-4i8) as u8], 0x0609_0030);
    assert_eq!(rig.read(0x6098, 0), 35);
}

// ---------------------------------------------------------------- item 5

/// A stand-in for any handler that shifts the position reference: in ip
/// it sets the actual position to 5 000 000 once.
struct Shifter {
    done: bool,
}

impl ModeHandler for Shifter {
    fn supported_modes(&self) -> u32 {
        op::supported_bit(op::IP)
    }
    fn enter(&mut self, _mode: i8, _io: &ModeIo<'_>) {}
    fn step(&mut self, _mode: i8, _io: &ModeIo<'_>, _dt: f64) -> ModeOutput {
        let mut out = ModeOutput::hold();
        if !self.done {
            self.done = true;
            out.position_reset = Some(5_000_000);
        }
        out
    }
}

/// Homing sees events in the present 6063h frame even when someone else
/// shifted it (`ModeIo::inc_offset`): method 34 (next index pulse,
/// positive) after an unrelated reference shift.
#[test]
fn homing_places_events_in_the_shifted_frame() {
    let mut p = DriveParams::servo_small();
    p.encoder.index_angle = 0.3;
    let handlers = boxed(vec![Box::new(Shifter { done: false }), Box::new(HomingMode::default())]);
    let mut rig = rig_with(p, handlers);
    rig.start();
    rig.write(0x6060, 0, &[7]);
    rig.enable();
    rig.run_ms(2.0);
    let pos = rig.read(0x6064, 0) as i32;
    assert!((pos - 5_000_000).abs() <= 1, "shifted: {pos}");
    rig.write(0x6060, 0, &[6]);
    rig.write(0x6098, 0, &[34]);
    rig.write(0x6099, 1, &1_800_000u32.to_le_bytes());
    rig.write(0x6099, 2, &180_000u32.to_le_bytes());
    rig.write(0x609A, 0, &36_000_000u32.to_le_bytes());
    rig.write(0x607C, 0, &12_345i32.to_le_bytes());
    rig.controlword(0x1F);
    let done = rig.run_until(1000, 5000.0, |r| r.drive().statusword() & 0x3400 != 0x0000);
    assert!(done.is_some());
    rig.run_until(1000, 5000.0, |r| r.drive().statusword() & 0x0400 != 0);
    assert_eq!(rig.statusword() & 0x3400, 0x1400, "homing completed");
    // The next index pulse right of 0°: 0.3 rad.
    let index_deg = 0.3f64.to_degrees();
    let shaft_deg = rig.drive().model().position().to_degrees();
    let want = 12_345.0 + (shaft_deg - index_deg) * 1000.0;
    let got = f64::from(rig.read(0x6064, 0) as i32);
    assert!((got - want).abs() <= 1.5, "6064h {got}, expected {want:.1}");
}

// ---------------------------------------------------------------- item 6

/// A csp stand-in that owns following-error supervision and jumps its
/// demand far away without reporting anything.
struct Runaway;

impl ModeHandler for Runaway {
    fn supported_modes(&self) -> u32 {
        op::supported_bit(op::CSP)
    }
    fn enter(&mut self, _mode: i8, _io: &ModeIo<'_>) {}
    fn step(&mut self, _mode: i8, io: &ModeIo<'_>, _dt: f64) -> ModeOutput {
        let target = io.demand_position.max(10_000_000.0);
        ModeOutput::new(ModeCommand::Position { position: target, velocity: 0.0, acceleration: 0.0 }, 0)
    }
    fn owns_following_error(&self, _mode: i8) -> bool {
        true
    }
}

#[test]
fn following_error_has_one_owner_per_mode() {
    let mut rig = rig_with(DriveParams::servo_small(), boxed(vec![Box::new(Runaway)]));
    rig.start();
    rig.write(0x6060, 0, &[8]);
    rig.enable();
    rig.run_ms(200.0);
    // 6065h 36 000 exceeded for far longer than 6066h 50 ms: not the
    // drive's business in a mode whose handler owns it.
    assert_eq!(rig.drive().state_machine().state(), State::OperationEnabled);
    assert_eq!(count_emcy(&rig.take(), 0x8611), 0);
}

#[test]
fn csp_following_error_is_raised_once_by_csp() {
    let mut rig = interp_rig();
    rig.start();
    rig.write(0x60C2, 1, &[1]);
    rig.write(0x60C2, 2, &[(-3i8) as u8]);
    rig.write(0x6060, 0, &[8]);
    rig.enable();
    rig.run_ms(2.0);
    rig.take();
    // A 10 000° jump: far outside 6065h for longer than 6066h.
    rig.write(0x607A, 0, &10_000_000i32.to_le_bytes());
    for _ in 0..200 {
        sync(&mut rig);
        rig.run_us(999);
    }
    let state = rig.drive().state_machine().state();
    assert!(matches!(state, State::Fault | State::FaultReactionActive), "{state:?}");
    assert_eq!(rig.read(0x603F, 0), 0x8611);
    assert_eq!(count_emcy(&rig.take(), 0x8611), 1);
}

// ---------------------------------------------------------------- item 7

/// csp / csv: 60B2h torque offset is torque feed-forward (CiA 402-4): the
/// current steps by it within a few control periods, before the loops react.
#[test]
fn torque_offset_is_feed_forward_in_csp_and_csv() {
    for mode in [8u8, 9] {
        let mut rig = interp_rig();
        rig.start();
        rig.write(0x60C2, 1, &[1]);
        rig.write(0x60C2, 2, &[(-3i8) as u8]);
        rig.write(0x6060, 0, &[mode]);
        rig.enable();
        rig.run_ms(5.0);
        for _ in 0..3 {
            sync(&mut rig);
            rig.run_us(999);
        }
        let rated_nm = f64::from(rig.read(0x6076, 0)) / 1000.0;
        let before = rig.drive().model().torque();
        rig.write(0x60B2, 0, &500i16.to_le_bytes()); // 50 % rated
        sync(&mut rig);
        rig.run_us(400);
        let step = rig.drive().model().torque() - before;
        assert!(
            step > 0.3 * rated_nm && step < 0.6 * rated_nm,
            "mode {mode}: torque step {step} Nm, rated {rated_nm} Nm"
        );
    }
}

/// csv: 60B1h velocity offset adds to 60FFh.
#[test]
fn velocity_offset_adds_in_csv() {
    let mut rig = interp_rig();
    rig.start();
    rig.write(0x60C2, 1, &[1]);
    rig.write(0x60C2, 2, &[(-3i8) as u8]);
    rig.write(0x6060, 0, &[9]);
    rig.enable();
    rig.run_ms(2.0);
    rig.write(0x60FF, 0, &30_000i32.to_le_bytes()); // 30°/s
    rig.write(0x60B1, 0, &60_000i32.to_le_bytes()); // + 60°/s
    for _ in 0..300 {
        sync(&mut rig);
        rig.run_us(999);
    }
    let v = rig.read(0x606C, 0) as i32;
    assert!((v - 90_000).abs() <= 2_000, "606Ch {v}");
}
