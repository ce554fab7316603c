//! The generic personality: every feature of the stack (CiA 301 + 402),
//! built with `Profile::Generic.build(id)` and exercised on the virtual bus
//! with frames computed from the standards (CiA 301 §7.2.4 SDO, CiA 305 LSS,
//! CiA 302-3 program download objects).

mod replay_rig;

use drivebus_can::Frame;
use drivebus_personality::Profile;
use replay_rig::*;

fn generic(id: u8) -> Rig {
    let (r, boot) = Rig::new(Profile::Generic, id);
    assert_eq!(boot, frs(&[&format!("{:03X}#00", 0x700 + u16::from(id))]));
    r
}

/// CRC-16-CCITT (XModem: poly 1021h, init 0), the block SDO checksum of
/// CiA 301 §7.2.4.3.16.
fn crc16(data: &[u8]) -> u16 {
    let mut crc = 0u16;
    for &b in data {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 { (crc << 1) ^ 0x1021 } else { crc << 1 };
        }
    }
    crc
}

/// CRC-32 (IEEE 802.3, reflected), as 1F56h reports the program.
fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

fn one(r: &mut Rig, f: Frame) -> Frame {
    r.take();
    r.bus.send_from(r.probe, f);
    r.run_for(drivebus_can::Duration::from_micros(1));
    let v = r.take();
    assert_eq!(v.len(), 1, "{v:?}");
    v[0]
}

/// Segmented download (CiA 301 §7.2.4.3.3–5) of `data` to index:sub of node 5.
fn segmented_download(r: &mut Rig, index: u16, sub: u8, data: &[u8]) {
    let [il, ih] = index.to_le_bytes();
    let n = (data.len() as u32).to_le_bytes();
    let resp = one(r, Frame::new(0x605, &[0x21, il, ih, sub, n[0], n[1], n[2], n[3]]));
    assert_eq!(resp, Frame::new(0x585, &[0x60, il, ih, sub, 0, 0, 0, 0]));
    let mut toggle = 0u8;
    for (i, chunk) in data.chunks(7).enumerate() {
        let last = (i + 1) * 7 >= data.len();
        let mut b = [0u8; 8];
        b[0] = toggle << 4 | (((7 - chunk.len()) as u8) << 1) | u8::from(last);
        b[1..1 + chunk.len()].copy_from_slice(chunk);
        let resp = one(r, Frame::new(0x605, &b));
        assert_eq!(resp, Frame::new(0x585, &[0x20 | toggle << 4, 0, 0, 0, 0, 0, 0, 0]));
        toggle ^= 1;
    }
}

/// Segmented (or expedited) upload of index:sub of node 5.
fn upload(r: &mut Rig, index: u16, sub: u8) -> Vec<u8> {
    let [il, ih] = index.to_le_bytes();
    let resp = one(r, Frame::new(0x605, &[0x40, il, ih, sub, 0, 0, 0, 0]));
    let d = resp.data().to_vec();
    assert_eq!(d[0] & 0xE0, 0x40, "upload response {resp:?}");
    if d[0] & 0x02 != 0 {
        let n = if d[0] & 1 != 0 { 4 - usize::from((d[0] >> 2) & 3) } else { 4 };
        return d[4..4 + n].to_vec();
    }
    let size = u32::from_le_bytes([d[4], d[5], d[6], d[7]]) as usize;
    let mut out = Vec::new();
    let mut toggle = 0u8;
    loop {
        let s = one(r, Frame::new(0x605, &[0x60 | toggle << 4, 0, 0, 0, 0, 0, 0, 0]));
        let d = s.data();
        assert_eq!(d[0] & 0xF0, toggle << 4, "toggle");
        let n = 7 - usize::from((d[0] >> 1) & 7);
        out.extend_from_slice(&d[1..1 + n]);
        toggle ^= 1;
        if d[0] & 1 != 0 {
            break;
        }
    }
    assert_eq!(out.len(), size);
    out
}

