//! A test rig for the personality replays: one [`PersonalityDevice`] built by
//! `drivebus_personality::build` and a probe on a zero-time virtual bus,
//! frames written candump-style (`603#2F 60 60 00 03 00 00 00`).
#![allow(dead_code)]

pub mod kollmorgen;
pub mod trace;

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Duration, Frame, Instant};
use drivebus_node::Node;
use drivebus_personality::{PersonalityDevice, Profile};

pub use trace::fr;

/// Frames from strings.
pub fn frs(list: &[&str]) -> Vec<Frame> {
    list.iter().map(|s| fr(s)).collect()
}

/// One printed step: a request and the responses in bus order.
pub type Step<'a> = (&'a str, &'a [&'a str]);

/// The device under test and a probe.
pub struct Rig {
    pub bus: Bus,
    pub probe: ProbeId,
    pub dut: NodeId,
}

impl Rig {
    /// `profile` built as node `id` through the personality framework,
    /// booted; the boot-up frame (and whatever else the personality sends
    /// at power-on) is returned by [`Rig::boot_frames`] once.
    pub fn new(profile: Profile, id: u8) -> (Rig, Vec<Frame>) {
        Self::with(profile.build(id).expect("build"))
    }

    /// A built node on a fresh bus.
    pub fn with(node: PersonalityDevice) -> (Rig, Vec<Frame>) {
        let mut bus = Bus::new(BusConfig::zero_time());
        let probe = bus.attach_probe();
        let dut = bus.attach(node);
        bus.run_for(Duration::from_millis(1));
        let mut rig = Rig { bus, probe, dut };
        let boot = rig.take();
        (rig, boot)
    }

    pub fn pn(&self) -> &PersonalityDevice {
        self.bus.node::<PersonalityDevice>(self.dut).expect("dut")
    }

    pub fn pn_mut(&mut self) -> &mut PersonalityDevice {
        self.bus.node_mut::<PersonalityDevice>(self.dut).expect("dut")
    }

    pub fn node(&self) -> &Node {
        &self.pn().node
    }

    pub fn now(&self) -> Instant {
        self.bus.now()
    }

    /// Send from the probe and let the bus settle for 1 µs.
    pub fn send(&mut self, f: &str) {
        self.bus.send_from(self.probe, fr(f));
        self.bus.run_for(Duration::from_micros(1));
    }

    /// Everything the probe received since the last call.
    pub fn take(&mut self) -> Vec<Frame> {
        self.bus.take_received(self.probe)
    }

    /// Send `req`, expect exactly `resp` within 1 µs.
    pub fn exchange(&mut self, req: &str, resp: &[&str]) {
        self.take();
        self.send(req);
        assert_eq!(self.take(), frs(resp), "after {req}");
    }

    /// Send `req`, let `ms` of simulated time pass, expect exactly `resp`
    /// (the drive's reactions: TPDOs of a changed statusword).
    pub fn exchange_ms(&mut self, req: &str, ms: u64, resp: &[&str]) {
        self.take();
        self.send(req);
        self.run_ms(ms);
        assert_eq!(self.take(), frs(resp), "after {req} and {ms} ms");
    }

    pub fn run_ms(&mut self, ms: u64) {
        self.bus.run_for(Duration::from_millis(ms));
    }

    pub fn run_for(&mut self, d: Duration) {
        self.bus.run_for(d);
    }

    /// Expedited download; returns the single response.
    pub fn sdo_write(&mut self, node: u8, index: u16, sub: u8, data: &[u8]) -> Frame {
        assert!((1..=4).contains(&data.len()));
        let cmd = 0x23 | ((4 - data.len() as u8) << 2);
        let mut b = [cmd, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
        b[4..4 + data.len()].copy_from_slice(data);
        self.take();
        self.bus.send_from(self.probe, Frame::new(0x600 + node as u16, &b));
        self.bus.run_for(Duration::from_micros(1));
        let r: Vec<Frame> =
            self.take().into_iter().filter(|f| f.std_id() == Some(0x580 + node as u16)).collect();
        assert_eq!(r.len(), 1, "one SDO response: {r:?}");
        r[0]
    }

    /// Expedited upload; returns the response.
    pub fn sdo_read(&mut self, node: u8, index: u16, sub: u8) -> Frame {
        self.take();
        self.bus.send_from(
            self.probe,
            Frame::new(0x600 + node as u16, &[0x40, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0]),
        );
        self.bus.run_for(Duration::from_micros(1));
        let r: Vec<Frame> =
            self.take().into_iter().filter(|f| f.std_id() == Some(0x580 + node as u16)).collect();
        assert_eq!(r.len(), 1, "one SDO response: {r:?}");
        r[0]
    }

    /// An expedited upload's value (little-endian, up to 4 bytes).
    pub fn read_u32(&mut self, node: u8, index: u16, sub: u8) -> u32 {
        let f = self.sdo_read(node, index, sub);
        let d = f.data();
        assert_eq!(d[0] & 0xF3, 0x43, "expedited upload of {index:04X}h:{sub}: {f:?}");
        u32::from_le_bytes([d[4], d[5], d[6], d[7]])
    }

    pub fn assert_abort(resp: Frame, node: u8, index: u16, sub: u8, code: u32) {
        let mut b = [0x80, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
        b[4..].copy_from_slice(&code.to_le_bytes());
        assert_eq!(resp, Frame::new(0x580 + node as u16, &b), "expected abort {code:08X}");
    }

    pub fn assert_written(resp: Frame, node: u8, index: u16, sub: u8) {
        assert_eq!(
            resp,
            Frame::new(0x580 + node as u16, &[0x60, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0])
        );
    }

    /// The statusword the drive publishes (6041h).
    pub fn statusword(&self) -> u16 {
        self.node().od().get_u32(0x6041, 0).map(|v| v as u16).unwrap_or(0)
    }

    /// 6064h position actual value.
    pub fn position(&self) -> i32 {
        self.node().od().get_i64(0x6064, 0).unwrap_or(0) as i32
    }

    /// 606Ch velocity actual value.
    pub fn velocity(&self) -> i32 {
        self.node().od().get_i64(0x606C, 0).unwrap_or(0) as i32
    }
}

/// Replay `steps` exactly, in order (1 µs after each request).
pub fn replay(r: &mut Rig, steps: &[Step<'_>]) {
    for (req, resp) in steps {
        r.exchange(req, resp);
    }
}

/// `f` in the form of the printed `|form` frame `l`: its COB-ID and length
/// (the values are those of the manual's machine).
pub fn assert_form(f: &Frame, l: trace::Line) {
    assert!(l.form(), "{l:?} is not marked `form`");
    assert_eq!((f.std_id(), f.len()), (Some(l.id()), l.dlc()), "in form: {l:?}");
}
