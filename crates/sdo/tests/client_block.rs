//! Frame-exact tests of block download and block upload (CiA 301
//! §7.2.4.3.11..16) from the client side, including the public CRC vectors.

mod client_util;

use client_util::*;
use drivebus_can::Instant;
use drivebus_od::SdoAbort;
use drivebus_sdo::client::{ClientError, Completed, Protocol, SdoClient, SdoClientConfig};

fn with(f: impl FnOnce(&mut SdoClientConfig)) -> Script {
    let mut cfg = SdoClientConfig::for_node(NODE);
    f(&mut cfg);
    Script::new(SdoClient::new(cfg))
}

#[track_caller]
fn failed(s: &mut Script, e: ClientError) {
    assert_eq!(s.c.take_result(), Some(Err(e)));
    assert!(!s.c.is_busy());
    assert_eq!(s.c.poll(Instant::MAX, &mut s.out), None);
}

/// Segment frame `seqno` (| 80h if last) carrying `chunk` zero-padded.
fn seg(seqno: u8, last: bool, chunk: &[u8]) -> String {
    let mut v = vec![seqno | if last { 0x80 } else { 0 }];
    v.extend_from_slice(chunk);
    v.resize(8, 0);
    v.iter().map(|b| format!("{b:02X}")).collect::<Vec<_>>().join(" ")
}

fn segs(data: &[u8], first: usize, count: usize) -> Vec<String> {
    let total = data.len().div_ceil(7).max(1);
    (0..count)
        .map(|i| {
            let k = first + i;
            let chunk = &data[(k * 7).min(data.len())..((k + 1) * 7).min(data.len())];
            seg(i as u8 + 1, k + 1 == total, chunk)
        })
        .collect()
}

fn refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

// ---- public vectors ----

/// canopen-python's block download test data: 30 bytes, CRC 0x6945, end
/// frame `D5 45 69 ..` (n = 5 unused bytes in the fifth segment).
#[test]
fn block_download_public_vector() {
    let data = b"A really really long string...";
    assert_eq!(data.len(), 30);
    let mut s = Script::node();
    s.download(0x2000, 0, data, Protocol::Block);
    // ccs = 6, cc = 1 (CRC), s = 1, size 30.
    s.sent(&["C6 00 20 00 1E 00 00 00"]);
    s.recv("A4 00 20 00 7F 00 00 00");
    s.sent(&[
        "01 41 20 72 65 61 6C 6C",
        "02 79 20 72 65 61 6C 6C",
        "03 79 20 6C 6F 6E 67 20",
        "04 73 74 72 69 6E 67 2E",
        "85 2E 2E 00 00 00 00 00",
    ]);
    assert_eq!(s.c.progress(), Some((0, Some(30))));
    s.recv("A2 05 7F 00 00 00 00 00");
    s.sent(&["D5 45 69 00 00 00 00 00"]);
    assert_eq!(s.c.progress(), Some((30, Some(30))));
    s.recv("A1 00 00 00 00 00 00 00");
    s.silent();
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Download)));
}

/// canopen-python's block upload test data: 26 bytes, CRC 0xE140, server end
/// frame `C9 40 E1 ..` (n = 2).
#[test]
fn block_upload_public_vector() {
    let data = b"Tiny Node - Mega Domains !";
    assert_eq!(data.len(), 26);
    let mut s = Script::node();
    s.upload(0x2000, 0, Protocol::Block);
    // ccs = 5, cc = 1, blksize 127, pst 0.
    s.sent(&["A4 00 20 00 7F 00 00 00"]);
    s.recv("C6 00 20 00 1A 00 00 00");
    s.sent(&["A3 00 00 00 00 00 00 00"]);
    for f in segs(data, 0, 4) {
        s.recv(&f);
    }
    s.sent(&["A2 04 7F 00 00 00 00 00"]);
    s.recv("C9 40 E1 00 00 00 00 00");
    s.sent(&["A1 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(data.to_vec()))));
}

// ---- block download ----

#[test]
fn block_download_several_sub_blocks_and_adapted_blksize() {
    let data: Vec<u8> = (0..50).collect(); // 8 segments, last has 1 byte (n = 6)
    let mut s = Script::node();
    s.download(0x2100, 3, &data, Protocol::Block);
    s.sent(&["C6 00 21 03 32 00 00 00"]);
    s.recv("A4 00 21 03 03 00 00 00");
    s.sent(&refs(&segs(&data, 0, 3)));
    // Server now wants 2 per sub-block.
    s.recv("A2 03 02 00 00 00 00 00");
    s.sent(&refs(&segs(&data, 3, 2)));
    assert_eq!(s.c.progress(), Some((21, Some(50))));
    s.recv("A2 02 7F 00 00 00 00 00");
    s.sent(&refs(&segs(&data, 5, 3)));
    s.recv("A2 03 7F 00 00 00 00 00");
    let crc = drivebus_sdo::crc::crc16(&data).to_le_bytes();
    s.sent(&[&format!("D9 {:02X} {:02X} 00 00 00 00 00", crc[0], crc[1])]);
    s.recv("A1 00 00 00 00 00 00 00");
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Download)));
}

