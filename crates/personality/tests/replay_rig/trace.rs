//! The printed manual traces of `crates/personality/traces/*.txt`, shared by
//! the CiA 301 replays (`crates/node/tests/manual_*.rs`, through
//! `common::trace`, included there with `#[path]`) and the personality
//! replays (`crates/personality/tests/`); with them the candump-style frame
//! parser [`fr`] every rig uses.
//!
//! One frame a line: `KEY|>ID#DATA` (to the drive) or `KEY|<ID#DATA` (from
//! it); `#` starts a comment line. KEY is the frame's time in ms (DDS6) or
//! its number in the examples file (KC1: the frame number, AKD: the source
//! line). An optional third field flags the frame:
//! * `|form`: the personality replay checks it in form only (COB-ID and
//!   length; the printed values are those of the manual's machine);
//! * `|derived`: not printed, built from the manual's text: an SDO
//!   confirmation of a request-only listing (no KEY, it follows its
//!   request), or the AKD §0 exchanges (requests numbered 1–4);
//! * `|skip`: printed incompletely, replayed by neither test.
#![allow(dead_code)]

use drivebus_can::{CanId, Frame};

/// `ID#HEX` or `ID#R<len>`.
pub fn fr(s: &str) -> Frame {
    let (id, data) = s.split_once('#').expect("ID#DATA");
    let cid = if id.len() == 8 {
        CanId::Extended(u32::from_str_radix(id, 16).unwrap())
    } else {
        CanId::Standard(u16::from_str_radix(id, 16).unwrap())
    };
    if let Some(n) = data.strip_prefix('R') {
        return Frame::try_remote(cid, n.parse().unwrap_or(0)).unwrap();
    }
    // Spaces and dots (`05.20.00`) only separate bytes.
    let data: String = data.chars().filter(|c| !c.is_whitespace() && *c != '.').collect();
    let bytes: Vec<u8> =
        (0..data.len()).step_by(2).map(|i| u8::from_str_radix(&data[i..i + 2], 16).unwrap()).collect();
    Frame::try_new(cid, &bytes).unwrap()
}

/// One line of a trace file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Line {
    /// Frame number / source line / time as printed; empty for a derived frame.
    pub key: &'static str,
    /// `>`: sent to the drive.
    pub input: bool,
    /// `ID#DATA`.
    pub frame: &'static str,
    /// `form`, `derived`, `skip` or empty.
    pub flag: &'static str,
}

impl Line {
    /// Checked in form only by the personality replay.
    pub fn form(&self) -> bool {
        self.flag == "form"
    }

    /// The COB-ID.
    pub fn id(&self) -> u16 {
        let (id, _) = self.frame.split_once('#').expect("ID#DATA");
        u16::from_str_radix(id, 16).expect("standard COB-ID")
    }

    /// The number of data bytes.
    pub fn dlc(&self) -> usize {
        let (_, data) = self.frame.split_once('#').expect("ID#DATA");
        data.chars().filter(|c| !c.is_whitespace()).count() / 2
    }
}

/// A request and the frames printed after it (before the next request).
#[derive(Debug, Clone)]
struct Group {
    key: f64,
    req: &'static str,
    resp: Vec<&'static str>,
}

/// A parsed trace file.
#[derive(Debug, Clone)]
pub struct Trace {
    pub lines: Vec<Line>,
    groups: Vec<Group>,
}

impl Trace {
    /// Parse `text` and check that it holds `printed` printed frames
    /// (derived ones not counted).
    pub fn parse(text: &'static str, printed: usize) -> Trace {
        let lines: Vec<Line> = text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(|l| {
                let mut f = l.split('|');
                let key = f.next().unwrap_or_default();
                let frame = f.next().unwrap_or_else(|| panic!("KEY|FRAME: {l}"));
                let flag = f.next().unwrap_or_default();
                assert!(["", "form", "derived", "skip"].contains(&flag), "flag of {l}");
                let input = frame.starts_with('>');
                assert!(input || frame.starts_with('<'), "direction of {l}");
                assert!(
                    !key.is_empty() || (flag == "derived" && !input),
                    "only a derived answer has no key: {l}"
                );
                Line { key, input, frame: &frame[1..], flag }
            })
            .collect();
        let n = lines.iter().filter(|l| l.flag != "derived").count();
        assert_eq!(n, printed, "printed frames in the trace");
        let mut groups: Vec<Group> = Vec::new();
        for l in &lines {
            if l.input {
                let key = l.key.parse().unwrap_or_else(|_| panic!("numeric key: {l:?}"));
                groups.push(Group { key, req: l.frame, resp: Vec::new() });
            } else if let Some(g) = groups.last_mut() {
                g.resp.push(l.frame);
            }
        }
        Trace { lines, groups }
    }

