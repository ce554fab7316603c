//! The iPOS manufacturer objects and the factor group acting as the manual
//! (seed002) says, each on the virtual bus against the built personality
//! (the behaviour ledger `src/ipos/ledger.tsv` names these tests).

mod ipos_rig;

use ipos_rig::*;

/// 6093h:01/02 as 32-bit values.
fn factor(r: &mut Rig, index: u16, num: u32, div: u32) {
    r.sdo(index, 1, &num.to_le_bytes());
    r.sdo(index, 2, &div.to_le_bytes());
}

/// IU velocity per rpm on the 2000-count motor: 2000/60 counts/s = 1/30
/// count per 1 ms sample, × 65536 = 131072/60.
const RPM: (u32, u32) = (131_072, 60);
/// IU acceleration per rpm/s: 2000/60 counts/s² / 10⁶ × 65536 = 4096/1875.
const RPM_PER_S: (u32, u32) = (4096, 1875);

/// §5.1.10.1 / §5.2.2: with the manual's own 2:1 example (6093h:01 =
/// 20000h, 6093h:02 = 10000h) a move of +1000 position units travels 2000
/// increments: one revolution of the 2000-count motor; 6064h reads the
/// user units, 6063h the increments.
#[test]
fn position_factor_two_to_one() {
    let mut r = enabled_in(1);
    factor(&mut r, 0x6093, 0x2_0000, 0x1_0000);
    r.target_position_rpdo2(1000);
    let bound = move_bound_ms(&mut r, 2000.0, iu_to_counts_s(f64::from(0x0021_0000)));
    start_and_wait(&mut r, 0x1F, bound);
    let inc = r.upload(0x6063, 0, 4);
    assert!((inc - 2000).abs() <= 2 * FEW_COUNTS, "6063h = {inc} increments, want 2000");
    let pos = r.upload(0x6064, 0, 4);
    assert!((pos - 1000).abs() <= FEW_COUNTS, "6064h = {pos} units, want 1000");
    assert!((r.motor_revs() - 1.0).abs() < 0.01, "one motor revolution, {}", r.motor_revs());
    // 6062h is scaled too: the demand is the target in user units.
    assert_eq!(r.upload(0x6062, 0, 4), 1000);
}

/// §5.2.7: velocities are VU × 6094h; in rpm (6094h = 131072/60) a
/// target velocity of 600 runs the motor at 600 rpm and 606Ch reads 600.
#[test]
fn velocity_encoder_factor_in_rpm() {
    let mut r = enabled_in(3);
    factor(&mut r, 0x6094, RPM.0, RPM.1);
    r.sdo(0x60FF, 0, &600i32.to_le_bytes());
    r.run_ms(500);
    let rpm = r.motor_rpm();
    assert!((rpm - 600.0).abs() < 6.0, "motor at {rpm} rpm, want 600");
    let v = r.upload(0x606C, 0, 4);
    // One 606Ch reading is within one increment per sample (30 rpm).
    assert!((v - 600).abs() <= 31, "606Ch = {v}, want 600 rpm");
}

/// The time a pv ramp from rest to 600 rpm takes at 6083h = 1200 (in the
/// acceleration unit in force): the speed after 250 ms, half of it when
/// the unit is rpm/s.
fn speed_after_quarter_second(r: &mut Rig) -> f64 {
    r.sdo(0x6083, 0, &1200u32.to_le_bytes());
    r.sdo(0x60FF, 0, &600i32.to_le_bytes());
    r.run_ms(250);
    r.motor_rpm()
}

/// §5.2.10: accelerations are AU × 210Fh; in rpm/s (210Fh = 4096/1875)
/// 6083h = 1200 takes the motor to 300 rpm in 250 ms.
#[test]
fn acceleration_encoder_factor_in_rpm_per_s() {
    let mut r = enabled_in(3);
    factor(&mut r, 0x6094, RPM.0, RPM.1);
    factor(&mut r, 0x210F, RPM_PER_S.0, RPM_PER_S.1);
    let rpm = speed_after_quarter_second(&mut r);
    assert!((rpm - 300.0).abs() < 15.0, "{rpm} rpm after 250 ms at 1200 rpm/s");
}

