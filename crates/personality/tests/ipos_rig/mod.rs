//! Shared rig of the iPOS motion replays (`replay_ipos_motion.rs`,
//! `replay_ipos_cyclic.rs`): the examples' machine, units and the CAN
//! counterparts of the EtherCAT steps (see `replay_ipos_motion.rs`).
#![allow(dead_code)]

pub use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
pub use drivebus_can::{Duration, Frame};
pub use drivebus_cia402::drive::DriveConfig;
use drivebus_node::MemoryStorage;
pub use drivebus_personality::ipos::Ipos;
pub use drivebus_personality::{PersonalityDevice, Profile, build_custom};

/// Encoder counts per motor revolution: a 500-line quadrature encoder
/// (§6.4 step 5, §7.3.1 step 6: "500 lines … 20 rotations … 9C40h").
pub const COUNTS_PER_REV: f64 = 2000.0;
/// The slow-loop sample (§6.4: "1ms sample rate for position/speed control").
pub const SAMPLE_S: f64 = 1e-3;
/// 16.16 fixed point.
pub const FIX: f64 = 65536.0;

/// rpm → IU (counts per sample, 16.16), as the examples compute it.
pub fn rpm_to_iu(rpm: f64) -> f64 {
    rpm / 60.0 * COUNTS_PER_REV * SAMPLE_S * FIX
}

/// IU velocity → counts/s.
pub fn iu_to_counts_s(iu: f64) -> f64 {
    iu / FIX / SAMPLE_S
}

/// IU acceleration (counts per sample², 16.16) → counts/s².
pub fn iu_to_counts_s2(iu: f64) -> f64 {
    iu / FIX / (SAMPLE_S * SAMPLE_S)
}

/// The examples' motor: the 500-line encoder; position IU = encoder counts
/// (§5: without a factor group the position unit is the increment), so the
/// feed follows the encoder.
pub fn manual_motor(cfg: &mut DriveConfig) {
    cfg.params.encoder.counts_per_rev = COUNTS_PER_REV as u32;
    cfg.factor.encoder = (COUNTS_PER_REV as u32, 1);
    cfg.factor.velocity_encoder = (COUNTS_PER_REV as u32, 1);
    cfg.factor.feed = (COUNTS_PER_REV as u32, 1);
}

/// Degrees of the model's rotary axis (switch positions) for `counts`.
pub fn deg(counts: f64) -> f64 {
    counts / COUNTS_PER_REV * 360.0
}

// Statusword bits.
pub const SW_TARGET_REACHED: u16 = 1 << 10;
pub const SW_ACK: u16 = 1 << 12;
pub const SW_BIT13: u16 = 1 << 13;

pub struct Rig {
    pub bus: Bus,
    pub probe: ProbeId,
    pub dut: NodeId,
    /// The last statusword seen in TPDO1.
    pub sw: Option<u16>,
    /// SDO replies (581h) not consumed yet.
    pub sdo: Vec<Frame>,
    /// EMCY frames (081h) seen.
    pub emcy: Vec<Frame>,
    /// Process image of RPDO1 as the examples map it: controlword, mode.
    pub cw: u16,
    pub mode: i8,
}

impl Rig {
    /// The iPOS on the examples' machine plus `machine` (switches).
    pub fn on(machine: impl FnOnce(&mut DriveConfig)) -> Rig {
        let node = build_custom(
            Profile::Ipos,
            1,
            Box::new(MemoryStorage::new()),
            Box::new(Ipos::new()),
            |c: &mut DriveConfig| {
                manual_motor(c);
                machine(c);
            },
        )
        .unwrap();
        let mut bus = Bus::new(BusConfig::zero_time());
        let probe = bus.attach_probe();
        let dut = bus.attach(node);
        bus.run_for(Duration::from_millis(1));
        assert_eq!(bus.take_received(probe), vec![Frame::new(0x701, &[0])]);
        Rig { bus, probe, dut, sw: None, sdo: Vec::new(), emcy: Vec::new(), cw: 0, mode: 0 }
    }

