//! EMCY producer scenarios (CiA 301 §7.2.7; §7.5.2 for 1001h, 1003h, 1014h, 1015h), frame-exact.

use drivebus_can::{Frame, Instant};
use drivebus_emcy::{Emcy, ErrorRegister, QUEUE_LEN, register_bit_for};
use drivebus_od::{NoHooks, ObjectDictionary, SdoAbort};

fn setup(node: u8, history: u8) -> (ObjectDictionary, Emcy) {
    let mut od = ObjectDictionary::new();
    let e = Emcy::install(&mut od, node, history);
    (od, e)
}

fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

fn poll_all(e: &mut Emcy, now: Instant) -> (Vec<Frame>, Option<Instant>) {
    let mut out = Vec::new();
    let next = e.poll(now, &mut out);
    (out, next)
}

/// SDO-style write through the service: check, store, reconfigure.
fn sdo_write(
    od: &mut ObjectDictionary,
    e: &mut Emcy,
    index: u16,
    sub: u8,
    data: &[u8],
) -> Result<(), SdoAbort> {
    e.check_write(od, index, sub, data)?;
    od.write(&mut NoHooks, index, sub, data)?;
    e.reconfigure(od, index, sub);
    Ok(())
}

#[test]
fn objects_and_defaults() {
    let (od, e) = setup(5, 8);
    assert_eq!(od.get_u32(0x1014, 0), Some(0x85));
    assert!(od.get(0x1014, 0).unwrap().node_id_relative);
    assert!(od.get(0x1001, 0).unwrap().tpdo_mappable());
    assert_eq!(od.get_u32(0x1003, 0), Some(0));
    assert!(od.get(0x1003, 8).is_some() && od.get(0x1003, 9).is_none());
    assert_eq!(od.get_u32(0x1015, 0), Some(0));
    assert!(e.is_valid());
    // Unconfigured node-ID: EMCY object invalid by default.
    let (od, e) = setup(0, 0);
    assert_eq!(od.get_u32(0x1014, 0), Some(0x8000_0080));
    assert!(od.get(0x1003, 0).is_none());
    assert!(!e.is_valid());
}

#[test]
fn raise_and_clear_are_frame_exact() {
    let (mut od, mut e) = setup(1, 8);
    let t = ms(10);
    assert!(e.raise(&mut od, 0x4310, register_bit_for(0x4310), [0x01, 0, 0, 0, 0], t));
    assert_eq!(e.error_register(), 0x09);
    assert_eq!(od.get_u32(0x1001, 0), Some(0x09));
    assert_eq!(od.get_u32(0x1003, 0), Some(1));
    assert_eq!(od.get_u32(0x1003, 1), Some(0x4310));
    // A second raise of an active code sends nothing (§7.2.7: once per occurrence).
    assert!(!e.raise(&mut od, 0x4310, 0x08, [0; 5], t));
    let (out, next) = poll_all(&mut e, t);
    assert_eq!(out, [Frame::new(0x081, &[0x10, 0x43, 0x09, 0x01, 0, 0, 0, 0])]);
    assert_eq!(next, None);

    assert!(e.clear(&mut od, 0x4310, ms(20)));
    assert!(!e.clear(&mut od, 0x4310, ms(20)));
    assert_eq!(od.get_u32(0x1001, 0), Some(0));
    // The history keeps the occurrence.
    assert_eq!(od.get_u32(0x1003, 0), Some(1));
    let (out, _) = poll_all(&mut e, ms(20));
    assert_eq!(out, [Frame::new(0x081, &[0, 0, 0, 0, 0, 0, 0, 0])]);
}

