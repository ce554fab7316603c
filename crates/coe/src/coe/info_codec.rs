//! The SDO Information wire format (ETG.1000.6 §5.6.3), both directions:
//! the server in `info.rs` decodes requests and encodes answers with it,
//! a master (`drivebus_ethercat::master`) encodes requests and decodes
//! answers with it.
//!
//! Every SDO Information mailbox is the CoE header (service 8), a 4-byte
//! info header (opcode bits 0-6, "incomplete" bit 7, a reserved byte,
//! "fragments left" as UNSIGNED16; §5.6.3.2) and the service data. The
//! `body` of every function here is the mailbox's service data: the CoE
//! header first, as many bytes as the mailbox header's length says.

use crate::mailbox::Put;
use alloc::string::String;
use alloc::vec::Vec;

/// CoE header plus info header, in front of every service's data.
pub const HEADER_LEN: usize = 6;

/// CoE header of SDO Information (service 8, number 0).
pub const COE_SDO_INFO: [u8; 2] = [0x00, 0x80];

/// Opcodes (§5.6.3.2).
pub mod opcode {
    /// Get OD List request.
    pub const OD_LIST_REQ: u8 = 0x01;
    /// Get OD List response.
    pub const OD_LIST_RES: u8 = 0x02;
    /// Get Object Description request.
    pub const OBJ_DESC_REQ: u8 = 0x03;
    /// Get Object Description response.
    pub const OBJ_DESC_RES: u8 = 0x04;
    /// Get Entry Description request.
    pub const ENTRY_DESC_REQ: u8 = 0x05;
    /// Get Entry Description response.
    pub const ENTRY_DESC_RES: u8 = 0x06;
    /// SDO Info Error request (an abort code, in both directions).
    pub const INFO_ERROR: u8 = 0x07;
}

/// The "more fragments follow" bit of the opcode byte.
pub(crate) const INCOMPLETE: u8 = 0x80;

/// Value-info bits of Get Entry Description: which optional fields follow
/// the fixed ones (§5.6.3, Get Entry Description).
pub mod value_info {
    /// Unit type (UNSIGNED16).
    pub const UNIT_TYPE: u8 = 0x08;
    /// Default value.
    pub const DEFAULT: u8 = 0x10;
    /// Minimum value.
    pub const MINIMUM: u8 = 0x20;
    /// Maximum value.
    pub const MAXIMUM: u8 = 0x40;
    /// Bits 0-2 (RxPDO, TxPDO, backup, settings flags asked for) carry no
    /// field in the response.
    pub const ECHO: u8 = 0x07;
}

/// CoE header and info header of a mailbox with `opcode`.
pub(crate) fn put_header(w: &mut Vec<u8>, opcode: u8, incomplete: bool, fragments_left: u16) {
    w.extend_from_slice(&COE_SDO_INFO);
    w.push(opcode | if incomplete { INCOMPLETE } else { 0 });
    w.push(0);
    w.put_u16(fragments_left);
}

/// A request a master sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InfoRequest {
    /// Get OD List of a list type (`list_type`).
    OdList(u16),
    /// Get Object Description of an index.
    ObjectDescription(u16),
    /// Get Entry Description, asking for the optional fields in `value_info`.
    EntryDescription {
        /// Object.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Optional fields asked for ([`value_info`] bits).
        value_info: u8,
    },
    /// SDO Info Error request: the master ends a fragmented answer.
    Error,
    /// An opcode that is no request.
    Other(u8),
}

impl InfoRequest {
    /// From a request's service data (CoE header first); `None` when it is
    /// shorter than its opcode needs.
    pub fn decode(body: &[u8]) -> Option<InfoRequest> {
        let op = body.get(2)? & 0x7F;
        if body.len() < HEADER_LEN {
            return None;
        }
        let arg = |at: usize| Some(u16::from_le_bytes([*body.get(at)?, *body.get(at + 1)?]));
        Some(match op {
            opcode::OD_LIST_REQ => InfoRequest::OdList(arg(6)?),
            opcode::OBJ_DESC_REQ => InfoRequest::ObjectDescription(arg(6)?),
            opcode::ENTRY_DESC_REQ => InfoRequest::EntryDescription {
                index: arg(6)?,
                sub: *body.get(8)?,
                value_info: *body.get(9)?,
            },
            opcode::INFO_ERROR => InfoRequest::Error,
            other => InfoRequest::Other(other),
        })
    }