    pub fn new() -> Rig {
        Rig::on(|_| {})
    }

    pub fn dn(&self) -> &PersonalityDevice {
        self.bus.node::<PersonalityDevice>(self.dut).unwrap()
    }

    /// Runs the bus for `us` µs, sorting what the drive sent.
    pub fn run_us(&mut self, us: u64) {
        self.bus.run_for(Duration::from_micros(us));
        for f in self.bus.take_received(self.probe) {
            match f.std_id() {
                Some(0x181) => self.sw = Some(u16::from_le_bytes([f.data()[0], f.data()[1]])),
                Some(0x581) => self.sdo.push(f),
                Some(0x081) => self.emcy.push(f),
                _ => {}
            }
        }
    }

    pub fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms {
            self.run_us(1000);
        }
    }

    pub fn send(&mut self, f: Frame) {
        self.bus.send_from(self.probe, f);
        self.run_us(500);
    }

    /// "Start remote node" (EtherCAT Pre-Op → Safe-Op → Op): NMT Start.
    pub fn start_remote_node(&mut self) {
        self.send(Frame::new(0x000, &[0x01, 0x01]));
    }

    /// SDO download (expedited), confirmed `581#60 …`.
    pub fn sdo(&mut self, index: u16, sub: u8, data: &[u8]) {
        self.sdo.clear();
        let cmd = 0x23 | ((4 - data.len() as u8) << 2);
        let mut b = [cmd, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
        b[4..4 + data.len()].copy_from_slice(data);
        self.send(Frame::new(0x601, &b));
        let ok = Frame::new(0x581, &[0x60, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0]);
        assert_eq!(self.sdo, vec![ok], "{index:04X}h:{sub} := {data:02X?}");
        self.sdo.clear();
    }

    /// SDO upload (expedited) of an object of `len` bytes, sign-extended.
    pub fn upload(&mut self, index: u16, sub: u8, len: usize) -> i64 {
        self.sdo.clear();
        self.send(Frame::new(0x601, &[0x40, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0]));
        assert_eq!(self.sdo.len(), 1, "{index:04X}h:{sub} upload");
        let d = self.sdo[0].data().to_vec();
        self.sdo.clear();
        let size = 4 - ((d[0] >> 2) & 3) as usize;
        assert_eq!((d[0] & 0xF3, &d[1..4], size), (0x43, &[index as u8, (index >> 8) as u8, sub][..], len));
        let mut v = [0u8; 8];
        v[..len].copy_from_slice(&d[4..4 + len]);
        let raw = i64::from_le_bytes(v);
        let shift = 64 - 8 * len as u32;
        (raw << shift) >> shift
    }

    /// RPDO1 as the examples map it (controlword, modes of operation).
    pub fn rpdo1(&mut self) {
        let [a, b] = self.cw.to_le_bytes();
        let f = Frame::new(0x201, &[a, b, self.mode as u8]);
        self.send(f);
    }

    /// "Set in Control Word mapped in RPDO1 the value …".
    pub fn controlword(&mut self, cw: u16) {
        self.cw = cw;
        self.rpdo1();
    }

    /// "Set in Modes of Operation mapped in RPDO1 the value …".
    pub fn modes_of_operation(&mut self, mode: i8) {
        self.mode = mode;
        self.rpdo1();
    }

    /// "Set in Target position mapped in RPDO2 the value …".
    pub fn target_position_rpdo2(&mut self, p: i32) {
        self.send(Frame::new(0x301, &p.to_le_bytes()));
    }

    /// Waits (bounded) until the TPDO1 statusword has `value` under `mask`;
    /// returns the time it took \[ms\].
    pub fn wait_sw(&mut self, what: &str, mask: u16, value: u16, bound_ms: u64) -> u64 {
        for t in 0..=bound_ms {
            if self.sw.is_some_and(|sw| sw & mask == value) {
                return t;
            }
            self.run_ms(1);
        }
        panic!("{what}: statusword {:04X?} after {bound_ms} ms", self.sw);
    }

    /// Steps 3–5 of every example: Shutdown, Switch on, Enable operation
    /// in RPDO1, each waited for in TPDO1 (state bits 6Fh).
    pub fn enable(&mut self) {
        self.controlword(0x06);
        self.wait_sw("ready to switch on", 0x6F, 0x21, 100);
        self.controlword(0x07);
        self.wait_sw("switched on", 0x6F, 0x23, 100);
        self.controlword(0x0F);
        self.wait_sw("operation enabled", 0x6F, 0x27, 100);
    }

    /// Motor shaft position \[revolutions\] of the model.
    pub fn motor_revs(&self) -> f64 {
        self.dn().app.drive.model().position() / (2.0 * core::f64::consts::PI)
    }

    /// Motor speed \[rpm\] of the model.
    pub fn motor_rpm(&self) -> f64 {
        self.dn().app.drive.model().velocity() * 60.0 / (2.0 * core::f64::consts::PI)
    }

    /// A live value straight from the dictionary (what the master's
    /// process image would show every cycle). The iPOS has no 6074h (its
    /// object list, Appendix A): for it, the drive's torque demand.
    pub fn od_i64(&self, index: u16, sub: u8) -> i64 {
        match self.dn().node.od().get_i64(index, sub) {
            Some(v) => v,
            None if (index, sub) == (0x6074, 0) => self.dn().app.drive.demand_torque().round() as i64,
            None => panic!("{index:04X}h:{sub} is not in the dictionary"),
        }
    }
}

