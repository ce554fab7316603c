//! Timeouts and retries with exact deadlines (CiA 301 §7.2.4.3.17: a client
//! that gives up sends abort `0504 0000`).

mod client_util;

use client_util::*;
use drivebus_can::{Duration, Instant};
use drivebus_od::SdoAbort;
use drivebus_sdo::client::{ClientError, Completed, Protocol, SdoClient, SdoClientConfig};

fn with(f: impl FnOnce(&mut SdoClientConfig)) -> Script {
    let mut cfg = SdoClientConfig::for_node(NODE);
    f(&mut cfg);
    Script::new(SdoClient::new(cfg))
}

#[test]
fn default_timeout_is_1000_ms_with_one_retry() {
    let mut s = Script::node();
    assert_eq!(s.c.poll(ms(0), &mut s.out), None, "idle: nothing scheduled");
    s.upload(0x6041, 0, Protocol::Auto);
    s.sent(&["40 41 60 00 00 00 00 00"]);
    assert_eq!(s.c.deadline(), Some(ms(1000)));
    // Early polls do nothing observable.
    assert_eq!(s.c.poll(ms(0), &mut s.out), Some(ms(1000)));
    assert_eq!(s.c.poll(Instant::from_nanos(999_999_999), &mut s.out), Some(ms(1000)));
    s.silent();
    // At the deadline: abort 0504 0000, then the retry re-initiates.
    assert_eq!(s.c.poll(ms(1000), &mut s.out), Some(ms(2000)));
    s.sent(&["80 41 60 00 00 00 04 05", "40 41 60 00 00 00 00 00"]);
    assert!(s.c.is_busy());
    assert_eq!(s.c.take_result(), None);
    // The retry times out too: abort and fail.
    assert_eq!(s.c.poll(ms(1999), &mut s.out), Some(ms(2000)));
    s.silent();
    assert_eq!(s.c.poll(ms(2000), &mut s.out), None);
    s.sent(&["80 41 60 00 00 00 04 05"]);
    assert_eq!(s.c.take_result(), Some(Err(ClientError::Timeout)));
    assert!(!s.c.is_busy());
    assert_eq!(s.c.deadline(), None);
}

#[test]
fn retry_succeeds() {
    let mut s = with(|c| c.timeout = Duration::from_millis(300));
    s.upload(0x6041, 0, Protocol::Auto);
    s.out.clear();
    // Polled late: the deadline counts from the moment of the retry.
    assert_eq!(s.c.poll(ms(450), &mut s.out), Some(ms(750)));
    s.sent(&["80 41 60 00 00 00 04 05", "40 41 60 00 00 00 00 00"]);
    s.now = ms(700);
    s.recv("4B 41 60 00 37 02 00 00");
    assert_eq!(s.c.take_result(), Some(Ok(Completed::Upload(vec![0x37, 0x02]))));
    assert_eq!(s.c.poll(ms(10_000), &mut s.out), None);
    s.silent();
}

#[test]
fn no_retries_fails_at_first_timeout() {
    let mut s = with(|c| {
        c.retries = 0;
        c.timeout = Duration::from_millis(50);
    });
    s.download(0x6040, 0, &[6, 0], Protocol::Auto);
    s.out.clear();
    assert_eq!(s.c.poll(ms(50), &mut s.out), None);
    s.sent(&["80 40 60 00 00 00 04 05"]);
    assert_eq!(s.c.take_result(), Some(Err(ClientError::Timeout)));
}

#[test]
fn several_retries_each_restart_the_transfer() {
    let mut s = with(|c| {
        c.retries = 3;
        c.timeout = Duration::from_millis(100);
    });
    let data: Vec<u8> = (0..10).collect();
    s.download(0x2000, 0, &data, Protocol::Auto);
    s.sent(&["21 00 20 00 0A 00 00 00"]);
    for k in 1..=3u64 {
        // Progress into the transfer, then silence: the retry starts over.
        s.now = ms(100 * (k - 1) + 10);
        s.c.handle_frame(&fr(RX, "60 00 20 00 00 00 00 00"), s.now, &mut s.out);
        s.sent(&["00 00 01 02 03 04 05 06"]);
        let deadline = s.now + Duration::from_millis(100);
        assert_eq!(s.c.poll(Instant::from_nanos(deadline.as_nanos() - 1), &mut s.out), Some(deadline));
        assert_eq!(s.c.poll(deadline, &mut s.out), Some(deadline + Duration::from_millis(100)));
        s.sent(&["80 00 20 00 00 00 04 05", "21 00 20 00 0A 00 00 00"]);
        assert_eq!(s.c.progress(), Some((0, Some(10))));
        s.now = deadline;
    }
    let last = s.c.deadline().unwrap();
    assert_eq!(s.c.poll(last, &mut s.out), None);
    s.sent(&["80 00 20 00 00 00 04 05"]);
    assert_eq!(s.c.take_result(), Some(Err(ClientError::Timeout)));
}

#[test]
fn every_response_restarts_the_timer() {
    let mut s = Script::node();
    s.upload(0x1008, 0, Protocol::Auto);
    s.now = ms(900);
    s.recv("41 08 10 00 0A 00 00 00"); // at 901 ms
    assert_eq!(s.c.poll(ms(1000), &mut s.out), Some(ms(1901)));
    s.now = ms(1800);
    s.recv("00 41 42 43 44 45 46 47");
    assert_eq!(s.c.poll(ms(1901), &mut s.out), Some(ms(2801)));
    // Frames that are not ours do not extend it.
    s.c.handle_frame(&fr(RX + 1, "10 48 49 4A 00 00 00 00"), ms(2800), &mut s.out);
    assert_eq!(s.c.deadline(), Some(ms(2801)));
}

#[test]
fn block_download_timeout_waiting_for_ack_retries_from_initiate() {
    let mut s = with(|c| c.timeout = Duration::from_millis(200));
    let data = [0x55u8; 20];
    s.download(0x2000, 1, &data, Protocol::Block);
    s.recv("A4 00 20 01 7F 00 00 00");
    s.out.clear();
    assert_eq!(s.c.deadline(), Some(ms(201)));
    s.c.poll(ms(201), &mut s.out);
    s.sent(&["80 00 20 01 00 00 04 05", "C6 00 20 01 14 00 00 00"]);
    assert_eq!(s.c.deadline(), Some(ms(401)));
}

#[test]
fn block_upload_timeout_in_sub_block() {
    let mut s = with(|c| {
        c.timeout = Duration::from_millis(300);
        c.retries = 0;
    });
    s.upload(0x2000, 1, Protocol::Block);
    s.recv("C6 00 20 01 40 00 00 00");
    s.recv("01 01 02 03 04 05 06 07");
    s.out.clear();
    // Last frame at 2 ms.
    assert_eq!(s.c.poll(ms(301), &mut s.out), Some(ms(302)));
    assert_eq!(s.c.poll(ms(302), &mut s.out), None);
    s.sent(&["80 00 20 01 00 00 04 05"]);
    assert_eq!(s.c.take_result(), Some(Err(ClientError::Timeout)));
}

#[test]
fn abort_code_of_timeout_is_0504_0000() {
    assert_eq!(SdoAbort::TIMEOUT.0, 0x0504_0000);
}
