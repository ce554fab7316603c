//! SDO Information (ETG.1000.6 §5.6.3): object lists, object and entry
//! descriptions, and the SDO Info error.
//!
//! The wire format is `info_codec.rs`. An OD list longer than the mailbox
//! is sent in fragments: the list type and the indices are one byte
//! stream cut at even offsets, the first fragment carrying the list type
//! (as SOEM's `ecx_readODlist` reads it). Fragments after the first are
//! produced one at a time, when the server is asked for its next response.

use super::Out;
use super::info_codec::{
    EntryDescription, HEADER_LEN, InfoRequest, ObjectDescription, opcode, put_header, put_text, value_info,
};
use crate::access::{ObjectAccess, access_bits};
use crate::mailbox::{HEADER_LEN as MBX_HEADER_LEN, MailboxErrorCode, MailboxType, Put};
use alloc::vec::Vec;
use drivebus_od::{Object, ObjectCode, SdoAbort, SubObject};

/// OD list types of Get OD List (§5.6.3.3.1).
pub mod list_type {
    /// The number of objects in each of the lists 1..=5.
    pub const COUNTS: u16 = 0;
    /// Every object.
    pub const ALL: u16 = 1;
    /// Objects with an RxPDO-mappable entry.
    pub const RXPDO: u16 = 2;
    /// Objects with a TxPDO-mappable entry.
    pub const TXPDO: u16 = 3;
    /// Objects stored for device replacement.
    pub const BACKUP: u16 = 4;
    /// Objects usable as startup parameters.
    pub const SETTINGS: u16 = 5;
}

/// Remaining fragments of an OD list answer.
#[derive(Clone, Debug, Default)]
pub(crate) struct Fragments {
    /// List type then indices, little-endian; capacity reused.
    data: Vec<u8>,
    pos: usize,
    active: bool,
}

impl Fragments {
    pub(crate) fn pending(&self) -> bool {
        self.active
    }

    pub(crate) fn cancel(&mut self) {
        self.active = false;
    }

    /// Queue the next fragment if one is waiting.
    pub(crate) fn next(&mut self, out: &mut Out<'_>) -> bool {
        if !self.active || !out.q.has_room() {
            return false;
        }
        // Fragments are cut at even offsets so no index is split.
        let chunk = (out.cap.saturating_sub(HEADER_LEN) & !1).max(2);
        let rest = self.data.get(self.pos..).unwrap_or(&[]);
        let k = rest.len().min(chunk);
        let remaining = rest.len() - k;
        let left = u16::try_from(remaining.div_ceil(chunk)).unwrap_or(u16::MAX);
        let w = out.q.begin();
        put_header(w, opcode::OD_LIST_RES, remaining > 0, left);
        w.extend_from_slice(&rest[..k]);
        out.q.commit(MailboxType::Coe);
        self.pos += k;
        self.active = remaining > 0;
        true
    }

    /// One SDO Information request (`body.len() >= HEADER_LEN`).
    pub(crate) fn handle<A: ObjectAccess + ?Sized>(&mut self, body: &[u8], objects: &A, out: &mut Out<'_>) {
        match InfoRequest::decode(body) {
            None => {
                out.q.push_error(MailboxErrorCode::SIZE_TOO_SHORT);
            }
            Some(InfoRequest::OdList(list)) => self.od_list(list, objects, out),
            Some(InfoRequest::ObjectDescription(index)) => object_description(index, objects, out),
            Some(InfoRequest::EntryDescription { index, sub, value_info }) => {
                entry_description(index, sub, value_info, objects, out)
            }
            // The master ends a fragmented answer with an Info error request;
            // the caller has already cancelled it. Nothing is answered.
            Some(InfoRequest::Error) => {}
            Some(InfoRequest::Other(_)) => info_error(out, SdoAbort::INVALID_COMMAND),
        }
    }

    /// Get OD List: counts (type 0) or the indices of one list.
    fn od_list<A: ObjectAccess + ?Sized>(&mut self, list: u16, objects: &A, out: &mut Out<'_>) {
        if list > list_type::SETTINGS {
            return info_error(out, SdoAbort::UNSUPPORTED_ACCESS);
        }
        let od = objects.dictionary();
        self.data.clear();
        self.data.put_u16(list);
        if list == list_type::COUNTS {
            for l in list_type::ALL..=list_type::SETTINGS {
                let n = od.objects().iter().filter(|o| in_list(l, o, objects)).count();
                self.data.put_u16(u16::try_from(n).unwrap_or(u16::MAX));
            }
        } else {
            // Reserved here, at the request: the fragments do not allocate.
            let n = od.objects().len();
            if self.data.try_reserve(2 * n).is_err() {
                return info_error(out, SdoAbort::OUT_OF_MEMORY);
            }
            for o in od.objects().iter().filter(|o| in_list(list, o, objects)) {
                self.data.put_u16(o.index);
            }
        }
        self.pos = 0;
        self.active = true;
        self.next(out);
    }
}

