//! What several personalities share: PDO default builders, the CiA 402
//! default mappings, the error-register class of an EMCY code, and the
//! frame fixes two Kollmorgen quirks need. Each personality lives in its
//! own module (`kc1/`, `akd/`, …); the framework in `build.rs`.

use crate::PdoDefault;
use drivebus_can::Frame;
use drivebus_od::ObjectDictionary;

extern crate alloc;

/// The CiA 301 error-register class bit of an EMCY code (§7.5.2.2 Table 48
/// classes), *without* the generic bit 0.
pub fn class_bit(code: u16) -> u8 {
    match code >> 12 {
        0x2 => 0x02,                                           // current
        0x3 => 0x04,                                           // voltage
        0x4 => 0x08,                                           // temperature
        0x8 if code >> 8 == 0x81 || code >> 8 == 0x82 => 0x10, // communication
        0x6 | 0x8 => 0x80,
        0x7 | 0x5 | 0x9 | 0xF => 0x80, // device hardware, external, additional functions, manufacturer
        _ => 0x00,
    }
}

/// An expedited SDO download whose size field disagrees with the object's
/// fixed size, rewritten to the object's size: drives that take the size
/// from their dictionary (KC1/AKD, seed000 example 13) accept such frames.
/// `None` when the frame is not such a download (or the object is unknown,
/// variable-sized or longer than 4 bytes).
pub fn resize_expedited(od: &ObjectDictionary, node_id: u8, f: &Frame) -> Option<Frame> {
    if f.std_id()? != 0x600 + u16::from(node_id) || f.data().len() != 8 {
        return None;
    }
    let d = f.data();
    // ccs 1, expedited (e = 1), size indicated (s = 1).
    if d[0] & 0xE3 != 0x23 {
        return None;
    }
    let n = 4 - usize::from((d[0] >> 2) & 3);
    let (index, sub) = (u16::from_le_bytes([d[1], d[2]]), d[3]);
    let r = od.find(index, sub).ok()?;
    let size = od.entry(r).data_type.fixed_size()?;
    if size == n || size > 4 || size == 0 {
        return None;
    }
    let mut b = [0u8; 8];
    b.copy_from_slice(d);
    b[0] = 0x23 | (((4 - size) as u8) << 2);
    for x in b.iter_mut().skip(4 + size) {
        *x = 0;
    }
    Some(Frame::new(0x600 + u16::from(node_id), &b))
}

/// An RPDO shorter than its mapping, padded with zero bytes to the mapped
/// length: the Kollmorgen drives take the bytes that came (KC1 example 6
/// `203 00 40` for a 32-bit 60FFh, example 9 `303 20 4E 00 00` for 8 bytes)
/// where CiA 301 would answer EMCY 8210h. `None` when the frame is not a
/// short RPDO of this node.
pub fn pad_short_rpdo(od: &ObjectDictionary, f: &Frame) -> Option<Frame> {
    let id = u32::from(f.std_id()?);
    // A full frame or a remote request is never padded: no search of the
    // RPDO parameters for it (this filter sees every received frame).
    if f.data().len() >= 8 || f.is_rtr() {
        return None;
    }
    for n in 0..512u16 {
        let cob = od.get_u32(0x1400 + n, 1)?;
        if cob & 0x8000_0000 != 0 || cob & 0x7FF != id {
            continue;
        }
        let count = od.get_u32(0x1600 + n, 0).unwrap_or(0) as u8;
        let bits: u32 = (1..=count).filter_map(|i| od.get_u32(0x1600 + n, i)).map(|e| e & 0xFF).sum();
        let len = (bits as usize).div_ceil(8);
        if f.data().len() >= len || len > 8 || f.is_rtr() {
            return None;
        }
        let mut b = [0u8; 8];
        b[..f.data().len()].copy_from_slice(f.data());
        return Some(Frame::new(id as u16, &b[..len]));
    }
    None
}

/// A CAN PDO default: valid unless `cob_id` has bit 31, transmission type 255.
pub(crate) const fn can(cob_id: u32, event_timer_ms: u16, mapping: &'static [u32]) -> PdoDefault {
    PdoDefault {
        cob_id: Some(cob_id),
        enabled: cob_id & 0x8000_0000 == 0,
        transmission_type: Some(0xFF),
        event_timer_ms,
        mapping,
    }
}

/// An EtherCAT (CoE) PDO default: no COB-ID, `enabled` = assigned in 1C12h/1C13h.
pub(crate) const fn coe(enabled: bool, mapping: &'static [u32]) -> PdoDefault {
    PdoDefault { cob_id: None, enabled, transmission_type: None, event_timer_ms: 0, mapping }
}

/// The CiA 402 default mappings the Kollmorgen drives and the SSD 630 use
/// (controlword/statusword first, then the mode's set-point or actual value).
pub(crate) mod maps {
    pub const CW: &[u32] = &[0x6040_0010];
    pub const CW_MODE: &[u32] = &[0x6040_0010, 0x6060_0008];
    pub const CW_POS: &[u32] = &[0x6040_0010, 0x607A_0020];
    pub const CW_VEL: &[u32] = &[0x6040_0010, 0x60FF_0020];
    pub const SW: &[u32] = &[0x6041_0010];
    pub const SW_MODE: &[u32] = &[0x6041_0010, 0x6061_0008];
    pub const SW_POS: &[u32] = &[0x6041_0010, 0x6064_0020];
    pub const SW_VEL: &[u32] = &[0x6041_0010, 0x606C_0020];
}