/// §5.1.12 (obsolete group): a non-zero acceleration dimension index 608Eh
/// validates 6097h as the acceleration factor (§5.1: "writing a non-zero
/// value into the respective dimension index objects validates these
/// factors"); with 608Eh = 0, 6097h is the §5.2.11 set-up value only.
#[test]
fn legacy_acceleration_factor_with_dimension_index() {
    let mut r = enabled_in(3);
    factor(&mut r, 0x6094, RPM.0, RPM.1);
    factor(&mut r, 0x6097, RPM_PER_S.0, RPM_PER_S.1);
    // Not validated: 1200 IU = 1200/65536 counts/ms² ≈ 549 rpm/s.
    let rpm = speed_after_quarter_second(&mut r);
    assert!((rpm - 137.0).abs() < 15.0, "{rpm} rpm after 250 ms at 1200 IU");
    r.sdo(0x60FF, 0, &0i32.to_le_bytes());
    r.run_ms(1500);
    r.sdo(0x608E, 0, &[0xB4]);
    let rpm = speed_after_quarter_second(&mut r);
    assert!((rpm - 300.0).abs() < 15.0, "{rpm} rpm after 250 ms at 1200 rpm/s");
}

/// A factor of 0 is refused (it would map every value to 0 or divide by
/// 0); the scaling in force stays.
#[test]
fn zero_factor_refused() {
    let mut r = Rig::new();
    for (index, sub) in [(0x6093, 1), (0x6093, 2), (0x6094, 2), (0x210F, 1), (0x2110, 2)] {
        r.sdo.clear();
        r.send(Frame::new(0x601, &[0x23, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0]));
        let abort = Frame::new(0x581, &[0x80, index as u8, (index >> 8) as u8, sub, 0x32, 0x00, 0x09, 0x06]);
        assert_eq!(r.sdo, vec![abort], "{index:04X}h:{sub} := 0");
    }
    assert_eq!(r.dn().app.drive.units().pos_to_inc(1000), 1000);
}

/// §4.3.2 / §4.6.1: the software limits work like LSP/LSN in profile
/// velocity too: past 607Dh:02 the motor decelerates on 6085h and stands,
/// EMCY FF06h goes out and 2002h bit 6 is set; motion further that way is
/// refused, the opposite way taken; leaving the limit sends 0000h and
/// resets the bit.
#[test]
fn software_limit_stops_profile_velocity() {
    let mut r = enabled_in(3);
    r.sdo(0x607D, 2, &5000i32.to_le_bytes());
    r.emcy.clear();
    r.sdo(0x60FF, 0, &(10i32 << 16).to_le_bytes());
    r.run_ms(1500);
    let pos = r.upload(0x6064, 0, 4);
    assert!((5000..5100).contains(&pos), "stopped just past the limit: 6064h = {pos}");
    assert!(r.motor_rpm().abs() < 1.0, "standing, {} rpm", r.motor_rpm());
    assert_eq!(r.emcy, vec![Frame::new(0x081, &[0x06, 0xFF, 0x01, 0, 0, 0, 0, 0])], "EMCY FF06h");
    // §4.4.1: the error register has bit 0 (generic) while it is active.
    assert_eq!(r.upload(0x1001, 0, 1), 0x01);
    assert_eq!(r.upload(0x2002, 0, 2) & 0xC0, 0x40, "2002h bit 6");
    assert_ne!(r.sw.unwrap() & 1 << 11, 0, "statusword bit 11 internal limit active");
    // Back inside: the opposite motion is taken.
    r.emcy.clear();
    r.sdo(0x60FF, 0, &(-10i32 << 16).to_le_bytes());
    r.run_ms(100);
    assert!(r.upload(0x6064, 0, 4) < 5000);
    assert_eq!(r.emcy, vec![Frame::new(0x081, &[0, 0, 0, 0, 0, 0, 0, 0])], "EMCY 0000h");
    assert_eq!(r.upload(0x2002, 0, 2) & 0xC0, 0);
}

/// §4.3.2: the negative limit likewise, with FF07h and 2002h bit 7.
#[test]
fn negative_software_limit_sends_ff07() {
    let mut r = enabled_in(3);
    r.sdo(0x607D, 1, &(-3000i32).to_le_bytes());
    r.emcy.clear();
    r.sdo(0x60FF, 0, &(-10i32 << 16).to_le_bytes());
    r.run_ms(1000);
    let pos = r.upload(0x6064, 0, 4);
    assert!((-3100..-3000).contains(&pos), "stopped just past the limit: 6064h = {pos}");
    assert_eq!(r.emcy, vec![Frame::new(0x081, &[0x07, 0xFF, 0x01, 0, 0, 0, 0, 0])], "EMCY FF07h");
    assert_eq!(r.upload(0x2002, 0, 2) & 0xC0, 0x80, "2002h bit 7");
}

