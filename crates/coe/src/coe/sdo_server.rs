//! SDO initiate services over CoE: expedited and normal upload and download,
//! the start of segmented transfers, and aborts (ETG.1000.6 §5.6.2).
//!
//! Layout of every SDO mailbox after the CoE header: command byte (size
//! indicator bit 0, expedited bit 1, unused-byte count bits 2-3, complete
//! access bit 4, command specifier bits 5-7), index (LE), sub-index, then 4
//! bytes: the expedited data or the complete size of a normal transfer,
//! whose data follows (§5.6.2.1.1).

use super::{CoeServer, Mux, Out, Transfer, complete};
use crate::access::ObjectAccess;
use crate::mailbox::{HEADER_LEN, MailboxType, Put};
use drivebus_base::Instant;
use drivebus_od::SdoAbort;
use drivebus_sdo::wire::{
    CCS_DOWNLOAD_SEGMENT, CCS_INITIATE_DOWNLOAD, CCS_INITIATE_UPLOAD, CCS_UPLOAD_SEGMENT, CS_ABORT,
    EXPEDITED, SCS_INITIATE_DOWNLOAD, SCS_INITIATE_UPLOAD, SIZE_INDICATED, expedited, expedited_len, scs,
};

/// Service data of an SDO mailbox without normal-transfer data: CoE header,
/// command, index, sub-index, 4 data bytes. Also the shortest valid request
/// (an upload segment request is padded to it).
pub(crate) const SDO_LEN: usize = 10;

/// CoE header of an SDO response (service 3, number 0).
pub(crate) const COE_SDO_RESPONSE: [u8; 2] = [0x00, 0x30];
/// CoE header of an SDO request (service 2): an abort is an SDO request in
/// both directions (ETG.1000.6 §5.6.2.7.1 Table 40).
const COE_SDO_REQUEST: [u8; 2] = [0x00, 0x20];

const CA_BIT: u8 = 0x10;

impl Mux {
    /// Index LSB, MSB, sub-index as the response echoes them.
    fn bytes(self) -> [u8; 3] {
        let i = self.index.to_le_bytes();
        [i[0], i[1], self.sub]
    }
    fn ca_bit(self) -> u8 {
        if self.ca { CA_BIT } else { 0 }
    }
}

impl Transfer {
    fn mux(self) -> Option<Mux> {
        match self {
            Transfer::Idle => None,
            Transfer::Upload { mux, .. } | Transfer::Download { mux, .. } => Some(mux),
        }
    }
}

/// Answer with an abort (0x80, index, sub-index, code).
pub(crate) fn abort(out: &mut Out<'_>, mux: Mux, code: SdoAbort) {
    let w = out.q.begin();
    w.extend_from_slice(&COE_SDO_REQUEST);
    w.push(CS_ABORT);
    w.extend_from_slice(&mux.bytes());
    w.put_u32(code.0);
    out.q.commit(MailboxType::Coe);
}

/// Write a value, or a complete-access image, through the device.
pub(crate) fn store<A: ObjectAccess + ?Sized>(
    objects: &mut A,
    mux: Mux,
    data: &[u8],
) -> Result<(), SdoAbort> {
    if mux.ca {
        complete::download(objects, mux.index, mux.sub, data)
    } else {
        objects.write(mux.index, mux.sub, data)
    }
}

/// The initiate download response (0x60, echoing index, sub-index and CA),
/// or the abort.
fn download_response(out: &mut Out<'_>, mux: Mux, result: Result<(), SdoAbort>) {
    if let Err(e) = result {
        return abort(out, mux, e);
    }
    let w = out.q.begin();
    w.extend_from_slice(&COE_SDO_RESPONSE);
    w.push((SCS_INITIATE_DOWNLOAD << 5) | mux.ca_bit());
    w.extend_from_slice(&mux.bytes());
    w.put_u32(0);
    out.q.commit(MailboxType::Coe);
}

/// The initiate upload response for `value`: expedited for 1..=4 bytes
/// (§5.6.2.4), otherwise normal with the complete size and as much data as
/// the mailbox holds (§5.6.2.5). Returns how many bytes went out when the
/// rest must follow in segments.
fn upload_response(out: &mut Out<'_>, mux: Mux, value: &[u8]) -> Option<usize> {
    let n = value.len();
    let w = out.q.begin();
    w.extend_from_slice(&COE_SDO_RESPONSE);
    if (1..=4).contains(&n) {
        w.push(expedited(SCS_INITIATE_UPLOAD << 5, n) | mux.ca_bit());
        w.extend_from_slice(&mux.bytes());
        w.extend_from_slice(value);
        w.resize(HEADER_LEN + SDO_LEN, 0);
        out.q.commit(MailboxType::Coe);
        return None;
    }
    w.push((SCS_INITIATE_UPLOAD << 5) | SIZE_INDICATED | mux.ca_bit());
    w.extend_from_slice(&mux.bytes());
    // Callers refuse values beyond u32 first.
    w.put_u32(n as u32);
    let k = n.min(out.cap.saturating_sub(SDO_LEN));
    w.extend_from_slice(&value[..k]);
    out.q.commit(MailboxType::Coe);
    (k < n).then_some(k)
}

