//! EMCY frames printed in the drive manuals (/work/shared/reference/seed00*-examples.md),
//! replayed through the decoder, the 1028h consumer and the producer.

use drivebus_can::{Frame, Instant};
use drivebus_emcy::{Emcy, EmcyConsumer, decode, describe, register_bit_for};
use drivebus_od::ObjectDictionary;

fn consumer() -> (ObjectDictionary, EmcyConsumer) {
    let mut od = ObjectDictionary::new();
    let c = EmcyConsumer::install(&mut od, 127);
    (od, c)
}

/// seed000 (KC1) Example 11 (§8.2.1.10), frames 28 and 29 (src lines 5575, 5576), and
/// seed001 (AKD) §11b rows 5999 and 6000: printed with 7 data bytes.
/// TYPO in the manuals: the category byte 3 is missing (the 8-byte forms are in
/// Example 12 / §13k below); the decoder is tolerant and zero-pads.
#[test]
fn kc1_akd_seven_byte_frames() {
    let (_od, c) = consumer();
    let f = Frame::new(0x081, &[0x10, 0x43, 0x08, 0x00, 0x00, 0x00, 0x00]);
    let r = c.handle_frame(&f).unwrap();
    assert_eq!((r.node_id, r.code, r.register, r.data), (Some(1), 0x4310, 0x08, [0; 5]));
    assert_eq!(decode(&f).unwrap().len, 7);
    assert_eq!(describe(r.code), Some("Excess temperature drive"));

    let f = Frame::new(0x081, &[0x00, 0x00, 0x88, 0x00, 0x00, 0x00, 0x00]);
    let r = c.handle_frame(&f).unwrap();
    // Code 0000h with register 88h: some errors reset, temperature + manufacturer remain.
    assert_eq!((r.code, r.register), (0x0000, 0x88));
    assert!(decode(&f).unwrap().is_reset());
}

/// seed000 (KC1) Example 12 (§8.2.2.1), frames 60 and 61 (src lines 5757, 5758), and
/// seed001 (AKD) §13k rows 6190 and 6191: 8 bytes, byte 3 = category (01 on error).
#[test]
fn kc1_akd_eight_byte_frames() {
    let (_od, c) = consumer();
    let err = Frame::new(0x081, &[0x10, 0x43, 0x08, 0x01, 0x00, 0x00, 0x00, 0x00]);
    let rst = Frame::new(0x081, &[0x00, 0x00, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00]);
    let r = c.handle_frame(&err).unwrap();
    assert_eq!((r.sub, r.code, r.register, r.data), (1, 0x4310, 0x08, [0x01, 0, 0, 0, 0]));
    let r = c.handle_frame(&rst).unwrap();
    assert_eq!((r.code, r.register), (0x0000, 0x08));

    // Produced by drivebus: a CiA 301 producer sets the generic bit 0 with any
    // error (§7.5.2 (1001h)), so the register reads 09h where the manual prints 08h,
    // and the reset after the last error carries 00h (the manual's 08h is the
    // quirk seed001 flags at row 6191).
    let mut od = ObjectDictionary::new();
    let mut e = Emcy::install(&mut od, 1, 10);
    e.raise(&mut od, 0x4310, register_bit_for(0x4310), [0x01, 0, 0, 0, 0], Instant::ZERO);
    e.clear(&mut od, 0x4310, Instant::ZERO);
    let mut out = Vec::new();
    e.poll(Instant::ZERO, &mut out);
    assert_eq!(
        out,
        [
            Frame::new(0x081, &[0x10, 0x43, 0x09, 0x01, 0x00, 0x00, 0x00, 0x00]),
            Frame::new(0x081, &[0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00]),
        ]
    );
    // A KC1 personality that must match the manual byte for byte uses send_raw.
    e.send_raw(0x4310, 0x08, [0x01, 0, 0, 0, 0], Instant::ZERO);
    e.send_raw(0x0000, 0x08, [0; 5], Instant::ZERO);
    out.clear();
    e.poll(Instant::ZERO, &mut out);
    assert_eq!(out, [err, rst]);
}

/// seed003 (SSD 630) §9 table 1: code | register | five zero bytes, with the
/// register values the manual prints; the codes whose register follows the
/// CiA 301 classes come out of `raise` with `register_bit_for`.
#[test]
fn ssd630_table_frames() {
    let mut od = ObjectDictionary::new();
    let mut e = Emcy::install(&mut od, 1, 8);
    let mut out = Vec::new();
    for (code, reg) in [(0x2311u16, 0x03u8), (0x3220, 0x05), (0x4210, 0x09), (0x8611, 0x21), (0x8700, 0x21)] {
        e.raise(&mut od, code, register_bit_for(code), [0; 5], Instant::ZERO);
        e.poll(Instant::ZERO, &mut out);
        let c = code.to_le_bytes();
        assert_eq!(out.pop(), Some(Frame::new(0x081, &[c[0], c[1], reg, 0, 0, 0, 0, 0])), "{code:04X}");
        e.clear_all(&mut od, Instant::ZERO);
        e.poll(Instant::ZERO, &mut out);
        assert_eq!(out.pop(), Some(Frame::new(0x081, &[0; 8])));
    }
    // Manufacturer-assigned registers (5441h contacts -> 81h) use explicit bits.
    e.raise(&mut od, 0x5441, 0x80, [0; 5], Instant::ZERO);
    e.poll(Instant::ZERO, &mut out);
    assert_eq!(out.pop(), Some(Frame::new(0x081, &[0x41, 0x54, 0x81, 0, 0, 0, 0, 0])));
    // 1003h: newest first, max 8 (seed003 B.7 transition 3).
    assert_eq!(od.get_u32(0x1003, 0), Some(6));
    assert_eq!(od.get_u32(0x1003, 1), Some(0x5441));
    assert_eq!(od.get_u32(0x1003, 6), Some(0x2311));
}
