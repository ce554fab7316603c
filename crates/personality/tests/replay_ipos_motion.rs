//! The motion examples of the Technosoft iPOS CoE manual (seed002,
//! P091.064.UM.0524, `seed002-ipos-examples.md`) replayed with their
//! motion against the built `ipos` personality on the zero-time virtual bus.
//!
//! On the manual's EtherCAT drive the process data (controlword, modes of
//! operation, targets) travel in RxPDOs and the statusword in TxPDO1; here
//! the same objects travel in CAN PDOs (CiA 301 pre-defined connection set
//! for node 1: RPDO1 201h, RPDO2 301h, RPDO3 401h, RPDO4 501h, TPDO1 181h).
//! Where an example says "SDO" the object is written by an expedited SDO
//! download to 601h and confirmed on 581h.
//!
//! EtherCAT → CAN, step by step:
//! * "Start remote node / Pre-Op / Safe-Op / Op" → NMT Start (`000#01 01`);
//! * "mapped in RPDO1/RPDO2" → the mapping the example relies on is written
//!   by SDO before the start (unprinted, derived: the examples say
//!   "Control Word / Modes of Operation mapped in RPDO1", "Target position
//!   mapped in RPDO2"; §2.3's defaults map 6040h + 607Ah in RxPDO1 and
//!   leave 6060h out, seed002-ipos.md §2.3 note);
//! * assigning a PDO in the Sync Manager (1C12h/1C13h) → making it valid on
//!   CAN (1400h+n:1 bit 31 := 0): on CAN a PDO is used when its COB-ID is
//!   valid, and every iPOS RPDO but RPDO1 is invalid after power-on
//!   (§2.3.10, `ipos_pdo_validity.rs`);
//! * "Wait for bit 10 in Status Word" → the statusword of TPDO1 (6041h +
//!   6064h + 6077h, valid by default, §2.3 / §2.3.11), sent on change,
//!   with a bounded wait;
//! * the cyclic modes' SYNC0 → the CAN SYNC (`080#`), the targets sent in
//!   their RPDO before each SYNC.
//!
//! Units are the manual's (§1.3/§5): positions in encoder counts, speeds in
//! counts per 1 ms sample in 16.16 fixed point, accelerations in counts per
//! sample² in 16.16. The examples' motor has "a 500 lines incremental
//! encoder" (§6.4, §7.3: 2000 counts per revolution); the drive is built on
//! that machine (`build_custom`, [`manual_motor`]), so the rotations the
//! manual counts are the model's motor revolutions. Every expected value
//! is computed here from the example's numbers, not read from the drive.

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Duration, Frame};
use drivebus_cia402::drive::DriveConfig;
use drivebus_node::MemoryStorage;
use drivebus_personality::behaviour::ipos::Ipos;
use drivebus_personality::{PersonalityNode, Profile, build_custom};

/// Encoder counts per motor revolution: a 500-line quadrature encoder
/// (§6.4 step 5, §7.3.1 step 6: "500 lines … 20 rotations … 9C40h").
const COUNTS_PER_REV: f64 = 2000.0;
/// The slow-loop sample (§6.4: "1ms sample rate for position/speed control").
const SAMPLE_S: f64 = 1e-3;
/// 16.16 fixed point.
const FIX: f64 = 65536.0;

/// rpm → IU (counts per sample, 16.16), as the examples compute it.
fn rpm_to_iu(rpm: f64) -> f64 {
    rpm / 60.0 * COUNTS_PER_REV * SAMPLE_S * FIX
}

/// IU velocity → counts/s.
fn iu_to_counts_s(iu: f64) -> f64 {
    iu / FIX / SAMPLE_S
}

/// IU acceleration (counts per sample², 16.16) → counts/s².
fn iu_to_counts_s2(iu: f64) -> f64 {
    iu / FIX / (SAMPLE_S * SAMPLE_S)
}

/// The examples' motor: the 500-line encoder; position IU = encoder counts
/// (§5: without a factor group the position unit is the increment), so the
/// feed follows the encoder.
fn manual_motor(cfg: &mut DriveConfig) {
    cfg.params.encoder.counts_per_rev = COUNTS_PER_REV as u32;
    cfg.factor.encoder = (COUNTS_PER_REV as u32, 1);
    cfg.factor.velocity_encoder = (COUNTS_PER_REV as u32, 1);
    cfg.factor.feed = (COUNTS_PER_REV as u32, 1);
}

/// Degrees of the model's rotary axis (switch positions) for `counts`.
fn deg(counts: f64) -> f64 {
    counts / COUNTS_PER_REV * 360.0
}

// Statusword bits.
const SW_TARGET_REACHED: u16 = 1 << 10;
const SW_ACK: u16 = 1 << 12;
const SW_BIT13: u16 = 1 << 13;

struct Rig {
    bus: Bus,
    probe: ProbeId,
    dut: NodeId,
    /// The last statusword seen in TPDO1.
    sw: Option<u16>,
    /// SDO replies (581h) not consumed yet.
    sdo: Vec<Frame>,
    /// EMCY frames (081h) seen.
    emcy: Vec<Frame>,
    /// Process image of RPDO1 as the examples map it: controlword, mode.
    cw: u16,
    mode: i8,
}

