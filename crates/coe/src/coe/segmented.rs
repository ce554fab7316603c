//! SDO segments over CoE (ETG.1000.6 §5.6.2.3 download, §5.6.2.6 upload).
//!
//! A segment is the CoE header, one command byte (last-segment bit 0,
//! unused-byte count bits 1-3, toggle bit 4, command specifier bits 5-7)
//! and the data. The service data is at least 10 bytes: a segment with
//! fewer than 7 data bytes is padded to 7 and says in bits 1-3 how many
//! of them are unused. A longer segment is sized by the mailbox length
//! alone (data = length - 3) and the count is 0.

use super::sdo_server::{COE_SDO_RESPONSE, SDO_LEN, abort, store};
use super::{CoeServer, Mux, Out, Transfer};
use crate::access::ObjectAccess;
use crate::mailbox::{HEADER_LEN, MailboxType};
use drivebus_base::Instant;
use drivebus_od::SdoAbort;
use drivebus_sdo::wire::{
    LAST_SEGMENT, SCS_DOWNLOAD_SEGMENT, SCS_UPLOAD_SEGMENT, TOGGLE, segment, segment_len,
};
/// Data bytes every segment carries at least (padding included).
const MIN_SEGMENT: usize = 7;
/// CoE header and command byte in front of segment data.
const SEGMENT_HEADER: usize = 3;

fn toggle_bit(t: bool) -> u8 {
    if t { TOGGLE } else { 0 }
}

/// Data bytes of a received segment: the mailbox length decides, except in
/// the 7-byte minimum segment where bits 1-3 count the padding.
pub(crate) fn segment_data_len(body_len: usize, cmd: u8) -> usize {
    let k = body_len.saturating_sub(SEGMENT_HEADER);
    if k == MIN_SEGMENT { segment_len(cmd) } else { k }
}

impl CoeServer {
    /// Upload segment request (command specifier 3): the next segment.
    pub(super) fn upload_segment(
        &mut self,
        cmd: u8,
        mux: Mux,
        pos: usize,
        toggle: bool,
        now: Instant,
        out: &mut Out<'_>,
    ) {
        if (cmd & TOGGLE != 0) != toggle {
            self.transfer = Transfer::Idle;
            return abort(out, mux, SdoAbort::TOGGLE_NOT_ALTERNATED);
        }
        let rest = self.buf.get(pos..).unwrap_or(&[]);
        let k = rest.len().min(out.cap.saturating_sub(SEGMENT_HEADER));
        let last = k == rest.len();
        let unused = MIN_SEGMENT.saturating_sub(k);
        let w = out.q.begin();
        w.extend_from_slice(&COE_SDO_RESPONSE);
        // n counts the padding of a short segment; a longer one says 0.
        w.push(segment(SCS_UPLOAD_SEGMENT << 5, toggle_bit(toggle), k.min(MIN_SEGMENT), last));
        w.extend_from_slice(&rest[..k]);
        w.resize(w.len() + unused, 0);
        out.q.commit(MailboxType::Coe);
        self.transfer =
            if last { Transfer::Idle } else { Transfer::Upload { mux, pos: pos + k, toggle: !toggle } };
        self.deadline = now + self.cfg.timeout;
    }

    /// Download segment request (command specifier 0).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn download_segment<A: ObjectAccess + ?Sized>(
        &mut self,
        body: &[u8],
        mux: Mux,
        total: usize,
        toggle: bool,
        now: Instant,
        objects: &mut A,
        out: &mut Out<'_>,
    ) {
        let cmd = body[2];
        if (cmd & TOGGLE != 0) != toggle {
            self.transfer = Transfer::Idle;
            return abort(out, mux, SdoAbort::TOGGLE_NOT_ALTERNATED);
        }
        let k = segment_data_len(body.len(), cmd);
        if self.buf.len() + k > total {
            self.transfer = Transfer::Idle;
            return abort(out, mux, SdoAbort::DATA_TOO_LONG);
        }
        // Within the capacity reserved at initiate: no allocation.
        self.buf.extend_from_slice(&body[SEGMENT_HEADER..SEGMENT_HEADER + k]);
        if cmd & LAST_SEGMENT == 0 {
            self.transfer = Transfer::Download { mux, total, toggle: !toggle };
            self.deadline = now + self.cfg.timeout;
            return segment_ack(out, toggle);
        }
        self.transfer = Transfer::Idle;
        if self.buf.len() < total {
            return abort(out, mux, SdoAbort::DATA_TOO_SHORT);
        }
        match store(objects, mux, &self.buf) {
            Ok(()) => segment_ack(out, toggle),
            Err(e) => abort(out, mux, e),
        }
    }
}

/// Download segment response: command specifier 1 with the toggle, padded
/// to the 10-byte minimum.
fn segment_ack(out: &mut Out<'_>, toggle: bool) {
    let w = out.q.begin();
    w.extend_from_slice(&COE_SDO_RESPONSE);
    w.push((SCS_DOWNLOAD_SEGMENT << 5) | toggle_bit(toggle));
    w.resize(HEADER_LEN + SDO_LEN, 0);
    out.q.commit(MailboxType::Coe);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_length_rules() {
        // 7-byte minimum: bits 1-3 count unused bytes.
        assert_eq!(segment_data_len(10, 3 << 1), 4);
        assert_eq!(segment_data_len(10, 0x01 | (7 << 1)), 0);
        // Longer segments: the mailbox length decides, bits 1-3 ignored.
        assert_eq!(segment_data_len(125, 0x0E), 122);
    }
}