    /// Appends the request's service data (CoE header first) to `w`.
    pub fn encode(&self, w: &mut Vec<u8>) {
        match *self {
            InfoRequest::OdList(list) => {
                put_header(w, opcode::OD_LIST_REQ, false, 0);
                w.put_u16(list);
            }
            InfoRequest::ObjectDescription(index) => {
                put_header(w, opcode::OBJ_DESC_REQ, false, 0);
                w.put_u16(index);
            }
            InfoRequest::EntryDescription { index, sub, value_info } => {
                put_header(w, opcode::ENTRY_DESC_REQ, false, 0);
                w.put_u16(index);
                w.extend_from_slice(&[sub, value_info]);
            }
            InfoRequest::Error => {
                put_header(w, opcode::INFO_ERROR, false, 0);
                w.put_u32(0);
            }
            InfoRequest::Other(op) => put_header(w, op & 0x7F, false, 0),
        }
    }
}

/// Appends `text`, cut so that `w` stays within `limit` bytes.
pub(crate) fn put_text(w: &mut Vec<u8>, text: &[u8], limit: usize) {
    let room = limit.saturating_sub(w.len());
    w.extend_from_slice(&text[..text.len().min(room)]);
}

/// Get Object Description response (§5.6.3, Get Object Description):
/// `B` holds the name, `&[u8]` borrowed from a mailbox or `Vec<u8>` kept
/// by a master ([`ObjectDescription::into_owned`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectDescription<B> {
    /// Object.
    pub index: u16,
    /// Data type index: of a VAR's value, of an ARRAY's elements, a
    /// RECORD's structure type (0 when it has none).
    pub data_type: u16,
    /// Highest sub-index.
    pub max_sub: u8,
    /// Object code: 7 VAR, 8 ARRAY, 9 RECORD.
    pub object_code: u8,
    /// Name (VISIBLE_STRING, not terminated).
    pub name: B,
}

impl<B: AsRef<[u8]>> ObjectDescription<B> {
    /// Appends the response's service data, the name cut so that `w`
    /// stays within `limit` bytes (the mailbox).
    pub fn encode(&self, w: &mut Vec<u8>, limit: usize) {
        put_header(w, opcode::OBJ_DESC_RES, false, 0);
        w.put_u16(self.index);
        w.put_u16(self.data_type);
        w.extend_from_slice(&[self.max_sub, self.object_code]);
        put_text(w, self.name.as_ref(), limit);
    }

    /// An ARRAY or RECORD (entries behind sub 0).
    pub fn compound(&self) -> bool {
        matches!(self.object_code, 8 | 9)
    }

    /// VAR, ARRAY or RECORD.
    pub fn code_name(&self) -> &'static str {
        match self.object_code {
            8 => "ARRAY",
            9 => "RECORD",
            7 => "VAR",
            _ => "unknown object code",
        }
    }

    /// The name as text ([`name_text`]).
    pub fn name_text(&self) -> String {
        name_text(self.name.as_ref())
    }

    /// The same description with its name copied out of the mailbox.
    pub fn into_owned(self) -> ObjectDescription<Vec<u8>> {
        let ObjectDescription { index, data_type, max_sub, object_code, name } = self;
        ObjectDescription { index, data_type, max_sub, object_code, name: name.as_ref().to_vec() }
    }
}

impl<'a> ObjectDescription<&'a [u8]> {
    /// From the data after the info header.
    fn decode(d: &'a [u8]) -> Option<ObjectDescription<&'a [u8]>> {
        Some(ObjectDescription {
            index: u16::from_le_bytes([*d.first()?, *d.get(1)?]),
            data_type: u16::from_le_bytes([*d.get(2)?, *d.get(3)?]),
            max_sub: *d.get(4)?,
            object_code: *d.get(5)?,
            name: d.get(6..)?,
        })
    }
}

/// Get Entry Description response (§5.6.3, Get Entry Description): `B`
/// holds the optional values and the name, as [`ObjectDescription`]'s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EntryDescription<B> {
    /// Object.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Which optional fields are given ([`value_info`] bits).
    pub value_info: u8,
    /// Data type index.
    pub data_type: u16,
    /// Length in bits.
    pub bit_length: u16,
    /// Object access bits (`access_bits`: read/write per state, PDO mapping).
    pub access: u16,
    /// The optional fields `value_info` announces, as sent (decoding only).
    pub values: B,
    /// Name (VISIBLE_STRING, not terminated).
    pub name: B,
}

impl<B: AsRef<[u8]>> EntryDescription<B> {
    /// Fixed fields after the info header.
    const FIXED: usize = 10;