#[test]
fn partial_clear_reports_remaining_register() {
    let (mut od, mut e) = setup(1, 8);
    e.raise(&mut od, 0x3210, register_bit_for(0x3210), [0; 5], ms(0));
    e.raise(&mut od, 0xFF01, register_bit_for(0xFF01), [0xAA, 0, 0, 0, 0], ms(0));
    assert_eq!(
        e.error_register(),
        ErrorRegister::GENERIC | ErrorRegister::VOLTAGE | ErrorRegister::MANUFACTURER
    );
    e.clear(&mut od, 0x3210, ms(1));
    e.clear_all(&mut od, ms(2));
    e.clear_all(&mut od, ms(3)); // nothing active: no frame
    let (out, _) = poll_all(&mut e, ms(3));
    assert_eq!(
        out,
        [
            Frame::new(0x081, &[0x10, 0x32, 0x05, 0, 0, 0, 0, 0]),
            Frame::new(0x081, &[0x01, 0xFF, 0x85, 0xAA, 0, 0, 0, 0]),
            // §7.2.7 transition 2: 0000h with the remaining errors' register.
            Frame::new(0x081, &[0, 0, 0x81, 0, 0, 0, 0, 0]),
            Frame::new(0x081, &[0, 0, 0, 0, 0, 0, 0, 0]),
        ]
    );
    assert!(e.active().is_empty());
    // Partial resets can be turned off; the last reset is still sent.
    e.set_partial_reset(false);
    e.raise(&mut od, 0x2310, 0x02, [0; 5], ms(4));
    e.raise(&mut od, 0x8611, 0x20, [0; 5], ms(4));
    e.clear(&mut od, 0x2310, ms(5));
    e.clear(&mut od, 0x8611, ms(5));
    let (out, _) = poll_all(&mut e, ms(5));
    assert_eq!(out.len(), 3);
    assert_eq!(out[2], Frame::new(0x081, &[0; 8]));
}

#[test]
fn history_order_and_overflow() {
    let (mut od, mut e) = setup(1, 3);
    for (i, code) in [0x1000u16, 0x2310, 0x3210, 0x4310].into_iter().enumerate() {
        e.raise(&mut od, code, register_bit_for(code), [0; 5], ms(i as u64));
    }
    // Newest at sub 1, the oldest (1000h) fell off.
    assert_eq!(e.history(), [0x4310, 0x3210, 0x2310]);
    assert_eq!(od.get_u32(0x1003, 0), Some(3));
    assert_eq!(od.get_u32(0x1003, 1), Some(0x4310));
    assert_eq!(od.get_u32(0x1003, 2), Some(0x3210));
    assert_eq!(od.get_u32(0x1003, 3), Some(0x2310));
    assert_eq!(e.check_read(0x1003, 3), Ok(()));
}

#[test]
fn history_sub0_writes() {
    let (mut od, mut e) = setup(1, 8);
    e.raise(&mut od, 0x2310, 0x02, [0; 5], ms(0));
    e.raise(&mut od, 0x3220, 0x04, [0; 5], ms(0));
    assert_eq!(e.check_read(0x1003, 2), Ok(()));
    // Reading past the count: 0800 0024 no data available.
    assert_eq!(e.check_read(0x1003, 3), Err(SdoAbort::NO_DATA));
    for v in [1u8, 2, 8, 255] {
        assert_eq!(sdo_write(&mut od, &mut e, 0x1003, 0, &[v]), Err(SdoAbort::INVALID_VALUE));
    }
    assert_eq!(sdo_write(&mut od, &mut e, 0x1003, 0, &[0, 0]), Err(SdoAbort::DATA_TOO_LONG));
    assert_eq!(sdo_write(&mut od, &mut e, 0x1003, 1, &[0; 4]), Err(SdoAbort::WRITE_READ_ONLY));
    sdo_write(&mut od, &mut e, 0x1003, 0, &[0]).unwrap();
    assert!(e.history().is_empty());
    assert_eq!(od.get_u32(0x1003, 0), Some(0));
    assert_eq!(od.get_u32(0x1003, 1), Some(0));
    assert_eq!(e.check_read(0x1003, 1), Err(SdoAbort::NO_DATA));
    // Active errors and 1001h are not touched by deleting the history.
    assert_eq!(od.get_u32(0x1001, 0), Some(0x07));
}