/// §7.2.19: 2081h sets the motor position, in increments whatever the
/// factor group: 6063h, 6064h and 6062h follow, the motor does not move.
#[test]
fn set_actual_position_object() {
    let mut r = enabled_in(1);
    let revs = r.motor_revs();
    r.sdo(0x2081, 0, &12_345i32.to_le_bytes());
    r.run_ms(10);
    assert_eq!(r.upload(0x6063, 0, 4), 12_345);
    assert_eq!(r.upload(0x6064, 0, 4), 12_345);
    assert_eq!(r.upload(0x6062, 0, 4), 12_345);
    assert!((r.motor_revs() - revs).abs() < 1e-3, "the motor stays");
    // Not scaled: with the 2:1 position factor 12346 increments are 6173 units.
    r.sdo(0x6093, 1, &0x2_0000u32.to_le_bytes());
    r.sdo(0x6093, 2, &0x1_0000u32.to_le_bytes());
    r.sdo(0x2081, 0, &12_346i32.to_le_bytes());
    r.run_ms(10);
    assert_eq!(r.upload(0x6063, 0, 4), 12_346);
    assert_eq!(r.upload(0x6064, 0, 4), 6173);
}

/// §4.9.8: a non-zero 2080h resets the drive: it leaves Operation enabled
/// for Switch on disabled and restarts (boot-up on CAN), as at power-on.
#[test]
fn reset_drive_object() {
    let mut r = enabled_in(1);
    assert_eq!(r.upload(0x6041, 0, 2) & 0x6F, 0x27);
    // 0 does nothing.
    r.sdo(0x2080, 0, &0u16.to_le_bytes());
    r.run_ms(5);
    assert_eq!(r.upload(0x6041, 0, 2) & 0x6F, 0x27);
    r.sdo.clear();
    r.send(Frame::new(0x601, &[0x2B, 0x80, 0x20, 0x00, 0x01, 0x00, 0x00, 0x00]));
    r.run_ms(5);
    assert_eq!(r.sdo.first(), Some(&Frame::new(0x581, &[0x60, 0x80, 0x20, 0, 0, 0, 0, 0])));
    r.bus.take_received(r.probe);
    r.run_ms(5);
    let sw = r.upload(0x6041, 0, 2);
    assert_eq!(sw & 0x4F, 0x40, "switch on disabled after the reset: {sw:04X}h");
    assert_eq!(r.upload(0x603F, 0, 2), 0, "no fault");
}

/// §4.9.6: 2076h saves the operating parameters: after a reset they come
/// back, unsaved changes do not.
#[test]
fn save_configuration_object() {
    let mut r = Rig::new();
    r.sdo(0x6081, 0, &0x0005_0000u32.to_le_bytes());
    r.sdo(0x2092, 1, &0xCAFEu32.to_le_bytes());
    r.sdo(0x2076, 0, &1u16.to_le_bytes());
    assert_eq!(r.upload(0x208A, 0, 2) & 1, 1, "208Ah bit 0: save complete");
    r.sdo(0x6083, 0, &0x0003_0000u32.to_le_bytes());
    // NMT reset node.
    r.send(Frame::new(0x000, &[0x81, 0x01]));
    r.run_ms(10);
    assert_eq!(r.upload(0x6081, 0, 4), 0x0005_0000, "saved");
    assert_eq!(r.upload(0x2092, 1, 4), 0xCAFE, "saved");
    assert_eq!(r.upload(0x6083, 0, 4), 0x0001_0000, "not saved: the default");
}

