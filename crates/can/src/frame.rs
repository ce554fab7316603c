//! Classic CAN frames (CAN FD ready: lengths are never assumed to be 8).

use core::fmt;

/// Largest payload a [`Frame`] carries. Classic CAN is 8; code that handles
/// payloads uses `frame.len()` and this constant, never a literal 8, so a
/// CAN FD frame type can replace it later.
pub const MAX_DATA_LEN: usize = 8;

/// An 11-bit (standard) or 29-bit (extended) CAN identifier.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CanId {
    /// 11-bit identifier, `0..=0x7FF`.
    Standard(u16),
    /// 29-bit identifier, `0..=0x1FFF_FFFF`.
    Extended(u32),
}

impl CanId {
    /// A standard identifier, or `None` if it does not fit in 11 bits.
    #[inline]
    pub const fn standard(id: u16) -> Option<CanId> {
        if id <= 0x7FF { Some(CanId::Standard(id)) } else { None }
    }
    /// An extended identifier, or `None` if it does not fit in 29 bits.
    #[inline]
    pub const fn extended(id: u32) -> Option<CanId> {
        if id <= 0x1FFF_FFFF { Some(CanId::Extended(id)) } else { None }
    }
    /// The numeric identifier.
    #[inline]
    pub const fn raw(self) -> u32 {
        match self {
            CanId::Standard(id) => id as u32,
            CanId::Extended(id) => id,
        }
    }
    /// True for a 29-bit identifier.
    #[inline]
    pub const fn is_extended(self) -> bool {
        matches!(self, CanId::Extended(_))
    }
    /// Arbitration priority key: lower wins. A standard frame beats an
    /// extended one with the same 11-bit base (the IDE bit is recessive).
    #[inline]
    pub const fn arbitration_key(self) -> u64 {
        match self {
            // base id (11 bits) << 19, then SRR/IDE recessive (1), then the 18-bit extension
            CanId::Standard(id) => (id as u64) << 20,
            CanId::Extended(id) => {
                let base = (id >> 18) as u64;
                let ext = (id & 0x3_FFFF) as u64;
                (base << 20) | (1 << 19) | (1 << 18) | ext
            }
        }
    }
}

impl fmt::Debug for CanId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CanId::Standard(id) => write!(f, "{id:03X}"),
            CanId::Extended(id) => write!(f, "{id:08X}x"),
        }
    }
}

/// Why a frame could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// The identifier is out of range for its format.
    BadId,
    /// More data than [`MAX_DATA_LEN`].
    TooLong,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::BadId => f.write_str("CAN identifier out of range"),
            FrameError::TooLong => f.write_str("CAN payload longer than 8 bytes"),
        }
    }
}

/// A classic CAN data or remote frame. `Copy`, fixed size, no allocation.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Frame {
    id: CanId,
    rtr: bool,
    len: u8,
    data: [u8; MAX_DATA_LEN],
}

impl Frame {
    /// A data frame with an 11-bit id. Panics only on a programming error
    /// (id > 0x7FF or data > 8 bytes); use [`Frame::try_new`] for input.
    #[inline]
    pub fn new(id: u16, data: &[u8]) -> Frame {
        match Frame::try_new(CanId::Standard(id), data) {
            Ok(f) => f,
            Err(e) => panic!("Frame::new({id:#x}): {e}"),
        }
    }

    /// A data frame with exactly 8 bytes and an 11-bit id (the SDO shape).
    #[inline]
    pub const fn new8(id: u16, data: [u8; 8]) -> Frame {
        Frame { id: CanId::Standard(id & 0x7FF), rtr: false, len: 8, data }
    }

    /// A data frame, checking the id range and length.
    pub fn try_new(id: CanId, data: &[u8]) -> Result<Frame, FrameError> {
        let ok = match id {
            CanId::Standard(v) => v <= 0x7FF,
            CanId::Extended(v) => v <= 0x1FFF_FFFF,
        };
        if !ok {
            return Err(FrameError::BadId);
        }
        if data.len() > MAX_DATA_LEN {
            return Err(FrameError::TooLong);
        }
        let mut buf = [0u8; MAX_DATA_LEN];
        buf[..data.len()].copy_from_slice(data);
        Ok(Frame { id, rtr: false, len: data.len() as u8, data: buf })
    }

