//! Bit-granular little-endian packing (CiA 301 7.4.7.1: mapped objects are
//! placed in mapping order, each least significant bit first).

/// Write the low `bit_len` bits of `value` into `buf` starting at bit
/// `bit_off` (bit 0 = LSB of byte 0). Bits falling outside `buf` are dropped;
/// `bit_len` above 64 is treated as 64.
#[inline]
pub fn pack_bits(buf: &mut [u8], bit_off: usize, bit_len: usize, value: u64) {
    let mut pos = bit_off;
    let mut left = bit_len.min(64);
    let mut v = value;
    while left > 0 {
        let shift = pos % 8;
        let n = (8 - shift).min(left);
        let mask = (((1u16 << n) - 1) as u8) << shift;
        if let Some(b) = buf.get_mut(pos / 8) {
            *b = (*b & !mask) | (((v as u8) << shift) & mask);
        }
        v = if n >= 64 { 0 } else { v >> n };
        pos += n;
        left -= n;
    }
}

/// Read `bit_len` bits starting at bit `bit_off` of `buf`, zero-extended.
/// Bits outside `buf` read as 0; `bit_len` above 64 is treated as 64.
#[inline]
pub fn unpack_bits(buf: &[u8], bit_off: usize, bit_len: usize) -> u64 {
    let mut pos = bit_off;
    let mut left = bit_len.min(64);
    let mut out = 0u64;
    let mut got = 0usize;
    while left > 0 {
        let shift = pos % 8;
        let n = (8 - shift).min(left);
        let byte = buf.get(pos / 8).copied().unwrap_or(0);
        let part = ((byte >> shift) as u64) & ((1u64 << n) - 1);
        out |= part << got;
        got += n;
        pos += n;
        left -= n;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;

    #[test]
    fn bool_nibble_u16() {
        // BOOLEAN at bit 0, a 4-bit field at bits 1..5, an u16 at bits 5..21.
        let mut b = [0u8; 3];
        pack_bits(&mut b, 0, 1, 1);
        pack_bits(&mut b, 1, 4, 0xA);
        pack_bits(&mut b, 5, 16, 0xBEEF);
        // 1 | 1010<<1 | 0xBEEF<<5 = 0x17DDF5
        assert_eq!(b, [0xF5, 0xDD, 0x17]);
        assert_eq!(unpack_bits(&b, 0, 1), 1);
        assert_eq!(unpack_bits(&b, 1, 4), 0xA);
        assert_eq!(unpack_bits(&b, 5, 16), 0xBEEF);
    }

    #[test]
    fn out_of_range_is_harmless() {
        let mut b = [0u8; 1];
        pack_bits(&mut b, 4, 64, u64::MAX);
        assert_eq!(b, [0xF0]);
        assert_eq!(unpack_bits(&b, 4, 200), 0xF);
    }

    proptest::proptest! {
        /// Random bit-granular layouts survive a pack/unpack round trip and
        /// never disturb their neighbours.
        #[test]
        fn round_trip(lens in proptest::collection::vec(1usize..=64, 1..16), vals in proptest::collection::vec(proptest::num::u64::ANY, 16), fill in proptest::num::u8::ANY) {
            let mut layout = Vec::new();
            let mut off = 0;
            for &l in &lens {
                if off + l > 64 { break; }
                layout.push((off, l));
                off += l;
            }
            let mut buf = [fill; 8];
            for (i, &(o, l)) in layout.iter().enumerate() {
                pack_bits(&mut buf, o, l, vals[i]);
            }
            for (i, &(o, l)) in layout.iter().enumerate() {
                let mask = if l == 64 { u64::MAX } else { (1u64 << l) - 1 };
                proptest::prop_assert_eq!(unpack_bits(&buf, o, l), vals[i] & mask);
            }
            // Bits after the layout keep the fill pattern.
            if off < 64 {
                let rest = 64 - off;
                let expect = unpack_bits(&[fill; 8], off, rest);
                proptest::prop_assert_eq!(unpack_bits(&buf, off, rest), expect);
            }
        }
    }
}
