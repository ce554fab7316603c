//! The latch objects of the capture engines (KC1 §7.2.2.7–13, AKD
//! §6.2.2.10–17) over the drive's touch probe (60B8h–60BDh, the same two
//! capture engines in CiA 402 form): 20A4h enables latch 1/2 on rising
//! and falling edges (or latch 1 on the encoder index), 20A5h shows which
//! latched (and DIN1–4), a write of its bits 8–11 acknowledges a value and
//! re-arms it; 20A0h–20A3h are the four latched positions, 20A6h/20A7h
//! the last edge of latch 1/2.

use super::Kollmorgen;
use crate::build::Context;
use drivebus_od::{EntryRef, ObjectDictionary, SdoAbort};

/// Handles of the latch objects and the touch probe they show.
#[derive(Debug, Clone, Default)]
struct Refs {
    objects: usize,
    status: Option<EntryRef>,
    function: Option<EntryRef>,
    latched: [Option<EntryRef>; 4],
    either: [Option<EntryRef>; 2],
    latch_status: Option<EntryRef>,
    probe: [Option<EntryRef>; 4],
    inputs: Option<EntryRef>,
}

/// The latches' view state.
#[derive(Debug, Clone, Default)]
pub struct Latch {
    refs: Refs,
    /// The probe values last seen, to tell which edge of a latch came last.
    seen: [u32; 4],
    last: [u32; 2],
}

/// 60B8h for a 20A4h control value: probe 1 = latch 1 (bits 0/1 rising /
/// falling), or the index pulse (bit 4) when latch 1 has no edge; probe 2
/// = latch 2 (bits 2/3). Single captures (60B8h bit 1 clear).
pub fn probe_function(control: u16) -> u16 {
    let one = if control & 0x3 != 0 {
        0x01 | (control & 0x1) << 4 | (control & 0x2) << 4
    } else if control & 0x10 != 0 {
        // Trigger 01b: the encoder index, its only edge rising.
        0x01 | 0x04 | 0x10
    } else {
        0
    };
    let two = if control & 0xC != 0 { 0x01 | (control & 0x4) << 2 | (control & 0x8) << 2 } else { 0 };
    one | two << 8
}

impl Latch {
    fn resolve(od: &ObjectDictionary) -> Refs {
        let f = |i: u16, s: u8| od.find(i, s).ok();
        Refs {
            objects: od.objects().len(),
            status: f(0x60B9, 0),
            function: f(0x60B8, 0),
            latched: [f(0x60BA, 0), f(0x60BB, 0), f(0x60BC, 0), f(0x60BD, 0)],
            either: [f(0x20A6, 0), f(0x20A7, 0)],
            latch_status: f(0x20A5, 0),
            probe: [f(0x20A0, 0), f(0x20A1, 0), f(0x20A2, 0), f(0x20A3, 0)],
            inputs: f(0x60FD, 0),
        }
    }

    /// After every step: the latched values and the status.
    pub fn update(&mut self, od: &mut ObjectDictionary) {
        if self.refs.objects != od.objects().len() {
            self.refs = Self::resolve(od);
        }
        let r = &self.refs;
        fn w(od: &ObjectDictionary, x: Option<EntryRef>) -> u64 {
            x.map_or(0, |x| od.word(x))
        }
        for k in 0..4 {
            let v = w(od, r.latched[k]) as u32;
            if v != self.seen[k] {
                self.seen[k] = v;
                self.last[k / 2] = v;
            }
            if let Some(e) = r.probe[k] {
                od.set_raw(e, &v.to_le_bytes());
            }
        }
        for k in 0..2 {
            if let Some(e) = r.either[k] {
                od.set_raw(e, &self.last[k].to_le_bytes());
            }
        }
        let st = w(od, r.status) as u16;
        let din = (w(od, r.inputs) >> 16) as u16;
        // Bits 12–15: DIN4..DIN1 (bit 15 = DIN1).
        let dins = (0..4).fold(0u16, |a, n| a | ((din >> n) & 1) << (15 - n));
        let index = st & 0x02 != 0 && w(od, r.function) & 0x0C == 0x04;
        let latch_status = if index { 0x10 } else { (st >> 1) & 0x3 | ((st >> 9) & 0x3) << 2 } | dins;
        if let Some(e) = r.latch_status {
            od.set_raw(e, &latch_status.to_le_bytes());
        }
    }
}

impl Kollmorgen {
    /// 20A4h: the latch enables as the touch probe function 60B8h.
    pub(crate) fn latch_control(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        control: u16,
    ) -> Result<(), SdoAbort> {
        self.local_write(cx, od, 0x60B8, 0, &probe_function(control).to_le_bytes())
    }

    /// 20A5h bits 8–11 = n (1..=5): acknowledge latch value n, re-arming
    /// its probe (60B8h enable cleared and set again).
    pub(crate) fn latch_acknowledge(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        value: u16,
    ) -> Result<(), SdoAbort> {
        let probe = match (value >> 8) & 0xF {
            0 => return Ok(()),
            1 | 2 | 5 => 0,
            3 | 4 => 1,
            _ => return Err(SdoAbort::INVALID_VALUE),
        };
        let f = od.get_u32(0x60B8, 0).unwrap_or(0) as u16;
        let off = f & !(1 << (8 * probe));
        self.local_write(cx, od, 0x60B8, 0, &off.to_le_bytes())?;
        self.local_write(cx, od, 0x60B8, 0, &f.to_le_bytes())
    }
}