/// Does object `o` belong to OD list `list` (1..=5)?
fn in_list<A: ObjectAccess + ?Sized>(list: u16, o: &Object, objects: &A) -> bool {
    let bit = match list {
        list_type::ALL => return true,
        list_type::RXPDO => access_bits::RXPDO,
        list_type::TXPDO => access_bits::TXPDO,
        list_type::BACKUP => access_bits::BACKUP,
        _ => access_bits::SETTINGS,
    };
    o.subs().iter().any(|s| objects.object_access(o.index, s.sub) & bit != 0)
}

/// Answer with an SDO Info error request carrying an abort code (§5.6.3).
fn info_error(out: &mut Out<'_>, code: SdoAbort) {
    let w = out.q.begin();
    put_header(w, opcode::INFO_ERROR, false, 0);
    w.put_u32(code.0);
    out.q.commit(MailboxType::Coe);
}

/// The ETG object code: 7 VAR, 8 ARRAY, 9 RECORD (a DOMAIN is a VAR).
fn object_code(o: &Object) -> u8 {
    match o.code {
        ObjectCode::Array => 8,
        ObjectCode::Record | ObjectCode::DefStruct => 9,
        _ => 7,
    }
}

/// The data type an object description names: the value's type for a VAR,
/// the element type of an ARRAY, and for a RECORD the CiA 301 complex type
/// of the standard records (0020h PDO communication, 0021h PDO mapping,
/// 0022h SDO parameter, 0023h identity), else 0.
fn object_data_type(o: &Object) -> u16 {
    match o.code {
        ObjectCode::Array => {
            o.subs().iter().find(|s| s.sub >= 1).or(o.subs().first()).map_or(0, |s| s.data_type as u16)
        }
        ObjectCode::Record | ObjectCode::DefStruct => match o.index {
            0x1018 => 0x0023,
            0x1200..=0x12FF => 0x0022,
            0x1400..=0x15FF | 0x1800..=0x19FF => 0x0020,
            0x1600..=0x17FF | 0x1A00..=0x1BFF => 0x0021,
            _ => 0,
        },
        _ => o.get(0).map_or(0, |s| s.data_type as u16),
    }
}

/// Get Object Description: index, data type, highest sub-index, object
/// code, name (§5.6.3, Get Object Description).
fn object_description<A: ObjectAccess + ?Sized>(index: u16, objects: &A, out: &mut Out<'_>) {
    let Some(o) = objects.dictionary().object(index) else {
        return info_error(out, SdoAbort::NO_OBJECT);
    };
    let max_sub = match o.code {
        ObjectCode::Array | ObjectCode::Record | ObjectCode::DefStruct => {
            o.subs().last().map_or(0, |s| s.sub)
        }
        _ => 0,
    };
    let limit = MBX_HEADER_LEN + out.cap;
    let d = ObjectDescription {
        index,
        data_type: object_data_type(o),
        max_sub,
        object_code: object_code(o),
        name: o.name.as_bytes(),
    };
    d.encode(out.q.begin(), limit);
    out.q.commit(MailboxType::Coe);
}

/// Length in bits an entry description states: the PDO size of fixed
/// types; for strings and domains the bound, else the current length.
fn bit_length(s: &SubObject) -> u16 {
    let bits = s.bit_len().map_or_else(|| 8 * s.max_len.unwrap_or(s.bytes().len()), |b| b as usize);
    u16::try_from(bits).unwrap_or(u16::MAX)
}

