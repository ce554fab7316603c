//! Mapping entries: validation (CiA 301 7.5.2.36 / 7.5.2.38), resolution into
//! a copy plan, and moving data between the object dictionary and a PDO.

use crate::bits::{pack_bits, unpack_bits};
use crate::config::{Granularity, PdoConfig};
use crate::events::{EventQueue, PdoEvent};
use alloc::vec::Vec;
use drivebus_can::MAX_DATA_LEN;
use drivebus_od::{DataType, EntryRef, ObjectDictionary, ObjectHooks, SdoAbort};

/// Direction of a PDO.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PdoKind {
    /// Receive PDO: the device consumes it (1400h/1600h).
    Rpdo,
    /// Transmit PDO: the device produces it (1800h/1A00h).
    Tpdo,
}

/// Build a mapping entry: `index << 16 | sub << 8 | bit length`.
#[inline]
pub const fn map_entry(index: u16, sub: u8, bits: u8) -> u32 {
    (index as u32) << 16 | (sub as u32) << 8 | bits as u32
}

/// Split a mapping entry into `(index, sub, bit length)`.
#[inline]
pub const fn split_entry(e: u32) -> (u16, u8, u8) {
    ((e >> 16) as u16, (e >> 8) as u8, e as u8)
}

/// One resolved mapping entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Seg {
    /// `None` for a dummy entry (RPDO: skipped; TPDO: zeros).
    pub r: Option<EntryRef>,
    pub bit_off: u16,
    pub bit_len: u8,
    /// Size of the object's value in bytes.
    pub size: u8,
    /// No owner, watcher or live value, no limits, not BOOLEAN: a raw copy is equivalent to a
    /// checked write/read, so the fast path may skip the checks.
    pub plain: bool,
}

/// One object of a byte-aligned plan: copy `len` bytes at `off`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Copy {
    pub r: EntryRef,
    pub off: u8,
    pub len: u8,
    /// The value's bits in the frame as a word: `(frame >> 8·off) & mask`.
    pub mask: u64,
}

/// A resolved mapping: what the frame path walks (no search, no allocation).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Plan {
    pub segs: Vec<Seg>,
    /// The non-dummy entries as byte copies (meaningful when `aligned`).
    pub copies: Vec<Copy>,
    /// Mapped length in bytes (rounded up).
    pub len: u8,
    /// Every entry is byte aligned and whole-object: copy bytes directly.
    pub aligned: bool,
    /// Every object entry is plain (see [`Seg::plain`]).
    pub all_plain: bool,
    /// Some entry is live: its owner refreshes it before sampling.
    pub hooked: bool,
}

/// Check one mapping entry for a PDO of direction `kind`; the entry's bit
/// length on success.
///
/// Aborts (CiA 301 7.5.2.36 and Table 22): object or sub-index absent
/// → `0602 0000`; not mappable, wrong direction, variable size, bit length
/// that is not the object's size for the granularity, unsupported dummy
/// → `0604 0041`; a single entry longer than the PDO → `0604 0042`.
pub fn validate_entry(
    od: &ObjectDictionary,
    cfg: &PdoConfig,
    kind: PdoKind,
    entry: u32,
) -> Result<u8, SdoAbort> {
    let (index, sub, bits) = split_entry(entry);
    if bits == 0 {
        return Err(SdoAbort::NOT_MAPPABLE);
    }
    if u32::from(bits) > cfg.max_bits() {
        return Err(SdoAbort::PDO_TOO_LONG);
    }
    if index < 0x0020 {
        // Data type indices are dummy entries (CiA 301 7.4.7.1).
        let dt = DataType::from_index(index).ok_or(SdoAbort::NOT_MAPPABLE)?;
        if !cfg.dummy_supported(index) || sub != 0 {
            return Err(SdoAbort::NOT_MAPPABLE);
        }
        let size = dt.fixed_size().ok_or(SdoAbort::NOT_MAPPABLE)?;
        return if length_fits(cfg.granularity, dt, size, bits) {
            Ok(bits)
        } else {
            Err(SdoAbort::NOT_MAPPABLE)
        };
    }
    let e = od.get(index, sub).ok_or(SdoAbort::NO_OBJECT)?;
    let ok_dir = match kind {
        PdoKind::Rpdo => e.rpdo_mappable(),
        PdoKind::Tpdo => e.tpdo_mappable(),
    };
    if !ok_dir {
        return Err(SdoAbort::NOT_MAPPABLE);
    }
    let size = e.data_type.fixed_size().ok_or(SdoAbort::NOT_MAPPABLE)?;
    if !length_fits(cfg.granularity, e.data_type, size, bits) {
        return Err(SdoAbort::NOT_MAPPABLE);
    }
    Ok(bits)
}

/// The mapped length must be the object's length (CiA 301 7.4.7.1); a
/// BOOLEAN takes one bit, or a whole byte (always so with byte granularity).
fn length_fits(g: Granularity, dt: DataType, size: usize, bits: u8) -> bool {
    let bits = usize::from(bits);
    match (g, dt) {
        (Granularity::Bit, DataType::Boolean) => bits == 1 || bits == 8,
        _ => bits == 8 * size,
    }
}

/// Validate `entries` as a whole mapping (sub 0 = `entries.len()`): every
/// entry, then the total length (`0604 0042`).
pub fn validate_mapping(
    od: &ObjectDictionary,
    cfg: &PdoConfig,
    kind: PdoKind,
    entries: impl IntoIterator<Item = u32>,
) -> Result<u32, SdoAbort> {
    let mut total = 0u32;
    for e in entries {
        total += u32::from(validate_entry(od, cfg, kind, e)?);
    }
    if total > cfg.max_bits() {
        return Err(SdoAbort::PDO_TOO_LONG);
    }
    Ok(total)
}

