//! The mailbox layer (ETG.1000.4 §5.6): error replies, counters, the
//! response queue, ESM gating, emergencies and their ordering, deadlines.

mod support;

use drivebus_base::Duration;
use drivebus_coe::mailbox::{MAX_MAILBOX_SIZE, MIN_MAILBOX_SIZE};
use drivebus_coe::{AlState, MailboxConfig, MailboxServer, MailboxSizeError, NoFiles};
use drivebus_od::NoHooks;
use support::{Dev, Rig, body, ethercrab, header, mbx, test_od};

fn rig() -> Rig<Dev, NoFiles> {
    Rig::new(MailboxConfig::default(), (test_od(), NoHooks), NoFiles)
}

/// The mailbox error reply: type 0, length 4, service 1, detail code.
fn mbx_error(cnt: u8, detail: u8) -> Vec<u8> {
    vec![0x04, 0x00, 0x00, 0x00, 0x00, cnt << 4, 0x01, 0x00, detail, 0x00]
}

#[test]
fn unsupported_protocols() {
    let mut r = rig();
    // EoE (a "get IP parameter" request), AoE, SoE, VoE, a reserved type.
    let requests = [
        mbx(0x02, 1, &[0x06, 0x00, 0x00, 0x00]),
        mbx(0x01, 2, &[0; 32]),
        mbx(0x05, 3, &[0x01, 0x00, 0, 0]),
        mbx(0x0F, 4, &[0; 8]),
        mbx(0x06, 5, &[0; 8]),
    ];
    for (n, req) in requests.iter().enumerate() {
        assert_eq!(r.one(req), mbx_error(n as u8 + 1, 0x02), "type {}", req[5] & 0x0F);
    }
    // FoE on a device without files.
    assert_eq!(r.one(&mbx(0x04, 6, &[2, 0, 0, 0, 0, 0, b'a'])), mbx_error(6, 0x02));
    assert_eq!(r.server.stats().mailbox_errors, 6);
}

