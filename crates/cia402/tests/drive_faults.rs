//! Faults and EMCY (CiA 402-2 §6.2 fault reaction, 603Fh; CiA 301 §7.2.7
//! EMCY on 080h + node-ID with 1001h) and the 6007h abort connection
//! reaction, on the virtual bus.

mod drive_rig;
use drive_rig::*;
use drivebus_can::Frame;
use drivebus_cia402::drive::Injection;
use drivebus_cia402::model::ModelInjection as M;

const FAULT: u16 = 0x0228;
const SOD: u16 = 0x0260;

/// Enable, inject, expect the EMCY frame and the fault state, then clear
/// and fault-reset: EMCY 0000h (error reset) and Switch on disabled.
fn fault_class(inj: Injection, code: u16, register: u8) {
    let mut r = Rig::generic();
    r.start();
    r.enable();
    r.run_ms(2.0);
    r.take();
    r.drive_mut().inject(inj);
    r.run_ms(100.0);
    assert_eq!(r.emcys(), vec![emcy(code, register)], "EMCY for {code:04X}");
    assert_eq!(r.statusword(), FAULT);
    assert_eq!(r.read(0x603F, 0), u32::from(code));
    assert_eq!(r.read(0x1001, 0), u32::from(register));
    r.drive_mut().inject(Injection::Model(M::Clear));
    r.controlword(0x80);
    r.run_ms(1.0);
    assert_eq!(r.emcys(), vec![emcy(0x0000, 0x00)], "error reset EMCY");
    assert_eq!(r.statusword(), SOD);
    assert_eq!(r.read(0x603F, 0), 0);
    assert_eq!(r.read(0x1001, 0), 0);
    // And it runs again.
    r.controlword(0x06);
    r.controlword(0x0F);
    assert_eq!(r.statusword() & 0x6F, 0x27);
}

// 1001h bits (CiA 301 §7.5.2.2): 0 generic, 1 current, 2 voltage,
// 3 temperature, 5 device profile.
#[test]
fn over_current_2310() {
    fault_class(Injection::Model(M::OverCurrent), 0x2310, 0x03);
}

#[test]
fn dc_link_over_voltage_3210() {
    fault_class(Injection::Model(M::BusOverVoltage), 0x3210, 0x05);
}

#[test]
fn dc_link_under_voltage_3220() {
    fault_class(Injection::Model(M::BusUnderVoltage), 0x3220, 0x05);
}

#[test]
fn winding_over_temperature_4310() {
    fault_class(Injection::Model(M::OverTemperature), 0x4310, 0x09);
}

#[test]
fn following_error_8611() {
    fault_class(Injection::FollowingError, 0x8611, 0x21);
}

#[test]
fn following_error_from_a_blocked_load_sets_bit13_then_faults() {
    let mut r = Rig::generic();
    r.start();
    r.write(0x6065, 0, &1000u32.to_le_bytes()); // 1°
    r.write(0x6066, 0, &20u16.to_le_bytes());
    r.enable();
    r.run_ms(2.0);
    r.take();
    // A load torque above the peak torque (2.56 Nm) drags the axis away.
    r.drive_mut().inject(Injection::Model(M::LoadTorqueStep(3.0)));
    r.run_ms(100.0);
    assert_eq!(r.emcys(), vec![emcy(0x8611, 0x21)]);
    assert_eq!(r.read(0x603F, 0), 0x8611);
}

#[test]
fn persisting_condition_faults_again_after_reset() {
    let mut r = Rig::generic();
    r.start();
    r.enable();
    r.drive_mut().inject(Injection::Model(M::BusUnderVoltage));
    r.run_ms(5.0);
    assert_eq!(r.emcys(), vec![emcy(0x3220, 0x05)]);
    r.controlword(0x80);
    r.run_ms(2.0);
    // Reset clears 3220h (error reset), the condition raises it again.
    assert_eq!(r.emcys(), vec![emcy(0x0000, 0x00), emcy(0x3220, 0x05)]);
    assert_eq!(r.statusword(), FAULT);
}

#[test]
fn heartbeat_loss_executes_6007h_fault() {
    let mut r = Rig::generic();
    r.start();
    // 1016h:1 consume node 1's heartbeat, 100 ms.
    r.write(0x1016, 1, &0x0001_0064u32.to_le_bytes());
    r.send(Frame::new(0x701, &[0x05]));
    r.enable();
    r.run_ms(2.0);
    r.take();
    r.run_ms(150.0);
    // CiA 301: the node raises 8130h; 6007h = 1 → fault with 603Fh = 8130h.
    let e = r.emcys();
    assert_eq!(e.first(), Some(&emcy(0x8130, 0x11)), "{e:?}");
    assert_eq!(r.statusword(), FAULT);
    assert_eq!(r.read(0x603F, 0), 0x8130);
}

