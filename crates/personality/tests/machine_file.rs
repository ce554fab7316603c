//! The machine file (`machine::MachineFile`, `docs/machine.md`): a good
//! file laid over the profile defaults, every kind of error with its line
//! and column, the per-profile defaults, and faults applied at run time —
//! a limit switch that trips stops the drive as it stops at a switch the
//! axis reaches (CiA 402-2 60FDh; iPOS §4.3.1 EMCY 5443h), an encoder fault
//! faults the drive (7305h).

use drivebus_can::{Device, Frame, Instant};
use drivebus_personality::machine::{FaultKind, Machine, MachineFile, Polarity, Switch};
use drivebus_personality::{PersonalityDevice, Profile};

const GOOD: &str = r#"
# node 5: a longer rotary axis with a gearbox
[[node]]
id = 5
feed = 360
gear_ratio = 4.0
start = -90.0

[node.limits]
negative = -900.0
positive = 900
polarity = "no"

[node.home_switch]
from = 45.0
to = 135.0

[node.index]
offset = 90.0

[node.load]
inertia = 2.0e-4
coulomb_friction = 0.1

[[node.faults]]
at = 1.5
kind = "trip"
switch = "positive_limit"
duration = 0.25

[[node.faults]]
at = 3
kind = "encoder"

[[node]]
id = 6
hard_stops = { enabled = false }
home_switch = { enabled = false }
"#;

#[test]
fn a_good_file_changes_only_what_it_names() {
    let f = MachineFile::parse(GOOD).unwrap();
    assert_eq!(f.nodes().collect::<Vec<_>>(), [5, 6]);
    let m = f.machine_for(Profile::Generic, 5).unwrap();
    let d = Machine::default_for(Profile::Generic);
    assert_eq!((m.feed, m.gear_ratio, m.start), (360.0, 4.0, -90.0));
    let l = m.limits.unwrap();
    assert_eq!((l.negative, l.positive, l.polarity), (-900.0, 900.0, Polarity::NormallyOpen));
    // Not named: kept from the default.
    assert_eq!(l.hysteresis, d.limits.unwrap().hysteresis);
    assert_eq!(m.hard_stops, d.hard_stops);
    let h = m.home_switch.unwrap();
    assert_eq!((h.from, h.to, h.polarity), (45.0, 135.0, Polarity::NormallyOpen));
    assert_eq!(m.index_offset, 90.0);
    assert_eq!((m.load.inertia, m.load.coulomb_friction), (2.0e-4, 0.1));
    assert_eq!(m.load.viscous_friction, d.load.viscous_friction);
    assert_eq!(m.faults.len(), 2);
    assert_eq!(m.faults[0].kind, FaultKind::Trip(Switch::PositiveLimit));
    assert_eq!((m.faults[0].at, m.faults[0].duration), (1.5, Some(0.25)));
    assert_eq!((m.faults[1].kind, m.faults[1].duration), (FaultKind::Encoder, None));
    let six = f.machine_for(Profile::Dds6, 6).unwrap();
    assert_eq!((six.hard_stops, six.home_switch), (None, None));
    assert_eq!(six.limits, Machine::default_for(Profile::Dds6).limits);
    // A node without a table: its profile's default.
    assert_eq!(f.machine_for(Profile::Akd, 7).unwrap(), Machine::default_for(Profile::Akd));
    assert!(f.check_nodes(&[5, 6, 7]).is_ok());
    let e = f.check_nodes(&[5]).unwrap_err();
    assert_eq!((e.line, e.column), (36, 6), "{e}");
    assert!(e.message.contains("node 6 has a machine but no drive"), "{e}");
    // The machine builds and runs.
    let mut dev = Profile::Generic.build_on(5, &m).unwrap();
    dev.start(Instant::ZERO, &mut Vec::new());
    assert_eq!(dev.app.drive.model().params().axis.gear_ratio, 4.0);
}

