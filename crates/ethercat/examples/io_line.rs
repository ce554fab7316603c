//! A line of bare I/O slaves made from real devices' EEPROM images (an
//! EK1100 coupler, then EL2004 and EL2828 output terminals in turn; `tests/vectors/ethercat/`), brought from their descriptions to OP
//! by ethercrab 0.7.1 over the in-process link on simulated time, then
//! ethercrab's frames of one cycle replayed (issue 17 §4):
//!
//! ```sh
//! cargo build --release -p drivebus-ethercat --example io_line
//! target/release/examples/io_line 1024 2000
//! valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*run_cycles*' \
//!     target/release/examples/io_line 1024 100
//! ```
//!
//! Prints the time to OP and the line's CPU per 1 ms cycle (thread CPU
//! time: not counting waits for a core on a loaded host). Exits non-zero
//! if a cycle's working counter is wrong or an output did not arrive.

#[path = "../benches/support/ipos_line.rs"]
#[allow(dead_code)]
mod ipos_line;
#[path = "../benches/support/replay.rs"]
#[allow(dead_code)] // the iPOS line and the mailbox poll frame are the bench's
mod replay;

use drivebus_can::{Duration, Instant};
use drivebus_ethercat::described::{self, Member};
use drivebus_ethercat::{Clock, Host};
use ethercrab::PduStorage;

/// Most slaves ethercrab's group holds here.
const MAX_SLAVES: usize = 1024;
/// Process image: one output byte per terminal.
const MAX_PDI: usize = MAX_SLAVES;

static STORAGE: replay::Storage = PduStorage::new();

/// The terminals after the coupler, in turn: (image, output bytes).
const TERMINALS: [(&str, usize); 2] = [("el2004.hex", 1), ("el2828.bin", 1)];

fn vector(name: &str) -> String {
    format!("{}/../../tests/vectors/ethercat/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(1024);
    let cycles: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1000);
    assert!((2..=MAX_SLAVES).contains(&n), "2..={MAX_SLAVES} slaves");
    // ethercrab's group of 1024 subdevices lives on the stack of the future.
    let run = std::thread::Builder::new().stack_size(512 << 20).spawn(move || run(n, cycles));
    std::process::exit(run.expect("thread").join().expect("run"));
}

fn run(n: usize, cycles: u32) -> i32 {
    let load = |f: &str| described::load(&vector(f)).unwrap_or_else(|e| panic!("{e}"));
    let coupler = Member::Device(Box::new(load("ek1100.bin")));
    let kinds: Vec<_> = TERMINALS.iter().map(|(f, _)| load(f)).collect();
    let members: Vec<Member> = std::iter::once(coupler)
        .chain((1..n).map(|i| Member::Device(Box::new(kinds[(i - 1) % kinds.len()].clone()))))
        .collect();
    let t_build = std::time::Instant::now();
    let host = Host::line(
        described::devices(&members, None).expect("line"),
        Clock::simulated(Instant::from_millis(1)),
    );
    let build = t_build.elapsed();
    let (md, recording, frames) = replay::recording_main_device(&host, &STORAGE);
    // ethercrab wants a `Copy` clock function.
    let clock: &'static Clock = Box::leak(Box::new(host.clock().clone()));
    let now = move || clock.ethercat_ns();
    let (t_op, sim_op) = (std::time::Instant::now(), host.clock().now());
    let out_bytes = |i: usize| TERMINALS[(i - 1) % TERMINALS.len()].1;
    let result = async_io::block_on(async {
        let group = md.init_single_group::<MAX_SLAVES, MAX_PDI>(now).await?;
        assert_eq!(group.len(), n, "every slave found");
        let names: Vec<String> = group.iter(&md).take(4).map(|s| s.name().to_owned()).collect();
        let g = group.into_op(&md).await?;
        let to_op = (t_op.elapsed(), host.clock().now() - sim_op);
        let mut wkc = 0;
        for k in 0..10u8 {
            for i in 1..n {
                let sd = g.subdevice(&md, i)?;
                for (j, b) in sd.outputs_raw_mut().iter_mut().enumerate() {
                    *b = (i as u8) ^ k ^ (j as u8);
                }
            }
            recording.store(k == 9, std::sync::atomic::Ordering::Release);
            wkc = g.tx_rx(&md).await?.working_counter;
            host.advance(Duration::from_millis(1));
        }
        Ok::<_, ethercrab::error::Error>((names, to_op, wkc))
    });
    let (names, (wall_op, sim_op), wkc) = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("ethercrab did not bring the line to OP: {e}");
            return 1;
        }
    };
    // Every terminal has the last pattern the master wrote.
    for i in 1..n {
        let got = described::with_device(&host, i, |s| s.app().outputs().to_vec()).expect("device");
        let want: Vec<u8> = (0..out_bytes(i)).map(|j| (i as u8) ^ 9 ^ (j as u8)).collect();
        if got[..want.len().min(got.len())] != want[..want.len().min(got.len())] {
            eprintln!("slave {i}: outputs {got:02X?}, the master wrote {want:02X?}");
            return 1;
        }
    }
    let frames = frames.lock().expect("frames").clone();
    // An LRW writing a slave's outputs counts 2 (ETG.1000.4 §5.4.3.5).
    let expected = 2 * (n as u16 - 1);
    if wkc != expected {
        eprintln!("working counter {wkc}, expected {expected}");
        return 1;
    }
    if std::env::var_os("IO_LINE_FRAMES").is_some() {
        for f in &frames {
            eprintln!("frame {} B: datagrams {:?}", f.len(), replay::datagrams(f));
        }
    }
    let (cpu0, wall0) = (thread_cpu_ns(), std::time::Instant::now());
    let bad = run_cycles(&host, &frames, expected, cycles);
    let (cpu, wall) = (thread_cpu_ns() - cpu0, wall0.elapsed());
    println!(
        "slaves={n} first={names:?} build_ms={:.1} to_op_wall_ms={:.0} to_op_simulated_ms={:.0} frames_per_cycle={} \
         cycles={cycles} bad_wkc={bad} cpu_per_cycle_us={:.1} wall_per_cycle_us={:.1}",
        build.as_secs_f64() * 1e3,
        wall_op.as_secs_f64() * 1e3,
        sim_op.as_secs_f64() * 1e3,
        frames.len(),
        cpu as f64 / 1e3 / f64::from(cycles),
        wall.as_secs_f64() * 1e6 / f64::from(cycles),
    );
    i32::from(bad != 0)
}

/// The measured loop (not inlined, so callgrind can collect it alone).
#[inline(never)]
fn run_cycles(host: &Host, frames: &[Vec<u8>], expected: u16, cycles: u32) -> u32 {
    let mut buf = vec![0u8; 1600];
    (0..cycles).filter(|_| replay::cycle(host, frames, &mut buf) != expected).count() as u32
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
