//! The `drive_mailbox` fuzz target's harness (`fuzz/fuzz_targets/
//! drive_mailbox.rs`), shared with the test that runs it over the seed
//! corpus and random inputs on stable (`tests/drive_fuzz.rs`).
//!
//! A drive slave on a segment (byte 0: bit 0 set = generic, else iPOS),
//! its mailbox set up and in PRE-OP, then records `[tag, len u16 LE,
//! payload]`:
//!
//! * tag % 4 = 0: `payload` written into SM0 as a request mailbox (padded
//!   to the mailbox length; what the master's FPWR carries);
//! * tag % 4 = 1: SM1 read if full (up to `payload[0] % 8 + 1` times);
//! * tag % 4 = 2: time passes: `payload[0]` ms, polled on the way;
//! * tag % 4 = 3: AL control := `payload[0]` (any state, any bits).
//!
//! Checked: nothing panics; every message read from SM1 has a length
//! field that fits the mailbox and a known type; afterwards, back in
//! INIT and PRE-OP, an expedited upload of 1000h answers the device type.

use super::{DriveSlaveSpec, slave};
use crate::host::BoxDevice;
use drivebus_can::{Duration, Instant};
use drivebus_esc::frame::{DatagramCommand, FrameBuilder, datagrams, position_address, station_address};
use drivebus_esc::segment::{Segment, SegmentConfig};
use drivebus_personality::Profile;

const ADDR: u16 = 0x1000;
const MBX: usize = 512;

struct Line {
    seg: Segment<BoxDevice>,
    now: Instant,
    buf: Vec<u8>,
}

impl Line {
    fn dg(&mut self, cmd: DatagramCommand, addr: u32, data: &[u8]) -> (Vec<u8>, u16) {
        self.now += Duration::from_micros(20);
        let n = {
            let mut b = FrameBuilder::new(&mut self.buf, [0x10; 6]);
            if b.push(cmd, 1, addr, data).is_err() {
                return (Vec::new(), 0);
            }
            b.finish()
        };
        self.seg.process_frame(&mut self.buf[..n], self.now);
        self.seg.poll(self.now);
        match datagrams(&self.buf[14..n]).next() {
            Some(d) => (d.data.to_vec(), d.wkc),
            None => (Vec::new(), 0),
        }
    }

    fn wr(&mut self, ado: u16, data: &[u8]) {
        self.dg(DatagramCommand::Fpwr, station_address(ADDR, ado), data);
    }

    fn rd(&mut self, ado: u16, len: usize) -> Vec<u8> {
        self.dg(DatagramCommand::Fprd, station_address(ADDR, ado), &vec![0; len]).0
    }

    fn mailbox_sms(&mut self) {
        for (n, start, ctrl) in [(0u16, 0x1000u16, 0x26u8), (1, 0x1200, 0x22)] {
            self.wr(0x0806 + 8 * n, &[0]);
            let mut b = [0u8; 8];
            b[..2].copy_from_slice(&start.to_le_bytes());
            b[2..4].copy_from_slice(&(MBX as u16).to_le_bytes());
            b[4] = ctrl;
            b[6] = 1;
            self.wr(0x0800 + 8 * n, &b);
        }
    }

    fn state(&mut self, s: u8) {
        self.wr(0x0120, &[s, 0]);
        self.tick(2);
    }

    fn tick(&mut self, ms: u64) {
        let end = self.now + Duration::from_millis(ms);
        while let Some(n) = self.seg.poll(self.now).filter(|n| *n > self.now && *n <= end) {
            self.now = n;
        }
        self.now = end;
        self.seg.poll(self.now);
    }

    /// SM1's message if it is full.
    fn read(&mut self) -> Option<Vec<u8>> {
        if self.rd(0x080D, 1).first().is_some_and(|s| s & 0x08 != 0) {
            let m = self.rd(0x1200, MBX);
            let len = usize::from(u16::from_le_bytes([m[0], m[1]]));
            assert!(6 + len <= MBX, "length field {len} beyond the mailbox");
            assert!(matches!(m[5] & 0x0F, 0x00 | 0x03 | 0x04), "mailbox type {:02X}", m[5]);
            return Some(m[..6 + len].to_vec());
        }
        None
    }
}

/// Runs one fuzz input (see the module docs); panics on a finding.
pub fn drive_mailbox(data: &[u8]) {
    let profile = if data.first().is_some_and(|b| b & 1 == 1) { Profile::Generic } else { Profile::Ipos };
    let Ok(s) = slave(&DriveSlaveSpec::new(profile, 1)) else { panic!("the drive builds") };
    let mut l = Line {
        seg: Segment::with_devices(SegmentConfig::default(), vec![Box::new(s) as BoxDevice]),
        now: Instant::ZERO,
        buf: vec![0u8; 1514],
    };
    l.seg.poll(l.now);
    l.dg(DatagramCommand::Apwr, position_address(0, 0x0010), &ADDR.to_le_bytes());
    l.mailbox_sms();
    l.state(0x02);
    let mut p = 1;
    while p + 3 <= data.len() {
        let tag = data[p];
        let len = usize::from(u16::from_le_bytes([data[p + 1], data[p + 2]]));
        p += 3;
        let end = (p + len).min(data.len());
        let payload = &data[p..end];
        p = end;
        match tag % 4 {
            0 => {
                let mut m = payload.to_vec();
                m.resize(MBX, 0);
                l.wr(0x1000, &m);
            }
            1 => {
                for _ in 0..=payload.first().map_or(0, |n| n % 8) {
                    l.read();
                }
            }
            2 => l.tick(u64::from(payload.first().copied().unwrap_or(1))),
            _ => l.state(payload.first().copied().unwrap_or(0x02)),
        }
    }
    // Back to a known state: INIT is always taken, then PRE-OP.
    l.state(0x11);
    l.mailbox_sms();
    l.state(0x12);
    l.tick(20);
    let req = [10, 0, 0, 0, 0, 0x03, 0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0];
    l.wr(0x1000, &{
        let mut m = req.to_vec();
        m.resize(MBX, 0);
        m
    });
    let mut answer = None;
    for _ in 0..200 {
        if let Some(m) = l.read() {
            // Emergencies may still come first.
            if m.len() >= 8 && m[5] & 0x0F == 3 && m[7] >> 4 == 1 {
                continue;
            }
            answer = Some(m);
            break;
        }
        l.tick(1);
    }
    let m = answer.expect("an answer to the upload of 1000h");
    let want = profile.info().device_type.to_le_bytes();
    assert_eq!(
        &m[6..16],
        &[0x00, 0x30, 0x43, 0x00, 0x10, 0x00, want[0], want[1], want[2], want[3]],
        "{m:02X?}"
    );
}
