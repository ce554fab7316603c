//! SSD Drives 630 objects that act (issue 14), seed003 *CANopen-630*
//! manual V0904, on the virtual bus:
//!
//! * §7, §11 2014h–2017h: with transmission type 254 only the masked bits
//!   of a TPDO trigger it ("Only valid in transmission type 254");
//! * §12 6080h: the negative / positive max motor speed limit profile
//!   velocity too;
//! * §14.15: 60FFh must be 0 before profile velocity is left;
//! * §9 transition 0: the "no error" EMCY after every initialisation (also
//!   the one NMT reset node starts);
//! * §11 1004h: sub 0 UNSIGNED32 "number of PDOs";
//! * §4 6049h: a VAR (UNSIGNED32);
//! * §12 60C2h:02: UNSIGNED8 "ip time index";
//! * the EDS served at 1021h says `$NODEID` for 100Bh, as the shipped one.

mod replay_rig;

use drivebus_node::MemoryStorage;
use drivebus_personality::Profile;
use drivebus_personality::build::BuildOptions;
use replay_rig::*;

const ID: u8 = 1;

fn rig() -> Rig {
    Rig::new(Profile::Ssd630, ID).0
}

fn write(r: &mut Rig, index: u16, sub: u8, data: &[u8]) {
    Rig::assert_written(r.sdo_write(ID, index, sub, data), ID, index, sub);
}

fn controlword(r: &mut Rig, cw: u16) {
    write(r, 0x6040, 0, &cw.to_le_bytes());
    r.run_ms(5);
}

fn enable(r: &mut Rig) {
    for cw in [0x06, 0x07, 0x0F] {
        controlword(r, cw);
    }
    assert_eq!(r.read_u32(ID, 0x6041, 0) & 0x6F, 0x27, "operation enabled");
}

/// TPDO1 frames (181h) among `frames`.
fn tpdo1(frames: &[drivebus_can::Frame]) -> Vec<drivebus_can::Frame> {
    frames.iter().copied().filter(|f| f.std_id() == Some(0x180 + u16::from(ID))).collect()
}

/// TPDO1 (6041h) with transmission type `tt` and 2014h:01 = `mask`, the
/// node operational; the TPDO1 frames of Switch on (0231h → 0233h: bit 1
/// changes only).
fn switch_on_with(tt: u8, mask: u32) -> Vec<drivebus_can::Frame> {
    let mut r = rig();
    write(&mut r, 0x1800, 2, &[tt]);
    write(&mut r, 0x2014, 1, &mask.to_le_bytes());
    r.send("000#01 01");
    r.run_ms(5);
    controlword(&mut r, 0x06);
    assert_eq!(r.read_u32(ID, 0x6041, 0) as u16, 0x0231);
    switch_on(&mut r)
}

/// Switch on (controlword 0007h by SDO, frames kept): the TPDO1 frames.
fn switch_on(r: &mut Rig) -> Vec<drivebus_can::Frame> {
    r.take();
    r.send("601#2B 40 60 00 07 00 00 00");
    r.run_ms(5);
    let frames = r.take();
    assert!(frames.contains(&fr("581#60 40 60 00 00 00 00 00")), "{frames:?}");
    assert_eq!(r.read_u32(ID, 0x6041, 0) as u16, 0x0233);
    tpdo1(&frames)
}

#[test]
fn tt254_sends_on_masked_bits_only() {
    // §11 2014h: mask low = PDO bytes 0–3; only statusword bit 6 (switch
    // on disabled) counts. 0231h → 0233h changes bit 1 only: no TPDO.
    assert_eq!(switch_on_with(254, 0x0000_0040), vec![]);
    // Bit 1 in the mask: the change is sent.
    assert_eq!(switch_on_with(254, 0x0000_0002), frs(&["181#33 02"]));
}