/// The process data mapping the examples rely on, written by SDO in
/// pre-operational (unprinted, derived): RPDO1 := controlword + modes of
/// operation, RPDO2 := target position, both asynchronous (type FFh: used
/// on reception, as the EtherCAT outputs are used in the cycle they arrive).
/// RPDO1 is valid and is invalidated while it is remapped (CiA 301
/// §7.5.2.36); RPDO2 is invalid after power-on: validating it is the CAN
/// counterpart of assigning 1601h in the Sync Manager 1C12h.
pub fn map_examples_rpdos(r: &mut Rig) {
    r.sdo(0x1400, 1, &0x8000_0201u32.to_le_bytes());
    r.sdo(0x1400, 2, &[0xFF]);
    r.sdo(0x1600, 0, &[0]);
    r.sdo(0x1600, 1, &0x6040_0010u32.to_le_bytes());
    r.sdo(0x1600, 2, &0x6060_0008u32.to_le_bytes());
    r.sdo(0x1600, 0, &[2]);
    r.sdo(0x1400, 1, &0x0000_0201u32.to_le_bytes());
    r.sdo(0x1401, 1, &0x8000_0301u32.to_le_bytes());
    r.sdo(0x1401, 2, &[0xFF]);
    r.sdo(0x1601, 0, &[0]);
    r.sdo(0x1601, 1, &0x607A_0020u32.to_le_bytes());
    r.sdo(0x1601, 0, &[1]);
    // CAN counterpart of 1C12h:02 := 1601h, 1C12h:00 := 2.
    r.sdo(0x1401, 1, &0x0000_0301u32.to_le_bytes());
    // The statusword the examples wait for comes in TxPDO1 (§2.3: 6041h
    // first, assigned by default in 1C13h, so valid on CAN).
    assert_eq!(r.upload(0x1A00, 1, 4) as u32, 0x6041_0010, "TxPDO1 starts with the statusword (§2.3)");
    assert_eq!(r.upload(0x1800, 1, 4) as u32 & 0x8000_07FF, 0x181, "TxPDO1 valid (§2.3.11)");
}

/// A bound for a profile move of `distance` counts at `v` counts/s with
/// the drive's present 6083h (the examples do not write it): cruise time,
/// twice the ramp time, plus 1 s.
pub fn move_bound_ms(r: &mut Rig, distance: f64, v: f64) -> u64 {
    let a = iu_to_counts_s2(r.upload(0x6083, 0, 4) as u32 as f64);
    assert!(a > 0.0, "6083h profile acceleration is 0: no profile can run");
    ((distance.abs() / v + 2.0 * v / a + 1.0) * 1000.0) as u64
}

