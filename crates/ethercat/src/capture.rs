//! pcapng capture of every frame in and out, for Wireshark.
//!
//! Written with the `pcap-file` crate (blocks: section header, one
//! Ethernet interface with nanosecond timestamps, one enhanced packet block
//! per frame with the inbound/outbound direction flag).

use pcap_file::DataLink;
use pcap_file::pcapng::PcapNgWriter;
use pcap_file::pcapng::blocks::enhanced_packet::{EnhancedPacketBlock, EnhancedPacketOption};
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};
use std::borrow::Cow;
use std::io::{self, Write};
use std::time::Duration;

/// Direction of a captured frame (pcapng `epb_flags` bits 1:0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// From the master to the slaves.
    Inbound,
    /// The reply.
    Outbound,
}

/// A pcapng writer.
pub struct Capture<W: Write> {
    w: PcapNgWriter<W>,
}

impl<W: Write> std::fmt::Debug for Capture<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Capture")
    }
}

fn io_err(e: pcap_file::PcapError) -> io::Error {
    io::Error::other(e.to_string())
}

impl<W: Write> Capture<W> {
    /// Starts a capture: section header and an Ethernet interface named
    /// `interface`.
    pub fn new(writer: W, interface: &str) -> io::Result<Self> {
        let mut w = PcapNgWriter::new(writer).map_err(io_err)?;
        w.write_pcapng_block(InterfaceDescriptionBlock {
            linktype: DataLink::ETHERNET,
            snaplen: 0,
            options: vec![
                InterfaceDescriptionOption::IfName(Cow::Owned(interface.to_owned())),
                // Timestamps are written in nanoseconds.
                InterfaceDescriptionOption::IfTsResol(9),
            ],
        })
        .map_err(io_err)?;
        Ok(Capture { w })
    }

    /// Appends one frame with its Unix timestamp in ns.
    pub fn write(&mut self, frame: &[u8], unix_ns: u64, dir: Direction) -> io::Result<()> {
        let flags = match dir {
            Direction::Inbound => 0b01,
            Direction::Outbound => 0b10,
        };
        self.w
            .write_pcapng_block(EnhancedPacketBlock {
                interface_id: 0,
                timestamp: Duration::from_nanos(unix_ns),
                original_len: frame.len() as u32,
                data: Cow::Borrowed(frame),
                options: vec![EnhancedPacketOption::Flags(flags)],
            })
            .map_err(io_err)?;
        Ok(())
    }

    /// Flushes the underlying writer.
    pub fn flush(&mut self) -> io::Result<()> {
        self.w.get_mut().flush()
    }

    /// The underlying writer.
    pub fn into_inner(self) -> W {
        self.w.into_inner()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcap_file::pcapng::{Block, PcapNgReader};

    #[test]
    fn frames_read_back_with_timestamps_and_direction() {
        let mut c = Capture::new(Vec::new(), "test0").unwrap();
        c.write(&[1, 2, 3], 1_700_000_000_123_456_789, Direction::Inbound).unwrap();
        c.write(&[4, 5], 1_700_000_000_123_456_999, Direction::Outbound).unwrap();
        let bytes = c.into_inner();
        let mut r = PcapNgReader::new(&bytes[..]).unwrap();
        let mut got = Vec::new();
        while let Some(b) = r.next_block() {
            if let Block::EnhancedPacket(p) = b.unwrap() {
                let flags = p.options.iter().find_map(|o| match o {
                    EnhancedPacketOption::Flags(f) => Some(*f),
                    _ => None,
                });
                got.push((p.data.to_vec(), p.timestamp.as_nanos() as u64, flags));
            }
        }
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].0, [1, 2, 3]);
        assert_eq!(got[0].1, 1_700_000_000_123_456_789);
        assert_eq!(got[0].2, Some(1), "inbound");
        assert_eq!(got[1].2, Some(2), "outbound");
    }
}