impl Rig {
    /// The iPOS on the examples' machine plus `machine` (switches).
    fn on(machine: impl FnOnce(&mut DriveConfig)) -> Rig {
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

    fn new() -> Rig {
        Rig::on(|_| {})
    }

    fn dn(&self) -> &PersonalityNode {
        self.bus.node::<PersonalityNode>(self.dut).unwrap()
    }

    /// Runs the bus for `us` µs, sorting what the drive sent.
    fn run_us(&mut self, us: u64) {
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

    fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms {
            self.run_us(1000);
        }
    }

    fn send(&mut self, f: Frame) {
        self.bus.send_from(self.probe, f);
        self.run_us(500);
    }

    /// "Start remote node" (EtherCAT Pre-Op → Safe-Op → Op): NMT Start.
    fn start_remote_node(&mut self) {
        self.send(Frame::new(0x000, &[0x01, 0x01]));
    }

    /// SDO download (expedited), confirmed `581#60 …`.
    fn sdo(&mut self, index: u16, sub: u8, data: &[u8]) {
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
    fn upload(&mut self, index: u16, sub: u8, len: usize) -> i64 {
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
    fn rpdo1(&mut self) {
        let [a, b] = self.cw.to_le_bytes();
        let f = Frame::new(0x201, &[a, b, self.mode as u8]);
        self.send(f);
    }

    /// "Set in Control Word mapped in RPDO1 the value …".
    fn controlword(&mut self, cw: u16) {
        self.cw = cw;
        self.rpdo1();
    }

    /// "Set in Modes of Operation mapped in RPDO1 the value …".
    fn modes_of_operation(&mut self, mode: i8) {
        self.mode = mode;
        self.rpdo1();
    }

    /// "Set in Target position mapped in RPDO2 the value …".
    fn target_position_rpdo2(&mut self, p: i32) {
        self.send(Frame::new(0x301, &p.to_le_bytes()));
    }

    /// Waits (bounded) until the TPDO1 statusword has `value` under `mask`;
    /// returns the time it took \[ms\].
    fn wait_sw(&mut self, what: &str, mask: u16, value: u16, bound_ms: u64) -> u64 {
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
    fn enable(&mut self) {
        self.controlword(0x06);
        self.wait_sw("ready to switch on", 0x6F, 0x21, 100);
        self.controlword(0x07);
        self.wait_sw("switched on", 0x6F, 0x23, 100);
        self.controlword(0x0F);
        self.wait_sw("operation enabled", 0x6F, 0x27, 100);
    }

    /// Motor shaft position \[revolutions\] of the model.
    fn motor_revs(&self) -> f64 {
        self.dn().drive.model().position() / (2.0 * core::f64::consts::PI)
    }

    /// Motor speed \[rpm\] of the model.
    fn motor_rpm(&self) -> f64 {
        self.dn().drive.model().velocity() * 60.0 / (2.0 * core::f64::consts::PI)
    }

    /// A live value straight from the dictionary (what the master's
    /// process image would show every cycle).
    fn od_i64(&self, index: u16, sub: u8) -> i64 {
        self.dn().node.od().get_i64(index, sub).unwrap()
    }
}

/// The process data mapping the examples rely on, written by SDO in
/// pre-operational (unprinted, derived): RPDO1 := controlword + modes of
/// operation, RPDO2 := target position, both asynchronous (type FFh: used
/// on reception, as the EtherCAT outputs are used in the cycle they arrive).
/// RPDO1 is valid and is invalidated while it is remapped (CiA 301
/// §7.5.2.36); RPDO2 is invalid after power-on: validating it is the CAN
/// counterpart of assigning 1601h in the Sync Manager 1C12h.
fn map_examples_rpdos(r: &mut Rig) {
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
fn move_bound_ms(r: &mut Rig, distance: f64, v: f64) -> u64 {
    let a = iu_to_counts_s2(r.upload(0x6083, 0, 4) as u32 as f64);
    assert!(a > 0.0, "6083h profile acceleration is 0: no profile can run");
    ((distance.abs() / v + 2.0 * v / a + 1.0) * 1000.0) as u64
}

/// "6064h = 6062h plus or minus few encoder counts depending on your
/// position tuning" (§7.3): a few = 5 here.
const FEW_COUNTS: i64 = 5;

/// From "target reached" to the operator's SDO read of 6064h \[ms\].
const SETTLE_MS: u64 = 20;

/// pp start: controlword with bit 4 (and bit 6 for relative), then the
/// example's "Wait for Bit10 to become 1 in Status Word", bounded. Bit 10
/// comes once the axis is inside the position window 6067h (10 counts,
/// window time 0): the following "Check the value of motor actual
/// position" step is read 20 ms later, when the axis has settled (with
/// the 1 ms speed filter it is still 6 counts short when bit 10 comes).
fn start_and_wait(r: &mut Rig, cw: u16, bound_ms: u64) -> u64 {
    r.controlword(cw);
    r.run_ms(2);
    let sw = r.sw.unwrap();
    assert_eq!(sw & (SW_ACK | SW_TARGET_REACHED), SW_ACK, "set-point acknowledged, moving: {sw:04X}h");
    let t = r.wait_sw("bit 10 target reached", SW_TARGET_REACHED, SW_TARGET_REACHED, bound_ms);
    r.run_ms(SETTLE_MS);
    t
}

/// E05 (§1.6.1): profile position with CoE commands — the default PDO
/// variables (RxPDO1 = controlword + target position, §2.3), 6060h and
/// 6081h by SDO. 80000 counts at 9 IU, then back to 40000.
#[test]
fn e05_profile_position_default_rxpdo1() {
    let mut r = Rig::new();
    // Default RxPDO1 (§2.3): 6040h + 607Ah, valid (assigned in 1C12h).
    assert_eq!(r.upload(0x1600, 1, 4) as u32, 0x6040_0010);
    assert_eq!(r.upload(0x1600, 2, 4) as u32, 0x607A_0020);
    r.start_remote_node();
    let rpdo1 = |r: &mut Rig, cw: u16, target: i32| {
        let t = target.to_le_bytes();
        let c = cw.to_le_bytes();
        r.send(Frame::new(0x201, &[c[0], c[1], t[0], t[1], t[2], t[3]]));
    };
    // Step 3: 6060h := 1 by SDO.
    r.sdo(0x6060, 0, &[1]);
    // Steps 5–6: controlword 06h, 07h.
    rpdo1(&mut r, 0x06, 0);
    r.wait_sw("ready to switch on", 0x6F, 0x21, 100);
    rpdo1(&mut r, 0x07, 0);
    r.wait_sw("switched on", 0x6F, 0x23, 100);
    // Step 7: target position 80000 in the same RxPDO1.
    rpdo1(&mut r, 0x07, 80_000);
    // Step 8: 6081h := 0009_0000h = 9.0 IU.
    r.sdo(0x6081, 0, &0x0009_0000u32.to_le_bytes());
    // Step 9: 0Fh, the motor holds its position.
    rpdo1(&mut r, 0x0F, 80_000);
    r.wait_sw("operation enabled", 0x6F, 0x27, 100);
    let v = iu_to_counts_s(f64::from(0x0009_0000));
    assert_eq!(v, 9000.0, "9 counts/ms");
    let bound = move_bound_ms(&mut r, 80_000.0, v);
    // Step 10: 1Fh starts the move; step 12: "After reaching 80000 counts,
    // the motor will stop and hold its position".
    rpdo1(&mut r, 0x1F, 80_000);
    r.run_ms(2);
    assert_eq!(r.sw.unwrap() & (SW_ACK | SW_TARGET_REACHED), SW_ACK);
    let t = r.wait_sw("80000 reached", SW_TARGET_REACHED, SW_TARGET_REACHED, bound);
    // At 9 counts/ms the cruise alone takes 80000 / 9 ms.
    assert!(t as f64 >= 80_000.0 / 9.0 * 0.95, "80000 counts at 9 counts/ms take ≥ 8.9 s, took {t} ms");
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 80_000).abs() <= FEW_COUNTS, "6064h {p}");
    // Steps 13–15: bit 4 reset, target 40000, bit 4 set: back to 40000.
    rpdo1(&mut r, 0x0F, 80_000);
    rpdo1(&mut r, 0x0F, 40_000);
    let bound = move_bound_ms(&mut r, 40_000.0, v);
    rpdo1(&mut r, 0x1F, 40_000);
    r.run_ms(2);
    r.wait_sw("40000 reached", SW_TARGET_REACHED, SW_TARGET_REACHED, bound);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 40_000).abs() <= FEW_COUNTS, "6064h {p}");
    assert!((r.motor_revs() - 40_000.0 / COUNTS_PER_REV).abs() < 0.01, "{} rev", r.motor_revs());
}

/// E06 (§1.6.2): cyclic synchronous position by hand — the default
/// RxPDO1 (controlword + target position), 6060h := 8 by SDO, small
/// target steps ("Maximum 20-200 encoder counts"), each reached "within
/// that communication cycle time value". The free-run 1 ms cycle of E04
/// becomes a 1 ms CAN SYNC; 60C2h keeps its stated default 1 × 10⁻³ s.
#[test]
fn e06_csp_manual_commands() {
    let mut r = Rig::new();
    assert_eq!(r.upload(0x1600, 1, 4) as u32, 0x6040_0010);
    assert_eq!(r.upload(0x1600, 2, 4) as u32, 0x607A_0020);
    // 60C2h default (§13.2.1): 1, −3 = 1 ms, the free-run cycle of E04.
    assert_eq!((r.upload(0x60C2, 1, 1), r.upload(0x60C2, 2, 1)), (1, -3));
    r.start_remote_node();
    let rpdo1 = |cw: u16, t: i64| {
        let (c, p) = (cw.to_le_bytes(), (t as i32).to_le_bytes());
        Frame::new(0x201, &[c[0], c[1], p[0], p[1], p[2], p[3]])
    };
    // "6060h should already be set to the value 08 if the XML file is
    // loaded. If it is not 08, then modify … 6060h value 08 via SDO".
    r.sdo(0x6060, 0, &[8]);
    for (cw, state) in [(0x06u16, 0x21u16), (0x07, 0x23), (0x0F, 0x27)] {
        sync_cycle(&mut r, rpdo1(cw, 0), 1, 0x6062);
        r.wait_sw("enable", 0x6F, state, 100);
    }
    for _ in 0..5 {
        sync_cycle(&mut r, rpdo1(0x0F, 0), 1, 0x6062);
    }
    // Steps of 20…200 counts, one per 1 ms cycle, some held: the demand
    // reaches each within the cycle after the SYNC that latched it.
    let targets = [20, 60, 120, 200, 200, 400, 400, 380, 300, 100, 0, 0];
    follow(&mut r, 1, |t| rpdo1(0x0F, t), 0x6062, 0, &targets, 2.0);
    for _ in 0..50 {
        sync_cycle(&mut r, rpdo1(0x0F, 0), 1, 0x6062);
    }
    let p = r.upload(0x6064, 0, 4);
    assert!(p.abs() <= FEW_COUNTS, "back at 0: 6064h {p}");
}

/// The homing machine of E18: the positive limit switch LSP, active from
/// 3 motor revolutions (6000 counts) up. The manual's operator "presses
/// for 5 s the LSP button" (§6.4 step 12) while the motor runs towards
/// it; here the switch is placed on the axis, where method 18 finds it.
const E18_LSP_COUNTS: f64 = 6000.0;

/// E18 (§6.4): homing method 18 (positive limit switch), 600 rpm search
/// for the switch, 150 rpm search for zero, 5 rot/s², home offset 1
/// rotation.
#[test]
fn e18_homing_method_18() {
    let mut r = Rig::on(|c| c.params.axis.positive_limit = Some(deg(E18_LSP_COUNTS)));
    map_examples_rpdos(&mut r);
    // Step 1: start remote node; steps 2–4: 06h, 07h, 0Fh in RPDO1.
    r.start_remote_node();
    r.enable();
    // Steps 5–9, each value computed as the text does.
    let zero = rpm_to_iu(150.0);
    let switch = rpm_to_iu(600.0);
    let acc = 5.0 * COUNTS_PER_REV * SAMPLE_S * SAMPLE_S * FIX; // 5 rot/s²
    assert_eq!(zero, f64::from(0x0005_0000));
    assert_eq!(switch, f64::from(0x0014_0000));
    assert_eq!(acc.round(), f64::from(0x028F));
    assert_eq!(COUNTS_PER_REV, f64::from(0x07D0));
    r.sdo(0x6099, 2, &0x0005_0000u32.to_le_bytes());
    r.sdo(0x6099, 1, &0x0014_0000u32.to_le_bytes());
    r.sdo(0x609A, 0, &0x0000_028Fu32.to_le_bytes());
    r.sdo(0x607C, 0, &0x0000_07D0i32.to_le_bytes());
    r.sdo(0x6098, 0, &[0x12]);
    // Step 10: homing mode in RPDO1; step 11: 001Fh starts the homing.
    // Method 18 (§6.2.8): LSP inactive → move positive, reverse on LSP,
    // home where LSP becomes inactive moving negative. TYPO (§6.2.8):
    // "rightward (negative sense)" — rightward is the positive sense.
    r.modes_of_operation(6);
    r.run_ms(2);
    r.controlword(0x1F);
    r.run_ms(2);
    assert_eq!(r.sw.unwrap() & 0x3400, 0, "homing in progress");
    // Step 13: "When Status Word (object 6040h) bit13=0, bit12=1 and
    // bit10=1, means homing procedure is completed successfully".
    // TYPO (§6.4 step 13): "Status Word (object 6040h)" — 6041h.
    // Bound: reach the switch, brake from at most 600 rpm, come back at
    // 150 rpm, brake: all at 5 rot/s² — a few seconds; 20 s allowed.
    r.wait_sw("homing completed", SW_BIT13 | SW_ACK | SW_TARGET_REACHED, SW_ACK | SW_TARGET_REACHED, 20_000);
    // Step 14: 6064h by SDO.
    let p = r.upload(0x6064, 0, 4);
    // CiA 402 method 18: the home position is where LSP becomes inactive
    // moving negative; there the position becomes 607Ch = 2000. So 6064h
    // is 2000 plus the travel since that edge (the model's shaft against
    // the placed switch).
    let past_edge = r.motor_revs() * COUNTS_PER_REV - E18_LSP_COUNTS;
    assert!(past_edge < 0.0, "stopped below the switch edge (moving negative)");
    let home = p as f64 - past_edge;
    assert!((home - 2000.0).abs() <= 2.0, "home position {home:.1} = 607Ch 2000 (6064h {p})");
    // The manual expects 6064h = 607Ch ± a few counts. The drive brakes
    // from the zero-search speed with the homing acceleration after the
    // edge: (5 counts/ms)² / (2 × 0.01 counts/ms²) = 1250 counts past the
    // home position. That is what the emulation shows (report: the
    // "± few counts" needs the real iPOS's stop, not 609Ah).
    let v = iu_to_counts_s(zero);
    let a = iu_to_counts_s2(f64::from(0x028F));
    let brake = v * v / (2.0 * a);
    assert!((brake - 1250.0).abs() < 1.0);
    assert!((p as f64 - (2000.0 - brake)).abs() <= 10.0, "6064h {p}, 2000 − {brake:.0} expected");
}

/// E19 (§7.3.1): relative trapezoidal profile, 20 rotations then 200
/// rotations at 500 rpm; "the motor should rotate 220 times".
///
/// TYPO (§7.3.1 intro): "Execute an absolute trapezoidal profile … 4
/// rotations … 16 rotations" is §7.3.2's sentence; the steps are the
/// relative 20 + 200 rotations.
#[test]
fn e19_relative_trapezoidal() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Step 2: position mode in RPDO1; steps 3–5: 06h, 07h, 0Fh.
    r.modes_of_operation(1);
    r.enable();
    // Step 6: target 20 rotations = 20 × 2000 = 9C40h counts, in RPDO2.
    assert_eq!(20.0 * COUNTS_PER_REV, f64::from(0x9C40));
    r.target_position_rpdo2(0x0000_9C40);
    // Step 7: 500 rpm = 16.667 counts/ms = 10AAABh (rounded); the manual
    // prints 10AAACh (1 LSB more) — sent as printed.
    assert_eq!(rpm_to_iu(500.0).round(), f64::from(0x0010_AAAB));
    r.sdo(0x6081, 0, &0x0010_AAACu32.to_le_bytes());
    let v = iu_to_counts_s(f64::from(0x0010_AAAC));
    // Steps 8–9: 005Fh (bit 6 relative), wait for bit 10.
    let bound = move_bound_ms(&mut r, 40_000.0, v);
    start_and_wait(&mut r, 0x5F, bound);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 40_000).abs() <= FEW_COUNTS, "after the first move 6064h {p}");
    // Step 10: 000Fh resets the set-point.
    r.controlword(0x0F);
    // Step 11: target 200 rotations = 61A80h, by SDO. On EtherCAT a
    // PDO-mapped 607Ah would be overwritten by the next cycle (§1.6.1
    // remark); a CAN RPDO is used only when received, so the SDO value
    // stays until an RPDO2 comes.
    assert_eq!(200.0 * COUNTS_PER_REV, f64::from(0x0006_1A80));
    r.sdo(0x607A, 0, &0x0006_1A80i32.to_le_bytes());
    // Steps 12–13.
    let bound = move_bound_ms(&mut r, 400_000.0, v);
    let t = start_and_wait(&mut r, 0x5F, bound);
    assert!(t as f64 >= 400_000.0 / v * 1000.0 * 0.99, "200 rotations at 500 rpm last ≥ 24 s ({t} ms)");
    // Steps 14–15: 6064h and 6062h by SDO.
    let actual = r.upload(0x6064, 0, 4);
    let demand = r.upload(0x6062, 0, 4);
    let expected = (20 + 200) * COUNTS_PER_REV as i64;
    assert_eq!(demand, expected, "6062h = 20 + 200 rotations");
    assert!((actual - demand).abs() <= FEW_COUNTS, "6064h {actual} = 6062h {demand} ± a few counts");
    assert!((r.motor_revs() - 220.0).abs() < 0.01, "rotated {} times", r.motor_revs());
}

