//! Builds `N` drives of one profile (default: 200 `generic` drives) and
//! prints the mean time per build: the loop to profile the cost of
//! building a node (issue 11 §5) with
//! `valgrind --tool=callgrind target/release/examples/build_many generic 20`.

use drivebus_personality::Profile;
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let profile = args.next().map_or(Some(Profile::Generic), |n| Profile::from_name(&n));
    let Some(profile) = profile else {
        eprintln!("usage: build_many [PROFILE] [N]");
        std::process::exit(2);
    };
    let n: u32 = args.next().and_then(|s| s.parse().ok()).unwrap_or(200);
    let start = Instant::now();
    for i in 0..n {
        let d = profile.build(1 + (i % 127) as u8).expect("profile builds");
        std::hint::black_box(d);
    }
    let per = start.elapsed() / n.max(1);
    println!("{profile}: {n} builds, {per:?} per build");
}
