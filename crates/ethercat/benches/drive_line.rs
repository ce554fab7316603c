//! Cost of a line of emulated iPOS drives (the `DriveLine` that `drivebus
//! ethercat serve --drive ipos` hosts) on a simulated clock.
//!
//! Set-up (not timed): ethercrab 0.7.1 over a recording in-process link
//! brings the line to OP with DC SYNC0 at 1 ms, csp, every drive enabled
//! and holding position (`support/ipos_line.rs`); the frames of its last
//! cycle are kept. They are what ethercrab sends every cycle: the LRW of
//! the process image (split over frames where it exceeds one), the FRMW of
//! the reference clock's system time, and an FPRD of AL status per slave.
//!
//! * `ipos{1,64}/cycle`: one 1 ms cycle: those frames through the line,
//!   then the simulated clock to the next cycle, which runs every drive's
//!   SYNC0 (latching set-points, its control step, sampling its inputs).
//! * `ipos64/cycle_mailbox_polls`: the same plus one frame of 64 FPRDs of
//!   the SM1 (mailbox in) status, as SOEM and TwinCAT poll mailboxes.
//! * `ipos64/drives_only`: the clock moved by 1 ms, no frame: the drives'
//!   own share of a cycle.
//! * `ipos{1,16,64}/to_reply`: the same cycle, timing only each frame's way
//!   to its reply (what a master waits for: `Host::process_frame_then`
//!   calls back before the drives' firmware reacts to the frame).
//! * `ipos{1,64}/fprd`, `/lrw`: one datagram through the line at a fixed
//!   instant (FPRD of the last slave's AL status; LRW of the whole image).
//!
//! Run: `cargo bench -p drivebus-ethercat --bench drive_line`.

// criterion_main! generates an undocumented `main`.
#![allow(missing_docs)]

#[path = "support/ipos_line.rs"]
mod ipos_line;
#[path = "support/replay.rs"]
mod replay;

use criterion::{BenchmarkId, Criterion, black_box, criterion_group, criterion_main};
use drivebus_can::Duration;
use drivebus_esc::frame::{DatagramCommand, FrameBuilder, station_address};
use ethercrab::PduStorage;
use replay::{Storage, cycle, line_in_op, mailbox_polls};

static STORAGE_1: Storage = PduStorage::new();
static STORAGE_16: Storage = PduStorage::new();
static STORAGE_64: Storage = PduStorage::new();

fn one_datagram(cmd: DatagramCommand, addr: u32, len: usize) -> Vec<u8> {
    let mut buf = vec![0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(cmd, 0, addr, &vec![0; len]).unwrap();
    let n = b.finish();
    buf.truncate(n);
    buf
}

fn bench_line(c: &mut Criterion, n: usize, storage: &'static Storage) {
    let (host, frames) = line_in_op(n, storage);
    let mut buf = vec![0u8; 1600];
    // Every drive answers the replayed cycle: the LRW counts 3 per drive.
    assert_eq!(cycle(&host, &frames, &mut buf), 3 * n as u16, "replayed LRW working counter");
    let mut g = c.benchmark_group(format!("ipos{n}"));
    g.bench_function("cycle", |b| b.iter(|| black_box(cycle(&host, &frames, &mut buf))));
    g.bench_function("to_reply", |b| b.iter_custom(|iters| cycles_to_reply(&host, &frames, &mut buf, iters)));
    if n > 1 {
        let mut with_polls = frames.clone();
        with_polls.push(mailbox_polls(n));
        g.bench_function("cycle_mailbox_polls", |b| {
            b.iter(|| black_box(cycle(&host, &with_polls, &mut buf)))
        });
        g.bench_function("drives_only", |b| b.iter(|| host.advance(Duration::from_millis(1))));
    }
    let fprd = one_datagram(DatagramCommand::Fprd, station_address(0x1000 + n as u16 - 1, 0x0130), 2);
    let lrw = one_datagram(DatagramCommand::Lrw, 0, 22 * n);
    for (name, f) in [("fprd", &fprd), ("lrw", &lrw)] {
        g.bench_with_input(BenchmarkId::new(name, f.len()), f, |b, f| {
            b.iter(|| {
                host.with_segment(|s| {
                    let fb = &mut buf[..f.len()];
                    fb.copy_from_slice(f);
                    black_box(s.process_frame(fb, host.clock().now()))
                })
            })
        });
    }
    g.finish();
    // The line is still in OP and every drive enabled after the runs.
    assert_eq!(cycle(&host, &frames, &mut buf), 3 * n as u16, "LRW working counter after the runs");
}

/// `iters` cycles as [`cycle`] runs them; the time from each frame's
/// arrival to its reply, summed.
fn cycles_to_reply(
    host: &drivebus_ethercat::Host,
    frames: &[Vec<u8>],
    buf: &mut [u8],
    iters: u64,
) -> std::time::Duration {
    let mut total = std::time::Duration::ZERO;
    for _ in 0..iters {
        let start = host.clock().now();
        for f in frames {
            let fb = &mut buf[..f.len()];
            fb.copy_from_slice(f);
            let arrival = std::time::Instant::now();
            let mut replied = arrival;
            host.process_frame_then(fb, |reply, _| {
                black_box(reply);
                replied = std::time::Instant::now();
            });
            total += replied - arrival;
        }
        host.advance((start + Duration::from_millis(1)).saturating_duration_since(host.clock().now()));
    }
    total
}

fn benches(c: &mut Criterion) {
    bench_line(c, 1, &STORAGE_1);
    bench_line(c, 16, &STORAGE_16);
    bench_line(c, 64, &STORAGE_64);
}

criterion_group!(drive_line, benches);
criterion_main!(drive_line);