/// §4.2.4: a mode written below Operation enabled shows in 6061h only
/// once Operation enabled is reached.
#[test]
fn mode_display_follows_in_operation_enabled() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(3);
    r.controlword(0x06);
    r.controlword(0x07);
    r.wait_sw("switched on", 0x6F, 0x23, 100);
    assert_eq!(r.upload(0x6061, 0, 1), 0, "6061h keeps the power-on mode");
    r.controlword(0x0F);
    r.wait_sw("operation enabled", 0x6F, 0x27, 100);
    assert_eq!(r.upload(0x6061, 0, 1), 3);
    // In Operation enabled a change shows at once.
    r.modes_of_operation(1);
    r.run_ms(2);
    assert_eq!(r.upload(0x6061, 0, 1), 1);
    // Below it, the display keeps the last mode shown.
    r.controlword(0x07);
    r.modes_of_operation(6);
    r.run_ms(2);
    assert_eq!(r.upload(0x6061, 0, 1), 1);
}

fn inject(r: &mut Rig, what: drivebus_cia402::model::ModelInjection) {
    r.bus
        .node_mut::<PersonalityDevice>(r.dut)
        .unwrap()
        .app
        .inject(drivebus_cia402::drive::Injection::Model(what));
    r.run_ms(5);
}

/// §4.4.2 Table 4.4.2: 2000h shows the drive's protections — set when
/// triggered, reset by a Reset Fault command.
#[test]
fn motion_error_register_shows_the_faults() {
    use drivebus_cia402::model::ModelInjection;
    for (what, bit) in [
        (ModelInjection::OverCurrent, 8),
        (ModelInjection::BusOverVoltage, 12),
        (ModelInjection::BusUnderVoltage, 13),
        (ModelInjection::OverTemperature, 10),
        (ModelInjection::EncoderFailure, 5),
    ] {
        let mut r = enabled_in(1);
        assert_eq!(r.upload(0x2000, 0, 2), 0);
        inject(&mut r, what);
        assert_eq!(r.upload(0x2000, 0, 2), 1 << bit, "{what:?}");
        inject(&mut r, ModelInjection::Clear);
        r.controlword(0x80);
        r.run_ms(5);
        assert_eq!(r.upload(0x2000, 0, 2), 0, "{what:?}: reset by Reset Fault");
    }
}

/// §4.5.5 / §4.5.4 / §4.5.3.1: 2045h shows the outputs 60FEh drives; the
/// 8-bit 2090h commands OUT0..OUT7 like 60FEh bits 16-23.
#[test]
fn digital_outputs_status_and_8bit_outputs() {
    let mut r = Rig::new();
    // §4.5.3.1: OUT0 := 0, OUT1 := 1.
    r.sdo(0x60FE, 1, &0x0002_0000u32.to_le_bytes());
    r.sdo(0x60FE, 2, &0x0003_0000u32.to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.upload(0x2045, 0, 2), 0x0002);
    r.sdo(0x2090, 1, &[0x05]);
    r.sdo(0x2090, 2, &[0x07]);
    r.run_ms(2);
    assert_eq!(r.upload(0x2045, 0, 2), 0x0005);
    assert_eq!(r.upload(0x60FE, 1, 4), 0x0005_0000);
    assert_eq!(r.upload(0x60FE, 2, 4), 0x0007_0000);
}

/// §4.5.2: 208Fh:01 shows 60FDh bits 0-3 (here the LSN).
#[test]
fn digital_inputs_8bit() {
    use drivebus_cia402::model::{ModelInjection, SwitchInput};
    let mut r = Rig::new();
    inject(&mut r, ModelInjection::ForceSwitch(SwitchInput::NegativeLimit, Some(true)));
    assert_eq!(r.upload(0x60FD, 0, 4) & 0x0F, 0x01);
    assert_eq!(r.upload(0x208F, 1, 1), 0x01);
    inject(&mut r, ModelInjection::ForceSwitch(SwitchInput::NegativeLimit, Some(false)));
    assert_eq!(r.upload(0x208F, 1, 1), 0x00);
}

/// The cam of §12.2.6 (master 640 → slave 4000): X step 2⁶, Y = 40·i².
fn cam() -> drivebus_personality::ipos::CamTable {
    drivebus_personality::ipos::CamTable { x0: 0, step_log2: 6, y: (0..=10).map(|i| i * i * 40).collect() }
}

/// E34 (§12.2.6.2): 2064h := load address + 08h (EEPROM, 16 bit,
/// auto-increment), then every word of the .sw block by 2065h.
fn download(r: &mut Rig, load: u16, words: &[u16]) {
    r.sdo(0x2064, 0, &(u32::from(load) << 16 | 0x08).to_le_bytes());
    for w in words {
        r.sdo(0x2065, 0, &u32::from(*w).to_le_bytes());
    }
}

