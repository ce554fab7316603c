//! Cyclic modes hold still (issue 14 §4): every personality in each of
//! csp, csv, cst and ip it supports (its facts' `modes`), driven the way
//! python `canopen` drives it — RPDO1 (controlword + set-point, type 1)
//! sent by one periodic timer, SYNC every 10 ms by another, TPDO1
//! (statusword + actual value, type 1) — settles on the constant
//! set-point after a ramp and stays there.
//!
//! The RPDOs land at chosen offsets to their SYNC: just before, just
//! after, from a timer a little faster (two set-points in some SYNC
//! periods) or slower (none in some), and both timers jittered by a seeded
//! RNG. Each runs once with the profile's 60C2h default (the master does
//! not touch it: 1 or 2 ms against the 10 ms SYNC) and once with 60C2h =
//! the SYNC period.

mod replay_rig;

use drivebus_can::{Duration, Frame};
use drivebus_personality::Profile;
use replay_rig::*;

const ID: u8 = 1;
/// The master's SYNC period \[µs\].
const CYCLE_US: i64 = 10_000;
/// Cycles streamed; the last [`CHECKED`] TPDOs are checked.
const CYCLES: i64 = 300;
const CHECKED: usize = 50;

#[derive(Debug, Clone, Copy)]
enum Timing {
    /// Each RPDO 1 ms before its SYNC.
    Before,
    /// Each RPDO 0.2 ms after a SYNC (latched at the next one).
    After,
    /// The RPDO timer at 9.7 ms: some SYNC periods bring two set-points.
    Doubled,
    /// The RPDO timer at 10.3 ms: some SYNC periods bring none.
    Missing,
    /// Both timers at 10 ms, in phase, each jittered by ±1 ms (seed): the
    /// order flips from cycle to cycle.
    Jitter(u64),
}

const TIMINGS: [Timing; 6] = [
    Timing::Before,
    Timing::After,
    Timing::Doubled,
    Timing::Missing,
    Timing::Jitter(1),
    Timing::Jitter(0x9E37_79B9_7F4A_7C15),
];

/// xorshift64*: a seeded, dependency-free jitter source.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in ±`span` µs.
    fn jitter(&mut self, span: i64) -> i64 {
        (self.next() % (2 * span as u64 + 1)) as i64 - span
    }
}

/// What the master sends and what it checks, per mode.
#[derive(Debug, Clone, Copy)]
struct Mode {
    name: &'static str,
    code: i8,
    /// The set-point object in RPDO1 after the controlword.
    target: (u16, u8, u8),
    /// The value in TPDO1 after the statusword: the actual value, or (csv)
    /// the velocity demand, whose mean the actual velocity (TPDO2) must
    /// meet.
    actual: (u16, u8, u8),
    controlword: u16,
    /// The set-point of cycle `n` relative to where the axis stood.
    setpoint: fn(i64) -> i64,
    /// Allowed |value − set-point| once settled, in the set-point's unit
    /// (csp/ip: room for the stick-slip of the model's static friction).
    tolerance: fn(i64) -> i64,
}

/// csp, ip: 10 units per cycle for 2 s, then 2000 held (the ramp).
fn position_ramp(n: i64) -> i64 {
    10 * n.clamp(0, 200)
}

/// csv: 1000 velocity units more per cycle for 2 s (fast enough that 606Ch
/// is not dominated by the encoder's quantisation), then held.
fn velocity_ramp(n: i64) -> i64 {
    1000 * n.clamp(0, 200)
}

/// cst: 5 ‰ per cycle up to 50 ‰ and back to 0 (the free axis would run
/// away under a constant torque), then 0 held.
fn torque_ramp(n: i64) -> i64 {
    5 * (10 - (n - 10).abs()).max(0)
}

const CSP: Mode = Mode {
    name: "csp",
    code: 8,
    target: (0x607A, 0, 32),
    actual: (0x6064, 0, 32),
    controlword: 0x0F,
    setpoint: position_ramp,
    tolerance: |_| 20,
};
const IP: Mode = Mode { name: "ip", code: 7, target: (0x60C1, 1, 32), controlword: 0x1F, ..CSP };
const CSV: Mode = Mode {
    name: "csv",
    code: 9,
    target: (0x60FF, 0, 32),
    actual: (0x606B, 0, 32),
    controlword: 0x0F,
    setpoint: velocity_ramp,
    tolerance: |_| 1,
};
const CST: Mode = Mode {
    name: "cst",
    code: 10,
    target: (0x6071, 0, 16),
    actual: (0x6077, 0, 16),
    controlword: 0x0F,
    setpoint: torque_ramp,
    tolerance: |_| 2,
};

fn mode_of(code: i8) -> Option<Mode> {
    [CSP, CSV, CST, IP].into_iter().find(|m| m.code == code)
}

