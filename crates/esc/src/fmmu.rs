//! Fieldbus memory management units (ESC data sheet Section I "FMMU",
//! Section II 0x0600–0x06FF).
//!
//! An FMMU maps a logical bit range (`logical start address` + `start bit`
//! to the `stop bit` of the last of `length` bytes) onto physical memory
//! from `physical start address` + `start bit`, bit for bit. Bits are
//! numbered LSB first. Physical memory means the whole ESC address space:
//! registers included (SOEM 2.0 maps the SM1 status byte 0x080D).

/// One decoded FMMU register block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Fmmu {
    /// Logical start address (0x0).
    pub logical_start: u32,
    /// Length in bytes from the start byte to the stop byte (0x4).
    pub length: u16,
    /// Logical start bit (0x6, bits 2:0).
    pub logical_start_bit: u8,
    /// Logical stop bit (0x7, bits 2:0).
    pub logical_stop_bit: u8,
    /// Physical start address (0x8).
    pub physical_start: u16,
    /// Physical start bit (0xA, bits 2:0).
    pub physical_start_bit: u8,
    /// Read enable (0xB bit 0): LRD/LRW copy memory into the frame.
    pub read: bool,
    /// Write enable (0xB bit 1): LWR/LRW copy the frame into memory.
    pub write: bool,
    /// Activate (0xC bit 0).
    pub enabled: bool,
}

impl Fmmu {
    /// Decodes the 16 register bytes.
    pub fn from_registers(r: &[u8; 16]) -> Fmmu {
        Fmmu {
            logical_start: u32::from_le_bytes([r[0], r[1], r[2], r[3]]),
            length: u16::from_le_bytes([r[4], r[5]]),
            logical_start_bit: r[6] & 7,
            logical_stop_bit: r[7] & 7,
            physical_start: u16::from_le_bytes([r[8], r[9]]),
            physical_start_bit: r[10] & 7,
            read: r[11] & 1 != 0,
            write: r[11] & 2 != 0,
            enabled: r[12] & 1 != 0,
        }
    }

    /// Encodes into 16 register bytes.
    pub fn to_registers(&self) -> [u8; 16] {
        let mut r = [0u8; 16];
        r[0..4].copy_from_slice(&self.logical_start.to_le_bytes());
        r[4..6].copy_from_slice(&self.length.to_le_bytes());
        r[6] = self.logical_start_bit & 7;
        r[7] = self.logical_stop_bit & 7;
        r[8..10].copy_from_slice(&self.physical_start.to_le_bytes());
        r[10] = self.physical_start_bit & 7;
        r[11] = u8::from(self.read) | (u8::from(self.write) << 1);
        r[12] = u8::from(self.enabled);
        r
    }

    /// Logical bit range `[start, end)` this FMMU covers (empty if length 0
    /// or the stop bit precedes the start bit in a one-byte mapping).
    pub fn logical_bits(&self) -> (u64, u64) {
        if self.length == 0 {
            return (0, 0);
        }
        let start = u64::from(self.logical_start) * 8 + u64::from(self.logical_start_bit);
        let end = (u64::from(self.logical_start) + u64::from(self.length) - 1) * 8
            + u64::from(self.logical_stop_bit)
            + 1;
        (start, end.max(start))
    }

    /// The part of this FMMU hit by a logical datagram `[addr, addr + len)`.
    pub fn map(&self, addr: u32, len: usize) -> Option<Mapping> {
        let (ls, le) = self.logical_bits();
        let ds = u64::from(addr) * 8;
        let de = ds + len as u64 * 8;
        let s = ls.max(ds);
        let e = le.min(de);
        if s >= e {
            return None;
        }
        let phys = u64::from(self.physical_start) * 8 + u64::from(self.physical_start_bit) + (s - ls);
        Some(Mapping { frame_bit: (s - ds) as usize, phys_bit: phys, bits: (e - s) as usize })
    }
}

