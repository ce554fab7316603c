//! The CiA 402 objects of the iPOS object table acting as the manual's
//! chapters 4, 5, 7 and 10 describe them, on the built personality (the
//! ledger `src/ipos/ledger.tsv` names these tests). The examples' motor:
//! 2000 increments per revolution, speeds in increments per 1 ms sample
//! (16.16), accelerations per sample² (16.16).

mod ipos_rig;

use ipos_rig::*;

/// 20 increments per 1 ms sample (600 rpm), 16.16.
const SPEED: i32 = 20 << 16;

/// The motor's speed `ms` after the command `cw`, from pv at [`SPEED`].
fn speed_after_command(setup: impl FnOnce(&mut Rig), cw: u16, ms: u64) -> f64 {
    let mut r = enabled_in(3);
    setup(&mut r);
    r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
    r.run_ms(300);
    assert!((r.motor_rpm() - 600.0).abs() < 10.0, "at speed: {} rpm", r.motor_rpm());
    r.controlword(cw);
    r.run_ms(ms);
    r.motor_rpm()
}

/// §4.4.8 605Bh: Shutdown from Operation enabled switches the power stage
/// off at once (0: the motor coasts) or after the slow-down ramp 6083h
/// (1: 20 IU at 1 IU/sample² take 20 ms).
#[test]
fn shutdown_option_code() {
    let coast = speed_after_command(|r| r.sdo(0x605B, 0, &0i16.to_le_bytes()), 0x06, 30);
    let ramp = speed_after_command(|r| r.sdo(0x605B, 0, &1i16.to_le_bytes()), 0x06, 30);
    assert!(coast > 300.0, "605Bh = 0 coasts: {coast} rpm after 30 ms");
    assert!(ramp.abs() < 30.0, "605Bh = 1 ramps down in 20 ms: {ramp} rpm");
}

/// §4.4.9 605Ch: Disable operation likewise (default 1: the ramp).
#[test]
fn disable_operation_option_code() {
    let coast = speed_after_command(|r| r.sdo(0x605C, 0, &0i16.to_le_bytes()), 0x07, 30);
    let ramp = speed_after_command(|_| {}, 0x07, 30);
    assert!(coast > 300.0, "605Ch = 0 coasts: {coast} rpm after 30 ms");
    assert!(ramp.abs() < 30.0, "605Ch = 1 (default) ramps down in 20 ms: {ramp} rpm");
}

/// §4.4.10 605Dh: Halt stops on the slow-down ramp 6083h (1, 20 ms) or the
/// quick-stop ramp 6085h (2: 4 IU/sample², 5 ms) and stays in Operation
/// enabled.
#[test]
fn halt_option_code() {
    let slow = speed_after_command(|_| {}, 0x10F, 12);
    let quick = speed_after_command(|r| r.sdo(0x605D, 0, &2i16.to_le_bytes()), 0x10F, 12);
    assert!(slow > 150.0, "605Dh = 1: still {slow} rpm after 12 ms of a 20 ms ramp");
    assert!(quick.abs() < 40.0, "605Dh = 2: stopped in 5 ms, {quick} rpm");
    let mut r = enabled_in(3);
    r.controlword(0x10F);
    r.run_ms(5);
    assert_eq!(r.upload(0x6041, 0, 2) & 0x6F, 0x27, "halted in Operation enabled");
}

/// §4.4.7 605Ah: the quick stop ramps down on 6085h (2, default) and ends
/// in Switch on disabled, or stays in Quick stop active (6).
#[test]
fn quick_stop_option_code() {
    for (code, state) in [(2i16, 0x40u16), (6, 0x07)] {
        let mut r = enabled_in(3);
        r.sdo(0x605A, 0, &code.to_le_bytes());
        r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
        r.run_ms(300);
        r.controlword(0x02);
        r.run_ms(12);
        assert!(r.motor_rpm().abs() < 40.0, "605Ah = {code}: stopped on 6085h in 5 ms");
        r.run_ms(20);
        let sw = r.upload(0x6041, 0, 2) as u16;
        let mask = if state == 0x40 { 0x4F } else { 0x6F };
        assert_eq!(sw & mask, state, "605Ah = {code}: {sw:04X}h");
    }
}