fn written(r: &mut Rig, index: u16, sub: u8, data: &[u8]) {
    Rig::assert_written(r.sdo_write(ID, index, sub, data), ID, index, sub);
}

/// PDO `comm` (1400h/1800h) type 1 mapping `objects` at `map`.
fn pdo(r: &mut Rig, comm: u16, map: u16, cob: u32, objects: &[(u16, u8, u8)]) {
    written(r, comm, 1, &(cob | 0x8000_0000).to_le_bytes());
    written(r, map, 0, &[0]);
    for (i, &(index, sub, bits)) in objects.iter().enumerate() {
        let e = u32::from(index) << 16 | u32::from(sub) << 8 | u32::from(bits);
        written(r, map, i as u8 + 1, &e.to_le_bytes());
    }
    written(r, map, 0, &[objects.len() as u8]);
    written(r, comm, 2, &[1]);
    written(r, comm, 1, &cob.to_le_bytes());
}

/// 60C2h = the SYNC period (the SSD 630 takes its ip cycle from 1006h).
fn match_period(r: &mut Rig, profile: Profile) {
    if profile == Profile::Ssd630 {
        written(r, 0x1006, 0, &(CYCLE_US as u32).to_le_bytes());
    } else {
        written(r, 0x60C2, 1, &[(CYCLE_US / 1000) as u8]);
        written(r, 0x60C2, 2, &[(-3i8) as u8]);
    }
}

fn sign_extend(d: &[u8]) -> i64 {
    let mut b = [0u8; 8];
    b[..d.len()].copy_from_slice(d);
    let shift = 64 - 8 * d.len() as u32;
    (i64::from_le_bytes(b) << shift) >> shift
}

/// The SYNC and RPDO instants of `timing` \[µs\], in order (`true` = SYNC).
fn schedule(timing: Timing) -> Vec<(i64, bool)> {
    let mut rng = Rng(match timing {
        Timing::Jitter(s) => s | 1,
        _ => 1,
    });
    let mut events = Vec::new();
    for k in 1..=CYCLES {
        let nominal = k * CYCLE_US;
        let (sync, rpdo) = match timing {
            Timing::Before => (nominal, nominal - 1000),
            Timing::After => (nominal, nominal + 200),
            Timing::Doubled => (nominal, k * 9_700),
            Timing::Missing => (nominal, k * 10_300),
            Timing::Jitter(_) => (nominal + rng.jitter(1000), nominal + rng.jitter(1000)),
        };
        events.push((sync, true));
        events.push((rpdo, false));
    }
    events.sort();
    events
}

/// The last [`CHECKED`] SYNCs of a run.
struct Tail {
    /// Statusword and the TPDO1 value.
    tpdo1: Vec<(u16, i64)>,
    /// csv: 606Ch.
    velocity: Vec<i64>,
    /// The final set-point.
    target: i64,
}

/// One run: the drive enabled in `mode` where the axis stands, the
/// set-points of `mode.setpoint` streamed by the master's timer (the value
/// of the cycle the timer is in when it fires).
fn run(profile: Profile, mode: Mode, timing: Timing, matched: bool) -> Tail {
    let (mut r, _boot) = Rig::new(profile, ID);
    let id = u32::from(ID);
    pdo(&mut r, 0x1400, 0x1600, 0x200 + id, &[(0x6040, 0, 16), mode.target]);
    pdo(&mut r, 0x1800, 0x1A00, 0x180 + id, &[(0x6041, 0, 16), mode.actual]);
    if mode.actual.0 == 0x606B {
        pdo(&mut r, 0x1801, 0x1A01, 0x280 + id, &[(0x606C, 0, 32)]);
    }
    if matched {
        match_period(&mut r, profile);
    }
    written(&mut r, 0x6060, 0, &[mode.code as u8]);
    r.send(&format!("000#01{ID:02X}"));
    r.run_ms(10);
    let start = match mode.actual.0 {
        0x6064 => sign_extend(&r.upload(ID, 0x6064, 0).expect("6064h")),
        _ => 0,
    };
    for cw in [0x06u16, 0x07, 0x0F] {
        written(&mut r, 0x6040, 0, &cw.to_le_bytes());
        r.run_ms(20);
    }
    let sw = u16::from_le_bytes(r.upload(ID, 0x6041, 0).expect("6041h")[..2].try_into().unwrap());
    assert_eq!(sw & 0x6F, 0x27, "{profile} {}: statusword {sw:04X}h after enabling", mode.name);
    r.take();

    let mut now = 0i64;
    let (mut tpdos, mut velocity) = (Vec::new(), Vec::new());
    for (t, is_sync) in schedule(timing) {
        r.run_for(Duration::from_micros((t - now).max(0) as u64));
        now = now.max(t);
        collect(&mut r, mode, &mut tpdos, &mut velocity);
        if is_sync {
            r.bus.send_from(r.probe, Frame::new(0x080, &[]));
        } else {
            let value = start + (mode.setpoint)(t / CYCLE_US);
            let mut d = mode.controlword.to_le_bytes().to_vec();
            d.extend_from_slice(&value.to_le_bytes()[..usize::from(mode.target.2 / 8)]);
            r.bus.send_from(r.probe, Frame::new(0x200 + u16::from(ID), &d));
        }
    }
    r.run_ms(1);
    collect(&mut r, mode, &mut tpdos, &mut velocity);
    assert!(tpdos.len() as i64 >= CYCLES - 1, "{profile} {} {timing:?}: {} TPDOs", mode.name, tpdos.len());
    let tpdo1 = tpdos.split_off(tpdos.len() - CHECKED);
    let velocity = velocity.split_off(velocity.len().saturating_sub(CHECKED));
    Tail { tpdo1, velocity, target: start + (mode.setpoint)(CYCLES) }
}