    /// The line printed as `key`.
    pub fn line(&self, key: u32) -> Line {
        let k = key.to_string();
        *self.lines.iter().find(|l| l.key == k).unwrap_or_else(|| panic!("no frame {key}"))
    }

    /// The frame printed as `key` (`ID#DATA`).
    pub fn frame(&self, key: u32) -> &'static str {
        self.line(key).frame
    }

    /// The requests printed as `from..=to`, each with the frames printed
    /// after it, for `replay`. Empty or inverted ranges are refused.
    pub fn steps(&self, from: u32, to: u32) -> Vec<(&'static str, &[&'static str])> {
        let v: Vec<_> = self
            .groups
            .iter()
            .filter(|g| (f64::from(from)..=f64::from(to)).contains(&g.key))
            .map(|g| (g.req, g.resp.as_slice()))
            .collect();
        assert!(!v.is_empty(), "no request in {from}..={to}");
        v
    }

    /// As [`Trace::steps`], only the requests on COB-ID `id` (e.g. `"601"`).
    pub fn steps_on(&self, from: u32, to: u32, id: &str) -> Vec<(&'static str, &[&'static str])> {
        let v: Vec<_> =
            self.steps(from, to).into_iter().filter(|(req, _)| req.split('#').next() == Some(id)).collect();
        assert!(!v.is_empty(), "no request on {id} in {from}..={to}");
        v
    }
}

/// KC1 example `n` (`traces/kc1_ex{n}.txt`, seed000-kc1-examples.md), with
/// its number of printed frames checked.
pub fn kc1(n: u32) -> Trace {
    let (text, printed) = match n {
        1 => (include_str!("../../traces/kc1_ex1.txt"), 5),
        3 => (include_str!("../../traces/kc1_ex3.txt"), 8),
        4 => (include_str!("../../traces/kc1_ex4.txt"), 14),
        5 => (include_str!("../../traces/kc1_ex5.txt"), 14),
        6 => (include_str!("../../traces/kc1_ex6.txt"), 42),
        7 => (include_str!("../../traces/kc1_ex7.txt"), 40),
        8 => (include_str!("../../traces/kc1_ex8.txt"), 29),
        9 => (include_str!("../../traces/kc1_ex9.txt"), 74),
        10 => (include_str!("../../traces/kc1_ex10.txt"), 16),
        11 => (include_str!("../../traces/kc1_ex11.txt"), 29),
        12 => (include_str!("../../traces/kc1_ex12.txt"), 61),
        13 => (include_str!("../../traces/kc1_ex13.txt"), 31),
        _ => panic!("KC1 example {n} has no frames"),
    };
    Trace::parse(text, printed)
}

/// AKD section `s` of seed001-akd-examples.md (`traces/akd_s{s}.txt`; the
/// sections byte-identical to a KC1 example read that example's file:
/// 1, 3, 4, 5, 10), with its number of printed frames checked.
pub fn akd(s: u32) -> Trace {
    match s {
        0 => Trace::parse(include_str!("../../traces/akd_s0.txt"), 0),
        1 | 3 | 4 | 5 | 10 => kc1(s),
        6 => Trace::parse(include_str!("../../traces/akd_s6.txt"), 50),
        7 => Trace::parse(include_str!("../../traces/akd_s7.txt"), 48),
        8 => Trace::parse(include_str!("../../traces/akd_s8.txt"), 29),
        9 => Trace::parse(include_str!("../../traces/akd_s9.txt"), 86),
        11 => Trace::parse(include_str!("../../traces/akd_s11.txt"), 41),
        13 => Trace::parse(include_str!("../../traces/akd_s13.txt"), 73),
        _ => panic!("AKD section {s} has no frames"),
    }
}

/// The SYNC pattern of KC1 example 11 / AKD section 11 (TPDO1 every 2nd,
/// TPDO2 every 3rd SYNC) over six SYNCs: each SYNC with the TPDOs due, in
/// bus order.
pub fn every_2nd_and_3rd<'a>(sync: &'a str, tpdo1: &'a str, tpdo2: &'a str) -> Vec<(&'a str, Vec<&'a str>)> {
    (1..=6)
        .map(|n| {
            let due = [(n % 2 == 0, tpdo1), (n % 3 == 0, tpdo2)];
            (sync, due.iter().filter(|d| d.0).map(|d| d.1).collect())
        })
        .collect()
}

/// The frame lines of a time-keyed trace (DDS6: `TIME_MS|>ID#DATA`),
/// comment and blank lines dropped; checks the printed frame count.
pub fn timed_lines(text: &'static str, frames: usize) -> Vec<&'static str> {
    let v: Vec<_> = text.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#')).collect();
    assert_eq!(v.len(), frames, "printed frames in the trace");
    v
}
