//! Frame-exact tests of the expedited and segmented client protocols
//! (CiA 301 §7.2.4.3.3..10) and of every violation the client detects there.

mod client_util;

use client_util::*;
use drivebus_can::{CanId, Frame, Instant};
use drivebus_od::SdoAbort;
use drivebus_sdo::client::{ClientError, Completed, Protocol, SdoClient, SdoClientConfig};

fn upload_ok(s: &mut Script) -> Vec<u8> {
    match s.c.take_result() {
        Some(Ok(Completed::Upload(d))) => d,
        other => panic!("expected an upload result, got {other:?}"),
    }
}

#[track_caller]
fn download_ok(s: &mut Script) {
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Download)));
    assert!(!s.c.is_busy());
}

#[track_caller]
fn failed(s: &mut Script, e: ClientError) {
    assert_eq!(s.c.take_result(), Some(Err(e)));
    assert!(!s.c.is_busy());
    assert_eq!(s.c.poll(Instant::MAX, &mut s.out), None, "no deadline after the end");
}

// ---- expedited ----

#[test]
fn expedited_upload_each_length() {
    // n = 4 - len in bits 3..2, e = 1, s = 1 (CiA 301 §7.2.4.3.7).
    for (cmd, len) in [("4F", 1), ("4B", 2), ("47", 3), ("43", 4)] {
        let mut s = Script::node();
        s.upload(0x2000, 7, Protocol::Auto);
        s.sent(&["40 00 20 07 00 00 00 00"]);
        s.recv(&format!("{cmd} 00 20 07 11 22 33 44"));
        s.silent();
        assert_eq!(upload_ok(&mut s), [0x11, 0x22, 0x33, 0x44][..len].to_vec());
    }
}

#[test]
fn expedited_upload_without_size_takes_four_bytes() {
    let mut s = Script::node();
    s.upload(0x2000, 0, Protocol::Expedited);
    s.sent(&["40 00 20 00 00 00 00 00"]);
    s.recv("42 00 20 00 01 02 03 04");
    assert_eq!(upload_ok(&mut s), vec![1, 2, 3, 4]);
}

#[test]
fn expedited_download_each_length() {
    for (len, cmd) in [(1, "2F"), (2, "2B"), (3, "27"), (4, "23")] {
        let mut s = Script::node();
        let data = &[0xA1, 0xB2, 0xC3, 0xD4][..len];
        s.download(0x6040, 0, data, Protocol::Auto);
        let mut want = format!("{cmd} 40 60 00");
        for i in 0..4 {
            want += &format!(" {:02X}", data.get(i).copied().unwrap_or(0));
        }
        s.sent(&[&want]);
        assert_eq!(s.c.progress(), Some((0, Some(len))));
        s.recv("60 40 60 00 00 00 00 00");
        s.silent();
        download_ok(&mut s);
    }
}

#[test]
fn expedited_download_rejects_bad_lengths() {
    let mut s = Script::node();
    for data in [&[][..], &[1, 2, 3, 4, 5][..]] {
        let r = s.c.start_download(0x2000, 0, data, Protocol::Expedited, s.now, &mut s.out);
        assert_eq!(r, Err(ClientError::InvalidRequest));
    }
    s.silent();
    assert!(!s.c.is_busy());
}

// ---- segmented download ----

#[test]
fn segmented_download_two_segments() {
    let mut s = Script::node();
    let data: Vec<u8> = (1..=10).collect();
    s.download(0x2001, 2, &data, Protocol::Auto);
    // e = 0, s = 1, size 10 in bytes 4..8 (§7.2.4.3.3).
    s.sent(&["21 01 20 02 0A 00 00 00"]);
    s.recv("60 01 20 02 00 00 00 00");
    // t = 0, n = 0, c = 0.
    s.sent(&["00 01 02 03 04 05 06 07"]);
    assert_eq!(s.c.progress(), Some((0, Some(10))));
    s.recv("20 00 00 00 00 00 00 00");
    // t = 1, n = 4 unused bytes, c = 1.
    s.sent(&["19 08 09 0A 00 00 00 00"]);
    assert_eq!(s.c.progress(), Some((7, Some(10))));
    s.recv("30 00 00 00 00 00 00 00");
    s.silent();
    download_ok(&mut s);
}

