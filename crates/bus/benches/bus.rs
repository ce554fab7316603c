//! Frames per second the virtual bus relays with 30 nodes.
//!
//! `cargo bench -p drivebus-bus --bench bus`

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
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

fn relay(c: &mut Criterion) {
    let mut g = c.benchmark_group("bus_30_nodes");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(3));

    // 30 frames per 1 ms period for 100 ms = 3000 frames.
    g.throughput(Throughput::Elements(3000));
    g.bench_function("zero_time", |b| {
        b.iter(|| {
            let mut bus = machine(BusConfig::zero_time(), Duration::from_millis(1));
            bus.run_until(Instant::from_micros(99_999));
            black_box(bus.stats().frames)
        })
    });

    // At 1 Mbit/s, 30 eight-byte frames take ~3.7 ms: 10 ms period, 1 s.
    g.bench_function("1mbit", |b| {
        b.iter(|| {
            let mut bus = machine(BusConfig::with_bitrate(1_000_000), Duration::from_millis(10));
            bus.run_until(Instant::from_micros(999_999));
            black_box(bus.stats().frames)
        })
    });
    g.finish();
}

criterion_group!(benches, relay);
criterion_main!(benches);