/// Resolve a validated mapping into a plan. Entries that no longer resolve
/// (an object removed since) make the whole mapping unusable: `Err`.
pub(crate) fn resolve(
    od: &ObjectDictionary,
    cfg: &PdoConfig,
    kind: PdoKind,
    entries: &[u32],
) -> Result<Plan, SdoAbort> {
    validate_mapping(od, cfg, kind, entries.iter().copied())?;
    let mut plan = Plan {
        segs: Vec::with_capacity(entries.len()),
        copies: Vec::with_capacity(entries.len()),
        len: 0,
        aligned: true,
        all_plain: true,
        hooked: false,
    };
    let mut off = 0u16;
    for &e in entries {
        let (index, sub, bits) = split_entry(e);
        let seg = if index < 0x0020 {
            let size = DataType::from_index(index).and_then(DataType::fixed_size).unwrap_or(1);
            Seg { r: None, bit_off: off, bit_len: bits, size: size as u8, plain: true }
        } else {
            let r = od.find(index, sub)?;
            let s = od.entry(r);
            let size = s.data_type.fixed_size().unwrap_or(0);
            let plain = !s.is_hooked()
                && s.low_limit.is_none()
                && s.high_limit.is_none()
                && s.data_type != DataType::Boolean;
            plan.hooked |= s.live;
            Seg { r: Some(r), bit_off: off, bit_len: bits, size: size as u8, plain }
        };
        if seg.bit_off % 8 != 0 || u16::from(seg.bit_len) != 8 * u16::from(seg.size) {
            plan.aligned = false;
        }
        plan.all_plain &= seg.plain;
        if let Some(r) = seg.r {
            let mask = if seg.size >= 8 { u64::MAX } else { (1u64 << (8 * u32::from(seg.size))) - 1 };
            plan.copies.push(Copy { r, off: (seg.bit_off / 8) as u8, len: seg.size, mask });
        }
        off += u16::from(bits);
        plan.segs.push(seg);
    }
    plan.len = off.div_ceil(8) as u8;
    Ok(plan)
}

/// Fill `buf` (zeroed by the caller) with the mapped values (TPDO sampling). Hooked objects are
/// refreshed through `read_ref` first; a refusal is reported and the stored
/// value sent.
#[inline]
pub(crate) fn sample<H: ObjectHooks + ?Sized>(
    plan: &Plan,
    od: &mut ObjectDictionary,
    hooks: &mut H,
    tpdo: u16,
    events: &mut EventQueue,
    buf: &mut [u8; MAX_DATA_LEN],
) {
    if plan.hooked {
        for s in &plan.segs {
            if let Some(r) = s.r
                && !s.plain
                && let Err(abort) = od.read_ref(hooks, r)
            {
                let (index, sub) = od.index_of(r);
                events.push(PdoEvent::TpdoReadFailed { tpdo, index, sub, abort });
            }
        }
    }
    if plan.aligned {
        // Whole-byte entries: OR the values' words into the frame word
        // (dummies stay zero: callers pass a zeroed buffer).
        let mut w = u64::from_le_bytes(*buf);
        for c in &plan.copies {
            w |= (od.word(c.r) & c.mask) << (8 * u32::from(c.off));
        }
        *buf = w.to_le_bytes();
    } else {
        for s in &plan.segs {
            if let Some(r) = s.r {
                let v = drivebus_od::le_u64(od.bytes(r));
                pack_bits(buf, usize::from(s.bit_off), usize::from(s.bit_len), v);
            }
        }
    }
}

/// Write the mapped values of a received PDO into the dictionary. Plain
/// entries are copied in place; the rest go through `write_local` (limits
/// and hooks), refusals are reported.
#[inline]
pub(crate) fn apply<H: ObjectHooks + ?Sized>(
    plan: &Plan,
    od: &mut ObjectDictionary,
    hooks: &mut H,
    rpdo: u16,
    events: &mut EventQueue,
    data: &[u8; MAX_DATA_LEN],
) {
    if plan.aligned && plan.all_plain {
        // Fast path: each value is a masked shift of the frame word, stored
        // in place; equivalent to checked writes for plain objects.
        let w = u64::from_le_bytes(*data);
        for c in &plan.copies {
            od.set_word(c.r, (w >> (8 * u32::from(c.off))) & c.mask);
        }
        return;
    }
    for s in &plan.segs {
        let Some(r) = s.r else { continue };
        let n = usize::from(s.size);
        let tmp: [u8; 8];
        let src: &[u8] = if plan.aligned {
            let off = usize::from(s.bit_off / 8);
            match data.get(off..off + n) {
                Some(x) => x,
                None => continue,
            }
        } else {
            let v = unpack_bits(data, usize::from(s.bit_off), usize::from(s.bit_len));
            tmp = v.to_le_bytes();
            match tmp.get(..n) {
                Some(x) => x,
                None => continue,
            }
        };
        if s.plain && od.bytes(r).len() == n {
            od.set_le(r, src);
        } else if let Err(abort) = od.write_local(hooks, r, src) {
            let (index, sub) = od.index_of(r);
            events.push(PdoEvent::RpdoWriteFailed { rpdo, index, sub, abort });
        }
    }
}
