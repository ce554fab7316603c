//! Every homing method a profile lists in 60E3h completes on the profile's
//! default machine (`machine::Machine::default_for`) from every start:
//! on the negative limit switch, left of the home switch, on it, right of
//! it, on the positive limit switch ([`Start`]). Issue 11 §1: a master that starts
//! method 17 on a served drive must not wait while the axis runs away.
//!
//! Each run is a fresh drive on the machine, enabled in homing mode
//! (CiA 402-2 6060h = 6) through the node's write path and stepped in
//! simulated time until statusword bit 12 (homing attained) with bit 10
//! (target reached) — or bit 13 (homing error), which fails the test — at
//! most [`LIMIT_S`] simulated seconds.
//!
//! Where the home position lies is checked against the machine, not taken
//! from the drive: the *reference* (the shaft angle at which 6064h reads
//! 607Ch, from the final 6064h and the true shaft angle of the model) must
//! be, by the method's class,
//! * the start position (35, 37 and their vendor aliases), and there
//!   6064h = 607Ch exactly;
//! * the first index pulse right (34) or left (33) of the start;
//! * otherwise one and the same place from every start, on an index pulse
//!   or a switch edge or a hard stop ± |607Ch| (iPOS −3/−4, §6).
//!
//! Drives that return to the home position after homing (iPOS, §6 / E18)
//! end with 6064h = 607Ch within the position window 6067h.

use core::f64::consts::PI;
use drivebus_can::{Device, Frame, Instant};
use drivebus_personality::machine::Machine;
use drivebus_personality::{PersonalityDevice, Profile};

/// Simulated-time bound of one homing run \[s\].
const LIMIT_S: f64 = 60.0;
/// Home offset 607Ch for every run (position units; small enough for the
/// iPOS −3/−4 travel away from the stop to stay inside the switches).
const OFFSET: i32 = 1234;
/// Where a run starts, from the machine's layout.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Start {
    /// 0.2 revolutions into the negative limit switch.
    OnNegativeLimit,
    /// Half-way between the negative limit switch and the home switch.
    LeftOfHome,
    /// On the home switch, 40 % of its width from its lower edge.
    OnHome,
    /// Half-way between the home switch and the positive limit switch.
    RightOfHome,
    /// 0.2 revolutions into the positive limit switch.
    OnPositiveLimit,
}

const STARTS: [Start; 5] =
    [Start::OnNegativeLimit, Start::LeftOfHome, Start::OnHome, Start::RightOfHome, Start::OnPositiveLimit];

impl Start {
    /// The start position in machine units.
    fn position(self, m: &Machine) -> f64 {
        let (l, h, r) = (m.limits.unwrap(), m.home_switch.unwrap(), m.units_per_motor_rev());
        match self {
            Start::OnNegativeLimit => l.negative - 0.2 * r,
            Start::LeftOfHome => (l.negative + h.from) / 2.0,
            Start::OnHome => h.from + 0.4 * (h.to - h.from),
            Start::RightOfHome => (h.to + l.positive) / 2.0,
            Start::OnPositiveLimit => l.positive + 0.2 * r,
        }
    }
}

struct Run {
    dev: PersonalityDevice,
    now: Instant,
    out: Vec<Frame>,
}

impl Run {
    fn new(profile: Profile, machine: &Machine) -> Run {
        let mut dev = profile.build_on(3, machine).expect("build");
        let mut out = Vec::new();
        dev.start(Instant::ZERO, &mut out);
        Run { dev, now: Instant::ZERO, out }
    }

    fn write(&mut self, index: u16, sub: u8, data: &[u8]) {
        let r = self.dev.write_object(index, sub, data, self.now, &mut self.out);
        assert_eq!(r, Ok(()), "{index:04X}h:{sub} ← {data:02X?}");
    }

    fn read_i32(&mut self, index: u16) -> i32 {
        let b = self.dev.read_object(index, 0, self.now).expect("read").to_vec();
        let mut a = [0u8; 4];
        a[..b.len().min(4)].copy_from_slice(&b[..b.len().min(4)]);
        i32::from_le_bytes(a)
    }

    fn statusword(&mut self) -> u16 {
        self.read_i32(0x6041) as u16
    }

    /// Runs the device to `until` from deadline to deadline.
    fn run_to(&mut self, until: Instant) {
        while self.now < until {
            let next = self.dev.poll(self.now, &mut self.out).unwrap_or(until);
            self.out.clear();
            self.now = next.clamp(Instant::from_nanos(self.now.as_nanos() + 1), until);
        }
        self.dev.poll(self.now, &mut self.out);
        self.out.clear();
    }