/// E20 (§7.3.2): absolute trapezoidal profile to 4 rotations, then to 16
/// rotations; "the motor should rotate 16 times".
#[test]
fn e20_absolute_trapezoidal() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    // Step 21: 4 rotations = 1F40h in RPDO2; step 22: 500 rpm.
    assert_eq!(4.0 * COUNTS_PER_REV, f64::from(0x1F40));
    r.target_position_rpdo2(0x0000_1F40);
    r.sdo(0x6081, 0, &0x0010_AAACu32.to_le_bytes());
    let v = iu_to_counts_s(f64::from(0x0010_AAAC));
    // Steps 23–24: 001Fh (absolute), wait for bit 10.
    let bound = move_bound_ms(&mut r, 8000.0, v);
    start_and_wait(&mut r, 0x1F, bound);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 8000).abs() <= FEW_COUNTS, "6064h {p}");
    // Steps 25–28: 000Fh, 607Ah := 16 rotations = 7D00h by SDO, 001Fh, wait.
    r.controlword(0x0F);
    assert_eq!(16.0 * COUNTS_PER_REV, f64::from(0x7D00));
    r.sdo(0x607A, 0, &0x0000_7D00i32.to_le_bytes());
    let bound = move_bound_ms(&mut r, 24_000.0, v);
    start_and_wait(&mut r, 0x1F, bound);
    // Steps 29–30.
    let actual = r.upload(0x6064, 0, 4);
    let demand = r.upload(0x6062, 0, 4);
    assert_eq!(demand, 16 * COUNTS_PER_REV as i64);
    assert!((actual - demand).abs() <= FEW_COUNTS, "6064h {actual} = 6062h {demand} ± a few counts");
    assert!((r.motor_revs() - 16.0).abs() < 0.01, "rotated {} times", r.motor_revs());
}

/// E21 (§7.3.3) relative and E22 (§7.3.4) absolute jerk-limited (S-curve)
/// profiles: 6086h = 3 with the jerk time 2023h. The personality accepts
/// and stores 6086h = 3 and 2023h but runs its linear (trapezoidal) ramp:
/// the S-curve shape is not emulated (report). Replayed and asserted: the
/// end positions and "6064h = 6062h ± few counts", which the manual
/// states; nothing about the ramp shape.
///
/// TYPO (§7.3.3 intro): "Execute an absolute Jerk-limited ramp profile" —
/// §7.3.3 is the relative one (controlword 005Fh).
#[test]
fn e21_e22_jerk_limited_profiles_end_positions() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    // E21 step 6: 6086h := 3; step 7: 10 rotations = 4E20h in RPDO2;
    // step 8: 450 rpm = 15 counts/ms = F0000h; step 9: 2023h := 1F4Bh.
    r.sdo(0x6086, 0, &3i16.to_le_bytes());
    assert_eq!(10.0 * COUNTS_PER_REV, f64::from(0x4E20));
    r.target_position_rpdo2(0x0000_4E20);
    assert_eq!(rpm_to_iu(450.0), f64::from(0x000F_0000));
    r.sdo(0x6081, 0, &0x000F_0000u32.to_le_bytes());
    r.sdo(0x2023, 0, &0x1F4Bu16.to_le_bytes());
    // Steps 10–11: 005Fh relative, wait for bit 10.
    let bound = move_bound_ms(&mut r, 20_000.0, iu_to_counts_s(f64::from(0x000F_0000)));
    start_and_wait(&mut r, 0x5F, bound);
    // Steps 12–13.
    let actual = r.upload(0x6064, 0, 4);
    let demand = r.upload(0x6062, 0, 4);
    assert_eq!(demand, 20_000);
    assert!((actual - demand).abs() <= FEW_COUNTS, "E21: 6064h {actual} = 6062h {demand}");
    assert_eq!(r.upload(0x6086, 0, 2), 3, "6086h kept");
    // E22 on the same drive (its steps 14–18 repeat the start and enable;
    // the drive is already enabled in pp): reset bit 4 first.
    r.controlword(0x0F);
    // Step 19: 6086h := 3; step 20: 5 rotations = 2710h in RPDO2; step
    // 21: 150 rpm = 5 counts/ms = 50000h; step 22: 2023h := 013Bh.
    r.sdo(0x6086, 0, &3i16.to_le_bytes());
    assert_eq!(5.0 * COUNTS_PER_REV, f64::from(0x2710));
    r.target_position_rpdo2(0x0000_2710);
    assert_eq!(rpm_to_iu(150.0), f64::from(0x0005_0000));
    r.sdo(0x6081, 0, &0x0005_0000u32.to_le_bytes());
    r.sdo(0x2023, 0, &0x013Bu16.to_le_bytes());
    // Steps 23–24: 001Fh absolute, wait for bit 10.
    let bound = move_bound_ms(&mut r, 10_000.0, iu_to_counts_s(f64::from(0x0005_0000)));
    start_and_wait(&mut r, 0x1F, bound);
    // Steps 25–26.
    let actual = r.upload(0x6064, 0, 4);
    let demand = r.upload(0x6062, 0, 4);
    assert_eq!(demand, 10_000);
    assert!((actual - demand).abs() <= FEW_COUNTS, "E22: 6064h {actual} = 6062h {demand}");
    assert!((r.motor_revs() - 5.0).abs() < 0.01, "at 5 rotations: {}", r.motor_revs());
}

/// E23 (§8.3): profile torque, rated current 1000 mA, slope 1000 ‰/s,
/// +50.0 % then −120.0 %. The machine: the motor shaft between two end
/// stops 2 revolutions either side (the manual gives no load; unloaded, a
/// torque set-point only runs the motor into its speed limit), so the
/// torque is held once the motor "moves positive" / "moves negative".
#[test]
fn e23_torque_profile() {
    let mut r = Rig::on(|c| {
        c.params.axis.positive_stop = Some(deg(2.0 * COUNTS_PER_REV));
        c.params.axis.negative_stop = Some(deg(-2.0 * COUNTS_PER_REV));
    });
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Step 2: mode 04h in RPDO1. TYPO (§8.3 step 2): "Select position
    // mode" — 04h is profile torque.
    r.modes_of_operation(4);
    r.enable();
    // Steps 6–7: 6075h := 1000 mA, 6087h := 1000 ‰/s. TYPO (§8.3 step 7):
    // the slope is printed "1000mA"; its unit is ‰ of 6075h per second
    // (§8.2.3), here 1000 mA/s.
    r.sdo(0x6075, 0, &0x03E8u32.to_le_bytes());
    r.sdo(0x6087, 0, &0x03E8u32.to_le_bytes());
    let slope = 1000.0; // ‰ per second
    // Step 8: 6071h := 01F4h = 500 = 50.0 %. The demand follows the slope:
    // 500 ‰ after 500 / 1000 s.
    r.sdo(0x6071, 0, &0x01F4i16.to_le_bytes());
    let t0 = 0.0005; // the SDO exchange (500 µs) after the write
    for ms in [100u64, 250, 400] {
        r.run_ms(if ms == 100 { 100 } else { 150 });
        let want = (slope * (ms as f64 / 1000.0 + t0)).min(500.0);
        let got = r.od_i64(0x6074, 0) as f64;
        assert!((got - want).abs() <= 3.0, "6074h {got} ‰ at {ms} ms, slope gives {want:.1}");
    }
    r.run_ms(200);
    assert_eq!(r.od_i64(0x6074, 0), 500, "target 50.0 % reached");
    assert!(r.motor_revs() > 1.9, "moved positive to the stop: {} rev", r.motor_revs());
    let tq = r.upload(0x6077, 0, 2);
    assert!((tq - 500).abs() <= 10, "6077h {tq} ‰ held against the stop");
    assert_ne!(r.sw.unwrap() & SW_TARGET_REACHED, 0, "bit 10: target torque reached");
    // Step 8: "reach a current of 50.0% of the motor rated current
    // (500mA)" (§8.2.1: ‰ of 6075h): 6078h in ‰ of 6075h and the motor's
    // own current.
    let rated_ma = 1000.0;
    let ma = 500.0 / 1000.0 * rated_ma;
    let i = r.upload(0x6078, 0, 2) as f64;
    assert!((i / 1000.0 * rated_ma - ma).abs() <= 10.0, "6078h {i} ‰ of 1000 mA, {ma} mA expected");
    let amps = r.dn().drive.model().current();
    assert!((amps * 1000.0 - ma).abs() <= 10.0, "motor current {amps} A, 500 mA expected");
    // Step 9: 6071h := FB50h = −1200 = −120.0 %: 1700 ‰ at 1000 ‰/s.
    assert_eq!(0xFB50u16 as i16, -1200);
    r.sdo(0x6071, 0, &0xFB50u16.to_le_bytes());
    r.run_ms(1000);
    let want = 500.0 - slope * (1.0 + t0);
    let got = r.od_i64(0x6074, 0) as f64;
    assert!((got - want).abs() <= 3.0, "6074h {got} ‰ 1 s after, slope gives {want:.1}");
    r.run_ms(800);
    assert_eq!(r.od_i64(0x6074, 0), -1200, "target −120.0 % reached after 1.7 s");
    r.run_ms(500);
    assert!(r.motor_revs() < -1.9, "moved negative to the stop: {} rev", r.motor_revs());
    let tq = r.upload(0x6077, 0, 2);
    assert!((tq + 1200).abs() <= 20, "6077h {tq} ‰ held against the stop");
    // "reach a current of -120.0% of the motor rated current (-1200mA)".
    let i = r.upload(0x6078, 0, 2) as f64;
    assert!((i + 1200.0).abs() <= 20.0, "6078h {i} ‰ of 1000 mA, −1200 mA expected");
    let amps = r.dn().drive.model().current();
    assert!((amps * 1000.0 + 1200.0).abs() <= 20.0, "motor current {amps} A, −1200 mA expected");
}