/// "6064h = 6062h plus or minus few encoder counts depending on your
/// position tuning" (§7.3): a few = 5 here.
pub const FEW_COUNTS: i64 = 5;

/// From "target reached" to the operator's SDO read of 6064h \[ms\].
pub const SETTLE_MS: u64 = 20;

/// pp start: controlword with bit 4 (and bit 6 for relative), then the
/// example's "Wait for Bit10 to become 1 in Status Word", bounded. Bit 10
/// comes once the axis is inside the position window 6067h (10 counts,
/// window time 0): the following "Check the value of motor actual
/// position" step is read 20 ms later, when the axis has settled (with
/// the 1 ms speed filter it is still 6 counts short when bit 10 comes).
pub fn start_and_wait(r: &mut Rig, cw: u16, bound_ms: u64) -> u64 {
    r.controlword(cw);
    r.run_ms(2);
    let sw = r.sw.unwrap();
    assert_eq!(sw & (SW_ACK | SW_TARGET_REACHED), SW_ACK, "set-point acknowledged, moving: {sw:04X}h");
    let t = r.wait_sw("bit 10 target reached", SW_TARGET_REACHED, SW_TARGET_REACHED, bound_ms);
    r.run_ms(SETTLE_MS);
    t
}

/// How long a pv ramp to `v` counts/s takes at the drive's present 6083h
/// (the examples do not write it), plus 0.5 s.
pub fn ramp_bound_ms(r: &mut Rig, v: f64) -> u64 {
    let a = iu_to_counts_s2(r.upload(0x6083, 0, 4) as u32 as f64);
    assert!(a > 0.0, "6083h is 0");
    ((v / a + 0.5) * 1000.0) as u64
}

/// The speed over one second, as the iPOS defines its speed unit (§10:
/// counts per 1 ms sample, 16.16): Δ6064h / 1000 samples × 65536; and the
/// motor's revolutions per minute from the turns it made.
pub fn speed_over_1s(r: &mut Rig) -> (f64, f64) {
    let (c0, p0) = (r.od_i64(0x6064, 0), r.motor_revs());
    r.run_ms(1000);
    let (c1, p1) = (r.od_i64(0x6064, 0), r.motor_revs());
    ((c1 - c0) as f64 / 1000.0 * FIX, (p1 - p0) * 60.0)
}

/// 606Ch read once: the iPOS reports increments per 1 ms slow-loop sample
/// (§10), whose resolution is one increment per sample = 1.0 IU (65536 in
/// 16.16); the personality measures the speed over one sample, so one
/// reading is within ±1 IU of the speed (E29/E39: 5 % of 20 IU; E30:
/// 0.2 % of 512 IU). A tighter bound is not what a 1 ms speed gives: at
/// 20 counts per sample one count more or less in a sample is 5 %.
pub const ONE_READING_IU: f64 = FIX;

/// The rig with the examples' PDOs, started, in `mode`, enabled.
pub fn enabled_in(mode: i8) -> Rig {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(mode);
    r.enable();
    r
}

/// An expedited SDO download answered by an abort with `code`.
pub fn sdo_aborts(r: &mut Rig, index: u16, sub: u8, data: &[u8], code: u32) {
    r.sdo.clear();
    let cmd = 0x23 | ((4 - data.len() as u8) << 2);
    let mut b = [cmd, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
    b[4..4 + data.len()].copy_from_slice(data);
    r.send(Frame::new(0x601, &b));
    let c = code.to_le_bytes();
    let abort = Frame::new(0x581, &[0x80, index as u8, (index >> 8) as u8, sub, c[0], c[1], c[2], c[3]]);
    assert_eq!(r.sdo, vec![abort], "{index:04X}h:{sub} := {data:02X?}");
    r.sdo.clear();
}
