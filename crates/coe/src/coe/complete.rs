//! SDO complete access (ETG.1000.6 §5.6.2, CA bit of the SDO command).
//!
//! The image of an ARRAY or RECORD starting at sub-index 0 is sub 0 as 16
//! bits (its UNSIGNED8 value and a pad byte, as SOEM's `ec_PDOassignt`
//! expects), then sub-indices 1..=SI0 at their own sizes; starting at
//! sub-index 1 the image omits sub 0. BOOLEAN entries take one bit and are
//! packed; every other entry starts on a byte boundary. Sub-indices that do
//! not exist (gaps in a RECORD) take no space. Entries of variable length
//! cannot be placed, so such objects answer `0601 0004`.
//!
//! A complete download writes in the order a device's mapping rules need
//! (ETG.1000.6 PDO assignment, iPOS manual §2.4): sub 0 = 0, the entries,
//! then sub 0 = n. Read-only entries in the image are skipped, as a
//! complete image necessarily carries them. A refused write ends the
//! download with the device's abort; the entries already written stay
//! written (the device's own rules, e.g. "only while sub 0 = 0", are what
//! keep a half-applied image inactive).

use super::abort;
use crate::access::ObjectAccess;
use alloc::vec::Vec;
use drivebus_od::{DataType, ObjectCode, SdoAbort};

/// Objects whose complete image is sub 0 plus entries (everything else is
/// a single value).
fn is_compound(code: ObjectCode) -> bool {
    matches!(code, ObjectCode::Array | ObjectCode::Record | ObjectCode::DefStruct)
}

/// Bits an entry takes in the image; `0601 0004` for variable-length types.
fn entry_bits(dt: DataType) -> Result<usize, SdoAbort> {
    match dt.fixed_size() {
        _ if dt == DataType::Boolean => Ok(1),
        Some(n) => Ok(8 * n),
        None => Err(abort::CA_VARIABLE_LENGTH),
    }
}

/// What a complete access needs to know about the object, copied out of
/// the dictionary so the device can be called mutably afterwards.
struct Shape {
    compound: bool,
    highest: u8,
    sub0_type: Option<DataType>,
    sub0_writable: bool,
}

fn shape<A: ObjectAccess + ?Sized>(objects: &A, index: u16, start_sub: u8) -> Result<Shape, SdoAbort> {
    // ETG.1000.6: a complete access starts at sub-index 0 or 1.
    if start_sub > 1 {
        return Err(SdoAbort::UNSUPPORTED_ACCESS);
    }
    let obj = objects.dictionary().object(index).ok_or(SdoAbort::NO_OBJECT)?;
    let s0 = obj.get(0);
    Ok(Shape {
        compound: is_compound(obj.code),
        highest: obj.subs().last().map_or(0, |s| s.sub),
        sub0_type: s0.map(|s| s.data_type),
        sub0_writable: s0.is_some_and(|s| s.access.writable()),
    })
}

/// Size in bits of the image of entries 1..=n (plus 16 bits of sub 0 when
/// starting at 0).
fn image_bits<A: ObjectAccess + ?Sized>(
    objects: &A,
    index: u16,
    start_sub: u8,
    n: u8,
) -> Result<usize, SdoAbort> {
    let obj = objects.dictionary().object(index).ok_or(SdoAbort::NO_OBJECT)?;
    let mut bits: usize = if start_sub == 0 { 16 } else { 0 };
    for s in obj.subs().iter().filter(|s| (1..=n).contains(&s.sub)) {
        let b = entry_bits(s.data_type)?;
        bits = entry_start(bits, b) + b;
    }
    Ok(bits)
}

/// Where an entry of `bits` bits starts in an image whose entries so far
/// end at bit `end`: entries shorter than a byte (BOOLEAN) are packed,
/// every other entry starts on a byte boundary.
const fn entry_start(end: usize, bits: usize) -> usize {
    if bits < 8 { end } else { end.next_multiple_of(8) }
}

