//! Arbitration order, FIFO transmit queues, echo.

use drivebus_bus::{Bus, BusConfig, ProbeId};
use drivebus_can::{CanId, Frame, Instant};

fn ids(frames: &[Frame]) -> Vec<u32> {
    frames.iter().map(|f| f.id().raw()).collect()
}

fn three_at_once(cfg: BusConfig) {
    let mut bus = Bus::new(cfg);
    let a = bus.attach_probe();
    let b = bus.attach_probe();
    let c = bus.attach_probe();
    let rx = bus.attach_probe();
    // Queued in "wrong" order and from different stations at the same time.
    bus.send_from(a, Frame::new(0x701, &[0x05]));
    bus.send_from(b, Frame::new(0x181, &[1, 2]));
    bus.send_from(c, Frame::new(0x080, &[]));
    bus.run_until(Instant::from_millis(10));
    assert_eq!(ids(&bus.take_received(rx)), [0x080, 0x181, 0x701]);
    // Nobody hears their own frame (no echo): a gets the other two.
    assert_eq!(ids(&bus.take_received(a)), [0x080, 0x181]);
}

#[test]
fn lowest_id_wins_zero_time() {
    three_at_once(BusConfig::zero_time());
}

#[test]
fn lowest_id_wins_bit_timed() {
    three_at_once(BusConfig::with_bitrate(125_000));
}

#[test]
fn fifo_head_blocks_later_high_priority_frame() {
    // Station A queues 0x700 then 0x001; only its head (0x700) competes, so
    // B's 0x100 goes first, then A's 0x700, and only then A's 0x001 even
    // though 0x001 would beat everything in arbitration.
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    let a = bus.attach_probe();
    let b = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.send_from(a, Frame::new(0x700, &[]));
    bus.send_from(a, Frame::new(0x001, &[]));
    bus.send_from(b, Frame::new(0x100, &[]));
    bus.run_until(Instant::from_millis(1));
    assert_eq!(ids(&bus.take_received(rx)), [0x100, 0x700, 0x001]);
}

#[test]
fn frame_queued_during_transmission_waits_for_idle_then_arbitrates() {
    // While 0x700 is on the wire, 0x300 and 0x200 are queued; when the bus
    // is idle they arbitrate: 0x200 first.
    let mut bus = Bus::new(BusConfig::with_bitrate(125_000));
    let a = bus.attach_probe();
    let b = bus.attach_probe();
    let c = bus.attach_probe();
    let rx = bus.attach_probe();
    bus.send_from(a, Frame::new(0x700, &[]));
    bus.send_at(b, Frame::new(0x300, &[]), Instant::from_micros(100));
    bus.send_at(c, Frame::new(0x200, &[]), Instant::from_micros(200));
    bus.run_until(Instant::from_millis(5));
    assert_eq!(ids(&bus.take_received(rx)), [0x700, 0x200, 0x300]);
}

#[test]
fn data_beats_remote_and_standard_beats_extended() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let p: Vec<ProbeId> = (0..4).map(|_| bus.attach_probe()).collect();
    let rx = bus.attach_probe();
    let ext = Frame::try_new(CanId::Extended(0x123 << 18), &[]).unwrap();
    let ext_rtr = Frame::try_remote(CanId::Extended(0x123 << 18), 0).unwrap();
    bus.send_from(p[0], ext_rtr);
    bus.send_from(p[1], ext);
    bus.send_from(p[2], Frame::remote(0x123, 0));
    bus.send_from(p[3], Frame::new(0x123, &[]));
    bus.run_until(Instant::from_millis(1));
    assert_eq!(bus.take_received(rx), [Frame::new(0x123, &[]), Frame::remote(0x123, 0), ext, ext_rtr]);
}

#[test]
fn echo_delivers_own_frames_when_enabled() {
    let mut bus = Bus::new(BusConfig { echo: true, ..BusConfig::zero_time() });
    let a = bus.attach_probe();
    bus.send_from(a, Frame::new(0x123, &[1]));
    bus.run_until(Instant::from_millis(1));
    assert_eq!(ids(&bus.take_received(a)), [0x123]);
}

