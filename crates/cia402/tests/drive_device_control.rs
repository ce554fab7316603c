//! CiA 402-2 §6.2 device control on the virtual bus: controlword by SDO and
//! RPDO, exact statuswords, mode switching, write validation aborts.

mod drive_rig;
use drive_rig::*;
use drivebus_can::Frame;

// Statusword codings (CiA 402-2 §6.2.2 table "State coding") with bit 9
// remote set and bit 5 quick stop (low-active) = 1 outside Quick stop active;
// bit 4 voltage enabled while the power stage may be energised.
const SOD: u16 = 0x0260;
const RTSO: u16 = 0x0231;
const SO: u16 = 0x0233;
const OE: u16 = 0x0237;
const QSA: u16 = 0x0217;
const FAULT: u16 = 0x0228;
const TARGET_REACHED: u16 = 1 << 10;

#[test]
fn state_walk_via_sdo() {
    let mut r = Rig::generic();
    assert_eq!(r.statusword(), SOD);
    r.controlword(0x06);
    assert_eq!(r.statusword(), RTSO);
    r.controlword(0x07);
    assert_eq!(r.statusword(), SO);
    r.controlword(0x0F);
    assert_eq!(r.statusword(), OE);
    // pp at rest: in the position window for 6068h (10 ms) → target reached.
    r.run_ms(12.0);
    assert_eq!(r.statusword(), OE | TARGET_REACHED);
    // Disable operation (605Ch = 1: slow-down ramp, already at rest).
    r.controlword(0x07);
    r.run_ms(1.0);
    assert_eq!(r.statusword(), SO);
    // Quick stop from operation enabled (605Ah = 2): QSA, then SOD.
    r.controlword(0x0F);
    r.run_ms(1.0);
    r.controlword(0x0B);
    assert_eq!(r.statusword(), QSA);
    r.run_ms(2.0);
    assert_eq!(r.statusword(), SOD);
    // Shutdown, then disable voltage (transition 7).
    r.controlword(0x06);
    assert_eq!(r.statusword(), RTSO);
    r.controlword(0x00);
    assert_eq!(r.statusword(), SOD);
    // 6061h shows pp.
    assert_eq!(r.read(0x6061, 0), 1);
}

#[test]
fn controlword_by_rpdo_and_statusword_tpdo() {
    let mut r = Rig::generic();
    r.start();
    // RPDO1 = controlword (0x200 + id); TPDO1 = statusword, event-driven.
    r.send(Frame::new(0x205, &[0x06, 0x00]));
    assert_eq!(r.take(), vec![Frame::new(0x185, &RTSO.to_le_bytes())]);
    r.send(Frame::new(0x205, &[0x0F, 0x00]));
    assert_eq!(r.take(), vec![Frame::new(0x185, &OE.to_le_bytes())]);
    r.run_ms(12.0);
    assert_eq!(r.take(), vec![Frame::new(0x185, &(OE | TARGET_REACHED).to_le_bytes())]);
}

#[test]
fn fault_reset_needs_rising_edge_of_bit7() {
    let mut r = Rig::generic();
    r.enable();
    r.drive_mut().inject(drivebus_cia402::drive::Injection::Fault(0x5530));
    r.run_ms(1.0);
    assert_eq!(r.statusword(), FAULT);
    assert_eq!(r.read(0x603F, 0), 0x5530);
    r.controlword(0x80);
    assert_eq!(r.statusword(), SOD);
    assert_eq!(r.read(0x603F, 0), 0);
    // Bit 7 held: no command decoded until it falls (CiA 402-2 §6.2.1).
    r.controlword(0x86);
    assert_eq!(r.statusword(), SOD);
    r.controlword(0x06);
    assert_eq!(r.statusword(), RTSO);
}

#[test]
fn mode_switch_on_the_fly() {
    let mut r = Rig::generic();
    r.enable();
    r.write(0x6060, 0, &[3]);
    // CiA 402-2 §6.3.2: takes effect at once, 6061h shows it.
    assert_eq!(r.read(0x6061, 0), 3);
    r.write(0x60FF, 0, &360_000i32.to_le_bytes());
    r.run_ms(200.0);
    let v = r.read(0x606C, 0) as i32;
    assert!((v - 360_000).abs() < 20_000, "pv running: {v}");
    r.write(0x6060, 0, &[1]);
    assert_eq!(r.read(0x6061, 0), 1);
}