impl CoeServer {
    /// One SDO request (`body.len() >= SDO_LEN`, checked by the caller).
    pub(super) fn sdo_request<A: ObjectAccess + ?Sized>(
        &mut self,
        body: &[u8],
        now: Instant,
        objects: &mut A,
        out: &mut Out<'_>,
    ) {
        let cmd = body[2];
        let req = Mux { index: u16::from_le_bytes([body[3], body[4]]), sub: body[5], ca: cmd & CA_BIT != 0 };
        const DOWNLOAD_SEGMENT: u8 = CCS_DOWNLOAD_SEGMENT >> 5;
        const INITIATE_DOWNLOAD: u8 = CCS_INITIATE_DOWNLOAD >> 5;
        const INITIATE_UPLOAD: u8 = CCS_INITIATE_UPLOAD >> 5;
        const UPLOAD_SEGMENT: u8 = CCS_UPLOAD_SEGMENT >> 5;
        const ABORT: u8 = CS_ABORT >> 5;
        match (scs(cmd), self.transfer) {
            (INITIATE_DOWNLOAD, _) => {
                self.transfer = Transfer::Idle;
                self.initiate_download(body, req, now, objects, out);
            }
            (INITIATE_UPLOAD, _) => {
                self.transfer = Transfer::Idle;
                self.initiate_upload(req, now, objects, out);
            }
            (DOWNLOAD_SEGMENT, Transfer::Download { mux, total, toggle }) => {
                self.download_segment(body, mux, total, toggle, now, objects, out);
            }
            (UPLOAD_SEGMENT, Transfer::Upload { mux, pos, toggle }) => {
                self.upload_segment(cmd, mux, pos, toggle, now, out)
            }
            // An abort from the master ends the transfer; it is not answered.
            (ABORT, _) => self.transfer = Transfer::Idle,
            // Block transfer does not exist in CoE: these bytes look like an
            // initiate, so the abort echoes their index and sub-index.
            (5..=7, _) => {
                self.transfer = Transfer::Idle;
                abort(out, Mux { ca: false, ..req }, SdoAbort::INVALID_COMMAND);
            }
            // A segment that belongs to no transfer of its kind.
            (_, t) => {
                self.transfer = Transfer::Idle;
                abort(out, t.mux().unwrap_or(Mux::NONE), SdoAbort::INVALID_COMMAND);
            }
        }
    }

    fn initiate_upload<A: ObjectAccess + ?Sized>(
        &mut self,
        mux: Mux,
        now: Instant,
        objects: &mut A,
        out: &mut Out<'_>,
    ) {
        let segmented_from = if mux.ca {
            if !self.cfg.complete_access {
                return abort(out, mux, SdoAbort::UNSUPPORTED_ACCESS);
            }
            if let Err(e) = complete::upload(objects, mux.index, mux.sub, &mut self.buf) {
                return abort(out, mux, e);
            }
            if u32::try_from(self.buf.len()).is_err() {
                return abort(out, mux, SdoAbort::OUT_OF_MEMORY);
            }
            upload_response(out, mux, &self.buf)
        } else {
            let value = match objects.read(mux.index, mux.sub) {
                Ok(v) => v,
                Err(e) => return abort(out, mux, e),
            };
            if u32::try_from(value.len()).is_err() {
                return abort(out, mux, SdoAbort::OUT_OF_MEMORY);
            }
            if value.len() > 4 && value.len() + SDO_LEN > out.cap {
                // Snapshot the value: it may change while the segments go out.
                self.buf.clear();
                if self.buf.try_reserve(value.len()).is_err() {
                    return abort(out, mux, SdoAbort::OUT_OF_MEMORY);
                }
                self.buf.extend_from_slice(value);
                upload_response(out, mux, &self.buf)
            } else {
                upload_response(out, mux, value)
            }
        };
        if let Some(pos) = segmented_from {
            self.transfer = Transfer::Upload { mux, pos, toggle: false };
            self.deadline = now + self.cfg.timeout;
        }
    }

