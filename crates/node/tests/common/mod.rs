//! A test rig: one device under test and a probe on a zero-time virtual
//! bus, with frames written candump-style (`605#4000100000000000`).
#![allow(dead_code)]

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Duration, Frame, Instant};
use drivebus_node::{Node, NodeConfig, NodeDevice};
use drivebus_od::NoHooks;

/// The candump-style frame parser shared with the manual traces.
#[path = "../../../personality/tests/replay_rig/trace.rs"]
pub mod trace;
pub use trace::fr;

/// Frames from a list of strings.
pub fn frs(list: &[&str]) -> Vec<Frame> {
    list.iter().map(|s| fr(s)).collect()
}

pub struct Rig {
    pub bus: Bus,
    pub probe: ProbeId,
    pub dut: NodeId,
}

impl Rig {
    /// A device built from `cfg`, booted, with the boot-up frame consumed
    /// (and checked).
    pub fn new(cfg: NodeConfig) -> Rig {
        Rig::with_node(Node::new(cfg))
    }

    pub fn with_node(node: Node) -> Rig {
        let id = node.node_id();
        let mut bus = Bus::new(BusConfig::zero_time());
        let probe = bus.attach_probe();
        let dut = bus.attach(NodeDevice::new(node, NoHooks));
        bus.run_for(Duration::from_micros(1));
        let mut rig = Rig { bus, probe, dut };
        if (1..=127).contains(&id) {
            assert_eq!(rig.take(), vec![Frame::new(0x700 + id as u16, &[0])], "boot-up");
        }
        rig
    }

    pub fn node(&self) -> &Node {
        &self.bus.node::<NodeDevice>(self.dut).expect("dut").node
    }

    pub fn node_mut(&mut self) -> &mut Node {
        &mut self.bus.node_mut::<NodeDevice>(self.dut).expect("dut").node
    }

    /// Raise an EMCY in the device (as its application would) and let it go out.
    pub fn raise_emcy(&mut self, code: u16, mfr: [u8; 5]) {
        let now = self.now();
        self.node_mut().raise_emcy(code, mfr, now);
        self.bus.wake(self.dut);
        self.bus.run_for(Duration::from_nanos(1));
    }

    pub fn clear_emcy(&mut self, code: u16) {
        let now = self.now();
        self.node_mut().clear_emcy(code, now);
        self.bus.wake(self.dut);
        self.bus.run_for(Duration::from_micros(1));
    }

    pub fn now(&self) -> Instant {
        self.bus.now()
    }

    /// Send from the probe and let the bus settle (1 µs of simulated time).
    pub fn send(&mut self, f: &str) {
        self.bus.send_from(self.probe, fr(f));
        self.bus.run_for(Duration::from_micros(1));
    }

    /// Everything the probe received since the last call.
    pub fn take(&mut self) -> Vec<Frame> {
        self.bus.take_received(self.probe)
    }

    /// Send `req`, expect exactly `resp` (empty: silence).
    pub fn exchange(&mut self, req: &str, resp: &[&str]) {
        self.take();
        self.send(req);
        assert_eq!(self.take(), frs(resp), "after {req}");
    }

    pub fn run_for(&mut self, d: Duration) {
        self.bus.run_for(d);
    }

    /// Received frames with their times, relative to `t0`, in ms.
    pub fn take_timed_ms(&mut self, t0: Instant) -> Vec<(f64, Frame)> {
        self.bus
            .take_received_timed(self.probe)
            .into_iter()
            .map(|(t, f)| ((t - t0).as_secs_f64() * 1e3, f))
            .collect()
    }

    /// Expedited SDO download of `data` (1..=4 bytes) to node 5-style ids; returns the response.
    pub fn sdo_write(&mut self, node: u8, index: u16, sub: u8, data: &[u8]) -> Frame {
        assert!((1..=4).contains(&data.len()));
        let cmd = 0x23 | ((4 - data.len() as u8) << 2);
        let mut b = [cmd, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
        b[4..4 + data.len()].copy_from_slice(data);
        self.take();
        self.bus.send_from(self.probe, Frame::new(0x600 + node as u16, &b));
        self.bus.run_for(Duration::from_micros(1));
        let r = self.take();
        assert_eq!(r.len(), 1, "one SDO response: {r:?}");
        r[0]
    }

    /// Expedited upload; returns the response frame.
    pub fn sdo_read(&mut self, node: u8, index: u16, sub: u8) -> Frame {
        self.take();
        self.bus.send_from(
            self.probe,
            Frame::new(0x600 + node as u16, &[0x40, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0]),
        );
        self.bus.run_for(Duration::from_micros(1));
        let r = self.take();
        assert_eq!(r.len(), 1, "one SDO response: {r:?}");
        r[0]
    }

    /// Expect an SDO abort with `code` for (index, sub) from `node`.
    pub fn assert_abort(resp: Frame, node: u8, index: u16, sub: u8, code: u32) {
        let mut b = [0x80, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
        b[4..].copy_from_slice(&code.to_le_bytes());
        assert_eq!(resp, Frame::new(0x580 + node as u16, &b), "expected abort {code:08X}");
    }

    /// Expect a download confirmation.
    pub fn assert_written(resp: Frame, node: u8, index: u16, sub: u8) {
        assert_eq!(
            resp,
            Frame::new(0x580 + node as u16, &[0x60, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0])
        );
    }
}

/// The default conformance device: node 5, generic CiA 301 config.
pub fn device() -> NodeConfig {
    let mut c = NodeConfig::new(5);
    c.device_type = 0x0002_0192;
    c.identity = drivebus_node::Identity {
        vendor_id: 0x0000_0ABC,
        product_code: 0x1234,
        revision: 0x0001_0000,
        serial: 42,
    };
    c.device_name = Some("drivebus test".into());
    c
}
