//! A register-level master for one drive slave: every access is a frame
//! through the ESC (FPRD/FPWR with the configured address), time moves
//! only when the rig says so. Mailbox and CoE helpers build the requests
//! as ETG.1000.4/.6 define them.

#![allow(dead_code)]

use drivebus_can::{Duration, Instant};
use drivebus_esc::frame::{DatagramCommand, FrameBuilder, datagrams, position_address, station_address};
use drivebus_ethercat::drive::{DriveSlave, DriveSlaveSpec, slave};
use drivebus_personality::Profile;

pub const ADDR: u16 = 0x1000;
pub const MBX_OUT: u16 = 0x1000;
pub const MBX_IN: u16 = 0x1200;
pub const MBX_LEN: usize = 512;
pub const PD_OUT: u16 = 0x1400;
pub const PD_IN: u16 = 0x1800;

/// AL states as AL control writes them.
pub mod al {
    pub const INIT: u8 = 1;
    pub const PREOP: u8 = 2;
    pub const BOOT: u8 = 3;
    pub const SAFEOP: u8 = 4;
    pub const OP: u8 = 8;
    pub const ACK: u8 = 0x10;
}

/// What a mailbox exchange gave instead of data.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fail {
    Abort(u32),
    MailboxError(u16),
    NoResponse,
    Unexpected(Vec<u8>),
}

pub struct Rig {
    pub s: DriveSlave,
    pub t: Instant,
    cnt: u8,
    /// SM2/SM3 lengths as configured.
    pub pd: (u16, u16),
    /// CoE emergencies seen while waiting for responses: (code, register, data).
    pub emergencies: Vec<(u16, u8, [u8; 5])>,
}

impl Rig {
    pub fn new(profile: Profile) -> Rig {
        Rig::with_spec(&DriveSlaveSpec::new(profile, 7))
    }

    pub fn with_spec(spec: &DriveSlaveSpec) -> Rig {
        let mut r =
            Rig { s: slave(spec).unwrap(), t: Instant::ZERO, cnt: 0, pd: (0, 0), emergencies: Vec::new() };
        r.s.poll(r.t);
        r.dg(DatagramCommand::Apwr, position_address(0, 0x0010), &ADDR.to_le_bytes());
        r
    }

    /// One datagram in its own frame; the slave's firmware runs after it.
    pub fn dg(&mut self, cmd: DatagramCommand, addr: u32, data: &[u8]) -> (Vec<u8>, u16) {
        self.t += Duration::from_micros(20);
        let mut buf = vec![0u8; 64 + data.len()];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
        b.push(cmd, 1, addr, data).unwrap();
        let n = b.finish();
        self.s.esc_mut().process_frame(&mut buf[..n], self.t);
        self.s.poll(self.t);
        let d = datagrams(&buf[14..n]).next().unwrap();
        (d.data.to_vec(), d.wkc)
    }

    pub fn rd(&mut self, ado: u16, len: usize) -> Vec<u8> {
        self.dg(DatagramCommand::Fprd, station_address(ADDR, ado), &vec![0; len]).0
    }

    pub fn rd16(&mut self, ado: u16) -> u16 {
        let b = self.rd(ado, 2);
        u16::from_le_bytes([b[0], b[1]])
    }

    pub fn wr(&mut self, ado: u16, data: &[u8]) -> u16 {
        self.dg(DatagramCommand::Fpwr, station_address(ADDR, ado), data).1
    }

    /// Time passes; the firmware runs at every deadline on the way.
    pub fn tick(&mut self, d: Duration) {
        let end = self.t + d;
        while let Some(n) = self.s.poll(self.t).filter(|n| *n <= end && *n > self.t) {
            self.t = n;
        }
        self.t = end;
        self.s.poll(self.t);
    }