/// How long a pv ramp to `v` counts/s takes at the drive's present 6083h
/// (the examples do not write it), plus 0.5 s.
fn ramp_bound_ms(r: &mut Rig, v: f64) -> u64 {
    let a = iu_to_counts_s2(r.upload(0x6083, 0, 4) as u32 as f64);
    assert!(a > 0.0, "6083h is 0");
    ((v / a + 0.5) * 1000.0) as u64
}

/// The speed over one second, as the iPOS defines its speed unit (§10:
/// counts per 1 ms sample, 16.16): Δ6064h / 1000 samples × 65536; and the
/// motor's revolutions per minute from the turns it made.
fn speed_over_1s(r: &mut Rig) -> (f64, f64) {
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
const ONE_READING_IU: f64 = FIX;

/// E29 (§10.3): profile velocity, 600 rpm = 20.0 IU = 140000h.
#[test]
fn e29_speed_profile_600_rpm() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Step 2: speed mode in RPDO1; steps 3–5.
    r.modes_of_operation(3);
    r.enable();
    // Step 6: 600 rpm × 2000 counts / 60 s × 1 ms = 20.0 IU.
    let iu = rpm_to_iu(600.0);
    assert_eq!(iu, f64::from(0x0014_0000));
    r.sdo(0x60FF, 0, &0x0014_0000i32.to_le_bytes());
    let bound = ramp_bound_ms(&mut r, iu_to_counts_s(iu));
    r.run_ms(bound);
    // Step 7: "It should rotate with 600 rpm. Read … 606Ch".
    let v = r.upload(0x606C, 0, 4) as f64;
    assert!((v - iu).abs() <= ONE_READING_IU, "606Ch {v} IU, 600 rpm = {iu} IU");
    // Not one lucky reading: every slow-loop sample for 100 ms.
    for ms in 0..100 {
        r.run_us(1000);
        let v = r.od_i64(0x606C, 0) as f64;
        assert!((v - iu).abs() <= ONE_READING_IU, "606Ch {v} IU at +{ms} ms, 600 rpm = {iu} IU");
    }
    let (speed, rpm) = speed_over_1s(&mut r);
    assert!((speed - iu).abs() <= iu * 0.005, "{speed:.0} IU over 1 s, 600 rpm = {iu} IU");
    assert!((rpm - 600.0).abs() <= 3.0, "{rpm} rpm");
}

/// E30 (§10.4): profile velocity of a stepper in open loop, 200 steps ×
/// 512 µsteps, 300 rpm = 512 IU = 200_0000h. The machine: the NEMA 23
/// stepper model with 512 µsteps, position IU = µsteps ("1 IU is
/// equivalent to 1 µstep per slow loop": 102 400 per revolution).
#[test]
fn e30_stepper_open_loop_300_rpm() {
    const USTEPS: u32 = 200 * 512;
    let mut r = Rig::on(|c| {
        let mut p = drivebus_cia402::model::DriveParams::stepper();
        if let drivebus_cia402::model::MotorKind::Stepper(s) = &mut p.motor.kind {
            s.microsteps = 512;
        }
        p.encoder.counts_per_rev = USTEPS;
        p.control.control_rate_hz = c.control_rate_hz;
        // The personality's speed filter (one slow-loop sample) stays.
        p.control.velocity_filter = c.params.control.velocity_filter;
        c.params = p;
        c.factor.encoder = (USTEPS, 1);
        c.factor.velocity_encoder = (USTEPS, 1);
        c.factor.feed = (USTEPS, 1);
    });
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(3);
    r.enable();
    // Step 6: 300 rpm = 5 rev/s = 512 000 µsteps/s = 512 µsteps per 1 ms
    // sample; × 65536 = 200_0000h.
    let iu = 300.0 / 60.0 * f64::from(USTEPS) * SAMPLE_S * FIX;
    assert_eq!(iu, f64::from(0x0200_0000));
    // TYPO (§10.4 step 6): the message prints "32-bit value 00140000h"
    // (E29's 600 rpm value); the text computes 2000000h, which is sent.
    r.sdo(0x60FF, 0, &0x0200_0000i32.to_le_bytes());
    let bound = ramp_bound_ms(&mut r, iu_to_counts_s(iu));
    r.run_ms(bound);
    let v = r.upload(0x606C, 0, 4) as f64;
    assert!((v - iu).abs() <= ONE_READING_IU, "606Ch {v} IU, 300 rpm = {iu} IU");
    let (speed, rpm) = speed_over_1s(&mut r);
    assert!((speed - iu).abs() <= iu * 0.005, "{speed:.0} IU over 1 s, 300 rpm = {iu} IU");
    assert!((rpm - 300.0).abs() <= 1.5, "{rpm} rpm");
}

/// One SYNC cycle of `period_ms`: the SYNC, then `rpdo` (the target for
/// the *next* SYNC) 1 ms before the next one; returns the values of
/// `index` 1, 2, … `period_ms` ms after the SYNC.
fn sync_cycle(r: &mut Rig, rpdo: Frame, period_ms: u64, index: u16) -> Vec<i64> {
    r.bus.send_from(r.probe, Frame::new(0x080, &[]));
    let mut v = Vec::new();
    for k in 1..=period_ms {
        if k == period_ms {
            r.bus.send_from(r.probe, rpdo);
        }
        r.run_us(1000);
        v.push(r.od_i64(index, 0));
    }
    v
}

/// Sends `targets` one per cycle of `period` ms (each in its RPDO,
/// `frame`, latched at the next SYNC), then one more cycle, and checks
/// that `index` heads linearly for each latched target over its cycle:
/// `j` ms after the SYNC it is `from + (to − from)·j/period` (±`tol`),
/// `from` the target latched before (`start` for the first), allowing
/// the value to lag by up to 0.2 ms (one control period of the drive's
/// loop, whose output is published after the period). Every cycle is
/// checked.
fn follow(
    r: &mut Rig,
    period: u64,
    frame: impl Fn(i64) -> Frame,
    index: u16,
    start: i64,
    targets: &[i64],
    tol: f64,
) {
    let last = *targets.last().unwrap();
    for k in 0..=targets.len() {
        let v = sync_cycle(r, frame(targets.get(k).copied().unwrap_or(last)), period, index);
        if k == 0 {
            // This SYNC latched `start`, sent before.
            continue;
        }
        let to = targets[k - 1];
        let from = if k >= 2 { targets[k - 2] } else { start };
        for (j, got) in v.iter().enumerate() {
            let slope = (to - from) as f64 / period as f64;
            let want = from as f64 + slope * (j as f64 + 1.0);
            assert!(
                (*got as f64 - want).abs() <= tol + 0.2 * slope.abs(),
                "{index:04X}h at SYNC {k} + {} ms: {got}, heading {from} → {to}: {want}",
                j + 1
            );
        }
    }
}

/// E37 (§13.2.1) as used by E38–E40: 60C2h = 4 × 10⁻³ s.
fn four_ms_cycle(r: &mut Rig) {
    r.sdo(0x60C2, 1, &[4]);
    r.sdo(0x60C2, 2, &[(-3i8) as u8]);
}

/// E38 (§13.3): cyclic synchronous position, 4 ms cycle; "If actual
/// position = 0 and the new target position is 40, then the motor will
/// move 10 increments in 1 ms".
#[test]
fn e38_csp_basic() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Step 2: 60C2h = 4, −3.
    four_ms_cycle(&mut r);
    // Step 3: mode 08h in RPDO1; steps 4–6.
    r.modes_of_operation(8);
    r.enable();
    assert_eq!(r.upload(0x6064, 0, 4), 0, "actual position = 0");
    // SYNC running, target 0 held.
    for _ in 0..5 {
        sync_cycle(&mut r, Frame::new(0x301, &0i32.to_le_bytes()), 4, 0x6062);
    }
    // Step 7: a new 607Ah in RPDO2 every cycle: 40, 80, … (10 counts/ms).
    // The target latched at a SYNC is reached linearly over the 4 ms
    // cycle: at SYNC + j ms the demand 6062h is 10·j counts on (the
    // printed value lags by less than one control period: ±2 counts).
    let rpdo2 = |t: i64| Frame::new(0x301, &(t as i32).to_le_bytes());
    let targets: Vec<i64> = (1..=50).map(|k| 40 * k).collect();
    follow(&mut r, 4, rpdo2, 0x6062, 0, &targets, 2.0);
    // Hold the last target: the axis follows to it.
    for _ in 0..50 {
        sync_cycle(&mut r, Frame::new(0x301, &2000i32.to_le_bytes()), 4, 0x6062);
    }
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 2000).abs() <= FEW_COUNTS, "6064h {p} at the last target 2000");
    let sw = r.sw.unwrap();
    assert_eq!(sw & 0x6F, 0x27, "still operation enabled: {sw:04X}h");
}