/// Cuts a complete-access image (a master's upload from `start_sub`, which
/// is 0 or 1) into its entries. `entries` are the sub-indices from 1 present in the
/// image (gaps of a RECORD left out) with their bit lengths, in order, as
/// the slave's SDO Information gives them. Starting at 0, sub 0 comes first
/// as 16 bits. An entry shorter than a byte comes back as one byte holding
/// its bits. `None` when the image is not exactly as long as the layout or
/// an entry has no length.
pub fn split_image(image: &[u8], start_sub: u8, entries: &[(u8, u16)]) -> Option<Vec<(u8, Vec<u8>)>> {
    let mut out = Vec::with_capacity(entries.len() + 1);
    let mut end = match start_sub {
        0 => {
            out.push((0, alloc::vec![*image.first()?]));
            16
        }
        1 => 0,
        _ => return None,
    };
    for &(sub, bits) in entries {
        let bits = usize::from(bits);
        if bits == 0 {
            return None;
        }
        let at = entry_start(end, bits);
        let value = if bits < 8 {
            let v = (*image.get(at / 8)? >> (at % 8)) & ((1u8 << bits) - 1);
            if at % 8 + bits > 8 {
                return None;
            }
            alloc::vec![v]
        } else {
            image.get(at / 8..(at + bits).div_ceil(8))?.to_vec()
        };
        out.push((sub, value));
        end = at + bits;
    }
    (image.len() == end.div_ceil(8)).then_some(out)
}

/// The current value of sub 0 (the number of entries).
fn read_sub0<A: ObjectAccess + ?Sized>(objects: &mut A, index: u16) -> Result<u8, SdoAbort> {
    Ok(objects.read(index, 0)?.first().copied().unwrap_or(0))
}

/// Build the complete image of `index` from `start_sub` (0 or 1) into `out`,
/// reading every entry through the device. Write-only entries read as zeros.
pub(crate) fn upload<A: ObjectAccess + ?Sized>(
    objects: &mut A,
    index: u16,
    start_sub: u8,
    out: &mut Vec<u8>,
) -> Result<(), SdoAbort> {
    let shape = shape(objects, index, start_sub)?;
    out.clear();
    if !shape.compound {
        if start_sub != 0 {
            return Err(SdoAbort::NO_SUB_INDEX);
        }
        entry_bits(shape.sub0_type.ok_or(SdoAbort::NO_SUB_INDEX)?)?;
        let v = objects.read(index, 0)?;
        out.try_reserve(v.len()).map_err(|_| SdoAbort::OUT_OF_MEMORY)?;
        out.extend_from_slice(v);
        return Ok(());
    }
    let n = read_sub0(objects, index)?;
    let bits = image_bits(objects, index, start_sub, n)?;
    out.try_reserve(bits.div_ceil(8)).map_err(|_| SdoAbort::OUT_OF_MEMORY)?;
    let mut bitpos = 0;
    if start_sub == 0 {
        out.extend_from_slice(&[n, 0]);
        bitpos = 16;
    }
    for sub in 1..=n {
        let Some((dt, readable)) =
            objects.dictionary().get(index, sub).map(|s| (s.data_type, s.access.readable()))
        else {
            continue;
        };
        let b = entry_bits(dt)?;
        if b == 1 {
            let v = if readable { objects.read(index, sub)?.first().copied().unwrap_or(0) & 1 } else { 0 };
            if bitpos % 8 == 0 {
                out.push(0);
            }
            if let Some(last) = out.last_mut() {
                *last |= v << (bitpos % 8);
            }
            bitpos += 1;
        } else {
            let len = b / 8;
            let start = out.len();
            if readable {
                let v = objects.read(index, sub)?;
                out.extend_from_slice(&v[..v.len().min(len)]);
            }
            out.resize(start + len, 0);
            bitpos = out.len() * 8;
        }
    }
    Ok(())
}

/// The largest image a download to `index` from `start_sub` may carry
/// (every entry present), for the check before segments arrive.
pub(crate) fn max_image_len<A: ObjectAccess + ?Sized>(
    objects: &A,
    index: u16,
    start_sub: u8,
) -> Result<usize, SdoAbort> {
    let shape = shape(objects, index, start_sub)?;
    if !shape.compound {
        if start_sub != 0 {
            return Err(SdoAbort::NO_SUB_INDEX);
        }
        let dt = shape.sub0_type.ok_or(SdoAbort::NO_SUB_INDEX)?;
        return entry_bits(dt).map(|b| b.div_ceil(8));
    }
    Ok(image_bits(objects, index, start_sub, shape.highest)?.div_ceil(8))
}

