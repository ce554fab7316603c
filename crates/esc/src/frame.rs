//! EtherCAT frame and datagram codec (ETG.1000.4 §5.3, ESC data sheet
//! Section I "EtherCAT frame format").
//!
//! An Ethernet II frame with EtherType 0x88A4 (optionally behind one
//! 802.1Q tag) carries a 2-byte EtherCAT header (`length:11 | reserved:1 |
//! type:4`) followed by datagrams. Each datagram is `cmd u8, idx u8,
//! address u32 (ADP u16 + ADO u16, or a 32-bit logical address),
//! len:11 | reserved:3 | C:1 | M:1, IRQ u16, data, WKC u16`, all little
//! endian. `M` ("more follows") chains the next datagram.
//!
//! This module only parses and builds; [`crate::Esc`] executes.

/// EtherType of EtherCAT frames.
pub const ETHERTYPE: u16 = 0x88A4;
/// EtherType of an IEEE 802.1Q VLAN tag.
pub const ETHERTYPE_VLAN: u16 = 0x8100;
/// Ethernet II header length (destination, source, EtherType).
pub const ETH_HEADER_LEN: usize = 14;
/// EtherCAT frame header length.
pub const ECAT_HEADER_LEN: usize = 2;
/// Datagram header length.
pub const DATAGRAM_HEADER_LEN: usize = 10;
/// Working counter length.
pub const WKC_LEN: usize = 2;
/// Largest datagram data length (11-bit length field).
pub const MAX_DATA_LEN: usize = 0x07FF;
/// Minimum Ethernet frame length without FCS (shorter frames are padded).
pub const MIN_FRAME_LEN: usize = 60;
/// EtherCAT header type for DL PDUs (datagrams).
pub const TYPE_DLPDU: u8 = 1;

/// EtherCAT commands (ETG.1000.4 Table 12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum DatagramCommand {
    /// No operation: slaves ignore the datagram.
    Nop = 0,
    /// Auto-increment physical read.
    Aprd = 1,
    /// Auto-increment physical write.
    Apwr = 2,
    /// Auto-increment physical read-write.
    Aprw = 3,
    /// Configured-address physical read.
    Fprd = 4,
    /// Configured-address physical write.
    Fpwr = 5,
    /// Configured-address physical read-write.
    Fprw = 6,
    /// Broadcast read (ORed into the datagram).
    Brd = 7,
    /// Broadcast write.
    Bwr = 8,
    /// Broadcast read-write.
    Brw = 9,
    /// Logical read.
    Lrd = 10,
    /// Logical write.
    Lwr = 11,
    /// Logical read-write.
    Lrw = 12,
    /// Auto-increment read, multiple write.
    Armw = 13,
    /// Configured-address read, multiple write.
    Frmw = 14,
}

impl DatagramCommand {
    /// Decodes a command byte; `None` for reserved codes (15–255).
    pub const fn from_u8(v: u8) -> Option<DatagramCommand> {
        Some(match v {
            0 => DatagramCommand::Nop,
            1 => DatagramCommand::Aprd,
            2 => DatagramCommand::Apwr,
            3 => DatagramCommand::Aprw,
            4 => DatagramCommand::Fprd,
            5 => DatagramCommand::Fpwr,
            6 => DatagramCommand::Fprw,
            7 => DatagramCommand::Brd,
            8 => DatagramCommand::Bwr,
            9 => DatagramCommand::Brw,
            10 => DatagramCommand::Lrd,
            11 => DatagramCommand::Lwr,
            12 => DatagramCommand::Lrw,
            13 => DatagramCommand::Armw,
            14 => DatagramCommand::Frmw,
            _ => return None,
        })
    }

    /// True for the logical (FMMU-mapped) commands.
    pub const fn is_logical(self) -> bool {
        matches!(self, DatagramCommand::Lrd | DatagramCommand::Lwr | DatagramCommand::Lrw)
    }
}