/// Parses `text` as node 5 of `profile` and returns the error's line,
/// column and message.
fn error(text: &str) -> (usize, usize, String) {
    let e = match MachineFile::parse(text) {
        Err(e) => e,
        Ok(f) => f.machine_for(Profile::Generic, 5).expect_err("an error"),
    };
    assert!(e.to_string().starts_with(&format!("line {}, column {}: ", e.line, e.column)), "{e}");
    (e.line, e.column, e.message)
}

#[test]
fn every_error_names_its_line_and_column() {
    // TOML syntax.
    let (l, c, m) = error("[[node]]\nid = 5\nfeed = \n");
    assert_eq!((l, c), (3, 8), "{m}");
    // Unknown key.
    let (l, c, m) = error("[[node]]\nid = 5\nfede = 10.0\n");
    assert_eq!((l, c), (3, 1), "{m}");
    assert!(m.contains("unknown field `fede`"), "{m}");
    let (l, c, m) = error("[[node]]\nid = 5\n[node.limits]\nnegatve = 1.0\n");
    assert_eq!((l, c), (4, 1), "{m}");
    assert!(m.contains("negatve"), "{m}");
    // Wrong type.
    let (l, c, m) = error("[[node]]\nid = 5\ngear_ratio = \"five\"\n");
    assert_eq!((l, c), (3, 14), "{m}");
    assert!(m.contains("invalid type"), "{m}");
    // Missing node-ID.
    let (l, _, m) = error("[[node]]\nfeed = 10.0\n");
    assert_eq!(l, 1, "{m}");
    assert!(m.contains("missing field `id`"), "{m}");
    // Node-ID out of range, and given twice.
    let (l, c, m) = error("[[node]]\nid = 0\n");
    assert_eq!((l, c, m.as_str()), (2, 6, "node id 0 is not in 1..127"));
    let (l, c, m) = error("[[node]]\nid = 5\n[[node]]\nid = 5\n");
    assert_eq!((l, c, m.as_str()), (4, 6, "node 5 is given twice"));
    // Unknown enumeration values.
    let (l, c, m) = error("[[node]]\nid = 5\nlimits = { polarity = \"nx\" }\n");
    assert_eq!((l, c), (3, 23), "{m}");
    let (l, c, m) = error("[[node]]\nid = 5\n[[node.faults]]\nat = 1.0\nkind = \"explode\"\n");
    assert_eq!((l, c), (5, 8), "{m}");
    assert!(m.contains("explode"), "{m}");
    // A value out of range, and values in the wrong order: at the key.
    let (l, c, m) = error("[[node]]\nid = 5\n  gear_ratio = -2.0\n");
    assert_eq!((l, c), (3, 16), "{m}");
    assert_eq!(m, "node 5: gear_ratio: -2 must be above 0");
    let (l, c, m) = error("[[node]]\nid = 5\n[node.limits]\nnegative = 100.0\npositive = -100.0\n");
    assert_eq!((l, c), (4, 12), "{m}");
    assert!(m.contains("limits.negative: 100 must be below limits.positive (-100)"), "{m}");
    let (l, c, m) = error("[[node]]\nid = 5\n[node.limits]\nhysteresis = 5000.0\n");
    assert_eq!((l, c), (4, 14), "{m}");
    assert!(m.contains("less than half the travel"), "{m}");
    let (l, c, m) = error("[[node]]\nid = 5\nstart = 99999.0\n");
    assert_eq!((l, c), (3, 9), "{m}");
    assert!(m.contains("beyond a hard stop"), "{m}");
    let (l, c, m) = error("[[node]]\nid = 5\n[node.hard_stops]\npositive = 1000.0\n");
    assert_eq!((l, c), (4, 12), "a limit switch behind its stop, at the stop: {m}");
    assert!(m.contains("limits.positive: must be inside hard_stops.positive"), "{m}");
    let (l, c, m) = error("[[node]]\nid = 5\n[node.home_switch]\nenabled = true\nfrom = 0.0\nto = 0.0\n");
    assert_eq!((l, c), (5, 8), "{m}");
    let (l, c, m) =
        error("[[node]]\nid = 5\n[node.limits]\nenabled = false\n[node.hard_stops]\npositive = -10.0\n");
    assert_eq!((l, c), (6, 12), "no limit switches, but the start beyond the stop? {m}");
    let (l, c, m) = error("[[node]]\nid = 5\nload = { inertia = -1.0 }\n");
    assert_eq!((l, c), (3, 20), "{m}");
    // Faults: a switch where one belongs, times.
    let (l, c, m) = error("[[node]]\nid = 5\n[[node.faults]]\nat = 1.0\nkind = \"trip\"\n");
    assert_eq!((l, c), (5, 8), "{m}");
    assert!(m.contains("needs `switch`"), "{m}");
    let (l, c, m) =
        error("[[node]]\nid = 5\n[[node.faults]]\nat = 1.0\nkind = \"encoder\"\nswitch = \"home_switch\"\n");
    assert_eq!((l, c), (6, 10), "{m}");
    let (l, c, m) = error("[[node]]\nid = 5\n[[node.faults]]\nat = -1.0\nkind = \"encoder\"\n");
    assert_eq!((l, c), (4, 6), "{m}");
    assert!(m.contains("faults[0].at"), "{m}");
    let (l, c, m) =
        error("[[node]]\nid = 5\n[[node.faults]]\nat = 1.0\nkind = \"over_current\"\nduration = 0.0\n");
    assert_eq!((l, c), (6, 12), "{m}");
    // Not a number.
    let (l, c, m) = error("[[node]]\nid = 5\nfeed = nan\n");
    assert_eq!((l, c), (3, 8), "{m}");
    // An empty file is a file without tables.
    assert_eq!(MachineFile::parse("").unwrap().nodes().count(), 0);
}