/// §17.2: what 2065h wrote reads back through 2066h (the address
/// advancing), 2069h sums it into 206Ah, 2067h writes one word anywhere.
#[test]
fn memory_objects_write_read_checksum() {
    let mut r = Rig::new();
    let words = cam().to_words();
    download(&mut r, 0x5638, &words);
    assert_eq!(r.upload(0x2064, 0, 4) as u32, (0x5638 + words.len() as u32) << 16 | 0x08, "auto-increment");
    r.sdo(0x2064, 0, &(0x5638u32 << 16 | 0x08).to_le_bytes());
    for w in &words[..3] {
        assert_eq!(r.upload(0x2066, 0, 4) as u32, u32::from(*w));
    }
    // 32-bit read (bit 0) without increment (bit 7): X0 low and high word.
    r.sdo(0x2064, 0, &(0x5639u32 << 16 | 0x89).to_le_bytes());
    assert_eq!(r.upload(0x2066, 0, 4), 0);
    assert_eq!(r.upload(0x2064, 0, 4) as u32, 0x5639u32 << 16 | 0x89, "no increment");
    let end = 0x5638 + words.len() as u32;
    r.sdo(0x2069, 0, &(end << 16 | 0x5638).to_le_bytes());
    let sum = words.iter().fold(0u16, |a, w| a.wrapping_add(*w));
    assert_eq!(r.upload(0x206A, 0, 2) as u16, sum);
    // §17.2.4.1: 2067h := 036A1234h writes 1234h at 036Ah.
    r.sdo(0x2064, 0, &0x0000_0084u32.to_le_bytes());
    r.sdo(0x2067, 0, &0x036A_1234u32.to_le_bytes());
    r.sdo(0x2064, 0, &(0x036Au32 << 16 | 0x84).to_le_bytes());
    assert_eq!(r.upload(0x2066, 0, 4), 0x1234);
}

/// The camming slave of §12.4 on the cam of §12.2.6: the table downloaded
/// as E34 does, copied to the RAM by 2019h (201Ah first, §12.2.1), the
/// master position online in 201Eh, one SYNC per 1 ms cycle.
fn camming_slave(cw_start: u16) -> Rig {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    download(&mut r, 0x5638, &cam().to_words());
    r.sdo(0x201A, 0, &0x97F6u16.to_le_bytes());
    r.sdo(0x2019, 0, &0x5638u16.to_le_bytes());
    r.sdo(0x201D, 0, &1u16.to_le_bytes());
    r.start_remote_node();
    r.modes_of_operation(-2);
    r.enable();
    assert_eq!(r.upload(0x6061, 0, 1), -2);
    master_to(&mut r, 0, 0);
    r.controlword(cw_start);
    r
}

/// Moves the online master from `from` to `to` in 8-increment steps, one
/// per 1 ms cycle with its SYNC, then lets the slave settle.
fn master_to(r: &mut Rig, from: i32, to: i32) {
    let step = if to >= from { 8 } else { -8 };
    let mut m = from;
    loop {
        r.sdo(0x201E, 0, &m.to_le_bytes());
        r.send(Frame::new(0x080, &[]));
        r.run_us(500);
        if m == to {
            break;
        }
        m = if (to - m).abs() < 8 { to } else { m + step };
    }
    for _ in 0..100 {
        r.send(Frame::new(0x080, &[]));
        r.run_us(500);
    }
}

/// §12.1 absolute mode (controlword bit 6 = 1): the slave position is the
/// cam output of the master position, interpolated between the points.
#[test]
fn camming_absolute_follows_the_table() {
    let mut r = camming_slave(0x5F);
    master_to(&mut r, 0, 320);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 1000).abs() <= FEW_COUNTS, "master 320 → slave 1000, at {p}");
    master_to(&mut r, 320, 352);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 1220).abs() <= FEW_COUNTS, "master 352 → slave 1220, at {p}");
    // 206Ch output scaling 2.0 (FIXED32).
    r.sdo(0x206C, 0, &0x0002_0000u32.to_le_bytes());
    master_to(&mut r, 352, 640);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 8000).abs() <= FEW_COUNTS, "master 640 → 2 × 4000, at {p}");
}

