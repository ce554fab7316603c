//! The consumer's share of the SYNC → TPDO path: a SYNC frame in, a
//! `SyncEvent` out (plus the window check a synchronous PDO makes).
//!
//! Run: `cargo bench -p drivebus-sync --bench sync`.

// criterion_main! generates an undocumented `main`.
#![allow(missing_docs)]

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use drivebus_can::{Frame, Instant};
use drivebus_od::ObjectDictionary;
use drivebus_sync::SyncService;

fn sync_in(c: &mut Criterion) {
    let mut od = ObjectDictionary::new();
    let mut s = SyncService::install(&mut od, 1);
    let sync = Frame::new(0x080, &[]);
    let other = Frame::new(0x181, &[0; 8]);
    let mut t = 0u64;
    c.bench_function("sync_frame_to_event", |b| {
        b.iter(|| {
            t += 1000;
            black_box(s.handle_frame(black_box(&sync), Instant::from_nanos(t)))
        })
    });
    c.bench_function("non_sync_frame_rejected", |b| {
        b.iter(|| black_box(s.handle_frame(black_box(&other), Instant::from_nanos(t))))
    });
    c.bench_function("window_open", |b| {
        b.iter(|| black_box(s.window_open(black_box(Instant::from_nanos(t)))))
    });
}

criterion_group!(benches, sync_in);
criterion_main!(benches);