#[test]
fn default_machines_suit_their_products() {
    for &p in Profile::all() {
        let m = Machine::default_for(p);
        m.check().unwrap();
        let (l, h, s) = (m.limits.unwrap(), m.home_switch.unwrap(), m.hard_stops.unwrap());
        let r = m.units_per_motor_rev();
        // Switches some revolutions either side, the home switch between,
        // hard stops beyond, the start left of the home switch.
        assert!(s.negative < l.negative && l.negative <= -3.0 * r, "{p}");
        assert!(s.positive > l.positive && l.positive >= 3.0 * r, "{p}");
        assert!(l.negative < h.from && h.to < l.positive && m.start < h.from, "{p}");
        assert_eq!(l.polarity, Polarity::NormallyClosed, "{p}: fail-safe limit switches");
        assert!(m.load.inertia > 0.0 && m.faults.is_empty(), "{p}");
        // The load, reflected, is near the rotor: the loops stay tuned.
        let reflected = m.load.inertia / (m.gear_ratio * m.gear_ratio);
        assert!((1.0e-5..=4.0e-5).contains(&reflected), "{p}: {reflected}");
        // Applied to the drive it is built with.
        let dev = p.build_on_default_machine(1).unwrap();
        let a = dev.app.drive.model().params().axis;
        assert_eq!((a.feed_constant, a.gear_ratio), (m.feed, m.gear_ratio), "{p}");
        assert_eq!((a.negative_limit, a.positive_limit), (Some(l.negative), Some(l.positive)), "{p}");
        assert_eq!(a.home_switch, Some((h.from, h.to)), "{p}");
    }
    let g = |p| {
        let m = Machine::default_for(p);
        (m.feed, m.gear_ratio)
    };
    // The Kollmorgen servos on a 10 mm ball screw, the iPOS and 630 behind
    // gearboxes, the DDS6 stepper on a 5 mm lead screw (docs/machine.md).
    assert_eq!(g(Profile::Kc1), (10.0, 1.0));
    assert_eq!(g(Profile::Akd), (10.0, 1.0));
    assert_eq!(g(Profile::Ipos), (360.0, 5.0));
    assert_eq!(g(Profile::Ssd630), (360.0, 3.0));
    assert_eq!(g(Profile::Dds6), (5.0, 1.0));
    assert_eq!(g(Profile::Generic), (360.0, 1.0));
    assert_eq!(Machine::default(), Machine::default_for(Profile::Generic));
    assert!(matches!(MotorKindOf::of(Profile::Dds6), drivebus_cia402::model::MotorKind::Stepper(_)));
}