/// A decoded datagram header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DatagramHeader {
    /// Command byte (kept raw so reserved commands pass through untouched).
    pub command: u8,
    /// Index chosen by the master; slaves never change it.
    pub index: u8,
    /// Address field: ADP in the low 16 bits and ADO in the high 16 bits,
    /// or a 32-bit logical address.
    pub address: u32,
    /// Data length in bytes (11 bits).
    pub len: u16,
    /// Circulating-frame bit.
    pub circulating: bool,
    /// More datagrams follow.
    pub more: bool,
    /// IRQ field.
    pub irq: u16,
}

impl DatagramHeader {
    /// Position/configured address (ADP).
    #[inline]
    pub const fn adp(&self) -> u16 {
        self.address as u16
    }

    /// Register offset (ADO).
    #[inline]
    pub const fn ado(&self) -> u16 {
        (self.address >> 16) as u16
    }

    /// Parses the first 10 bytes of `b`.
    #[inline]
    pub fn parse(b: &[u8]) -> Option<DatagramHeader> {
        let h: &[u8; DATAGRAM_HEADER_LEN] = b.get(..DATAGRAM_HEADER_LEN)?.try_into().ok()?;
        let lf = u16::from_le_bytes([h[6], h[7]]);
        Some(DatagramHeader {
            command: h[0],
            index: h[1],
            address: u32::from_le_bytes([h[2], h[3], h[4], h[5]]),
            len: lf & 0x07FF,
            circulating: lf & 0x4000 != 0,
            more: lf & 0x8000 != 0,
            irq: u16::from_le_bytes([h[8], h[9]]),
        })
    }

    /// Encodes into the first 10 bytes of `b`.
    pub fn write(&self, b: &mut [u8]) {
        let lf = (self.len & 0x07FF) | (u16::from(self.circulating) << 14) | (u16::from(self.more) << 15);
        b[0] = self.command;
        b[1] = self.index;
        b[2..6].copy_from_slice(&self.address.to_le_bytes());
        b[6..8].copy_from_slice(&lf.to_le_bytes());
        b[8..10].copy_from_slice(&self.irq.to_le_bytes());
    }

    /// Total bytes of this datagram: header, data and working counter.
    #[inline]
    pub const fn total_len(&self) -> usize {
        DATAGRAM_HEADER_LEN + self.len as usize + WKC_LEN
    }
}

/// Where the EtherCAT header starts in an Ethernet frame, if the frame is
/// EtherCAT (EtherType 0x88A4, optionally behind one VLAN tag).
pub fn ethercat_offset(frame: &[u8]) -> Option<usize> {
    let et = u16::from_be_bytes([*frame.get(12)?, *frame.get(13)?]);
    match et {
        ETHERTYPE => Some(ETH_HEADER_LEN),
        ETHERTYPE_VLAN => {
            let inner = u16::from_be_bytes([*frame.get(16)?, *frame.get(17)?]);
            (inner == ETHERTYPE).then_some(ETH_HEADER_LEN + 4)
        }
        _ => None,
    }
}

/// Decodes the EtherCAT header: `(payload length, type)`.
#[inline]
pub fn ecat_header(payload: &[u8]) -> Option<(usize, u8)> {
    let v = u16::from_le_bytes([*payload.first()?, *payload.get(1)?]);
    Some((usize::from(v & 0x07FF), (v >> 12) as u8))
}

/// Sets the locally-administered bit of the source MAC, as the first ESC
/// of a segment does on the way back (ESC data sheet Section I "Frame
/// processing"; ethercrab drops replies whose source equals its own).
pub fn mark_reply_source(frame: &mut [u8]) {
    if let Some(b) = frame.get_mut(6) {
        *b |= 0x02;
    }
}

/// One datagram of a received frame, for masters and tests.
#[derive(Debug, Clone, Copy)]
pub struct DatagramRef<'a> {
    /// The header.
    pub header: DatagramHeader,
    /// The data bytes.
    pub data: &'a [u8],
    /// The working counter.
    pub wkc: u16,
}

/// Iterates the datagrams of an EtherCAT payload (starting at the EtherCAT
/// header). Stops at the first datagram that does not fit.
pub fn datagrams(payload: &[u8]) -> Datagrams<'_> {
    let (len, _) = ecat_header(payload).unwrap_or((0, 0));
    let end = (ECAT_HEADER_LEN + len).min(payload.len());
    Datagrams { buf: payload.get(..end).unwrap_or(&[]), pos: ECAT_HEADER_LEN, done: false }
}

