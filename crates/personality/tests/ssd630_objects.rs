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
fn number_of_pdos_is_unsigned32() {
    // §11 1004h: sub 0 "Unsigned 32 Number of PDO's", sub 1/2 synchronous /
    // asynchronous (UNSIGNED32): 4 RPDOs (bits 0–15) and 4 TPDOs (16–31).
    let mut r = rig();
    assert_eq!(r.upload(ID, 0x1004, 0), Ok(0x0004_0004u32.to_le_bytes().to_vec()));
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
