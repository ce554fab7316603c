//! Test rig for the drive tests: one `NodeDevice` (node + drive, or node +
//! an application wrapping the drive) and a probe on a zero-time virtual bus.
#![allow(dead_code)]

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Duration, Frame, Instant};
use drivebus_cia402::drive::{Drive, DriveConfig, generic_drive, generic_drive_with};
use drivebus_node::{Application, NodeDevice};

pub const ID: u8 = 5;

pub struct Rig<A: Application + 'static = Drive> {
    pub bus: Bus,
    pub probe: ProbeId,
    pub dut: NodeId,
    /// Frames other than SDO responses seen during SDO exchanges.
    stash: Vec<Frame>,
    app: core::marker::PhantomData<A>,
}

impl Rig<Drive> {
    /// The generic drive, booted, boot-up frame consumed.
    pub fn generic() -> Rig {
        Rig::with(generic_drive(ID))
    }

    pub fn with_config(cfg: DriveConfig) -> Rig {
        Rig::with(generic_drive_with(ID, cfg, Vec::new()))
    }

    pub fn drive(&self) -> &Drive {
        &self.dn().app
    }
    pub fn drive_mut(&mut self) -> &mut Drive {
        &mut self.dn_mut().app
    }
}

impl<A: Application + 'static> Rig<A> {
    pub fn with(dn: NodeDevice<A>) -> Rig<A> {
        let mut bus = Bus::new(BusConfig::zero_time());
        let probe = bus.attach_probe();
        let dut = bus.attach(dn);
        bus.run_for(Duration::from_micros(1));
        let mut rig = Rig { bus, probe, dut, stash: Vec::new(), app: core::marker::PhantomData };
        assert_eq!(rig.take(), vec![Frame::new(0x700 + ID as u16, &[0])], "boot-up");
        rig
    }

    pub fn dn(&self) -> &NodeDevice<A> {
        self.bus.node::<NodeDevice<A>>(self.dut).expect("dut")
    }
    pub fn dn_mut(&mut self) -> &mut NodeDevice<A> {
        self.bus.node_mut::<NodeDevice<A>>(self.dut).expect("dut")
    }
    pub fn now(&self) -> Instant {
        self.bus.now()
    }
    /// Everything received since the last call (SDO responses consumed by
    /// the SDO helpers excluded).
    pub fn take(&mut self) -> Vec<Frame> {
        let mut v = core::mem::take(&mut self.stash);
        v.extend(self.bus.take_received(self.probe));
        v
    }

    fn sdo_response(&mut self) -> Vec<Frame> {
        let (sdo, other): (Vec<Frame>, Vec<Frame>) = self
            .bus
            .take_received(self.probe)
            .into_iter()
            .partition(|f| f.std_id() == Some(0x580 + ID as u16));
        self.stash.extend(other);
        sdo
    }
    pub fn send(&mut self, f: Frame) {
        self.bus.send_from(self.probe, f);
        self.bus.run_for(Duration::from_micros(1));
    }
    pub fn run_ms(&mut self, ms: f64) {
        self.bus.run_for(Duration::from_nanos((ms * 1e6) as u64));
    }
    pub fn run_us(&mut self, us: u64) {
        self.bus.run_for(Duration::from_micros(us));
    }
    /// NMT start (operational).
    pub fn start(&mut self) {
        self.send(Frame::new(0x000, &[0x01, ID]));
        self.take();
    }

    /// Expedited SDO download; returns the response.
    pub fn sdo_write(&mut self, index: u16, sub: u8, data: &[u8]) -> Frame {
        let cmd = 0x23 | ((4 - data.len() as u8) << 2);
        let mut b = [cmd, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
        b[4..4 + data.len()].copy_from_slice(data);
        self.send(Frame::new(0x600 + ID as u16, &b));
        let r = self.sdo_response();
        assert_eq!(r.len(), 1, "one SDO response: {r:?}");
        r[0]
    }

    /// SDO download that must succeed.
    pub fn write(&mut self, index: u16, sub: u8, data: &[u8]) {
        let r = self.sdo_write(index, sub, data);
        assert_eq!(
            r,
            Frame::new(0x580 + ID as u16, &[0x60, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0]),
            "write {index:04X}:{sub}"
        );
    }

    /// SDO download that must abort with `code`.
    pub fn write_aborts(&mut self, index: u16, sub: u8, data: &[u8], code: u32) {
        let r = self.sdo_write(index, sub, data);
        let mut b = [0x80, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
        b[4..].copy_from_slice(&code.to_le_bytes());
        assert_eq!(r, Frame::new(0x580 + ID as u16, &b), "abort {code:08X} for {index:04X}:{sub}");
    }

    /// Expedited upload as a little-endian integer (zero-extended).
    pub fn read(&mut self, index: u16, sub: u8) -> u32 {
        self.send(Frame::new(0x600 + ID as u16, &[0x40, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0]));
        let r = self.sdo_response();
        assert_eq!(r.len(), 1, "one SDO response");
        let d = r[0].data();
        assert_eq!(d[0] & 0xE3, 0x43, "expedited upload response {:?}", r[0]);
        u32::from_le_bytes([d[4], d[5], d[6], d[7]])
    }

    pub fn statusword(&mut self) -> u16 {
        self.read(0x6041, 0) as u16
    }

    pub fn controlword(&mut self, cw: u16) {
        self.write(0x6040, 0, &cw.to_le_bytes());
    }

    /// Shutdown, switch on, enable operation.
    pub fn enable(&mut self) {
        self.controlword(0x06);
        self.controlword(0x07);
        self.controlword(0x0F);
    }

    /// Runs in steps of `step_us` until `pred` holds or `max_ms` passed;
    /// returns the elapsed time in seconds.
    pub fn run_until(
        &mut self,
        step_us: u64,
        max_ms: f64,
        mut pred: impl FnMut(&Rig<A>) -> bool,
    ) -> Option<f64> {
        let t0 = self.now();
        loop {
            if pred(self) {
                return Some((self.now() - t0).as_secs_f64());
            }
            if (self.now() - t0).as_secs_f64() * 1e3 > max_ms {
                return None;
            }
            self.run_us(step_us);
        }
    }

    /// EMCY frames (080h + id) received since the last take.
    pub fn emcys(&mut self) -> Vec<Frame> {
        self.take().into_iter().filter(|f| f.std_id() == Some(0x80 + ID as u16)).collect()
    }
}

/// The EMCY frame CiA 301 §7.2.7.3.1 defines: code, 1001h, 5 zero bytes.
pub fn emcy(code: u16, register: u8) -> Frame {
    Frame::new(0x80 + ID as u16, &[code as u8, (code >> 8) as u8, register, 0, 0, 0, 0, 0])
}