/// E25 (§9.3): linear interpolation — "identical with the Cyclic
/// Synchronous Position Mode basic example" (E38) with 6060h = 7 and
/// 60C1h:01 instead of 607Ah (208Eh bit 8 = 1, its default: not written).
/// RPDO2 carries 60C1h:01. Inserted (unprinted, derived): controlword
/// 001Fh — in ip bit 4 is "enable ip mode" (§9.1), which E38's 000Fh
/// leaves off.
#[test]
fn e25_linear_interpolation() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.sdo(0x1401, 1, &0x8000_0301u32.to_le_bytes());
    r.sdo(0x1601, 0, &[0]);
    r.sdo(0x1601, 1, &0x60C1_0120u32.to_le_bytes());
    r.sdo(0x1601, 0, &[1]);
    r.sdo(0x1401, 1, &0x0000_0301u32.to_le_bytes());
    r.start_remote_node();
    four_ms_cycle(&mut r);
    r.modes_of_operation(7);
    r.enable();
    let rpdo2 = |t: i64| Frame::new(0x301, &(t as i32).to_le_bytes());
    r.controlword(0x1F);
    for _ in 0..5 {
        sync_cycle(&mut r, rpdo2(0), 4, 0x6062);
    }
    assert_eq!(r.sw.unwrap() & SW_ACK, SW_ACK, "ip mode active");
    let targets: Vec<i64> = (1..=50).map(|k| 40 * k).collect();
    follow(&mut r, 4, rpdo2, 0x6062, 0, &targets, 2.0);
}

/// E39 (§14.2): cyclic synchronous velocity with 60FFh in RxPDO4.
#[test]
fn e39_csv_basic() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    // Steps 2–7 (pre-operational): 1C12h:00 := 0 … 1C12h:03 := 1603h,
    // 1C12h:00 := 3 — on CAN: RPDO4 invalid while mapped (it is invalid
    // after power-on, §2.3.10), then valid. TYPO (§14.2): "PRDO4" — RPDO4.
    r.sdo(0x1403, 1, &0x8000_0501u32.to_le_bytes());
    r.sdo(0x1403, 2, &[0xFF]);
    r.sdo(0x1603, 0, &[0]);
    r.sdo(0x1603, 1, &0x60FF_0020u32.to_le_bytes());
    r.sdo(0x1603, 0, &[1]);
    r.sdo(0x1403, 1, &0x0000_0501u32.to_le_bytes());
    // Step 8: operational; step 9: 60C2h = 4 ms. TYPO (§14.2 step 9): "when
    // every new position command is received in object 607Ah" (copied
    // from §13.3) — in csv it is 60FFh.
    r.start_remote_node();
    four_ms_cycle(&mut r);
    // Step 10: mode 09h in RPDO1; steps 11–13.
    r.modes_of_operation(9);
    r.enable();
    let rpdo4 = |v: i32| Frame::new(0x501, &v.to_le_bytes());
    for _ in 0..5 {
        sync_cycle(&mut r, rpdo4(0), 4, 0x606B);
    }
    // Step 14: a new 60FFh (16.16 IU) every cycle: 0 → 20.0 IU (600 rpm)
    // in steps of 2.0 IU, then held.
    let top = rpm_to_iu(600.0) as i64;
    let targets: Vec<i64> = (1..=10).map(|k| top * k / 10).collect();
    follow(&mut r, 4, |v| rpdo4(v as i32), 0x606B, 0, &targets, 0.01 * top as f64);
    for _ in 0..50 {
        sync_cycle(&mut r, rpdo4(top as i32), 4, 0x606B);
    }
    let v = r.upload(0x606C, 0, 4) as f64;
    assert!((v - top as f64).abs() <= ONE_READING_IU, "606Ch {v} IU, 600 rpm = {top} IU");
    // SYNC keeps coming: a second of cycles, the speed measured over it.
    let (c0, p0) = (r.od_i64(0x6064, 0), r.motor_revs());
    for _ in 0..250 {
        sync_cycle(&mut r, rpdo4(top as i32), 4, 0x606C);
    }
    let speed = (r.od_i64(0x6064, 0) - c0) as f64 / 1000.0 * FIX;
    let rpm = (r.motor_revs() - p0) * 60.0;
    assert!((speed - top as f64).abs() <= top as f64 * 0.005, "{speed:.0} IU over 1 s, 600 rpm = {top} IU");
    assert!((rpm - 600.0).abs() <= 3.0, "{rpm} rpm");
}

/// E40 (§15.3): cyclic synchronous torque with the default RxPDO3
/// (6060h + 6071h, §2.3 — "The RPDO3 has mapped by default, the object
/// 6071h").
#[test]
fn e40_cst_basic() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    assert_eq!(r.upload(0x1602, 0, 1), 2);
    assert_eq!(r.upload(0x1602, 1, 4) as u32, 0x6060_0008, "RxPDO3 default (§2.3)");
    assert_eq!(r.upload(0x1602, 2, 4) as u32, 0x6071_0010, "RxPDO3 default (§2.3)");
    // Steps 2–4: 1C12h:00 := 0, 1C12h:03 := 1602h, 1C12h:00 := 3 — on CAN
    // RPDO3 made valid.
    r.sdo(0x1402, 1, &0x8000_0401u32.to_le_bytes());
    r.sdo(0x1402, 2, &[0xFF]);
    r.sdo(0x1402, 1, &0x0000_0401u32.to_le_bytes());
    // Step 5: operational. 60C2h is not written by E40: the E37 4 ms
    // cycle of the preceding examples is used (unprinted, derived).
    r.start_remote_node();
    four_ms_cycle(&mut r);
    // The emulation's cst unit is ‰ of 6075h (the ASR4.0 = 1 variant,
    // docs/personalities.md), whose power-on value 0 leaves no torque:
    // 6075h := 1000 mA as in E23 (inserted, unprinted).
    r.sdo(0x6075, 0, &1000u32.to_le_bytes());
    // Steps 6–8, then step 9: mode 0Ah in RPDO1.
    r.enable();
    r.modes_of_operation(10);
    // RxPDO3 carries 6060h too: the process image keeps 0Ah there.
    let rpdo3 = |t: i16| {
        let b = t.to_le_bytes();
        Frame::new(0x401, &[0x0A, b[0], b[1]])
    };
    for _ in 0..5 {
        sync_cycle(&mut r, rpdo3(0), 4, 0x6074);
    }
    // Step 10: a new 6071h every cycle: 0 → 100 in steps of 10, then held.
    // The manual's CST unit is the current IU (65520·I / (2·Ipeak)) unless
    // ASR4.0 = 1 (‰ of 6075h); the emulation takes ‰ (report).
    let targets: Vec<i64> = (1..=10).map(|k| 10 * k).collect();
    follow(&mut r, 4, |t| rpdo3(t as i16), 0x6074, 0, &targets, 1.5);
    for _ in 0..3 {
        sync_cycle(&mut r, rpdo3(100), 4, 0x6074);
    }
    assert_eq!(r.od_i64(0x6074, 0), 100);
    let tq = r.upload(0x6077, 0, 2);
    assert!((tq - 100).abs() <= 5, "6077h {tq} ‰ follows");
    assert!(r.motor_rpm() > 0.0, "the motor turns positive");
    // "The drive applies the new current reference": 100 ‰ of 1000 mA.
    let amps = r.dn().drive.model().current();
    assert!((amps - 0.1).abs() <= 0.01, "motor current {amps} A, 100 mA expected");
}

/// The machine of E41: LSP active from 1.5 revolutions (3000 counts) up,
/// inside the 4-rotation move.
const E41_LSP_COUNTS: f64 = 3000.0;