/// §4.4.11 605Eh: a fault (over-voltage, non-fatal) disables the drive at
/// once (0: coasting) or stops on the quick-stop ramp first (2, default).
#[test]
fn fault_reaction_option_code() {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Model;
    let after_fault = |code: i16| {
        let mut r = enabled_in(3);
        r.sdo(0x605E, 0, &code.to_le_bytes());
        r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
        r.run_ms(300);
        r.bus
            .node_mut::<PersonalityDevice>(r.dut)
            .unwrap()
            .app
            .inject(Injection::Model(Model::BusOverVoltage));
        r.run_ms(10);
        (r.motor_rpm(), r.upload(0x603F, 0, 2) as u16)
    };
    let (coast, code) = after_fault(0);
    assert_eq!(code, 0x3210);
    assert!(coast > 300.0, "605Eh = 0: coasting, {coast} rpm after 10 ms");
    let (stopped, _) = after_fault(2);
    assert!(stopped.abs() < 30.0, "605Eh = 2: quick-stop ramp, {stopped} rpm");
}

/// §7.2.10 / §7.2.11 / §7.2.16: a following error beyond 6065h for longer
/// than 6066h is a control error: fault 8611h, 2000h bit 3; 60F4h shows
/// the error while it grows.
#[test]
fn following_error_window_and_time_out() {
    let mut r = enabled_in(1);
    r.sdo(0x6065, 0, &5u32.to_le_bytes());
    r.sdo(0x6066, 0, &3u16.to_le_bytes());
    r.sdo(0x6081, 0, &(100u32 << 16).to_le_bytes());
    r.sdo(0x6083, 0, &(20u32 << 16).to_le_bytes());
    r.target_position_rpdo2(100_000);
    r.controlword(0x1F);
    r.run_ms(20);
    assert_eq!(r.upload(0x603F, 0, 2) as u16, 0x8611, "control error");
    assert_ne!(r.upload(0x2000, 0, 2) & 1 << 3, 0, "2000h bit 3");
    r.run_ms(100);
    assert_eq!(r.upload(0x6041, 0, 2) & 0x4F, 0x08, "fault after the fault reaction");
    // With a window of one revolution the same move runs.
    let mut r = enabled_in(1);
    r.sdo(0x6081, 0, &(100u32 << 16).to_le_bytes());
    r.sdo(0x6083, 0, &(20u32 << 16).to_le_bytes());
    r.target_position_rpdo2(100_000);
    r.controlword(0x1F);
    r.run_ms(20);
    assert_eq!(r.upload(0x603F, 0, 2), 0);
    assert_ne!(r.upload(0x60F4, 0, 4), 0, "60F4h: the lag while accelerating");
}

/// §10.2.4 / §10.2.5: pv target reached (bit 10) once 606Ch is within
/// 606Dh of 60FFh for 606Eh ms; §10.2.6: bit 12 (speed = 0) while |606Ch|
/// is below 606Fh. In rpm (6094h = 131072/60), as "user-defined velocity
/// units" (§10.2.4): a 1 ms speed jitters by one increment per sample.
#[test]
fn velocity_window_time_and_threshold() {
    let mut r = enabled_in(3);
    r.sdo(0x6094, 1, &131_072u32.to_le_bytes());
    r.sdo(0x6094, 2, &60u32.to_le_bytes());
    r.sdo(0x606D, 0, &100u16.to_le_bytes());
    r.sdo(0x606E, 0, &100u16.to_le_bytes());
    r.sdo(0x606F, 0, &50u16.to_le_bytes());
    r.run_ms(50);
    assert_ne!(r.upload(0x6041, 0, 2) & 1 << 12, 0, "standing: bit 12");
    r.sdo(0x60FF, 0, &600i32.to_le_bytes());
    // 20 ms of ramp, then 100 ms in the window.
    r.run_ms(60);
    let sw = r.upload(0x6041, 0, 2);
    assert_eq!(sw & (1 << 10 | 1 << 12), 0, "running, not yet 606Eh in the window: {sw:04X}h");
    let t = r.wait_sw("target reached", 1 << 10, 1 << 10, 200);
    assert!(t >= 40, "bit 10 after 606Eh = 100 ms in the window ({t} ms more)");
}

