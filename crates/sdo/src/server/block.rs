//! Block upload and block download of the SDO server (CiA 301 §7.2.4.3).
//!
//! Sub-blocks are emitted in one go: the sans-IO caller receives all
//! segments of a sub-block from the `handle_frame` call that triggered them
//! (the start command or the previous ack), in sequence order.
//!
//! Block download recovery (CiA 301 §7.2.4.3, block download): the first
//! out-of-order segment is answered at once with an ack carrying the last
//! in-order sequence number; the client then restarts with sequence number 1
//! at the first missing segment. Segments of the old sub-block still in flight are ignored until
//! that restart. A lost *last* segment of a sub-block leaves no gap to see,
//! so that case (and a lost first segment of the restart) ends with the
//! protocol timeout, as in CANopenNode.

use super::{MAX_BLOCK_SIZE, SdoServer, State};
use crate::crc::crc16;
use crate::wire::*;
use drivebus_can::{Instant, TxSink};
use drivebus_od::{ObjectDictionary, ObjectHooks, SdoAbort};

/// The server's block download response to `ss`.
const BLOCK_DOWN: u8 = SCS_BLOCK_DOWNLOAD << 5;
/// The server's block upload command `ss`.
const BLOCK_UP: u8 = SCS_BLOCK_UPLOAD << 5;

impl SdoServer {
    /// Block upload initiate (A0h | cc<<2): blksize in byte 4, pst in byte 5.
    pub(super) fn block_upload_initiate<H: ObjectHooks + ?Sized>(
        &mut self,
        d: &[u8; 8],
        now: Instant,
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        let mux = [d[1], d[2], d[3]];
        if !self.config.block_transfer {
            return self.abort_with(&mux, SdoAbort::INVALID_COMMAND, out);
        }
        let (blksize, pst) = (d[4], d[5]);
        if blksize == 0 || blksize > MAX_BLOCK_SIZE {
            return self.abort_with(&mux, SdoAbort::INVALID_BLOCK_SIZE, out);
        }
        let r = match self
            .resolve(od, u16::from_le_bytes([d[1], d[2]]), d[3])
            .and_then(|r| od.read_ref(hooks, r).map(|()| r))
        {
            Ok(r) => r,
            Err(e) => return self.abort_with(&mux, e, out),
        };
        let value = od.bytes(r);
        // Protocol switch threshold (CiA 301 block upload initiate): small
        // objects go the expedited/segmented way, answered with that
        // protocol's initiate response.
        if pst != 0 && value.len() <= usize::from(pst) {
            return self.answer_upload(mux, value, now, out);
        }
        let size = match self.snapshot(value) {
            Ok(size) => size,
            Err(e) => return self.abort_with(&mux, e, out),
        };
        self.mux = mux;
        self.pos = 0;
        self.blksize = blksize;
        self.use_crc = d[0] & BLOCK_CRC != 0 && self.config.crc;
        self.state = State::BlkUpStart;
        self.deadline = now + self.config.timeout;
        let s = size.to_le_bytes();
        // scs=6, sc, s=1 (size indicated), ss=0.
        let b0 = BLOCK_UP | self.crc_bit() | BLOCK_SIZE_INDICATED | BLOCK_INITIATE;
        self.send([b0, mux[0], mux[1], mux[2], s[0], s[1], s[2], s[3]], out);
    }

    /// Start command (A3h): send the first sub-block.
    pub(super) fn block_upload_start(&mut self, out: &mut impl TxSink) {
        self.send_sub_block(out);
    }

    /// Emit up to `blksize` segments from `pos`; `pos` stays at the start of
    /// the sub-block until the client acknowledges it.
    fn send_sub_block(&mut self, out: &mut impl TxSink) {
        let len = self.buf.len();
        let mut p = self.pos;
        let mut seq = 0u8;
        let mut last = false;
        while seq < self.blksize && !last {
            seq += 1;
            let end = (p + 7).min(len);
            last = p + 7 >= len;
            let mut seg = [seq | (u8::from(last) << 7), 0, 0, 0, 0, 0, 0, 0];
            super::copy_segment(&mut seg, self.buf.get(p..end).unwrap_or(&[]));
            self.send(seg, out);
            p = end;
        }
        self.state = State::BlkUpAck { seqs: seq, last };
    }

