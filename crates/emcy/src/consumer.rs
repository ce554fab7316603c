//! The EMCY consumer (1028h, CiA 301 §7.5.2) and the EMCY frame decoder.

use crate::{COB_ID_INVALID, OD_EMCY_CONSUMER, can_id_of, check_cob_id_write, describe, u32_of};
use core::fmt;
use drivebus_can::{CanId, Frame};
use drivebus_od::{Access, DataType, Object, ObjectCode, ObjectDictionary, SdoAbort, SubObject, Value};

/// Most consumer entries (1028h sub 1..127).
const MAX_CONSUMERS: usize = 127;

/// The content of one EMCY frame (CiA 301 §7.2.7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmcyMessage {
    /// Emergency error code (bytes 0..1, little-endian).
    pub code: u16,
    /// Error register 1001h of the producer (byte 2).
    pub register: u8,
    /// Manufacturer-specific error field (bytes 3..7), zero-padded when the
    /// frame was shorter than 8 bytes.
    pub data: [u8; 5],
    /// The frame's DLC; CiA 301 requires 8, shorter frames are still decoded.
    pub len: u8,
}

impl EmcyMessage {
    /// True for an error-reset / no-error message (code 00xxh).
    pub fn is_reset(&self) -> bool {
        self.code >> 8 == 0
    }
}

impl fmt::Display for EmcyMessage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "EMCY {:04X}", self.code)?;
        if let Some(t) = describe(self.code) {
            write!(f, " ({t})")?;
        }
        write!(f, " register {:02X} data", self.register)?;
        for b in self.data {
            write!(f, " {b:02X}")?;
        }
        Ok(())
    }
}

/// Decode an EMCY payload without looking at the identifier.
///
/// Accepts DLC 3..=8 (code and register are the minimum that means
/// anything): CiA 301 EMCYs are 8 bytes, but some manuals print 7-byte
/// frames (seed000 KC1 §8.2.1.10) and a tolerant reader is more useful to a
/// master. RTR frames and DLC < 3 give `None`.
pub fn decode(frame: &Frame) -> Option<EmcyMessage> {
    let d = frame.data();
    if frame.is_rtr() || d.len() < 3 {
        return None;
    }
    let mut data = [0u8; 5];
    let extra = &d[3..];
    data[..extra.len().min(5)].copy_from_slice(&extra[..extra.len().min(5)]);
    Some(EmcyMessage { code: u16::from_le_bytes([d[0], d[1]]), register: d[2], data, len: d.len() as u8 })
}

/// An EMCY received from a producer configured in 1028h.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmcyReceived {
    /// The 1028h sub-index that matched.
    pub sub: u8,
    /// The identifier the frame came on.
    pub cob_id: CanId,
    /// The producer's node-ID when the identifier is the default `80h + id`.
    pub node_id: Option<u8>,
    /// Emergency error code.
    pub code: u16,
    /// The producer's error register.
    pub register: u8,
    /// Manufacturer-specific error field.
    pub data: [u8; 5],
}

/// The EMCY consumer: which producers' EMCYs this node listens to.
#[derive(Clone, Debug)]
pub struct EmcyConsumer {
    /// Raw 1028h entries; index `i` is sub-index `i + 1`.
    entries: [u32; MAX_CONSUMERS],
    /// Identifiers of the valid entries, same indexing.
    ids: [Option<CanId>; MAX_CONSUMERS],
    n: usize,
    /// One bit per 11-bit identifier of a valid entry: rejects the bus's
    /// other frames without scanning the entries.
    std_mask: [u64; 32],
    any_extended: bool,
}

impl EmcyConsumer {
    /// Insert 1028h with `count` entries (1..=127). Entry `k` defaults to
    /// `80h + k`, valid: the default EMCY of node `k` (CiA 301 leaves the
    /// defaults to the manufacturer; this is what a master wants).
    pub fn install(od: &mut ObjectDictionary, count: u8) -> EmcyConsumer {
        let n = (count as usize).clamp(1, MAX_CONSUMERS);
        let mut o = Object::with_code(OD_EMCY_CONSUMER, ObjectCode::Array, "Emergency consumer object")
            .with_sub(SubObject::new(
                0,
                "Highest sub-index supported",
                DataType::Unsigned8,
                Access::Const,
                Value::U8(0),
            ));
        let mut c = EmcyConsumer {
            entries: [COB_ID_INVALID; MAX_CONSUMERS],
            ids: [None; MAX_CONSUMERS],
            n,
            std_mask: [0; 32],
            any_extended: false,
        };
        for k in 1..=n {
            let v = 0x80 + k as u32;
            o = o.with_sub(
                SubObject::new(
                    k as u8,
                    alloc::format!("Emergency consumer {k}"),
                    DataType::Unsigned32,
                    Access::Rw,
                    Value::U32(v),
                )
                .hooked(),
            );
            c.set(k - 1, v);
        }
        od.insert(o);
        c
    }

    /// Configure entry `sub` (1-based) directly, as a master does for itself
    /// (no OD write; use the SDO path for a remote device).
    pub fn set_entry(&mut self, sub: u8, cob_id: u32) {
        if (1..=self.n).contains(&(sub as usize)) {
            self.set(sub as usize - 1, cob_id);
        }
    }

