//! Where mapped objects sit in a PDO, or in a process-data image of several
//! PDOs in a row (EtherCAT's 1C12h/1C13h assignment): the bit offsets of a
//! mapping are added up here and nowhere else, for the masters, the
//! gateway and the tools (CiA 301 7.4.7.1: mapping order, LSB first).

use crate::bits::{pack_bits, unpack_bits};
use crate::mapping::{map_entry, split_entry};

/// One mapping entry (1600h…/1A00h… sub 1..): an object and its length.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PdoMapEntry {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Length in bits.
    pub bits: u8,
}

impl PdoMapEntry {
    /// An entry.
    pub const fn new(index: u16, sub: u8, bits: u8) -> Self {
        PdoMapEntry { index, sub, bits }
    }
    /// The 32-bit mapping value `iiiissll`.
    pub const fn raw(self) -> u32 {
        map_entry(self.index, self.sub, self.bits)
    }
    /// From the 32-bit mapping value.
    pub const fn from_raw(v: u32) -> Self {
        let (index, sub, bits) = split_entry(v);
        PdoMapEntry { index, sub, bits }
    }
}

impl From<u32> for PdoMapEntry {
    fn from(v: u32) -> Self {
        PdoMapEntry::from_raw(v)
    }
}

/// A mapped object at its place in the data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MappedObject {
    /// The entry.
    pub entry: PdoMapEntry,
    /// Its first bit, counted from bit 0 of byte 0.
    pub bit_offset: usize,
}

impl MappedObject {
    /// Whether this is `index:sub`.
    pub fn is(&self, index: u16, sub: u8) -> bool {
        self.entry.index == index && self.entry.sub == sub
    }
    /// `(byte offset, byte length)` when the object starts on a byte
    /// boundary and fills whole bytes; `None` for a bit field.
    pub fn bytes(&self) -> Option<(usize, usize)> {
        let bits = usize::from(self.entry.bits);
        (self.bit_offset.is_multiple_of(8) && bits.is_multiple_of(8))
            .then_some((self.bit_offset / 8, bits / 8))
    }
    /// Its value in `data`, zero-extended; `None` when `data` is too short
    /// or the entry is empty or longer than 64 bits.
    pub fn read(&self, data: &[u8]) -> Option<u64> {
        let bits = usize::from(self.entry.bits);
        (bits > 0 && bits <= 64 && self.end() <= data.len() * 8)
            .then(|| unpack_bits(data, self.bit_offset, bits))
    }
    /// Puts the low bits of `value` into `data` (bits past its end are dropped).
    pub fn write(&self, data: &mut [u8], value: u64) {
        pack_bits(data, self.bit_offset, usize::from(self.entry.bits), value);
    }
    /// The bit after its last.
    pub fn end(&self) -> usize {
        self.bit_offset + usize::from(self.entry.bits)
    }
}

/// The entries of a mapping (or of several PDOs' mappings chained) with
/// their offsets, in order. Takes [`PdoMapEntry`]s or raw `u32` values.
pub fn layout<E: Into<PdoMapEntry>>(
    entries: impl IntoIterator<Item = E>,
) -> impl Iterator<Item = MappedObject> {
    entries.into_iter().scan(0usize, |at, e| {
        let entry = e.into();
        let m = MappedObject { entry, bit_offset: *at };
        *at += usize::from(entry.bits);
        Some(m)
    })
}

/// The first place of `index:sub` in the mapping.
pub fn find_mapped<E: Into<PdoMapEntry>>(
    entries: impl IntoIterator<Item = E>,
    index: u16,
    sub: u8,
) -> Option<MappedObject> {
    layout(entries).find(|m| m.is(index, sub))
}

/// The mapping's length in bits.
pub fn mapped_bits<E: Into<PdoMapEntry>>(entries: impl IntoIterator<Item = E>) -> usize {
    layout(entries).last().map_or(0, |m| m.end())
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;

    #[test]
    fn offsets_add_up_in_mapping_order() {
        let raw = [0x6041_0010u32, 0x2000_0101, 0x6064_0020, 0x6061_0008];
        let l: Vec<_> = layout(raw).collect();
        assert_eq!(l.iter().map(|m| m.bit_offset).collect::<Vec<_>>(), [0, 16, 17, 49]);
        assert_eq!(l[0].bytes(), Some((0, 2)));
        assert_eq!(l[1].bytes(), None, "a 1-bit field");
        assert_eq!(l[2].bytes(), None, "starts at bit 17");
        assert_eq!(mapped_bits(raw), 57);
        assert_eq!(find_mapped(raw, 0x6061, 0).map(|m| m.bit_offset), Some(49));
        assert_eq!(find_mapped(raw, 0x6060, 0), None);
    }

    #[test]
    fn read_and_write_at_the_place() {
        let raw = [0x6040_0010u32, 0x2000_0101, 0x607A_0020];
        let l: Vec<_> = layout(raw).collect();
        let mut data = [0u8; 7];
        l[0].write(&mut data, 0x000F);
        l[1].write(&mut data, 1);
        l[2].write(&mut data, 0x1234_5678);
        assert_eq!(l[0].read(&data), Some(0x000F));
        assert_eq!(l[1].read(&data), Some(1));
        assert_eq!(l[2].read(&data), Some(0x1234_5678));
        assert_eq!(l[2].read(&data[..6]), None, "past the end");
    }

    #[test]
    fn raw_round_trips() {
        let e = PdoMapEntry::new(0x6064, 0, 32);
        assert_eq!(e.raw(), 0x6064_0020);
        assert_eq!(PdoMapEntry::from(e.raw()), e);
    }
}
