//! External injection, node hooks, bad ids and other API edges.

use drivebus_bus::{Bus, BusConfig, FaultRule, LinkState, NodeId};
use drivebus_can::{Device, Duration, Frame, Instant, TxSink};

#[test]
fn inject_sends_from_a_silent_external_station() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let rx = bus.attach_probe();
    bus.inject(Frame::new(0x123, &[1]), Instant::from_millis(5));
    assert_eq!(bus.next_event_time(), Some(Instant::from_millis(5)));
    bus.run_until(Instant::from_millis(10));
    assert_eq!(bus.take_received_timed(rx), [(Instant::from_millis(5), Frame::new(0x123, &[1]))]);
    // The external station exists now, captures nothing and is a normal
    // station for fault rules.
    let ext = bus.external_probe();
    bus.add_fault(FaultRule::drop_frames().from(ext));
    bus.send_from(rx, Frame::new(0x124, &[]));
    bus.inject(Frame::new(0x125, &[]), Instant::ZERO); // in the past: now
    bus.run_until(Instant::from_millis(20));
    assert!(bus.received(ext).is_empty());
    assert_eq!(bus.stats().dropped, 1);
    assert_eq!(bus.now(), Instant::from_millis(20));
}

#[test]
fn unknown_stations_are_harmless() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let ghost = NodeId(99);
    assert!(!bus.send_from(ghost, Frame::new(1, &[])));
    assert!(!bus.send_at(ghost, Frame::new(1, &[]), Instant::ZERO));
    bus.set_bus_off(ghost);
    bus.recover(ghost);
    bus.disconnect(ghost);
    bus.reconnect(ghost);
    bus.wake(ghost);
    assert_eq!(bus.pending(ghost), 0);
    assert_eq!(bus.link_state(ghost), None);
    assert_eq!(bus.tec(ghost), None);
    assert!(bus.node::<u8>(ghost).is_none());
    assert_eq!(bus.step(), None);
}

/// Records the hooks it sees; sends 0x300 when told to.
#[derive(Default)]
struct Watcher {
    links: Vec<(LinkState, Instant)>,
    errors: u32,
    polls: u32,
    send: bool,
}