/// E41 (§16.3): touch probe 1 on the LSP rising edge during a pp move at
/// 2 IU/ms; the LSP stops the motor. Replayed: set-up, 60B9h = 0001h
/// before the event, the move, the stop at the LSP. Not asserted: the
/// capture (60B9h = 0003h, 60BAh): the personality's touch probe 1 input
/// is the drive's generic probe input (home switch), not the iPOS's LSP
/// (report).
#[test]
fn e41_touch_probe_move_and_lsp_stop() {
    let mut r = Rig::on(|c| c.params.axis.positive_limit = Some(deg(E41_LSP_COUNTS)));
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    // Step 6: 4 rotations = 1F40h in RPDO2; step 7: 2 IU/ms.
    assert_eq!(4.0 * COUNTS_PER_REV, f64::from(0x1F40));
    r.target_position_rpdo2(0x0000_1F40);
    r.sdo(0x6081, 0, &0x0002_0000u32.to_le_bytes());
    // Step 8: 60B8h := 0011h; step 9: 60B9h = 0001h — TYPO (§16.3 step
    // 9): the text reads it as "a capture was detected (bit1=1)"; 0001h
    // is "enabled, nothing stored" (Table 16.2.2).
    r.sdo(0x60B8, 0, &0x0011u16.to_le_bytes());
    assert_eq!(r.upload(0x60B9, 0, 2), 0x0001);
    // Step 10 "while the motor is moving": the example gives no start
    // command; 001Fh inserted (unprinted, derived).
    r.controlword(0x1F);
    r.run_ms(2);
    assert_eq!(r.sw.unwrap() & (SW_ACK | SW_TARGET_REACHED), SW_ACK, "moving");
    // At 2 counts/ms the LSP (3000 counts) comes after ~1.5 s: "The motor
    // should stop".
    let v = iu_to_counts_s(f64::from(0x0002_0000));
    let bound = move_bound_ms(&mut r, E41_LSP_COUNTS, v);
    r.wait_sw("LSP: internal limit active", 1 << 11, 1 << 11, bound);
    // Steps 11–12 (60B9h = 0003h, 60BAh close to 6064h) are not asserted:
    // see the doc comment. TYPO (§16.3 step 11): 0003h is read as "no
    // capture was detected (bit1=0)"; it is "enabled, positive edge
    // stored in 60BAh" (bit 1 = 1).
    r.run_ms(500);
    let p = r.upload(0x6064, 0, 4);
    assert!(p as f64 >= E41_LSP_COUNTS - 1.0 && p < 8000, "stopped at the LSP, short of 8000: 6064h {p}");
    let before = r.upload(0x6064, 0, 4);
    r.run_ms(100);
    assert_eq!(r.upload(0x6064, 0, 4), before, "at rest");
    // §4.3.1: the limit switch stop keeps Operation enabled (no Quick stop
    // active, 605Ah has no effect).
    assert_eq!(r.sw.unwrap() & 0x6F, 0x27, "Operation enabled: {:04X?}", r.sw);
    // §4.3.1: "If the positive limit switch is activated, the emergency
    // error code 0x5443 will be sent automatically and object 2000h bit 6
    // will be 1" (60B8h bit 6 = 0: limit switch functions on).
    // The model's switch has no hysteresis and the drive holds the axis
    // within a count of its edge, so the input may chatter there: every
    // change is an EMCY (report). Checked: 5443h first, then 0000h and
    // 5443h alternating.
    let codes = |r: &Rig| r.emcy.iter().map(|f| (f.data()[0], f.data()[1], f.data()[2])).collect::<Vec<_>>();
    assert_limit_emcys(&codes(&r), (0x43, 0x54, 0x01));
    if r.dn().drive.view().digital_inputs & 2 != 0 {
        assert_eq!(r.upload(0x2000, 0, 2) & 0xC0, 0x40, "2000h bit 6 on the LSP");
    }
    r.emcy.clear();
    // Back off the switch (not in the example): target 0, new set-point.
    // "When a limit switch becomes inactive, the emergency error code
    // 0x0000 will be sent automatically and object 2000h bit 6 … 0".
    r.controlword(0x0F);
    r.target_position_rpdo2(0);
    r.controlword(0x1F);
    let bound = move_bound_ms(&mut r, E41_LSP_COUNTS, v);
    r.wait_sw("back at 0", SW_TARGET_REACHED, SW_TARGET_REACHED, bound);
    let c = codes(&r);
    assert_eq!(c.last(), Some(&(0x00, 0x00, 0x00)), "EMCY 0000h, error register clear: {c:02X?}");
    assert_eq!(r.upload(0x2000, 0, 2) & 0xC0, 0, "2000h bit 6 reset");
}

/// Limit switch EMCYs as received: `set` (code LSB, MSB, register) first,
/// then 0000h (register 0) and `set` alternating (§4.3.1).
fn assert_limit_emcys(c: &[(u8, u8, u8)], set: (u8, u8, u8)) {
    assert!(!c.is_empty(), "no limit switch EMCY");
    for (k, e) in c.iter().enumerate() {
        let want = if k % 2 == 0 { set } else { (0, 0, 0) };
        assert_eq!(*e, want, "EMCY {k} of {c:02X?}");
    }
}

/// §4.3.1: the negative limit switch sends EMCY 5442h (2000h bit 7) and
/// 0000h when released; with 60B8h bit 6 = 1 (limit switch functions
/// off) no EMCY is sent.
#[test]
fn lsn_emcy_and_60b8_bit6() {
    let lsn = -E41_LSP_COUNTS;
    let mut r = Rig::on(|c| c.params.axis.negative_limit = Some(deg(lsn)));
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    r.modes_of_operation(1);
    r.enable();
    r.sdo(0x6081, 0, &0x0002_0000u32.to_le_bytes());
    let v = iu_to_counts_s(f64::from(0x0002_0000));
    let bound = move_bound_ms(&mut r, -lsn, v);
    r.target_position_rpdo2(-8000);
    r.controlword(0x1F);
    r.wait_sw("LSN: internal limit active", 1 << 11, 1 << 11, bound);
    r.run_ms(10);
    let codes = |r: &Rig| r.emcy.iter().map(|f| (f.data()[0], f.data()[1], f.data()[2])).collect::<Vec<_>>();
    assert_limit_emcys(&codes(&r), (0x42, 0x54, 0x01));
    if r.dn().drive.view().digital_inputs & 1 != 0 {
        assert_eq!(r.upload(0x2000, 0, 2) & 0xC0, 0x80, "2000h bit 7 on the LSN");
    }
    r.emcy.clear();
    r.controlword(0x0F);
    r.target_position_rpdo2(0);
    r.controlword(0x1F);
    r.wait_sw("back at 0", SW_TARGET_REACHED, SW_TARGET_REACHED, bound);
    let c = codes(&r);
    assert_eq!(c.last(), Some(&(0x00, 0x00, 0x00)), "EMCY 0000h: {c:02X?}");
    assert_eq!(r.upload(0x2000, 0, 2) & 0xC0, 0, "2000h bit 7 reset");
    r.emcy.clear();
    // 60B8h bit 6 = 1: the EMCYs are disabled.
    r.sdo(0x60B8, 0, &0x0040u16.to_le_bytes());
    r.controlword(0x0F);
    r.target_position_rpdo2(-8000);
    r.controlword(0x1F);
    r.run_ms(bound);
    assert!(r.dn().drive.view().digital_inputs & 1 != 0, "on the LSN");
    assert!(codes(&r).is_empty(), "no EMCY with 60B8h bit 6 = 1: {:?}", codes(&r));
}

/// E26–E28 steps 2–5: RPDO3 := 60C1h:01 (X1) + 60C1h:02 (X2). On CAN the
/// Sync Manager assignment 1C12h:03 := 1602h is RPDO3 made valid (401h).
fn map_interpolation_rpdo3(r: &mut Rig) {
    r.sdo(0x1402, 1, &0x8000_0401u32.to_le_bytes());
    r.sdo(0x1402, 2, &[0xFF]);
    r.sdo(0x1602, 0, &[0]);
    r.sdo(0x1602, 1, &0x60C1_0120u32.to_le_bytes());
    r.sdo(0x1602, 2, &0x60C1_0220u32.to_le_bytes());
    r.sdo(0x1602, 0, &[2]);
    r.sdo(0x1402, 1, &0x0000_0401u32.to_le_bytes());
}

/// One interpolation point: X1 and X2 in RPDO3.
fn point(r: &mut Rig, x1: u32, x2: u32) {
    let (a, b) = (x1.to_le_bytes(), x2.to_le_bytes());
    r.send(Frame::new(0x401, &[a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]));
}

/// The PT X2 the examples print: time (bits 0–15), integrity counter in
/// byte 3 bits 1–7 (§9.2.2.2).
fn pt_x2(time: u16, ic: u8) -> u32 {
    u32::from(ic) << 25 | u32::from(time)
}

/// PVT X1/X2 from position, velocity (16.8 IU), time, counter (§9.2.2.3,
/// the layout every correctly printed E27/E28 point follows).
fn pvt_x(p: i32, v_16_8: i32, t: u16, ic: u8) -> (u32, u32) {
    let p = p as u32 & 0xFF_FFFF;
    let v = v_16_8 as u32 & 0xFF_FFFF;
    let t = u32::from(t) & 0x1FF;
    let x1 = (p >> 16) << 24 | (v & 0xFF) << 16 | (p & 0xFFFF);
    let x2 = u32::from(ic) << 25 | (t >> 8) << 24 | (t & 0xFF) << 16 | (v >> 8);
    (x1, x2)
}

/// EMCY FF01h frames received since the last call: their 2072h (bytes 3–4).
fn ip_status_emcys(r: &mut Rig) -> Vec<u16> {
    let v = r
        .emcy
        .iter()
        .filter(|f| f.data()[0..2] == [0x01, 0xFF])
        .map(|f| u16::from_le_bytes([f.data()[3], f.data()[4]]))
        .collect();
    r.emcy.clear();
    v
}

/// 2072h status bits (Table 9.2.1).
const IPS_EMPTY: u16 = 1 << 15;
const IPS_LOW: u16 = 1 << 14;
const IPS_INTEGRITY: u16 = 1 << 12;

/// Steps common to E26–E28 up to the buffer set-up: mapping, start,
/// 208Eh bit 8 := 0 (legacy interpolation; "must be 0 (default 1)": the
/// write is not printed, inserted by SDO), enable with `enable_cw`, mode 7.
fn legacy_ip_setup(r: &mut Rig, enable_cw: u16) {
    map_examples_rpdos(r);
    map_interpolation_rpdo3(r);
    r.start_remote_node();
    assert_eq!(r.upload(0x208E, 0, 2), 0x0100, "208Eh default: bit 8 = 1 (§4.9.11)");
    r.sdo(0x208E, 0, &0x0000u16.to_le_bytes());
    r.controlword(0x06);
    r.wait_sw("ready to switch on", 0x6F, 0x21, 100);
    r.controlword(0x07);
    r.wait_sw("switched on", 0x6F, 0x23, 100);
    r.controlword(enable_cw);
    r.wait_sw("operation enabled", 0x6F, 0x27, 100);
    r.modes_of_operation(7);
    r.run_ms(2);
    assert_eq!(r.upload(0x6061, 0, 1), 7);
}

/// Runs until `t_ms` after the start and checks 6062h against `want`
/// within the distance `slope` (counts/ms) covers in 2 ms, plus 2 counts.
fn demand_at(r: &mut Rig, now: &mut u64, t_ms: u64, want: f64, slope: f64) {
    r.run_ms(t_ms - *now);
    *now = t_ms;
    let got = r.od_i64(0x6062, 0) as f64;
    assert!(
        (got - want).abs() <= 2.0 * slope.abs() + 2.0,
        "6062h {got} at {t_ms} ms, the points give {want}"
    );
}