/// A generic drive goes on the bus in a few lines, with CiA 402 defaults:
/// 1000h 0002_0192h, every mode (6502h: pp pv tq hm ip csp csv cst), the
/// standard homing methods in 60E3h, switch on disabled.
#[test]
fn generic_on_the_bus() {
    let mut r = generic(5);
    assert_eq!(r.read_u32(5, 0x1000, 0), 0x0002_0192);
    assert_eq!(r.read_u32(5, 0x6502, 0), 0x3ED);
    for m in [1u8, 3, 4, 6, 7, 8, 9, 10] {
        Rig::assert_written(r.sdo_write(5, 0x6060, 0, &[m]), 5, 0x6060, 0);
    }
    let n = r.read_u32(5, 0x60E3, 0);
    assert_eq!(n, 32, "CiA 402-2: 1–14, 17–30, 33–35, 37");
    for m in [1u8, 14, 17, 30, 33, 34, 35, 37] {
        Rig::assert_written(r.sdo_write(5, 0x6098, 0, &[m]), 5, 0x6098, 0);
    }
    assert_eq!(r.statusword() & 0x4F, 0x40);
    // NMT 80h is supported (CiA 301 §7.2.8.3.1.3).
    r.send("000#01 05");
    r.run_ms(1);
    r.take();
    r.send("000#80 05");
    assert_eq!(r.node().nmt_state(), drivebus_node::NmtState::PreOperational);
    // TIME exists (1012h).
    assert!(r.node().od().object(0x1012).is_some());
}

/// Every mode runs: csp follows SYNC-latched targets; cst/csv accept
/// their set-points (6502h bit per mode, CiA 402-2 §6.3).
#[test]
fn generic_cyclic_position_follows_sync() {
    let mut r = generic(5);
    Rig::assert_written(r.sdo_write(5, 0x6060, 0, &[8]), 5, 0x6060, 0);
    for cw in [6u16, 7, 0xF] {
        Rig::assert_written(r.sdo_write(5, 0x6040, 0, &cw.to_le_bytes()), 5, 0x6040, 0);
        r.run_ms(1);
    }
    assert_eq!(r.statusword() & 0x6F, 0x27);
    r.send("000#01 05");
    for k in 1..=200i32 {
        Rig::assert_written(r.sdo_write(5, 0x607A, 0, &(k * 10).to_le_bytes()), 5, 0x607A, 0);
        r.send("080#");
        r.take();
        r.run_ms(1);
    }
    r.run_ms(50);
    let p = r.position();
    assert!((p - 2000).abs() < 20, "csp position {p}");
}

/// 1F50h:1 program data written by segmented download and read back by
/// upload; 1F56h:1 is the CRC-32 of the program; 1F51h:1 controls it
/// (CiA 302-3: 0 stop, 1 start, 3 clear); a download while running is
/// refused with 0800 0022.
#[test]
fn generic_program_download_segmented() {
    let mut r = generic(5);
    let program: Vec<u8> = (0..100u8).map(|i| i.wrapping_mul(7) ^ 0x5A).collect();
    segmented_download(&mut r, 0x1F50, 1, &program);
    assert_eq!(upload(&mut r, 0x1F50, 1), program);
    assert_eq!(r.read_u32(5, 0x1F56, 1), crc32(&program));
    Rig::assert_written(r.sdo_write(5, 0x1F51, 1, &[1]), 5, 0x1F51, 1);
    // The write reaches the application when the transfer completes: an
    // expedited download is refused at once.
    let resp = r.sdo_write(5, 0x1F50, 1, &[1, 2, 3, 4]);
    Rig::assert_abort(resp, 5, 0x1F50, 1, 0x0800_0022);
    Rig::assert_written(r.sdo_write(5, 0x1F51, 1, &[0]), 5, 0x1F51, 1);
    Rig::assert_written(r.sdo_write(5, 0x1F51, 1, &[3]), 5, 0x1F51, 1);
    assert_eq!(r.read_u32(5, 0x1F56, 1), 0);
    Rig::assert_abort(r.sdo_write(5, 0x1F51, 1, &[9]), 5, 0x1F51, 1, 0x0609_0030);
}