#[test]
fn heartbeat_loss_with_6007h_quick_stop() {
    let mut r = Rig::generic();
    r.start();
    r.write(0x6007, 0, &3i16.to_le_bytes());
    r.write(0x1016, 1, &0x0001_0064u32.to_le_bytes());
    r.send(Frame::new(0x701, &[0x05]));
    r.enable();
    r.run_ms(150.0);
    // 6007h = 3: quick stop command → Quick stop active → SOD (605Ah = 2).
    assert_eq!(r.statusword(), SOD);
    assert_eq!(r.read(0x603F, 0), 0);
}

#[test]
fn nmt_stop_while_enabled_aborts_the_connection() {
    let mut r = Rig::generic();
    r.start();
    r.enable();
    r.send(Frame::new(0x000, &[0x02, ID]));
    r.run_ms(5.0);
    assert_eq!(r.drive().statusword(), FAULT);
    assert_eq!(r.drive().state_machine().fault_code(), 0x8130);
}

#[test]
fn fault_reaction_option_0_disables_at_once() {
    let mut r = Rig::generic();
    r.write(0x605E, 0, &0i16.to_le_bytes());
    r.enable();
    r.drive_mut().inject(Injection::Fault(0x5530));
    r.run_ms(0.2);
    assert_eq!(r.statusword(), FAULT);
}

/// A cyclic mode stand-in (csv): holds the target velocity.
struct Csv;

impl drivebus_cia402::drive::ModeHandler for Csv {
    fn supported_modes(&self) -> u32 {
        drivebus_cia402::drive::op::supported_bit(drivebus_cia402::drive::op::CSV)
    }
    fn enter(&mut self, _: i8, _: &drivebus_cia402::drive::ModeIo<'_>) {}
    fn step(
        &mut self,
        _: i8,
        _: &drivebus_cia402::drive::ModeIo<'_>,
        _: f64,
    ) -> drivebus_cia402::drive::ModeOutput {
        drivebus_cia402::drive::ModeOutput::hold()
    }
}

#[test]
fn sync_loss_in_a_cyclic_mode_faults() {
    let dn = drivebus_cia402::drive::generic_drive_with(ID, Default::default(), vec![Box::new(Csv)]);
    let mut r = Rig::with(dn);
    r.start();
    // 1006h: 1 ms communication cycle; the node reports a missing SYNC.
    r.write(0x1006, 0, &1000u32.to_le_bytes());
    r.write(0x6060, 0, &[9]);
    r.enable();
    for _ in 0..10 {
        r.send(Frame::new(0x080, &[]));
        r.run_ms(1.0);
    }
    assert_eq!(r.statusword() & 0x6F, 0x27);
    r.take();
    r.run_ms(5.0);
    assert_eq!(r.emcys(), vec![emcy(0x8700, 0x21)]);
    assert_eq!(r.read(0x603F, 0), 0x8700);
}

/// `Drive::set_fault_action`: a fault taken without action signals its
/// EMCY while the condition lasts and the drive stays enabled; the error
/// reset EMCY follows when the condition is gone. A per-code reaction
/// replaces 605Eh's.
#[test]
fn fault_actions_per_code() {
    use drivebus_cia402::drive::ErrorReaction;
    use drivebus_cia402::state_machine::Reaction;
    let mut r = Rig::generic();
    r.start();
    r.drive_mut().set_fault_action(0x3210, Some(ErrorReaction::NoAction));
    r.enable();
    r.run_ms(2.0);
    r.take();
    r.drive_mut().inject(Injection::Model(M::BusOverVoltage));
    r.run_ms(20.0);
    assert_eq!(r.emcys(), vec![emcy(0x3210, 0x05)], "signalled once");
    assert_eq!(r.statusword() & 0x6F, 0x27, "still enabled");
    assert_eq!(r.drive().ignored_fault(), Some(0x3210));
    r.drive_mut().inject(Injection::Model(M::Clear));
    r.run_ms(5.0);
    assert_eq!(r.emcys(), vec![emcy(0x0000, 0x00)], "condition gone");
    assert_eq!(r.drive().ignored_fault(), None);
    // A reaction instead of 605Eh's (generic default 2, quick stop ramp).
    r.drive_mut().set_fault_action(0x3210, Some(ErrorReaction::React(Reaction::DisableDrive)));
    r.drive_mut().inject(Injection::Model(M::BusOverVoltage));
    r.run_ms(1.0);
    assert_eq!(r.statusword(), FAULT, "straight to Fault");
}
