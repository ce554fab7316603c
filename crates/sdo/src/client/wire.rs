//! Byte layout of SDO frames as the client sees them (CiA 301 §7.2.4.3).
//!
//! Every SDO frame is 8 bytes: a command byte, then either the multiplexer
//! (index LSB, index MSB, sub-index) and 4 data bytes, or 7 segment bytes.

use drivebus_can::{CanId, Frame};
use drivebus_od::SdoAbort;

/// Client command specifiers (ccs, bits 7..5 of byte 0).
pub(super) const CCS_DOWNLOAD_SEGMENT: u8 = 0 << 5;
pub(super) const CCS_INITIATE_DOWNLOAD: u8 = 1 << 5;
pub(super) const CCS_INITIATE_UPLOAD: u8 = 2 << 5;
pub(super) const CCS_UPLOAD_SEGMENT: u8 = 3 << 5;
pub(super) const CS_ABORT: u8 = 4 << 5;
pub(super) const CCS_BLOCK_UPLOAD: u8 = 5 << 5;
pub(super) const CCS_BLOCK_DOWNLOAD: u8 = 6 << 5;

/// Server command specifiers (scs, bits 7..5 of byte 0).
pub(super) const SCS_UPLOAD_SEGMENT: u8 = 0;
pub(super) const SCS_DOWNLOAD_SEGMENT: u8 = 1;
pub(super) const SCS_INITIATE_UPLOAD: u8 = 2;
pub(super) const SCS_INITIATE_DOWNLOAD: u8 = 3;
pub(super) const SCS_BLOCK_DOWNLOAD: u8 = 5;
pub(super) const SCS_BLOCK_UPLOAD: u8 = 6;

/// Block sub-commands (cs/ss, bits 1..0 of byte 0).
pub(super) const BLOCK_INITIATE: u8 = 0;
pub(super) const BLOCK_END: u8 = 1;
pub(super) const BLOCK_ACK: u8 = 2;
pub(super) const BLOCK_START: u8 = 3;

/// The toggle bit of segment frames.
pub(super) const TOGGLE: u8 = 0x10;
/// The "last segment" bit of block segments.
pub(super) const BLOCK_LAST: u8 = 0x80;
/// Payload bytes of one segment.
pub(super) const SEG: usize = 7;

/// The server command specifier of a response.
#[inline]
pub(super) const fn scs(b0: u8) -> u8 {
    b0 >> 5
}

/// A request carrying the multiplexer and 4 data bytes.
#[inline]
pub(super) fn mux_frame(cmd: u8, index: u16, sub: u8, d: [u8; 4]) -> [u8; 8] {
    let [lo, hi] = index.to_le_bytes();
    [cmd, lo, hi, sub, d[0], d[1], d[2], d[3]]
}

/// The multiplexer echoed in a response.
#[inline]
pub(super) fn mux_of(d: &[u8; 8]) -> (u16, u8) {
    (u16::from_le_bytes([d[1], d[2]]), d[3])
}

/// Bytes 4..8 as a little-endian UNSIGNED32.
#[inline]
pub(super) fn u32_at4(d: &[u8; 8]) -> u32 {
    u32::from_le_bytes([d[4], d[5], d[6], d[7]])
}

/// An abort transfer request (CiA 301 §7.2.4.3.17).
#[inline]
pub(super) fn abort_frame(index: u16, sub: u8, code: SdoAbort) -> [u8; 8] {
    mux_frame(CS_ABORT, index, sub, code.0.to_le_bytes())
}

/// A data frame on `id`. Out-of-range ids (a hand-built `CanId`) are masked
/// so that building a frame can never fail or panic.
#[inline]
pub(super) fn frame(id: CanId, data: [u8; 8]) -> Frame {
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
pub(super) const fn segments(len: usize) -> usize {
    if len == 0 { 1 } else { len.div_ceil(SEG) }
}
