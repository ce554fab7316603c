//! Supervision state (following error, SYNC loss, injected faults) and the
//! touch probe (60B8h–60BDh).

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
}

/// Touch probe function and captures (CiA 402-2 §6.x touch probe;
/// ETG.6010 §5 coding of 60B8h/60B9h).
///
/// 60B8h per probe (probe 2 shifted by 8): bit 0 enable, bit 1 continuous
/// (0: first event only), bits 2–3 trigger (00 touch probe input = home
/// switch, 01 encoder index pulse), bit 4 capture rising edge, bit 5
/// capture falling edge. 60B9h: bit 0 enabled, bit 1 rising edge stored,
/// bit 2 falling edge stored (probe 2: bits 8–10).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Probe {
    pub function: u16,
    pub status: u16,
    /// 60BAh, 60BBh, 60BCh, 60BDh.
    pub pos: [i32; 4],
}

impl Probe {
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

    /// Latches an edge; `pos` is the position \[position units\] at the event.
    pub fn on_event(&mut self, e: &Event, pos: i64) {
        for k in 0..2 {
            let sh = 8 * k;
            let f = self.function >> sh;
            if f & 1 == 0 {
                continue;
            }
            let source = match (f >> 2) & 3 {
                0 => EventKind::Home,
                1 => EventKind::Index,
                _ => continue,
            };
            if e.kind != source {
                continue;
            }
            // The index pulse has only a "rising" edge.
            let rising = e.active;
            let (en_bit, st_bit, slot) = if rising { (4, 1, 2 * k) } else { (5, 2, 2 * k + 1) };
            if f >> en_bit & 1 == 0 {
                continue;
            }
            let continuous = f & 2 != 0;
            if !continuous && self.status >> (sh + st_bit) & 1 != 0 {
                continue;
            }
            self.pos[slot] = pos as i32;
            self.status |= 1 << (sh + st_bit);
        }
    }
}