    fn sm(&mut self, n: u16, start: u16, len: u16, control: u8) {
        // Deactivated first: an enabled SM keeps its configuration.
        self.wr(0x0806 + 8 * n, &[0]);
        let mut b = [0u8; 8];
        b[..2].copy_from_slice(&start.to_le_bytes());
        b[2..4].copy_from_slice(&len.to_le_bytes());
        b[4] = control;
        b[6] = 1;
        self.wr(0x0800 + 8 * n, &b);
    }

    /// SM0/SM1 as the SII says (512 bytes at 0x1000/0x1200).
    pub fn mailbox_sms(&mut self) {
        self.sm(0, MBX_OUT, MBX_LEN as u16, 0x26);
        self.sm(1, MBX_IN, MBX_LEN as u16, 0x22);
    }

    /// SM2/SM3 for `out`/`inp` bytes; SM2 with the watchdog when `wd`.
    pub fn pd_sms(&mut self, out: u16, inp: u16, wd: bool) {
        self.pd = (out, inp);
        self.sm(2, PD_OUT, out, if wd { 0x64 } else { 0x24 });
        self.sm(3, PD_IN, inp, 0x20);
    }

    /// Writes AL control, lets the firmware act, returns (AL status, AL status code).
    pub fn request(&mut self, state: u8) -> (u16, u16) {
        self.wr(0x0120, &[state, 0]);
        self.tick(Duration::from_millis(2));
        let b = self.rd(0x0130, 6);
        (u16::from_le_bytes([b[0], b[1]]), u16::from_le_bytes([b[4], b[5]]))
    }

    /// INIT → PRE-OP with the mailbox set up.
    pub fn preop(&mut self) {
        self.mailbox_sms();
        assert_eq!(self.request(al::PREOP), (0x02, 0), "PRE-OP");
    }

    /// PRE-OP → SAFE-OP with SM2/SM3 sized from the current mapping.
    pub fn safeop(&mut self) -> (u16, u16) {
        let sizes = drivebus_esc::slave::SlaveApp::process_data_sizes(self.s.app());
        let (o, i) = (sizes.output_bytes() as u16, sizes.input_bytes() as u16);
        self.pd_sms(o, i, true);
        assert_eq!(self.request(al::SAFEOP), (0x04, 0), "SAFE-OP");
        (o, i)
    }

    pub fn counter(&mut self) -> u8 {
        self.cnt = if self.cnt >= 7 { 1 } else { self.cnt + 1 };
        self.cnt
    }

    /// Writes a whole request mailbox into SM0.
    pub fn send(&mut self, msg: &[u8]) {
        let mut m = msg.to_vec();
        m.resize(MBX_LEN, 0);
        self.wr(MBX_OUT, &m);
    }

    /// The next message from SM1 (waits up to 100 ms of simulated time).
    pub fn read_any(&mut self) -> Option<Vec<u8>> {
        for _ in 0..100 {
            if self.rd(0x080D, 1)[0] & 0x08 != 0 {
                let m = self.rd(MBX_IN, MBX_LEN);
                let len = 6 + usize::from(u16::from_le_bytes([m[0], m[1]]));
                return Some(m[..len.min(MBX_LEN)].to_vec());
            }
            self.tick(Duration::from_millis(1));
        }
        None
    }

    /// The next message that is not a CoE emergency (those are collected).
    pub fn read(&mut self) -> Option<Vec<u8>> {
        loop {
            let m = self.read_any()?;
            if is_emergency(&m) {
                let c = u16::from_le_bytes([m[8], m[9]]);
                self.emergencies.push((c, m[10], [m[11], m[12], m[13], m[14], m[15]]));
                continue;
            }
            return Some(m);
        }
    }

    /// Waits for emergencies (they go out when the mailbox is idle).
    pub fn collect_emergencies(&mut self, d: Duration) {
        let end = self.t + d;
        while self.t < end {
            if let Some(m) = self.read_any() {
                assert!(is_emergency(&m), "unexpected mailbox {m:02X?}");
                let c = u16::from_le_bytes([m[8], m[9]]);
                self.emergencies.push((c, m[10], [m[11], m[12], m[13], m[14], m[15]]));
            }
        }
    }

