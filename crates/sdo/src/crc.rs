//! CRC-16 of SDO block transfer (CiA 301 §7.2.4.3, SDO block CRC): polynomial
//! x^16 + x^12 + x^5 + 1 (0x1021), initial value 0, no reflection, no final
//! XOR — the catalogue's CRC-16/XMODEM.
//!
//! Shared by the server and the client. [`Crc16`] is incremental so a side
//! may checksum data as it is produced or received; [`crc16`] does a whole
//! buffer. Both use the `crc` crate's 16-lane table (8 KiB, built at compile
//! time), so the CRC of a 10 KiB block transfer costs a few microseconds.

use crc::{CRC_16_XMODEM, Crc, Table};

/// The table-driven engine. XMODEM has no reflection and no output XOR, so
/// a finalized value is the raw register and can seed the next update:
/// that is what makes [`Crc16`] chainable through `digest_with_initial`.
static ENGINE: Crc<u16, Table<16>> = Crc::<u16, Table<16>>::new(&CRC_16_XMODEM);

/// CRC-16/XMODEM of `data` (initial value 0), as sent in a block end frame.
#[inline]
pub fn crc16(data: &[u8]) -> u16 {
    ENGINE.checksum(data)
}

/// An incremental CRC-16/XMODEM: feed data in any number of pieces.
///
/// ```
/// use drivebus_sdo::crc::{Crc16, crc16};
/// let mut c = Crc16::new();
/// c.update(b"1234");
/// c.update(b"56789");
/// assert_eq!(c.value(), 0x31C3);
/// assert_eq!(crc16(b"123456789"), 0x31C3);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Crc16 {
    state: u16,
}

impl Crc16 {
    /// A fresh CRC with the CiA 301 initial value 0.
    #[inline]
    pub const fn new() -> Self {
        Crc16 { state: 0 }
    }

    /// A CRC starting from another register value (e.g. 0xFFFF for the
    /// CCITT-FALSE variant some tools print). CiA 301 uses 0.
    #[inline]
    pub const fn with_initial(init: u16) -> Self {
        Crc16 { state: init }
    }

    /// Feed more data.
    #[inline]
    pub fn update(&mut self, data: &[u8]) {
        let mut d = ENGINE.digest_with_initial(self.state);
        d.update(data);
        self.state = d.finalize();
    }

    /// The CRC of everything fed so far (the value does not consume `self`,
    /// so updating may continue).
    #[inline]
    pub const fn value(&self) -> u16 {
        self.state
    }

    /// Start again from 0.
    #[inline]
    pub fn reset(&mut self) {
        self.state = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Public check value of the CRC-16/XMODEM catalogue entry.
    #[test]
    fn catalogue_check_value() {
        assert_eq!(crc16(b"123456789"), 0x31C3);
        assert_eq!(crc16(b""), 0);
    }

    // Widely published CRC-16/CCITT vectors computed with initial value
    // 0xFFFF (same polynomial, no reflection): they exercise `with_initial`.
    #[test]
    fn vectors_with_initial_ffff() {
        let cases: [(&[u8], u16); 5] = [
            (&[0x00, 0x00], 0x1D0F),
            (&[0x00, 0x00, 0x00], 0xCC9C),
            (&[0xAB, 0xCD, 0xEF, 0x01], 0x04A2),
            (&[0x14, 0x56, 0xF8, 0x9A, 0x00, 0x01], 0x7FD5),
            (b"123456789", 0x29B1),
        ];
        for (data, want) in cases {
            let mut c = Crc16::with_initial(0xFFFF);
            c.update(data);
            assert_eq!(c.value(), want, "{data:02X?}");
        }
    }

    #[test]
    fn incremental_equals_whole_for_every_split() {
        let data: alloc::vec::Vec<u8> = (0..300u32).map(|i| (i * 7 + 3) as u8).collect();
        let whole = crc16(&data);
        for split in [0, 1, 7, 15, 16, 17, 150, 299, 300] {
            let mut c = Crc16::new();
            c.update(&data[..split]);
            c.update(&data[split..]);
            assert_eq!(c.value(), whole, "split at {split}");
        }
        let mut c = Crc16::new();
        for chunk in data.chunks(7) {
            c.update(chunk);
        }
        assert_eq!(c.value(), whole);
        c.reset();
        assert_eq!(c.value(), 0);
    }
}