    fn set(&mut self, i: usize, v: u32) {
        self.entries[i] = v;
        self.ids[i] = if v & COB_ID_INVALID != 0 { None } else { can_id_of(v) };
        self.std_mask = [0; 32];
        self.any_extended = false;
        for id in self.ids[..self.n].iter().flatten() {
            match *id {
                CanId::Standard(v) => self.std_mask[v as usize >> 6] |= 1 << (v & 63),
                CanId::Extended(_) => self.any_extended = true,
            }
        }
    }

    /// A received frame: `Some` if it comes from a valid 1028h producer and
    /// decodes as an EMCY (see [`decode`]).
    #[inline]
    pub fn handle_frame(&self, frame: &Frame) -> Option<EmcyReceived> {
        let id = frame.id();
        let maybe = match id {
            CanId::Standard(v) => self.std_mask[(v as usize >> 6) & 31] & (1 << (v & 63)) != 0,
            CanId::Extended(_) => self.any_extended,
        };
        if !maybe {
            return None;
        }
        let i = self.ids[..self.n].iter().position(|x| *x == Some(id))?;
        let m = decode(frame)?;
        let node_id = match id {
            CanId::Standard(v @ 0x81..=0xFF) => Some((v - 0x80) as u8),
            _ => None,
        };
        Some(EmcyReceived {
            sub: i as u8 + 1,
            cob_id: id,
            node_id,
            code: m.code,
            register: m.register,
            data: m.data,
        })
    }

    /// The abort for a refused 1028h write: changing the CAN-ID of a valid
    /// entry, reserved bit 30, a bad or restricted CAN-ID → `0609 0030`
    /// (the 1014h COB-ID rules of CiA 301 §7.5.2 applied to 1028h).
    pub fn check_write(
        &self,
        od: &ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        if index != OD_EMCY_CONSUMER || sub == 0 {
            return Ok(());
        }
        let new = u32_of(data)?;
        let old = od.get_u32(index, sub).ok_or(SdoAbort::NO_SUB_INDEX)?;
        check_cob_id_write(old, new)
    }

    /// Re-read a 1028h entry after a write was stored.
    pub fn reconfigure(&mut self, od: &ObjectDictionary, index: u16, sub: u8) {
        if index == OD_EMCY_CONSUMER
            && (1..=self.n).contains(&(sub as usize))
            && let Some(v) = od.get_u32(index, sub)
        {
            self.set(sub as usize - 1, v);
        }
    }

    /// Re-read every entry (after restore or reset communication).
    pub fn reconfigure_all(&mut self, od: &ObjectDictionary) {
        for k in 1..=self.n {
            self.reconfigure(od, OD_EMCY_CONSUMER, k as u8);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_od::NoHooks;

    #[test]
    fn decode_shapes() {
        let f = Frame::new(0x081, &[0x10, 0x43, 0x09, 1, 2, 3, 4, 5]);
        let m = decode(&f).unwrap();
        assert_eq!((m.code, m.register, m.data, m.len), (0x4310, 0x09, [1, 2, 3, 4, 5], 8));
        assert!(!m.is_reset());
        assert_eq!(m.to_string(), "EMCY 4310 (Excess temperature drive) register 09 data 01 02 03 04 05");
        assert!(decode(&Frame::new(0x081, &[0, 0])).is_none());
        assert!(decode(&Frame::remote(0x081, 8)).is_none());
        let short = decode(&Frame::new(0x081, &[0, 0, 0])).unwrap();
        assert!(short.is_reset());
        assert_eq!(short.len, 3);
    }

    #[test]
    fn consumer_filters_and_reconfigures() {
        let mut od = ObjectDictionary::new();
        let mut c = EmcyConsumer::install(&mut od, 4);
        assert_eq!(od.get_u32(0x1028, 0), Some(4));
        let f = Frame::new(0x083, &[0x30, 0x81, 0x11, 0, 0, 0, 0, 0]);
        let r = c.handle_frame(&f).unwrap();
        assert_eq!((r.sub, r.node_id, r.code, r.register), (3, Some(3), 0x8130, 0x11));
        assert!(c.handle_frame(&Frame::new(0x085, &[0; 8])).is_none(), "no entry for node 5");
        // Move entry 3 to a 29-bit id: invalidate first, then change.
        let h = &mut NoHooks;
        assert_eq!(
            c.check_write(&od, 0x1028, 3, &0x2000_1234u32.to_le_bytes()),
            Err(SdoAbort::INVALID_VALUE)
        );
        for v in [0x8000_0083u32, 0xA000_1234, 0x2000_1234] {
            c.check_write(&od, 0x1028, 3, &v.to_le_bytes()).unwrap();
            od.write(h, 0x1028, 3, &v.to_le_bytes()).unwrap();
            c.reconfigure(&od, 0x1028, 3);
        }
        assert!(c.handle_frame(&f).is_none());
        let x = Frame::try_new(CanId::Extended(0x1234), &[0, 0, 0, 0, 0, 0, 0, 0]).unwrap();
        let r = c.handle_frame(&x).unwrap();
        assert_eq!((r.sub, r.node_id, r.code), (3, None, 0));
        assert_eq!(c.check_write(&od, 0x1028, 9, &[0; 4]), Err(SdoAbort::NO_SUB_INDEX));
        assert_eq!(c.check_write(&od, 0x1028, 1, &[0; 2]), Err(SdoAbort::DATA_TOO_SHORT));
    }
}