/// §12.1 relative mode (bit 6 = 0): the slave adds dY to where it stood;
/// the cam offset 201Bh shifts the master (§12.2.3).
#[test]
fn camming_relative_adds_the_cam_increments() {
    let mut r = camming_slave(0x0F);
    r.sdo(0x201B, 0, &320u32.to_le_bytes());
    let p0 = r.upload(0x6064, 0, 4);
    // Master 320 + 201Bh 320 = X 320 at the start: Y_old = 1000.
    master_to(&mut r, 0, 640);
    r.controlword(0x1F);
    master_to(&mut r, 640, 960);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - p0 - 3000).abs() <= FEW_COUNTS, "X 320 → 640 adds 4000 − 1000: moved {}", p - p0);
}

/// §18.2.2.1 / §18.3.1: a function number outside 1..10 is 0609 0030h; a
/// valid one with no TML function there, or a program start with no
/// program, 0800 0020h (the twin holds no TML).
#[test]
fn tml_function_and_program_objects() {
    let mut r = Rig::new();
    sdo_aborts(&mut r, 0x2006, 0, &11u16.to_le_bytes(), 0x0609_0030);
    sdo_aborts(&mut r, 0x2006, 0, &0u16.to_le_bytes(), 0x0609_0030);
    sdo_aborts(&mut r, 0x2006, 0, &3u16.to_le_bytes(), 0x0800_0020);
    sdo_aborts(&mut r, 0x2077, 0, &1u16.to_le_bytes(), 0x0800_0020);
}

/// §3.2.6: 2112h ≠ 0 gives TML priority: 6040h and 6060h are not written
/// (SDO: 0800 0021h local control; an RPDO's controlword is dropped).
#[test]
fn tml_priority_locks_controlword_and_mode() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.sdo(0x2112, 0, &1u16.to_le_bytes());
    sdo_aborts(&mut r, 0x6040, 0, &6u16.to_le_bytes(), 0x0800_0021);
    sdo_aborts(&mut r, 0x6060, 0, &[1], 0x0800_0021);
    r.controlword(0x06);
    r.run_ms(5);
    assert_eq!(r.upload(0x6041, 0, 2) & 0x4F, 0x40, "still switch on disabled");
    r.sdo(0x2112, 0, &0u16.to_le_bytes());
    r.sdo(0x6060, 0, &[3]);
    r.enable();
}

/// §7.2.17 / §10.2.1 / §4.9.16: 60FCh is the demand in increments, 6069h
/// the encoder speed in internal units whatever the factor group, 2103h
/// the counts per revolution.
#[test]
fn internal_demand_and_velocity_sensor_values() {
    let mut r = enabled_in(3);
    assert_eq!(r.upload(0x2103, 0, 4), 2000);
    r.sdo(0x6093, 1, &2u32.to_le_bytes());
    r.sdo(0x6094, 1, &RPM.0.to_le_bytes());
    r.sdo(0x6094, 2, &RPM.1.to_le_bytes());
    r.sdo(0x60FF, 0, &600i32.to_le_bytes());
    r.run_ms(500);
    // 600 rpm = 20 increments per 1 ms sample = 20 × 65536.
    let v = r.upload(0x6069, 0, 4);
    assert!((v - 20 * 65536).abs() <= 65536, "6069h = {v}");
    r.sdo(0x60FF, 0, &0i32.to_le_bytes());
    r.modes_of_operation(1);
    r.run_ms(300);
    let here = r.upload(0x6064, 0, 4) as i32;
    r.target_position_rpdo2(here + 500);
    start_and_wait(&mut r, 0x1F, 2000);
    let demand = r.upload(0x6062, 0, 4);
    assert_eq!(r.upload(0x60FC, 0, 4), 2 * demand, "60FCh = 2 × 6062h at 2:1");
}

/// §5.1.13: with a non-zero time dimension index 2070h the time factor
/// 2071h scales the times: 6068h = 5 in units of 10 ms (2071h = 10/1)
/// holds target reached back 50 ms instead of 5 ms; 6068h reads 5.
#[test]
fn time_factor_with_dimension_index() {
    let reached_after = |validate: bool| {
        let mut r = enabled_in(1);
        r.sdo(0x2071, 1, &10u32.to_le_bytes());
        if validate {
            r.sdo(0x2070, 0, &[0x03]);
        }
        r.sdo(0x6068, 0, &5u16.to_le_bytes());
        assert_eq!(r.upload(0x6068, 0, 2), 5);
        r.target_position_rpdo2(2000);
        start_and_wait(&mut r, 0x1F, 2000)
    };
    let plain = reached_after(false);
    let scaled = reached_after(true);
    assert!((40..=50).contains(&(scaled - plain)), "5 ms vs 50 ms window time: {plain} / {scaled} ms");
}

