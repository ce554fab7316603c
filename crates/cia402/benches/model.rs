//! Cost of one model step at the control rate (servo with cascaded loops
//! following a CSP-like ramp; stepper in open loop). Target: well under
//! ~500 ns so ≥ 256 drives run in real time at 8 kHz on one core.
//!
//! `cargo bench -p drivebus-cia402 --bench model`

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use drivebus_cia402::model::{Demand, DriveModel, DriveParams};
use std::hint::black_box;

fn bench_step(c: &mut Criterion, name: &str, params: DriveParams) {
    let mut m = DriveModel::new(params).unwrap();
    let dt = m.params().control_period();
    let mut t = 0.0f64;
    c.bench_function(name, |b| {
        b.iter(|| {
            t += dt;
            // A slow sinusoid keeps every loop and the index detection busy
            // without ever running away.
            let pos = 20.0 * (t * 0.5).sin();
            m.set_demand(Demand::Position {
                position: pos,
                velocity: 10.0 * (t * 0.5).cos(),
                acceleration: 0.0,
            });
            black_box(m.step(black_box(dt)).len())
        })
    });
}

fn model(c: &mut Criterion) {
    bench_step(c, "servo_small step (8 kHz, position loop)", DriveParams::servo_small());
    bench_step(c, "stepper step (4 kHz, open loop)", DriveParams::stepper());
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2))
        .sample_size(20);
    targets = model
}
criterion_main!(benches);