    /// Appends the headers and the fixed fields; the optional fields
    /// `value_info` announces and then the name follow.
    pub(crate) fn encode_head(&self, w: &mut Vec<u8>) {
        put_header(w, opcode::ENTRY_DESC_RES, false, 0);
        w.put_u16(self.index);
        w.extend_from_slice(&[self.sub, self.value_info]);
        w.put_u16(self.data_type);
        w.put_u16(self.bit_length);
        w.put_u16(self.access);
    }

    /// `rw`, `ro`, `wo` or `none` from the access bits (bits 0-2 readable
    /// in PRE-OP/SAFE-OP/OP, 3-5 writable).
    pub fn access_text(&self) -> &'static str {
        match (self.access & 0x07 != 0, self.access & 0x38 != 0) {
            (true, true) => "rw",
            (true, false) => "ro",
            (false, true) => "wo",
            (false, false) => "none",
        }
    }

    /// The name as text ([`name_text`]).
    pub fn name_text(&self) -> String {
        name_text(self.name.as_ref())
    }

    /// The same description with its values and name copied out of the
    /// mailbox.
    pub fn into_owned(self) -> EntryDescription<Vec<u8>> {
        let EntryDescription { index, sub, value_info, data_type, bit_length, access, values, name } = self;
        EntryDescription {
            index,
            sub,
            value_info,
            data_type,
            bit_length,
            access,
            values: values.as_ref().to_vec(),
            name: name.as_ref().to_vec(),
        }
    }
}