/// E26 (§9.4): absolute PT, 4 points, initial position 2079h = 1000.
#[test]
fn e26_pt_absolute() {
    let mut r = Rig::new();
    legacy_ip_setup(&mut r, 0x0F);
    // Steps 12–15.
    r.sdo(0x60C0, 0, &0i16.to_le_bytes());
    r.sdo(0x2073, 0, &0x000Cu16.to_le_bytes());
    r.sdo(0x2074, 0, &0xA001u16.to_le_bytes());
    r.sdo(0x2079, 0, &1000i32.to_le_bytes());
    r.emcy.clear();
    // Steps 17–20 as printed (X2 = IC << 25 | time).
    let points: [(i32, u16, u8, u32, u32); 4] = [
        (20_000, 1000, 1, 0x0000_4E20, 0x0200_03E8),
        (30_000, 2000, 2, 0x0000_7530, 0x0400_07D0),
        (2000, 1000, 3, 0x0000_07D0, 0x0600_03E8),
        (0, 500, 4, 0x0000_0000, 0x0800_01F4),
    ];
    for (k, &(p, t, ic, x1, x2)) in points.iter().enumerate() {
        assert_eq!((x1, x2), (p as u32, pt_x2(t, ic)), "point {} as printed", k + 1);
        point(&mut r, x1, x2);
        if k == 0 {
            // The buffer is no longer empty (nor low): EMCY FF01h with
            // 2072h (§9.2.3).
            let e = ip_status_emcys(&mut r);
            assert_eq!(e.len(), 1, "one FF01h EMCY: {e:04X?}");
            assert_eq!(e[0] & (IPS_EMPTY | IPS_LOW | IPS_INTEGRITY), 0, "2072h {:04X}h", e[0]);
        }
    }
    assert_eq!(r.od_i64(0x6062, 0), 0, "nothing moves before bit 4");
    // Step 21: 1Fh. "if the drive actual position before starting the
    // motion was 0, now it should be -1000 counts because of Step 15":
    // each point P is reached at P − 1000, linearly over its time.
    r.controlword(0x1F);
    let mut now = 0;
    let mut from = 0.0;
    let mut at = 0u64;
    for &(p, t, ..) in &points {
        let to = f64::from(p) - 1000.0;
        let slope = (to - from) / f64::from(t);
        demand_at(&mut r, &mut now, at + u64::from(t) / 2, (from + to) / 2.0, slope);
        demand_at(&mut r, &mut now, at + u64::from(t), to, slope);
        from = to;
        at += u64::from(t);
    }
    assert_eq!(at, 4500);
    r.run_ms(200);
    assert_eq!(r.od_i64(0x6062, 0), -1000);
    let p = r.upload(0x6064, 0, 4);
    assert!((p + 1000).abs() <= FEW_COUNTS, "6064h {p}, −1000 expected");
    // The buffer ran empty: FF01h with 2072h bit 15 (and low) set.
    let e = ip_status_emcys(&mut r);
    assert!(e.iter().any(|s| s & IPS_EMPTY != 0), "FF01h with buffer empty: {e:04X?}");
    assert_ne!(r.upload(0x2072, 0, 2) as u16 & IPS_EMPTY, 0);
}

/// E27 (§9.5): absolute PVT, 12 points, initial position = the position
/// demand (2074h = B001h).
#[test]
fn e27_pvt_absolute() {
    let mut r = Rig::new();
    legacy_ip_setup(&mut r, 0x0F);
    // Steps 12–14.
    r.sdo(0x60C0, 0, &(-1i16).to_le_bytes());
    r.sdo(0x2073, 0, &0x000Fu16.to_le_bytes());
    r.sdo(0x2074, 0, &0xB001u16.to_le_bytes());
    // Steps 16–27: (P, V in 16.8, T, printed X1, printed X2).
    // TYPO (§9.5 step 25): X2 printed "159AFF2" — the layout gives
    // 159AFFF2h. TYPO (step 26): X1 printed "FF990C2B" (P8's position
    // bytes) — P = −9135 = FFDC51h gives FF99DC51h. TYPO (step 27): X2
    // printed "18F0000" — 18F00000h; its velocity is printed "−7.4 IU
    // (0x00000)": the value sent is 0. The layout-derived values are sent.
    let pts: [(i32, i32, u16, u32, u32); 12] = [
        (88, 0x354, 55, 0x0054_0058, 0x0237_0003),
        (370, 0x6A8, 55, 0x00A8_0172, 0x0437_0006),
        (2982, 0x6A8, 390, 0x00A8_0BA6, 0x0786_0006),
        (5631, 0x6A8, 400, 0x00A8_15FF, 0x0990_0006),
        (5925, 0x300, 60, 0x0000_1725, 0x0A3C_0003),
        (6000, 0, 50, 0x0000_1770, 0x0C32_0000),
        (5127, -0x780, 240, 0x0080_1407, 0x0EF0_FFF8),
        (3115, -0xD55, 190, 0x00AB_0C2B, 0x10BE_FFF2),
        (-1686, -0xD55, 360, 0xFFAB_F96A, 0x1368_FFF2),
        (-7145, -0xD55, 410, 0xFFAB_E417, 0x159A_FFF2),
        (-9135, -0x767, 190, 0xFF99_DC51, 0x16BE_FFF8),
        (-10_000, 0, 240, 0xFF00_D8F0, 0x18F0_0000),
    ];
    for (k, &(p, v, t, x1, x2)) in pts.iter().enumerate() {
        assert_eq!(pvt_x(p, v, t, k as u8 + 1), (x1, x2), "point {}", k + 1);
        point(&mut r, x1, x2);
    }
    // 12 points in a 15-point buffer: neither full nor empty.
    assert_eq!(r.upload(0x2072, 0, 2) as u16 & (IPS_EMPTY | (1 << 13)), 0);
    // Step 28: 1Fh. The cubic passes through every point at its time.
    r.controlword(0x1F);
    let mut now = 0;
    let mut at = 0u64;
    let mut from = 0.0;
    let mut top = i64::MIN;
    for &(p, _, t, ..) in &pts {
        at += u64::from(t);
        let slope = (f64::from(p) - from) / f64::from(t);
        // Sample the way there for the extreme.
        while now + 10 < at {
            r.run_ms(10);
            now += 10;
            top = top.max(r.od_i64(0x6062, 0));
        }
        demand_at(&mut r, &mut now, at, f64::from(p), 2.0 * slope);
        top = top.max(r.od_i64(0x6062, 0));
        from = f64::from(p);
    }
    // "All points should be executed within 2.64s".
    assert_eq!(at, 2640);
    // "3 positive rotations and another 8 negatively": up to 6000 counts,
    // then down to −10000 (−5 rotations).
    assert!((top - 6000).abs() <= 5, "highest demand {top}, 3 rotations = 6000");
    r.run_ms(200);
    assert_eq!(r.od_i64(0x6062, 0), -10_000);
    let p = r.upload(0x6064, 0, 4);
    assert!((p + 10_000).abs() <= FEW_COUNTS, "6064h {p}, −10000 expected");
    assert!((r.motor_revs() + 5.0).abs() < 0.01, "{} rev, −5 expected", r.motor_revs());
    // The last velocity was 0: no quick stop (2072h bit 11), still enabled.
    assert_eq!(r.upload(0x2072, 0, 2) as u16 & (1 << 11), 0);
    assert_eq!(r.sw.unwrap() & 0x6F, 0x27);
}

/// E28 (§9.6): relative PVT, 6 points, controlword 4Fh/5Fh.
#[test]
fn e28_pvt_relative() {
    let mut r = Rig::new();
    // Step 10: 4Fh (enable operation, relative).
    legacy_ip_setup(&mut r, 0x4F);
    r.cw = 0x4F;
    r.sdo(0x60C0, 0, &(-1i16).to_le_bytes());
    r.sdo(0x2073, 0, &0x000Cu16.to_le_bytes());
    r.sdo(0x2074, 0, &0xA001u16.to_le_bytes());
    // Steps 16–21 (X1 printed with 7 digits, e.g. "00004D8").
    let pts: [(i32, i32, u32, u32); 6] = [
        (400, 0x300, 0x0000_0190, 0x02FA_0003),
        (1240, 0x600, 0x0000_04D8, 0x04FA_0006),
        (1674, 0x600, 0x0000_068A, 0x06FA_0006),
        (1666, 0x600, 0x0000_0682, 0x08FA_0006),
        (1240, 0x300, 0x0000_04D8, 0x0AFA_0003),
        (410, 0, 0x0000_019A, 0x0CFA_0000),
    ];
    for (k, &(p, v, x1, x2)) in pts.iter().enumerate() {
        assert_eq!(pvt_x(p, v, 250, k as u8 + 1), (x1, x2), "point {}", k + 1);
        point(&mut r, x1, x2);
    }
    // Step 22: 5Fh. Each point is a distance from the previous one.
    r.controlword(0x5F);
    let mut now = 0;
    let mut sum = 0.0;
    for (k, &(p, v, ..)) in pts.iter().enumerate() {
        sum += f64::from(p);
        // The speed there: the velocity of the point [counts/ms].
        let slope = f64::from(v) / 256.0 + f64::from(p) / 250.0;
        demand_at(&mut r, &mut now, 250 * (k as u64 + 1), sum, slope);
    }
    // "the final position should be 6630 IU (3.315 rotation …) All points
    // should be executed in 1.5s".
    assert_eq!(sum, 6630.0);
    r.run_ms(200);
    assert_eq!(r.od_i64(0x6062, 0), 6630);
    let p = r.upload(0x6064, 0, 4);
    assert!((p - 6630).abs() <= FEW_COUNTS, "6064h {p}");
    assert!((r.motor_revs() - 3.315).abs() < 0.005, "{} rev", r.motor_revs());
}