#[test]
fn malformed_mailboxes() {
    let mut r = rig();
    // Type 0 comes only from a slave.
    assert_eq!(r.one(&mbx(0x00, 1, &[1, 0, 2, 0])), mbx_error(1, 0x01));
    // Fewer bytes than a header.
    r.server.handle_request(&[0x0a, 0x00, 0x03], r.now, r.state, &mut r.dev, &mut r.files);
    assert_eq!(r.read().unwrap(), mbx_error(2, 0x01));
    // Channel 5.
    let mut m = mbx(0x03, 2, &[0x00, 0x20, 0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
    m[4] = 0x05;
    assert_eq!(r.one(&m), mbx_error(3, 0x03));
    // Length 0.
    assert_eq!(r.one(&header(0, 0x03, 3)), mbx_error(4, 0x06));
    // CoE: too short for an SDO request; no CoE header at all.
    assert_eq!(r.one(&mbx(0x03, 4, &[0x00, 0x20, 0x40, 0x00, 0x10, 0x00])), mbx_error(5, 0x06));
    assert_eq!(r.one(&mbx(0x03, 5, &[0x00])), mbx_error(6, 0x06));
    // CoE services: 0 and 9..15 are no service; 1, 3..7 are not offered.
    assert_eq!(r.one(&mbx(0x03, 6, &[0x00, 0x00, 0, 0, 0, 0, 0, 0, 0, 0])), mbx_error(7, 0x05));
    assert_eq!(r.one(&mbx(0x03, 7, &[0x00, 0x90, 0, 0, 0, 0, 0, 0, 0, 0])), mbx_error(1, 0x05));
    for (n, s) in [0x10u8, 0x30, 0x40, 0x50, 0x60, 0x70].into_iter().enumerate() {
        let c = (n % 7) as u8 + 1;
        let resp = r.one(&mbx(0x03, c, &[0x00, s, 0, 0, 0, 0, 0, 0, 0, 0]));
        assert_eq!(resp[8], 0x04, "service {}", s >> 4);
    }
    // SDO Info header cut short.
    assert_eq!(r.one(&mbx(0x03, 7, &[0x00, 0x80, 0x01, 0x00]))[8], 0x06);
    assert_eq!(r.one(&mbx(0x03, 1, &[0x00, 0x80, 0x05, 0x00, 0, 0, 0x00, 0x10]))[8], 0x06);
    // Every one of them counted, the CoE ones included.
    assert_eq!(r.server.stats().mailbox_errors, 16);
}

#[test]
fn lengths_that_disagree_with_the_buffer() {
    let mut r = rig();
    // The length field says more than was written.
    let mut m = mbx(0x03, 1, &[0x00, 0x20, 0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
    m[0] = 200;
    r.server.handle_request(&m, r.now, r.state, &mut r.dev, &mut r.files);
    assert_eq!(r.read().unwrap()[8], 0x08);
    // A request longer than SM0 (128 bytes).
    let m = mbx(0x03, 2, &[0u8; 130]);
    r.server.handle_request(&m, r.now, r.state, &mut r.dev, &mut r.files);
    assert_eq!(r.read().unwrap()[8], 0x08);
    // A length that fits SM0 but not the slice handed in.
    let m = [0x0a, 0x00, 0x00, 0x00, 0x00, 0x33, 0x00, 0x20, 0x40];
    r.server.handle_request(&m, r.now, r.state, &mut r.dev, &mut r.files);
    assert_eq!(r.read().unwrap()[8], 0x08);
}

#[test]
fn repeated_counter_is_not_executed_again() {
    let mut r = rig();
    let req = ethercrab::download(3, 0x2003, Some(0), &[9, 0]);
    assert_eq!(body(&r.one(&req))[2], 0x60);
    // The master repeats the write with the same counter: dropped.
    r.send(&req);
    assert_eq!(r.read(), None);
    assert_eq!(r.server.stats().repeated, 1);
    // It gets the answer again through the SM1 repeat.
    assert_eq!(body(r.server.last_response().unwrap())[2], 0x60);
    // Counter 0 is never a repetition.
    let req0 = ethercrab::upload(0, 0x1000, Some(0));
    assert_eq!(body(&r.one(&req0))[2], 0x43);
    assert_eq!(body(&r.one(&req0))[2], 0x43);
    // After a mailbox reset the same counter is new again.
    assert_eq!(body(&r.one(&ethercrab::upload(5, 0x1000, Some(0))))[2], 0x43);
    r.server.reset(&mut r.files);
    assert_eq!(body(&r.one(&ethercrab::upload(5, 0x1000, Some(0))))[2], 0x43);
}

#[test]
fn response_counter_runs_1_to_7_and_restarts_at_reset() {
    let mut r = rig();
    let mut seen = Vec::new();
    for _ in 0..9 {
        let c = r.counter();
        seen.push(r.one(&ethercrab::upload(c, 0x1000, Some(0)))[5] >> 4);
    }
    assert_eq!(seen, [1, 2, 3, 4, 5, 6, 7, 1, 2]);
    r.server.reset(&mut r.files);
    assert_eq!(r.server.last_response(), None);
    assert_eq!(r.one(&ethercrab::upload(1, 0x1000, Some(0)))[5] >> 4, 1);
}

#[test]
fn full_queue_refuses_with_no_more_memory() {
    // Two slots: one response, then one "no more memory", then silence.
    let cfg = MailboxConfig { response_slots: 2, ..MailboxConfig::default() };
    let mut r = Rig::new(cfg, (test_od(), NoHooks), NoFiles);
    r.send(&ethercrab::upload(1, 0x1000, Some(0)));
    r.send(&ethercrab::download(2, 0x2003, Some(0), &[42, 0]));
    r.send(&ethercrab::download(3, 0x2003, Some(0), &[43, 0]));
    assert_eq!(body(&r.read().unwrap())[2], 0x43);
    assert_eq!(r.read().unwrap(), mbx_error(2, 0x07));
    assert_eq!(r.read(), None);
    // The refused writes were not executed.
    assert_eq!(r.dev.0.get_i64(0x2003, 0), Some(5));
    assert_eq!(r.server.stats().refused, 2);
}

#[test]
fn esm_state_gates_the_mailbox() {
    let mut r = rig();
    r.state = AlState::Init;
    r.send(&ethercrab::upload(1, 0x1000, Some(0)));
    assert_eq!(r.read(), None);
    assert_eq!(r.server.stats().ignored, 1);
    // BOOT: FoE only, emergencies wait.
    r.state = AlState::Boot;
    r.server.queue_emergency(0x5000, 0, [0; 5]).unwrap();
    assert_eq!(r.one(&ethercrab::upload(2, 0x1000, Some(0))), mbx_error(1, 0x02));
    assert_eq!(r.read(), None);
    for s in [AlState::PreOp, AlState::SafeOp, AlState::Op] {
        r.state = s;
        let c = r.counter();
        assert_eq!(body(&r.one(&ethercrab::upload(c, 0x1000, Some(0))))[2], 0x43);
    }
    assert_eq!(body(&r.read().unwrap())[..4], [0x00, 0x10, 0x00, 0x50]);
}

#[test]
fn sdo_info_can_be_switched_off() {
    let cfg = MailboxConfig { sdo_info: false, ..MailboxConfig::default() };
    let mut r = Rig::new(cfg, (test_od(), NoHooks), NoFiles);
    assert_eq!(r.one(&ethercrab::od_list(1, 1)), mbx_error(1, 0x04));
}

#[test]
fn emergencies_wait_for_multi_mailbox_transfers() {
    let mut r = rig();
    // A segmented upload (300 bytes through 128).
    r.send(&ethercrab::upload(1, 0x2000, Some(0)));
    r.server.queue_emergency(0x8210, 0x01, [0; 5]).unwrap();
    assert_eq!(body(&r.read().unwrap())[2], 0x41);
    // Between segments SM1 stays empty: the emergency is held.
    assert!(!r.server.has_response());
    assert_eq!(r.read(), None);
    r.send(&ethercrab::upload_segment(2, false));
    assert_eq!(body(&r.read().unwrap())[2], 0x00);
    assert_eq!(r.read(), None);
    r.send(&ethercrab::upload_segment(3, true));
    let last = r.read().unwrap();
    assert_eq!(body(&last)[2] & 0x01, 0x01, "last segment");
    // Transfer over: out it comes.
    assert!(r.server.has_response());
    assert_eq!(body(&r.read().unwrap())[..4], [0x00, 0x10, 0x10, 0x82]);
    // A transfer the master abandons releases it at the timeout.
    r.send(&ethercrab::upload(4, 0x2000, Some(0)));
    r.server.queue_emergency(0x4210, 0x08, [1, 0, 0, 0, 0]).unwrap();
    assert_eq!(body(&r.read().unwrap())[2], 0x41);
    assert_eq!(r.read(), None);
    r.tick(Duration::from_secs(2));
    assert_eq!(body(&r.read().unwrap())[..4], [0x00, 0x10, 0x10, 0x42]);
    assert_eq!(r.server.stats().emergencies_sent, 2);
}

#[test]
fn emergency_queue_bounds() {
    let cfg = MailboxConfig { emergency_slots: 2, ..MailboxConfig::default() };
    let mut r = Rig::new(cfg, (test_od(), NoHooks), NoFiles);
    r.server.queue_emergency(1, 0, [0; 5]).unwrap();
    r.server.queue_emergency(2, 0, [0; 5]).unwrap();
    assert!(r.server.queue_emergency(3, 0, [0; 5]).is_err());
    assert_eq!(r.server.pending_emergencies(), 2);
    // Oldest first, each with the next counter; the third was refused.
    let a = r.read().unwrap();
    let b = r.read().unwrap();
    assert_eq!((a[8], a[5] >> 4, b[8], b[5] >> 4), (1, 1, 2, 2));
    assert_eq!(r.read(), None);
    assert_eq!(r.server.stats().emergencies_dropped, 1);
    // Emergencies off.
    let cfg = MailboxConfig { emergency_slots: 0, ..MailboxConfig::default() };
    let mut s = MailboxServer::new(cfg).unwrap();
    assert!(s.queue_emergency(1, 0, [0; 5]).is_err());
    assert!(s.is_idle());
}

#[test]
fn poll_reports_deadlines() {
    let mut r = rig();
    assert_eq!(r.server.poll(r.now, &mut r.files), None);
    r.send(&ethercrab::upload(1, 0x2000, Some(0)));
    let sent = r.now;
    r.read();
    assert_eq!(r.server.poll(r.now, &mut r.files), Some(sent + Duration::from_secs(2)));
    // Polling early changes nothing.
    assert_eq!(r.server.poll(r.now, &mut r.files), Some(sent + Duration::from_secs(2)));
    assert_eq!(r.server.poll(sent + Duration::from_secs(2), &mut r.files), None);
    assert!(r.server.is_idle());
}

#[test]
fn mailbox_sizes_are_checked() {
    for bad in [0, MIN_MAILBOX_SIZE - 1, MAX_MAILBOX_SIZE + 1] {
        assert_eq!(
            MailboxServer::new(MailboxConfig::with_sizes(bad, 128)).err(),
            Some(MailboxSizeError { size: bad })
        );
        assert_eq!(
            MailboxServer::new(MailboxConfig::with_sizes(128, bad)).err(),
            Some(MailboxSizeError { size: bad })
        );
    }
    let mut r = rig();
    assert!(r.server.set_mailbox_sizes(16, 16, &mut r.files).is_err());
    // The bootstrap mailbox may differ; responses follow the new SM1.
    r.server.set_mailbox_sizes(MIN_MAILBOX_SIZE, MIN_MAILBOX_SIZE, &mut r.files).unwrap();
    let resp = r.one(&ethercrab::upload(1, 0x1008, Some(0)));
    assert_eq!(resp.len(), MIN_MAILBOX_SIZE);
    assert_eq!(body(&resp)[2], 0x41);
}
