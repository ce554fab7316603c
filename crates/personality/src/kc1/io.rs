//! The Kollmorgen digital inputs in 60FDh (KC1 §7.2.3.8, AKD §6.2.3.8):
//! bits 16–22 mirror the machine's DIN1–7, bits 24–30 flag a change of
//! each since its flag was reset through 20B8h (KC1 §7.2.2.14, AKD
//! §6.2.2.18, bits 0–6 for DIN1–7).

use crate::build::Context;
use drivebus_od::{EntryRef, ObjectDictionary};

/// The seven digital inputs of the drive.
const DINS: u16 = 0x7F;

/// Input mirror and change flags.
#[derive(Debug, Clone, Default)]
pub struct Inputs {
    objects: usize,
    inputs: Option<EntryRef>,
    /// The levels last seen (`None` before the first step: no change yet).
    seen: Option<u16>,
    changed: u16,
}

impl Inputs {
    /// 20B8h: reset the change flags of the inputs whose bits are set.
    pub fn reset_changes(&mut self, bits: u16) {
        self.changed &= !bits;
    }

    /// After every step: 60FDh bits 16–22 and 24–30.
    pub fn update(&mut self, cx: &Context<'_>, od: &mut ObjectDictionary) {
        if self.objects != od.objects().len() {
            self.objects = od.objects().len();
            self.inputs = od.find(0x60FD, 0).ok();
        }
        let lines = cx.drive.model().digital_inputs() & DINS;
        if let Some(seen) = self.seen {
            self.changed |= (lines ^ seen) & DINS;
        }
        self.seen = Some(lines);
        if let Some(r) = self.inputs {
            let base = od.word(r) as u32 & 0xFFFF;
            let v = base | u32::from(lines) << 16 | u32::from(self.changed) << 24;
            od.set_raw(r, &v.to_le_bytes());
        }
    }
}