    /// A remote (RTR) frame requesting `len` bytes.
    pub fn try_remote(id: CanId, len: u8) -> Result<Frame, FrameError> {
        let mut f = Frame::try_new(id, &[])?;
        if len as usize > MAX_DATA_LEN {
            return Err(FrameError::TooLong);
        }
        f.rtr = true;
        f.len = len;
        Ok(f)
    }

    /// A remote frame with an 11-bit id (panics on id > 0x7FF or len > 8).
    pub fn remote(id: u16, len: u8) -> Frame {
        match Frame::try_remote(CanId::Standard(id), len) {
            Ok(f) => f,
            Err(e) => panic!("Frame::remote({id:#x}): {e}"),
        }
    }

    /// The identifier.
    #[inline]
    pub const fn id(&self) -> CanId {
        self.id
    }
    /// The 11-bit identifier, or `None` for an extended frame.
    #[inline]
    pub const fn std_id(&self) -> Option<u16> {
        match self.id {
            CanId::Standard(v) => Some(v),
            CanId::Extended(_) => None,
        }
    }
    /// True for a remote transmission request.
    #[inline]
    pub const fn is_rtr(&self) -> bool {
        self.rtr
    }
    /// The DLC (for an RTR frame: the requested length).
    #[inline]
    pub const fn len(&self) -> usize {
        self.len as usize
    }
    /// True when the frame carries no data bytes.
    #[inline]
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }
    /// The payload (empty for an RTR frame).
    #[inline]
    pub fn data(&self) -> &[u8] {
        if self.rtr { &[] } else { &self.data[..self.len as usize] }
    }
    /// The whole 8-byte buffer, zero-padded beyond `len()`.
    #[inline]
    pub const fn raw_data(&self) -> &[u8; MAX_DATA_LEN] {
        &self.data
    }
}

impl fmt::Debug for Frame {
    /// `601#4000100000000000` / `705#R1` (candump style).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.id {
            CanId::Standard(id) => write!(f, "{id:03X}#")?,
            CanId::Extended(id) => write!(f, "{id:08X}#")?,
        }
        if self.rtr {
            return write!(f, "R{}", self.len);
        }
        for b in self.data() {
            write!(f, "{b:02X}")?;
        }
        Ok(())
    }
}

impl fmt::Display for Frame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_checked() {
        assert_eq!(Frame::try_new(CanId::Standard(0x800), &[]), Err(FrameError::BadId));
        assert_eq!(Frame::try_new(CanId::Extended(0x2000_0000), &[]), Err(FrameError::BadId));
        assert_eq!(Frame::try_new(CanId::Standard(1), &[0; 9]), Err(FrameError::TooLong));
        assert_eq!(Frame::try_remote(CanId::Standard(1), 9), Err(FrameError::TooLong));
    }

    #[test]
    fn display_is_candump_like() {
        let f = Frame::new(0x601, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
        assert_eq!(format!("{f}"), "601#4000100000000000");
        assert_eq!(format!("{}", Frame::remote(0x705, 1)), "705#R1");
        let e = Frame::try_new(CanId::Extended(0x18FF50E5), &[1, 2]).unwrap();
        assert_eq!(format!("{e}"), "18FF50E5#0102");
    }

    #[test]
    fn rtr_has_no_data() {
        let f = Frame::remote(0x705, 1);
        assert!(f.is_rtr());
        assert_eq!(f.len(), 1);
        assert!(f.data().is_empty());
    }

    #[test]
    fn standard_beats_extended_with_same_base() {
        let s = CanId::Standard(0x100);
        let e = CanId::Extended(0x100 << 18);
        assert!(s.arbitration_key() < e.arbitration_key());
        assert!(CanId::Standard(0x080).arbitration_key() < CanId::Standard(0x081).arbitration_key());
    }
}
