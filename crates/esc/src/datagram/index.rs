//! One frame's datagrams parsed once for a whole segment, so each slave
//! executes only the datagrams that can concern it: configured-address
//! reads and writes (FPRD, FPWR, FPRW) addressed to another station pass a
//! slave untouched unless its IRQ field must be ORed in (ETG.1000.4
//! §5.4.1.2). A line of n slaves with one FPRD per slave then costs O(n)
//! datagram executions per frame instead of O(n²).

use crate::esc::{Esc, FrameReport, FrameTiming};
use crate::frame::{self, DatagramCommand, DatagramHeader, ECAT_HEADER_LEN, TYPE_DLPDU};
use crate::registers::REGISTER_SPACE;
use alloc::vec::Vec;

/// The datagrams of one frame, by whom they concern.
#[derive(Debug, Default, Clone)]
pub struct FrameIndex {
    /// (offset in the EtherCAT payload, header as the frame came) of every
    /// datagram, in order; ADP and IRQ change on the way, so slaves read
    /// the header again.
    datagrams: Vec<(usize, DatagramHeader)>,
    /// Datagrams every slave executes (all but FPRD, FPWR, FPRW), by index.
    shared: Vec<u16>,
    /// FPRD, FPWR and FPRW datagrams as (ADP, index), sorted.
    addressed: Vec<(u16, u16)>,
    /// Scratch: the datagrams one slave executes.
    selected: Vec<u16>,
}

/// What decides which datagrams a slave takes: its masked event request
/// (ORed into every datagram), station address and alias.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Addressing {
    irq: u16,
    station: u16,
    alias: Option<u16>,
}

impl FrameIndex {
    /// Indexes an EtherCAT payload (from the EtherCAT header on). False
    /// when it is not a consistent DL PDU frame: then each slave walks it
    /// itself ([`Esc::process_ethercat`]), which also counts the error.
    pub fn build(&mut self, payload: &[u8]) -> bool {
        self.datagrams.clear();
        self.shared.clear();
        self.addressed.clear();
        let Some((len, TYPE_DLPDU)) = frame::ecat_header(payload) else { return false };
        let end = ECAT_HEADER_LEN + len;
        if end > payload.len() {
            return false;
        }
        let mut pos = ECAT_HEADER_LEN;
        loop {
            let Some(h) = payload.get(pos..end).and_then(DatagramHeader::parse) else { return false };
            if pos + h.total_len() > end || self.datagrams.len() >= usize::from(u16::MAX) {
                return false;
            }
            let k = self.datagrams.len() as u16;
            match DatagramCommand::from_u8(h.command) {
                Some(DatagramCommand::Fprd | DatagramCommand::Fpwr | DatagramCommand::Fprw) => {
                    self.addressed.push((h.adp(), k))
                }
                _ => self.shared.push(k),
            }
            self.datagrams.push((pos, h));
            pos += h.total_len();
            if !h.more {
                break;
            }
        }
        self.addressed.sort_unstable();
        true
    }

    /// Datagrams in the frame.
    pub fn len(&self) -> usize {
        self.datagrams.len()
    }

    /// Whether the frame has no datagram.
    pub fn is_empty(&self) -> bool {
        self.datagrams.is_empty()
    }

    /// Into `selected`: the shared datagrams and those addressed to
    /// `station` or `alias`, in frame order.
    fn select(&mut self, station: u16, alias: Option<u16>) {
        self.selected.clear();
        self.selected.extend_from_slice(&self.shared);
        for a in core::iter::once(station).chain(alias.filter(|a| *a != station)) {
            let from = self.addressed.partition_point(|(adp, _)| *adp < a);
            self.selected
                .extend(self.addressed[from..].iter().take_while(|(adp, _)| *adp == a).map(|(_, k)| *k));
        }
        self.selected.sort_unstable();
    }
}

impl Esc {
    fn addressing(&self) -> Addressing {
        let word = |a: usize| u16::from_le_bytes([self.mem[a], self.mem[a + 1]]);
        Addressing {
            irq: word(0x0210) & word(0x0200),
            station: word(0x0010),
            alias: (self.mem[0x0103] & 1 != 0).then(|| word(0x0012)),
        }
    }