    pub fn one(&mut self, msg: &[u8]) -> Vec<u8> {
        self.send(msg);
        self.read().expect("a response")
    }

    /// SDO upload (expedited, normal or segmented).
    pub fn up(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, Fail> {
        self.upload(index, sub, false)
    }

    /// SDO upload, complete access when `ca` (from sub 0, SOEM-style).
    pub fn upload(&mut self, index: u16, sub: u8, ca: bool) -> Result<Vec<u8>, Fail> {
        let c = self.counter();
        let i = index.to_le_bytes();
        let m =
            self.one(&coe(c, &[0x00, 0x20, 0x40 | if ca { 0x10 } else { 0 }, i[0], i[1], sub, 0, 0, 0, 0]));
        let b = check(&m)?;
        if b[2] & 0x02 != 0 {
            let n = 4 - usize::from((b[2] >> 2) & 3);
            return Ok(b[6..6 + n].to_vec());
        }
        let size = u32::from_le_bytes([b[6], b[7], b[8], b[9]]) as usize;
        let len = usize::from(u16::from_le_bytes([m[0], m[1]]));
        let mut out = b[10..(len + 6 - 6).min(b.len())].to_vec();
        out.truncate(size);
        let mut toggle = 0u8;
        while out.len() < size {
            let c = self.counter();
            let m = self.one(&coe(c, &[0x00, 0x20, 0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]));
            let b = check(&m)?;
            let len = usize::from(u16::from_le_bytes([m[0], m[1]]));
            let n = if len == 10 { 7 - usize::from((b[2] >> 1) & 7) } else { len - 3 };
            out.extend_from_slice(&b[3..3 + n]);
            toggle ^= 0x10;
        }
        Ok(out)
    }

    /// SDO download (expedited up to 4 bytes, else normal).
    pub fn down(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), Fail> {
        let c = self.counter();
        let i = index.to_le_bytes();
        let msg = if data.len() <= 4 {
            let mut d = [0u8; 4];
            d[..data.len()].copy_from_slice(data);
            let cmd = 0x23 | ((4 - data.len() as u8) << 2);
            coe(c, &[0x00, 0x20, cmd, i[0], i[1], sub, d[0], d[1], d[2], d[3]])
        } else {
            // Normal initiate with as much as fits, then segments
            // (ETG.1000.6 download segment: 7 data bytes minimum).
            let first = data.len().min(MBX_LEN - 16);
            let mut b = vec![0x00, 0x20, 0x21, i[0], i[1], sub];
            b.extend_from_slice(&(data.len() as u32).to_le_bytes());
            b.extend_from_slice(&data[..first]);
            let m = self.one(&coe(c, &b));
            check(&m)?;
            let mut pos = first;
            let mut toggle = 0u8;
            while pos < data.len() {
                let n = (data.len() - pos).min(MBX_LEN - 9);
                let last = pos + n == data.len();
                let pad = 7usize.saturating_sub(n);
                let cmd = toggle | ((pad as u8) << 1) | u8::from(last);
                let mut seg = vec![0x00, 0x20, cmd];
                seg.extend_from_slice(&data[pos..pos + n]);
                seg.resize(3 + n + pad, 0);
                let c = self.counter();
                let m = self.one(&coe(c, &seg));
                let b = check(&m)?;
                if b[2] & 0xE0 != 0x20 {
                    return Err(Fail::Unexpected(m));
                }
                pos += n;
                toggle ^= 0x10;
            }
            return Ok(());
        };
        let m = self.one(&msg);
        let b = check(&m)?;
        if b[2] == 0x60 { Ok(()) } else { Err(Fail::Unexpected(m)) }
    }

    pub fn up_u32(&mut self, index: u16, sub: u8) -> u32 {
        let v = self.up(index, sub).unwrap_or_else(|e| panic!("{index:04X}:{sub}: {e:?}"));
        let mut b = [0u8; 4];
        b[..v.len().min(4)].copy_from_slice(&v[..v.len().min(4)]);
        u32::from_le_bytes(b)
    }

    /// Outputs into SM2; inputs from SM3.
    pub fn outputs(&mut self, data: &[u8]) {
        self.wr(PD_OUT, data);
    }

    /// The whole SM3 buffer (reading its last byte frees it for new inputs).
    pub fn inputs(&mut self) -> Vec<u8> {
        let n = usize::from(self.pd.1);
        self.rd(PD_IN, n)
    }
}

/// A CoE mailbox with counter `c`.
pub fn coe(c: u8, body: &[u8]) -> Vec<u8> {
    mbx(0x03, c, body)
}

/// A mailbox of type `t` with counter `c`.
pub fn mbx(t: u8, c: u8, body: &[u8]) -> Vec<u8> {
    let l = (body.len() as u16).to_le_bytes();
    let mut v = vec![l[0], l[1], 0, 0, 0, t | (c << 4)];
    v.extend_from_slice(body);
    v
}

pub fn is_emergency(m: &[u8]) -> bool {
    m.len() >= 16 && m[5] & 0x0F == 3 && m[7] >> 4 == 1
}

/// The CoE body of an SDO response, or why there is none.
pub fn check(m: &[u8]) -> Result<&[u8], Fail> {
    if m[5] & 0x0F == 0 {
        return Err(Fail::MailboxError(u16::from_le_bytes([m[8], m[9]])));
    }
    let b = &m[6..];
    if b.len() >= 10 && b[2] == 0x80 {
        return Err(Fail::Abort(u32::from_le_bytes([b[6], b[7], b[8], b[9]])));
    }
    Ok(b)
}

/// How an FoE write ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FoeResult {
    /// Every packet acknowledged; BUSY answers on the way.
    Done { busy: usize },
    /// The drive answered ERR with this code.
    Error(u32),
    /// A mailbox error.
    Mailbox(u16),
    /// No answer.
    NoResponse,
}

