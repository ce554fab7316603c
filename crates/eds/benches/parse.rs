//! Reading the shipped EDS files (issue 11 §5): `parse` alone, and
//! `parse` + `to_od` (what building a drive from its EDS costs).
//!
//! `cargo bench -p drivebus-eds --bench parse -- --warm-up-time 1 --measurement-time 3`
// criterion's macros generate undocumented items.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// The personalities' EDS files (`crates/personality/eds/`); read here
/// directly, since `drivebus-personality` depends on this crate.
const FILES: [(&str, &str); 6] = [
    ("kc1", include_str!("../../personality/eds/kc1.eds")),
    ("akd", include_str!("../../personality/eds/akd.eds")),
    ("ipos", include_str!("../../personality/eds/ipos.eds")),
    ("ssd630", include_str!("../../personality/eds/ssd630.eds")),
    ("dds6", include_str!("../../personality/eds/dds6.eds")),
    ("generic", include_str!("../../personality/eds/generic.eds")),
];

fn parse(c: &mut Criterion) {
    let mut g = c.benchmark_group("eds");
    for (name, text) in FILES {
        g.bench_with_input(BenchmarkId::new("parse", name), text, |b, t| {
            b.iter(|| black_box(drivebus_eds::parse(black_box(t)).unwrap()))
        });
        let parsed = drivebus_eds::parse(text).unwrap();
        g.bench_with_input(BenchmarkId::new("to_od", name), &parsed.eds, |b, e| {
            b.iter(|| black_box(drivebus_eds::to_od(black_box(e), 5).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, parse);
criterion_main!(benches);