#[test]
fn tt255_ignores_the_masks() {
    // "Only valid in transmission type 254": 255 sends on any change.
    assert_eq!(switch_on_with(255, 0x0000_0040), frs(&["181#33 02"]));
}

#[test]
fn masks_follow_a_later_transmission_type_change() {
    // Mask written first (at 255), 254 afterwards: the mask now applies.
    let mut r = rig();
    write(&mut r, 0x2014, 1, &0x40u32.to_le_bytes());
    write(&mut r, 0x1800, 2, &[254]);
    r.send("000#01 01");
    r.run_ms(5);
    controlword(&mut r, 0x06);
    assert_eq!(switch_on(&mut r), vec![]);
}

/// Profile velocity with 60FFh = `target` min⁻¹ after 6080h:1/2 = 50/50:
/// the speed after the ramp \[min⁻¹\], from the travel in 600 ms (606Ch
/// itself is the encoder's 4096 counts differentiated per control period:
/// too coarse at this speed).
fn pv_speed(target: i32) -> f64 {
    let mut r = rig();
    write(&mut r, 0x6080, 1, &50u16.to_le_bytes());
    write(&mut r, 0x6080, 2, &50u16.to_le_bytes());
    write(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    write(&mut r, 0x6060, 0, &[3]);
    enable(&mut r);
    write(&mut r, 0x60FF, 0, &target.to_le_bytes());
    r.run_ms(200);
    let p0 = r.read_u32(ID, 0x6064, 0) as i32;
    r.run_ms(600);
    let p1 = r.read_u32(ID, 0x6064, 0) as i32;
    f64::from(p1 - p0) / 4096.0 / 0.6 * 60.0
}

#[test]
fn max_motor_speed_limits_profile_velocity() {
    // §12 6080h: max motor speed, both directions; 60FFh beyond it runs at it.
    for target in [-100, 100] {
        let v = pv_speed(target);
        assert!((v.abs() - 50.0).abs() < 1.5, "60FFh {target}: {v} min^-1");
        assert_eq!(v.signum(), f64::from(target.signum()));
    }
    // Within the limit the target is kept.
    let v = pv_speed(-40);
    assert!((v + 40.0).abs() < 1.5, "{v} min^-1");
}

#[test]
fn leaving_pv_needs_60ff_zero() {
    // §14.15: "The object 60FFh must be set to 0 before the operating mode
    // is changed"; a mode change against it is refused with §5's 0800 0022h.
    let mut r = rig();
    write(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    write(&mut r, 0x6060, 0, &[3]);
    enable(&mut r);
    write(&mut r, 0x60FF, 0, &200i32.to_le_bytes());
    r.run_ms(50);
    Rig::assert_abort(r.sdo_write(ID, 0x6060, 0, &[1]), ID, 0x6060, 0, 0x0800_0022);
    assert_eq!(r.read_u32(ID, 0x6061, 0) as u8, 3, "still profile velocity");
    // Writing pv again is no change of mode.
    write(&mut r, 0x6060, 0, &[3]);
    write(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    write(&mut r, 0x6060, 0, &[1]);
    assert_eq!(r.read_u32(ID, 0x6061, 0) as u8, 1);
}

#[test]
fn no_error_emcy_after_reset_node() {
    // §9 transition 0: "After the initialisation of the drive … the message
    // 'no error' is being sent" — NMT reset node initialises the drive again.
    let (mut r, boot) = Rig::new(Profile::Ssd630, ID);
    let emcy = fr("081#00 00 00 56 38 31 39 64");
    assert!(boot.contains(&emcy), "{boot:?}");
    r.send("000#81 01");
    r.run_ms(5);
    let after = r.take();
    let boot_up = after.iter().position(|f| *f == fr("701#00"));
    let no_error = after.iter().position(|f| *f == emcy);
    assert!(boot_up.is_some() && no_error > boot_up, "{after:?}");
    // Reset communication does not initialise the drive (§6: the
    // communication only).
    r.send("000#82 01");
    r.run_ms(5);
    assert!(!r.take().contains(&emcy));
}

#[test]
fn number_of_pdos() {
    // §11 1004h: sub 1/2 the synchronous / asynchronous PDOs (UNSIGNED32,
    // one direction per 16 bits as DS301 v4.01 codes 1004h): 4 + 4. Sub 0
    // is UNSIGNED8, the highest sub-index: an EDS cannot describe the
    // printed UNSIGNED32 (CiA 306; docs/personalities.md).
    let mut r = rig();
    assert_eq!(r.upload(ID, 0x1004, 0), Ok(vec![2]));
    assert_eq!(r.upload(ID, 0x1004, 1), Ok(0x0004_0004u32.to_le_bytes().to_vec()));
    assert_eq!(r.upload(ID, 0x1004, 2), Ok(0x0004_0004u32.to_le_bytes().to_vec()));
}

#[test]
fn vl_deceleration_is_a_var() {
    // §4: "6049h vl velocity deceleration VAR unsigned 32" (printed as a
    // second 6048h).
    let mut r = rig();
    let v = r.upload(ID, 0x6049, 0).expect("6049h");
    assert_eq!(v.len(), 4, "UNSIGNED32");
    write(&mut r, 0x6049, 0, &1234u32.to_le_bytes());
    assert_eq!(r.read_u32(ID, 0x6049, 0), 1234);
    assert_eq!(r.upload(ID, 0x6049, 1), Err(0x0609_0011));
    let od = r.node().od();
    assert_eq!(od.object(0x6049).map(|o| o.code), Some(drivebus_od::ObjectCode::Var));
}

#[test]
fn ip_time_index_is_unsigned8() {
    // §12 60C2h:02 "Unsigned 8 lp time index": the byte the §14.13 cycle
    // writes (FDh = 10^-3) is taken as UNSIGNED8.
    let r = rig();
    let s = r.node().od().get(0x60C2, 2).expect("60C2h:02").clone();
    assert_eq!(s.data_type, drivebus_od::DataType::Unsigned8);
    let mut r = r;
    write(&mut r, 0x60C2, 2, &[0xFD]);
    assert_eq!(r.upload(ID, 0x60C2, 2), Ok(vec![0xFD]));
}

#[test]
fn served_eds_keeps_nodeid_for_100b() {
    // The shipped EDS gives 100Bh "$NODEID" (§14.6: the drive reads its own
    // node-ID); the served one must say the same, not node 5's literal 5.
    let pn = Profile::Ssd630
        .build_with_options(5, Box::new(MemoryStorage::new()), BuildOptions { eds_object: true })
        .unwrap();
    let (mut r, _) = Rig::with(pn);
    let text = String::from_utf8(r.upload(5, 0x1021, 0).expect("1021h")).unwrap();
    let eds = drivebus_eds::parse(&text).unwrap().eds;
    let o = &eds.objects[&0x100B];
    let v = o.var.as_ref().or_else(|| o.subs.get(&0)).expect("100Bh value");
    assert_eq!(v.default.as_deref(), Some("$NODEID"));
}

#[test]
fn configuration_mode_5_ignores_the_controlword() {
    // §1.4 mode 5: "The control of the DS402 State-machine is being
    // ignored. 6040h, 6041h control- and statusword are not being
    // evaluated"; mode 4 (DS402) is the CANopen drive's.
    let mut r = rig();
    assert_eq!(r.read_u32(ID, 0x4804, 5), 4);
    write(&mut r, 0x4804, 5, &[5]);
    controlword(&mut r, 0x06);
    assert_eq!(r.read_u32(ID, 0x6041, 0) as u16, 0x0240, "not followed");
    write(&mut r, 0x4804, 5, &[4]);
    controlword(&mut r, 0x06);
    assert_eq!(r.read_u32(ID, 0x6041, 0) as u16, 0x0231);
}

#[test]
fn can_node_number_is_the_node_id() {
    // §13 4804h:01 "CAN node number" (ro, 1..127), like 100Bh (§14.6).
    let (mut r, _) = Rig::new(Profile::Ssd630, 7);
    assert_eq!(r.read_u32(7, 0x4804, 1), 7);
    assert_eq!(r.read_u32(7, 0x100B, 0), 7);
}

/// The EMCY frames (081h) among `frames`.
fn emcy(frames: &[drivebus_can::Frame]) -> Vec<drivebus_can::Frame> {
    frames.iter().copied().filter(|f| f.std_id() == Some(0x80 + u16::from(ID))).collect()
}

#[test]
fn emcy_inhibit_time_1015h() {
    // §4 1015h "Inhibit time EMCY" (CiA 301: 100 µs): the "error reset"
    // EMCY after a fault reset waits until the inhibit time has passed.
    let mut r = rig();
    write(&mut r, 0x1015, 0, &5000u16.to_le_bytes()); // 500 ms
    enable(&mut r);
    // Past the inhibit time of the boot EMCY.
    r.run_ms(600);
    r.take();
    r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Fault(0x4310));
    r.run_ms(5);
    assert_eq!(emcy(&r.take()), frs(&["081#10 43 09 00 00 00 00 00"]));
    r.send("601#2B 40 60 00 80 00 00 00");
    r.run_ms(100);
    assert_eq!(emcy(&r.take()), vec![], "within the inhibit time");
    r.run_ms(500);
    assert_eq!(emcy(&r.take()), frs(&["081#00 00 00 00 00 00 00 00"]));
}

#[test]
fn velocity_mode_objects() {
    // §12 vl: 6042h target (min⁻¹), 6046h min / max amount, 6048h delta
    // speed per delta time, 6043h demand and 6044h effort follow.
    let mut r = rig();
    write(&mut r, 0x6046, 2, &200u32.to_le_bytes());
    write(&mut r, 0x6048, 1, &100u32.to_le_bytes());
    write(&mut r, 0x6048, 2, &1u16.to_le_bytes());
    write(&mut r, 0x6060, 0, &[2]);
    enable(&mut r);
    write(&mut r, 0x6042, 0, &500i16.to_le_bytes());
    r.run_ms(1000);
    let demand = r.read_u32(ID, 0x6043, 0) as i16;
    assert!((95..=105).contains(&demand), "100 min⁻¹ after 1 s at 100 min⁻¹/s: {demand}");
    r.run_ms(2000);
    let demand = r.read_u32(ID, 0x6043, 0) as i16;
    assert_eq!(demand, 200, "bounded by 6046h:2");
    // 6044h: the measured speed (4096 counts differentiated per control
    // period: noisy), on average the demand.
    let mut sum = 0i32;
    for _ in 0..50 {
        r.run_ms(3);
        sum += i32::from(r.read_u32(ID, 0x6044, 0) as i16);
    }
    assert!((sum / 50 - 200).abs() <= 15, "{}", sum / 50);
}

#[test]
fn quick_stop_ends_in_switch_on_disabled() {
    // §12 605Ah (default 2: the quick-stop ramp 6085h, then Switch on
    // disabled).
    let mut r = rig();
    write(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    write(&mut r, 0x6060, 0, &[3]);
    enable(&mut r);
    write(&mut r, 0x60FF, 0, &1000i32.to_le_bytes());
    r.run_ms(300);
    controlword(&mut r, 0x0B);
    r.run_ms(200);
    assert_eq!(r.read_u32(ID, 0x6041, 0) & 0x4F, 0x40, "switch on disabled");
}

/// The 630 on an axis with an end stop at +100 000 increments (the motor
/// blocks there), a move to 1 000 000 with 6065h = `window`: the EMCYs.
fn blocked_move(window: u32) -> Vec<drivebus_can::Frame> {
    let pn = drivebus_personality::build::build_on_machine(
        Profile::Ssd630,
        ID,
        Box::new(MemoryStorage::new()),
        |cfg| cfg.params.axis.positive_stop = Some(100_000.0 / 4096.0 * 360.0),
    )
    .unwrap();
    let (mut r, _) = Rig::with(pn);
    write(&mut r, 0x6065, 0, &window.to_le_bytes());
    enable(&mut r);
    r.run_ms(600);
    r.take();
    r.send("601#23 7A 60 00 40 42 0F 00");
    r.send("601#2B 40 60 00 1F 00 00 00");
    r.run_ms(2000);
    emcy(&r.take())
}

#[test]
fn following_error_window_6065h() {
    // §12 6065h "following error window": a position error beyond it is
    // 8611h (§9 Table 1, register 21h); a window wider than the rest of
    // the move lets the blocked axis be.
    assert!(blocked_move(4096).contains(&fr("081#11 86 21 00 00 00 00 00")));
    assert_eq!(blocked_move(2_000_000), vec![]);
}

#[test]
fn position_values_during_a_move() {
    // §12 6062h demand, 6063h/6064h actual (increments, factor 1), 607Fh
    // bounds 6081h.
    let mut r = rig();
    write(&mut r, 0x607F, 0, &500u32.to_le_bytes());
    enable(&mut r);
    write(&mut r, 0x607A, 0, &1_000_000i32.to_le_bytes());
    controlword(&mut r, 0x1F);
    r.run_ms(2000);
    let d0 = r.read_u32(ID, 0x6062, 0) as i32;
    r.run_ms(600);
    let d1 = r.read_u32(ID, 0x6062, 0) as i32;
    // 500 min⁻¹ = 4096 · 500 / 60 increments/s.
    let speed = f64::from(d1 - d0) / 0.6 * 60.0 / 4096.0;
    assert!((speed - 500.0).abs() < 5.0, "{speed}");
    let (a, b) = (r.read_u32(ID, 0x6063, 0) as i32, r.read_u32(ID, 0x6064, 0) as i32);
    assert!((a - b).abs() < 200, "{a} {b}");
}

#[test]
fn digital_inputs_and_outputs() {
    // §12 60FDh digital inputs (CiA 402: bit 1 positive limit switch), the
    // axis standing on its positive limit switch; 60FEh:1 physical outputs
    // under the bit mask 60FEh:2 (default FFFF0000h: the manufacturer
    // outputs).
    let pn = drivebus_personality::build::build_on_machine(
        Profile::Ssd630,
        ID,
        Box::new(MemoryStorage::new()),
        |cfg| {
            cfg.params.axis.positive_limit = Some(10.0);
            cfg.params.axis.initial_position = 20.0;
        },
    )
    .unwrap();
    let (mut r, _) = Rig::with(pn);
    r.run_ms(5);
    assert_eq!(r.read_u32(ID, 0x60FD, 0) & 0b11, 0b10);
    write(&mut r, 0x60FE, 1, &0x0003_0001u32.to_le_bytes());
    r.run_ms(5);
    assert_eq!(r.pn().app.drive.digital_outputs(), 0x0003_0000);
}

#[test]
fn drive_information_reads_the_machine() {
    // §13 4803h "Drive information": 05h motor temperature (°C), 06h Ucc
    // (V), 07h analog input X10 (mV); units are not given (our choice).
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Plant;
    let mut r = rig();
    r.pn_mut().app.inject(Injection::Model(Plant::AnalogInput { channel: 1, volts: -2.5 }));
    r.run_ms(5);
    let m = r.pn().app.drive.model();
    let (temp, ucc) = (m.temperature().round() as u32, m.bus_voltage().round() as u32);
    assert!(ucc > 0);
    assert_eq!(r.read_u32(ID, 0x4803, 5), temp);
    assert_eq!(r.read_u32(ID, 0x4803, 6), ucc);
    assert_eq!(r.read_u32(ID, 0x4803, 7) as u16 as i16, -2500);
}
