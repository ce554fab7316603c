//! Heartbeat producer (1017h) and consumer (1016h), CiA 301 §7.2.8.3.2.2.

mod common;

use common::{Dev, NODE, ms};
use drivebus_can::Frame;
use drivebus_nmt::{ConsumerEntry, NmtConfig, NmtEvent, RemoteState};
use drivebus_od::SdoAbort;

fn hb(state: u8) -> Frame {
    Frame::new(0x705, &[state])
}

fn entry(node: u8, time_ms: u16) -> [u8; 4] {
    ConsumerEntry { node, time_ms }.raw().to_le_bytes()
}

#[test]
fn producer_off_by_default() {
    let mut d = Dev::booted();
    assert_eq!(d.poll(ms(10_000)), None);
    assert!(d.take().is_empty());
}

#[test]
fn first_heartbeat_one_period_after_boot_up() {
    let mut d = Dev::new(NmtConfig::new(NODE), 0, 0);
    d.od.set_value(0x1017, 0, &drivebus_od::Value::U16(100)).unwrap();
    d.boot(ms(3));
    assert_eq!(d.take(), [Frame::new(0x705, &[0x00])]);
    assert_eq!(d.poll(ms(3)), Some(ms(103)));
    assert_eq!(d.poll(ms(102)), Some(ms(103)), "an early poll does nothing");
    assert!(d.take().is_empty());
    assert_eq!(d.run(103, 350), [(103, hb(0x7F)), (203, hb(0x7F)), (303, hb(0x7F))]);
}

#[test]
fn heartbeat_carries_the_state() {
    let mut d = Dev::booted();
    d.write(0x1017, 0, &50u16.to_le_bytes(), ms(0)).unwrap();
    let mut got = d.run(1, 59);
    d.cmd(0x01, NODE, ms(60));
    got.extend(d.run(60, 100));
    d.cmd(0x02, 0, ms(120));
    got.extend(d.run(101, 150));
    d.cmd(0x80, NODE, ms(160));
    got.extend(d.run(151, 200));
    assert_eq!(got, [(50, hb(0x7F)), (100, hb(0x05)), (150, hb(0x04)), (200, hb(0x7F))]);
}

#[test]
fn writing_1017h_restarts_the_timer() {
    let mut d = Dev::booted();
    d.write(0x1017, 0, &100u16.to_le_bytes(), ms(0)).unwrap();
    assert_eq!(d.run(0, 250), [(100, hb(0x7F)), (200, hb(0x7F))]);
    // Changed at 250: next at 250 + 30.
    d.write(0x1017, 0, &30u16.to_le_bytes(), ms(250)).unwrap();
    assert_eq!(d.poll(ms(250)), Some(ms(280)));
    assert_eq!(d.run(251, 345), [(280, hb(0x7F)), (310, hb(0x7F)), (340, hb(0x7F))]);
    // Same value again still restarts.
    d.write(0x1017, 0, &30u16.to_le_bytes(), ms(345)).unwrap();
    assert_eq!(d.run(346, 380), [(375, hb(0x7F))]);
    // 0 switches it off.
    d.write(0x1017, 0, &0u16.to_le_bytes(), ms(380)).unwrap();
    assert_eq!(d.poll(ms(10_000)), None);
    assert!(d.take().is_empty());
}

#[test]
fn heartbeat_stops_in_initialisation_and_restarts_after_boot() {
    let mut d = Dev::booted();
    d.write(0x1017, 0, &100u16.to_le_bytes(), ms(0)).unwrap();
    assert_eq!(d.run(0, 100), [(100, hb(0x7F))]);
    assert_eq!(d.cmd(0x82, NODE, ms(150)), Some(NmtEvent::ResetCommunication));
    assert!(d.run(150, 400).is_empty());
    // The node restores 1000h–1FFFh: 1017h back to 0 by default. Keep 100 to
    // show the restart: boot-up at 400, heartbeat at 500.
    d.boot(ms(400));
    assert_eq!(d.take(), [Frame::new(0x705, &[0])]);
    assert_eq!(d.run(401, 500), [(500, hb(0x7F))]);
}

