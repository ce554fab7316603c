//! Conformance-style cases, category TIME (CiA 301 §7.2.6).

mod common;
use common::*;
use drivebus_can::Duration;
use drivebus_sync::TimeOfDay;

#[test]
fn time_01_producer_only_when_configured() {
    let mut r = Rig::new(device());
    let stamp = TimeOfDay { ms: 0x0123_4567, days: 0x2A };
    let mut out = Vec::new();
    // 1012h default: neither producer nor consumer.
    assert!(!r.node_mut().send_time(stamp, &mut out));
    Rig::assert_written(r.sdo_write(5, 0x1012, 0, &0x4000_0100u32.to_le_bytes()), 5, 0x1012, 0);
    assert!(r.node_mut().send_time(stamp, &mut out));
    assert_eq!(out, frs(&["100#674523012A00"]));
    // Not in stopped.
    r.send("000#0205");
    out.clear();
    assert!(!r.node_mut().send_time(stamp, &mut out));
}

#[test]
fn time_02_consumer_accepts_only_six_byte_stamps() {
    let mut r = Rig::new(device());
    Rig::assert_written(r.sdo_write(5, 0x1012, 0, &0x8000_0100u32.to_le_bytes()), 5, 0x1012, 0);
    // A consumer is silent on the bus; a malformed stamp must not disturb it.
    r.exchange("100#67452301", &[]);
    r.exchange("100#6745230100002A00", &[]);
    r.exchange("100#674523012A00", &[]);
    r.run_for(Duration::from_millis(10));
    r.exchange("605#4000100000000000", &["585#4300100092010200"]);
}

#[derive(Default)]
struct Recorder(Vec<drivebus_node::NodeEvent>);
impl drivebus_node::Application for Recorder {
    fn on_event(&mut self, _: &mut drivebus_node::AppContext<'_>, e: drivebus_node::NodeEvent) {
        self.0.push(e);
    }
}

#[test]
fn time_03_consumer_delivers_the_stamp_to_the_application() {
    use drivebus_can::{Frame, Instant};
    let mut node = drivebus_node::Node::new(device());
    let mut app = Recorder::default();
    let mut out = Vec::new();
    node.boot(Instant::ZERO, &mut app, &mut out);
    let t = Instant::from_millis(1);
    node.handle_frame(&Frame::new(0x605, &[0x23, 0x12, 0x10, 0, 0x00, 0x01, 0, 0x80]), t, &mut app, &mut out);
    node.handle_frame(&Frame::new(0x100, &[0x67, 0x45, 0x23, 0x01, 0x2A, 0x00, 0, 0]), t, &mut app, &mut out);
    node.handle_frame(&Frame::new(0x100, &[0x67, 0x45, 0x23, 0x01, 0x2A, 0x00]), t, &mut app, &mut out);
    let stamps: Vec<_> = app
        .0
        .iter()
        .filter_map(|e| if let drivebus_node::NodeEvent::Time(t) = e { Some(*t) } else { None })
        .collect();
    assert_eq!(stamps, vec![TimeOfDay { ms: 0x0123_4567, days: 0x2A }]);
}