/// 1F50h:1 by SDO block download with CRC (CiA 301 §7.2.4.3.9–14), read
/// back by segmented upload.
#[test]
fn generic_program_download_block() {
    let mut r = generic(5);
    let program: Vec<u8> = (0..40u8).collect();
    let n = (program.len() as u32).to_le_bytes();
    // Initiate: ccs 6, cc (CRC) 1, s 1.
    let resp = one(&mut r, Frame::new(0x605, &[0xC6, 0x50, 0x1F, 1, n[0], n[1], n[2], n[3]]));
    let d = resp.data();
    assert_eq!(&d[..4], &[0xA4, 0x50, 0x1F, 1], "initiate response {resp:?}");
    let blksize = d[4];
    assert!(blksize >= 6);
    // 40 bytes = 6 segments, the last one flagged (c = 1) with 5 bytes.
    r.take();
    for (i, chunk) in program.chunks(7).enumerate() {
        let mut b = [0u8; 8];
        let last = (i + 1) * 7 >= program.len();
        b[0] = (i as u8 + 1) | if last { 0x80 } else { 0 };
        b[1..1 + chunk.len()].copy_from_slice(chunk);
        r.bus.send_from(r.probe, Frame::new(0x605, &b));
    }
    r.run_for(drivebus_can::Duration::from_micros(10));
    let ack = r.take();
    assert_eq!(ack.len(), 1);
    assert_eq!(&ack[0].data()[..2], &[0xA2, 6], "block ack {:?}", ack[0]);
    // End: n = 2 unused bytes in the last segment, CRC.
    let crc = crc16(&program).to_le_bytes();
    let resp = one(&mut r, Frame::new(0x605, &[0xC1 | (2 << 2), crc[0], crc[1], 0, 0, 0, 0, 0]));
    assert_eq!(resp, Frame::new(0x585, &[0xA1, 0, 0, 0, 0, 0, 0, 0]));
    assert_eq!(upload(&mut r, 0x1F50, 1), program);
    assert_eq!(r.read_u32(5, 0x1F56, 1), crc32(&program));
}

/// 1021h: the device's EDS, read by segmented upload, parses and describes
/// the running device (CiA 301 §7.5.2.21, CiA 306).
#[test]
fn generic_serves_its_eds_at_1021h() {
    let mut r = generic(5);
    let text = upload(&mut r, 0x1021, 0);
    let parsed = drivebus_eds::parse(std::str::from_utf8(&text).unwrap()).unwrap();
    let od = drivebus_eds::to_od(&parsed.eds, 5).unwrap();
    assert_eq!(od.get_u32(0x1000, 0), Some(0x0002_0192));
    assert!(od.object(0x1F50).is_some());
}

/// LSS (CiA 305): switch state global to configuration, inquire the
/// vendor-ID (§6.3.4: cs 5Ah) — the generic identity's vendor-ID 0.
#[test]
fn generic_lss_inquire_vendor() {
    let mut r = generic(5);
    r.exchange("7E5#04 01 00 00 00 00 00 00", &[]);
    r.exchange("7E5#5A 00 00 00 00 00 00 00", &["7E4#5A 00 00 00 00 00 00 00"]);
    r.exchange("7E5#5E 00 00 00 00 00 00 00", &["7E4#5E 05 00 00 00 00 00 00"]);
}

/// Every personality is built from its name, as the CLI's
/// `serve --drive PROFILE:NODE` does, and boots on the bus.
#[test]
fn every_profile_builds_from_its_name() {
    for p in Profile::all() {
        let spec = format!("{}:7", p.name());
        let (profile, id) = drivebus_personality::parse_drive_spec(&spec).expect("spec");
        assert_eq!((profile, id), (*p, 7));
        let (r, _boot) = Rig::with(profile.build(id).unwrap_or_else(|e| panic!("{spec}: {e}")));
        assert_eq!(r.pn().app.profile(), *p);
        assert_eq!(r.node().od().get_u32(0x1000, 0), Some(p.info().device_type), "{spec}");
    }
    assert!(drivebus_personality::parse_drive_spec("akd:0x10").is_some());
    assert!(drivebus_personality::parse_drive_spec("akd:0").is_none());
    assert!(drivebus_personality::parse_drive_spec("nope:3").is_none());
}