/// E24 (§9.2.8): the integrity counter. A point with a counter 2 ahead is
/// ignored with EMCY FF01h and 2072h bit 12; the same counter again is
/// ignored with EMCY FF01h; the right one is taken and clears bit 12.
/// Only the points taken are travelled.
#[test]
fn e24_integrity_counter() {
    let mut r = Rig::new();
    legacy_ip_setup(&mut r, 0x0F);
    r.sdo(0x60C0, 0, &0i16.to_le_bytes());
    r.sdo(0x2073, 0, &0x000Cu16.to_le_bytes());
    // Clear, counter := 1, initial position = the demand (B001h).
    r.sdo(0x2074, 0, &0xB001u16.to_le_bytes());
    point(&mut r, 1000, pt_x2(100, 1));
    ip_status_emcys(&mut r);
    // IC 3 instead of 2: ignored, integrity error.
    point(&mut r, 50_000, pt_x2(100, 3));
    let e = ip_status_emcys(&mut r);
    assert_eq!(e.len(), 1, "{e:04X?}");
    assert_ne!(e[0] & IPS_INTEGRITY, 0, "2072h {:04X}h: integrity counter error", e[0]);
    // IC 1 again (the same as the last taken): ignored with an EMCY.
    point(&mut r, 60_000, pt_x2(100, 1));
    assert_eq!(ip_status_emcys(&mut r).len(), 1);
    // IC 2: taken, the error goes away (EMCY FF01h with bit 12 clear).
    point(&mut r, 2000, pt_x2(100, 2));
    let e = ip_status_emcys(&mut r);
    assert!(e.iter().any(|s| s & IPS_INTEGRITY == 0), "{e:04X?}");
    assert_eq!(r.upload(0x2072, 0, 2) as u16 & IPS_INTEGRITY, 0);
    // Wrong counter with checking off (2074h bit 14): taken.
    r.sdo(0x2074, 0, &0x4000u16.to_le_bytes());
    point(&mut r, 3000, pt_x2(100, 77));
    r.controlword(0x1F);
    r.run_ms(100);
    assert!((r.od_i64(0x6062, 0) - 1000).abs() <= 20, "first point at 100 ms");
    r.run_ms(100);
    assert!((r.od_i64(0x6062, 0) - 2000).abs() <= 20, "the ignored points were not travelled");
    r.run_ms(300);
    assert_eq!(r.od_i64(0x6062, 0), 3000);
    // 2073h = 0 is not allowed (§9.2.4); above 000Fh neither (§9.4).
    r.sdo.clear();
    r.send(Frame::new(0x601, &[0x2B, 0x73, 0x20, 0, 0, 0, 0, 0]));
    assert_eq!(r.sdo.len(), 1);
    assert_eq!(r.sdo[0].data()[0], 0x80, "2073h := 0 aborted");
    r.sdo.clear();
}

/// E32 (§11.4): electronic gearing through online communication. The
/// master position 201Eh comes in RPDO2 every 1 ms communication cycle
/// with the SYNC ("It is recommended to set the SYNC 0 time equal to the
/// communication cycle and slow loop"); master resolution 2000 (a
/// 500-line master encoder, cyclic).
#[test]
fn e32_gearing_online() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    // Step 1: 201Eh in an RPDO (RPDO2, instead of 607Ah).
    r.sdo(0x1401, 1, &0x8000_0301u32.to_le_bytes());
    r.sdo(0x1601, 0, &[0]);
    r.sdo(0x1601, 1, &0x201E_0020u32.to_le_bytes());
    r.sdo(0x1601, 0, &[1]);
    r.sdo(0x1401, 1, &0x0000_0301u32.to_le_bytes());
    // Step 2: operational; step 3: mode FFh; step 4: 06h, 07h, 0Fh.
    r.start_remote_node();
    r.modes_of_operation(-1);
    r.enable();
    assert_eq!(r.upload(0x6061, 0, 1), -1, "6061h shows gearing");
    // Steps 5–8.
    r.sdo(0x201D, 0, &1u16.to_le_bytes());
    r.sdo(0x2012, 0, &0x0000_07D0u32.to_le_bytes());
    r.sdo(0x2013, 1, &1i16.to_le_bytes());
    r.sdo(0x2013, 2, &1u16.to_le_bytes());
    let master = |m: i64| Frame::new(0x301, &((m.rem_euclid(2000)) as i32).to_le_bytes());
    // Step 9: the initial master position (1500); the slave holds.
    let mut m = 1500i64;
    for _ in 0..20 {
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    assert_eq!(r.od_i64(0x2017, 0), 1500, "2017h: master actual position");
    let start = r.od_i64(0x6064, 0);
    // A master move before bit 4: not followed.
    for _ in 0..20 {
        m += 10;
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    assert!((r.od_i64(0x6062, 0) - start).abs() <= 1, "not engaged: the slave holds");
    // Step 10: 1Fh starts gearing; step 11: the master moves 20 counts
    // per 1 ms cycle (20 IU), through its 2000-count roll-over.
    r.controlword(0x1F);
    let d0 = r.od_i64(0x6062, 0);
    let cycles = 1000i64;
    for _ in 0..cycles {
        m += 20;
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    assert_eq!(r.od_i64(0x2018, 0), 20, "2018h: master speed 20 increments/sample");
    // "Slave speed equals master position difference per slow loop": the
    // ratio 1/1 takes the master's 20000 counts (ten roll-overs) one for
    // one. The slave lags up to two cycles: the RPDO sent before a SYNC
    // is latched at that SYNC and interpolated over the next 1 ms.
    let lag = 2 * 20;
    let moved = r.od_i64(0x6062, 0) - d0;
    assert!((moved - 20 * cycles).abs() <= lag, "slave demand moved {moved}, master {}", 20 * cycles);
    let v = r.upload(0x606C, 0, 4) as f64;
    assert!((v - 20.0 * FIX).abs() <= ONE_READING_IU, "606Ch {v}, the master's 20 IU");
    // Statusword bit 10 is always 0 in gearing with Halt = 0 (Table
    // 11.1.2).
    assert_eq!(r.sw.unwrap() & (SW_TARGET_REACHED | 0x6F), 0x27, "{:04X?}", r.sw);
    // §11.2.3: 2013h:01 alone does not change the ratio; with 2013h:02
    // written after it, −1/2 reverses at half the master's speed.
    r.sdo(0x2013, 1, &(-1i16).to_le_bytes());
    let d1 = r.od_i64(0x6062, 0);
    for _ in 0..100 {
        m += 20;
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    let moved = r.od_i64(0x6062, 0) - d1;
    assert!((moved - 2000).abs() <= lag, "ratio still 1/1 before 2013h:02: moved {moved}");
    r.sdo(0x2013, 2, &2u16.to_le_bytes());
    let d2 = r.od_i64(0x6062, 0);
    for _ in 0..100 {
        m += 20;
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    let moved = r.od_i64(0x6062, 0) - d2;
    assert!((moved + 1000).abs() <= lag, "ratio −1/2: moved {moved}, −1000 expected");
    // The actual position follows the demand.
    for _ in 0..50 {
        sync_cycle(&mut r, master(m), 1, 0x6062);
    }
    let p = r.upload(0x6064, 0, 4);
    let dem = r.upload(0x6062, 0, 4);
    assert!((p - dem).abs() <= FEW_COUNTS, "6064h {p}, 6062h {dem}");
}

/// §9.2.3 bit 11: PVT with the buffer run empty after a point whose
/// velocity is not 0 — the drive performs a quick stop and sets 2072h bit
/// 11 (EMCY FF01h); with a last velocity 0 (E27, E28) it stays enabled.
#[test]
fn pvt_empty_buffer_with_speed_quick_stops() {
    let mut r = Rig::new();
    legacy_ip_setup(&mut r, 0x0F);
    r.sdo(0x60C0, 0, &(-1i16).to_le_bytes());
    r.sdo(0x2074, 0, &0xB001u16.to_le_bytes());
    // 1000 counts in 200 ms, ending at 5 counts/ms: then nothing.
    let (x1, x2) = pvt_x(1000, 5 * 256, 200, 1);
    point(&mut r, x1, x2);
    r.emcy.clear();
    r.controlword(0x1F);
    r.run_ms(150);
    assert_eq!(r.sw.unwrap() & 0x6F, 0x27, "moving");
    assert_eq!(r.upload(0x2072, 0, 2) as u16 & (1 << 11), 0);
    r.run_ms(100);
    let st = r.upload(0x2072, 0, 2) as u16;
    assert_ne!(st & (1 << 11), 0, "2072h {st:04X}h: quick stop after buffer empty");
    assert!(ip_status_emcys(&mut r).iter().any(|s| s & (1 << 11) != 0), "FF01h with bit 11");
    // The quick stop left Operation enabled; 605Ah (quick stop option
    // code) decides where it ends: Quick stop active or, as here,
    // Switch on disabled.
    r.run_ms(100);
    let sw = r.sw.unwrap();
    assert!(matches!(sw & 0x6F, 0x07 | 0x40 | 0x60), "statusword {sw:04X}h after the quick stop");
    assert!(r.dn().drive.model().velocity().abs() < 1e-3, "at rest");
}

/// E31 (§11.3): electronic gearing through the second encoder input. The
/// master encoder (2000 counts/rev, the same 500-line encoder) is the
/// personality's simulated second encoder input (`Ipos::set_second_encoder`);
/// the drive's csp stand-in takes the reference at a 1 ms SYNC (the
/// EtherCAT cycle of the example's network).
#[test]
fn e31_gearing_second_encoder() {
    let mut r = Rig::new();
    map_examples_rpdos(&mut r);
    r.start_remote_node();
    // Steps 2–3: mode FFh, 06h, 07h, 0Fh.
    r.modes_of_operation(-1);
    r.enable();
    // Steps 4–7: 201Dh := 3 (digital: the 2nd encoder), 2012h := 7D0h,
    // 2013h := 1/1.
    r.sdo(0x201D, 0, &3u16.to_le_bytes());
    r.sdo(0x2012, 0, &0x0000_07D0u32.to_le_bytes());
    r.sdo(0x2013, 1, &1i16.to_le_bytes());
    r.sdo(0x2013, 2, &1u16.to_le_bytes());
    let enc = |r: &mut Rig, m: i64| {
        let id = r.dut;
        let pn = r.bus.node_mut::<PersonalityNode>(id).unwrap();
        pn.behaviour_mut::<Ipos>().unwrap().set_second_encoder(m.rem_euclid(2000));
    };
    // Step 8 (201Eh) is not used with 201Dh = 3: an online master position
    // is ignored.
    r.sdo(0x201E, 0, &500i32.to_le_bytes());
    let mut m = 100i64;
    enc(&mut r, m);
    let sync = |r: &mut Rig| {
        r.bus.send_from(r.probe, Frame::new(0x080, &[]));
        r.run_us(1000);
    };
    for _ in 0..10 {
        sync(&mut r);
    }
    assert_eq!(r.od_i64(0x2017, 0), 100, "2017h: the encoder, not 201Eh");
    // Step 9: 1Fh; step 10: the master turns 15 counts per ms for 1 s.
    r.controlword(0x1F);
    let d0 = r.od_i64(0x6062, 0);
    for _ in 0..1000 {
        m += 15;
        enc(&mut r, m);
        sync(&mut r);
    }
    let moved = r.od_i64(0x6062, 0) - d0;
    assert!((moved - 15_000).abs() <= 2 * 15, "slave demand moved {moved}, the master 15000");
    for _ in 0..50 {
        sync(&mut r);
    }
    let p = r.upload(0x6064, 0, 4);
    assert!((p - (d0 + 15_000)).abs() <= FEW_COUNTS, "6064h {p}, 1:1 from where it stood");
}
