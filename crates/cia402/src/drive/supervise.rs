//! Supervision state (following error, SYNC loss, injected faults) and the
//! touch probe (60B8h–60BDh).

use super::config::ProbeInput;
use crate::model::{Event, EventKind};

/// Supervision flags and timers.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Supervision {
    /// Time the following error has been outside 6065h \[s\].
    pub fe_timer: f64,
    /// Statusword bit 13 (pp/csp): following error.
    pub fe_active: bool,
    /// Injected: treat the following error as outside the window.
    pub force_following_error: bool,
    /// Injected fault code, raised at the next period.
    pub pending_fault: Option<u16>,
    /// The node reported a SYNC timeout (cleared by the next SYNC).
    pub sync_lost: bool,
    /// Negative (−1) or positive (+1) limit switch blocks motion that way.
    pub limit_block: i8,
    /// Past the negative (−1) or positive (+1) software limit 607Dh
    /// ([`IoConfig::software_limit_switches`](super::IoConfig::software_limit_switches)).
    pub soft_limit: i8,
}

/// Where a touch probe takes its trigger from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Source {
    /// Touch probe input 1 or 2 (0, 1), wired per [`ProbeInput`].
    Input(usize),
    /// The encoder index (zero impulse).
    Index,
}

/// Touch probe function and captures (CiA 402-2 touch probe; ETG.6010 §5
/// coding of 60B8h/60B9h).
///
/// 60B8h per probe (probe 2 shifted by 8): bit 0 enable, bit 1 continuous
/// (0: first event only), bits 2–3 trigger (00 touch probe input — probe 1
/// uses touch probe input 1, probe 2 input 2, each wired per
/// [`IoConfig::probe_inputs`](super::IoConfig::probe_inputs); 01 encoder
/// index pulse; 10 the source in 60D0h:1/2 when the drive has that object;
/// 11 reserved, captures nothing), bit 4 capture rising edge, bit 5 capture
/// falling edge. 60B9h: bit 0 enabled, bit 1 rising edge stored, bit 2
/// falling edge stored (probe 2: bits 8–10).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Probe {
    pub function: u16,
    pub status: u16,
    /// 60BAh, 60BBh, 60BCh, 60BDh.
    pub pos: [i32; 4],
    /// 60D0h:1/2 (1, 2 touch probe input 1/2, 5 / 6 hardware / software
    /// zero impulse; 0 none).
    pub source: [i16; 2],
    /// 60D0h honoured (trigger selection 10b).
    pub source_object: bool,
    /// The physical inputs behind touch probe input 1/2.
    inputs: [ProbeInput; 2],
    /// Dedicated inputs: level as set by the application, level as last
    /// sampled by the control period.
    dedicated: [bool; 2],
    dedicated_seen: [bool; 2],
}

impl Probe {
    /// Probes wired to `inputs`, 60D0h honoured when `source_object`.
    pub fn new(inputs: [ProbeInput; 2], source_object: bool) -> Probe {
        Probe { inputs, source_object, source: [1, 2], ..Probe::default() }
    }

    /// 60B8h written: enabling a probe (re)arms it, disabling clears it.
    pub fn configure(&mut self, f: u16) {
        for k in 0..2 {
            let sh = 8 * k;
            let en = f >> sh & 1 != 0;
            let was = self.function >> sh & 1 != 0;
            if en && !was {
                self.status = (self.status & !(0x7 << sh)) | 1 << sh;
            } else if !en {
                self.status &= !(0x7 << sh);
            }
        }
        self.function = f;
    }

    /// The trigger of enabled probe `k` (`None`: disabled or nothing).
    fn source_of(&self, k: usize) -> Option<Source> {
        let f = self.function >> (8 * k);
        if f & 1 == 0 {
            return None;
        }
        match (f >> 2) & 3 {
            0 => Some(Source::Input(k)),
            1 => Some(Source::Index),
            2 if self.source_object => match self.source[k] {
                1 => Some(Source::Input(0)),
                2 => Some(Source::Input(1)),
                5 | 6 => Some(Source::Index),
                _ => None,
            },
            _ => None,
        }
    }

    /// The model switch behind touch probe input `n` (`None`: dedicated).
    fn input_kind(&self, n: usize) -> Option<EventKind> {
        match self.inputs[n] {
            ProbeInput::HomeSwitch => Some(EventKind::Home),
            ProbeInput::PositiveLimit => Some(EventKind::PositiveLimit),
            ProbeInput::NegativeLimit => Some(EventKind::NegativeLimit),
            ProbeInput::Dedicated => None,
        }
    }

    /// Latches an edge; `pos` is the position \[position units\] at the event.
    pub fn on_event(&mut self, e: &Event, pos: i64) {
        for k in 0..2 {
            let hit = match self.source_of(k) {
                Some(Source::Index) => e.kind == EventKind::Index,
                Some(Source::Input(n)) => self.input_kind(n) == Some(e.kind),
                None => false,
            };
            if hit {
                // The index pulse has only a "rising" edge.
                self.latch(k, e.active, pos);
            }
        }
    }

    /// Sets dedicated input `n` (0, 1); out of range is ignored.
    pub fn set_dedicated(&mut self, n: usize, active: bool) {
        if let Some(l) = self.dedicated.get_mut(n) {
            *l = active;
        }
    }

    /// A dedicated input changed since the last sample.
    pub fn dedicated_pending(&self) -> bool {
        self.dedicated != self.dedicated_seen
    }

    /// Once per control period: edges of the dedicated inputs, latched at
    /// `pos` (the input is sampled at the control rate).
    pub fn sample_dedicated(&mut self, pos: i64) {
        for n in 0..2 {
            if self.dedicated[n] == self.dedicated_seen[n] {
                continue;
            }
            self.dedicated_seen[n] = self.dedicated[n];
            if self.inputs[n] != ProbeInput::Dedicated {
                continue;
            }
            let rising = self.dedicated[n];
            for k in 0..2 {
                if self.source_of(k) == Some(Source::Input(n)) {
                    self.latch(k, rising, pos);
                }
            }
        }
    }

    fn latch(&mut self, k: usize, rising: bool, pos: i64) {
        let sh = 8 * k;
        let f = self.function >> sh;
        let (en_bit, st_bit, slot) = if rising { (4, 1, 2 * k) } else { (5, 2, 2 * k + 1) };
        if f >> en_bit & 1 == 0 {
            return;
        }
        let continuous = f & 2 != 0;
        if !continuous && self.status >> (sh + st_bit) & 1 != 0 {
            return;
        }
        self.pos[slot] = pos as i32;
        self.status |= 1 << (sh + st_bit);
    }
}
