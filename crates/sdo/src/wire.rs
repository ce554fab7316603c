//! The SDO command byte and frame layout (CiA 301 §7.2.4.3), both
//! directions: the client and the server here, CoE's SDO server (the same
//! command byte in a mailbox, ETG.1000.6 §5.6.2) and the CLI's frame
//! decoder all build and read byte 0 with these names.
//!
//! Every SDO frame is 8 bytes: a command byte, then either the multiplexer
//! (index LSB, index MSB, sub-index) and 4 data bytes, or 7 segment bytes.

use drivebus_can::{CanId, Frame};
use drivebus_od::SdoAbort;

// Client command specifiers (ccs, bits 7..5 of byte 0), shifted into place.
/// Download segment request.
pub const CCS_DOWNLOAD_SEGMENT: u8 = 0 << 5;
/// Initiate download request.
pub const CCS_INITIATE_DOWNLOAD: u8 = 1 << 5;
/// Initiate upload request.
pub const CCS_INITIATE_UPLOAD: u8 = 2 << 5;
/// Upload segment request.
pub const CCS_UPLOAD_SEGMENT: u8 = 3 << 5;
/// Abort transfer (either side, already shifted).
pub const CS_ABORT: u8 = 4 << 5;
/// Block upload (initiate, start, ack, end).
pub const CCS_BLOCK_UPLOAD: u8 = 5 << 5;
/// Block download (initiate, end).
pub const CCS_BLOCK_DOWNLOAD: u8 = 6 << 5;

// Server command specifiers (scs, bits 7..5 of byte 0), as `scs` returns
// them (shift left by 5 to build a command byte).
/// Upload segment response.
pub const SCS_UPLOAD_SEGMENT: u8 = 0;
/// Download segment response.
pub const SCS_DOWNLOAD_SEGMENT: u8 = 1;
/// Initiate upload response.
pub const SCS_INITIATE_UPLOAD: u8 = 2;
/// Initiate download response.
pub const SCS_INITIATE_DOWNLOAD: u8 = 3;
/// Block download responses.
pub const SCS_BLOCK_DOWNLOAD: u8 = 5;
/// Block upload responses.
pub const SCS_BLOCK_UPLOAD: u8 = 6;

// Block sub-commands (cs/ss, bits 1..0 of byte 0).
/// Initiate.
pub const BLOCK_INITIATE: u8 = 0;
/// End.
pub const BLOCK_END: u8 = 1;
/// Acknowledge a sub-block.
pub const BLOCK_ACK: u8 = 2;
/// Start sending (block upload).
pub const BLOCK_START: u8 = 3;

/// The toggle bit of segment frames.
pub const TOGGLE: u8 = 0x10;
/// The "last segment" bit of block segments.
pub const BLOCK_LAST: u8 = 0x80;
/// Payload bytes of one segment.
pub const SEG: usize = 7;

/// Initiate bits: s (size indicated; with e, n says the unused bytes).
pub const SIZE_INDICATED: u8 = 0x01;
/// Initiate bit e: expedited (the data is in bytes 4..8).
pub const EXPEDITED: u8 = 0x02;
/// Segment bit c: no more segments follow.
pub const LAST_SEGMENT: u8 = 0x01;
/// Block initiate bit cc/sc: CRC supported.
pub const BLOCK_CRC: u8 = 0x04;
/// Block initiate bit s: size indicated.
pub const BLOCK_SIZE_INDICATED: u8 = 0x02;

/// The command specifier (ccs or scs, bits 7..5) of a command byte.
#[inline]
pub const fn scs(b0: u8) -> u8 {
    b0 >> 5
}

/// The command byte of an expedited initiate carrying `n` (1..=4) bytes:
/// `specifier` is the shifted ccs/scs (`CCS_INITIATE_DOWNLOAD`, or
/// `SCS_INITIATE_UPLOAD << 5`).
#[inline]
pub const fn expedited(specifier: u8, n: usize) -> u8 {
    specifier | EXPEDITED | SIZE_INDICATED | (((4 - n) as u8 & 0x03) << 2)
}

/// The data bytes of an expedited initiate: `Some(1..=4)` when the size is
/// indicated, `None` when it is not (the receiver knows the type).
#[inline]
pub const fn expedited_len(b0: u8) -> Option<usize> {
    if b0 & SIZE_INDICATED != 0 { Some(4 - ((b0 >> 2) & 0x03) as usize) } else { None }
}

