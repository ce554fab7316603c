//! Length of a classic CAN frame on the wire, bit for bit.
//!
//! The bit stream follows ISO 11898-1 (classic base and extended format):
//! the frame is built field by field, the CRC-15 is computed over it, stuff
//! bits are counted over SOF..CRC sequence, and the unstuffed trailer
//! (CRC delimiter, ACK slot, ACK delimiter, EOF) plus intermission is added.

use crate::{CanId, Frame};
use core::time::Duration;

/// CRC-15/CAN generator x¹⁵+x¹⁴+x¹⁰+x⁸+x⁷+x⁴+x³+1 (ISO 11898-1, CRC field).
pub const CRC15_POLY: u16 = 0x4599;

/// Unstuffed bits after the CRC sequence: CRC delimiter (1), ACK slot (1),
/// ACK delimiter (1), end of frame (7).
pub const TRAILER_BITS: u32 = 10;

/// Intermission between frames (ISO 11898-1 interframe space).
pub const INTERMISSION_BITS: u32 = 3;

/// Error flag (6 dominant) plus error delimiter (8 recessive).
pub const ERROR_FRAME_BITS: u32 = 14;

/// Bits a bus-off node must see before it may recover: 128 occurrences of
/// 11 consecutive recessive bits (ISO 11898-1 fault confinement).
pub const BUS_OFF_RECOVERY_BITS: u32 = 128 * 11;

/// CRC-15/CAN over a bit sequence, most significant bit first, initial value 0.
pub fn crc15(bits: impl IntoIterator<Item = bool>) -> u16 {
    let mut crc: u16 = 0;
    for bit in bits {
        let next = bit ^ ((crc >> 14) & 1 == 1);
        crc = (crc << 1) & 0x7FFF;
        if next {
            crc ^= CRC15_POLY;
        }
    }
    crc
}

/// The bit-level length of one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameBits {
    /// Bits from SOF to the end of the CRC sequence before stuffing.
    pub unstuffed: u32,
    /// Stuff bits inserted into that range.
    pub stuff: u32,
    /// The 15-bit CRC of the frame.
    pub crc: u16,
}

impl FrameBits {
    /// Bits from SOF to the end of EOF: what receivers need before they
    /// accept the frame.
    #[inline]
    pub const fn to_end_of_frame(&self) -> u32 {
        self.unstuffed + self.stuff + TRAILER_BITS
    }
    /// Bits the frame occupies the bus, intermission included.
    #[inline]
    pub const fn total(&self) -> u32 {
        self.to_end_of_frame() + INTERMISSION_BITS
    }
    /// Bits the bus is occupied by a transmission destroyed by a CRC error,
    /// intermission included. A CRC error is signalled starting at the bit
    /// after the ACK delimiter (ISO 11898-1 error signalling), so the stuffed
    /// frame up to the ACK delimiter is spent, then error flag and delimiter.
    #[inline]
    pub const fn with_crc_error(&self) -> u32 {
        self.unstuffed + self.stuff + 3 + ERROR_FRAME_BITS + INTERMISSION_BITS
    }
}

/// Fixed-size bit buffer: the longest stuffed region (extended, 8 bytes) is
/// 118 bits, so a `u128` holds it without allocation.
struct Bits {
    v: u128,
    len: u32,
}

impl Bits {
    #[inline]
    fn push(&mut self, value: u64, n: u32) {
        let mask = (1u128 << n) - 1;
        self.v = (self.v << n) | (u128::from(value) & mask);
        self.len += n;
    }
}

/// CRC-15/CAN of one byte shifted through the register (MSB first).
const CRC15_TABLE: [u16; 256] = {
    let mut t = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = (i as u16) << 7;
        let mut k = 0;
        while k < 8 {
            crc = if crc & 0x4000 != 0 { ((crc << 1) ^ CRC15_POLY) & 0x7FFF } else { (crc << 1) & 0x7FFF };
            k += 1;
        }
        t[i] = crc;
        i += 1;
    }
    t
};

/// CRC-15/CAN of the `len` low bits of `v`, most significant first: the
/// leading `len % 8` bits one by one, then a byte per table step (the
/// virtual bus prices every frame, so this is on its hot path).
fn crc15_bits(v: u128, len: u32) -> u16 {
    let mut crc: u16 = 0;
    let head = len % 8;
    for i in (len - head..len).rev() {
        let next = ((v >> i) & 1 == 1) ^ ((crc >> 14) & 1 == 1);
        crc = (crc << 1) & 0x7FFF;
        if next {
            crc ^= CRC15_POLY;
        }
    }
    let mut i = len - head;
    while i >= 8 {
        i -= 8;
        let byte = (v >> i) as u8;
        crc = ((crc << 8) ^ CRC15_TABLE[usize::from((crc >> 7) as u8 ^ byte)]) & 0x7FFF;
    }
    crc
}

/// Stuff bits ISO 11898-1 inserts into the `len` low bits of `v` (after
/// five equal bits, the complement, which starts the next run), counted a
/// run at a time.
fn stuff_bits(v: u128, len: u32) -> u32 {
    if len == 0 {
        return 0;
    }
    // Top-aligned: bit `p` of the stream is bit 127 of `x << p`.
    let x = v << (128 - len);
    let (mut p, mut stuff) = (0u32, 0u32);
    let mut last = x >> 127 == 1;
    let mut run = 0u32;
    while p < len {
        let y = x << p;
        // Bits from `p` equal to `last`.
        let same = if last { (!y).leading_zeros() } else { y.leading_zeros() }.min(len - p);
        if run + same >= 5 {
            // A stuff bit after the run's fifth bit; its complement starts
            // a run of one.
            p += 5 - run;
            stuff += 1;
            last = !last;
            run = 1;
        } else {
            p += same;
            run += same;
            if p < len {
                // The next bit differs: a new run starts there.
                last = !last;
                run = 0;
            }
        }
    }
    stuff
}