#[test]
fn segmented_download_forced_for_small_data_and_exact_multiple() {
    let mut s = Script::node();
    s.download(0x2001, 0, &[9, 8], Protocol::Segmented);
    s.sent(&["21 01 20 00 02 00 00 00"]);
    s.recv("60 01 20 00 00 00 00 00");
    s.sent(&["0B 09 08 00 00 00 00 00"]);
    s.recv("20 00 00 00 00 00 00 00");
    download_ok(&mut s);

    // 14 bytes: two full segments, the second with c = 1 and n = 0.
    let data: Vec<u8> = (0..14).collect();
    s.download(0x2001, 0, &data, Protocol::Segmented);
    s.sent(&["21 01 20 00 0E 00 00 00"]);
    s.recv("60 01 20 00 00 00 00 00");
    s.sent(&["00 00 01 02 03 04 05 06"]);
    s.recv("20 00 00 00 00 00 00 00");
    s.sent(&["11 07 08 09 0A 0B 0C 0D"]);
    s.recv("30 00 00 00 00 00 00 00");
    download_ok(&mut s);
}

#[test]
fn zero_length_segmented_download() {
    let mut s = Script::node();
    s.download(0x2002, 0, &[], Protocol::Auto);
    s.sent(&["21 02 20 00 00 00 00 00"]);
    s.recv("60 02 20 00 00 00 00 00");
    // One empty last segment: n = 7, c = 1.
    s.sent(&["0F 00 00 00 00 00 00 00"]);
    s.recv("20 00 00 00 00 00 00 00");
    download_ok(&mut s);
}

#[test]
fn owned_download_buffer() {
    let mut s = Script::node();
    s.c.start_download_owned(0x2002, 1, vec![1, 2, 3, 4, 5], Protocol::Auto, s.now, &mut s.out).unwrap();
    s.sent(&["21 02 20 01 05 00 00 00"]);
    s.recv("60 02 20 01 00 00 00 00");
    s.sent(&["05 01 02 03 04 05 00 00"]);
    s.recv("20 00 00 00 00 00 00 00");
    download_ok(&mut s);
}

// ---- segmented upload ----

