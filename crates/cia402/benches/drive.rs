//! One whole drive (node + CiA 402 drive + motor model) per 1 ms SYNC cycle,
//! position following at 8 kHz: an RPDO with controlword and target
//! position, the SYNC (synchronous TPDOs 2–4 sampled and sent), then eight
//! control periods. Reports ns per drive per cycle; 1 ms divided by it is
//! how many drives one core simulates in real time (target ≥ 256).
//!
//! `cargo bench -p drivebus-cia402 --bench drive`

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use drivebus_can::{Duration, Frame, Instant};
use drivebus_cia402::drive::{Drive, DriveConfig, generic_drive, generic_drive_with};
use drivebus_cia402::interp::CspMode;
use drivebus_node::NodeDevice;
use std::hint::black_box;

const ID: u8 = 1;

/// A booted, operational, enabled drive in `mode` at `t`.
fn station(mut dn: NodeDevice<Drive>, mode: u8, out: &mut Vec<Frame>) -> Instant {
    let mut t = Instant::ZERO;
    dn.node.boot(t, &mut dn.app, out);
    dn_poll(&mut dn, t, out);
    let sdo = |dn: &mut NodeDevice<Drive>, t, out: &mut Vec<Frame>, idx: u16, data: &[u8]| {
        let mut b = [0x2F - 4 * (data.len() as u8 - 1), idx as u8, (idx >> 8) as u8, 0, 0, 0, 0, 0];
        b[4..4 + data.len()].copy_from_slice(data);
        frame(dn, &Frame::new(0x600 + u16::from(ID), &b), t, out);
    };
    frame(&mut dn, &Frame::new(0x000, &[0x01, ID]), t, out);
    sdo(&mut dn, t, out, 0x6060, &[mode]);
    for cw in [0x06u16, 0x0F] {
        frame(&mut dn, &Frame::new(0x200 + u16::from(ID), &cw.to_le_bytes()), t, out);
    }
    t += Duration::from_millis(1);
    dn_poll(&mut dn, t, out);
    out.clear();
    STATION.with(|s| *s.borrow_mut() = Some(dn));
    t
}

thread_local! {
    static STATION: std::cell::RefCell<Option<NodeDevice<Drive>>> = const { std::cell::RefCell::new(None) };
}

/// A received frame, through the node's generic (monomorphised) path.
fn frame(dn: &mut NodeDevice<Drive>, f: &Frame, t: Instant, out: &mut Vec<Frame>) {
    dn.node.handle_frame(f, t, &mut dn.app, out);
}

fn dn_poll(dn: &mut NodeDevice<Drive>, t: Instant, out: &mut Vec<Frame>) {
    dn.node.poll(t, &mut dn.app, out);
}

fn bench_mode(c: &mut Criterion, name: &str, dn: NodeDevice<Drive>, mode: u8, pp: bool) {
    let mut out = Vec::with_capacity(64);
    let mut t = station(dn, mode, &mut out);
    let mut dn = STATION.with(|s| s.borrow_mut().take()).expect("station");
    let mut k = 0u64;
    let rpdo2 = 0x300 + u16::from(ID);
    let sync = Frame::new(0x080, &[]);
    c.bench_function(name, |b| {
        b.iter(|| {
            k += 1;
            // A slow sinusoid (±90°, 0.5 Hz) in 0.001° units.
            let target = (90_000.0 * (k as f64 * 1e-3 * std::f64::consts::PI).sin()) as i32;
            // pp: a new set-point each cycle with "change immediately";
            // csp: the target is taken at SYNC.
            let cw: u16 = if pp { if k.is_multiple_of(2) { 0x3F } else { 0x2F } } else { 0x0F };
            let mut d = [0u8; 6];
            d[..2].copy_from_slice(&cw.to_le_bytes());
            d[2..].copy_from_slice(&target.to_le_bytes());
            frame(&mut dn, &Frame::new(rpdo2, &d), t, &mut out);
            frame(&mut dn, &sync, t, &mut out);
            t += Duration::from_millis(1);
            dn_poll(&mut dn, t, &mut out);
            black_box(out.len());
            out.clear();
        })
    });
    // Eight control periods per 1 ms cycle actually ran.
    assert!(dn.app.steps() >= 8 * k, "{name}: {} steps for {k} cycles", dn.app.steps());
    let sw = dn.app.statusword();
    assert_eq!(sw & 0x6F, 0x27, "{name}: still operation enabled ({sw:04X})");
}

fn drive(c: &mut Criterion) {
    bench_mode(c, "drive 1 ms cycle, pp set-point per SYNC (8 kHz)", generic_drive(ID), 1, true);
    let csp = generic_drive_with(ID, DriveConfig::default(), vec![Box::new(CspMode::new())]);
    bench_mode(c, "drive 1 ms cycle, csp (8 kHz)", csp, 8, false);
}

criterion_group! {
    name = benches;
    config = Criterion::default().measurement_time(std::time::Duration::from_secs(5));
    targets = drive
}
criterion_main!(benches);