/// §5.1.1 607Eh: bit 7 negates positions (607Ah, 6064h), bit 6 velocities
/// (60FFh, 606Ch): the motor turns the other way, the objects read the
/// user's sign.
#[test]
fn polarity() {
    let mut r = enabled_in(1);
    r.sdo(0x607E, 0, &[0x80]);
    r.target_position_rpdo2(1000);
    start_and_wait(&mut r, 0x1F, 2000);
    assert!((r.motor_revs() + 0.5).abs() < 0.01, "half a turn negative: {}", r.motor_revs());
    assert!((r.upload(0x6064, 0, 4) - 1000).abs() <= FEW_COUNTS);
    let mut r = enabled_in(3);
    r.sdo(0x607E, 0, &[0x40]);
    r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
    r.run_ms(300);
    assert!((r.motor_rpm() + 600.0).abs() < 10.0, "{} rpm", r.motor_rpm());
    assert!((r.upload(0x606C, 0, 4) - i64::from(SPEED)).abs() <= 65536);
}

/// §15.2.3 6080h: the speed is limited to it (0, the default, is no limit).
#[test]
fn max_motor_speed() {
    let mut r = enabled_in(3);
    r.sdo(0x6080, 0, &(10u32 << 16).to_le_bytes());
    r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
    r.run_ms(300);
    assert!((r.motor_rpm() - 300.0).abs() < 10.0, "limited to 10 IU = 300 rpm: {}", r.motor_rpm());
}

/// §10.1 remark 2: a target velocity set before profile velocity is
/// entered does not start the motion; writing 60FFh again (even the same
/// value) does.
#[test]
fn target_velocity_must_be_written_again_in_pv() {
    let mut r = enabled_in(1);
    r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
    r.modes_of_operation(3);
    r.run_ms(200);
    assert!(r.motor_rpm().abs() < 1.0, "standing: {} rpm", r.motor_rpm());
    assert_eq!(r.upload(0x60FF, 0, 4), i64::from(SPEED), "60FFh keeps its value");
    r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
    r.run_ms(200);
    assert!((r.motor_rpm() - 600.0).abs() < 10.0, "{} rpm", r.motor_rpm());
}

/// §10.2.8 / §10.2.9: with a max slippage 60F8h set, a speed error beyond
/// it for longer than 2005h is a control error (8611h, 2000h bit 3); with
/// 60F8h = 0 (the speed control error off, as in the set-up by default)
/// the same blocked motor does not fault. The motor is blocked by the
/// machine's holding brake, held engaged.
#[test]
fn max_slippage_and_time_out() {
    use drivebus_cia402::drive::BrakeControl;
    use drivebus_cia402::model::BrakeParams;
    let blocked = |slippage: i32| {
        let mut r = Rig::on(|c| {
            c.params.io.brake =
                Some(BrakeParams { release_delay: 0.0, apply_delay: 0.0, holding_torque: 100.0 });
        });
        map_examples_rpdos(&mut r);
        r.start_remote_node();
        r.modes_of_operation(3);
        r.enable();
        r.sdo(0x60F8, 0, &slippage.to_le_bytes());
        r.sdo(0x2005, 0, &20u16.to_le_bytes());
        r.bus
            .node_mut::<PersonalityDevice>(r.dut)
            .unwrap()
            .app
            .drive
            .set_brake_control(BrakeControl::Engaged);
        r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
        r.run_ms(100);
        r
    };
    let mut r = blocked(2 << 16);
    assert_eq!(r.upload(0x603F, 0, 2) as u16, 0x8611, "control error");
    assert_ne!(r.upload(0x2000, 0, 2) & 1 << 3, 0, "2000h bit 3");
    let mut r = blocked(0);
    assert_eq!(r.upload(0x603F, 0, 2), 0, "off with 60F8h = 0");
}