/// A contiguous bit run shared by a datagram and an FMMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mapping {
    /// First bit, counted from the start of the datagram data.
    pub frame_bit: usize,
    /// First physical bit (byte address × 8 + bit).
    pub phys_bit: u64,
    /// Number of bits.
    pub bits: usize,
}

impl Mapping {
    /// Whole bytes on both sides: the mapping is a plain byte copy.
    #[inline]
    pub fn byte_aligned(&self) -> Option<(usize, u64, usize)> {
        (self.frame_bit.is_multiple_of(8) && self.phys_bit.is_multiple_of(8) && self.bits.is_multiple_of(8))
            .then_some((self.frame_bit / 8, self.phys_bit / 8, self.bits / 8))
    }

    /// Calls `f(physical byte address, mask, value)` for every physical byte
    /// this mapping writes, taking the bits from `frame`.
    pub fn for_each_write(&self, frame: &[u8], mut f: impl FnMut(u64, u8, u8)) {
        let mut pb = self.phys_bit;
        let end = self.phys_bit + self.bits as u64;
        while pb < end {
            let byte = pb / 8;
            let lo = (pb % 8) as u32;
            let hi = ((end - byte * 8).min(8)) as u32;
            let n = hi - lo;
            let fb = self.frame_bit + (pb - self.phys_bit) as usize;
            let mask = (((1u16 << n) - 1) << lo) as u8;
            let value = ((read_bits(frame, fb, n) as u16) << lo) as u8;
            f(byte, mask, value);
            pb = (byte + 1) * 8;
        }
    }

    /// Calls `read(physical byte address)` for every physical byte this
    /// mapping reads and merges the mapped bits into `frame`. Returns true
    /// if any byte was readable.
    pub fn for_each_read(&self, frame: &mut [u8], mut read: impl FnMut(u64) -> Option<u8>) -> bool {
        let mut any = false;
        let mut pb = self.phys_bit;
        let end = self.phys_bit + self.bits as u64;
        while pb < end {
            let byte = pb / 8;
            let lo = (pb % 8) as u32;
            let hi = ((end - byte * 8).min(8)) as u32;
            let n = hi - lo;
            let fb = self.frame_bit + (pb - self.phys_bit) as usize;
            if let Some(v) = read(byte) {
                any = true;
                write_bits(frame, fb, n, v >> lo);
            }
            pb = (byte + 1) * 8;
        }
        any
    }
}

/// `n` (≤ 8) bits of `buf` from bit `bit`, LSB first.
#[inline]
fn read_bits(buf: &[u8], bit: usize, n: u32) -> u8 {
    let i = bit / 8;
    let lo = u16::from(buf.get(i).copied().unwrap_or(0));
    let hi = u16::from(buf.get(i + 1).copied().unwrap_or(0));
    let w = (lo | (hi << 8)) >> (bit % 8);
    (w & ((1u16 << n) - 1)) as u8
}

