//! LAM DDS6 objects that act (issue 14), seed004 manual HW 1.00 / FW
//! 0.22, on the virtual bus:
//!
//! * §5 error classes: 0 warning, 2 quick stop without FAULT, 4 quick stop
//!   then FAULT, 6 disable and FAULT, 8 as 6 until a power cycle; 8611h's
//!   class is 2480h:01 (§6.4.7);
//! * §5 8612h "Limit switch activation" with its sub-codes;
//! * §6.4.12 3080h Sync Guard;
//! * §6.4.9–6.4.15 digital outputs (2830h–2832h sources, 3230h) and
//!   inputs (3210h);
//! * §6.4.3 2360h sub 0 as printed.

mod replay_rig;

use drivebus_can::Frame;
use drivebus_cia402::drive::Injection;
use drivebus_cia402::model::AxisParams;
use drivebus_node::MemoryStorage;
use drivebus_personality::Profile;
use drivebus_personality::build::build_with;
use drivebus_personality::dds6::Dds6;
use replay_rig::*;

const ID: u8 = 1;

fn rig() -> Rig {
    Rig::new(Profile::Dds6, ID).0
}

/// A DDS6 on `axis` (switches wired as 2810h's defaults assign them).
fn rig_on(axis: AxisParams) -> Rig {
    let pn = build_with(Profile::Dds6, ID, Box::new(MemoryStorage::new()), Box::new(Dds6::with_axis(axis)));
    Rig::with(pn.unwrap()).0
}

fn write(r: &mut Rig, index: u16, sub: u8, data: &[u8]) {
    Rig::assert_written(r.sdo_write(ID, index, sub, data), ID, index, sub);
}

fn statusword(r: &mut Rig) -> u16 {
    r.read_u32(ID, 0x6041, 0) as u16
}