#[test]
fn block_download_partial_ack_resends_from_ackseq_plus_one() {
    let data: Vec<u8> = (100..135).collect(); // 5 segments
    let mut s = Script::node();
    s.download(0x2100, 0, &data, Protocol::Block);
    s.out.clear();
    s.recv("A4 00 21 00 7F 00 00 00");
    s.sent(&refs(&segs(&data, 0, 5)));
    // Segment 3 was lost: the server acks 2; the client resends 3..5 as 1..3.
    s.recv("A2 02 7F 00 00 00 00 00");
    s.sent(&refs(&segs(&data, 2, 3)));
    // Nothing arrived this time: ack 0 resends all three again.
    s.recv("A2 00 7F 00 00 00 00 00");
    s.sent(&refs(&segs(&data, 2, 3)));
    s.recv("A2 03 7F 00 00 00 00 00");
    s.out.clear();
    s.recv("A1 00 00 00 00 00 00 00");
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Download)));
}

#[test]
fn block_download_without_crc_and_zero_length() {
    let mut s = with(|c| c.crc = false);
    s.download(0x2100, 0, &[], Protocol::Block);
    // cc = 0, s = 1, size 0.
    s.sent(&["C2 00 21 00 00 00 00 00"]);
    // The server supports CRC, but the client did not offer it.
    s.recv("A4 00 21 00 10 00 00 00");
    s.sent(&["81 00 00 00 00 00 00 00"]);
    s.recv("A2 01 10 00 00 00 00 00");
    // n = 7, CRC field 0.
    s.sent(&["DD 00 00 00 00 00 00 00"]);
    s.recv("A1 00 00 00 00 00 00 00");
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Download)));

    // Server without CRC support (sc = 0): the CRC field stays 0.
    let mut s = Script::node();
    s.download(0x2100, 0, &[1, 2, 3], Protocol::Block);
    s.sent(&["C6 00 21 00 03 00 00 00"]);
    s.recv("A0 00 21 00 7F 00 00 00");
    s.sent(&["81 01 02 03 00 00 00 00"]);
    s.recv("A2 01 7F 00 00 00 00 00");
    s.sent(&["D1 00 00 00 00 00 00 00"]);
    s.recv("A1 00 00 00 00 00 00 00");
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Download)));
}

#[test]
fn auto_uses_block_at_threshold() {
    let mut s = with(|c| c.block_threshold = Some(8));
    s.download(0x2100, 0, &[0; 7], Protocol::Auto);
    s.sent(&["21 00 21 00 07 00 00 00"]);
    s.c.abort(SdoAbort::GENERAL_ERROR, &mut s.out);
    s.out.clear();
    s.c.take_result();
    s.download(0x2100, 0, &[0; 8], Protocol::Auto);
    s.sent(&["C6 00 21 00 08 00 00 00"]);
}