/// Apply a complete image to `index` from `start_sub` (0 or 1).
///
/// Length rules (ETG.1020 asks for the image of the current object, i.e.
/// of sub 0's value): shorter than the image of entries 1..=n is
/// `0607 0013`; longer is accepted up to the image of every entry (a
/// conformance tester writes whole objects), beyond that `0607 0012`.
pub(crate) fn download<A: ObjectAccess + ?Sized>(
    objects: &mut A,
    index: u16,
    start_sub: u8,
    data: &[u8],
) -> Result<(), SdoAbort> {
    let shape = shape(objects, index, start_sub)?;
    if !shape.compound {
        if start_sub != 0 {
            return Err(SdoAbort::NO_SUB_INDEX);
        }
        entry_bits(shape.sub0_type.ok_or(SdoAbort::NO_SUB_INDEX)?)?;
        return objects.write(index, 0, data);
    }
    let (n, mut bitpos) = if start_sub == 0 {
        (*data.first().ok_or(SdoAbort::DATA_TOO_SHORT)?, 16)
    } else {
        (read_sub0(objects, index)?, 0)
    };
    if n > shape.highest {
        return Err(SdoAbort::VALUE_TOO_HIGH);
    }
    let need = image_bits(objects, index, start_sub, n)?.div_ceil(8);
    let full = image_bits(objects, index, start_sub, shape.highest)?.div_ceil(8);
    if data.len() < need {
        return Err(SdoAbort::DATA_TOO_SHORT);
    }
    if data.len() > need.max(full) {
        return Err(SdoAbort::DATA_TOO_LONG);
    }
    let set_sub0 = start_sub == 0 && shape.sub0_writable;
    if start_sub == 0 && !shape.sub0_writable && n != read_sub0(objects, index)? {
        return Err(SdoAbort::WRITE_READ_ONLY);
    }
    if set_sub0 {
        objects.write(index, 0, &[0])?;
    }
    for sub in 1..=n {
        let Some((dt, writable)) =
            objects.dictionary().get(index, sub).map(|s| (s.data_type, s.access.writable()))
        else {
            continue;
        };
        let b = entry_bits(dt)?;
        let mut value = [0u8; 8];
        // Checked reads: the length was verified against the layout, but a
        // device whose writes change the object's shape must not make us
        // index past the image.
        let len = if b == 1 {
            value[0] = (data.get(bitpos / 8).ok_or(SdoAbort::DATA_TOO_SHORT)? >> (bitpos % 8)) & 1;
            bitpos += 1;
            1
        } else {
            let start = bitpos.div_ceil(8);
            let len = b / 8;
            value[..len].copy_from_slice(data.get(start..start + len).ok_or(SdoAbort::DATA_TOO_SHORT)?);
            bitpos = (start + len) * 8;
            len
        };
        if writable {
            objects.write(index, sub, &value[..len])?;
        }
    }
    if set_sub0 {
        objects.write(index, 0, &[n])?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_od::{Access, NoHooks, Object, ObjectDictionary, SubObject, Value};

    fn dev() -> (ObjectDictionary, NoHooks) {
        let mut od = ObjectDictionary::new();
        // A PDO assignment: writable sub 0, four u16 entries.
        let mut a = Object::with_code(0x1C12, ObjectCode::Array, "RxPDO assign").with_sub(SubObject::new(
            0,
            "n",
            DataType::Unsigned8,
            Access::Rw,
            Value::U8(1),
        ));
        for i in 1..=4u8 {
            a = a.with_sub(SubObject::new(
                i,
                "pdo",
                DataType::Unsigned16,
                Access::Rw,
                Value::U16(0x15FF + u16::from(i)),
            ));
        }
        od.insert(a);
        // A record with a gap, a boolean pair and a read-only entry.
        od.insert(
            Object::record(0x2100, "Rec")
                .with_sub(SubObject::new(1, "a", DataType::Unsigned8, Access::Rw, Value::U8(0x11)))
                .with_sub(SubObject::new(2, "b0", DataType::Boolean, Access::Rw, Value::Bool(true)))
                .with_sub(SubObject::new(3, "b1", DataType::Boolean, Access::Rw, Value::Bool(false)))
                .with_sub(SubObject::new(4, "c", DataType::Unsigned32, Access::Ro, Value::U32(0xA1B2C3D4)))
                .with_sub(SubObject::new(6, "w", DataType::Integer16, Access::Wo, Value::I16(-1))),
        );
        od.insert(Object::var(0x2200, "s", DataType::VisibleString, Access::Rw, Value::Str("ab".into())));
        od.insert(Object::var(0x2201, "v", DataType::Unsigned32, Access::Rw, Value::U32(5)));
        (od, NoHooks)
    }

    #[test]
    fn upload_pads_sub0_and_follows_its_value() {
        let mut d = dev();
        let mut out = Vec::new();
        upload(&mut d, 0x1C12, 0, &mut out).unwrap();
        assert_eq!(out, [1, 0, 0x00, 0x16]);
        upload(&mut d, 0x1C12, 1, &mut out).unwrap();
        assert_eq!(out, [0x00, 0x16]);
        // Sub 0 of the record is 6 (the highest sub-index); sub 5 is a gap,
        // booleans share a byte, the write-only entry reads as zeros.
        upload(&mut d, 0x2100, 0, &mut out).unwrap();
        assert_eq!(out, [6, 0, 0x11, 0b01, 0xD4, 0xC3, 0xB2, 0xA1, 0, 0]);
        assert_eq!(upload(&mut d, 0x2100, 2, &mut out), Err(SdoAbort::UNSUPPORTED_ACCESS));
        assert_eq!(upload(&mut d, 0x2200, 0, &mut out), Err(abort::CA_VARIABLE_LENGTH));
        upload(&mut d, 0x2201, 0, &mut out).unwrap();
        assert_eq!(out, [5, 0, 0, 0]);
        assert_eq!(upload(&mut d, 0x2201, 1, &mut out), Err(SdoAbort::NO_SUB_INDEX));
        assert_eq!(upload(&mut d, 0x3000, 0, &mut out), Err(SdoAbort::NO_OBJECT));
    }

    #[test]
    fn a_master_splits_what_upload_builds() {
        let mut d = dev();
        let mut img = Vec::new();
        upload(&mut d, 0x2100, 0, &mut img).unwrap();
        let layout = [(1, 8), (2, 1), (3, 1), (4, 32), (6, 16)];
        let e = split_image(&img, 0, &layout).unwrap();
        assert_eq!(e[0], (0, vec![6]));
        assert_eq!(e[1..4], [(1, vec![0x11]), (2, vec![1]), (3, vec![0])]);
        assert_eq!(e[4], (4, vec![0xD4, 0xC3, 0xB2, 0xA1]));
        upload(&mut d, 0x2100, 1, &mut img).unwrap();
        assert_eq!(split_image(&img, 1, &layout).unwrap()[3], (4, vec![0xD4, 0xC3, 0xB2, 0xA1]));
        // A layout that does not match the image is refused, not guessed.
        assert_eq!(split_image(&img, 1, &layout[..4]), None);
        assert_eq!(split_image(&img, 1, &[(1, 0)]), None);
        assert_eq!(split_image(&img, 2, &layout), None);
    }

    #[test]
    fn download_writes_sub0_last_and_checks_length() {
        let mut d = dev();
        download(&mut d, 0x1C12, 0, &[2, 0, 0x01, 0x16, 0x03, 0x16]).unwrap();
        assert_eq!(d.0.get_u64(0x1C12, 0), Some(2));
        assert_eq!(d.0.get_u64(0x1C12, 2), Some(0x1603));
        assert_eq!(download(&mut d, 0x1C12, 0, &[2, 0, 0x01, 0x16]), Err(SdoAbort::DATA_TOO_SHORT));
        assert_eq!(download(&mut d, 0x1C12, 0, &[0; 11]), Err(SdoAbort::DATA_TOO_LONG));
        assert_eq!(download(&mut d, 0x1C12, 0, &[5, 0]), Err(SdoAbort::VALUE_TOO_HIGH));
        // A whole-object image with sub 0 = 1 is accepted; only entry 1 is written.
        download(&mut d, 0x1C12, 0, &[1, 0, 0x00, 0x17, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA]).unwrap();
        assert_eq!((d.0.get_u64(0x1C12, 0), d.0.get_u64(0x1C12, 1)), (Some(1), Some(0x1700)));
        assert_eq!(d.0.get_u64(0x1C12, 2), Some(0x1603));
        // From sub 1: entries 1..=current sub 0.
        download(&mut d, 0x1C12, 1, &[0x02, 0x16]).unwrap();
        assert_eq!(d.0.get_u64(0x1C12, 1), Some(0x1602));
    }

    #[test]
    fn download_of_a_record_skips_read_only_entries() {
        let mut d = dev();
        // Sub 0 of a record is constant: the image must keep its value.
        let img = [6, 0, 0x22, 0b10, 0, 0, 0, 0, 0x34, 0x12];
        download(&mut d, 0x2100, 0, &img).unwrap();
        assert_eq!(d.0.get_u64(0x2100, 1), Some(0x22));
        assert_eq!((d.0.get_u64(0x2100, 2), d.0.get_u64(0x2100, 3)), (Some(0), Some(1)));
        assert_eq!(d.0.get_u64(0x2100, 4), Some(0xA1B2C3D4));
        assert_eq!(d.0.get_i64(0x2100, 6), Some(0x1234));
        assert_eq!(download(&mut d, 0x2100, 0, &[4, 0, 0, 0, 0, 0, 0, 0]), Err(SdoAbort::WRITE_READ_ONLY));
        assert_eq!(max_image_len(&d, 0x2100, 0), Ok(10));
        assert_eq!(max_image_len(&d, 0x1C12, 1), Ok(8));
        assert_eq!(max_image_len(&d, 0x2201, 0), Ok(4));
    }
}
