//! A line of emulated iPOS drives in OP (ethercrab brings it there over
//! the in-process link, DC SYNC0 at 1 ms, every drive enabled), then
//! `CYCLES` replays of ethercrab's cycle frames on simulated time: the loop
//! of the `drive_line` bench without criterion, for instruction counts.
//!
//! ```sh
//! cargo build --release -p drivebus-ethercat --example drive_line_loop
//! valgrind --tool=callgrind target/release/examples/drive_line_loop 64 1000
//! valgrind --tool=callgrind target/release/examples/drive_line_loop 64 3000
//! ```
//!
//! Prints the loop's CPU time per cycle (thread CPU time: unaffected by
//! waiting for a core on a loaded host) beside its wall time.
//!
//! The difference of the two runs' instruction counts divided by 2000 is
//! one cycle of the line (set-up cancels out); or count only the cycles
//! with `--collect-atstart=no --toggle-collect='*run_cycles*'`. Prints the
//! host's counters.

#[path = "../benches/support/ipos_line.rs"]
mod ipos_line;
#[path = "../benches/support/replay.rs"]
#[allow(dead_code)] // the bench uses the mailbox poll frame
mod replay;

use ethercrab::PduStorage;

static STORAGE: replay::Storage = PduStorage::new();

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(64);
    let cycles: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1000);
    assert!((1..=ipos_line::MAX_SLAVES).contains(&n), "1..=64 drives");
    let (host, frames) = replay::line_in_op(n, &STORAGE);
    let before = host.stats();
    let steps = |h: &drivebus_ethercat::Host| {
        drivebus_ethercat::drive::with_drive(h, 0, |d| d.app().device().app.drive.steps()).expect("a drive")
    };
    let k0 = steps(&host);
    let s0 = drivebus_ethercat::drive::with_drive(&host, 0, |d| d.app().stats()).expect("a drive");
    let (cpu0, wall0) = (thread_cpu_ns(), std::time::Instant::now());
    let bad = run_cycles(&host, &frames, n, cycles);
    let (cpu, wall) = (thread_cpu_ns() - cpu0, wall0.elapsed());
    let after = host.stats();
    let s1 = drivebus_ethercat::drive::with_drive(&host, 0, |d| d.app().stats()).expect("a drive");
    println!(
        "drive 0 per cycle: control periods {:.2}, outputs applied {:.2}, inputs sampled {:.2}, SYNC0 pulses {:.2}",
        (steps(&host) - k0) as f64 / f64::from(cycles),
        (s1.outputs_applied - s0.outputs_applied) as f64 / f64::from(cycles),
        (s1.inputs_sampled - s0.inputs_sampled) as f64 / f64::from(cycles),
        (s1.sync0_pulses - s0.sync0_pulses) as f64 / f64::from(cycles),
    );
    println!(
        "drives={n} cycles={cycles} frames_per_cycle={} bad_wkc={bad} deadline_polls_per_cycle={:.1} \
         cpu_per_cycle_us={:.1} wall_per_cycle_us={:.1}",
        frames.len(),
        (after.deadline_polls - before.deadline_polls) as f64 / f64::from(cycles),
        cpu as f64 / 1e3 / f64::from(cycles),
        wall.as_secs_f64() * 1e6 / f64::from(cycles),
    );
}

/// CPU time of the calling thread (not counting time spent waiting for a
/// core: the host is shared).
#[allow(unsafe_code)]
fn thread_cpu_ns() -> u64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: a live timespec; CLOCK_THREAD_CPUTIME_ID always exists on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// The measured loop (not inlined, so callgrind can collect it alone).
#[inline(never)]
fn run_cycles(host: &drivebus_ethercat::Host, frames: &[Vec<u8>], n: usize, cycles: u32) -> u32 {
    let mut buf = vec![0u8; 1600];
    let mut bad = 0;
    for _ in 0..cycles {
        if replay::cycle(host, frames, &mut buf) != 3 * n as u16 {
            bad += 1;
        }
    }
    bad
}