struct MotorKindOf;
impl MotorKindOf {
    fn of(p: Profile) -> drivebus_cia402::model::MotorKind {
        p.build_on_default_machine(1).unwrap().app.drive.model().params().motor.kind
    }
}

/// A drive on the virtual clock, stepped from deadline to deadline.
struct Run {
    dev: PersonalityDevice,
    now: Instant,
    frames: Vec<Frame>,
}

impl Run {
    fn new(p: Profile, m: &Machine) -> Run {
        let mut dev = p.build_on(3, m).unwrap();
        let mut frames = Vec::new();
        dev.start(Instant::ZERO, &mut frames);
        Run { dev, now: Instant::ZERO, frames }
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8]) {
        assert_eq!(
            self.dev.write_object(index, sub, data, self.now, &mut self.frames),
            Ok(()),
            "{index:04X}h"
        );
    }
    fn read_u32(&mut self, index: u16) -> u32 {
        let b = self.dev.read_object(index, 0, self.now).unwrap().to_vec();
        let mut a = [0u8; 4];
        a[..b.len().min(4)].copy_from_slice(&b[..b.len().min(4)]);
        u32::from_le_bytes(a)
    }
    fn run_to_s(&mut self, t: f64) {
        let until = Instant::from_nanos((t * 1e9) as u64);
        while self.now < until {
            let next = self.dev.poll(self.now, &mut self.frames).unwrap_or(until);
            self.now = next.clamp(Instant::from_nanos(self.now.as_nanos() + 1), until);
        }
        self.dev.poll(self.now, &mut self.frames);
    }
    fn emcy(&self, code: u16) -> bool {
        self.frames.iter().any(|f| {
            f.std_id() == Some(0x83)
                && f.data().len() >= 2
                && u16::from_le_bytes([f.data()[0], f.data()[1]]) == code
        })
    }
    /// Profile velocity mode, enabled, at `v` velocity units.
    fn enable_pv(&mut self, v: i32) {
        self.write(0x6060, 0, &[3]);
        for cw in [0x06u16, 0x07, 0x0F] {
            self.write(0x6040, 0, &cw.to_le_bytes());
            let t = self.now.as_nanos() as f64 / 1e9 + 0.03;
            self.run_to_s(t);
        }
        assert_eq!(self.read_u32(0x6041) & 0x6F, 0x27);
        self.write(0x60FF, 0, &v.to_le_bytes());
    }
}

#[test]
fn a_limit_switch_that_trips_stops_the_drive_and_its_release_frees_it() {
    let f = MachineFile::parse(
        "[[node]]\nid = 3\n[[node.faults]]\nat = 0.5\nkind = \"trip\"\nswitch = \"positive_limit\"\nduration = 0.5\n",
    )
    .unwrap();
    let m = f.machine_for(Profile::Generic, 3).unwrap();
    let mut r = Run::new(Profile::Generic, &m);
    // 0.5 rev/s positive, far from the real switch (3.5 rev).
    r.enable_pv(180_000);
    r.run_to_s(0.45);
    assert!(r.dev.app.drive.model().velocity() > 2.0);
    assert_eq!(r.read_u32(0x60FD) & 0b111, 0);
    r.run_to_s(0.8);
    // Tripped: 60FDh bit 1, stopped on the quick-stop ramp, statusword
    // bit 11 (internal limit active) with the drive still enabled.
    assert_eq!(r.read_u32(0x60FD) & 0b111, 0b010);
    assert!(r.dev.app.drive.model().velocity().abs() < 0.05, "{}", r.dev.app.drive.model().velocity());
    let sw = r.read_u32(0x6041);
    assert_eq!(sw & 0x086F, 0x0827, "statusword {sw:04X}h");
    // Released at 1.0 s: the input clears and the velocity comes back.
    r.run_to_s(1.3);
    assert_eq!(r.read_u32(0x60FD) & 0b111, 0);
    assert_eq!(r.read_u32(0x6041) & 0x0800, 0);
    assert!(r.dev.app.drive.model().velocity() > 2.0);
    // The axis never came near the real switch.
    assert!(r.dev.app.drive.model().position() < 2.0 * std::f64::consts::PI);
}