/// Counts the bits of `frame` on the wire.
pub fn frame_bits(frame: &Frame) -> FrameBits {
    let mut b = Bits { v: 0, len: 0 };
    let rtr = u64::from(frame.is_rtr());
    b.push(0, 1); // SOF, dominant
    match frame.id() {
        CanId::Standard(id) => {
            b.push(u64::from(id), 11);
            b.push(rtr, 1);
            b.push(0, 2); // IDE dominant, r0
        }
        CanId::Extended(id) => {
            b.push(u64::from(id >> 18), 11);
            b.push(0b11, 2); // SRR and IDE, recessive
            b.push(u64::from(id & 0x3_FFFF), 18);
            b.push(rtr, 1);
            b.push(0, 2); // r1, r0
        }
    }
    // A remote frame's DLC is the requested length but it carries no data.
    b.push(frame.len() as u64, 4);
    for &byte in frame.data() {
        b.push(u64::from(byte), 8);
    }
    let crc = crc15_bits(b.v, b.len);
    b.push(u64::from(crc), 15);
    FrameBits { unstuffed: b.len, stuff: stuff_bits(b.v, b.len), crc }
}

/// Duration of `bits` bit times at `bitrate` bit/s (truncated to ns).
#[inline]
pub fn bits_duration(bits: u32, bitrate: u32) -> Duration {
    if bitrate == 0 {
        return Duration::ZERO;
    }
    Duration::from_nanos(u64::from(bits) * 1_000_000_000 / u64::from(bitrate))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn byte_bits(bytes: &[u8]) -> impl Iterator<Item = bool> + '_ {
        bytes.iter().flat_map(|b| (0..8).rev().map(move |i| (b >> i) & 1 == 1))
    }

    #[test]
    fn crc15_check_value() {
        // CRC-15/CAN check value over ASCII "123456789" is 0x059E
        // (CRC RevEng catalogue, width=15 poly=0x4599 init=0 refin=false).
        assert_eq!(crc15(byte_bits(b"123456789")), 0x059E);
    }

    #[test]
    fn all_dominant_frame_by_hand() {
        // 000# : SOF + 11 id + RTR + IDE + r0 + DLC = 19 zeros; the CRC of
        // all-zero input with init 0 is 0, so SOF..CRC is 34 zeros. A stuff
        // bit follows zeros 5, 10, 15, 20, 25, 30 (each stuff bit breaks the
        // run): 6 stuff bits. 34 + 6 + 10 trailer + 3 IFS = 53.
        let fb = frame_bits(&Frame::new(0, &[]));
        assert_eq!(fb, FrameBits { unstuffed: 34, stuff: 6, crc: 0 });
        assert_eq!(fb.total(), 53);
    }

    /// The bit-by-bit definitions the fast forms must equal.
    fn reference(frame: &Frame) -> FrameBits {
        let mut b = Bits { v: 0, len: 0 };
        let rtr = u64::from(frame.is_rtr());
        b.push(0, 1);
        match frame.id() {
            CanId::Standard(id) => {
                b.push(u64::from(id), 11);
                b.push(rtr, 1);
                b.push(0, 2);
            }
            CanId::Extended(id) => {
                b.push(u64::from(id >> 18), 11);
                b.push(0b11, 2);
                b.push(u64::from(id & 0x3_FFFF), 18);
                b.push(rtr, 1);
                b.push(0, 2);
            }
        }
        b.push(frame.len() as u64, 4);
        for &byte in frame.data() {
            b.push(u64::from(byte), 8);
        }
        let bits = |b: &Bits| (0..b.len).rev().map(|i| (b.v >> i) & 1 == 1).collect::<Vec<_>>();
        let crc = crc15(bits(&b));
        b.push(u64::from(crc), 15);
        let (mut stuff, mut last, mut run) = (0, None, 0u32);
        for bit in bits(&b) {
            if last == Some(bit) {
                run += 1;
            } else {
                last = Some(bit);
                run = 1;
            }
            if run == 5 {
                stuff += 1;
                last = Some(!bit);
                run = 1;
            }
        }
        FrameBits { unstuffed: b.len, stuff, crc }
    }

    proptest::proptest! {
        #[test]
        fn fast_forms_equal_the_bitwise_definition(id in 0u32..1 << 29, ext: bool, rtr: bool,
                                                    data in proptest::collection::vec(proptest::num::u8::ANY, 0..=8)) {
            let cid = if ext { CanId::Extended(id) } else { CanId::Standard((id & 0x7FF) as u16) };
            let f = if rtr { Frame::try_remote(cid, data.len() as u8) } else { Frame::try_new(cid, &data) };
            let f = f.expect("valid frame");
            proptest::prop_assert_eq!(frame_bits(&f), reference(&f));
        }
    }

    #[test]
    fn stuffing_of_long_runs() {
        // 0xFF bytes and an all-zero id give long runs on both levels.
        for f in [Frame::new(0, &[0xFF; 8]), Frame::new(0x7FF, &[0; 8]), Frame::new(0x555, &[0x55; 8])] {
            assert_eq!(frame_bits(&f), reference(&f));
        }
    }

    #[test]
    fn rtr_carries_dlc_but_no_data() {
        let fb = frame_bits(&Frame::remote(0x705, 1));
        assert_eq!(fb.unstuffed, 34);
    }
}
