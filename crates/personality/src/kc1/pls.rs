//! The position limit switches (PLS, KC1 §8.1.3 / AKD §7.1.4 object
//! tables 34A0h–34A3h): eight position windows whose states PLS.STATE
//! 34A3h:4 reads, bit `n − 1` for switch `n`.
//!
//! The tables name the parameters only; our reading (docs/personalities.md
//! "Position limit switches"): switch `n`, enabled by bit `n − 1` of
//! PLS.EN 34A3h:1, is active while the actual position 6064h is within
//! `[PLS.Pn, PLS.Pn + PLS.WIDTHn]` (34A0h:n, 34A1h:n, a negative width
//! reaches below PLS.Pn); with a PLS.Tn 34A2h:n (ms) other than 0 it is
//! active for PLS.Tn from entering the window instead. PLS.MODE 34A3h:3
//! bit `n − 1` makes the switch single-shot: it triggers once and then
//! stays inactive until PLS.RESET 34A3h:2 (a write of the bits to re-arm).

use crate::build::Context;
use drivebus_od::{EntryRef, ObjectDictionary};

/// The number of switches.
const SWITCHES: usize = 8;

#[derive(Debug, Clone, Default)]
struct Refs {
    objects: usize,
    position: [Option<EntryRef>; SWITCHES],
    width: [Option<EntryRef>; SWITCHES],
    time: [Option<EntryRef>; SWITCHES],
    enable: Option<EntryRef>,
    mode: Option<EntryRef>,
    state: Option<EntryRef>,
}

/// The switches' state.
#[derive(Debug, Clone, Default)]
pub struct Pls {
    refs: Refs,
    /// Inside the window at the last period (bit per switch).
    inside: u8,
    /// Single-shot switches that have triggered.
    fired: u8,
    /// When a timed switch entered its window \[µs\].
    entered: [u64; SWITCHES],
    /// Timed switches whose time runs.
    timing: u8,
    /// The state shown.
    state: u8,
}

fn int(od: &ObjectDictionary, r: Option<EntryRef>) -> i64 {
    r.map_or(0, |r| {
        let w = od.word(r);
        match od.bytes(r).len() {
            4 => i64::from(w as u32 as i32),
            2 => i64::from(w as u16),
            _ => w as i64,
        }
    })
}

impl Pls {
    /// A write of PLS.RESET: the single-shot switches of `bits` re-arm.
    pub fn reset(&mut self, bits: u16) {
        self.fired &= !(bits as u8);
    }

    /// After every step: the windows against the actual position.
    pub fn update(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        if self.refs.objects != od.objects().len() {
            let sub = |i: u16, s: usize| od.find(i, s as u8 + 1).ok();
            self.refs = Refs {
                objects: od.objects().len(),
                position: core::array::from_fn(|s| sub(0x34A0, s)),
                width: core::array::from_fn(|s| sub(0x34A1, s)),
                time: core::array::from_fn(|s| sub(0x34A2, s)),
                enable: od.find(0x34A3, 1).ok(),
                mode: od.find(0x34A3, 3).ok(),
                state: od.find(0x34A3, 4).ok(),
            };
        }
        let r = &self.refs;
        let enabled = int(od, r.enable) as u8;
        let mut state = 0u8;
        if enabled != 0 {
            let pos = cx.drive.position();
            let now = cx.now.as_micros();
            let single = int(od, r.mode) as u8;
            for n in 0..SWITCHES {
                let bit = 1u8 << n;
                if enabled & bit == 0 {
                    self.inside &= !bit;
                    continue;
                }
                let p = int(od, r.position[n]);
                let w = int(od, r.width[n]);
                let (lo, hi) = if w >= 0 { (p, p.saturating_add(w)) } else { (p.saturating_add(w), p) };
                let inside = (lo..=hi).contains(&pos);
                if inside && self.inside & bit == 0 {
                    self.entered[n] = now;
                    self.timing |= bit;
                }
                let t_us = (int(od, r.time[n]).max(0) as u64).saturating_mul(1000);
                let mut active = if t_us == 0 {
                    inside
                } else {
                    self.timing & bit != 0 && now.saturating_sub(self.entered[n]) < t_us
                };
                if !active {
                    self.timing &= !bit;
                }
                if single & bit != 0 {
                    // Triggered before (not this activation): off until reset.
                    if active && self.state & bit == 0 && self.fired & bit != 0 {
                        active = false;
                    } else if active {
                        self.fired |= bit;
                    }
                }
                if active {
                    state |= bit;
                }
                self.inside = if inside { self.inside | bit } else { self.inside & !bit };
            }
        } else {
            self.inside = 0;
        }
        self.state = state;
        if let Some(s) = r.state {
            let n = od.bytes(s).len().min(2);
            od.set_raw(s, &u16::from(state).to_le_bytes()[..n]);
        }
    }
}