#[test]
fn inhibit_time_queues() {
    let (mut od, mut e) = setup(2, 8);
    // 1015h = 100 -> 10 ms.
    sdo_write(&mut od, &mut e, 0x1015, 0, &100u16.to_le_bytes()).unwrap();
    e.raise(&mut od, 0x2310, 0x02, [0; 5], ms(0));
    e.raise(&mut od, 0x3210, 0x04, [0; 5], ms(1));
    e.raise(&mut od, 0x4310, 0x08, [0; 5], ms(2));
    let (out, next) = poll_all(&mut e, ms(2));
    assert_eq!(out, [Frame::new(0x082, &[0x10, 0x23, 0x03, 0, 0, 0, 0, 0])]);
    assert_eq!(next, Some(ms(12)));
    // Polling early does nothing observable.
    assert_eq!(poll_all(&mut e, ms(11)), (vec![], Some(ms(12))));
    let (out, next) = poll_all(&mut e, ms(12));
    assert_eq!(out, [Frame::new(0x082, &[0x10, 0x32, 0x07, 0, 0, 0, 0, 0])]);
    assert_eq!(next, Some(ms(22)));
    // A late poll sends one frame and restarts the inhibit time from then.
    let (out, next) = poll_all(&mut e, ms(40));
    assert_eq!(out, [Frame::new(0x082, &[0x10, 0x43, 0x0F, 0, 0, 0, 0, 0])]);
    assert_eq!(next, None);
    // A new event after the inhibit time has run out goes at once.
    e.clear_all(&mut od, ms(55));
    assert_eq!(poll_all(&mut e, ms(55)).0, [Frame::new(0x082, &[0; 8])]);
    // Inside the inhibit time it waits for the rest of it.
    e.raise(&mut od, 0x9000, 0, [0; 5], ms(60));
    assert_eq!(poll_all(&mut e, ms(60)), (vec![], Some(ms(65))));
    // Shortening 1015h shortens the pending wait.
    sdo_write(&mut od, &mut e, 0x1015, 0, &20u16.to_le_bytes()).unwrap();
    assert_eq!(poll_all(&mut e, ms(60)), (vec![Frame::new(0x082, &[0x00, 0x90, 0x01, 0, 0, 0, 0, 0])], None));
}

#[test]
fn queue_is_bounded() {
    let (mut od, mut e) = setup(1, 0);
    sdo_write(&mut od, &mut e, 0x1015, 0, &10u16.to_le_bytes()).unwrap();
    for i in 0..(QUEUE_LEN as u16 + 3) {
        e.send_raw(0xFF00 + i, 0x80, [0; 5], ms(0));
    }
    assert_eq!(e.dropped(), 3);
    let mut sent = 0;
    let mut now = ms(0);
    while let (out, Some(next)) = poll_all(&mut e, now) {
        sent += out.len();
        now = next;
    }
    assert_eq!(sent + 1, QUEUE_LEN);
}

#[test]
fn cob_id_rules_and_invalid_sends_nothing() {
    let (mut od, mut e) = setup(1, 8);
    assert_eq!(sdo_write(&mut od, &mut e, 0x1014, 0, &0x82u32.to_le_bytes()), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(sdo_write(&mut od, &mut e, 0x1014, 0, &0x81u32.to_le_bytes()), Ok(()));
    // Queue something, then invalidate: the queue is dropped, nothing is sent.
    e.raise(&mut od, 0x5530, 0, [0; 5], ms(0));
    sdo_write(&mut od, &mut e, 0x1014, 0, &0x8000_0081u32.to_le_bytes()).unwrap();
    assert!(!e.is_valid());
    e.raise(&mut od, 0x6100, 0, [0; 5], ms(1));
    assert_eq!(poll_all(&mut e, ms(1)), (vec![], None));
    // 1001h and 1003h still follow the errors.
    assert_eq!(od.get_u32(0x1001, 0), Some(0x01));
    assert_eq!(od.get_u32(0x1003, 0), Some(2));
    // While invalid the id may change; restricted ids are refused once valid.
    sdo_write(&mut od, &mut e, 0x1014, 0, &0x8000_0090u32.to_le_bytes()).unwrap();
    assert_eq!(
        sdo_write(&mut od, &mut e, 0x1014, 0, &0x0000_0701u32.to_le_bytes()),
        Err(SdoAbort::INVALID_VALUE)
    );
    assert_eq!(
        sdo_write(&mut od, &mut e, 0x1014, 0, &0x4000_0090u32.to_le_bytes()),
        Err(SdoAbort::INVALID_VALUE)
    );
    sdo_write(&mut od, &mut e, 0x1014, 0, &0x90u32.to_le_bytes()).unwrap();
    e.clear(&mut od, 0x6100, ms(2));
    assert_eq!(poll_all(&mut e, ms(2)).0, [Frame::new(0x090, &[0, 0, 0x01, 0, 0, 0, 0, 0])]);
}

/// SSD 630 boot message (seed003 §9 transition 0 / EX summary item 8):
/// code 0000h, register 00h, firmware version "V819d" in bytes 3..7.
#[test]
fn ssd630_boot_emcy_via_send_raw() {
    let (mut od, mut e) = setup(1, 8);
    e.send_raw(0x0000, 0x00, *b"V819d", ms(0));
    let (out, _) = poll_all(&mut e, ms(0));
    assert_eq!(out, [Frame::new(0x081, &[0x00, 0x00, 0x00, b'V', b'8', b'1', b'9', b'd'])]);
    assert_eq!(od.get_u32(0x1003, 0), Some(0), "raw sends are not history");
    let _ = &mut od;
}
