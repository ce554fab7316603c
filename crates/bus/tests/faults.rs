//! Every fault rule, bus-off and disconnection.

use drivebus_bus::{Bus, BusConfig, FaultRule, LinkState};
use drivebus_can::{CanId, Device, Duration, Frame, Instant, TxSink};

fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

#[test]
fn drop_a_counted_number_of_frames() {
    let mut bus = Bus::new(BusConfig::with_bitrate(125_000));
    let tx = bus.attach_probe();
    let rx = bus.attach_probe();
    let rule = bus.add_fault(FaultRule::drop_frames().id(0x181).times(2));
    for i in 0..4 {
        bus.send_from(tx, Frame::new(0x181, &[i]));
    }
    bus.send_from(tx, Frame::new(0x182, &[9]));
    bus.run_until(ms(100));
    let data: Vec<u8> = bus.take_received(rx).iter().map(|f| f.data()[0]).collect();
    assert_eq!(data, [2, 3, 9]);
    assert_eq!(bus.stats().dropped, 2);
    assert_eq!(bus.stats().frames, 5); // dropped frames still used the bus
    assert_eq!(bus.log().len(), 3); // but were seen by no one
    assert_eq!(bus.fault(rule).map(|r| r.fired()), Some(2));
    assert!(bus.remove_fault(rule).is_some());
    assert!(bus.fault(rule).is_none());
}

#[test]
fn corrupt_costs_an_error_frame_and_retransmits() {
    // 000# at 125 kbit/s: 34 + 6 stuff bits, CRC delimiter and ACK (3), then
    // error flag 6 + delimiter 8 + intermission 3 = 60 bits = 480 µs lost;
    // the retransmission reaches receivers 50 bits later: 110 bits = 880 µs.
    let mut bus = Bus::new(BusConfig::with_bitrate(125_000));
    let tx = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.add_fault(FaultRule::corrupt().times(1));
    bus.send_from(tx, Frame::new(0, &[]));
    bus.run_until(ms(10));
    assert_eq!(bus.take_received_timed(rx), [(Instant::from_micros(880), Frame::new(0, &[]))]);
    let s = bus.stats();
    assert_eq!((s.error_frames, s.frames, s.bits), (1, 1, 60 + 53));
    // ISO 11898-1 fault confinement: +8 for the error, -1 for the success.
    assert_eq!(bus.tec(tx), Some(7));
}

#[test]
fn retransmission_competes_in_arbitration_again() {
    let mut bus = Bus::new(BusConfig::with_bitrate(500_000));
    let a = bus.attach_probe();
    let b = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.add_fault(FaultRule::corrupt().id(0x100).times(1));
    bus.send_from(a, Frame::new(0x100, &[]));
    // Queued while 0x100 is being destroyed; wins the next arbitration.
    bus.send_at(b, Frame::new(0x050, &[]), Instant::from_micros(10));
    bus.run_until(ms(10));
    let ids: Vec<u32> = bus.take_received(rx).iter().map(|f| f.id().raw()).collect();
    assert_eq!(ids, [0x050, 0x100]);
}

#[test]
fn persistent_corruption_drives_the_transmitter_bus_off() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let bad = bus.attach_probe();
    let good = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.add_fault(FaultRule::corrupt().from(bad));
    bus.send_from(bad, Frame::new(0x100, &[]));
    bus.send_from(bad, Frame::new(0x101, &[]));
    bus.send_from(good, Frame::new(0x200, &[]));
    bus.run_until(ms(1));
    // TEC +8 per error: 32 errors reach 256 > 255.
    assert_eq!(bus.stats().error_frames, 32);
    assert_eq!(bus.stats().bus_off, 1);
    assert_eq!(bus.stats().discarded, 2); // the frame and the one behind it
    assert_eq!(bus.link_state(bad), Some(LinkState::BusOff { recover_at: None }));
    assert_eq!(bus.take_received(rx), [Frame::new(0x200, &[])]);
    assert!(!bus.send_from(bad, Frame::new(0x100, &[])));
    bus.recover(bad);
    assert_eq!(bus.link_state(bad), Some(LinkState::Active));
    assert_eq!(bus.tec(bad), Some(0));
}