/// §4.9.12: 210Bh bit 12 = 1 keeps the actual position at the end of a
/// homing; 0 (default) sets it to 607Ch (method 35: here).
#[test]
fn homing_keeps_the_position_with_asr2_bit_12() {
    let home = |keep: bool| {
        let mut r = enabled_in(1);
        r.target_position_rpdo2(1500);
        start_and_wait(&mut r, 0x1F, 2000);
        r.controlword(0x0F);
        if keep {
            r.sdo(0x210B, 0, &0x1000u16.to_le_bytes());
        }
        r.sdo(0x607C, 0, &500i32.to_le_bytes());
        r.sdo(0x6098, 0, &[35]);
        r.modes_of_operation(6);
        r.controlword(0x1F);
        r.wait_sw("homing attained", 0x1400, 0x1400, 1000);
        r.run_ms(10);
        r.upload(0x6064, 0, 4)
    };
    assert_eq!(home(false), 500);
    let kept = home(true);
    assert!((kept - 1500).abs() <= FEW_COUNTS, "position kept: {kept}");
}

/// §4.9.4 / §4.9.5: 2085h gives OUT0 to position trigger 1 (2075h:01):
/// with bit 8 = 1 it is high once 6064h has reached the trigger, with bit
/// 8 = 0 the other way round; 2045h shows it.
#[test]
fn position_triggered_outputs() {
    let mut r = enabled_in(1);
    r.sdo(0x2075, 1, &500i32.to_le_bytes());
    r.sdo(0x2085, 0, &0x0101u16.to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.upload(0x2045, 0, 2) & 1, 0, "before the trigger");
    r.target_position_rpdo2(1000);
    start_and_wait(&mut r, 0x1F, 2000);
    assert_eq!(r.upload(0x2045, 0, 2) & 1, 1, "past the trigger");
    r.sdo(0x2085, 0, &0x0001u16.to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.upload(0x2045, 0, 2) & 1, 0, "inverted polarity");
}

/// §4.5.6: 2102h is 1 while the brake output holds the motor's brake: at
/// rest disabled, through the release delay after the enable ("it may still
/// be active even when the drive reaches the Operation Enabled state"), 0
/// once released, 1 again after a disable.
#[test]
fn brake_status_follows_the_brake() {
    let mut r = Rig::on(|c| {
        c.params.io.brake = Some(drivebus_cia402::model::BrakeParams {
            release_delay: 0.1,
            apply_delay: 0.05,
            holding_torque: 1.0,
        });
    });
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.run_ms(2);
    assert_eq!(r.upload(0x2102, 0, 1), 1, "disabled: the brake holds");
    r.modes_of_operation(1);
    r.enable();
    assert_eq!(r.upload(0x2102, 0, 1), 1, "Operation enabled, the release delay runs");
    r.run_ms(120);
    assert_eq!(r.upload(0x2102, 0, 1), 0, "released");
    r.controlword(0x06);
    r.run_ms(80);
    assert_eq!(r.upload(0x2102, 0, 1), 1, "applied after the disable");
    // Without a brake fitted the output never holds one.
    let mut r = Rig::new();
    r.run_ms(2);
    assert_eq!(r.upload(0x2102, 0, 1), 0);
}

/// §4.5.1 / §4.5.2: the machine's input lines 1–16 are IN0..IN15 (60FDh
/// bits 16–31, 208Fh:02); the home switch is IN0 too (§6.1: "home switch
/// (IN0)").
#[test]
fn digital_input_lines() {
    use drivebus_cia402::model::{ModelInjection, SwitchInput};
    let mut r = Rig::new();
    inject(&mut r, ModelInjection::DigitalInput { line: 3, level: true });
    assert_eq!(r.upload(0x60FD, 0, 4) as u32, 1 << 18, "IN2");
    assert_eq!(r.upload(0x208F, 2, 1), 0x04);
    inject(&mut r, ModelInjection::ForceSwitch(SwitchInput::Home, Some(true)));
    assert_eq!(r.upload(0x60FD, 0, 4) as u32, 1 << 18 | 1 << 16 | 1 << 2, "home = bit 2 and IN0");
    assert_eq!(r.upload(0x208F, 2, 1), 0x05);
}

