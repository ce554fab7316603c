//! Value storage: up to 8 bytes inline, longer values on the heap.

use alloc::vec::Vec;
use core::ops::Deref;

/// The bytes of one value. Every numeric CiA 301 type fits in 8 bytes, so
/// PDO and SDO hot paths read and write values without chasing a heap
/// pointer; strings and domains spill to a `Vec`.
#[derive(PartialEq, Eq)]
pub(crate) enum ValueBytes {
    Inline { len: u8, buf: [u8; 8] },
    Heap(Vec<u8>),
}

impl Clone for ValueBytes {
    fn clone(&self) -> Self {
        match self {
            ValueBytes::Inline { len, buf } => ValueBytes::Inline { len: *len, buf: *buf },
            ValueBytes::Heap(v) => ValueBytes::Heap(v.clone()),
        }
    }

    /// The same variant as `source`; a heap buffer is reused.
    fn clone_from(&mut self, source: &Self) {
        match (&mut *self, source) {
            (ValueBytes::Heap(v), ValueBytes::Heap(s)) => v.clone_from(s),
            _ => *self = source.clone(),
        }
    }
}

impl ValueBytes {
    pub(crate) fn from_slice(b: &[u8]) -> Self {
        if b.len() <= 8 {
            let mut buf = [0u8; 8];
            buf[..b.len()].copy_from_slice(b);
            ValueBytes::Inline { len: b.len() as u8, buf }
        } else {
            ValueBytes::Heap(b.to_vec())
        }
    }

    /// Replace the content, keeping a heap buffer's capacity.
    pub(crate) fn set(&mut self, b: &[u8]) {
        match self {
            ValueBytes::Heap(v) => {
                v.clear();
                v.extend_from_slice(b);
            }
            _ => *self = ValueBytes::from_slice(b),
        }
    }

    /// Overwrite an inline value of the same length with one 64-bit
    /// compare and store; `Some(changed)`, or `None` if not applicable.
    #[inline(always)]
    pub(crate) fn set_inline(&mut self, b: &[u8]) -> Option<bool> {
        if let ValueBytes::Inline { len, buf } = self
            && usize::from(*len) == b.len()
        {
            let new = load_le(b)?;
            let old = u64::from_le_bytes(*buf);
            *buf = new.to_le_bytes();
            return Some(old != new);
        }
        None
    }

    /// The content as a zero-extended word. Inline bytes past `len` are
    /// always zero (every write keeps them so), so no length dispatch.
    #[inline(always)]
    pub(crate) fn word(&self) -> u64 {
        match self {
            ValueBytes::Inline { buf, .. } => u64::from_le_bytes(*buf),
            ValueBytes::Heap(v) => crate::types::le_u64(v),
        }
    }

    /// Store a word into an inline value (the caller keeps bits past the
    /// value's size zero); `Some(changed)`, `None` for a heap value.
    #[inline(always)]
    pub(crate) fn set_word(&mut self, w: u64) -> Option<bool> {
        if let ValueBytes::Inline { buf, .. } = self {
            let old = u64::from_le_bytes(*buf);
            *buf = w.to_le_bytes();
            return Some(old != w);
        }
        None
    }

    /// Store the low `len` bytes of `w` into an inline value of at most
    /// `max` bytes (the bytes past `len` stay zero); `Some(changed)`, or
    /// `None` if not applicable.
    #[inline(always)]
    pub(crate) fn set_low(&mut self, w: u64, max: usize) -> Option<bool> {
        if let ValueBytes::Inline { len, buf } = self
            && usize::from(*len) <= max.min(8)
        {
            let bits = 8 * u32::from(*len);
            let w = if bits >= 64 { w } else { w & ((1u64 << bits) - 1) };
            let old = u64::from_le_bytes(*buf);
            *buf = w.to_le_bytes();
            return Some(old != w);
        }
        None
    }

    /// Mutable view of the current content (length unchanged).
    #[inline]
    pub(crate) fn as_mut_slice(&mut self) -> &mut [u8] {
        match self {
            ValueBytes::Inline { len, buf } => &mut buf[..usize::from(*len).min(8)],
            ValueBytes::Heap(v) => v,
        }
    }
}

/// A 1-, 2-, 4- or 8-byte little-endian value as a word, with fixed-size
/// loads (no `memcpy`); `None` for other lengths.
#[inline(always)]
fn load_le(b: &[u8]) -> Option<u64> {
    Some(match *b {
        [a] => u64::from(a),
        [a, b1] => u64::from(u16::from_le_bytes([a, b1])),
        [a, b1, c, d] => u64::from(u32::from_le_bytes([a, b1, c, d])),
        [a, b1, c, d, e, f, g, h] => u64::from_le_bytes([a, b1, c, d, e, f, g, h]),
        _ => return None,
    })
}

impl Deref for ValueBytes {
    type Target = [u8];
    #[inline]
    fn deref(&self) -> &[u8] {
        match self {
            ValueBytes::Inline { len, buf } => &buf[..usize::from(*len).min(8)],
            ValueBytes::Heap(v) => v,
        }
    }
}

impl core::fmt::Debug for ValueBytes {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        core::fmt::Debug::fmt(&**self, f)
    }
}