/// Iterator returned by [`datagrams`].
#[derive(Debug, Clone)]
pub struct Datagrams<'a> {
    buf: &'a [u8],
    pos: usize,
    done: bool,
}

impl<'a> Iterator for Datagrams<'a> {
    type Item = DatagramRef<'a>;

    fn next(&mut self) -> Option<DatagramRef<'a>> {
        if self.done {
            return None;
        }
        let rest = self.buf.get(self.pos..)?;
        let header = DatagramHeader::parse(rest)?;
        let total = header.total_len();
        if rest.len() < total {
            self.done = true;
            return None;
        }
        let data = &rest[DATAGRAM_HEADER_LEN..DATAGRAM_HEADER_LEN + usize::from(header.len)];
        let wkc = u16::from_le_bytes([rest[total - 2], rest[total - 1]]);
        self.pos += total;
        self.done = !header.more;
        Some(DatagramRef { header, data, wkc })
    }
}

/// Why a [`FrameBuilder`] refused a datagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameBuildError {
    /// The buffer or the 11-bit EtherCAT length has no room for it.
    TooLong,
}

/// Builds an Ethernet frame with EtherCAT datagrams in a caller buffer
/// (no allocation). Used by tests, benchmarks, fuzz seeds and tools.
#[derive(Debug)]
pub struct FrameBuilder<'a> {
    buf: &'a mut [u8],
    pos: usize,
    last: Option<usize>,
}

impl<'a> FrameBuilder<'a> {
    /// Starts a broadcast frame from `src` in `buf` (at least 60 bytes).
    pub fn new(buf: &'a mut [u8], src: [u8; 6]) -> Self {
        assert!(buf.len() >= MIN_FRAME_LEN, "frame buffer shorter than an Ethernet frame");
        buf[..6].fill(0xFF);
        buf[6..12].copy_from_slice(&src);
        buf[12..14].copy_from_slice(&ETHERTYPE.to_be_bytes());
        buf[14..16].fill(0);
        FrameBuilder { buf, pos: ETH_HEADER_LEN + ECAT_HEADER_LEN, last: None }
    }

    /// Appends a datagram; `data` gives the length and the initial bytes.
    /// Returns the offset of the data in the buffer.
    pub fn push(
        &mut self,
        command: DatagramCommand,
        index: u8,
        address: u32,
        data: &[u8],
    ) -> Result<usize, FrameBuildError> {
        self.push_raw(command as u8, index, address, data, 0)
    }

    /// Appends a datagram with a raw command byte and working counter.
    pub fn push_raw(
        &mut self,
        command: u8,
        index: u8,
        address: u32,
        data: &[u8],
        wkc: u16,
    ) -> Result<usize, FrameBuildError> {
        let total = DATAGRAM_HEADER_LEN + data.len() + WKC_LEN;
        let payload_len = self.pos + total - ETH_HEADER_LEN - ECAT_HEADER_LEN;
        if data.len() > MAX_DATA_LEN || self.pos + total > self.buf.len() || payload_len > 0x07FF {
            return Err(FrameBuildError::TooLong);
        }
        if let Some(prev) = self.last {
            self.buf[prev + 7] |= 0x80;
        }
        let h = DatagramHeader {
            command,
            index,
            address,
            len: data.len() as u16,
            circulating: false,
            more: false,
            irq: 0,
        };
        h.write(&mut self.buf[self.pos..]);
        let d = self.pos + DATAGRAM_HEADER_LEN;
        self.buf[d..d + data.len()].copy_from_slice(data);
        self.buf[d + data.len()..d + data.len() + 2].copy_from_slice(&wkc.to_le_bytes());
        self.last = Some(self.pos);
        self.pos += total;
        let hdr = (payload_len as u16) | (u16::from(TYPE_DLPDU) << 12);
        self.buf[ETH_HEADER_LEN..ETH_HEADER_LEN + 2].copy_from_slice(&hdr.to_le_bytes());
        Ok(d)
    }

