//! pcapng capture for Wireshark: one writer for every link drivebus
//! records, EtherCAT frames (Ethernet) and CAN frames (SocketCAN).
//!
//! Written with the `pcap-file` crate: a section header, one interface
//! with nanosecond timestamps, one enhanced packet block per frame with
//! the inbound/outbound direction flag. CAN frames use
//! `LINKTYPE_CAN_SOCKETCAN` (227), the layout Linux hands to libpcap and
//! Wireshark's CANopen dissector reads ([`socketcan_bytes`]).

use std::borrow::Cow;
use std::io::{self, Write};
use std::time::Duration;

use pcap_file::DataLink;
use pcap_file::pcapng::PcapNgWriter;
use pcap_file::pcapng::blocks::enhanced_packet::{EnhancedPacketBlock, EnhancedPacketOption};
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};

use crate::{CanId, Frame};

/// Direction of a captured frame (pcapng `epb_flags` bits 1:0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Received (on EtherCAT: from the master to the slaves).
    Inbound,
    /// Sent (on EtherCAT: the reply).
    Outbound,
}

/// What the captured bytes are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkType {
    /// Ethernet frames (EtherCAT), `LINKTYPE_ETHERNET` (1).
    Ethernet,
    /// CAN frames in the Linux SocketCAN layout, `LINKTYPE_CAN_SOCKETCAN` (227).
    SocketCan,
}

/// SocketCAN `can_id` flag: 29-bit identifier.
pub const CAN_EFF_FLAG: u32 = 0x8000_0000;
/// SocketCAN `can_id` flag: remote transmission request.
pub const CAN_RTR_FLAG: u32 = 0x4000_0000;
/// SocketCAN `can_id` flag: error frame (the class in the identifier bits,
/// details in the data, `linux/can/error.h`).
pub const CAN_ERR_FLAG: u32 = 0x2000_0000;

/// A frame as `LINKTYPE_CAN_SOCKETCAN` stores it: the identifier with its
/// flags in network byte order, the length (the DLC of a remote frame),
/// three bytes of padding and eight data bytes (zero past the length).
pub fn socketcan_bytes(frame: &Frame) -> [u8; 16] {
    let mut id = match frame.id() {
        CanId::Standard(v) => u32::from(v),
        CanId::Extended(v) => v | CAN_EFF_FLAG,
    };
    if frame.is_rtr() {
        id |= CAN_RTR_FLAG;
    }
    let mut b = [0u8; 16];
    b[..4].copy_from_slice(&id.to_be_bytes());
    b[4] = frame.len() as u8;
    b[8..8 + frame.data().len()].copy_from_slice(frame.data());
    b
}

/// A pcapng writer.
pub struct Capture<W: Write> {
    w: PcapNgWriter<W>,
    link: LinkType,
}

impl<W: Write> std::fmt::Debug for Capture<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Capture({:?})", self.link)
    }
}

fn io_err(e: pcap_file::PcapError) -> io::Error {
    io::Error::other(e.to_string())
}

impl<W: Write> Capture<W> {
    /// Starts a capture: section header and one interface of `link` type
    /// named `interface`.
    pub fn new(writer: W, interface: &str, link: LinkType) -> io::Result<Self> {
        let mut w = PcapNgWriter::new(writer).map_err(io_err)?;
        w.write_pcapng_block(InterfaceDescriptionBlock {
            linktype: match link {
                LinkType::Ethernet => DataLink::ETHERNET,
                LinkType::SocketCan => DataLink::CAN_SOCKETCAN,
            },
            snaplen: 0,
            options: vec![
                InterfaceDescriptionOption::IfName(Cow::Owned(interface.to_owned())),
                // Timestamps are written in nanoseconds.
                InterfaceDescriptionOption::IfTsResol(9),
            ],
        })
        .map_err(io_err)?;
        Ok(Capture { w, link })
    }

    /// The link type of this capture.
    pub fn link(&self) -> LinkType {
        self.link
    }

    /// Appends one frame (the link's bytes) with its Unix timestamp in ns.
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

    /// Appends one CAN frame; refused on a capture that is not SocketCAN.
    pub fn write_can(&mut self, frame: &Frame, unix_ns: u64, dir: Direction) -> io::Result<()> {
        if self.link != LinkType::SocketCan {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, "a CAN frame in a non-CAN capture"));
        }
        self.write(&socketcan_bytes(frame), unix_ns, dir)
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

    /// A packet read back: data, timestamp in ns, `epb_flags`.
    type Packet = (Vec<u8>, u64, Option<u64>);

    fn packets(bytes: &[u8]) -> (Vec<DataLink>, Vec<Packet>) {
        let mut r = PcapNgReader::new(bytes).unwrap();
        let (mut links, mut got) = (Vec::new(), Vec::new());
        while let Some(b) = r.next_block() {
            match b.unwrap() {
                Block::InterfaceDescription(i) => links.push(i.linktype),
                Block::EnhancedPacket(p) => {
                    let flags = p.options.iter().find_map(|o| match o {
                        EnhancedPacketOption::Flags(f) => Some(u64::from(*f)),
                        _ => None,
                    });
                    got.push((p.data.to_vec(), p.timestamp.as_nanos() as u64, flags));
                }
                _ => {}
            }
        }
        (links, got)
    }

    #[test]
    fn frames_read_back_with_timestamps_and_direction() {
        let mut c = Capture::new(Vec::new(), "test0", LinkType::Ethernet).unwrap();
        c.write(&[1, 2, 3], 1_700_000_000_123_456_789, Direction::Inbound).unwrap();
        c.write(&[4, 5], 1_700_000_000_123_456_999, Direction::Outbound).unwrap();
        assert!(c.write_can(&Frame::new(1, &[]), 0, Direction::Inbound).is_err());
        let (links, got) = packets(&c.into_inner());
        assert_eq!(links, [DataLink::ETHERNET]);
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].0, [1, 2, 3]);
        assert_eq!(got[0].1, 1_700_000_000_123_456_789);
        assert_eq!(got[0].2, Some(1), "inbound");
        assert_eq!(got[1].2, Some(2), "outbound");
    }

    #[test]
    fn can_frames_in_the_socketcan_layout() {
        assert_eq!(
            socketcan_bytes(&Frame::new(0x581, &[0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00])),
            [0, 0, 0x05, 0x81, 8, 0, 0, 0, 0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00]
        );
        assert_eq!(
            socketcan_bytes(&Frame::remote(0x705, 1)),
            [0x40, 0, 0x07, 0x05, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]
        );
        let ext = Frame::try_new(CanId::Extended(0x18FF_50E5), &[1, 2]).unwrap();
        assert_eq!(socketcan_bytes(&ext)[..6], [0x98, 0xFF, 0x50, 0xE5, 2, 0]);
        let mut c = Capture::new(Vec::new(), "can0", LinkType::SocketCan).unwrap();
        c.write_can(&Frame::new(0x080, &[]), 5, Direction::Inbound).unwrap();
        let (links, got) = packets(&c.into_inner());
        assert_eq!(links, [DataLink::CAN_SOCKETCAN]);
        assert_eq!(got[0].0, socketcan_bytes(&Frame::new(0x080, &[])));
    }
}
