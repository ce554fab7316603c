//! The cost of building a node (issue 11 §5): each profile's drive from
//! its shipped EDS and the code (`Profile::build`), and a bare CiA 301
//! node (`Node::new`) for comparison.
//!
//! `cargo bench -p drivebus-personality --bench build -- --warm-up-time 1 --measurement-time 3`
// criterion's macros generate undocumented items.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use drivebus_node::{Node, NodeConfig};
use drivebus_personality::Profile;
use std::hint::black_box;

fn build(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    for &p in Profile::all() {
        g.bench_with_input(BenchmarkId::new("drive", p.name()), &p, |b, &p| {
            b.iter(|| black_box(p.build(black_box(5)).unwrap()))
        });
    }
    g.bench_function("bare node", |b| b.iter(|| black_box(Node::new(NodeConfig::new(black_box(5))))));
    g.finish();
}

criterion_group!(benches, build);
criterion_main!(benches);