impl<'a> EntryDescription<&'a [u8]> {
    /// From the data after the info header: the optional fields take 2
    /// bytes (unit type) and the entry's length in bytes (each value).
    fn decode(d: &'a [u8]) -> Option<EntryDescription<&'a [u8]>> {
        let u = |at: usize| Some(u16::from_le_bytes([*d.get(at)?, *d.get(at + 1)?]));
        let value_info = *d.get(3)?;
        let bit_length = u(6)?;
        let value_len = usize::from(bit_length).div_ceil(8);
        let optional = [
            (value_info::UNIT_TYPE, 2),
            (value_info::DEFAULT, value_len),
            (value_info::MINIMUM, value_len),
            (value_info::MAXIMUM, value_len),
        ]
        .iter()
        .filter(|(bit, _)| value_info & bit != 0)
        .map(|(_, n)| n)
        .sum::<usize>();
        let names_at = Self::FIXED.checked_add(optional)?;
        Some(EntryDescription {
            index: u(0)?,
            sub: *d.get(2)?,
            value_info,
            data_type: u(4)?,
            bit_length,
            access: u(8)?,
            values: d.get(Self::FIXED..names_at)?,
            name: d.get(names_at..)?,
        })
    }
}

/// An SDO Information answer as a master reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InfoResponse<'a> {
    /// A fragment of Get OD List: the data (the first fragment starts
    /// with the list type), whether more follow, how many.
    OdList {
        /// List type (first fragment) and indices, little-endian.
        data: &'a [u8],
        /// More fragments follow.
        incomplete: bool,
        /// Fragments still to come.
        fragments_left: u16,
    },
    /// Get Object Description.
    ObjectDescription(ObjectDescription<&'a [u8]>),
    /// Get Entry Description.
    EntryDescription(EntryDescription<&'a [u8]>),
    /// SDO Info Error: an abort code (`0602 0000` no object, ...).
    Error(u32),
}

impl<'a> InfoResponse<'a> {
    /// From an answer's service data (CoE header first); `None` when it is
    /// no SDO Information answer or too short for its opcode.
    pub fn decode(body: &'a [u8]) -> Option<InfoResponse<'a>> {
        if body.len() < HEADER_LEN || body[1] >> 4 != COE_SDO_INFO[1] >> 4 {
            return None;
        }
        let d = &body[HEADER_LEN..];
        Some(match body[2] & 0x7F {
            opcode::OD_LIST_RES => InfoResponse::OdList {
                data: d,
                incomplete: body[2] & INCOMPLETE != 0,
                fragments_left: u16::from_le_bytes([body[4], body[5]]),
            },
            opcode::OBJ_DESC_RES => InfoResponse::ObjectDescription(ObjectDescription::decode(d)?),
            opcode::ENTRY_DESC_RES => InfoResponse::EntryDescription(EntryDescription::decode(d)?),
            opcode::INFO_ERROR => InfoResponse::Error(u32::from_le_bytes(*d.first_chunk()?)),
            _ => return None,
        })
    }
}

/// A VISIBLE_STRING name as text: invalid UTF-8 replaced, a terminating
/// NUL some slaves send and surrounding blanks dropped.
pub fn name_text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).trim_end_matches('\0').trim().into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_round_trip() {
        for r in [
            InfoRequest::OdList(1),
            InfoRequest::ObjectDescription(0x1C13),
            InfoRequest::EntryDescription { index: 0x1018, sub: 2, value_info: 0x10 },
            InfoRequest::Error,
        ] {
            let mut w = Vec::new();
            r.encode(&mut w);
            assert_eq!(InfoRequest::decode(&w), Some(r), "{w:02X?}");
        }
        let mut w = Vec::new();
        InfoRequest::EntryDescription { index: 0x1C13, sub: 1, value_info: 0 }.encode(&mut w);
        assert_eq!(w, [0x00, 0x80, 0x05, 0, 0, 0, 0x13, 0x1C, 0x01, 0x00]);
        assert_eq!(InfoRequest::decode(&w[..9]), None, "too short for an entry description");
        assert_eq!(InfoRequest::decode(&[0x00, 0x80, 0x03, 0, 0, 0]), None);
    }

    #[test]
    fn descriptions_decode_what_the_server_encodes() {
        let mut w = Vec::new();
        let o = ObjectDescription {
            index: 0x1C13,
            data_type: 6,
            max_sub: 4,
            object_code: 8,
            name: &b"TxPDO assign"[..],
        };
        o.encode(&mut w, 64);
        assert_eq!(InfoResponse::decode(&w), Some(InfoResponse::ObjectDescription(o)));
        // The name is cut to the mailbox.
        w.clear();
        o.encode(&mut w, 16);
        assert_eq!(w.len(), 16);
        let e = EntryDescription {
            index: 0x6040,
            sub: 0,
            value_info: value_info::DEFAULT | value_info::UNIT_TYPE,
            data_type: 6,
            bit_length: 16,
            access: 0x003F,
            values: &[][..],
            name: &b""[..],
        };
        w.clear();
        e.encode_head(&mut w);
        w.extend_from_slice(&[0x00, 0x00, 0x34, 0x12]);
        w.extend_from_slice(b"Controlword");
        let Some(InfoResponse::EntryDescription(d)) = InfoResponse::decode(&w) else { panic!("{w:02X?}") };
        assert_eq!((d.index, d.sub, d.data_type, d.bit_length, d.access), (0x6040, 0, 6, 16, 0x3F));
        assert_eq!((d.values, d.name), (&[0x00, 0x00, 0x34, 0x12][..], &b"Controlword"[..]));
        // An SDO Info error; anything not SDO Information is no answer.
        let err = [0x00, 0x80, 0x07, 0, 0, 0, 0x00, 0x00, 0x02, 0x06];
        assert_eq!(InfoResponse::decode(&err), Some(InfoResponse::Error(0x0602_0000)));
        assert_eq!(InfoResponse::decode(&[0x00, 0x30, 0x04, 0, 0, 0, 0, 0]), None);
        assert_eq!(InfoResponse::decode(&[0x00, 0x80, 0x06, 0, 0, 0, 1]), None);
    }

    #[test]
    fn a_master_keeps_a_description_as_sent_and_reads_its_name() {
        let mut w = Vec::new();
        let o = ObjectDescription {
            index: 0x1008,
            data_type: 9,
            max_sub: 0,
            object_code: 7,
            name: &b"Name\0"[..],
        };
        o.encode(&mut w, 64);
        let Some(InfoResponse::ObjectDescription(d)) = InfoResponse::decode(&w) else { panic!("{w:02X?}") };
        let kept = d.into_owned();
        assert_eq!(kept.name, b"Name\0");
        assert_eq!((kept.name_text().as_str(), kept.code_name(), kept.compound()), ("Name", "VAR", false));
        let e = EntryDescription {
            index: 0x1018,
            sub: 1,
            value_info: 0,
            data_type: 7,
            bit_length: 32,
            access: 0x0007,
            values: &[][..],
            name: &b" Vendor ID "[..],
        };
        let kept = e.into_owned();
        assert_eq!((kept.name_text().as_str(), kept.access_text()), ("Vendor ID", "ro"));
        assert_eq!(EntryDescription { access: 0x38, ..kept.clone() }.access_text(), "wo");
        assert_eq!(name_text(&[0xFF, b'x']), "\u{FFFD}x", "invalid UTF-8 is replaced, not refused");
    }
}
