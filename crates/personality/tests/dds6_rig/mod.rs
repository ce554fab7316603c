//! The replay rig of the LAM DDS6 §4.4 traces (seed004), shared by
//! `replay_dds6.rs` (EX1–EX8) and `replay_dds6_ip.rs` (EX9): the built
//! `dds6` personality as node 0Dh on the zero-time virtual bus, every
//! printed request sent at its printed time on simulated time.
//!
//! Checking rule (see `replay_report.md`):
//! * the drive's frames are matched in order, per COB-ID, with the printed
//!   ones; a printed frame the drive never sends fails the test;
//! * frames without live values (SDO confirmations, parameter uploads, the
//!   mode display, NMT) must be identical;
//! * frames with the drive's live CiA 402 values (TPDOs, uploads of 6041h,
//!   6064h, 606Ch, 6077h) are decoded with the drive's own PDO mapping:
//!   the statusword must be the printed one; positions, velocities and
//!   torques are *identical* or *close* (within [`tolerance`]) or *differ*:
//!   the emulated stepper is not the manual's motor;
//! * drive frames no printed frame matches are counted as extra.
#![allow(dead_code)]

#[path = "../replay_rig/trace.rs"]
mod shared_trace;

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Duration, Frame};
use drivebus_node::MemoryStorage;
use drivebus_personality::dds6::Dds6;
use drivebus_personality::{PersonalityDevice, Profile, build_with};

/// The frame lines of a trace file, comments dropped; checks the count.
pub fn trace(text: &'static str, frames: usize) -> Vec<&'static str> {
    shared_trace::timed_lines(text, frames)
}

pub use shared_trace::fr;

/// How one trace replayed.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Outcome {
    /// Request frames sent.
    pub sent: usize,
    /// Printed drive frames produced byte for byte.
    pub identical: usize,
    /// Live frames with the printed statusword and every value within
    /// [`tolerance`] of the printed one.
    pub close: usize,
    /// Live frames whose statusword differs: (printed, sent) frames.
    pub statusword_differs: Vec<(Frame, Frame)>,
    /// Live frames with the printed statusword but a value beyond
    /// [`tolerance`].
    pub value_differs: Vec<(Frame, Frame)>,
    /// Largest |printed − sent| per object over the close frames.
    pub max_deviation: Vec<(u16, i64)>,
    /// Drive frames matched with no printed frame.
    pub extra: usize,
}

impl Outcome {
    /// Prints the summary line (and with `REPLAY_DEBUG` every difference)
    /// and checks that every printed drive frame was accounted for.
    pub fn report(&self, name: &str, printed: usize) {
        let dev: Vec<String> = self.max_deviation.iter().map(|(i, d)| format!("{i:04X}h ±{d}")).collect();
        println!(
            "{name}: {} requests, {printed} drive frames printed: {} identical, {} close ({}), \
             {} statusword differs, {} value differs; {} extra",
            self.sent,
            self.identical,
            self.close,
            dev.join(", "),
            self.statusword_differs.len(),
            self.value_differs.len(),
            self.extra
        );
        if std::env::var("REPLAY_DEBUG").is_ok() {
            for (p, g) in self.statusword_differs.iter().chain(&self.value_differs) {
                println!("  printed {p:?} sent {g:?}");
            }
        }
        let n = self.identical + self.close + self.statusword_differs.len() + self.value_differs.len();
        assert_eq!(n, printed, "every printed drive frame is accounted for");
    }
}

/// How far a live value may be from the printed one and still count as
/// close: 40 position units (1/250 rev; at most 1.7 ms of motion at the
/// traces' top speed, 23.5 units/ms in EX9 — the real drive's own lag
/// behind its set-points is ~1 ms), 20 velocity units (2 rpm), 2 torque
/// units (0.2 %). The report prints the largest deviation found.
pub fn tolerance(index: u16) -> i64 {
    match index {
        0x6062..=0x6064 => 40,
        0x606B | 0x606C => 20,
        0x6074 | 0x6077 | 0x6078 => 2,
        _ => 0,
    }
}

/// The DDS6 on the virtual bus.
pub struct Rig {
    /// The bus.
    pub bus: Bus,
    /// The master's probe.
    pub probe: ProbeId,
    /// The drive.
    pub dut: NodeId,
}

impl Rig {
    /// A DDS6 from power-on.
    pub fn new() -> Rig {
        Rig::with(Dds6::new())
    }

    /// A DDS6 with this behaviour (e.g. on an axis with switches).
    pub fn with(b: Dds6) -> Rig {
        let node = build_with(Profile::Dds6, 0x0D, Box::new(MemoryStorage::new()), Box::new(b)).unwrap();
        let mut bus = Bus::new(BusConfig::zero_time());
        let probe = bus.attach_probe();
        let dut = bus.attach(node);
        bus.run_for(Duration::from_millis(1));
        let boot = bus.take_received(probe);
        assert_eq!(boot, vec![fr("70D#00")], "boot-up only");
        Rig { bus, probe, dut }
    }

    /// The personality node.
    pub fn dn(&self) -> &PersonalityDevice {
        self.bus.node::<PersonalityDevice>(self.dut).unwrap()
    }

    /// A dictionary value.
    pub fn i64(&self, index: u16, sub: u8) -> i64 {
        self.dn().node.od().get_i64(index, sub).unwrap()
    }

    /// Statusword state bits (0–6).
    pub fn state(&self) -> u16 {
        self.i64(0x6041, 0) as u16 & 0x6F
    }