#[test]
fn consumer_monitoring_starts_with_the_first_heartbeat() {
    let mut d = Dev::booted();
    d.write(0x1016, 1, &entry(9, 100), ms(0)).unwrap();
    // Nothing is monitored before the first heartbeat.
    assert_eq!(d.poll(ms(10_000)), None);
    assert!(d.events().is_empty());
    assert_eq!(
        d.rx(Frame::new(0x709, &[0x7F]), ms(10_000)),
        Some(NmtEvent::RemoteStateChange { node: 9, state: RemoteState::PreOperational })
    );
    assert_eq!(d.poll(ms(10_000)), Some(ms(10_100)));
    assert_eq!(d.rx(Frame::new(0x709, &[0x7F]), ms(10_090)), None, "same state, no event");
    assert_eq!(d.poll(ms(10_189)), Some(ms(10_190)));
    assert!(d.events().is_empty());
    assert_eq!(d.poll(ms(10_190)), None);
    assert_eq!(d.events(), [NmtEvent::HeartbeatTimeout { node: 9 }]);
    assert!(d.nmt.is_heartbeat_timed_out(9));
    // Reported once.
    assert_eq!(d.poll(ms(20_000)), None);
    assert!(d.events().is_empty());
    // Recovery with the first heartbeat after the timeout.
    assert_eq!(
        d.rx(Frame::new(0x709, &[0x05]), ms(20_000)),
        Some(NmtEvent::HeartbeatRecovered { node: 9, state: RemoteState::Operational })
    );
    assert!(!d.nmt.is_heartbeat_timed_out(9));
    assert_eq!(d.nmt.remote_state(9), Some(RemoteState::Operational));
    assert_eq!(d.poll(ms(20_000)), Some(ms(20_100)));
    assert!(d.take().is_empty(), "the consumer never sends");
}

#[test]
fn several_entries_time_out_independently() {
    let mut d = Dev::booted();
    d.write(0x1016, 1, &entry(1, 100), ms(0)).unwrap();
    d.write(0x1016, 2, &entry(2, 250), ms(0)).unwrap();
    d.write(0x1016, 3, &entry(3, 0), ms(0)).unwrap(); // time 0: unused
    d.write(0x1016, 4, &entry(0, 50), ms(0)).unwrap(); // node 0: unused
    for n in 1..=3u16 {
        d.rx(Frame::new(0x700 + n, &[0x05]), ms(10));
    }
    d.rx(Frame::new(0x700, &[0x05]), ms(10)); // 700h is no node
    let mut got = Vec::new();
    for t in 10..=400 {
        if t % 50 == 0 && t <= 300 {
            // node 2 keeps sending until 300
            d.rx(Frame::new(0x702, &[0x05]), ms(t));
        }
        d.poll(ms(t));
        got.extend(d.events().into_iter().map(|e| (t, e)));
    }
    assert_eq!(got, [(110, NmtEvent::HeartbeatTimeout { node: 1 })]);
    d.poll(ms(550));
    assert_eq!(d.events(), [NmtEvent::HeartbeatTimeout { node: 2 }]);
    assert_eq!(d.nmt.remote_state(3), None, "not monitored");
    assert_eq!(d.nmt.consumer_entries().count(), 4);
}

#[test]
fn remote_boot_up_restarts_monitoring() {
    let mut d = Dev::booted();
    d.write(0x1016, 2, &entry(7, 100), ms(0)).unwrap();
    d.rx(Frame::new(0x707, &[0x05]), ms(0));
    assert_eq!(d.rx(Frame::new(0x707, &[0x00]), ms(50)), Some(NmtEvent::RemoteBootup { node: 7 }));
    assert_eq!(d.nmt.remote_state(7), Some(RemoteState::BootUp));
    // Waiting for its first heartbeat again: no timeout however long.
    assert_eq!(d.poll(ms(5_000)), None);
    assert!(d.events().is_empty());
    assert_eq!(
        d.rx(Frame::new(0x707, &[0x7F]), ms(5_000)),
        Some(NmtEvent::RemoteStateChange { node: 7, state: RemoteState::PreOperational })
    );
    assert_eq!(d.poll(ms(5_100)), None);
    assert_eq!(d.events(), [NmtEvent::HeartbeatTimeout { node: 7 }]);
    // A boot-up after a timeout restarts monitoring; the next heartbeat
    // is the recovery.
    assert_eq!(d.rx(Frame::new(0x707, &[0x00]), ms(6_000)), Some(NmtEvent::RemoteBootup { node: 7 }));
    assert_eq!(
        d.rx(Frame::new(0x707, &[0x7F]), ms(6_100)),
        Some(NmtEvent::HeartbeatRecovered { node: 7, state: RemoteState::PreOperational })
    );
}