#[test]
fn block_download_violations() {
    let data = [7u8; 20];
    // blksize 0 and 128 in the initiate response.
    for bad in ["00", "80"] {
        let mut s = Script::node();
        s.download(0x2100, 1, &data, Protocol::Block);
        s.out.clear();
        s.recv(&format!("A4 00 21 01 {bad} 00 00 00"));
        s.sent(&["80 00 21 01 02 00 04 05"]);
        failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_BLOCK_SIZE));
    }
    // blksize 0 in an ack.
    let mut s = Script::node();
    s.download(0x2100, 1, &data, Protocol::Block);
    s.recv("A4 00 21 01 7F 00 00 00");
    s.out.clear();
    s.recv("A2 03 00 00 00 00 00 00");
    s.sent(&["80 00 21 01 02 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_BLOCK_SIZE));
    // ackseq beyond what was sent.
    s.download(0x2100, 1, &data, Protocol::Block);
    s.recv("A4 00 21 01 7F 00 00 00");
    s.out.clear();
    s.recv("A2 04 7F 00 00 00 00 00");
    s.sent(&["80 00 21 01 03 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_SEQUENCE));
    // Wrong command specifier for the initiate, the ack and the end.
    s.download(0x2100, 1, &data, Protocol::Block);
    s.out.clear();
    s.recv("60 00 21 01 00 00 00 00");
    s.sent(&["80 00 21 01 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));
    s.download(0x2100, 1, &data, Protocol::Block);
    s.recv("A4 00 21 01 7F 00 00 00");
    s.out.clear();
    s.recv("A1 00 00 00 00 00 00 00");
    s.sent(&["80 00 21 01 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));
    s.download(0x2100, 1, &data, Protocol::Block);
    s.recv("A4 00 21 01 7F 00 00 00");
    s.recv("A2 03 7F 00 00 00 00 00");
    s.out.clear();
    s.recv("A2 03 7F 00 00 00 00 00");
    s.sent(&["80 00 21 01 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));
    // Multiplexer mismatch: another client's answer, ignored.
    s.download(0x2100, 1, &data, Protocol::Block);
    s.out.clear();
    s.recv("A4 00 21 02 7F 00 00 00");
    s.silent();
    assert_eq!(s.c.foreign_answers(), 1);
    s.c.abort(SdoAbort::GENERAL_ERROR, &mut s.out);
    s.out.clear();
    // Server abort in the middle.
    s.download(0x2100, 1, &data, Protocol::Block);
    s.recv("A4 00 21 01 7F 00 00 00");
    s.out.clear();
    s.recv("80 00 21 01 04 00 04 05");
    s.silent();
    failed(&mut s, ClientError::ServerAbort(SdoAbort::CRC_ERROR));
}

// ---- block upload ----

#[test]
fn block_upload_missing_segment_is_acked_partially() {
    let data: Vec<u8> = (0..40).collect(); // 6 segments, last has 5 bytes (n = 2)
    let mut s = with(|c| c.block_size = 4);
    s.upload(0x2200, 0, Protocol::Block);
    s.sent(&["A4 00 22 00 04 00 00 00"]);
    s.recv("C6 00 22 00 28 00 00 00");
    s.sent(&["A3 00 00 00 00 00 00 00"]);
    let all = segs(&data, 0, 6);
    // Sub-block 1: seqno 1, 2, (3 lost), 4: ack 2.
    s.recv(&all[0]);
    s.recv(&all[1]);
    s.recv(&seg(4, false, &data[21..28]));
    s.sent(&["A2 02 04 00 00 00 00 00"]);
    assert_eq!(s.c.progress(), Some((14, Some(40))));
    // The server resends from segment 3 as seqno 1..4.
    for f in segs(&data, 2, 4) {
        s.recv(&f);
    }
    s.sent(&["A2 04 04 00 00 00 00 00"]);
    let crc = drivebus_sdo::crc::crc16(&data).to_le_bytes();
    s.recv(&format!("C9 {:02X} {:02X} 00 00 00 00 00", crc[0], crc[1]));
    s.sent(&["A1 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(data))));
}

#[test]
fn block_upload_lost_segment_before_last_and_first_lost() {
    let data: Vec<u8> = (0..20).collect(); // 3 segments
    let mut s = Script::node();
    s.upload(0x2200, 0, Protocol::Block);
    s.recv("C6 00 22 00 14 00 00 00");
    s.out.clear();
    // Segment 1 lost; the last (c = 1) arrives out of sequence: ack 0.
    let all = segs(&data, 0, 3);
    s.recv(&all[1]);
    s.silent();
    s.recv(&all[2]);
    s.sent(&["A2 00 7F 00 00 00 00 00"]);
    for f in &all {
        s.recv(f);
    }
    s.sent(&["A2 03 7F 00 00 00 00 00"]);
    let crc = drivebus_sdo::crc::crc16(&data).to_le_bytes();
    s.recv(&format!("C5 {:02X} {:02X} 00 00 00 00 00", crc[0], crc[1]));
    s.sent(&["A1 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(data))));
}

#[test]
fn block_upload_without_size_and_without_crc() {
    let mut s = with(|c| c.crc = false);
    s.upload(0x2200, 0, Protocol::Block);
    s.sent(&["A0 00 22 00 7F 00 00 00"]);
    // sc = 1 but the client did not offer CRC: the CRC field is ignored.
    s.recv("C4 00 22 00 00 00 00 00");
    s.sent(&["A3 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.progress(), Some((0, None)));
    s.recv("81 0A 0B 00 00 00 00 00");
    s.sent(&["A2 01 7F 00 00 00 00 00"]);
    s.recv("D5 FF FF 00 00 00 00 00");
    s.sent(&["A1 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(vec![0x0A, 0x0B]))));
}

#[test]
fn block_upload_zero_length() {
    let mut s = Script::node();
    s.upload(0x2200, 0, Protocol::Block);
    s.recv("C6 00 22 00 00 00 00 00");
    s.out.clear();
    s.recv("81 00 00 00 00 00 00 00");
    s.sent(&["A2 01 7F 00 00 00 00 00"]);
    s.recv("DD 00 00 00 00 00 00 00");
    s.sent(&["A1 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(vec![]))));
}

#[test]
fn block_upload_protocol_switch() {
    // Expedited fallback.
    let mut s = with(|c| c.pst = 4);
    s.upload(0x1000, 0, Protocol::Block);
    s.sent(&["A4 00 10 00 7F 04 00 00"]);
    s.recv("43 00 10 00 92 01 02 00");
    s.silent();
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(vec![0x92, 0x01, 0x02, 0x00]))));
    // Segmented fallback.
    s.upload(0x1008, 0, Protocol::Block);
    s.out.clear();
    s.recv("41 08 10 00 03 00 00 00");
    s.sent(&["60 00 00 00 00 00 00 00"]);
    s.recv("09 4B 43 31 00 00 00 00");
    s.silent();
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(b"KC1".to_vec()))));
    // Without pst the switch is a protocol violation.
    let mut s = Script::node();
    s.upload(0x1000, 0, Protocol::Block);
    s.out.clear();
    s.recv("43 00 10 00 92 01 02 00");
    s.sent(&["80 00 10 00 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));
}

#[test]
fn block_upload_invalid_seqno_aborts_0504_0003() {
    for bad in [0x00u8, 0x05, 0x7F, 0xFF] {
        let mut s = with(|c| c.block_size = 4);
        s.upload(0x2200, 0, Protocol::Block);
        s.recv("C6 00 22 00 40 00 00 00");
        s.out.clear();
        s.recv(&seg(1, false, &[1; 7]));
        s.recv(&format!("{bad:02X} 00 00 00 00 00 00 00"));
        s.sent(&["80 00 22 00 03 00 04 05"]);
        failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_SEQUENCE));
    }
}

#[test]
fn block_upload_80h_is_the_server_abort() {
    let mut s = Script::node();
    s.upload(0x2200, 0, Protocol::Block);
    s.recv("C6 00 22 00 40 00 00 00");
    s.out.clear();
    s.recv("80 00 22 00 00 00 02 06");
    s.silent();
    failed(&mut s, ClientError::ServerAbort(SdoAbort::NO_OBJECT));
}

#[test]
fn block_upload_crc_mismatch_aborts_0504_0004() {
    let data = b"Tiny Node - Mega Domains !";
    let mut s = Script::node();
    s.upload(0x2000, 0, Protocol::Block);
    s.recv("C6 00 20 00 1A 00 00 00");
    for f in segs(data, 0, 4) {
        s.recv(&f);
    }
    s.out.clear();
    s.recv("C9 41 E1 00 00 00 00 00");
    s.sent(&["80 00 20 00 04 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::CRC_ERROR));
}

#[test]
fn block_upload_size_mismatch_aborts_0607_0010() {
    let data = b"Tiny Node - Mega Domains !";
    // End says n = 3 (25 bytes) but 26 were announced.
    let mut s = Script::node();
    s.upload(0x2000, 0, Protocol::Block);
    s.recv("C6 00 20 00 1A 00 00 00");
    for f in segs(data, 0, 4) {
        s.recv(&f);
    }
    s.out.clear();
    s.recv("CD 40 E1 00 00 00 00 00");
    s.sent(&["80 00 20 00 10 00 07 06"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::TYPE_MISMATCH));
    // More segments than 10 announced bytes need.
    s.upload(0x2000, 0, Protocol::Block);
    s.recv("C6 00 20 00 0A 00 00 00");
    s.recv(&seg(1, false, &[1; 7]));
    s.recv(&seg(2, false, &[1; 7]));
    s.out.clear();
    s.recv(&seg(3, true, &[1; 7]));
    s.sent(&["80 00 20 00 10 00 07 06"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::TYPE_MISMATCH));
}

#[test]
fn block_upload_violations() {
    // Wrong command specifier for the initiate and the end.
    let mut s = Script::node();
    s.upload(0x2000, 0, Protocol::Block);
    s.out.clear();
    s.recv("A4 00 20 00 7F 00 00 00");
    s.sent(&["80 00 20 00 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));
    s.upload(0x2000, 0, Protocol::Block);
    s.recv("C6 00 20 00 03 00 00 00");
    s.recv(&seg(1, true, &[1, 2, 3]));
    s.out.clear();
    s.recv("81 00 00 00 00 00 00 00");
    s.sent(&["80 00 20 00 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));
    // Multiplexer mismatch: another client's answer, ignored.
    s.upload(0x2000, 0, Protocol::Block);
    s.out.clear();
    s.recv("C6 01 20 00 03 00 00 00");
    s.silent();
    assert_eq!(s.c.foreign_answers(), 1);
}

#[test]
fn block_upload_larger_than_cap() {
    let mut s = with(|c| c.max_upload = 10);
    s.upload(0x2000, 0, Protocol::Block);
    s.out.clear();
    s.recv("C6 00 20 00 0B 00 00 00");
    s.sent(&["80 00 20 00 05 00 04 05"]);
    failed(&mut s, ClientError::LocalAbort(SdoAbort::OUT_OF_MEMORY));
    // Unknown size: two full segments exceed 10 + 7.
    s.upload(0x2000, 0, Protocol::Block);
    s.recv("C4 00 20 00 00 00 00 00");
    s.recv(&seg(1, false, &[1; 7]));
    s.recv(&seg(2, false, &[1; 7]));
    s.out.clear();
    s.recv(&seg(3, false, &[1; 7]));
    s.sent(&["80 00 20 00 05 00 04 05"]);
    failed(&mut s, ClientError::LocalAbort(SdoAbort::OUT_OF_MEMORY));
}

#[test]
fn block_upload_blksize_one() {
    let data: Vec<u8> = (0..15).collect();
    let mut s = with(|c| c.block_size = 0); // clamped to 1
    s.upload(0x2000, 0, Protocol::Block);
    s.sent(&["A4 00 20 00 01 00 00 00"]);
    s.recv("C6 00 20 00 0F 00 00 00");
    s.sent(&["A3 00 00 00 00 00 00 00"]);
    for (i, f) in segs(&data, 0, 3).iter().enumerate() {
        // Every sub-block is one segment with seqno 1.
        let f = format!("{:02X}{}", u8::from_str_radix(&f[..2], 16).unwrap() - i as u8, &f[2..]);
        s.recv(&f);
        s.sent(&["A2 01 01 00 00 00 00 00"]);
    }
    let crc = drivebus_sdo::crc::crc16(&data).to_le_bytes();
    s.recv(&format!("D9 {:02X} {:02X} 00 00 00 00 00", crc[0], crc[1]));
    s.sent(&["A1 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(data))));
}