/// §4.5.3: 60FEh drives the machine's output lines (OUT0 = line 1); an
/// output the iPOS360x does not have (OUT4..OUT15) selected in the mask
/// sends EMCY FF05h and does not reach the machine.
#[test]
fn output_lines_and_unavailable_outputs() {
    let mut r = Rig::new();
    r.sdo(0x60FE, 1, &0x0082_0000u32.to_le_bytes());
    r.emcy.clear();
    r.sdo(0x60FE, 2, &0x0002_0000u32.to_le_bytes());
    r.run_ms(2);
    assert!(r.emcy.is_empty(), "OUT1 exists: {:?}", r.emcy);
    assert_eq!(r.dn().app.drive.output_lines(), 0x0002, "line 2 = OUT1");
    r.sdo(0x60FE, 2, &0x0082_0000u32.to_le_bytes());
    r.run_ms(2);
    assert_eq!(r.emcy, vec![Frame::new(0x081, &[0x05, 0xFF, 0x01, 0, 0, 0, 0, 0])], "EMCY FF05h");
    assert_eq!(r.dn().app.drive.output_lines(), 0x0002, "OUT7 does not exist");
    assert_eq!(r.upload(0x60FE, 2, 4) as u32, 0x0082_0000, "the mask reads as written");
    // The 8-bit image likewise.
    r.emcy.clear();
    r.sdo(0x2090, 2, &[0x10]);
    r.run_ms(2);
    assert_eq!(r.emcy.len(), 1, "OUT4 through 2090h: FF05h");
}

/// §4.5.7 / §4.5.8: 2046h and 2047h show the machine's analogue inputs 1
/// (reference) and 2 (feedback), 0…65520 over 0…5 V.
#[test]
fn analogue_inputs() {
    use drivebus_cia402::model::ModelInjection;
    let mut r = Rig::new();
    inject(&mut r, ModelInjection::AnalogInput { channel: 1, volts: 2.5 });
    inject(&mut r, ModelInjection::AnalogInput { channel: 2, volts: 7.0 });
    assert_eq!(r.upload(0x2046, 0, 2), 32_760);
    assert_eq!(r.upload(0x2047, 0, 2) as u16, 65_520, "beyond full scale");
    inject(&mut r, ModelInjection::AnalogInput { channel: 1, volts: -1.0 });
    assert_eq!(r.upload(0x2046, 0, 2), 0);
}

/// §11.1 / §11.1.1: gearing started with controlword bit 5 couples with
/// the acceleration limited to 6083h: the slave's speed ramps to the
/// master's (15 increments per 1.5 ms cycle: 10000 increments/s) instead of
/// jumping to it.
#[test]
fn gearing_couples_with_limited_acceleration() {
    let moved = |cw: u16| {
        let mut r = Rig::new();
        map_examples_rpdos(&mut r);
        r.sdo(0x201D, 0, &1u16.to_le_bytes());
        r.sdo(0x2012, 0, &0x8000_0001u32.to_le_bytes());
        // 1/16 IU = 62500 increments/s²: 10000 increments/s after 160 ms.
        r.sdo(0x6083, 0, &0x1000u32.to_le_bytes());
        r.start_remote_node();
        r.modes_of_operation(-1);
        r.enable();
        master_to(&mut r, 0, 0);
        r.controlword(cw);
        let p0 = r.upload(0x6062, 0, 4);
        let mut m = 0i32;
        for _ in 0..100 {
            m += 15;
            r.sdo(0x201E, 0, &m.to_le_bytes());
            r.send(Frame::new(0x080, &[]));
            r.run_us(500);
        }
        r.upload(0x6062, 0, 4) - p0
    };
    let free = moved(0x1F);
    let limited = moved(0x3F);
    assert!((free - 1500).abs() <= 45, "without bit 5 the slave follows at once: {free}");
    // ½ · 62500 · 0.15² = 703 increments in the first 150 ms.
    assert!((limited - 703).abs() <= 60, "with bit 5 it ramps: {limited}");
}
