//! One device contract, two hosts: the same devices on the deterministic
//! virtual bus (`drivebus_bus::Bus`) and on the real-time host over an
//! in-process hub answer a request script with the same frames.

use std::time::Duration;

use drivebus_bus::{Bus, BusConfig};
use drivebus_can::{Device, Frame, Instant, TxSink};
use drivebus_node::{Node, NodeConfig, NodeDevice};
use drivebus_od::{Access, DataType, NoHooks, Object, Value};
use drivebus_transport::host::{bridge, spawn};
use drivebus_transport::{CanBus, Hub};

/// A device that is not a CANopen node: counts SYNCs, answers each with a
/// TPDO carrying the count, says hello at start.
#[derive(Default)]
struct Counter(u8);

impl Device for Counter {
    fn start(&mut self, _: Instant, out: &mut dyn TxSink) {
        out.send(Frame::new(0x7AA, &[0xAA]));
    }
    fn handle_frame(&mut self, f: &Frame, _: Instant, out: &mut dyn TxSink) {
        if f.std_id() == Some(0x080) {
            self.0 = self.0.wrapping_add(1);
            out.send(Frame::new(0x1AA, &[self.0]));
        }
    }
    fn poll(&mut self, _: Instant, _: &mut dyn TxSink) -> Option<Instant> {
        None
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

fn node() -> NodeDevice {
    let mut cfg = NodeConfig::new(5);
    cfg.device_type = 0x0002_0192;
    let mut n = Node::new(cfg);
    n.insert_object(Object::var(0x2000, "x", DataType::Unsigned32, Access::Rw, Value::U32(7)));
    NodeDevice::new(n, NoHooks)
}

/// Requests that each get an immediate, timing-independent answer.
fn script() -> Vec<Frame> {
    vec![
        Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]),
        Frame::new(0x605, &[0x23, 0x00, 0x20, 0, 0x78, 0x56, 0x34, 0x12]),
        Frame::new(0x605, &[0x40, 0x00, 0x20, 0, 0, 0, 0, 0]),
        Frame::new(0x605, &[0x2B, 0x00, 0x10, 0, 0, 0, 0, 0]),
        Frame::new(0x080, &[]),
        Frame::new(0x000, &[0x01, 0x05]),
        Frame::new(0x080, &[]),
        Frame::new(0x605, &[0x40, 0x18, 0x10, 1, 0, 0, 0, 0]),
    ]
}

/// The frames after start and after each request, on the virtual bus.
fn on_the_virtual_bus() -> Vec<Vec<Frame>> {
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    bus.attach(node());
    bus.attach(Counter::default());
    let probe = bus.attach_probe();
    bus.run_for(drivebus_can::Duration::from_millis(1));
    let mut got = vec![bus.take_received(probe)];
    for f in script() {
        bus.send_from(probe, f);
        bus.run_for(drivebus_can::Duration::from_millis(1));
        got.push(bus.take_received(probe));
    }
    got
}

/// What `port` receives until it has been quiet for 50 ms.
async fn quiet(port: &mut CanBus) -> Vec<Frame> {
    let mut v = Vec::new();
    while let Ok(Ok(f)) = tokio::time::timeout(Duration::from_millis(50), port.recv()).await {
        v.push(f);
    }
    v
}

/// The same on the real-time host, each device its own hub participant.
async fn on_the_real_time_host(hub: &Hub, mut port: CanBus) -> Vec<Vec<Frame>> {
    let a = spawn(node(), hub.attach());
    let b = spawn(Counter::default(), hub.attach());
    let mut got = vec![quiet(&mut port).await];
    for f in script() {
        port.send(f).await.unwrap();
        got.push(quiet(&mut port).await);
    }
    a.stop();
    b.stop();
    got
}

/// Order between the two devices' answers is arbitration on the bus and
/// scheduling on the host: compare each step as a sorted set.
fn sorted(mut steps: Vec<Vec<Frame>>) -> Vec<Vec<Frame>> {
    for s in &mut steps {
        s.sort_by_key(|f| (f.id().arbitration_key(), f.data().to_vec()));
    }
    steps
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_same_devices_answer_alike_on_both_hosts() {
    let want = on_the_virtual_bus();
    assert_eq!(want[0], [Frame::new(0x705, &[0]), Frame::new(0x7AA, &[0xAA])], "start");
    assert_eq!(want[5], [Frame::new(0x1AA, &[1])], "a SYNC before operational: the counter only");
    let hub = Hub::default();
    let port = hub.attach();
    let got = tokio::time::timeout(Duration::from_secs(20), on_the_real_time_host(&hub, port)).await.unwrap();
    assert_eq!(sorted(got), sorted(want));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn devices_on_a_hub_bridged_to_another_bus() {
    // The "real" bus is a second hub: a station there talks to the device
    // hosted on the first hub through the bridge.
    let (outer, inner) = (Hub::default(), Hub::default());
    let mut station = outer.attach();
    let _bridge = bridge(&inner, outer.attach());
    let dev = spawn(node(), inner.attach());
    let boot = tokio::time::timeout(Duration::from_secs(5), station.recv()).await.unwrap().unwrap();
    assert_eq!(boot, Frame::new(0x705, &[0]));
    station.send(script()[0]).await.unwrap();
    let r = tokio::time::timeout(Duration::from_secs(5), station.recv()).await.unwrap().unwrap();
    assert_eq!(r, Frame::new(0x585, &[0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00]));
    dev.stop();
}