impl Device for Watcher {
    fn handle_frame(&mut self, _: &Frame, _: Instant, _: &mut dyn TxSink) {}
    fn poll(&mut self, _now: Instant, out: &mut dyn TxSink) -> Option<Instant> {
        self.polls += 1;
        if std::mem::take(&mut self.send) {
            out.send(Frame::new(0x300, &[]));
        }
        None
    }
    fn handle_error_frame(&mut self, _now: Instant, _out: &mut dyn TxSink) {
        self.errors += 1;
    }
    fn link_changed(&mut self, state: LinkState, now: Instant, _out: &mut dyn TxSink) {
        self.links.push((state, now));
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
fn nodes_hear_error_frames_and_their_own_link_changes() {
    let mut bus = Bus::new(BusConfig::with_bitrate(125_000));
    let victim = bus.attach(Watcher::default());
    let other = bus.attach(Watcher::default());
    let probe = bus.attach_probe();
    bus.add_fault(FaultRule::corrupt().from(probe).times(1));
    bus.add_fault(FaultRule::bus_off().from(victim).times(1));
    bus.send_from(probe, Frame::new(0, &[]));
    bus.run_until(Instant::from_millis(1));
    assert_eq!(bus.node::<Watcher>(victim).map(|w| w.errors), Some(1));
    assert_eq!(bus.node::<Watcher>(other).map(|w| w.errors), Some(1));

    // Make the victim send 300#: 34 bits + 4 stuff bits, then 3 up to the
    // ACK delimiter and 14 of error frame: it goes bus-off at 1 ms + 55 bits
    // (440 µs), then recovers 1408 bits (11264 µs) later.
    if let Some(w) = bus.node_mut::<Watcher>(victim) {
        w.send = true;
    }
    bus.wake(victim);
    bus.run_until(Instant::from_millis(20));
    let off = Instant::from_micros(1_440);
    let back = off + Duration::from_micros(11_264);
    let links = bus.node::<Watcher>(victim).map(|w| w.links.clone()).unwrap_or_default();
    assert_eq!(links, [(LinkState::BusOff { recover_at: Some(back) }, off), (LinkState::Active, back)]);
    assert_eq!(bus.node::<Watcher>(other).map(|w| w.errors), Some(2));

    bus.disconnect(other);
    bus.reconnect(other);
    let links = bus.node::<Watcher>(other).map(|w| w.links.clone()).unwrap_or_default();
    let now = bus.now();
    assert_eq!(links, [(LinkState::Disconnected, now), (LinkState::Active, now)]);
}

/// Always asks to be polled again "now".
struct Eager(u32);

impl Device for Eager {
    fn handle_frame(&mut self, _: &Frame, _: Instant, _: &mut dyn TxSink) {}
    fn poll(&mut self, now: Instant, _: &mut dyn TxSink) -> Option<Instant> {
        self.0 += 1;
        Some(now)
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
fn a_deadline_in_the_past_cannot_stall_time() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let n = bus.attach(Eager(0));
    bus.run_until(Instant::from_nanos(9));
    // Polled at 0, 1, ..., 9 ns.
    assert_eq!(bus.node::<Eager>(n).map(|e| e.0), Some(10));
}

#[test]
fn a_station_hears_it_went_error_passive_and_back() {
    // 16 destroyed transmissions: TEC 128 > 127, error passive (ISO
    // 11898-1 §12.1.4.2); the retransmission then succeeds, one success
    // brings it to 127: error active again.
    let mut bus = Bus::new(BusConfig::zero_time());
    let w = bus.attach(Watcher::default());
    let probe = bus.attach_probe();
    bus.add_fault(FaultRule::corrupt().from(w).times(16));
    if let Some(n) = bus.node_mut::<Watcher>(w) {
        n.send = true;
    }
    bus.wake(w);
    bus.run_until(Instant::from_millis(1));
    let links: Vec<LinkState> =
        bus.node::<Watcher>(w).map(|n| n.links.iter().map(|l| l.0).collect()).unwrap();
    assert_eq!(links, [LinkState::ErrorPassive, LinkState::Active]);
    assert_eq!(bus.tec(w), Some(127));
    // Error passive still transmits: the frame arrived.
    assert_eq!(bus.take_received(probe), [Frame::new(0x300, &[])]);
}

/// Sends 0x700 + its count at start and every 10 ms (a heartbeat).
#[derive(Default)]
struct Beater {
    next: Option<Instant>,
    boots: u8,
}

impl Device for Beater {
    fn handle_frame(&mut self, _: &Frame, _: Instant, _: &mut dyn TxSink) {}
    fn poll(&mut self, now: Instant, out: &mut dyn TxSink) -> Option<Instant> {
        if self.next.is_some_and(|n| n <= now) {
            out.send(Frame::new(0x705, &[5]));
            self.next = Some(now + Duration::from_millis(10));
        }
        self.next
    }
    fn start(&mut self, now: Instant, out: &mut dyn TxSink) {
        self.boots += 1;
        out.send(Frame::new(0x705, &[0]));
        self.next = Some(now + Duration::from_millis(10));
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

#[test]
fn a_node_powered_off_is_silent_and_boots_when_powered_on() {
    let mut bus = Bus::new(BusConfig::zero_time());
    let rx = bus.attach_probe();
    let n = bus.attach(Beater::default());
    bus.run_until(Instant::from_millis(35));
    assert_eq!(bus.take_received(rx).len(), 4); // boot-up + 3 beats
    let dev = bus.power_off(n).expect("it had power");
    assert_eq!(dev.as_any().downcast_ref::<Beater>().map(|b| b.boots), Some(1));
    assert!(bus.node::<Beater>(n).is_none());
    assert!(bus.power_off(n).is_none());
    bus.reconnect(n); // does not switch the power on
    bus.run_until(Instant::from_millis(100));
    assert!(bus.take_received(rx).is_empty());
    assert!(bus.power_on(n, Beater::default()));
    assert!(!bus.power_on(n, Beater::default()));
    bus.run_until(Instant::from_millis(115));
    let got = bus.take_received_timed(rx);
    assert_eq!(got[0], (Instant::from_millis(100), Frame::new(0x705, &[0])));
    assert_eq!(got.len(), 2);
}