/// Get Entry Description: index, sub-index, value info, data type, bit
/// length, object access, the optional fields asked for and available
/// (default, minimum, maximum; no unit type), then the name (§5.6.3).
fn entry_description<A: ObjectAccess + ?Sized>(
    index: u16,
    sub: u8,
    asked: u8,
    objects: &A,
    out: &mut Out<'_>,
) {
    let od = objects.dictionary();
    let s = match od.find(index, sub) {
        Ok(r) => od.entry(r),
        Err(e) => return info_error(out, e),
    };
    let access = objects.object_access(index, sub);
    let limit = MBX_HEADER_LEN + out.cap;
    let w = out.q.begin();
    // The value-info byte, set once the fields that fit are known.
    let vi_at = w.len() + HEADER_LEN + 3;
    let head = EntryDescription {
        index,
        sub,
        value_info: 0,
        data_type: s.data_type as u16,
        bit_length: bit_length(s),
        access,
        values: &[][..],
        name: &[][..],
    };
    head.encode_head(w);
    let mut given = asked & value_info::ECHO;
    let fields = [
        (value_info::DEFAULT, Some(s.default.as_slice())),
        (value_info::MINIMUM, s.low_limit.as_deref()),
        (value_info::MAXIMUM, s.high_limit.as_deref()),
    ];
    for (bit, value) in fields {
        if let Some(v) = value
            && asked & bit != 0
            && w.len() + v.len() <= limit
        {
            w.extend_from_slice(v);
            given |= bit;
        }
    }
    w[vi_at] = given;
    put_text(w, s.name.as_bytes(), limit);
    out.q.commit(MailboxType::Coe);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mailbox::ResponseQueue;
    use drivebus_od::{Access, DataType, NoHooks, ObjectDictionary, SubObject, Value};

    fn od(n: u16) -> (ObjectDictionary, NoHooks) {
        let mut od = ObjectDictionary::new();
        for i in 0..n {
            od.insert(Object::var(0x2000 + i, "x", DataType::Unsigned8, Access::Rw, Value::U8(0)));
        }
        (od, NoHooks)
    }

    fn drain(q: &mut ResponseQueue) -> Vec<Vec<u8>> {
        let mut all = Vec::new();
        let mut m = Vec::new();
        while q.pop_into(&mut m) {
            all.push(m.clone());
        }
        all
    }

    #[test]
    fn od_list_is_cut_at_even_offsets_with_fragments_counting_down() {
        // 32-byte mailbox: 26 bytes of service data, 20 of them list.
        let dev = od(15);
        let mut q = ResponseQueue::new(4, 32);
        let mut f = Fragments::default();
        f.handle(&[0x00, 0x80, 0x01, 0, 0, 0, 0x01, 0x00], &dev, &mut Out { q: &mut q, cap: 26 });
        while f.next(&mut Out { q: &mut q, cap: 26 }) {}
        let frags = drain(&mut q);
        // 2 + 30 bytes: 20 + 12.
        assert_eq!(frags.len(), 2);
        assert_eq!(frags[0][6..12], [0x00, 0x80, 0x82, 0x00, 0x01, 0x00]);
        assert_eq!(frags[0][12..14], [0x01, 0x00], "list type first");
        assert_eq!(frags[0].len(), 6 + 6 + 20);
        assert_eq!(frags[1][6..12], [0x00, 0x80, 0x02, 0x00, 0x00, 0x00]);
        assert_eq!(frags[1][12..], [0x09, 0x20, 0x0A, 0x20, 0x0B, 0x20, 0x0C, 0x20, 0x0D, 0x20, 0x0E, 0x20]);
        assert!(!f.pending());
    }

    #[test]
    fn unknown_list_type_and_opcode_are_info_errors() {
        let dev = od(1);
        let mut q = ResponseQueue::new(4, 32);
        let mut f = Fragments::default();
        f.handle(&[0x00, 0x80, 0x01, 0, 0, 0, 0x06, 0x00], &dev, &mut Out { q: &mut q, cap: 26 });
        f.handle(&[0x00, 0x80, 0x09, 0, 0, 0], &dev, &mut Out { q: &mut q, cap: 26 });
        let r = drain(&mut q);
        assert_eq!(r[0][6..], [0x00, 0x80, 0x07, 0, 0, 0, 0x00, 0x00, 0x01, 0x06]);
        assert_eq!(r[1][6..], [0x00, 0x80, 0x07, 0, 0, 0, 0x01, 0x00, 0x04, 0x05]);
    }

    #[test]
    fn descriptions_fit_the_mailbox() {
        let mut dev = od(0);
        let long: String = core::iter::repeat_n('n', 40).collect();
        dev.0.insert(Object::var(
            0x2100,
            long.clone(),
            DataType::VisibleString,
            Access::Rw,
            Value::Str(long.clone()),
        ));
        let mut q = ResponseQueue::new(4, 32);
        object_description(0x2100, &dev, &mut Out { q: &mut q, cap: 26 });
        // Default asked but 40 bytes do not fit: not given, name cut.
        entry_description(0x2100, 0, 0x10, &dev, &mut Out { q: &mut q, cap: 26 });
        let r = drain(&mut q);
        assert_eq!(r[0].len(), 32);
        assert_eq!(r[0][12..18], [0x00, 0x21, 0x09, 0x00, 0x00, 0x07]);
        assert_eq!(r[1].len(), 32);
        assert_eq!(r[1][15], 0x00, "no optional field given");
        assert_eq!(u16::from_le_bytes([r[1][18], r[1][19]]), 8 * 40);
    }

    #[test]
    fn object_data_types() {
        let rec = |i| Object::record(i, "r");
        assert_eq!(object_data_type(&rec(0x1018)), 0x23);
        assert_eq!(object_data_type(&rec(0x1200)), 0x22);
        assert_eq!(object_data_type(&rec(0x1800)), 0x20);
        assert_eq!(object_data_type(&rec(0x1A00)), 0x21);
        assert_eq!(object_data_type(&rec(0x2000)), 0);
        let arr = Object::array(0x2001, "a", DataType::Integer16, Access::Rw, 2, Value::I16(0));
        assert_eq!((object_data_type(&arr), object_code(&arr)), (0x03, 8));
        let s =
            SubObject::new(0, "s", DataType::OctetString, Access::Rw, Value::Bytes(vec![0; 3])).max_len(10);
        assert_eq!(bit_length(&s), 80);
    }
}
