//! Block download and block upload (CiA 301 §7.2.4.3.11..16), client side.

use super::{SdoClient, State};
use crate::crc::crc16;
use crate::wire::*;
use drivebus_can::TxSink;
use drivebus_od::SdoAbort;

/// A block size a server may announce: 1..=127.
#[inline]
fn valid_blksize(b: u8) -> bool {
    (1..=super::MAX_BLOCK_SIZE).contains(&b)
}

impl SdoClient {
    // ---- block download ----

    pub(super) fn on_block_down_init(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if scs(d[0]) != SCS_BLOCK_DOWNLOAD || d[0] & 0x03 != BLOCK_INITIATE {
            return self.violation(SdoAbort::INVALID_COMMAND, out);
        }
        if !self.mux_ok(d, out) {
            return;
        }
        if !valid_blksize(d[4]) {
            return self.violation(SdoAbort::INVALID_BLOCK_SIZE, out);
        }
        self.blksize = d[4];
        // CRC only when both sides support it (sc bit of the response).
        self.crc = self.cfg.crc && d[0] & BLOCK_CRC != 0;
        self.seg_base = 0;
        self.send_sub_block(out);
    }

    /// Send the whole sub-block starting at segment `seg_base` in one go; the
    /// bus serialises the frames.
    fn send_sub_block(&mut self, out: &mut impl TxSink) {
        let len = self.data.len();
        let total = segments(len);
        let count = (total - self.seg_base).min(usize::from(self.blksize));
        for i in 0..count {
            let seg = self.seg_base + i;
            let start = seg * SEG;
            let end = (start + SEG).min(len);
            let mut f = [0u8; 8];
            // seqno fits 7 bits: count <= blksize <= 127.
            f[0] = (i + 1) as u8 | if seg + 1 == total { BLOCK_LAST } else { 0 };
            f[1..=end - start].copy_from_slice(&self.data[start..end]);
            self.send(out, f);
        }
        self.seg_sent = count as u8;
        self.state = State::BlockDownAck;
    }

    pub(super) fn on_block_down_ack(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if scs(d[0]) != SCS_BLOCK_DOWNLOAD || d[0] & 0x03 != BLOCK_ACK {
            return self.violation(SdoAbort::INVALID_COMMAND, out);
        }
        let (ackseq, blksize) = (d[1], d[2]);
        if ackseq > self.seg_sent {
            return self.violation(SdoAbort::INVALID_SEQUENCE, out);
        }
        if !valid_blksize(blksize) {
            return self.violation(SdoAbort::INVALID_BLOCK_SIZE, out);
        }
        let len = self.data.len();
        let total = segments(len);
        // Segments after ackseq were lost: the next sub-block restarts at
        // seqno 1 with the first unacknowledged segment.
        self.seg_base += usize::from(ackseq);
        self.pos = (self.seg_base * SEG).min(len);
        self.blksize = blksize;
        if self.seg_base < total {
            return self.send_sub_block(out);
        }
        // End: n = bytes of the last segment that carried no data.
        let n = (total * SEG - len) as u8;
        let crc = if self.crc { crc16(&self.data) } else { 0 };
        let [lo, hi] = crc.to_le_bytes();
        self.send(out, [CCS_BLOCK_DOWNLOAD | (n << 2) | BLOCK_END, lo, hi, 0, 0, 0, 0, 0]);
        self.state = State::BlockDownEnd;
    }

    pub(super) fn on_block_down_end(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if scs(d[0]) != SCS_BLOCK_DOWNLOAD || d[0] & 0x03 != BLOCK_END {
            return self.violation(SdoAbort::INVALID_COMMAND, out);
        }
        self.complete();
    }

    // ---- block upload ----

    pub(super) fn on_block_up_init(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        match scs(d[0]) {
            SCS_BLOCK_UPLOAD if d[0] & 0x01 == BLOCK_INITIATE => {}
            // Protocol switch: with pst > 0 the server may answer a small
            // object with a normal initiate upload response.
            SCS_INITIATE_UPLOAD if self.cfg.pst != 0 => return self.accept_init_upload(d, out),
            _ => return self.violation(SdoAbort::INVALID_COMMAND, out),
        }
        if !self.mux_ok(d, out) {
            return;
        }
        let size = (d[0] & BLOCK_SIZE_INDICATED != 0).then(|| u32_at4(d) as usize);
        if !self.reserve_upload(size, out) {
            return;
        }
        self.size = size;
        self.crc = self.cfg.crc && d[0] & BLOCK_CRC != 0;
        self.expected = 1;
        self.send(out, [CCS_BLOCK_UPLOAD | BLOCK_START, 0, 0, 0, 0, 0, 0, 0]);
        self.state = State::BlockUpData;
    }

    fn send_block_ack(&mut self, ackseq: u8, out: &mut impl TxSink) {
        self.send(out, [CCS_BLOCK_UPLOAD | BLOCK_ACK, ackseq, self.blksize, 0, 0, 0, 0, 0]);
        self.expected = 1;
    }

    pub(super) fn on_block_up_segment(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        let seqno = d[0] & 0x7F;
        let last = d[0] & BLOCK_LAST != 0;
        if seqno == 0 || seqno > self.blksize {
            return self.violation(SdoAbort::INVALID_SEQUENCE, out);
        }
        if seqno != self.expected {
            // A segment was lost: drop the rest of the sub-block and, at its
            // end, acknowledge the last one received in sequence so the
            // server retransmits from there (not an error in CiA 301).
            if last || seqno == self.blksize {
                self.send_block_ack(self.expected - 1, out);
            }
            return;
        }
        let new_len = self.data.len() + SEG;
        if self.size.is_some_and(|n| new_len > segments(n).saturating_mul(SEG)) {
            // More segments than the announced size needs.
            return self.violation(SdoAbort::TYPE_MISMATCH, out);
        }
        if new_len > self.cfg.max_upload.saturating_add(SEG) {
            let code = SdoAbort::OUT_OF_MEMORY;
            return self.fail_with_abort(code, super::ClientError::LocalAbort(code), out);
        }
        // Whole segments are kept; the end frame says how many padding bytes
        // the last one had.
        self.data.extend_from_slice(&d[1..]);
        self.pos = self.data.len();
        self.expected += 1;
        if last {
            self.send_block_ack(seqno, out);
            self.state = State::BlockUpEnd;
        } else if seqno == self.blksize {
            self.send_block_ack(seqno, out);
        }
    }

    pub(super) fn on_block_up_end(&mut self, d: &[u8; 8], out: &mut impl TxSink) {
        if scs(d[0]) != SCS_BLOCK_UPLOAD || d[0] & 0x03 != BLOCK_END {
            return self.violation(SdoAbort::INVALID_COMMAND, out);
        }
        let n = block_end_unused(d[0]);
        let len = self.data.len().saturating_sub(n);
        self.data.truncate(len);
        self.pos = len;
        if self.size.is_some_and(|s| s != len) {
            return self.violation(SdoAbort::TYPE_MISMATCH, out);
        }
        if self.crc && crc16(&self.data) != u16::from_le_bytes([d[1], d[2]]) {
            return self.violation(SdoAbort::CRC_ERROR, out);
        }
        self.send(out, [CCS_BLOCK_UPLOAD | BLOCK_END, 0, 0, 0, 0, 0, 0, 0]);
        self.complete();
    }
}