#[test]
fn bus_off_rule_and_automatic_recovery() {
    // Bus-off at the end of the error frame (60 − 3 bits = 456 µs at
    // 125 kbit/s), recovery after 128 × 11 = 1408 bits = 11264 µs.
    let mut bus = Bus::new(BusConfig::with_bitrate(125_000));
    let tx = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.add_fault(FaultRule::bus_off().times(1));
    bus.send_from(tx, Frame::new(0, &[]));
    bus.run_until(ms(1));
    let back = Instant::from_micros(456 + 11_264);
    assert_eq!(bus.link_state(tx), Some(LinkState::BusOff { recover_at: Some(back) }));
    bus.send_at(tx, Frame::new(0x1, &[]), ms(5)); // discarded: still bus-off
    bus.send_at(tx, Frame::new(0x2, &[]), ms(12)); // after recovery
    bus.run_until(ms(20));
    assert_eq!(bus.link_state(tx), Some(LinkState::Active));
    assert_eq!(bus.take_received(rx), [Frame::new(0x2, &[])]);
    assert_eq!(bus.stats().discarded, 2); // the destroyed frame, then 0x1
}

#[test]
fn corrupt_silently_with_mask_and_random_bit() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let tx = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.add_fault(FaultRule::corrupt_with([0xFF, 0, 0, 0, 0, 0, 0, 0]).id(0x201).times(1));
    bus.add_fault(FaultRule::corrupt_silently().id(0x202));
    bus.send_from(tx, Frame::new(0x201, &[0x01, 0x02]));
    bus.send_from(tx, Frame::new(0x201, &[0x01, 0x02]));
    bus.send_from(tx, Frame::new(0x202, &[0; 8]));
    bus.send_from(tx, Frame::new(0x202, &[])); // no data: unaltered
    bus.run_until(ms(1));
    let got = bus.take_received(rx);
    assert_eq!(got[0].data(), &[0xFE, 0x02]);
    assert_eq!(got[1].data(), &[0x01, 0x02]);
    let flipped: u32 = got[2].data().iter().map(|b| b.count_ones()).sum();
    assert_eq!(flipped, 1);
    assert_eq!(got[3], Frame::new(0x202, &[]));
    assert_eq!(bus.stats().corrupted, 3);
    // The log shows what receivers saw.
    assert_eq!(bus.log()[0].frame.data(), &[0xFE, 0x02]);
}

#[test]
fn delay_reorders_delivery() {
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    let tx = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.add_fault(FaultRule::delay(Duration::from_millis(5)).id(0x701));
    bus.send_from(tx, Frame::new(0x701, &[0x05])); // 58 bits, EOF end at 55 µs
    bus.send_from(tx, Frame::new(0x080, &[])); // 51 bits, EOF end at 58 + 48
    bus.run_until(ms(10));
    let got = bus.take_received_timed(rx);
    assert_eq!(got[0], (Instant::from_micros(106), Frame::new(0x080, &[])));
    assert_eq!(got[1], (Instant::from_micros(5_055), Frame::new(0x701, &[0x05])));
    assert_eq!(bus.stats().delayed, 1);
    assert_eq!(bus.log()[1].time, Instant::from_micros(5_055));
}

#[test]
fn duplicate_delivers_twice_and_costs_a_second_frame() {
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    let tx = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.add_fault(FaultRule::duplicate());
    bus.send_from(tx, Frame::new(0x701, &[0x05]));
    bus.run_until(ms(1));
    let times: Vec<u64> = bus.take_received_timed(rx).iter().map(|(t, _)| t.as_micros()).collect();
    assert_eq!(times, [55, 113]);
    assert_eq!((bus.stats().duplicated, bus.stats().frames, bus.stats().bits), (1, 2, 116));
}