/// Stores the low `n` (≤ 8) bits of `v` into `buf` from bit `bit`.
#[inline]
fn write_bits(buf: &mut [u8], bit: usize, n: u32, v: u8) {
    let i = bit / 8;
    let sh = (bit % 8) as u32;
    let mask = ((1u16 << n) - 1) << sh;
    let val = (u16::from(v) << sh) & mask;
    if let Some(b) = buf.get_mut(i) {
        *b = (*b & !(mask as u8)) | val as u8;
    }
    if mask > 0xFF
        && let Some(b) = buf.get_mut(i + 1)
    {
        *b = (*b & !((mask >> 8) as u8)) | (val >> 8) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn fmmu(ls: u32, len: u16, lsb: u8, leb: u8, ps: u16, psb: u8) -> Fmmu {
        Fmmu {
            logical_start: ls,
            length: len,
            logical_start_bit: lsb,
            logical_stop_bit: leb,
            physical_start: ps,
            physical_start_bit: psb,
            read: true,
            write: true,
            enabled: true,
        }
    }

    /// Reference model: walk every logical bit of the datagram one by one.
    fn reference_write(f: &Fmmu, addr: u32, frame: &[u8], mem: &mut [u8]) {
        let (ls, le) = f.logical_bits();
        for k in 0..frame.len() * 8 {
            let lb = u64::from(addr) * 8 + k as u64;
            if lb < ls || lb >= le {
                continue;
            }
            let pb = u64::from(f.physical_start) * 8 + u64::from(f.physical_start_bit) + (lb - ls);
            let bit = (frame[k / 8] >> (k % 8)) & 1;
            let idx = (pb / 8) as usize;
            if idx < mem.len() {
                mem[idx] = (mem[idx] & !(1 << (pb % 8))) | (bit << (pb % 8));
            }
        }
    }

    fn reference_read(f: &Fmmu, addr: u32, frame: &mut [u8], mem: &[u8]) {
        let (ls, le) = f.logical_bits();
        for k in 0..frame.len() * 8 {
            let lb = u64::from(addr) * 8 + k as u64;
            if lb < ls || lb >= le {
                continue;
            }
            let pb = u64::from(f.physical_start) * 8 + u64::from(f.physical_start_bit) + (lb - ls);
            let idx = (pb / 8) as usize;
            if idx < mem.len() {
                let bit = (mem[idx] >> (pb % 8)) & 1;
                frame[k / 8] = (frame[k / 8] & !(1 << (k % 8))) | (bit << (k % 8));
            }
        }
    }

    #[test]
    fn registers_round_trip() {
        let f = fmmu(0x0001_0002, 3, 4, 2, 0x1100, 5);
        assert_eq!(Fmmu::from_registers(&f.to_registers()), f);
    }

    #[test]
    fn byte_aligned_mapping() {
        let f = fmmu(0x100, 4, 0, 7, 0x1000, 0);
        let m = f.map(0xFE, 8).unwrap();
        assert_eq!(m.byte_aligned(), Some((2, 0x1000, 4)));
        assert_eq!(f.map(0x104, 4), None);
        assert_eq!(f.map(0xF0, 0x10), None);
    }

    #[test]
    fn single_bit_mapping() {
        // Logical bit 3 of byte 0x10 -> physical 0x0F00 bit 6.
        let f = fmmu(0x10, 1, 3, 3, 0x0F00, 6);
        let m = f.map(0x10, 1).unwrap();
        let mut seen = Vec::new();
        m.for_each_write(&[0b0000_1000], |a, mask, v| seen.push((a, mask, v)));
        assert_eq!(seen, vec![(0x0F00, 0x40, 0x40)]);
        let mut frame = [0xFFu8];
        assert!(m.for_each_read(&mut frame, |_| Some(0)));
        assert_eq!(frame, [0xF7]);
    }

    proptest! {
        #[test]
        fn bit_mapping_matches_reference(
            ls in 0u32..24, len in 0u16..6, lsb in 0u8..8, leb in 0u8..8, ps in 0u16..24, psb in 0u8..8,
            addr in 0u32..32, frame in proptest::collection::vec(any::<u8>(), 0..12),
            mem0 in proptest::collection::vec(any::<u8>(), 40),
        ) {
            let f = fmmu(ls, len, lsb, leb, ps, psb);
            // Write direction.
            let mut want = mem0.clone();
            reference_write(&f, addr, &frame, &mut want);
            let mut got = mem0.clone();
            if let Some(m) = f.map(addr, frame.len()) {
                m.for_each_write(&frame, |a, mask, v| {
                    if let Some(b) = got.get_mut(a as usize) { *b = (*b & !mask) | (v & mask); }
                });
            }
            prop_assert_eq!(&got, &want);
            // Read direction.
            let mut want_f = frame.clone();
            reference_read(&f, addr, &mut want_f, &mem0);
            let mut got_f = frame.clone();
            if let Some(m) = f.map(addr, frame.len()) {
                m.for_each_read(&mut got_f, |a| mem0.get(a as usize).copied());
            }
            prop_assert_eq!(got_f, want_f);
        }
    }
}