#[test]
fn ipos_reports_a_tripped_limit_switch_by_emcy() {
    let mut m = Machine::default_for(Profile::Ipos);
    m.faults.push(drivebus_personality::machine::Fault {
        at: 0.2,
        kind: FaultKind::Trip(Switch::NegativeLimit),
        duration: Some(0.2),
    });
    let mut r = Run::new(Profile::Ipos, &m);
    r.run_to_s(0.1);
    r.frames.clear();
    r.run_to_s(0.3);
    // §4.3.1: 5442h "negative limit switch active", then 0000h on release.
    assert!(r.emcy(0x5442), "{:02X?}", r.frames);
    assert!(!r.emcy(0x0000));
    r.run_to_s(0.5);
    assert!(r.emcy(0x0000));
}

#[test]
fn a_wire_break_reads_per_the_wiring() {
    for (pol, active) in [("nc", 0b001), ("no", 0)] {
        let f = MachineFile::parse(&format!(
            "[[node]]\nid = 3\nstart = -1270.0\nlimits = {{ polarity = \"{pol}\" }}\n\
             [[node.faults]]\nat = 0.1\nkind = \"wire_break\"\nswitch = \"negative_limit\"\n"
        ))
        .unwrap();
        let m = f.machine_for(Profile::Generic, 3).unwrap();
        let mut r = Run::new(Profile::Generic, &m);
        // Starts on the negative limit switch (−1260°): active.
        r.run_to_s(0.05);
        assert_eq!(r.read_u32(0x60FD) & 1, 1);
        // Normally closed: a broken wire still reads active; normally
        // open: the switch is dead.
        r.run_to_s(0.2);
        assert_eq!(r.read_u32(0x60FD) & 1, active, "{pol}");
    }
}

#[test]
fn an_encoder_fault_faults_the_drive() {
    let f = MachineFile::parse("[[node]]\nid = 3\n[[node.faults]]\nat = 0.4\nkind = \"encoder\"\n").unwrap();
    let mut r = Run::new(Profile::Generic, &f.machine_for(Profile::Generic, 3).unwrap());
    r.enable_pv(36_000);
    r.run_to_s(0.35);
    assert_eq!(r.read_u32(0x6041) & 0x6F, 0x27, "operation enabled");
    r.frames.clear();
    r.run_to_s(0.6);
    assert_eq!(r.read_u32(0x6041) & 0x4F, 0x08, "fault");
    assert_eq!(r.read_u32(0x603F) & 0xFFFF, 0x7305);
    assert!(r.emcy(0x7305), "{:02X?}", r.frames);
}

#[test]
fn the_documented_example_file_parses_and_builds() {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/examples/machine.toml"))
            .expect("docs/examples/machine.toml");
    let f = MachineFile::parse(&text).unwrap();
    f.check_nodes(&[1, 2, 5]).unwrap();
    for (p, id) in [(Profile::Generic, 5u8), (Profile::Akd, 1), (Profile::Dds6, 2)] {
        let m = f.machine_for(p, id).unwrap();
        p.build_on(id, &m).unwrap();
    }
    let m = f.machine_for(Profile::Generic, 5).unwrap();
    assert_eq!(m.index_offset, 45.0);
    assert_eq!(m.faults.len(), 2);
    assert_eq!(m.inputs.len(), 2);
    assert!(m.brake.is_some() && m.io.wiring[1] == 4);
    assert_eq!(f.machine_for(Profile::Dds6, 2).unwrap().home_switch, None);
}