    fn run_ms(&mut self, ms: u64) {
        let t = Instant::from_nanos(self.now.as_nanos() + ms * 1_000_000);
        self.run_to(t);
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Class {
    /// Homes on the present position.
    Current,
    /// The next index pulse in this direction (positive: `true`).
    Index(bool),
    /// A place of the machine, the same from every start.
    Fixed,
}

/// The class of a 6098h code on a profile, from the manuals' method lists
/// (the vendor codes as `docs/personalities.md` maps them).
fn class(profile: Profile, code: i8) -> Class {
    let standard = match (profile, code) {
        (Profile::Akd, c) if c < 0 => drivebus_personality::akd::HOMING_ALIASES
            .iter()
            .find(|a| a.0 == c)
            .map(|a| a.1)
            .expect("AKD alias"),
        (Profile::Ssd630, c) if c < 0 => drivebus_personality::ssd630::HOMING_EQUIVALENT[(c + 24) as usize],
        _ => code,
    };
    match standard {
        35 | 37 => Class::Current,
        33 => Class::Index(false),
        34 => Class::Index(true),
        _ => Class::Fixed,
    }
}

struct Outcome {
    /// The reference \[rad of the motor shaft\].
    reference: f64,
    /// The start \[rad\].
    start: f64,
    /// 6064h − 607Ch at the end \[position units\].
    rest_offset: i64,
    /// 6067h position window.
    window: i64,
    seconds: f64,
}

/// Homes; `Err(statusword)` on a homing error (bit 13).
fn home(profile: Profile, code: i8, from: Start) -> Result<Outcome, u16> {
    let mut m = Machine::default_for(profile);
    m.start = from.position(&m);
    let mut r = Run::new(profile, &m);
    r.run_ms(10);
    r.write(0x6060, 0, &[6]);
    for cw in [0x06u16, 0x07, 0x0F] {
        r.write(0x6040, 0, &cw.to_le_bytes());
        r.run_ms(30);
    }
    // The DDS6 in closed loop takes longer; wait for operation enabled.
    for _ in 0..100 {
        if r.statusword() & 0x6F == 0x27 {
            break;
        }
        r.run_ms(10);
    }
    assert_eq!(r.statusword() & 0x6F, 0x27, "{profile} from {from:?}: operation enabled");
    r.write(0x607C, 0, &OFFSET.to_le_bytes());
    r.write(0x6098, 0, &[code as u8]);
    let start = r.dev.app.drive.model().position();
    let t0 = r.now;
    r.write(0x6040, 0, &0x1Fu16.to_le_bytes());
    let limit = Instant::from_nanos(t0.as_nanos() + (LIMIT_S * 1e9) as u64);
    let mut sw = r.statusword();
    while r.now < limit {
        r.run_ms(5);
        sw = r.statusword();
        if sw & 0x2000 != 0 {
            return Err(sw);
        }
        assert_ne!(sw & 0x4F, 0x08, "{profile} method {code} from {from:?}: fault, statusword {sw:04X}h");
        if sw & 0x1400 == 0x1400 {
            break;
        }
    }
    assert_eq!(
        sw & 0x3400,
        0x1400,
        "{profile} method {code} from {from:?}: not completed in {LIMIT_S} s (statusword {sw:04X}h)"
    );
    let seconds = r.now.saturating_duration_since(t0).as_secs_f64();
    let pos = i64::from(r.read_i32(0x6064));
    // 6067h: only where the profile has it (the KC1 has not).
    let window = if profile == Profile::Ipos { i64::from(r.read_i32(0x6067)) } else { 0 };
    let d = &r.dev.app.drive;
    let theta = d.model().position();
    // 6064h runs parallel to the shaft: at the reference it read 607Ch.
    let raw_now = d.units().rad_to_pos(theta);
    let raw_ref = raw_now - (pos - i64::from(OFFSET)) as f64;
    Ok(Outcome {
        reference: d.units().pos_to_rad(raw_ref),
        start,
        rest_offset: pos - i64::from(OFFSET),
        window,
        seconds,
    })
}

/// The places (motor rad) of a profile's default machine a reference may
/// be at: the index pulses, the switch edges, the hard stops ± |607Ch|.
struct Features {
    /// Angle of the index pulse in a revolution.
    index: f64,
    /// Switch edges and the iPOS −3/−4 points.
    places: Vec<f64>,
}

impl Features {
    fn of(profile: Profile) -> Features {
        let m = Machine::default_for(profile);
        let k = 2.0 * PI / m.units_per_motor_rev();
        let mut edges = Vec::new();
        if let Some(l) = m.limits {
            edges.extend([l.negative, l.negative + l.hysteresis, l.positive, l.positive - l.hysteresis]);
        }
        if let Some(h) = m.home_switch {
            edges.extend([h.from, h.to]);
        }
        let mut places = edges.iter().map(|e| e * k).collect::<Vec<_>>();
        if let Some(s) = m.hard_stops {
            // iPOS −3/−4: |607Ch| position units away from the stop.
            let d = profile.build(1).unwrap().app.drive.units().pos_to_rad(f64::from(OFFSET)).abs();
            places.extend([s.negative * k + d, s.positive * k - d]);
        }
        Features { index: (m.index_offset * PI / 180.0).rem_euclid(2.0 * PI), places }
    }

    fn on_index(&self, rad: f64, tol: f64) -> bool {
        let phase = (rad - self.index).rem_euclid(2.0 * PI);
        phase < tol || 2.0 * PI - phase < tol
    }

    fn on_any(&self, rad: f64, tol: f64) -> bool {
        self.on_index(rad, tol) || self.places.iter().any(|x| (x - rad).abs() < tol)
    }
}

/// Every method of `p` from every start; returns (runs, refused).
fn check(p: Profile) -> (usize, usize) {
    let mut runs = 0;
    let mut refused = 0;
    let mut longest: f64 = 0.0;
    {
        let methods = p.info().homing_methods;
        assert!(!methods.is_empty(), "{p}");
        // Tolerance: a few encoder counts (the stepper's 4000 per rev) or
        // position units (6064h is whole units: the Kollmorgen 36000/rev),
        // at least 0.05° of the motor: an edge met at the search speed
        // (generic: 12.5 rev/s, 1.6° per control period) is taken to a
        // hundredth of the period's travel.
        let d = p.build(1).unwrap();
        let cpr = f64::from(d.app.drive.config().params.encoder.counts_per_rev);
        let unit = d.app.drive.units().pos_to_rad(1.0).abs();
        let tol = (4.0 * 2.0 * PI / cpr).max(2.0 * unit).max(0.05_f64.to_radians());
        let features = Features::of(p);
        for &code in methods {
            let c = class(p, code);
            let mut outcomes = Vec::new();
            for s in STARTS {
                // An index search into the limit switch the axis stands on
                // would drive it further into overtravel: the drive
                // refuses with a homing error (bit 13), without moving.
                let into_limit = match c {
                    Class::Index(true) => s == Start::OnPositiveLimit,
                    Class::Index(false) => s == Start::OnNegativeLimit,
                    _ => false,
                };
                match home(p, code, s) {
                    Err(sw) if into_limit => {
                        assert_eq!(sw & 0x3400, 0x2400, "{p} method {code} from {s:?}: error at rest");
                        refused += 1;
                    }
                    Err(sw) => panic!("{p} method {code} from {s:?}: homing error, statusword {sw:04X}h"),
                    Ok(_) if into_limit => {
                        panic!("{p} method {code} from {s:?}: homed into the limit switch")
                    }
                    Ok(o) => outcomes.push((s, o)),
                }
            }
            let first = outcomes[0].1.reference;
            for (s, o) in &outcomes {
                runs += 1;
                longest = longest.max(o.seconds);
                let at = format!("{p} method {code} ({c:?}) from {s:?}");
                match c {
                    Class::Current => {
                        assert!(
                            (o.reference - o.start).abs() < tol,
                            "{at}: reference {} ≠ start {}",
                            o.reference,
                            o.start
                        );
                        assert_eq!(o.rest_offset, 0, "{at}: 6064h = 607Ch");
                    }
                    Class::Index(positive) => {
                        let d = o.reference - o.start;
                        let ok = if positive {
                            d > 0.0 && d <= 2.0 * PI + tol
                        } else {
                            d < 0.0 && d >= -2.0 * PI - tol
                        };
                        assert!(ok, "{at}: reference {} is not the next index from {}", o.reference, o.start);
                        assert!(
                            features.on_index(o.reference, tol),
                            "{at}: reference {} on no index",
                            o.reference
                        );
                    }
                    Class::Fixed => {
                        assert!(
                            (o.reference - first).abs() < tol,
                            "{at}: reference {} differs from the one from {:?} ({first})",
                            o.reference,
                            outcomes[0].0
                        );
                        assert!(
                            features.on_any(o.reference, tol),
                            "{at}: reference {} is on no switch, index or stop",
                            o.reference
                        );
                    }
                }
                if p == Profile::Ipos {
                    assert!(
                        o.rest_offset.abs() <= o.window,
                        "{at}: 6064h − 607Ch = {} at rest",
                        o.rest_offset
                    );
                }
            }
        }
    }
    // 33 and 34 (or their aliases) each refuse once; the rest ran.
    assert_eq!(runs + refused, 5 * p.info().homing_methods.len(), "{p}");
    assert!(longest < LIMIT_S, "{p}: {longest} s");
    (runs, refused)
}

#[test]
fn kc1_homes_on_its_default_machine() {
    assert_eq!(check(Profile::Kc1).1, 2);
}

#[test]
fn akd_homes_on_its_default_machine() {
    assert_eq!(check(Profile::Akd).1, 2);
}

#[test]
fn ipos_homes_on_its_default_machine() {
    assert_eq!(check(Profile::Ipos).1, 2);
}

#[test]
fn ssd630_homes_on_its_default_machine() {
    // Modes −24 (34) and −23 (33).
    assert_eq!(check(Profile::Ssd630).1, 2);
}

#[test]
fn dds6_homes_on_its_default_machine() {
    assert_eq!(check(Profile::Dds6).1, 2);
}

#[test]
fn generic_homes_on_its_default_machine() {
    assert_eq!(check(Profile::Generic).1, 2);
}