    /// Executes the datagram at `pos`, its header read again: the slaves
    /// before this one changed its ADP (auto-increment, broadcast) and
    /// IRQ fields; its length and command they do not change.
    fn execute_at(&mut self, payload: &mut [u8], pos: usize) {
        if let Some(h) = DatagramHeader::parse(&payload[pos..]) {
            self.execute(&mut payload[pos..pos + h.total_len()], &h);
        }
    }

    /// [`Esc::process_ethercat`] for a frame `index` was built from
    /// ([`FrameIndex::build`] returned true): the same result, but
    /// datagrams addressed to other stations are skipped while this ESC's
    /// IRQ field contribution is zero and its addressing does not change.
    pub fn process_indexed(
        &mut self,
        payload: &mut [u8],
        timing: &FrameTiming,
        index: &mut FrameIndex,
    ) -> FrameReport {
        self.advance(timing.at);
        self.timing = *timing;
        self.frame_no += 1;
        {
            let (head, _) = self.mem.split_at_mut(REGISTER_SPACE);
            self.sii.start_of_frame(head);
        }
        let mut report = FrameReport { datagrams: index.datagrams.len() as u16, ..FrameReport::default() };
        // Every datagram passes this ESC, executed for it or not.
        self.traffic.datagrams += index.datagrams.len() as u64;
        let key = self.addressing();
        // From which datagram on every datagram is walked.
        let mut walk_from = index.datagrams.len();
        if key.irq != 0 {
            walk_from = 0;
        } else {
            index.select(key.station, key.alias);
            for &k in &index.selected {
                let (pos, _) = index.datagrams[usize::from(k)];
                self.execute_at(payload, pos);
                report.touched = true;
                if self.addressing() != key {
                    walk_from = usize::from(k) + 1;
                    break;
                }
            }
        }
        for &(pos, _) in &index.datagrams[walk_from..] {
            self.execute_at(payload, pos);
            report.touched = true;
        }
        if self.reset_stage.0 == 3 {
            self.reset_stage = (0, 0);
            self.reset();
        }
        report
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::EscConfig;
    use crate::frame::{FrameBuilder, station_address};
    use drivebus_base::Instant;
    use proptest::prelude::*;

    const SLAVES: usize = 5;

    /// A datagram of a generated frame: (command, address, data).
    type Gen = (DatagramCommand, u32, Vec<u8>);

    fn command() -> impl Strategy<Value = DatagramCommand> {
        use DatagramCommand::*;
        prop::sample::select(vec![
            Nop, Aprd, Apwr, Aprw, Fprd, Fpwr, Fprw, Brd, Bwr, Brw, Lrd, Lwr, Lrw, Armw, Frmw,
        ])
    }

    /// Addresses that hit something: the stations 0x1000.. and their
    /// aliases, auto-increment positions, and the registers that decide
    /// addressing (station, alias, DL control, event mask) and user RAM.
    fn datagram() -> impl Strategy<Value = Gen> {
        let adp = prop_oneof![
            (0x1000u16..0x1000 + SLAVES as u16 + 1),
            (0x2000u16..0x2003),
            (0u16..3),
            Just(0xFFFF)
        ];
        let ado =
            prop::sample::select(vec![0x0010u16, 0x0012, 0x0103, 0x0200, 0x0210, 0x0220, 0x1000, 0x1002]);
        (command(), adp, ado, prop::collection::vec(any::<u8>(), 1..4)).prop_map(|(c, adp, ado, data)| {
            let address = match c {
                DatagramCommand::Lrd | DatagramCommand::Lwr | DatagramCommand::Lrw => {
                    0x0001_0000 + u32::from(ado)
                }
                _ => station_address(adp, ado),
            };
            (c, address, data)
        })
    }

    /// A line whose slaves have stations 0x1000.., aliases 0x2000.. (the
    /// first two enabled) and, on the last, an event mask so its IRQ
    /// field is not zero.
    fn line() -> Vec<Esc> {
        let mut escs: Vec<Esc> = (0..SLAVES).map(|_| Esc::new(EscConfig::default())).collect();
        let mut buf = [0u8; 1500];
        let mut b = FrameBuilder::new(&mut buf, [2; 6]);
        for i in 0..SLAVES as u16 {
            let pos = 0u16.wrapping_sub(i);
            b.push(DatagramCommand::Apwr, 0, station_address(pos, 0x0010), &(0x1000 + i).to_le_bytes())
                .unwrap();
            b.push(DatagramCommand::Apwr, 0, station_address(pos, 0x0012), &(0x2000 + i).to_le_bytes())
                .unwrap();
            if i < 2 {
                b.push(DatagramCommand::Apwr, 0, station_address(pos, 0x0103), &[1]).unwrap();
            }
        }
        b.push(
            DatagramCommand::Apwr,
            0,
            station_address(0u16.wrapping_sub(SLAVES as u16 - 1), 0x0200),
            &[0xFF, 0xFF],
        )
        .unwrap();
        let len = b.finish();
        for (i, e) in escs.iter_mut().enumerate() {
            e.process_frame(&mut buf[..len], Instant::from_micros(i as u64));
        }
        escs
    }

    fn memory(e: &Esc) -> Vec<u8> {
        let mut m = vec![0u8; 0x1100];
        e.peek(0, &mut m);
        m
    }

    proptest! {
        /// Skipping datagrams addressed to other stations changes nothing:
        /// the frame and every slave's memory end up as when each slave
        /// walks every datagram.
        #[test]
        fn indexed_walk_equals_the_full_walk(frames in prop::collection::vec(prop::collection::vec(datagram(), 1..12), 1..6)) {
            let (mut full, mut indexed) = (line(), line());
            let mut index = FrameIndex::default();
            for (k, datagrams) in frames.iter().enumerate() {
                let mut buf = [0u8; 1500];
                let mut b = FrameBuilder::new(&mut buf, [2; 6]);
                for (c, address, data) in datagrams {
                    b.push(*c, 0, *address, data).unwrap();
                }
                let len = b.finish();
                let (mut a, mut z) = (buf, buf);
                let off = frame::ethercat_offset(&a[..len]).unwrap();
                prop_assert!(index.build(&z[off..len]));
                for i in 0..SLAVES {
                    let t = FrameTiming::at(Instant::from_micros(100 * (k as u64 + 1) + i as u64));
                    let ra = full[i].process_ethercat(&mut a[off..len], &t);
                    let rz = indexed[i].process_indexed(&mut z[off..len], &t, &mut index);
                    prop_assert_eq!(ra.datagrams, rz.datagrams);
                }
                prop_assert_eq!(&a[..len], &z[..len], "the frame after the line");
                for i in 0..SLAVES {
                    prop_assert_eq!(memory(&full[i]), memory(&indexed[i]), "slave {}", i);
                    prop_assert_eq!(full[i].traffic(), indexed[i].traffic(), "slave {}", i);
                }
            }
        }
    }

    #[test]
    fn a_datagram_for_another_station_leaves_a_slave_untouched() {
        let mut escs = line();
        let mut buf = [0u8; 64];
        let mut b = FrameBuilder::new(&mut buf, [2; 6]);
        b.push(DatagramCommand::Fprd, 0, station_address(0x1001, 0x0010), &[0, 0]).unwrap();
        let len = b.finish();
        let off = frame::ethercat_offset(&buf[..len]).unwrap();
        let mut index = FrameIndex::default();
        assert!(index.build(&buf[off..len]));
        let t = FrameTiming::at(Instant::from_millis(1));
        assert!(!escs[0].process_indexed(&mut buf[off..len], &t, &mut index).touched);
        assert!(escs[1].process_indexed(&mut buf[off..len], &t, &mut index).touched);
        assert_eq!(u16::from_le_bytes([buf[off + 12], buf[off + 13]]), 0x1001, "station 0x1001 read itself");
    }
}