    /// Client ack (A2h): ackseq in byte 1, next blksize in byte 2.
    pub(super) fn block_upload_ack(&mut self, d: &[u8; 8], seqs: u8, last: bool, out: &mut impl TxSink) {
        let (ackseq, blksize) = (d[1], d[2]);
        if ackseq > seqs {
            return self.abort(SdoAbort::INVALID_SEQUENCE, out);
        }
        if blksize == 0 || blksize > MAX_BLOCK_SIZE {
            return self.abort(SdoAbort::INVALID_BLOCK_SIZE, out);
        }
        self.blksize = blksize;
        if last && ackseq == seqs {
            // Everything acknowledged: end frame with the unused byte count
            // of the last segment (7 for an empty value's lone segment).
            let len = self.buf.len();
            let n = if len == 0 { 7 } else { (7 - len % 7) % 7 };
            let crc = if self.use_crc { crc16(&self.buf) } else { 0 }.to_le_bytes();
            self.state = State::BlkUpEnd;
            self.send([BLOCK_UP | ((n as u8) << 2) | BLOCK_END, crc[0], crc[1], 0, 0, 0, 0, 0], out);
            return;
        }
        // Advance past what was acknowledged; a partial ack makes the next
        // sub-block start with the first segment the client missed.
        self.pos = (self.pos + usize::from(ackseq) * 7).min(self.buf.len());
        self.send_sub_block(out);
    }

    /// Block download initiate (C0h | cc<<2 | s<<1): size in bytes 4..8.
    pub(super) fn block_download_initiate(
        &mut self,
        d: &[u8; 8],
        now: Instant,
        od: &ObjectDictionary,
        out: &mut impl TxSink,
    ) {
        let mux = [d[1], d[2], d[3]];
        if !self.config.block_transfer {
            return self.abort_with(&mux, SdoAbort::INVALID_COMMAND, out);
        }
        let r = match self.resolve(od, u16::from_le_bytes([d[1], d[2]]), d[3]) {
            Ok(r) => r,
            Err(e) => return self.abort_with(&mux, e, out),
        };
        let size =
            (d[0] & BLOCK_SIZE_INDICATED != 0).then(|| u32::from_le_bytes([d[4], d[5], d[6], d[7]]) as usize);
        if let Err(e) = self.prepare_download(od, r, size) {
            return self.abort_with(&mux, e, out);
        }
        self.mux = mux;
        self.blksize = self.config.block_size;
        self.use_crc = d[0] & BLOCK_CRC != 0 && self.config.crc;
        self.state = State::BlkDownSub { last: 0, resync: false };
        self.deadline = now + self.config.timeout;
        // scs=5, sc, ss=0; blksize in byte 4.
        let b0 = BLOCK_DOWN | self.crc_bit() | BLOCK_INITIATE;
        self.send([b0, mux[0], mux[1], mux[2], self.blksize, 0, 0, 0], out);
    }

    /// One segment of a block download sub-block: c<<7 | seqno, 7 bytes.
    pub(super) fn block_segment(&mut self, d: &[u8; 8], last: u8, resync: bool, out: &mut impl TxSink) {
        let seq = d[0] & !BLOCK_LAST;
        let c = d[0] & BLOCK_LAST != 0;
        if seq == 0 || seq > self.blksize {
            return self.abort(SdoAbort::INVALID_SEQUENCE, out);
        }
        if seq != last.wrapping_add(1) {
            // A duplicate, or a stale segment still in flight after our
            // partial ack: ignore. A gap: acknowledge what we have now so the
            // client retransmits from ackseq+1 (CiA 301 block download).
            if seq > last && !resync {
                self.state = State::BlkDownSub { last: 0, resync: true };
                self.send([BLOCK_DOWN | BLOCK_ACK, last, self.blksize, 0, 0, 0, 0, 0], out);
            }
            return;
        }
        // Every byte allowed is already here (the first segment always fits:
        // an empty value still travels as one segment of padding).
        if self.buf.len() >= self.limit && !self.buf.is_empty() {
            let e = self.over_limit();
            return self.abort(e, out);
        }
        self.buf.extend_from_slice(&d[1..8]);
        if c {
            self.state = State::BlkDownEnd;
            self.send([BLOCK_DOWN | BLOCK_ACK, seq, self.blksize, 0, 0, 0, 0, 0], out);
        } else if seq == self.blksize {
            self.state = State::BlkDownSub { last: 0, resync: false };
            self.send([BLOCK_DOWN | BLOCK_ACK, seq, self.blksize, 0, 0, 0, 0, 0], out);
        } else {
            self.state = State::BlkDownSub { last: seq, resync: false };
        }
    }

    /// Block download end (C1h | n<<2): CRC in bytes 1..3.
    pub(super) fn block_download_end<H: ObjectHooks + ?Sized>(
        &mut self,
        d: &[u8; 8],
        od: &mut ObjectDictionary,
        hooks: &mut H,
        out: &mut impl TxSink,
    ) {
        let n = block_end_unused(d[0]);
        let len = self.buf.len().saturating_sub(n);
        self.buf.truncate(len);
        if self.size.is_none_or(|s| s == len)
            && self.use_crc
            && crc16(&self.buf) != u16::from_le_bytes([d[1], d[2]])
        {
            return self.abort(SdoAbort::CRC_ERROR, out);
        }
        self.finish_download(BLOCK_DOWN | BLOCK_END, od, hooks, out);
    }
}

impl SdoServer {
    /// The sc bit: this server checks and sends CRCs.
    #[inline]
    fn crc_bit(&self) -> u8 {
        if self.config.crc { BLOCK_CRC } else { 0 }
    }
}
