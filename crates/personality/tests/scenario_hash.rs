//! A long scenario per personality on a 1 Mbit/s virtual bus in simulated
//! time — NMT start, SYNC at 1 kHz, enable, a profile-position move,
//! homing, profile velocity, a CSP sine streamed one target per SYNC,
//! disable, with SDO uploads of every sub-object in motion and at the end
//! — whose frame log (candump lines with timestamps) and final dictionary
//! bytes are hashed. The expected hashes were taken before the drives
//! stopped re-publishing unchanged live values every control period: any
//! frame, timestamp or dictionary byte that changes fails the test.
//!
//! `DRIVEBUS_SCENARIO_LOG=DIR` writes each log to `DIR/<name>.log`
//! (`sha256sum` them to compare two trees).

use drivebus_bus::{Bus, BusConfig, ProbeId};
use drivebus_can::{Duration, Frame};
use drivebus_personality::{PersonalityDevice, Profile};

const ID: u8 = 1;

/// FNV-1a, 64 bits: a stable hash without a dependency.
struct Fnv(u64);

impl Fnv {
    fn new() -> Fnv {
        Fnv(0xCBF2_9CE4_8422_2325)
    }
    fn add(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ u64::from(x)).wrapping_mul(0x0100_0000_01B3);
        }
    }
}

struct Sim {
    bus: Bus,
    probe: ProbeId,
    dut: drivebus_bus::NodeId,
}

impl Sim {
    fn new(profile: Profile) -> Sim {
        let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
        let probe = bus.attach_probe();
        let dut = bus.attach(profile.build(ID).expect("build"));
        bus.run_for(Duration::from_millis(5));
        Sim { bus, probe, dut }
    }

    fn pn(&self) -> &PersonalityDevice {
        self.bus.node::<PersonalityDevice>(self.dut).expect("dut")
    }

    fn send(&mut self, id: u16, data: &[u8]) {
        self.bus.send_from(self.probe, Frame::new(id, data));
    }

    /// One SDO request; runs until the node's response (at most 5 ms).
    fn sdo(&mut self, data: [u8; 8]) -> [u8; 8] {
        self.bus.take_received(self.probe);
        self.send(0x600 + u16::from(ID), &data);
        for _ in 0..50 {
            self.bus.run_for(Duration::from_micros(100));
            let r = self.bus.take_received(self.probe);
            if let Some(f) = r.iter().find(|f| f.std_id() == Some(0x580 + u16::from(ID))) {
                return *f.raw_data();
            }
        }
        [0; 8]
    }

    fn write(&mut self, index: u16, sub: u8, value: &[u8]) {
        let [il, ih] = index.to_le_bytes();
        let mut b = [0x23 | ((4 - value.len() as u8) << 2), il, ih, sub, 0, 0, 0, 0];
        b[4..4 + value.len()].copy_from_slice(value);
        self.sdo(b);
    }

    /// Upload, expedited or segmented (the bytes go to the log only).
    fn upload(&mut self, index: u16, sub: u8) {
        let [il, ih] = index.to_le_bytes();
        let d = self.sdo([0x40, il, ih, sub, 0, 0, 0, 0]);
        if d[0] & 0xE2 != 0x40 {
            return;
        }
        let mut toggle = 0u8;
        for _ in 0..64 {
            let s = self.sdo([0x60 | toggle << 4, 0, 0, 0, 0, 0, 0, 0]);
            if s[0] & 0xE0 != 0 || s[0] & 1 != 0 {
                return;
            }
            toggle ^= 1;
        }
    }

    /// Uploads every sub-object of the dictionary.
    fn upload_all(&mut self) {
        let entries: Vec<(u16, u8)> = self
            .pn()
            .node
            .od()
            .objects()
            .iter()
            .flat_map(|o| o.subs().iter().map(move |s| (o.index, s.sub)))
            .collect();
        for (i, s) in entries {
            self.upload(i, s);
        }
    }

    /// `ms` SYNC periods; `each(k)` may write a set-point before SYNC k.
    fn cycles(&mut self, ms: u32, mut each: impl FnMut(&mut Sim, u32)) {
        for k in 0..ms {
            each(self, k);
            self.send(0x080, &[]);
            self.bus.run_for(Duration::from_millis(1));
        }
    }

    fn cw(&mut self, cw: u16) {
        self.write(0x6040, 0, &cw.to_le_bytes());
        self.cycles(5, |_, _| {});
    }