#[test]
fn segmented_upload_with_size() {
    let mut s = Script::node();
    s.upload(0x1008, 0, Protocol::Auto);
    s.sent(&["40 08 10 00 00 00 00 00"]);
    s.recv("41 08 10 00 0A 00 00 00");
    s.sent(&["60 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.progress(), Some((0, Some(10))));
    s.recv("00 41 42 43 44 45 46 47");
    s.sent(&["70 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.progress(), Some((7, Some(10))));
    s.recv("19 48 49 4A 00 00 00 00");
    s.silent();
    assert_eq!(upload_ok(&mut s), b"ABCDEFGHIJ".to_vec());
}

#[test]
fn segmented_upload_without_size() {
    let mut s = Script::node();
    s.upload(0x1008, 0, Protocol::Segmented);
    s.sent(&["40 08 10 00 00 00 00 00"]);
    s.recv("40 08 10 00 00 00 00 00");
    s.sent(&["60 00 00 00 00 00 00 00"]);
    assert_eq!(s.c.progress(), Some((0, None)));
    s.recv("00 31 32 33 34 35 36 37");
    s.sent(&["70 00 00 00 00 00 00 00"]);
    s.recv("1D 38 00 00 00 00 00 00");
    assert_eq!(upload_ok(&mut s), b"12345678".to_vec());
}

#[test]
fn zero_length_segmented_upload() {
    let mut s = Script::node();
    s.upload(0x1008, 0, Protocol::Auto);
    s.sent(&["40 08 10 00 00 00 00 00"]);
    s.recv("41 08 10 00 00 00 00 00");
    s.sent(&["60 00 00 00 00 00 00 00"]);
    s.recv("0F 00 00 00 00 00 00 00");
    s.silent();
    assert_eq!(upload_ok(&mut s), Vec::<u8>::new());
}

// ---- violations ----

#[test]
fn unexpected_command_specifier_aborts_0504_0001() {
    // Initiate download answered with an upload response.
    let mut s = Script::node();
    s.download(0x2000, 1, &[1], Protocol::Auto);
    s.sent(&["2F 00 20 01 01 00 00 00"]);
    s.recv("43 00 20 01 00 00 00 00");
    s.sent(&["80 00 20 01 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));

    // Initiate upload answered with a download response.
    s.upload(0x2000, 1, Protocol::Auto);
    s.sent(&["40 00 20 01 00 00 00 00"]);
    s.recv("60 00 20 01 00 00 00 00");
    s.sent(&["80 00 20 01 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));

    // Download segment answered with an upload segment.
    s.download(0x2000, 1, &[0; 8], Protocol::Auto);
    s.recv("60 00 20 01 00 00 00 00");
    s.out.clear();
    s.recv("00 00 00 00 00 00 00 00");
    s.sent(&["80 00 20 01 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));

    // Upload segment answered with a block response.
    s.upload(0x2000, 1, Protocol::Auto);
    s.recv("41 00 20 01 10 00 00 00");
    s.out.clear();
    s.recv("A1 00 00 00 00 00 00 00");
    s.sent(&["80 00 20 01 01 00 04 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::INVALID_COMMAND));
}

#[test]
fn wrong_toggle_aborts_0503_0000() {
    let mut s = Script::node();
    s.download(0x2000, 0, &[0; 9], Protocol::Auto);
    s.recv("60 00 20 00 00 00 00 00");
    s.sent(&["21 00 20 00 09 00 00 00", "00 00 00 00 00 00 00 00"]);
    s.recv("30 00 00 00 00 00 00 00"); // toggle 1, expected 0
    s.sent(&["80 00 20 00 00 00 03 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::TOGGLE_NOT_ALTERNATED));

    s.upload(0x2000, 0, Protocol::Auto);
    s.recv("41 00 20 00 0E 00 00 00");
    s.sent(&["40 00 20 00 00 00 00 00", "60 00 00 00 00 00 00 00"]);
    s.recv("00 01 02 03 04 05 06 07");
    s.sent(&["70 00 00 00 00 00 00 00"]);
    s.recv("01 01 02 03 04 05 06 07"); // repeats toggle 0
    s.sent(&["80 00 20 00 00 00 03 05"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::TOGGLE_NOT_ALTERNATED));
}

/// Issue 15: an answer naming another object is another client's (a
/// monitor on the same node): not taken, not aborted (that would break the
/// other client's transfer), counted; the transfer takes its own answer.
#[test]
fn another_clients_answers_are_ignored_not_aborted() {
    let mut s = Script::node();
    s.upload(0x6041, 0, Protocol::Auto);
    s.out.clear();
    s.recv("4B 40 60 00 37 02 00 00"); // answer for 6040h
    s.silent();
    assert!(s.c.is_busy());
    assert_eq!(s.c.foreign_answers(), 1);
    assert_eq!(s.c.last_foreign(), Some((0x6040, 0)));
    s.recv("80 00 10 00 00 00 02 06"); // another transfer's abort (1000h)
    s.silent();
    assert_eq!(s.c.foreign_answers(), 2);
    s.recv("4B 41 60 00 37 02 00 00");
    assert_eq!(upload_ok(&mut s), vec![0x37, 0x02]);

    s.download(0x6040, 0, &[6, 0], Protocol::Auto);
    s.out.clear();
    assert_eq!(s.c.foreign_answers(), 0, "counted per transfer");
    s.recv("60 40 60 01 00 00 00 00"); // wrong sub-index
    s.silent();
    s.recv("60 40 60 00 00 00 00 00");
    download_ok(&mut s);

    // In the middle of a segmented upload: another client's initiate answer.
    s.upload(0x1008, 0, Protocol::Auto);
    s.recv("41 08 10 00 0A 00 00 00");
    s.out.clear();
    s.recv("43 41 60 00 37 02 00 00");
    s.silent();
    assert_eq!(s.c.foreign_answers(), 1);
    assert!(s.c.is_busy());
}

#[test]
fn segmented_upload_size_mismatch_aborts_0607_0010() {
    // Fewer bytes than announced.
    let mut s = Script::node();
    s.upload(0x2000, 0, Protocol::Auto);
    s.recv("41 00 20 00 0A 00 00 00");
    s.out.clear();
    s.recv("01 01 02 03 04 05 06 07");
    s.sent(&["80 00 20 00 10 00 07 06"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::TYPE_MISMATCH));

    // More bytes than announced.
    s.upload(0x2000, 0, Protocol::Auto);
    s.recv("41 00 20 00 03 00 00 00");
    s.out.clear();
    s.recv("05 01 02 03 04 05 00 00");
    s.sent(&["80 00 20 00 10 00 07 06"]);
    failed(&mut s, ClientError::ProtocolViolation(SdoAbort::TYPE_MISMATCH));
}

#[test]
fn server_abort_ends_transfer_without_reply() {
    let mut s = Script::node();
    s.download(0x6099, 1, &[0x40, 0x19, 0x01, 0x00], Protocol::Auto);
    s.out.clear();
    s.recv("80 99 60 01 31 00 09 06");
    s.silent();
    failed(&mut s, ClientError::ServerAbort(SdoAbort::VALUE_TOO_HIGH));

    // Mid segmented upload too.
    s.upload(0x2000, 0, Protocol::Auto);
    s.recv("41 00 20 00 14 00 00 00");
    s.recv("00 01 02 03 04 05 06 07");
    s.out.clear();
    s.recv("80 00 20 00 00 00 00 08");
    s.silent();
    failed(&mut s, ClientError::ServerAbort(SdoAbort::GENERAL_ERROR));
}

#[test]
fn upload_larger_than_cap_is_aborted_0504_0005() {
    let mut cfg = SdoClientConfig::for_node(NODE);
    cfg.max_upload = 8;
    let mut s = Script::new(SdoClient::new(cfg));
    s.upload(0x2000, 0, Protocol::Auto);
    s.out.clear();
    s.recv("41 00 20 00 09 00 00 00");
    s.sent(&["80 00 20 00 05 00 04 05"]);
    failed(&mut s, ClientError::LocalAbort(SdoAbort::OUT_OF_MEMORY));

    // Unknown size: the cap applies as data arrives.
    s.upload(0x2000, 0, Protocol::Auto);
    s.recv("40 00 20 00 00 00 00 00");
    s.recv("00 01 02 03 04 05 06 07");
    s.out.clear();
    s.recv("10 01 02 03 04 05 06 07");
    s.sent(&["80 00 20 00 05 00 04 05"]);
    failed(&mut s, ClientError::LocalAbort(SdoAbort::OUT_OF_MEMORY));
}

#[test]
fn busy_and_cancel() {
    let mut s = Script::node();
    s.upload(0x1000, 0, Protocol::Auto);
    s.out.clear();
    let r = s.c.start_upload(0x1001, 0, Protocol::Auto, s.now, &mut s.out);
    assert_eq!(r, Err(ClientError::Busy));
    let r = s.c.start_download(0x1001, 0, &[1], Protocol::Auto, s.now, &mut s.out);
    assert_eq!(r, Err(ClientError::Busy));
    s.silent();
    s.c.abort(SdoAbort::GENERAL_ERROR, &mut s.out);
    s.sent(&["80 00 10 00 00 00 00 08"]);
    failed(&mut s, ClientError::LocalAbort(SdoAbort::GENERAL_ERROR));
    // Idle: abort does nothing.
    s.c.abort(SdoAbort::GENERAL_ERROR, &mut s.out);
    s.silent();
    assert_eq!(s.c.take_result(), None);
}

#[test]
fn foreign_idle_and_remote_frames_are_ignored() {
    let mut s = Script::node();
    // Idle: nothing happens.
    s.recv("4B 41 60 00 40 02 00 00");
    s.silent();
    assert_eq!(s.c.take_result(), None);
    s.upload(0x6041, 0, Protocol::Auto);
    s.out.clear();
    let now = s.now;
    // Another node's response, our request COB-ID, an RTR, an extended id.
    s.c.handle_frame(&fr(RX + 1, "4B 41 60 00 40 02 00 00"), now, &mut s.out);
    s.c.handle_frame(&fr(TX, "4B 41 60 00 40 02 00 00"), now, &mut s.out);
    s.c.handle_frame(&Frame::remote(RX, 8), now, &mut s.out);
    let ext = Frame::try_new(CanId::Extended(u32::from(RX)), &hex("4B 41 60 00 40 02 00 00")).unwrap();
    s.c.handle_frame(&ext, now, &mut s.out);
    s.c.handle_frame(&Frame::new(RX, &[]), now, &mut s.out);
    s.silent();
    assert!(s.c.is_busy());
    s.recv("4B 41 60 00 40 02 00 00");
    assert_eq!(upload_ok(&mut s), vec![0x40, 0x02]);
}

#[test]
fn new_transfer_after_each_outcome() {
    let mut s = Script::node();
    for _ in 0..3 {
        s.upload(0x1000, 0, Protocol::Auto);
        s.recv("43 00 10 00 92 01 02 00");
        assert_eq!(upload_ok(&mut s), vec![0x92, 0x01, 0x02, 0x00]);
    }
    s.out.clear();
    assert_eq!(s.c.progress(), None);
}
