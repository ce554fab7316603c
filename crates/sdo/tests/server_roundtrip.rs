//! Whole transfers against the server with the scripted client: segmented
//! and block, 10 KiB, with and without CRC, with lost segments.

mod server_support;

use drivebus_od::{SdoAbort, Value};
use drivebus_sdo::server::ServerConfig;
use server_support::{Wire, pattern, test_od};

const LEN: usize = 10 * 1024;

fn abort_code(f: [u8; 8]) -> SdoAbort {
    SdoAbort(u32::from_le_bytes([f[4], f[5], f[6], f[7]]))
}

#[test]
fn segmented_10k_round_trip() {
    let mut w = Wire::new(test_od(LEN), ServerConfig::default());
    assert_eq!(w.upload(0x2000, 0).unwrap(), pattern(LEN, 1));
    let data = pattern(LEN, 2);
    w.download(0x2000, 0, &data).unwrap();
    assert_eq!(w.od.get(0x2000, 0).unwrap().bytes(), &data[..]);
    assert_eq!(w.upload(0x2000, 0).unwrap(), data);
    assert!(w.server.is_idle());
}

#[test]
fn block_10k_round_trip_with_and_without_crc() {
    for crc in [true, false] {
        for blksize in [127u8, 1, 16] {
            let mut w = Wire::new(test_od(LEN), ServerConfig::default());
            assert_eq!(w.block_upload(0x2000, 0, blksize, crc, &[]).unwrap(), pattern(LEN, 1));
            let data = pattern(LEN, 3);
            w.block_download(0x2000, 0, &data, crc, &[]).unwrap();
            assert_eq!(w.od.get(0x2000, 0).unwrap().bytes(), &data[..]);
            assert!(w.server.is_idle());
        }
    }
    // A server without CRC support talking to a client with it.
    let mut w = Wire::new(test_od(LEN), ServerConfig { crc: false, ..ServerConfig::default() });
    assert_eq!(w.block_upload(0x2000, 0, 127, true, &[]).unwrap(), pattern(LEN, 1));
    w.block_download(0x2000, 0, &pattern(LEN, 4), true, &[]).unwrap();
}

#[test]
fn block_with_lost_segments_is_retransmitted() {
    let mut w = Wire::new(test_od(LEN), ServerConfig::default());
    // Lost: one early in the first sub-block, one in a later one, and the
    // first segment of the retransmitted sub-block.
    let lose = [5usize, 127 + 40, 300, 301];
    assert_eq!(w.block_upload(0x2000, 0, 127, true, &lose).unwrap(), pattern(LEN, 1));
    let data = pattern(LEN, 5);
    w.block_download(0x2000, 0, &data, true, &[5, 200, 400]).unwrap();
    assert_eq!(w.od.get(0x2000, 0).unwrap().bytes(), &data[..]);
    // Sizes that end exactly on a segment and a sub-block boundary.
    for len in [0usize, 1, 6, 7, 8, 889, 890, 1778] {
        let data = pattern(len, len as u32);
        w.block_download(0x2000, 0, &data, true, &[]).unwrap();
        assert_eq!(w.block_upload(0x2000, 0, 127, true, &[]).unwrap(), data, "len {len}");
        w.download(0x2000, 0, &data).unwrap();
        assert_eq!(w.upload(0x2000, 0).unwrap(), data, "len {len}");
    }
}

#[test]
fn corrupted_block_download_is_refused_and_object_unchanged() {
    let mut w = Wire::new(test_od(LEN), ServerConfig::default());
    let data = pattern(100, 9);
    let i = 0x2000u16.to_le_bytes();
    w.send([0xC6, i[0], i[1], 0, 100, 0, 0, 0]);
    for (k, c) in data.chunks(7).enumerate() {
        let last = k == data.len().div_ceil(7) - 1;
        let mut f = [(k as u8 + 1) | (u8::from(last) << 7), 0, 0, 0, 0, 0, 0, 0];
        f[1..1 + c.len()].copy_from_slice(c);
        if k == 3 {
            f[2] ^= 0x40; // a bit flipped on the way
        }
        w.send(f);
    }
    let crc = drivebus_sdo::crc::crc16(&data).to_le_bytes();
    let r = w.send([0xC1 | (5 << 2), crc[0], crc[1], 0, 0, 0, 0, 0]);
    assert_eq!(abort_code(r[0]), SdoAbort::CRC_ERROR);
    assert_eq!(w.od.get(0x2000, 0).unwrap().bytes(), &pattern(LEN, 1)[..]);
}

#[test]
fn pst_switches_small_objects_to_segmented() {
    let mut w = Wire::new(test_od(LEN), ServerConfig::default());
    let i = 0x2001u16.to_le_bytes();
    let r = w.send([0xA4, i[0], i[1], 0, 127, 21, 0, 0]);
    assert_eq!(r[0][0], 0x41);
    assert_eq!(w.finish_upload(r[0]).unwrap(), b"hello");
    // Above the threshold: a real block upload.
    w.od.set_value(0x2001, 0, &Value::Str("x".repeat(22))).unwrap();
    assert_eq!(w.send([0xA4, i[0], i[1], 0, 127, 21, 0, 0])[0][0], 0xC6);
}

#[test]
fn record_members_and_aborts_through_the_client() {
    let mut w = Wire::new(test_od(LEN), ServerConfig::default());
    assert_eq!(w.upload(0x2010, 2).unwrap(), (-2i64).to_le_bytes());
    w.download(0x2010, 2, &5i64.to_le_bytes()).unwrap();
    assert_eq!(w.od.get_i64(0x2010, 2), Some(5));
    assert_eq!(abort_code(w.upload(0x2010, 3).unwrap_err()), SdoAbort::NO_SUB_INDEX);
    assert_eq!(abort_code(w.download(0x2010, 2, &[1; 9]).unwrap_err()), SdoAbort::DATA_TOO_LONG);
    assert_eq!(abort_code(w.download(0x1000, 0, &[1; 4]).unwrap_err()), SdoAbort::WRITE_READ_ONLY);
    assert_eq!(abort_code(w.block_upload(0x3000, 0, 127, true, &[]).unwrap_err()), SdoAbort::NO_OBJECT);
    assert_eq!(
        abort_code(w.block_download(0x1000, 0, &[0; 10], true, &[]).unwrap_err()),
        SdoAbort::WRITE_READ_ONLY
    );
}

#[test]
fn large_domain_needs_a_larger_max_download() {
    let big = 2 * 1024 * 1024;
    let mut w = Wire::new(test_od(16), ServerConfig::default());
    let s = (big as u32).to_le_bytes();
    let r = w.send([0xC6, 0x00, 0x20, 0, s[0], s[1], s[2], s[3]]);
    assert_eq!(abort_code(r[0]), SdoAbort::OUT_OF_MEMORY);
    let mut w = Wire::new(test_od(16), ServerConfig { max_download: 4 << 20, ..ServerConfig::default() });
    let data = pattern(big, 11);
    w.block_download(0x2000, 0, &data, true, &[]).unwrap();
    assert_eq!(w.od.get(0x2000, 0).unwrap().bytes().len(), big);
}