/// The command byte of a segment carrying `k` (0..=7) bytes: toggle, n,
/// c. `specifier` is the shifted ccs/scs (0 for an upload segment
/// response and a download segment request).
#[inline]
pub const fn segment(specifier: u8, toggle: u8, k: usize, last: bool) -> u8 {
    specifier | (toggle & TOGGLE) | ((((SEG - k) as u8) & 0x07) << 1) | last as u8
}

/// The data bytes of a segment (7 minus n).
#[inline]
pub const fn segment_len(b0: u8) -> usize {
    SEG - ((b0 >> 1) & 0x07) as usize
}

/// The bytes of the last block segment that carry no data (n of a block
/// end, bits 4..2).
#[inline]
pub const fn block_end_unused(b0: u8) -> usize {
    ((b0 >> 2) & 0x07) as usize
}

/// A request carrying the multiplexer and 4 data bytes.
#[inline]
pub fn mux_frame(cmd: u8, index: u16, sub: u8, d: [u8; 4]) -> [u8; 8] {
    let [lo, hi] = index.to_le_bytes();
    [cmd, lo, hi, sub, d[0], d[1], d[2], d[3]]
}

/// The multiplexer echoed in a response.
#[inline]
pub fn mux_of(d: &[u8; 8]) -> (u16, u8) {
    (u16::from_le_bytes([d[1], d[2]]), d[3])
}

/// Bytes 4..8 as a little-endian UNSIGNED32.
#[inline]
pub fn u32_at4(d: &[u8; 8]) -> u32 {
    u32::from_le_bytes([d[4], d[5], d[6], d[7]])
}

/// An abort transfer request (CiA 301 §7.2.4.3.17).
#[inline]
pub fn abort_frame(index: u16, sub: u8, code: SdoAbort) -> [u8; 8] {
    mux_frame(CS_ABORT, index, sub, code.0.to_le_bytes())
}

/// A data frame on `id`. Out-of-range ids (a hand-built `CanId`) are masked
/// so that building a frame can never fail or panic.
#[inline]
pub fn frame(id: CanId, data: [u8; 8]) -> Frame {
    match id {
        CanId::Standard(v) => Frame::new8(v, data),
        CanId::Extended(v) => match Frame::try_new(CanId::Extended(v & 0x1FFF_FFFF), &data) {
            Ok(f) => f,
            // Unreachable: the id is masked into range and the payload is 8 bytes.
            Err(_) => Frame::new8(0, data),
        },
    }
}

/// Number of 7-byte segments needed for `len` bytes; an empty transfer still
/// sends one (empty) segment.
#[inline]
pub const fn segments(len: usize) -> usize {
    if len == 0 { 1 } else { len.div_ceil(SEG) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_bytes_as_cia_301_codes_them() {
        // Expedited upload response of 2 bytes (43h | n=2): 4Bh; download of 4: 23h.
        assert_eq!(expedited(SCS_INITIATE_UPLOAD << 5, 2), 0x4B);
        assert_eq!(expedited(CCS_INITIATE_DOWNLOAD, 4), 0x23);
        assert_eq!(expedited(CCS_INITIATE_DOWNLOAD, 1), 0x2F);
        // A last upload segment with 3 bytes and the toggle set: 10h | n=4 | c.
        assert_eq!(segment(SCS_UPLOAD_SEGMENT << 5, TOGGLE, 3, true), 0x19);
        assert_eq!(segment(CCS_DOWNLOAD_SEGMENT, 0, 7, false), 0x00);
        assert_eq!(expedited_len(0x22), None, "e=1, s=0: size not indicated");
        assert_eq!(block_end_unused(0xC1 | (5 << 2)), 5);
    }

    #[test]
    fn every_length_round_trips() {
        for n in 1..=4 {
            for spec in [CCS_INITIATE_DOWNLOAD, SCS_INITIATE_UPLOAD << 5] {
                let b0 = expedited(spec, n);
                assert_eq!((scs(b0), expedited_len(b0)), (spec >> 5, Some(n)));
            }
        }
        for k in 0..=SEG {
            for (toggle, last) in [(0, false), (TOGGLE, true)] {
                let b0 = segment(SCS_UPLOAD_SEGMENT << 5, toggle, k, last);
                assert_eq!(segment_len(b0), k);
                assert_eq!((b0 & TOGGLE, b0 & LAST_SEGMENT != 0), (toggle, last));
            }
        }
    }
}
