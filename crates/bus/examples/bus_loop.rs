//! Instruction-count instrument for `valgrind --tool=callgrind`: the
//! scenarios of `benches/bus.rs` (30 nodes, zero-time or 1 Mbit/s),
//! `bus_loop zero|1mbit N` runs one N times.

use drivebus_bus::{Bus, BusConfig};
use drivebus_can::{Device, Duration, Frame, Instant, TxSink};
use std::hint::black_box;

const NODES: u16 = 30;

/// Sends one 8-byte TPDO per period and counts what it receives.
struct PdoNode {
    id: u16,
    period: Duration,
    next: Instant,
    seen: u64,
}

impl Device for PdoNode {
    fn handle_frame(&mut self, frame: &Frame, _now: Instant, _out: &mut dyn TxSink) {
        self.seen += u64::from(frame.raw_data()[0]);
    }
    fn poll(&mut self, now: Instant, out: &mut dyn TxSink) -> Option<Instant> {
        if now >= self.next {
            out.send(Frame::new8(0x180 + self.id, [self.seen as u8, 1, 2, 3, 4, 5, 6, 7]));
            self.next = now + self.period;
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

fn machine(cfg: BusConfig, period: Duration) -> Bus {
    let mut bus = Bus::new(BusConfig { log: false, ..cfg });
    for n in 1..=NODES {
        bus.attach(PdoNode { id: n, period, next: Instant::ZERO, seen: 0 });
    }
    bus
}

fn main() {
    let which = std::env::args().nth(1).unwrap_or_default();
    let n: u32 = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    for _ in 0..n {
        let frames = if which == "1mbit" {
            let mut bus = machine(BusConfig::with_bitrate(1_000_000), Duration::from_millis(10));
            bus.run_until(Instant::from_micros(999_999));
            bus.stats().frames
        } else {
            let mut bus = machine(BusConfig::zero_time(), Duration::from_millis(1));
            bus.run_until(Instant::from_micros(99_999));
            bus.stats().frames
        };
        black_box(frames);
    }
}