    fn mode(&mut self, m: i8) {
        self.write(0x6060, 0, &m.to_le_bytes());
        self.cycles(3, |_, _| {});
    }
}

/// The scenario; the frame log's and the final dictionary's hashes.
fn run(profile: Profile) -> (u64, u64, usize) {
    let mut s = Sim::new(profile);
    s.send(0x000, &[0x01, 0]);
    s.cycles(10, |_, _| {});
    // Enable in pp.
    s.write(0x6081, 0, &20_000u32.to_le_bytes());
    s.write(0x6083, 0, &200_000u32.to_le_bytes());
    s.write(0x6084, 0, &200_000u32.to_le_bytes());
    s.mode(1);
    for cw in [0x06, 0x07, 0x0F] {
        s.cw(cw);
    }
    // A move, uploads of everything while moving.
    s.write(0x607A, 0, &5_000i32.to_le_bytes());
    s.cw(0x1F);
    s.cycles(20, |_, _| {});
    s.upload_all();
    s.cycles(300, |_, _| {});
    s.cw(0x0F);
    // Homing on the current position (35 and the newer 37).
    s.mode(6);
    s.write(0x6098, 0, &37i8.to_le_bytes());
    s.write(0x6098, 0, &35i8.to_le_bytes());
    s.cw(0x1F);
    s.cycles(100, |_, _| {});
    s.cw(0x0F);
    // Profile velocity, then stop.
    s.mode(3);
    s.write(0x60FF, 0, &10_000i32.to_le_bytes());
    s.cycles(200, |_, _| {});
    s.write(0x60FF, 0, &0i32.to_le_bytes());
    s.cycles(100, |_, _| {});
    // CSP: a sine, one target per SYNC.
    s.mode(8);
    s.cycles(500, |s, k| {
        let t = f64::from(k) / 1000.0;
        let p = (3000.0 * (1.0 - (2.0 * std::f64::consts::PI * t / 0.5).cos())).round() as i32;
        s.write(0x607A, 0, &p.to_le_bytes());
        s.upload(0x6064, 0);
        s.upload(0x606C, 0);
        if k == 250 {
            s.upload_all();
        }
    });
    // Halt, quick stop, disable.
    s.cw(0x010F);
    s.cw(0x0B);
    s.cycles(50, |_, _| {});
    s.cw(0x00);
    s.cycles(20, |_, _| {});
    s.upload_all();
    s.send(0x000, &[0x80, 0]);
    s.cycles(10, |_, _| {});

    let lines = s.bus.log_lines();
    let mut log = Fnv::new();
    for l in &lines {
        log.add(l.as_bytes());
        log.add(b"\n");
    }
    if let Some(dir) = std::env::var_os("DRIVEBUS_SCENARIO_LOG") {
        let text: String = lines.iter().map(|l| format!("{l}\n")).collect();
        let path = std::path::Path::new(&dir).join(format!("{}.log", profile.name()));
        std::fs::write(path, text).expect("write log");
    }
    let mut od = Fnv::new();
    for o in s.pn().node.od().objects() {
        for e in o.subs() {
            od.add(&o.index.to_le_bytes());
            od.add(&[e.sub]);
            od.add(e.bytes());
        }
    }
    (log.0, od.0, lines.len())
}

/// (profile, frame log hash, dictionary hash, frames), taken before the
/// change to the live values' publication.
const EXPECTED: [(Profile, u64, u64, usize); 6] = [
    (Profile::Kc1, 0x30718BA3DD377625, 0xD009E0B995F5AD34, 154149),
    (Profile::Akd, 0xDF18D8FCC1B5FE8B, 0xD39F8734116A6C0A, 175455),
    (Profile::Ipos, 0xE475B53777B2C170, 0x221336BEDB4C285A, 71691),
    (Profile::Ssd630, 0x525E04AEE1E95DC5, 0xE96D63979BEF1601, 53336),
    (Profile::Dds6, 0x0C65A3E64A03D9C0, 0x636B6B5FD451670B, 6280),
    (Profile::Generic, 0x179C26E491CBD519, 0x194E338BCA0D6DBF, 170068),
];

#[test]
fn scenario_frame_logs_unchanged() {
    let mut got = Vec::new();
    for &p in Profile::all() {
        let (log, od, n) = run(p);
        println!("(Profile::{p:?}, 0x{log:016X}, 0x{od:016X}, {n}),");
        got.push((p, log, od, n));
    }
    assert_eq!(got, EXPECTED.to_vec());
}