    /// Request in, exactly these frames out (within 5 ms).
    pub fn ex(&mut self, req: &str, resp: &[&str]) {
        self.bus.take_received(self.probe);
        self.bus.send_from(self.probe, fr(req));
        self.bus.run_for(Duration::from_millis(5));
        let want: Vec<Frame> = resp.iter().map(|s| fr(s)).collect();
        assert_eq!(self.bus.take_received(self.probe), want, "after {req}");
    }

    /// The objects a TPDO on `cob` carries: (index, size in bytes).
    fn tpdo_layout(&self, cob: u16) -> Option<Vec<(u16, usize)>> {
        let od = self.dn().node.od();
        let n = (0..4u16).find(|n| od.get_u32(0x1800 + n, 1).is_some_and(|c| c & 0x7FF == u32::from(cob)))?;
        let count = od.get_u32(0x1A00 + n, 0)? as u8;
        Some(
            (1..=count)
                .filter_map(|i| od.get_u32(0x1A00 + n, i))
                .map(|e| ((e >> 16) as u16, (e & 0xFF) as usize / 8))
                .collect(),
        )
    }

    /// Replays `trace` (see the module docs).
    pub fn replay(&mut self, trace: &[&str]) -> Outcome {
        let t0 = self.bus.now();
        let mut out = Outcome::default();
        let mut printed: Vec<Frame> = Vec::new();
        let mut got: Vec<(f64, Frame)> = Vec::new();
        let take = |r: &mut Rig, got: &mut Vec<(f64, Frame)>| {
            for (t, f) in r.bus.take_received_timed(r.probe) {
                got.push(((t - t0).as_nanos() as f64 / 1e6, f));
            }
        };
        for line in trace {
            let (t, f) = line.split_once('|').expect("t|frame");
            let at = Duration::from_nanos((t.parse::<f64>().unwrap() * 1e6).round() as u64);
            let now = self.bus.now() - t0;
            if at > now {
                self.bus.run_for(at - now);
            }
            take(self, &mut got);
            if let Some(req) = f.strip_prefix('>') {
                self.bus.send_from(self.probe, fr(req));
                self.bus.run_for(Duration::from_nanos(1));
                out.sent += 1;
            } else {
                printed.push(fr(&f[1..]));
            }
        }
        self.bus.run_for(Duration::from_millis(5));
        take(self, &mut got);
        if std::env::var("REPLAY_DEBUG").as_deref() == Ok("2") {
            for (t, f) in &got {
                println!("    {t:10.1} {f:?}");
            }
        }
        let mut used = vec![false; got.len()];
        let mut from = std::collections::HashMap::<u16, usize>::new();
        for p in &printed {
            let id = p.std_id().unwrap();
            let start = *from.get(&id).unwrap_or(&0);
            let Some(k) = (start..got.len()).find(|&k| !used[k] && got[k].1.std_id() == Some(id)) else {
                let sent: Vec<_> = got.iter().map(|g| g.1).collect();
                panic!("printed {p:?} never sent (sent: {sent:?})");
            };
            used[k] = true;
            from.insert(id, k + 1);
            let g = got[k].1;
            if g == *p {
                out.identical += 1;
                continue;
            }
            let Some(fields) = self.live_fields(p) else {
                panic!("printed {p:?}, drive sent {g:?}");
            };
            assert_eq!(g.data().len(), p.data().len(), "layout of {p:?} vs {g:?}");
            let (pd, gd) = (p.data(), g.data());
            let mut close = true;
            for (index, off, size) in fields {
                let read = |d: &[u8]| {
                    let mut b = [0u8; 8];
                    b[..size].copy_from_slice(&d[off..off + size]);
                    let v = i64::from_le_bytes(b);
                    // Sign-extend from `size` bytes.
                    let sh = 64 - 8 * size as u32;
                    (v << sh) >> sh
                };
                let (pv, gv) = (read(pd), read(gd));
                if index == 0x6041 {
                    if pv != gv {
                        out.statusword_differs.push((*p, g));
                        close = false;
                        break;
                    }
                    continue;
                }
                let d = (pv - gv).abs();
                if d > tolerance(index) {
                    out.value_differs.push((*p, g));
                    close = false;
                    break;
                }
                match out.max_deviation.iter_mut().find(|(i, _)| *i == index) {
                    Some((_, m)) => *m = (*m).max(d),
                    None => out.max_deviation.push((index, d)),
                }
            }
            if close {
                out.close += 1;
            }
        }
        out.extra = used.iter().filter(|u| !**u).count();
        if std::env::var("REPLAY_DEBUG").is_ok() {
            for (_, (t, f)) in got.iter().enumerate().filter(|(k, _)| !used[*k]) {
                println!("  extra at {t:.1} ms: {f:?}");
            }
        }
        out
    }

    /// The live fields of a drive frame: (index, byte offset, size); `None`
    /// for frames that carry no live value.
    fn live_fields(&self, f: &Frame) -> Option<Vec<(u16, usize, usize)>> {
        let id = f.std_id()?;
        let d = f.data();
        if (0x180..0x500).contains(&id) {
            let mut off = 0;
            let mut v = Vec::new();
            for (index, size) in self.tpdo_layout(id)? {
                v.push((index, off, size));
                off += size;
            }
            return Some(v);
        }
        let index = u16::from_le_bytes([*d.get(1)?, *d.get(2)?]);
        let upload = (0x580..0x600).contains(&id) && d.len() == 8 && d[0] & 0xE0 == 0x40;
        let size = match index {
            0x6041 | 0x6077 => 2,
            0x6063 | 0x6064 | 0x606C => 4,
            _ => return None,
        };
        upload.then(|| vec![(index, 4, size)])
    }
}

/// Printed request and drive frame counts of a trace.
pub fn count(trace: &[&str]) -> (usize, usize) {
    let p = trace.iter().filter(|l| l.contains("|<")).count();
    (trace.len() - p, p)
}