#[test]
fn rules_match_by_node_predicate_extended_and_skip() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let a = bus.attach_probe();
    let b = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.add_fault(FaultRule::drop_frames().from(b));
    bus.add_fault(FaultRule::drop_frames().when(|f| f.data().first() == Some(&0x40)));
    bus.add_fault(FaultRule::drop_frames().extended(true));
    bus.add_fault(FaultRule::drop_frames().ids(0x300..0x310).skip(2).times(1));
    bus.send_from(b, Frame::new(0x100, &[]));
    bus.send_from(a, Frame::new(0x600, &[0x40, 0]));
    bus.send_from(a, Frame::new(0x600, &[0x41, 0]));
    bus.send_from(a, Frame::try_new(CanId::Extended(5), &[]).unwrap());
    for i in 0..4 {
        bus.send_from(a, Frame::new(0x305, &[i]));
    }
    bus.send_from(a, Frame::new(0x310, &[]));
    bus.run_until(ms(1));
    let got: Vec<String> = bus.take_received(rx).iter().map(|f| f.to_string()).collect();
    // FIFO per station: 600#41.. was queued before the 305s.
    assert_eq!(got, ["600#4100", "305#00", "305#01", "305#03", "310#"]);
}

fn drops_with_seed(seed: u64) -> u64 {
    let mut bus = Bus::new(BusConfig { seed, ..BusConfig::zero_time() });
    let tx = bus.attach_probe();
    bus.add_fault(FaultRule::drop_frames().probability(0.25));
    for i in 0..1000u64 {
        bus.send_at(tx, Frame::new(0x181, &i.to_le_bytes()), Instant::from_micros(i));
    }
    bus.run_until(ms(2));
    bus.stats().dropped
}

#[test]
fn probability_is_seeded_and_deterministic() {
    let n = drops_with_seed(1);
    assert_eq!(n, drops_with_seed(1));
    assert!((200..300).contains(&n), "{n}");
    let others: Vec<u64> = (2..6).map(drops_with_seed).collect();
    assert!(others.iter().any(|&m| m != n));
}

/// Sends one frame per millisecond, numbered.
struct Ticker {
    ticks: u8,
    next: Instant,
}

impl Device for Ticker {
    fn handle_frame(&mut self, _: &Frame, _: Instant, _: &mut dyn TxSink) {}
    fn poll(&mut self, now: Instant, out: &mut dyn TxSink) -> Option<Instant> {
        if now >= self.next {
            self.ticks += 1;
            out.send(Frame::new(0x700, &[self.ticks]));
            self.next += Duration::from_millis(1);
        }
        Some(self.next)
    }
    fn start(&mut self, _now: Instant, _out: &mut dyn TxSink) {}
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

#[test]
fn disconnected_stations_neither_send_nor_receive() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let node = bus.attach(Ticker { ticks: 0, next: Instant::ZERO });
    let probe = bus.attach_probe();
    bus.run_until(Instant::from_micros(2_500)); // polls at 0, 1, 2 ms
    assert_eq!(bus.take_received(probe).len(), 3);
    bus.disconnect(node);
    bus.disconnect(probe);
    assert!(!bus.send_from(probe, Frame::new(0x1, &[])));
    bus.run_until(Instant::from_micros(5_500)); // 3, 4, 5 ms: discarded
    assert_eq!(bus.link_state(node), Some(LinkState::Disconnected));
    assert_eq!(bus.node::<Ticker>(node).map(|t| t.ticks), Some(6)); // it kept running
    bus.reconnect(node);
    bus.reconnect(probe);
    bus.run_until(Instant::from_micros(6_500));
    assert_eq!(bus.take_received(probe), [Frame::new(0x700, &[7])]);
    assert_eq!(bus.stats().discarded, 4);
    assert_eq!(bus.stats().frames, 4);
}