/// Shutdown, then Enable operation (the DDS6 passes Switched on itself,
/// 16 ms open loop).
fn enable(r: &mut Rig) {
    write(r, 0x6040, 0, &[0x06, 0]);
    r.run_ms(5);
    write(r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(50);
    assert_eq!(statusword(r) & 0x6F, 0x27, "operation enabled");
}

/// The EMCY frames (081h) among `frames`.
fn emcy(frames: &[Frame]) -> Vec<Frame> {
    frames.iter().copied().filter(|f| f.std_id() == Some(0x80 + u16::from(ID))).collect()
}

/// EMCY `code` with sub-code `sub` (bytes 3–4) among `frames`.
fn has_emcy(frames: &[Frame], code: u16, sub: u16) -> bool {
    emcy(frames).iter().any(|f| {
        let d = f.data();
        d.len() == 8 && d[0..2] == code.to_le_bytes() && d[3..5] == sub.to_le_bytes()
    })
}

const QUICK_STOP_ACTIVE: u16 = 0x07;
const FAULT: u16 = 0x08;

#[test]
fn heartbeat_loss_is_class_2_a_quick_stop_without_fault() {
    // §5 8130h "Error Life Guard or Heartbeat", class 2: "stop of the motor
    // but not the transition to FAULT … Deceleration with Quick Stop".
    let mut r = rig();
    write(&mut r, 0x1016, 1, &((5u32 << 16) | 100).to_le_bytes());
    r.send("705#05");
    enable(&mut r);
    r.take();
    r.run_ms(300);
    let frames = r.take();
    assert!(emcy(&frames).iter().any(|f| f.data()[0..2] == [0x30, 0x81]), "EMCY 8130h: {frames:?}");
    let sw = statusword(&mut r);
    assert_eq!(sw & 0x6F, QUICK_STOP_ACTIVE, "quick stop active, motor enabled: {sw:04X}h");
    assert_eq!(sw & 0x08, 0, "no FAULT");
    // Enable operation again (transition 16): back in operation.
    write(&mut r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(20);
    assert_eq!(statusword(&mut r) & 0x6F, 0x27);
}

/// Enabled in pp, a following error injected; the frames and the
/// statusword 100 ms later.
fn following_error(class: Option<u8>) -> (Vec<Frame>, u16) {
    let mut r = rig();
    if let Some(c) = class {
        write(&mut r, 0x2480, 1, &[c]);
    }
    enable(&mut r);
    r.take();
    r.pn_mut().app.inject(Injection::FollowingError);
    r.run_ms(100);
    let frames = r.take();
    (frames, statusword(&mut r))
}

#[test]
fn following_error_class_is_2480h() {
    // §6.4.7 2480h:01, default 6: disabling and FAULT.
    let (frames, sw) = following_error(None);
    assert!(has_emcy(&frames, 0x8611, 0), "{frames:?}");
    assert_eq!(sw & 0x4F, FAULT, "{sw:04X}h");
    // Class 2: quick stop, no FAULT.
    let (frames, sw) = following_error(Some(2));
    assert!(has_emcy(&frames, 0x8611, 0), "{frames:?}");
    assert_eq!(sw & 0x6F, QUICK_STOP_ACTIVE, "{sw:04X}h");
    // Class 4: FAULT after the quick stop.
    let (_, sw) = following_error(Some(4));
    assert_eq!(sw & 0x4F, FAULT, "{sw:04X}h");
    // Only the classes of the §6.4.7 table.
    let mut r = rig();
    Rig::assert_abort(r.sdo_write(ID, 0x2480, 1, &[3]), ID, 0x2480, 1, 0x0609_0030);
    Rig::assert_abort(r.sdo_write(ID, 0x2480, 1, &[0]), ID, 0x2480, 1, 0x0609_0030);
}

#[test]
fn class_8_is_reset_by_a_power_cycle_only() {
    // §4.4.3 / §5: torque mode without encoder feedback, 63A0h sub-code
    // 0701h, class 8 ("can be reset only through a cycle of turning off and
    // on").
    let mut r = rig();
    write(&mut r, 0x6060, 0, &[4]);
    write(&mut r, 0x6040, 0, &[0x06, 0]);
    r.run_ms(5);
    r.take();
    write(&mut r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(50);
    assert_eq!(statusword(&mut r) & 0x4F, FAULT);
    for cw in [0x00, 0x80, 0x00, 0x80] {
        write(&mut r, 0x6040, 0, &[cw, 0]);
        r.run_ms(5);
    }
    assert_eq!(statusword(&mut r) & 0x4F, FAULT, "fault reset refused");
    // NMT Reset Node restarts the drive (§4.2: as at power-on).
    r.send("000#81 01");
    r.run_ms(5);
    assert_eq!(statusword(&mut r) & 0x4F, 0x40, "switch on disabled");
}

/// A rotary axis (degrees of the shaft) with the positive limit switch at
/// +90°.
fn limited_axis() -> AxisParams {
    let mut a = AxisParams::rotary_degrees(3.0e-5);
    a.positive_limit = Some(90.0);
    a
}

#[test]
fn limit_switch_stop_raises_8612h() {
    // §5 8612h "Limit switch activation", class 2; sub-code 0801h
    // "Positive limit activation", 0803h "Positive movement with active
    // positive limit".
    let mut r = rig_on(limited_axis());
    write(&mut r, 0x6060, 0, &[3]);
    enable(&mut r);
    r.take();
    write(&mut r, 0x60FF, 0, &600i32.to_le_bytes()); // 60 rpm
    // 100 (rpm)/s (6083h default): the switch is reached after ~540 ms.
    r.run_ms(1000);
    let frames = r.take();
    assert!(has_emcy(&frames, 0x8612, 0x0801), "{frames:?}");
    assert_eq!(statusword(&mut r) & 0x6F, QUICK_STOP_ACTIVE);
    // DI7 (2810h:03 = 0207h) shows the switch.
    assert_eq!(r.read_u32(ID, 0x3210, 1) & 0x80, 0x80, "DI7");
    // Enabled again with the target still positive: 0803h, stopped again.
    r.take();
    write(&mut r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(50);
    let frames = r.take();
    assert!(has_emcy(&frames, 0x8612, 0x0803), "{frames:?}");
    assert_eq!(statusword(&mut r) & 0x6F, QUICK_STOP_ACTIVE);
    // Away from the switch: no error.
    write(&mut r, 0x60FF, 0, &(-600i32).to_le_bytes());
    r.take();
    write(&mut r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(300);
    assert!(emcy(&r.take()).iter().all(|f| f.data()[0..2] != [0x12, 0x86]));
    assert_eq!(statusword(&mut r) & 0x6F, 0x27);
    assert_eq!(r.read_u32(ID, 0x3210, 1) & 0x80, 0, "DI7 released");
}

#[test]
fn inputs_show_the_switches() {
    // §6.4.14 3210h:01 bits 2..7 = DI2..DI7; the axis stands on its
    // positive limit switch (DI7) and home switch (DI5) at power-on.
    let mut a = limited_axis();
    a.initial_position = 100.0;
    a.home_switch = Some((95.0, 105.0));
    let mut r = rig_on(a);
    r.run_ms(5);
    assert_eq!(r.read_u32(ID, 0x3210, 1), 0xA0);
}

#[test]
fn outputs_follow_their_sources() {
    // §6.4.9–6.4.11 defaults: DO0 8040h "No Fault", DO1 0041h "Operation
    // enabled", DO2 006Ah statusword bit 10 (set in pp while disabled,
    // 2650h).
    let mut r = rig();
    r.run_ms(5);
    assert_eq!(r.read_u32(ID, 0x3230, 1), 0b101);
    enable(&mut r);
    assert_eq!(r.read_u32(ID, 0x3230, 1) & 0b011, 0b011);
}

#[test]
fn general_purpose_output_takes_set_output() {
    // §6.4.9: with 0000h "General Purpose" DO0 is bit 0 of 3230h:01;
    // §6.4.15: 3230h:02 = 00h sets bit 0, 80h clears it.
    let mut r = rig();
    write(&mut r, 0x2830, 1, &0u16.to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.read_u32(ID, 0x3230, 1) & 1, 0);
    write(&mut r, 0x3230, 2, &[0x00]);
    r.run_ms(2);
    assert_eq!(r.read_u32(ID, 0x3230, 1) & 1, 1);
    write(&mut r, 0x3230, 2, &[0x80]);
    r.run_ms(2);
    assert_eq!(r.read_u32(ID, 0x3230, 1) & 1, 0);
    // 3230h:01 written: only the General Purpose bit is taken (DO1 stays
    // "Operation enabled" = 0, DO2 statusword bit 10 = 1).
    write(&mut r, 0x3230, 1, &0b011u16.to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.read_u32(ID, 0x3230, 1), 0b101);
    // An output with an internal source ignores 3230h:02.
    write(&mut r, 0x3230, 2, &[0x81]);
    r.run_ms(2);
    assert_eq!(r.read_u32(ID, 0x3230, 1), 0b101);
}

#[test]
fn sync_guard_counts_and_reports_late_syncs() {
    // §6.4.12: 10 ms expected, 1 ms jitter, threshold 15, EMCY enabled.
    let mut r = rig();
    write(&mut r, 0x3080, 4, &10_000u32.to_le_bytes());
    write(&mut r, 0x3080, 5, &1000u16.to_le_bytes());
    write(&mut r, 0x3080, 1, &[0x03]);
    for _ in 0..5 {
        r.send("080#");
        r.run_ms(10);
    }
    assert_eq!(r.read_u32(ID, 0x3080, 3), 5, "Sync_Counter_SYGD");
    assert_eq!(r.read_u32(ID, 0x3080, 8), 0, "Out_Of_Sync_Counter_SYGD");
    r.take();
    // 20 ms since the last SYNC, twice.
    r.run_ms(10);
    r.send("080#");
    r.run_ms(20);
    r.send("080#");
    r.run_ms(2);
    // +10 per late SYNC: 20 > 15 raises 82B2h (class 2: the motor is not
    // enabled, so the EMCY only).
    assert!(has_emcy(&r.take(), 0x82B2, 0));
    assert_eq!(r.read_u32(ID, 0x3080, 8), 20);
    assert_eq!(r.read_u32(ID, 0x3080, 7), 20, "Peak_Out_Of_Sync_SYGD");
    // "Changeable only with monitoring disabled".
    Rig::assert_abort(r.sdo_write(ID, 0x3080, 4, &2000u32.to_le_bytes()), ID, 0x3080, 4, 0x0800_0022);
    // Bit 5 / 7 reset the counters on the write.
    write(&mut r, 0x3080, 1, &[0xA3]);
    assert_eq!(r.read_u32(ID, 0x3080, 8), 0);
    assert_eq!(r.read_u32(ID, 0x3080, 3), 0);
    assert_eq!(r.read_u32(ID, 0x3080, 7), 20);
}

#[test]
fn sync_breach_class_0_is_a_warning() {
    // 3080h:02 = 0: "Warning … no impediment": statusword bit 7, motion on.
    let mut r = rig();
    write(&mut r, 0x3080, 2, &[0]);
    write(&mut r, 0x3080, 4, &10_000u32.to_le_bytes());
    write(&mut r, 0x3080, 6, &[5]);
    write(&mut r, 0x3080, 1, &[0x03]);
    enable(&mut r);
    r.send("080#");
    r.run_ms(25);
    r.send("080#");
    r.run_ms(2);
    let sw = statusword(&mut r);
    assert_eq!(sw & 0x6F, 0x27, "{sw:04X}h");
    assert_eq!(sw & 0x80, 0x80, "warning");
}

#[test]
fn brake_setup_sub_0_is_as_printed() {
    // §6.4.3: Number_of_Entries 06h.
    let mut r = rig();
    assert_eq!(r.upload(ID, 0x2360, 0), Ok(vec![6]));
    assert!(r.upload(ID, 0x2360, 6).is_ok());
}

#[test]
fn error_register_and_history_record_an_error() {
    // §6.3.2 1001h (bit 0 generic), §6.3.3 1003h:01 the most recent error
    // (bits 15..0 the code), 603Fh the last error (§6.5.1).
    let (frames, _) = following_error(Some(2));
    assert!(has_emcy(&frames, 0x8611, 0));
    let mut r = rig();
    enable(&mut r);
    r.pn_mut().app.inject(Injection::FollowingError);
    r.run_ms(100);
    assert_eq!(r.read_u32(ID, 0x1001, 0) & 1, 1);
    assert_eq!(r.read_u32(ID, 0x1003, 0), 1);
    assert_eq!(r.read_u32(ID, 0x1003, 1) & 0xFFFF, 0x8611);
    assert_eq!(r.read_u32(ID, 0x603F, 0), 0x8611);
    // §6.3.3: writing 0 to sub 0 clears the history.
    write(&mut r, 0x1003, 0, &[0]);
    assert_eq!(r.read_u32(ID, 0x1003, 0), 0);
}

#[test]
fn producer_heartbeat_1017h() {
    // §6.3.15: 1017h in ms, 0 = off.
    let mut r = rig();
    write(&mut r, 0x1017, 0, &100u16.to_le_bytes());
    r.take();
    r.run_ms(350);
    let beats = r.take().into_iter().filter(|f| *f == fr("701#7F")).count();
    assert_eq!(beats, 3, "pre-operational heartbeats every 100 ms");
}

#[test]
fn error_behaviour_1029h_stops_the_node() {
    // §6.3.17 1029h:01 = 2: a communication error in Operational changes
    // to Stopped (0 = Pre-operational, the default).
    let mut r = rig();
    write(&mut r, 0x1029, 1, &[2]);
    write(&mut r, 0x1016, 1, &((5u32 << 16) | 100).to_le_bytes());
    r.send("000#01 01");
    r.send("705#05");
    r.run_ms(300);
    assert_eq!(r.node().nmt_state(), drivebus_node::NmtState::Stopped);
    let mut r = rig();
    write(&mut r, 0x1016, 1, &((5u32 << 16) | 100).to_le_bytes());
    r.send("000#01 01");
    r.send("705#05");
    r.run_ms(300);
    assert_eq!(r.node().nmt_state(), drivebus_node::NmtState::PreOperational);
}

#[test]
fn emcy_inhibit_time_1015h() {
    // §6.3.13: 1015h in 0.1 ms, the minimum time between two EMCYs.
    let mut r = rig();
    write(&mut r, 0x1015, 0, &5000u16.to_le_bytes()); // 500 ms
    write(&mut r, 0x3080, 4, &10_000u32.to_le_bytes());
    write(&mut r, 0x3080, 6, &[0]);
    write(&mut r, 0x3080, 2, &[0]); // a warning: the motor stays enabled
    write(&mut r, 0x3080, 1, &[0x03]);
    write(&mut r, 0x2480, 1, &[2]);
    enable(&mut r);
    r.take();
    // 82B2h (a late SYNC, threshold 0) and 8611h close together.
    r.send("080#");
    r.run_ms(30);
    r.send("080#");
    r.pn_mut().app.inject(Injection::FollowingError);
    r.run_ms(100);
    let first = emcy(&r.take());
    assert_eq!(first.len(), 1, "{first:?}");
    r.run_ms(500);
    let later = emcy(&r.take());
    assert!(has_emcy(&later, 0x8611, 0), "the second EMCY after the inhibit time: {later:?}");
}

/// The speed after 1 s of profile velocity at `target` (0.1 rpm), from the
/// travel in 500 ms \[0.1 rpm\].
fn pv_speed(r: &mut Rig, target: i32) -> f64 {
    write(r, 0x6083, 0, &5000u32.to_le_bytes());
    write(r, 0x6060, 0, &[3]);
    enable(r);
    write(r, 0x60FF, 0, &target.to_le_bytes());
    r.run_ms(500);
    let p0 = r.read_u32(ID, 0x6064, 0) as i32;
    r.run_ms(500);
    let p1 = r.read_u32(ID, 0x6064, 0) as i32;
    // 10 000 units per revolution (§4.4).
    f64::from(p1 - p0) / 10_000.0 / 0.5 * 600.0
}

#[test]
fn max_speed_of_the_motor_data_prevails() {
    // §6.4.1 2310h:0Bh "can never be exceeded and prevails over any other
    // setting": 100 rpm against a 60FFh of 300 rpm.
    let mut r = rig();
    write(&mut r, 0x2310, 0x0B, &1000u16.to_le_bytes());
    let v = pv_speed(&mut r, 3000);
    assert!((v - 1000.0).abs() < 20.0, "{v}");
    let mut r = rig();
    let v = pv_speed(&mut r, 3000);
    assert!((v - 3000.0).abs() < 40.0, "{v}");
}

#[test]
fn enable_takes_the_current_ramp() {
    // §6.4.5 2410h:02 Current_Enable_Ramp_MTNSTP: the time to the rated
    // current when the motor is enabled (default 10 ms: 16 ms in the
    // §4.4.2 traces).
    let mut r = rig();
    write(&mut r, 0x2410, 2, &200u16.to_le_bytes());
    write(&mut r, 0x6040, 0, &[0x06, 0]);
    r.run_ms(5);
    write(&mut r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(150);
    assert_eq!(statusword(&mut r) & 0x6F, 0x23, "still switched on");
    r.run_ms(100);
    assert_eq!(statusword(&mut r) & 0x6F, 0x27);
}

/// Enable operation after `setup`: the EMCY frames.
fn enable_after(setup: &[(u16, u8, &[u8])]) -> (Vec<Frame>, u16) {
    let mut r = rig();
    for (i, s, d) in setup {
        write(&mut r, *i, *s, d);
    }
    write(&mut r, 0x6040, 0, &[0x06, 0]);
    r.run_ms(5);
    r.take();
    r.send("601#2B 40 60 00 0F 00 00 00");
    r.run_ms(50);
    let frames = r.take();
    (frames, statusword(&mut r))
}

#[test]
fn configuration_conflicts_are_class_8() {
    // §5 63A0h 0704h: encoder feedback (2410h:01 bit 0) without a
    // configured encoder (2330h, §6.4.2: 0 disables the input).
    let (frames, sw) = enable_after(&[(0x2410, 1, &[1])]);
    assert!(has_emcy(&frames, 0x63A0, 0x0704), "{frames:?}");
    assert_eq!(sw & 0x4F, FAULT);
    // With the encoder configured the closed loop enables.
    let enc: [(u16, u8, &[u8]); 3] = [(0x2330, 1, &[0x79]), (0x2330, 2, &[0xE8, 0x03]), (0x2410, 1, &[1])];
    let (frames, _) = enable_after(&enc);
    assert!(emcy(&frames).is_empty(), "{frames:?}");
    // 0702h: load-proportional current (23A0h:01 = 1) in open loop.
    let (frames, sw) = enable_after(&[(0x23A0, 1, &[1])]);
    assert!(has_emcy(&frames, 0x63A0, 0x0702), "{frames:?}");
    assert_eq!(sw & 0x4F, FAULT);
}

#[test]
fn home_offset_is_the_homed_position() {
    // §6.5.22 / §4.4.4: after homing "Position_actual_value := Home_offset";
    // method 37 homes at the actual position.
    let mut r = rig();
    write(&mut r, 0x607C, 0, &1234i32.to_le_bytes());
    write(&mut r, 0x6098, 0, &[37]);
    write(&mut r, 0x6060, 0, &[6]);
    enable(&mut r);
    write(&mut r, 0x6040, 0, &[0x1F, 0]);
    r.run_ms(50);
    assert_eq!(statusword(&mut r) & 0x1400, 0x1400, "homing attained");
    assert_eq!(r.read_u32(ID, 0x6064, 0) as i32, 1234);
}

#[test]
fn software_limits_bound_the_target() {
    // §6.5.23 607Dh: min / max position limits (both 0 = off).
    let mut r = rig();
    write(&mut r, 0x607D, 1, &(-5000i32).to_le_bytes());
    write(&mut r, 0x607D, 2, &5000i32.to_le_bytes());
    write(&mut r, 0x6081, 0, &6000u32.to_le_bytes());
    write(&mut r, 0x6083, 0, &5000u32.to_le_bytes());
    write(&mut r, 0x6084, 0, &5000u32.to_le_bytes());
    enable(&mut r);
    write(&mut r, 0x607A, 0, &20_000i32.to_le_bytes());
    write(&mut r, 0x6040, 0, &[0x1F, 0]);
    r.run_ms(1500);
    let p = r.read_u32(ID, 0x6064, 0) as i32;
    assert!((p - 5000).abs() <= 10, "stopped at the max limit: {p}");
}

#[test]
fn motion_values_follow_the_move() {
    // §6.5.6 6062h demand, §6.5.12 606Bh velocity demand, §6.5.34 60F4h
    // following error actual value (6062h − 6064h) while moving in pp.
    let mut r = rig();
    write(&mut r, 0x6081, 0, &3000u32.to_le_bytes());
    enable(&mut r);
    write(&mut r, 0x607A, 0, &100_000i32.to_le_bytes());
    write(&mut r, 0x6040, 0, &[0x1F, 0]);
    r.run_ms(3000);
    let demand = r.read_u32(ID, 0x6062, 0) as i32;
    let vdemand = r.read_u32(ID, 0x606B, 0) as i32;
    let actual = r.read_u32(ID, 0x6064, 0) as i32;
    let fe = r.read_u32(ID, 0x60F4, 0) as i32;
    assert!(demand > 10_000 && demand < 100_000, "{demand}");
    assert_eq!(vdemand, 3000, "at 6081h");
    assert!((demand - actual - fe).abs() <= 50, "{demand} {actual} {fe}");
    // §6.5.20 6078h: the motor current (0.1 % of the rated current) while
    // the motor turns.
    let current = r.read_u32(ID, 0x6078, 0) as i16;
    assert!(current > 0, "{current}");
}

#[test]
fn following_error_window_raises_8611h() {
    // §6.5.8 / §6.5.9: the position error beyond 6065h for 6066h ms is a
    // following error (8611h, class 2480h:01 = 2 here: quick stop).
    let mut r = rig();
    write(&mut r, 0x2480, 1, &[2]);
    write(&mut r, 0x6065, 0, &1u32.to_le_bytes());
    write(&mut r, 0x6066, 0, &1u16.to_le_bytes());
    write(&mut r, 0x6081, 0, &3000u32.to_le_bytes());
    write(&mut r, 0x6083, 0, &5000u32.to_le_bytes());
    enable(&mut r);
    r.take();
    r.send("601#23 7A 60 00 40 0D 03 00");
    r.send("601#2B 40 60 00 1F 00 00 00");
    r.run_ms(300);
    let frames = r.take();
    assert!(has_emcy(&frames, 0x8611, 0), "{frames:?}");
    assert_eq!(statusword(&mut r) & 0x6F, QUICK_STOP_ACTIVE);
    // A wide window: no following error on the same move.
    let mut r = rig();
    write(&mut r, 0x6081, 0, &3000u32.to_le_bytes());
    write(&mut r, 0x6083, 0, &5000u32.to_le_bytes());
    enable(&mut r);
    r.take();
    r.send("601#23 7A 60 00 40 0D 03 00");
    r.send("601#2B 40 60 00 1F 00 00 00");
    r.run_ms(300);
    assert!(!has_emcy(&r.take(), 0x8611, 0));
}

#[test]
fn phase_current_follows_the_motor_configuration() {
    // §6.4.20 static current: Current_Max_MTRCNF (3310h:03, 80 %) while
    // turning and for Current_Idle_Delay (3310h:04, 500 ms) after,
    // Current_Min (3310h:02, 40 %) then; of Rated_Current_MTRDT (2310h:08,
    // 1.00 A); §6.4.21 3312h:01 in 10 mArms, 0 with the motor disabled.
    let mut r = rig();
    assert_eq!(r.read_u32(ID, 0x3312, 1) as i16, 0);
    enable(&mut r);
    assert_eq!(r.read_u32(ID, 0x3312, 1) as i16, 80);
    r.run_ms(600);
    assert_eq!(r.read_u32(ID, 0x3312, 1) as i16, 40, "idle after 500 ms");
    write(&mut r, 0x3310, 2, &2500u16.to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.read_u32(ID, 0x3312, 1) as i16, 25);
    write(&mut r, 0x607A, 0, &50_000i32.to_le_bytes());
    write(&mut r, 0x6040, 0, &[0x1F, 0]);
    r.run_ms(100);
    assert_eq!(r.read_u32(ID, 0x3312, 1) as i16, 80, "turning");
}

#[test]
fn power_voltage_is_the_supply() {
    // §6.4.13 3140h:03 Power_Voltage_DVSTS in 0.1 V: the machine's supply.
    let mut r = rig();
    r.run_ms(5);
    let v = r.read_u32(ID, 0x3140, 3) as u16;
    let bus = r.pn().app.drive.model().bus_voltage();
    assert!(v > 0 && (f64::from(v) - bus * 10.0).abs() <= 1.0, "{v} {bus}");
}

#[test]
fn ip_period_is_locked_while_interpolating() {
    // §6.5.33: 60C2h "can be modified only if the interpolation is not
    // active (bit ipa in the Statusword set to 0)".
    let mut r = rig();
    write(&mut r, 0x6060, 0, &[7]);
    enable(&mut r);
    write(&mut r, 0x60C2, 1, &[2]);
    write(&mut r, 0x6040, 0, &[0x1F, 0]);
    r.run_ms(5);
    assert_eq!(statusword(&mut r) & 0x1000, 0x1000, "ipa");
    Rig::assert_abort(r.sdo_write(ID, 0x60C2, 1, &[5]), ID, 0x60C2, 1, 0x0800_0022);
    write(&mut r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(5);
    write(&mut r, 0x60C2, 1, &[5]);
}

/// pv at 300 rpm, closed loop or not, on an axis blocked at +30° or free:
/// statusword bit 13 after 1.5 s.
fn slippage(closed: bool, blocked: bool) -> u16 {
    let mut a = AxisParams::rotary_degrees(3.0e-5);
    if blocked {
        a.positive_stop = Some(30.0);
    }
    let mut r = rig_on(a);
    if closed {
        write(&mut r, 0x2330, 1, &[0x79]);
        write(&mut r, 0x2330, 2, &1000u16.to_le_bytes());
        write(&mut r, 0x2410, 1, &[1]);
    }
    write(&mut r, 0x3450, 1, &50u16.to_le_bytes());
    write(&mut r, 0x6083, 0, &5000u32.to_le_bytes());
    write(&mut r, 0x6060, 0, &[3]);
    write(&mut r, 0x6040, 0, &[0x06, 0]);
    r.run_ms(5);
    write(&mut r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(600);
    write(&mut r, 0x60FF, 0, &3000i32.to_le_bytes());
    r.run_ms(1500);
    statusword(&mut r) & 0x2000
}

#[test]
fn pv_slippage_sets_bit_13_in_closed_loop() {
    // §6.4.23 3450h:01 / §6.5.35 60F8h: the speed off the target by more
    // than 60F8h (100 rpm) for 3450h:01 ms sets "max slippage error"; the
    // speed is known in closed loop only.
    assert_eq!(slippage(true, true), 0x2000);
    assert_eq!(slippage(true, false), 0);
    assert_eq!(slippage(false, true), 0);
}

#[test]
fn homing_error_raises_8613h() {
    // §5 8613h "Homing error", class 2, sub-code 0602h "Unexpected
    // clockwise limit": method 34 searches the index clockwise and meets
    // the positive limit switch (+90°) before the next index (+360°).
    let mut a = limited_axis();
    a.initial_position = 10.0;
    let mut r = rig_on(a);
    write(&mut r, 0x6098, 0, &[34]);
    write(&mut r, 0x6060, 0, &[6]);
    enable(&mut r);
    r.take();
    r.send("601#2B 40 60 00 1F 00 00 00");
    // The index is searched at 6099h:2 (6 rpm): +80° take ~2.2 s.
    r.run_ms(4000);
    let frames = r.take();
    assert!(has_emcy(&frames, 0x8613, 0x0602), "{frames:?}");
    assert_eq!(statusword(&mut r) & 0x6F, QUICK_STOP_ACTIVE);
}

#[test]
fn rated_current_scales_6078h() {
    // §6.5.20 6078h is in 0.1 % of Rated_Current_MTRDT (2310h:08): twice
    // the rated current, half the per mille for the same motor current.
    let mut r = rig();
    enable(&mut r);
    r.run_ms(20);
    let before = i32::from(r.read_u32(ID, 0x6078, 0) as i16);
    write(&mut r, 0x2310, 0x08, &200u16.to_le_bytes());
    r.run_ms(2);
    let after = i32::from(r.read_u32(ID, 0x6078, 0) as i16);
    assert!(before > 0, "{before}");
    assert!((after * 2 - before).abs() <= 2, "{before} → {after}");
}

/// A DDS6 on a machine with a holding brake (50 ms to release / apply)
/// and its I/O.
fn rig_with_brake() -> Rig {
    use drivebus_cia402::model::BrakeParams;
    let pn = drivebus_personality::build::build_custom(
        Profile::Dds6,
        ID,
        Box::new(MemoryStorage::new()),
        Box::new(Dds6::new()),
        |cfg| {
            cfg.params.io.brake =
                Some(BrakeParams { release_delay: 0.05, apply_delay: 0.05, holding_torque: 10.0 })
        },
    );
    Rig::with(pn.unwrap()).0
}

fn brake_engaged(r: &Rig) -> bool {
    r.pn().app.drive.model().brake().engaged
}

#[test]
fn handled_brake_releases_before_operation() {
    // §4.3 / §6.4.3: with 2360h:01 bit 0 the drive activates the brake
    // output at the enable and enters the operating state after
    // Release_Time_HBRKS (200 ms); on disable it engages the brake.
    // §6.4.22 3360h:02: bit 0 output active, bit 1 released, bit 2 engaged.
    let mut r = rig_with_brake();
    assert_eq!(r.read_u32(ID, 0x3360, 2), 0b100, "engaged at power-on");
    write(&mut r, 0x2360, 1, &1u16.to_le_bytes());
    write(&mut r, 0x6040, 0, &[0x06, 0]);
    r.run_ms(5);
    write(&mut r, 0x6040, 0, &[0x0F, 0]);
    r.run_ms(100);
    assert_eq!(r.read_u32(ID, 0x3360, 2), 0b001, "output active, release time running");
    assert_eq!(statusword(&mut r) & 0x6F, 0x23, "not yet operating");
    assert!(!brake_engaged(&r), "the machine's brake (50 ms) is free");
    r.run_ms(150);
    assert_eq!(r.read_u32(ID, 0x3360, 2), 0b011);
    assert_eq!(statusword(&mut r) & 0x6F, 0x27);
    write(&mut r, 0x6040, 0, &[0x06, 0]);
    r.run_ms(100);
    assert_eq!(r.read_u32(ID, 0x3360, 2), 0b000);
    assert!(brake_engaged(&r));
    r.run_ms(150);
    assert_eq!(r.read_u32(ID, 0x3360, 2), 0b100, "application time passed");
}

#[test]
fn unhandled_brake_stays_engaged() {
    // 2360h:01 = 0 (default): "the holding brake is not handled through
    // the drive": its output stays inactive, the brake engaged.
    let mut r = rig_with_brake();
    enable(&mut r);
    assert!(brake_engaged(&r));
    assert_eq!(r.read_u32(ID, 0x3360, 2) & 1, 0);
}

#[test]
fn manual_brake_control_and_brake_output_source() {
    // §6.4.3 bit 1 manual: only Control_HBRKC bit 0 (3360h:01) or the
    // 2810h:0Ah input commands the brake; §6.4.9 source 0044h "Holding
    // Brake" puts the brake output on DO0 (machine output line 1).
    let mut r = rig_with_brake();
    write(&mut r, 0x2830, 1, &0x0044u16.to_le_bytes());
    write(&mut r, 0x2360, 1, &3u16.to_le_bytes());
    write(&mut r, 0x3360, 1, &[1]);
    r.run_ms(100);
    assert!(!brake_engaged(&r), "released by hand, motor disabled");
    assert_eq!(r.read_u32(ID, 0x3230, 1) & 1, 1);
    assert_eq!(r.pn().app.drive.output_lines() & 1, 1);
    // The input: DI4 active (2810h:0Ah = 0204h) instead of the bit.
    write(&mut r, 0x3360, 1, &[0]);
    write(&mut r, 0x2810, 0x0A, &0x0204u16.to_le_bytes());
    r.run_ms(100);
    assert!(brake_engaged(&r));
    r.pn_mut().app.inject(Injection::Model(drivebus_cia402::model::ModelInjection::DigitalInput {
        line: 4,
        level: true,
    }));
    r.run_ms(100);
    assert!(!brake_engaged(&r));
}

#[test]
fn machine_inputs_reach_3210h_and_3250h() {
    // §6.4.14 DI2..DI7 = the machine's lines 2..7; §6.4.16 AI0 in mV.
    use drivebus_cia402::model::ModelInjection as Plant;
    let mut r = rig();
    r.pn_mut().app.inject(Injection::Model(Plant::DigitalInput { line: 3, level: true }));
    r.pn_mut().app.inject(Injection::Model(Plant::AnalogInput { channel: 1, volts: 2.5 }));
    r.pn_mut().app.inject(Injection::Model(Plant::AnalogInput { channel: 2, volts: -1.25 }));
    r.run_ms(5);
    assert_eq!(r.read_u32(ID, 0x3210, 1), 1 << 3);
    assert_eq!(r.read_u32(ID, 0x3250, 1) as i16, 2500);
    assert_eq!(r.read_u32(ID, 0x3251, 1) as i16, -1250);
}

#[test]
fn fault_reset_input_di2() {
    // §6.4.8 2810h:02 default 0502h: a falling edge of DI2 resets a fault.
    use drivebus_cia402::model::ModelInjection as Plant;
    let mut r = rig();
    enable(&mut r);
    r.pn_mut().app.inject(Injection::FollowingError);
    r.run_ms(50);
    assert_eq!(statusword(&mut r) & 0x4F, FAULT);
    r.pn_mut().app.inject(Injection::Model(Plant::DigitalInput { line: 2, level: true }));
    r.run_ms(10);
    assert_eq!(statusword(&mut r) & 0x4F, FAULT, "rising edge: nothing");
    r.pn_mut().app.inject(Injection::Model(Plant::DigitalInput { line: 2, level: false }));
    r.run_ms(10);
    assert_eq!(statusword(&mut r) & 0x4F, 0x40, "switch on disabled");
}