impl Rig {
    /// SOEM's `ecx_FOEwrite`: WRQ, DATA packets of SM0 − 12 bytes (an
    /// empty last one after a full one), the same packet again after a
    /// BUSY (10 ms later).
    pub fn foe_write(&mut self, name: &str, password: u32, data: &[u8]) -> FoeResult {
        let maxdata = MBX_LEN - 12;
        let c = self.counter();
        let mut b = vec![2u8, 0];
        b.extend_from_slice(&password.to_le_bytes());
        b.extend_from_slice(name.as_bytes());
        self.send(&mbx(0x04, c, &b));
        let (mut sent, mut pos, mut seg, mut busy) = (0u32, 0usize, 0usize, 0usize);
        let mut final_zero = true;
        loop {
            let Some(m) = self.read() else { return FoeResult::NoResponse };
            if m[5] & 0x0F == 0 {
                return FoeResult::Mailbox(u16::from_le_bytes([m[8], m[9]]));
            }
            let b = &m[6..];
            let word = u32::from_le_bytes([b[2], b[3], b[4], b[5]]);
            match b[0] {
                4 if word == sent => {
                    let k = (data.len() - pos).min(maxdata);
                    if k == 0 && !final_zero {
                        return FoeResult::Done { busy };
                    }
                    final_zero = pos + k == data.len() && k == maxdata;
                    seg = k;
                }
                6 if sent > 0 => {
                    busy += 1;
                    self.tick(Duration::from_millis(10));
                    pos -= seg;
                    sent -= 1;
                    let k = (data.len() - pos).min(maxdata);
                    final_zero = pos + k == data.len() && k == maxdata;
                    seg = k;
                }
                5 => return FoeResult::Error(word),
                _ => return FoeResult::Error(0),
            }
            sent += 1;
            let c = self.counter();
            let mut d = vec![3u8, 0];
            d.extend_from_slice(&sent.to_le_bytes());
            d.extend_from_slice(&data[pos..pos + seg]);
            pos += seg;
            self.send(&mbx(0x04, c, &d));
        }
    }
}