#[test]
fn write_validation_aborts() {
    let mut r = Rig::generic();
    // Unsupported modes (ip 7, reserved 5, manufacturer −1).
    for m in [7u8, 5, 0xFF] {
        r.write_aborts(0x6060, 0, &[m], 0x0609_0030);
    }
    // 607Dh: min > max.
    r.write(0x607D, 2, &1000i32.to_le_bytes());
    r.write_aborts(0x607D, 1, &2000i32.to_le_bytes(), 0x0609_0036);
    r.write(0x607D, 1, &(-1000i32).to_le_bytes());
    r.write_aborts(0x607D, 2, &(-2000i32).to_le_bytes(), 0x0609_0036);
    // 607Bh likewise.
    r.write(0x607B, 2, &359_999i32.to_le_bytes());
    r.write_aborts(0x607B, 1, &400_000i32.to_le_bytes(), 0x0609_0036);
    // Option codes out of range: above → 0031, below → 0032.
    r.write_aborts(0x605A, 0, &9i16.to_le_bytes(), 0x0609_0031);
    r.write_aborts(0x605A, 0, &(-1i16).to_le_bytes(), 0x0609_0032);
    r.write_aborts(0x605D, 0, &0i16.to_le_bytes(), 0x0609_0032);
    r.write_aborts(0x605E, 0, &5i16.to_le_bytes(), 0x0609_0031);
    r.write_aborts(0x6007, 0, &4i16.to_le_bytes(), 0x0609_0031);
    r.write(0x605A, 0, &6i16.to_le_bytes());
    // Zero ramps and factors.
    r.write_aborts(0x6083, 0, &0u32.to_le_bytes(), 0x0609_0032);
    r.write_aborts(0x6092, 1, &0u32.to_le_bytes(), 0x0609_0032);
    // Motion profile type: 0 and 1 only.
    r.write_aborts(0x6086, 0, &2i16.to_le_bytes(), 0x0609_0030);
    r.write(0x6086, 0, &1i16.to_le_bytes());
    // Polarity: bits 6 and 7 only.
    r.write_aborts(0x607E, 0, &[0x01], 0x0609_0030);
    // Read-only live values.
    r.write_aborts(0x6041, 0, &[0, 0], 0x0601_0002);
    r.write_aborts(0x6064, 0, &[0, 0, 0, 0], 0x0601_0002);
    // 6502h: pp, vl, pv, tq.
    assert_eq!(r.read(0x6502, 0), 0b1111);
}

#[test]
fn quick_stop_option_6_holds_in_qsa() {
    let mut r = Rig::generic();
    r.write(0x605A, 0, &6i16.to_le_bytes());
    r.enable();
    r.controlword(0x0B);
    r.run_ms(5.0);
    // 605Ah 5–8: stay in Quick stop active; enable operation leaves it (16).
    assert_eq!(r.statusword() & 0x6F, 0x07);
    r.controlword(0x0F);
    assert_eq!(r.statusword() & 0x6F, 0x27);
}

#[test]
fn interlock_keeps_the_drive_off() {
    let mut cfg = drivebus_cia402::drive::DriveConfig::default();
    cfg.io.interlock = true;
    let mut r = Rig::with_config(cfg);
    r.enable();
    r.drive_mut().set_interlock(true);
    r.run_ms(1.0);
    assert_eq!(r.statusword(), SOD);
    assert_eq!(r.read(0x60FD, 0) & 0x8, 0x8);
    r.drive_mut().set_interlock(false);
    r.run_ms(1.0);
    r.enable();
    assert_eq!(r.statusword(), OE);
}

#[test]
fn nmt_reset_node_restarts_the_application() {
    let mut r = Rig::generic();
    r.write(0x6081, 0, &1234u32.to_le_bytes());
    r.enable();
    r.send(Frame::new(0x000, &[0x81, ID]));
    r.run_ms(1.0);
    r.take();
    // Power-on values again: Switch on disabled, 6081h default.
    assert_eq!(r.statusword(), SOD);
    assert_ne!(r.read(0x6081, 0), 1234);
}
