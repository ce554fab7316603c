//! Block SDO on a bit-timed 1 Mbit/s virtual bus: how close our client and
//! server come to the bus limit (the wire time of the same frames sent back
//! to back). Simulated time, so the figure is exact and repeatable.
//!
//! `cargo test -p drivebus-node --test bus_efficiency -- --nocapture`
//! prints the figures recorded in BENCHMARKS.md.

use drivebus_bus::{Bus, BusConfig};
use drivebus_can::{Device, Duration, Frame, Instant, TxSink};
use drivebus_node::{Node, NodeConfig, NodeDevice};
use drivebus_od::{Access, DataType, NoHooks, Object, Value};
use drivebus_sdo::client::{Completed, Protocol, SdoClient, SdoClientConfig};
use std::cell::RefCell;
use std::rc::Rc;

const LEN: usize = 10_240;

enum Job {
    Download(Vec<u8>),
    Upload,
}

/// The SDO client as a bus station; logs every frame it sees on the bus
/// so the test can price the whole exchange on the wire.
struct Master {
    client: SdoClient,
    job: Option<Job>,
    result: Rc<RefCell<Option<(Instant, Completed)>>>,
}

impl Device for Master {
    fn handle_frame(&mut self, frame: &Frame, now: Instant, mut out: &mut dyn TxSink) {
        self.client.handle_frame(frame, now, &mut out);
        if let Some(r) = self.client.take_result() {
            *self.result.borrow_mut() = Some((now, r.expect("transfer succeeds")));
        }
    }
    fn poll(&mut self, now: Instant, mut out: &mut dyn TxSink) -> Option<Instant> {
        match self.job.take() {
            Some(Job::Download(d)) => {
                self.client.start_download(0x2000, 0, &d, Protocol::Block, now, &mut out).unwrap()
            }
            Some(Job::Upload) => self.client.start_upload(0x2000, 0, Protocol::Block, now, &mut out).unwrap(),
            None => {}
        }
        self.client.poll(now, &mut out)
    }
    fn start(&mut self, _now: Instant, _out: &mut dyn TxSink) {}
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// Run one transfer; returns (payload bytes/s achieved, % of the wire limit).
fn run(job: Job) -> (f64, f64, usize) {
    let mut cfg = NodeConfig::new(5);
    cfg.sdo.max_download = 1 << 20;
    let mut node = Node::new(cfg);
    let blob: Vec<u8> = (0..LEN).map(|i| (i * 31 + 7) as u8).collect();
    node.insert_object(Object::var(0x2000, "Blob", DataType::Domain, Access::Rw, Value::Bytes(blob.clone())));
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    bus.attach(NodeDevice::new(node, NoHooks));
    bus.run_for(Duration::from_millis(1));
    let log_start = bus.log().len();
    let result = Rc::new(RefCell::new(None));
    let upload = matches!(job, Job::Upload);
    let t0 = bus.now();
    let master = Master {
        client: SdoClient::new(SdoClientConfig::for_node(5)),
        job: Some(job),
        result: result.clone(),
    };
    bus.attach(master);
    bus.run_for(Duration::from_secs(2));
    let (t_end, completed) = result.borrow_mut().take().expect("finished");
    if upload {
        assert_eq!(completed.into_data(), blob);
    }
    let frames: Vec<Frame> = bus.log()[log_start..].iter().map(|e| e.frame).collect();
    let wire_bits: u32 = frames.iter().map(|f| drivebus_bus::timing::frame_bits(f).total()).sum();
    let wire = drivebus_bus::timing::bits_duration(wire_bits, 1_000_000);
    let elapsed = t_end - t0;
    let rate = LEN as f64 / elapsed.as_secs_f64();
    (rate, 100.0 * wire.as_secs_f64() / elapsed.as_secs_f64(), frames.len())
}

#[test]
fn block_download_reaches_the_bus_limit() {
    let (rate, pct, frames) = run(Job::Download((0..LEN).map(|i| (i * 13) as u8).collect()));
    println!(
        "block download 10 KiB @1 Mbit/s: {frames} frames, {:.1} kB/s, {pct:.1} % of the bus limit",
        rate / 1e3
    );
    assert!(pct >= 95.0, "{pct:.1} %");
}

#[test]
fn block_upload_reaches_the_bus_limit() {
    let (rate, pct, frames) = run(Job::Upload);
    println!(
        "block upload 10 KiB @1 Mbit/s: {frames} frames, {:.1} kB/s, {pct:.1} % of the bus limit",
        rate / 1e3
    );
    assert!(pct >= 95.0, "{pct:.1} %");
}
