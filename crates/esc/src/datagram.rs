//! Frame walking and command execution (ETG.1000.4 §5.4, ESC data sheet
//! Section I "EtherCAT protocol").
//!
//! Addressing: auto-increment commands (APxx, ARMW) act on the slave that
//! sees ADP = 0 and every slave increments ADP; configured-address commands
//! (FPxx, FRMW) act when ADP equals 0x0010, or the alias 0x0012 when DL
//! control 0x0103 bit 0 enables it; broadcasts act on every slave, which
//! also increment ADP. BRD/BRW OR the read data into the datagram.
//! ARMW/FRMW: the addressed slave reads, every other slave writes.
//!
//! Working counter: physical reads +1, writes +1, read-writes +1 for the
//! read and +2 for the write part; ARMW/FRMW +1 per slave that read or
//! wrote. Logical commands: +1 if any read FMMU delivered data and +2 if
//! any write FMMU stored data, so at most 3 per ESC however many FMMUs hit
//! (the ETG forum rule SOEM follows). Nothing counts unless at least one
//! byte was actually read or written (see `access.rs` for what counts).
//!
//! Read-write commands read first: the datagram returns memory as it was,
//! and memory receives the datagram as it arrived (for LRW this holds
//! across FMMUs too: all reads see memory before this datagram's writes).
//!
//! Every datagram's IRQ field is ORed with the ECAT event request masked by
//! the ECAT event mask (0x0210 & 0x0200).
//!
//! A frame is inconsistent when a datagram header or its data and working
//! counter do not fit in the EtherCAT length (or the buffer). Processing
//! stops there: earlier datagrams keep their results, that datagram and
//! everything after it stay untouched, and the ECAT processing unit error
//! counter (0x030C) counts the frame. Reserved command codes pass through
//! untouched.

use crate::esc::{Esc, EscTraffic, FrameReport, FrameTiming};
use crate::fmmu::Fmmu;
use crate::frame::{self, DATAGRAM_HEADER_LEN, DatagramCommand, DatagramHeader, ECAT_HEADER_LEN, TYPE_DLPDU};
use crate::registers::REGISTER_SPACE;
use crate::sm::Side;
use drivebus_base::Instant;

mod index;
pub use index::FrameIndex;

impl Esc {
    /// Processes an Ethernet frame in place, as if it arrived on port 0 at
    /// `now` and left again through port 0. Non-EtherCAT frames are left
    /// alone. Sets the locally administered bit of the source MAC of
    /// EtherCAT frames (the reply marker masters look for).
    pub fn process_frame(&mut self, frame: &mut [u8], now: Instant) -> FrameReport {
        self.advance(now);
        let Some(off) = frame::ethercat_offset(frame) else {
            return FrameReport { ignored: true, ..FrameReport::default() };
        };
        let r = self.process_ethercat(&mut frame[off..], &FrameTiming::at(now));
        if !r.ignored {
            frame::mark_reply_source(frame);
        }
        r
    }

    /// Processes an EtherCAT payload in place (from the 2-byte EtherCAT
    /// header on) with explicit timing, as a segment does.
    pub fn process_ethercat(&mut self, payload: &mut [u8], timing: &FrameTiming) -> FrameReport {
        self.advance(timing.at);
        self.timing = *timing;
        self.frame_no += 1;
        let mut report = FrameReport::default();
        let Some((len, kind)) = frame::ecat_header(payload) else {
            report.malformed = true;
            self.count_frame_error();
            return report;
        };
        if kind != TYPE_DLPDU {
            report.ignored = true;
            return report;
        }
        {
            let (head, _) = self.mem.split_at_mut(REGISTER_SPACE);
            self.sii.start_of_frame(head);
        }
        let end = ECAT_HEADER_LEN + len;
        if end > payload.len() {
            report.malformed = true;
        }
        let end = end.min(payload.len());
        let mut pos = ECAT_HEADER_LEN;
        loop {
            let Some(h) = payload.get(pos..end).and_then(DatagramHeader::parse) else {
                report.malformed = true;
                break;
            };
            let total = h.total_len();
            if pos + total > end {
                report.malformed = true;
                break;
            }
            self.execute(&mut payload[pos..pos + total], &h);
            report.datagrams += 1;
            report.touched = true;
            self.traffic.datagrams += 1;
            pos += total;
            if !h.more {
                break;
            }
        }
        if report.malformed {
            self.count_frame_error();
        }
        if self.reset_stage.0 == 3 {
            self.reset_stage = (0, 0);
            self.reset();
        }
        report
    }

    /// Frames, datagrams and working counter increments since power-up.
    pub fn traffic(&self) -> EscTraffic {
        EscTraffic { frames: self.frame_no, ..self.traffic }
    }

    fn count_frame_error(&mut self) {
        self.mem[0x030C] = self.mem[0x030C].saturating_add(1);
    }