#[test]
fn unmonitored_and_malformed_heartbeats_are_ignored() {
    let mut d = Dev::booted();
    d.write(0x1016, 1, &entry(9, 100), ms(0)).unwrap();
    assert_eq!(d.rx(Frame::new(0x70A, &[0x05]), ms(1)), None, "node 10 is not in 1016h");
    assert_eq!(d.rx(Frame::new(0x709, &[]), ms(1)), None, "DLC 0");
    assert_eq!(d.rx(Frame::new(0x709, &[0x05, 0x00]), ms(1)), None, "DLC 2");
    assert_eq!(d.rx(Frame::remote(0x709, 1), ms(1)), None, "a guarding request to node 9");
    assert_eq!(d.poll(ms(1_000)), None);
    // A guarding answer from node 9 (toggle set) decodes as its state.
    assert_eq!(
        d.rx(Frame::new(0x709, &[0x85]), ms(1_000)),
        Some(NmtEvent::RemoteStateChange { node: 9, state: RemoteState::Operational })
    );
    assert_eq!(
        d.rx(Frame::new(0x709, &[0x01]), ms(1_001)),
        Some(NmtEvent::RemoteStateChange { node: 9, state: RemoteState::Other(1) })
    );
}

#[test]
fn duplicate_consumer_entry_is_refused() {
    let mut d = Dev::booted();
    d.write(0x1016, 1, &entry(9, 100), ms(0)).unwrap();
    // CiA 301 §7.5.2.26: the same node-ID twice with a non-zero time.
    assert_eq!(d.write(0x1016, 2, &entry(9, 200), ms(0)), Err(SdoAbort::PARAM_INCOMPATIBLE));
    assert_eq!(d.write(0x1016, 2, &entry(9, 200), ms(0)).unwrap_err().0, 0x0604_0043);
    assert_eq!(d.od.get_u32(0x1016, 2), Some(0), "not stored");
    // Time 0 for the same node is allowed (entry unused), as is rewriting
    // the same sub-index.
    d.write(0x1016, 2, &entry(9, 0), ms(0)).unwrap();
    d.write(0x1016, 1, &entry(9, 300), ms(0)).unwrap();
    // Freeing sub 1 makes room.
    d.write(0x1016, 1, &0u32.to_le_bytes(), ms(0)).unwrap();
    d.write(0x1016, 2, &entry(9, 200), ms(0)).unwrap();
    // Reserved bits 24..31.
    assert_eq!(d.write(0x1016, 3, &0x0100_0001u32.to_le_bytes(), ms(0)), Err(SdoAbort::INVALID_VALUE));
    // Length is the dictionary's check.
    assert_eq!(d.nmt.check_write(&d.od, 0x1016, 3, &[1, 2]), Err(SdoAbort::DATA_TOO_SHORT));
    // Sub 0 is read-only in the dictionary.
    assert_eq!(d.write(0x1016, 0, &[1], ms(0)), Err(SdoAbort::WRITE_READ_ONLY));
}

#[test]
fn changing_an_entry_restarts_its_monitoring() {
    let mut d = Dev::booted();
    d.write(0x1016, 1, &entry(9, 100), ms(0)).unwrap();
    d.rx(Frame::new(0x709, &[0x05]), ms(0));
    d.write(0x1016, 1, &entry(9, 500), ms(50)).unwrap();
    assert_eq!(d.poll(ms(1_000)), None, "waits for the next heartbeat");
    assert!(d.events().is_empty());
    d.rx(Frame::new(0x709, &[0x05]), ms(1_000));
    assert_eq!(d.poll(ms(1_000)), Some(ms(1_500)));
    // Rewriting the same value keeps the running supervision.
    d.write(0x1016, 1, &entry(9, 500), ms(1_100)).unwrap();
    assert_eq!(d.poll(ms(1_100)), Some(ms(1_500)));
}

#[test]
fn consumer_timeouts_are_never_lost_when_the_queue_is_full() {
    let n = 40u8;
    let mut d = Dev::new(NmtConfig::new(NODE), n, 0);
    d.boot(ms(0));
    for i in 1..=n {
        let node = i + 10;
        d.write(0x1016, i, &entry(node, 100), ms(0)).unwrap();
        d.rx(Frame::new(0x700 + u16::from(node), &[0x05]), ms(0));
    }
    let mut timeouts = Vec::new();
    let mut t = 100;
    for _ in 0..10 {
        let next = d.poll(ms(t));
        timeouts.extend(d.events());
        match next {
            Some(n) => t = n.as_nanos() / 1_000_000,
            None => break,
        }
    }
    assert_eq!(timeouts.len(), n as usize);
    assert!(timeouts.iter().all(|e| matches!(e, NmtEvent::HeartbeatTimeout { .. })));
}

#[test]
fn heartbeat_not_supported() {
    let cfg = NmtConfig { heartbeat_supported: false, ..NmtConfig::new(NODE) };
    let mut d = Dev::new(cfg, 4, 0);
    d.boot(ms(0));
    assert!(d.od.get(0x1017, 0).is_none() && d.od.get(0x1016, 0).is_none());
    assert_eq!(d.rx(Frame::new(0x709, &[0x05]), ms(1)), None);
    assert_eq!(d.poll(ms(10_000)), None);
}