/// §7.2.14 / §7.2.15: on a modulo axis (607Bh = 0..1999, one revolution)
/// 60F2h rado decides the way: 00 (default) as a linear axis (absolute
/// 3000 from 0 is one and a half turns, Figure 7.2.2), 01 only negative,
/// 10 only positive, 11 the shortest way; 6064h wraps in the range.
#[test]
fn positioning_option_code_on_a_modulo_axis() {
    let turns = |rado: u16, target: i32| {
        let mut r = enabled_in(1);
        r.sdo(0x607B, 1, &0i32.to_le_bytes());
        r.sdo(0x607B, 2, &1999i32.to_le_bytes());
        r.sdo(0x60F2, 0, &rado.to_le_bytes());
        let revs = r.motor_revs();
        r.target_position_rpdo2(target);
        start_and_wait(&mut r, 0x1F, 3000);
        (r.motor_revs() - revs, r.upload(0x6064, 0, 4))
    };
    let (t, p) = turns(0x00, 3000);
    assert!((t - 1.5).abs() < 0.01 && (p - 1000).abs() <= FEW_COUNTS, "rado 00: {t} turns to {p}");
    let (t, _) = turns(0x40, 500);
    assert!((t + 0.75).abs() < 0.01, "rado 01: negative only, {t} turns");
    let (t, _) = turns(0x80, 1500);
    assert!((t - 0.75).abs() < 0.01, "rado 10: positive only, {t} turns");
    let (t, _) = turns(0xC0, 1500);
    assert!((t + 0.25).abs() < 0.01, "rado 11: the shortest way, {t} turns");
}

/// Over-voltage in pv at speed: the motor's speed 12 ms later, the state
/// bits, and the EMCY codes sent.
fn over_voltage_in_pv(setup: impl FnOnce(&mut Rig)) -> (f64, u16, Rig) {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Model;
    let mut r = enabled_in(3);
    setup(&mut r);
    r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
    r.run_ms(300);
    r.emcy.clear();
    r.bus.node_mut::<PersonalityDevice>(r.dut).unwrap().app.inject(Injection::Model(Model::BusOverVoltage));
    r.run_ms(12);
    let sw = r.upload(0x6041, 0, 2) as u16;
    (r.motor_rpm(), sw, r)
}

/// §4.4.11: 605Eh = −1, "no action" for a non-fatal error (over-voltage):
/// the motion goes on, EMCY 3210h and 2000h bit 12 signal it.
#[test]
fn fault_reaction_no_action() {
    let (rpm, sw, mut r) = over_voltage_in_pv(|r| r.sdo(0x605E, 0, &(-1i16).to_le_bytes()));
    assert_eq!(sw & 0x6F, 0x27, "still Operation enabled: {sw:04X}h");
    assert!((rpm - 600.0).abs() < 10.0, "still running: {rpm} rpm");
    assert_eq!(r.emcy.first().map(|f| f.data()[..2].to_vec()), Some(vec![0x10, 0x32]), "EMCY 3210h");
    assert_ne!(r.upload(0x2000, 0, 2) & 1 << 12, 0, "2000h bit 12");
}

/// §4.4.13 / §4.4.14: a 2114h bit hands its error to the 2113h option,
/// before 605Eh: over-voltage (bit 12, sub 12) with option 2 stops on the
/// quick-stop ramp although 605Eh = 0 would let the motor coast.
#[test]
fn fault_override_option_codes() {
    let (rpm, _, _) = over_voltage_in_pv(|r| {
        r.sdo(0x605E, 0, &0i16.to_le_bytes());
        r.sdo(0x2113, 0x0C, &2u16.to_le_bytes());
        r.sdo(0x2114, 0, &0x9000u16.to_le_bytes());
    });
    assert!(rpm.abs() < 40.0, "quick-stop ramp by 2113h:0Ch: {rpm} rpm");
    let (rpm, _, _) = over_voltage_in_pv(|r| r.sdo(0x605E, 0, &0i16.to_le_bytes()));
    assert!(rpm > 300.0, "605Eh = 0 without the override: coasting, {rpm} rpm");
}

/// §4.4.11: 605Eh is for the non-fatal errors; an over-current (fatal)
/// disables the drive at once even with 605Eh = 2.
#[test]
fn fatal_errors_disable_the_drive() {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Model;
    let mut r = enabled_in(3);
    r.sdo(0x60FF, 0, &SPEED.to_le_bytes());
    r.run_ms(300);
    r.bus.node_mut::<PersonalityDevice>(r.dut).unwrap().app.inject(Injection::Model(Model::OverCurrent));
    r.run_ms(12);
    assert_eq!(r.upload(0x603F, 0, 2) as u16, 0x2310);
    assert_eq!(r.upload(0x6041, 0, 2) & 0x4F, 0x08, "Fault at once");
    assert!(r.motor_rpm() > 300.0, "coasting: {} rpm", r.motor_rpm());
}