    /// Finishes the frame, padding to 60 bytes; returns its length.
    pub fn finish(self) -> usize {
        let len = self.pos.max(MIN_FRAME_LEN);
        self.buf[self.pos..len].fill(0);
        len
    }
}

/// Address field of a position (auto-increment) command: ADP = −position.
pub const fn position_address(position: u16, ado: u16) -> u32 {
    (0u16.wrapping_sub(position) as u32) | ((ado as u32) << 16)
}

/// Address field of a configured-address or broadcast command.
pub const fn station_address(adp: u16, ado: u16) -> u32 {
    adp as u32 | ((ado as u32) << 16)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn builds_and_parses_a_two_datagram_frame() {
        let mut buf = [0u8; 128];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
        b.push(DatagramCommand::Brd, 7, station_address(0, 0x0000), &[0; 2]).unwrap();
        b.push(DatagramCommand::Fpwr, 8, station_address(0x1000, 0x0120), &[2, 0]).unwrap();
        let n = b.finish();
        assert_eq!(n, MIN_FRAME_LEN);
        assert_eq!(ethercat_offset(&buf[..n]), Some(14));
        assert_eq!(ecat_header(&buf[14..]), Some((2 * 12 + 4, 1)));
        let ds: Vec<_> = datagrams(&buf[14..n]).collect();
        assert_eq!(ds.len(), 2);
        assert!(ds[0].header.more && !ds[1].header.more);
        assert_eq!(ds[1].header.adp(), 0x1000);
        assert_eq!(ds[1].header.ado(), 0x0120);
        assert_eq!(ds[1].data, &[2, 0]);
    }

    #[test]
    fn vlan_tagged_frames_are_found() {
        let mut f = [0u8; 64];
        f[12..14].copy_from_slice(&ETHERTYPE_VLAN.to_be_bytes());
        f[16..18].copy_from_slice(&ETHERTYPE.to_be_bytes());
        assert_eq!(ethercat_offset(&f), Some(18));
        f[17] = 0;
        assert_eq!(ethercat_offset(&f), None);
        assert_eq!(ethercat_offset(&f[..10]), None);
    }

    #[test]
    fn position_address_is_negative_position() {
        assert_eq!(position_address(0, 0x10) & 0xFFFF, 0);
        assert_eq!(position_address(3, 0x10) & 0xFFFF, 0xFFFD);
        assert_eq!(position_address(3, 0x10) >> 16, 0x10);
    }

    proptest! {
        #[test]
        fn header_round_trip(cmd: u8, idx: u8, addr: u32, len in 0u16..0x800, c: bool, m: bool, irq: u16) {
            let h = DatagramHeader { command: cmd, index: idx, address: addr, len, circulating: c, more: m, irq };
            let mut b = [0u8; 10];
            h.write(&mut b);
            prop_assert_eq!(DatagramHeader::parse(&b), Some(h));
        }

        #[test]
        fn built_frames_iterate_back(ds in proptest::collection::vec((0u8..15, any::<u8>(), any::<u32>(), proptest::collection::vec(any::<u8>(), 0..64), any::<u16>()), 1..8)) {
            let mut buf = [0u8; 1514];
            let mut b = FrameBuilder::new(&mut buf, [2; 6]);
            for (c, i, a, d, w) in &ds {
                b.push_raw(*c, *i, *a, d, *w).unwrap();
            }
            let n = b.finish();
            let got: Vec<_> = datagrams(&buf[14..n]).collect();
            prop_assert_eq!(got.len(), ds.len());
            for (g, (c, i, a, d, w)) in got.iter().zip(&ds) {
                prop_assert_eq!(g.header.command, *c);
                prop_assert_eq!(g.header.index, *i);
                prop_assert_eq!(g.header.address, *a);
                prop_assert_eq!(g.data, &d[..]);
                prop_assert_eq!(g.wkc, *w);
            }
        }

        #[test]
        fn iterating_garbage_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
            let _ = datagrams(&bytes).count();
        }
    }
}
