//! A test rig for the personality replays: one [`PersonalityDevice`] built by
//! `drivebus_personality::build` and a probe on a zero-time virtual bus,
//! frames written candump-style (`603#2F 60 60 00 03 00 00 00`).
#![allow(dead_code)]

pub mod kc_objects;
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

    /// One SDO request to `node`, exactly one response from it.
    fn sdo_exchange(&mut self, node: u8, data: [u8; 8]) -> Frame {
        self.take();
        self.bus.send_from(self.probe, Frame::new(0x600 + node as u16, &data));
        self.bus.run_for(Duration::from_micros(1));
        let r: Vec<Frame> =
            self.take().into_iter().filter(|f| f.std_id() == Some(0x580 + node as u16)).collect();
        assert_eq!(r.len(), 1, "one SDO response: {r:?}");
        r[0]
    }

    /// SDO upload (CiA 301 §7.2.4.3.3–8), expedited or segmented: the
    /// value, or the abort code.
    pub fn upload(&mut self, node: u8, index: u16, sub: u8) -> Result<Vec<u8>, u32> {
        let [il, ih] = index.to_le_bytes();
        let d = *self.sdo_exchange(node, [0x40, il, ih, sub, 0, 0, 0, 0]).raw_data();
        let abort = |d: &[u8; 8]| u32::from_le_bytes([d[4], d[5], d[6], d[7]]);
        match d[0] & 0xE0 {
            0x80 => return Err(abort(&d)),
            0x40 => {}
            _ => panic!("upload of {index:04X}h:{sub}: {d:02X?}"),
        }
        if d[0] & 0x02 != 0 {
            let n = if d[0] & 1 != 0 { 4 - usize::from((d[0] >> 2) & 3) } else { 4 };
            return Ok(d[4..4 + n].to_vec());
        }
        let size = (d[0] & 1 != 0).then(|| abort(&d) as usize);
        let mut data = Vec::new();
        let mut toggle = 0u8;
        loop {
            let s = *self.sdo_exchange(node, [0x60 | toggle << 4, 0, 0, 0, 0, 0, 0, 0]).raw_data();
            if s[0] == 0x80 {
                return Err(abort(&s));
            }
            assert_eq!(s[0] & 0xF0, toggle << 4, "segment toggle of {index:04X}h:{sub}: {s:02X?}");
            let n = 7 - usize::from((s[0] >> 1) & 7);
            data.extend_from_slice(&s[1..1 + n]);
            if s[0] & 1 != 0 {
                break;
            }
            toggle ^= 1;
        }
        if let Some(size) = size {
            assert_eq!(data.len(), size, "size of {index:04X}h:{sub}");
        }
        Ok(data)
    }

    /// SDO download, expedited up to 4 bytes, segmented above: `Ok` on
    /// the confirmation, else the abort code.
    pub fn download(&mut self, node: u8, index: u16, sub: u8, value: &[u8]) -> Result<(), u32> {
        let [il, ih] = index.to_le_bytes();
        let abort = |d: &[u8; 8]| Err(u32::from_le_bytes([d[4], d[5], d[6], d[7]]));
        if (1..=4).contains(&value.len()) {
            let mut b = [0x23 | ((4 - value.len() as u8) << 2), il, ih, sub, 0, 0, 0, 0];
            b[4..4 + value.len()].copy_from_slice(value);
            let d = *self.sdo_exchange(node, b).raw_data();
            return if d[0] == 0x60 { Ok(()) } else { abort(&d) };
        }
        let [s0, s1, s2, s3] = (value.len() as u32).to_le_bytes();
        let d = *self.sdo_exchange(node, [0x21, il, ih, sub, s0, s1, s2, s3]).raw_data();
        if d[0] != 0x60 {
            return abort(&d);
        }
        let mut toggle = 0u8;
        let mut chunks = value.chunks(7).peekable();
        if value.is_empty() {
            let d = *self.sdo_exchange(node, [0x0F, 0, 0, 0, 0, 0, 0, 0]).raw_data();
            return if d[0] == 0x20 { Ok(()) } else { abort(&d) };
        }
        while let Some(c) = chunks.next() {
            let last = chunks.peek().is_none();
            let mut b = [0u8; 8];
            b[0] = toggle << 4 | ((7 - c.len() as u8) << 1) | u8::from(last);
            b[1..1 + c.len()].copy_from_slice(c);
            let d = *self.sdo_exchange(node, b).raw_data();
            if d[0] != 0x20 | toggle << 4 {
                return abort(&d);
            }
            toggle ^= 1;
        }
        Ok(())
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