    pub(crate) fn execute(&mut self, d: &mut [u8], h: &DatagramHeader) {
        let irq = u16::from_le_bytes([self.mem[0x0210], self.mem[0x0211]])
            & u16::from_le_bytes([self.mem[0x0200], self.mem[0x0201]]);
        if irq != 0 {
            d[8..10].copy_from_slice(&(h.irq | irq).to_le_bytes());
        }
        let Some(cmd) = DatagramCommand::from_u8(h.command) else {
            return;
        };
        let len = usize::from(h.len);
        let (head, rest) = d.split_at_mut(DATAGRAM_HEADER_LEN);
        let (data, wkc_bytes) = rest.split_at_mut(len);
        let adp = h.adp();
        let ado = usize::from(h.ado());
        let add = match cmd {
            DatagramCommand::Nop => 0,
            DatagramCommand::Aprd | DatagramCommand::Apwr | DatagramCommand::Aprw | DatagramCommand::Armw => {
                head[2..4].copy_from_slice(&adp.wrapping_add(1).to_le_bytes());
                self.physical(cmd, adp == 0, ado, data)
            }
            DatagramCommand::Fprd | DatagramCommand::Fpwr | DatagramCommand::Fprw | DatagramCommand::Frmw => {
                let station = u16::from_le_bytes([self.mem[0x0010], self.mem[0x0011]]);
                let me = adp == station
                    || (self.mem[0x0103] & 1 != 0
                        && adp == u16::from_le_bytes([self.mem[0x0012], self.mem[0x0013]]));
                self.physical(cmd, me, ado, data)
            }
            DatagramCommand::Brd | DatagramCommand::Bwr | DatagramCommand::Brw => {
                head[2..4].copy_from_slice(&adp.wrapping_add(1).to_le_bytes());
                self.physical(cmd, true, ado, data)
            }
            DatagramCommand::Lrd | DatagramCommand::Lwr | DatagramCommand::Lrw => {
                self.logical(cmd, h.address, data)
            }
        };
        if add != 0 {
            self.traffic.wkc += u64::from(add);
            let wkc = u16::from_le_bytes([wkc_bytes[0], wkc_bytes[1]]).wrapping_add(add);
            wkc_bytes.copy_from_slice(&wkc.to_le_bytes());
        }
    }

    fn physical(&mut self, cmd: DatagramCommand, me: bool, ado: usize, data: &mut [u8]) -> u16 {
        let n = data.len();
        match cmd {
            DatagramCommand::Aprd | DatagramCommand::Fprd if me => {
                u16::from(self.read(Side::Ecat, ado, data) > 0)
            }
            DatagramCommand::Apwr | DatagramCommand::Fpwr | DatagramCommand::Bwr if me => {
                u16::from(self.write(Side::Ecat, ado, data) > 0)
            }
            DatagramCommand::Aprw | DatagramCommand::Fprw if me => {
                let mut tmp = core::mem::take(&mut self.scratch);
                tmp[..n].copy_from_slice(data);
                let r = self.read(Side::Ecat, ado, data) > 0;
                let w = self.write(Side::Ecat, ado, &tmp[..n]) > 0;
                self.scratch = tmp;
                u16::from(r) + 2 * u16::from(w)
            }
            DatagramCommand::Brd | DatagramCommand::Brw => {
                let mut tmp = core::mem::take(&mut self.scratch);
                tmp[..n].fill(0);
                let r = self.read(Side::Ecat, ado, &mut tmp[..n]) > 0;
                let w = cmd == DatagramCommand::Brw && self.write(Side::Ecat, ado, data) > 0;
                data.iter_mut().zip(&tmp[..n]).for_each(|(d, t)| *d |= *t);
                self.scratch = tmp;
                u16::from(r) + 2 * u16::from(w)
            }
            DatagramCommand::Armw | DatagramCommand::Frmw => {
                if me {
                    u16::from(self.read(Side::Ecat, ado, data) > 0)
                } else {
                    u16::from(self.write(Side::Ecat, ado, data) > 0)
                }
            }
            _ => 0,
        }
    }

    fn logical(&mut self, cmd: DatagramCommand, addr: u32, data: &mut [u8]) -> u16 {
        let (want_read, want_write) = match cmd {
            DatagramCommand::Lrd => (true, false),
            DatagramCommand::Lwr => (false, true),
            _ => (true, true),
        };
        let n = data.len();
        // LRW: the writes use the datagram as it arrived, the reads replace
        // it; keep a copy (on the stack) only when both happen.
        let hits = |f: &Fmmu| f.map(addr, n).is_some();
        let both = want_read
            && want_write
            && (0..self.fmmu_n).any(|k| self.fmmus[usize::from(self.fmmu_active[k])].write)
            && (0..self.fmmu_n).any(|k| {
                let f = &self.fmmus[usize::from(self.fmmu_active[k])];
                f.read && hits(f)
            });
        let mut snapshot = core::mem::take(&mut self.scratch);
        if both {
            snapshot[..n].copy_from_slice(data);
        }
        let mut read_hit = false;
        let mut write_hit = false;
        if want_read {
            for k in 0..self.fmmu_n {
                let f = self.fmmus[usize::from(self.fmmu_active[k])];
                if !f.read {
                    continue;
                }
                let Some(m) = f.map(addr, n) else { continue };
                if let Some((fo, po, len)) = m.byte_aligned() {
                    read_hit |= self.read(Side::Ecat, po as usize, &mut data[fo..fo + len]) > 0;
                } else {
                    read_hit |= m.for_each_read(data, |a| {
                        let mut b = [0u8];
                        (self.read(Side::Ecat, a as usize, &mut b) == 1).then_some(b[0])
                    });
                }
            }
        }
        if want_write {
            let src: &[u8] = if both { &snapshot[..n] } else { data };
            for k in 0..self.fmmu_n {
                let f = self.fmmus[usize::from(self.fmmu_active[k])];
                if !f.write {
                    continue;
                }
                let Some(m) = f.map(addr, n) else { continue };
                if let Some((fo, po, len)) = m.byte_aligned() {
                    write_hit |= self.write(Side::Ecat, po as usize, &src[fo..fo + len]) > 0;
                } else {
                    m.for_each_write(src, |a, mask, v| {
                        write_hit |= self.write_masked(Side::Ecat, a as usize, &[v], mask) > 0;
                    });
                }
            }
        }
        self.scratch = snapshot;
        u16::from(read_hit) + 2 * u16::from(write_hit)
    }
}