fn collect(r: &mut Rig, mode: Mode, tpdos: &mut Vec<(u16, i64)>, velocity: &mut Vec<i64>) {
    for f in r.take() {
        let d = f.data();
        match f.std_id().map(|id| id - u16::from(ID)) {
            Some(0x180) => {
                let sw = u16::from_le_bytes([d[0], d[1]]);
                tpdos.push((sw, sign_extend(&d[2..2 + usize::from(mode.actual.2 / 8)])));
            }
            Some(0x280) if mode.actual.0 == 0x606B => velocity.push(sign_extend(&d[..4])),
            _ => {}
        }
    }
}

/// Why `tail` does not hold still on `target`, if it does not: it left
/// Operation enabled, strays beyond `tolerance`, or reverses direction
/// from one SYNC to the next (the alternation of issue 14 §4; the model's
/// stick-slip moves far slower than that).
fn unsettled(tail: &[(u16, i64)], target: i64, tolerance: i64) -> Option<String> {
    if let Some((sw, _)) = tail.iter().find(|(sw, _)| sw & 0x6F != 0x27) {
        return Some(format!("statusword {sw:04X}h"));
    }
    let v: Vec<i64> = tail.iter().map(|&(_, v)| v).collect();
    let worst = v.iter().map(|x| (x - target).abs()).max().unwrap_or(0);
    let reversals = v.windows(3).filter(|w| (w[1] - w[0]) * (w[2] - w[1]) < 0).count();
    (worst > tolerance || reversals > 4).then(|| {
        format!(
            "off by up to {worst} (tolerance {tolerance}), {reversals} reversals: {:?}",
            &v[v.len() - 8..]
        )
    })
}

/// Every timing, both 60C2h settings, every cyclic mode of the profile.
fn holds_still(profile: Profile) {
    let mut failures = Vec::new();
    let mut runs = 0;
    for &code in profile.info().modes {
        let Some(mode) = mode_of(code) else { continue };
        for matched in [false, true] {
            for timing in TIMINGS {
                runs += 1;
                let tail = run(profile, mode, timing, matched);
                let target = tail.target;
                let mut why = unsettled(&tail.tpdo1, target, (mode.tolerance)(target));
                if why.is_none() && !tail.velocity.is_empty() {
                    // csv: the demand holds still; the measured velocity
                    // (quantised by the encoder: ±15 % sample to sample on
                    // the iPOS's 2000-count encoder) meets it on average.
                    let mean = tail.velocity.iter().sum::<i64>() / tail.velocity.len() as i64;
                    why = ((mean - target).abs() > target / 20).then(|| format!("606Ch averages {mean}"));
                }
                if let Some(why) = why {
                    let period = if matched { "= SYNC" } else { "default" };
                    failures
                        .push(format!("{} {timing:?}, 60C2h {period}: target {target}, {why}", mode.name));
                }
            }
        }
    }
    assert!(runs > 0, "{profile}: no cyclic mode in its facts");
    assert!(failures.is_empty(), "{profile} does not hold still:\n{}", failures.join("\n"));
}

#[test]
fn generic_holds_still() {
    holds_still(Profile::Generic);
}

#[test]
fn akd_holds_still() {
    holds_still(Profile::Akd);
}

#[test]
fn kc1_holds_still() {
    holds_still(Profile::Kc1);
}

#[test]
fn ipos_holds_still() {
    holds_still(Profile::Ipos);
}

#[test]
fn ssd630_holds_still() {
    holds_still(Profile::Ssd630);
}

#[test]
fn dds6_holds_still() {
    holds_still(Profile::Dds6);
}