#[test]
fn step_reports_event_times_and_goes_quiet() {
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    let a = bus.attach_probe();
    assert_eq!(bus.next_event_time(), None);
    assert!(bus.send_from(a, Frame::new(0, &[])));
    assert_eq!(bus.next_event_time(), Some(Instant::ZERO));
    assert_eq!(bus.step(), Some(Instant::ZERO)); // starts the frame
    // 000# is 53 bits with intermission; receivers have it after 50.
    assert_eq!(bus.next_event_time(), Some(Instant::from_micros(50)));
    assert_eq!(bus.step(), Some(Instant::from_micros(50)));
    assert_eq!(bus.step(), None);
    assert_eq!(bus.stats().frames, 1);
}

mod invariants {
    use drivebus_bus::timing::frame_bits;
    use drivebus_bus::{Bus, BusConfig};
    use drivebus_can::{Duration, Frame, Instant};
    use proptest::prelude::*;

    proptest! {
        /// Random traffic from 4 stations at 250 kbit/s: every frame arrives
        /// once, each station's frames stay in order, transmissions never
        /// overlap, and bits/busy time add up.
        #[test]
        fn random_traffic(sends in proptest::collection::vec((0usize..4, 0u16..0x800, 0u64..2_000), 1..60)) {
            let mut bus = Bus::new(BusConfig::with_bitrate(250_000));
            let tx: Vec<_> = (0..4).map(|_| bus.attach_probe()).collect();
            let rx = bus.attach_probe();
            let mut sorted: Vec<(usize, (usize, u16, u64))> = sends.into_iter().enumerate().collect();
            sorted.sort_by_key(|&(n, (_, _, at))| (at, n));
            for &(n, (st, id, at)) in &sorted {
                // The payload carries the sequence number to identify the frame.
                let f = Frame::new(id, &(n as u16).to_le_bytes());
                bus.send_at(tx[st], f, Instant::from_micros(at));
            }
            bus.run_until(Instant::from_millis(100));
            let got = bus.take_received_timed(rx);
            prop_assert_eq!(got.len(), sorted.len());
            let seq = |f: &Frame| u16::from_le_bytes([f.data()[0], f.data()[1]]) as usize;
            // Per-station FIFO.
            for st in 0..4 {
                let want: Vec<usize> = sorted.iter().filter(|s| s.1.0 == st).map(|s| s.0).collect();
                let have: Vec<usize> = got.iter().map(|(_, f)| seq(f)).filter(|&n| sorted.iter().any(|s| s.0 == n && s.1.0 == st)).collect();
                prop_assert_eq!(want, have);
            }
            // Start times from delivery times; no overlap, never before queued.
            let bit = Duration::from_micros(4);
            let mut free = Instant::ZERO;
            let mut bits = 0u64;
            let mut delivered = Vec::new();
            for (t, f) in &got {
                let fb = frame_bits(f);
                let start = Instant::from_nanos(t.as_nanos() - u64::from(fb.to_end_of_frame()) * 4_000);
                prop_assert!(start >= free);
                let queued = sorted.iter().find(|s| s.0 == seq(f)).map(|s| s.1.2).unwrap_or(0);
                prop_assert!(start >= Instant::from_micros(queued));
                // Arbitration: no other station had a waiting head with a
                // lower id (or the same id and a lower station number).
                let me = sorted.iter().find(|s| s.0 == seq(f)).map(|s| s.1).unwrap_or_default();
                for st in 0..4 {
                    let head = sorted.iter().find(|s| s.1.0 == st && !delivered.contains(&s.0));
                    if let Some(&(_, (hs, hid, hat))) = head
                        && hs != me.0
                        && Instant::from_micros(hat) <= start
                    {
                        prop_assert!((me.1, me.0) < (hid, hs), "{:?} beat {:?}", me, (hs, hid, hat));
                    }
                }
                delivered.push(seq(f));
                free = start + bit * fb.total();
                bits += u64::from(fb.total());
            }
            prop_assert_eq!(bus.stats().bits, bits);
            prop_assert_eq!(bus.stats().busy, bit * bits as u32);
        }
    }
}