    fn initiate_download<A: ObjectAccess + ?Sized>(
        &mut self,
        body: &[u8],
        mux: Mux,
        now: Instant,
        objects: &mut A,
        out: &mut Out<'_>,
    ) {
        let cmd = body[2];
        if mux.ca && !self.cfg.complete_access {
            return abort(out, mux, SdoAbort::UNSUPPORTED_ACCESS);
        }
        if cmd & EXPEDITED != 0 {
            // Expedited (§5.6.2.1): the data is in the 4 bytes; without the
            // size indicator the object's own size says how many count.
            let len = expedited_len(cmd).unwrap_or_else(|| unsized_len(objects, mux));
            let result = store(objects, mux, &body[6..6 + len]);
            return download_response(out, mux, result);
        }
        // Normal (§5.6.2.2): complete size, then as much data as fits.
        let total = u32::from_le_bytes([body[6], body[7], body[8], body[9]]) as usize;
        let here = &body[SDO_LEN..];
        if here.len() > total {
            return abort(out, mux, SdoAbort::TYPE_MISMATCH);
        }
        if here.len() == total {
            let result = store(objects, mux, here);
            return download_response(out, mux, result);
        }
        if let Err(e) = self.prepare_download(objects, mux, total) {
            return abort(out, mux, e);
        }
        self.buf.extend_from_slice(here);
        self.transfer = Transfer::Download { mux, total, toggle: false };
        self.deadline = now + self.cfg.timeout;
        download_response(out, mux, Ok(()));
    }

    /// Refuse a segmented download before its data flows if the object
    /// cannot take `total` bytes, and reserve the buffer (the only
    /// allocation of the transfer).
    fn prepare_download<A: ObjectAccess + ?Sized>(
        &mut self,
        objects: &A,
        mux: Mux,
        total: usize,
    ) -> Result<(), SdoAbort> {
        if total > self.cfg.max_download {
            return Err(SdoAbort::OUT_OF_MEMORY);
        }
        if mux.ca {
            if total > complete::max_image_len(objects, mux.index, mux.sub)? {
                return Err(SdoAbort::DATA_TOO_LONG);
            }
        } else {
            let od = objects.dictionary();
            let e = od.entry(od.find(mux.index, mux.sub)?);
            if !e.access.writable() {
                return Err(SdoAbort::WRITE_READ_ONLY);
            }
            drivebus_od::check_len(e.data_type, total)?;
            if e.max_len.is_some_and(|m| total > m) {
                return Err(SdoAbort::DATA_TOO_LONG);
            }
        }
        self.buf.clear();
        self.buf.try_reserve(total).map_err(|_| SdoAbort::OUT_OF_MEMORY)
    }
}

/// Bytes an expedited download without size indication carries: the
/// entry's own size when it is 1..=4 bytes, else all 4.
fn unsized_len<A: ObjectAccess + ?Sized>(objects: &A, mux: Mux) -> usize {
    if mux.ca {
        return 4;
    }
    objects
        .dictionary()
        .get(mux.index, mux.sub)
        .and_then(|e| e.data_type.fixed_size())
        .filter(|n| (1..=4).contains(n))
        .unwrap_or(4)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mailbox::ResponseQueue;
    use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, Value};

    fn first(q: &mut ResponseQueue) -> alloc::vec::Vec<u8> {
        let mut m = alloc::vec::Vec::new();
        assert!(q.pop_into(&mut m));
        m
    }

    #[test]
    fn upload_response_kinds_by_size() {
        // 32-byte mailbox: 26 bytes of service data, 16 of data after the
        // normal initiate header.
        let mut q = ResponseQueue::new(6, 32);
        let mux = Mux { index: 0x2000, sub: 1, ca: false };
        let mut out = Out { q: &mut q, cap: 26 };
        assert_eq!(upload_response(&mut out, mux, &[]), None);
        assert_eq!(upload_response(&mut out, mux, &[1, 2, 3]), None);
        assert_eq!(upload_response(&mut out, Mux { ca: true, ..mux }, &[1, 2, 3, 4]), None);
        assert_eq!(upload_response(&mut out, mux, &[7; 16]), None);
        assert_eq!(upload_response(&mut out, mux, &[7; 17]), Some(16));
        assert_eq!(first(&mut q)[6..], [0x00, 0x30, 0x41, 0x00, 0x20, 0x01, 0, 0, 0, 0]);
        assert_eq!(first(&mut q)[6..], [0x00, 0x30, 0x47, 0x00, 0x20, 0x01, 1, 2, 3, 0]);
        assert_eq!(first(&mut q)[6..], [0x00, 0x30, 0x53, 0x00, 0x20, 0x01, 1, 2, 3, 4]);
        assert_eq!(first(&mut q).len(), 32);
    }

    #[test]
    fn unsized_expedited_length_follows_the_entry() {
        let mut od = ObjectDictionary::new();
        od.insert(Object::var(0x2000, "a", DataType::Unsigned16, Access::Rw, Value::U16(0)));
        od.insert(Object::var(0x2001, "b", DataType::Unsigned64, Access::Rw, Value::U64(0)));
        let dev = (od, NoHooks);
        let m = |index, ca| Mux { index, sub: 0, ca };
        assert_eq!(unsized_len(&dev, m(0x2000, false)), 2);
        assert_eq!(unsized_len(&dev, m(0x2001, false)), 4);
        assert_eq!(unsized_len(&dev, m(0x2002, false)), 4);
        assert_eq!(unsized_len(&dev, m(0x2000, true)), 4);
    }
}
