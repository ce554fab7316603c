//! FoE: frames, packet numbering, BUSY, errors, timeouts, and the iPOS file
//! rules (manual §17.4.3-§17.4.7) expressed through `FileHandler` to show
//! the trait can carry them. The policy here is test code: the iPOS
//! personality owns the real one.

mod support;

use drivebus_base::{Duration, Instant};
use drivebus_coe::{AlState, FileHandler, FoeEnd, FoeError, FoeProgress, MailboxConfig};
use drivebus_od::NoHooks;
use support::{Dev, Fail, Rig, body, mbx, pattern, soem, test_od};

/// iPOS firmware passwords (§17.4.6).
const F515X: u32 = 0x3531_3546;
const FA0XX: u32 = 0x4130_3041;

/// What the iPOS takes over FoE.
#[derive(Debug, PartialEq, Eq, Clone, Copy)]
enum Kind {
    Setup,
    Firmware,
}

/// The iPOS file rules. `sw_in_boot` mirrors object 210Ch ("enable SW file
/// download": 1 = a setup file may come in BOOT, 0 = BOOT is for firmware).
struct IposFiles {
    firmware_password: u32,
    sw_in_boot: bool,
    /// Flash erase and programming times (BUSY while they run).
    erase: Duration,
    program: Duration,
    current: Option<Kind>,
    programming: bool,
    busy_until: Instant,
    received: Vec<u8>,
    stored: Vec<(Kind, Vec<u8>)>,
    ends: Vec<FoeEnd>,
}

impl IposFiles {
    fn new(firmware_password: u32) -> Self {
        IposFiles {
            firmware_password,
            sw_in_boot: false,
            erase: Duration::from_millis(30),
            program: Duration::from_millis(20),
            current: None,
            programming: false,
            busy_until: Instant::ZERO,
            received: Vec::new(),
            stored: Vec::new(),
            ends: Vec::new(),
        }
    }

    fn progress(&self, now: Instant, total: Duration) -> FoeProgress {
        let left = self.busy_until - now;
        let done = 100 - (100 * left.as_micros() / total.as_micros().max(1)) as u16;
        FoeProgress::Busy { done, entire: 100 }
    }
}

impl FileHandler for IposFiles {
    fn begin_write(
        &mut self,
        name: &[u8],
        password: u32,
        state: AlState,
        now: Instant,
    ) -> Result<(), FoeError> {
        let name = core::str::from_utf8(name).map_err(|_| FoeError::NOT_FOUND)?;
        let (stem, ext) = name.rsplit_once('.').unwrap_or((name, ""));
        let kind = if stem.starts_with("FOESW_") {
            // §17.4.3.1: at most 14 characters without the extension,
            // .bin or .efw, password 0, only in OP, PRE-OP and SAFE-OP
            // (in BOOT only with 210Ch = 1, §17.4.5).
            if stem.len() > 14 || !(ext.eq_ignore_ascii_case("bin") || ext.eq_ignore_ascii_case("efw")) {
                return Err(FoeError::NOT_FOUND);
            }
            if password != 0 {
                return Err(FoeError::ACCESS_DENIED);
            }
            if state == AlState::Boot && !self.sw_in_boot {
                return Err(FoeError::NOT_BOOTSTRAP);
            }
            Kind::Setup
        } else if name.starts_with("FOEFW_") {
            // §17.4.6: only in BOOT, with the password of the firmware
            // generation; 210Ch = 0 selects firmware in BOOT (§17.2.7).
            if state != AlState::Boot {
                return Err(FoeError::BOOTSTRAP_ONLY);
            }
            if password != self.firmware_password {
                return Err(FoeError::ACCESS_DENIED);
            }
            if self.sw_in_boot {
                return Err(FoeError::ILLEGAL);
            }
            // The flash is erased first (§17.4.6 warning).
            self.busy_until = now + self.erase;
            Kind::Firmware
        } else {
            return Err(FoeError::NOT_FOUND);
        };
        self.current = Some(kind);
        self.received.clear();
        Ok(())
    }

    fn write(&mut self, offset: u32, data: &[u8], now: Instant) -> Result<FoeProgress, FoeError> {
        if now < self.busy_until {
            return Ok(self.progress(now, self.erase));
        }
        assert_eq!(offset as usize, self.received.len(), "offsets follow the data");
        self.received.extend_from_slice(data);
        Ok(FoeProgress::Ready)
    }

    fn finish_write(&mut self, now: Instant) -> Result<FoeProgress, FoeError> {
        if self.current == Some(Kind::Firmware) && !self.programming {
            // Called after the last packet: programming starts.
            self.programming = true;
            self.busy_until = now + self.program;
        }
        if now < self.busy_until {
            return Ok(self.progress(now, self.program));
        }
        let kind = self.current.take().ok_or(FoeError::PROGRAM_ERROR)?;
        self.programming = false;
        self.stored.push((kind, core::mem::take(&mut self.received)));
        Ok(FoeProgress::Ready)
    }

    fn end(&mut self, how: FoeEnd) {
        self.current = None;
        self.programming = false;
        self.ends.push(how);
    }
}

fn rig(files: IposFiles) -> Rig<Dev, IposFiles> {
    Rig::new(MailboxConfig::default(), (test_od(), NoHooks), files)
}

fn write(r: &mut Rig<Dev, IposFiles>, name: &str, password: u32, data: &[u8]) -> Result<usize, Fail> {
    let mut busy = 0;
    soem::foe_write(r, name, password, data, &mut busy).map(|()| busy)
}

#[test]
fn setup_file_in_the_operational_states() {
    for state in [AlState::PreOp, AlState::SafeOp, AlState::Op] {
        let mut r = rig(IposFiles::new(F515X));
        r.state = state;
        let file = pattern(1000, 4);
        assert_eq!(write(&mut r, "FOESW_AXIS1.bin", 0, &file), Ok(0));
        assert_eq!(r.files.stored, [(Kind::Setup, file)]);
        assert_eq!(r.files.ends, [FoeEnd::Completed]);
        assert!(r.server.is_idle());
    }
    // 14 characters before the extension is the limit; .efw is allowed.
    let mut r = rig(IposFiles::new(F515X));
    assert_eq!(write(&mut r, "FOESW_12345678.efw", 0, b"x"), Ok(0));
}

#[test]
fn setup_file_refusals() {
    let mut r = rig(IposFiles::new(F515X));
    let refused = [
        ("FOESW_123456789.bin", 0, FoeError::NOT_FOUND),
        ("FOESW_SETUP.sw", 0, FoeError::NOT_FOUND),
        ("SETUP.bin", 0, FoeError::NOT_FOUND),
        ("FOESW_SETUP.bin", 1, FoeError::ACCESS_DENIED),
    ];
    for (name, pw, e) in refused {
        assert_eq!(write(&mut r, name, pw, b"data"), Err(Fail::FoeError(e.0)), "{name}");
    }
    // In BOOT only with 210Ch = 1 (§17.4.5).
    r.state = AlState::Boot;
    assert_eq!(write(&mut r, "FOESW_SETUP.bin", 0, b"data"), Err(Fail::FoeError(0x8009)));
    r.files.sw_in_boot = true;
    assert_eq!(write(&mut r, "FOESW_SETUP.bin", 0, b"data"), Ok(0));
    // A refusal at the request starts no transfer: no `end`.
    assert_eq!(r.files.ends, [FoeEnd::Completed]);
}

#[test]
fn firmware_only_in_boot_with_its_password() {
    let mut r = rig(IposFiles::new(F515X));
    let fw = pattern(5000, 7);
    assert_eq!(write(&mut r, "FOEFW_F515G", F515X, &fw), Err(Fail::FoeError(0x8008)));
    r.state = AlState::Boot;
    assert_eq!(write(&mut r, "FOEFW_F515G", FA0XX, &fw), Err(Fail::FoeError(0x8002)));
    r.files.sw_in_boot = true;
    assert_eq!(write(&mut r, "FOEFW_F515G", F515X, &fw), Err(Fail::FoeError(0x8004)));
    r.files.sw_in_boot = false;
    // Erase, then program: the master is told BUSY and repeats the packet
    // (SOEM's algorithm); every byte arrives once and in order.
    let busy = write(&mut r, "FOEFW_F515G", F515X, &fw).unwrap();
    assert!(busy >= 4, "BUSY while erasing and programming ({busy})");
    assert_eq!(r.files.stored, [(Kind::Firmware, fw)]);
    assert_eq!(r.files.ends, [FoeEnd::Completed]);
    // An FA0xx drive has the other password.
    let mut r = rig(IposFiles::new(FA0XX));
    r.state = AlState::Boot;
    // 3 BUSY while erasing (30 ms, SOEM retrying every 10 ms), 2 while
    // programming (20 ms).
    assert_eq!(write(&mut r, "FOEFW_FA00G", FA0XX, b"fw"), Ok(5));
}

#[test]
fn frames() {
    let mut r = rig(IposFiles::new(F515X));
    // WRQ: opcode 2, password, name → ACK 0 (opcode 4, packet 0).
    let mut wrq = vec![2, 0, 0, 0, 0, 0];
    wrq.extend_from_slice(b"FOESW_A.bin");
    assert_eq!(r.one(&mbx(4, 1, &wrq)), [6, 0, 0, 0, 0, 0x14, 4, 0, 0, 0, 0, 0]);
    // A full DATA (128 − 12 = 116 bytes) → ACK 1.
    let mut d = vec![3, 0, 1, 0, 0, 0];
    d.extend_from_slice(&[0xAB; 116]);
    assert_eq!(body(&r.one(&mbx(4, 2, &d))), [4, 0, 1, 0, 0, 0]);
    // The same packet again (our ACK got lost): ACK 1 again, not stored twice.
    assert_eq!(body(&r.one(&mbx(4, 3, &d))), [4, 0, 1, 0, 0, 0]);
    // Packet 3 instead of 2: ERR 8005h with its text, transfer over.
    let d3 = [3, 0, 3, 0, 0, 0, 1, 2];
    let mut err = vec![5, 0, 0x05, 0x80, 0, 0];
    err.extend_from_slice(b"Packet number wrong");
    assert_eq!(body(&r.one(&mbx(4, 4, &d3))), err);
    assert_eq!(r.files.ends, [FoeEnd::Error(FoeError::PACKET_NUMBER_WRONG)]);
    // Out of a transfer, DATA and ACK are illegal.
    assert_eq!(body(&r.one(&mbx(4, 5, &d3)))[..6], [5, 0, 0x04, 0x80, 0, 0]);
    // An unknown opcode is a mailbox error (service not supported).
    assert_eq!(r.one(&mbx(4, 6, &[9, 0, 0, 0, 0, 0])), [4, 0, 0, 0, 0, 0x60, 1, 0, 4, 0]);
    // Too short for the FoE header.
    assert_eq!(r.one(&mbx(4, 7, &[2, 0, 0])), [4, 0, 0, 0, 0, 0x70, 1, 0, 6, 0]);
}

#[test]
fn busy_frame_and_exact_multiple_file() {
    let mut r = rig(IposFiles::new(F515X));
    r.state = AlState::Boot;
    let mut wrq = vec![2, 0];
    wrq.extend_from_slice(&F515X.to_le_bytes());
    wrq.extend_from_slice(b"FOEFW_X");
    assert_eq!(body(&r.one(&mbx(4, 1, &wrq))), [4, 0, 0, 0, 0, 0]);
    let mut d = vec![3, 0, 1, 0, 0, 0];
    d.extend_from_slice(&[1; 116]);
    // Erasing: BUSY, done 1 (%) of 100.
    assert_eq!(body(&r.one(&mbx(4, 2, &d))), [6, 0, 1, 0, 100, 0]);
    r.tick(Duration::from_millis(30));
    assert_eq!(body(&r.one(&mbx(4, 3, &d))), [4, 0, 1, 0, 0, 0]);
    // The file was exactly one packet: an empty DATA ends it.
    let end = [3, 0, 2, 0, 0, 0];
    assert_eq!(body(&r.one(&mbx(4, 4, &end)))[0], 6, "programming");
    r.tick(Duration::from_millis(25));
    assert_eq!(body(&r.one(&mbx(4, 5, &end))), [4, 0, 2, 0, 0, 0]);
    assert_eq!(r.files.stored, [(Kind::Firmware, vec![1; 116])]);
}

#[test]
fn master_error_timeout_reset_and_new_request() {
    let mut r = rig(IposFiles::new(F515X));
    let mut wrq = vec![2, 0, 0, 0, 0, 0];
    wrq.extend_from_slice(b"FOESW_A.bin");
    r.one(&mbx(4, 1, &wrq));
    // The master's ERR ends it, unanswered.
    r.send(&mbx(4, 2, &[5, 0, 0x00, 0x80, 0, 0]));
    assert_eq!(r.read(), None);
    // A timeout ends it silently.
    r.one(&mbx(4, 3, &wrq));
    let deadline = r.server.poll(r.now, &mut r.files).unwrap();
    assert_eq!(r.server.poll(deadline, &mut r.files), None);
    assert_eq!(r.read(), None);
    // A mailbox reset, and a new WRQ in the middle of a transfer.
    r.one(&mbx(4, 4, &wrq));
    r.server.reset(&mut r.files);
    r.one(&mbx(4, 5, &wrq));
    assert_eq!(body(&r.one(&mbx(4, 6, &wrq))), [4, 0, 0, 0, 0, 0]);
    assert_eq!(
        r.files.ends,
        [FoeEnd::AbortedByMaster(0x8000), FoeEnd::Timeout, FoeEnd::Reset, FoeEnd::Reset]
    );
}

/// A device that serves one file for reading.
struct Log(Vec<u8>, Vec<FoeEnd>);
impl FileHandler for Log {
    fn begin_write(&mut self, _: &[u8], _: u32, _: AlState, _: Instant) -> Result<(), FoeError> {
        Err(FoeError::ACCESS_DENIED)
    }
    fn write(&mut self, _: u32, _: &[u8], _: Instant) -> Result<FoeProgress, FoeError> {
        Err(FoeError::ILLEGAL)
    }
    fn finish_write(&mut self, _: Instant) -> Result<FoeProgress, FoeError> {
        Err(FoeError::ILLEGAL)
    }
    fn begin_read(&mut self, name: &[u8], _: u32, _: AlState, _: Instant) -> Result<(), FoeError> {
        if name == b"log.txt" { Ok(()) } else { Err(FoeError::NOT_FOUND) }
    }
    fn read(&mut self, offset: u32, buf: &mut [u8], _: Instant) -> Result<usize, FoeError> {
        let rest = self.0.get(offset as usize..).unwrap_or(&[]);
        let k = rest.len().min(buf.len());
        buf[..k].copy_from_slice(&rest[..k]);
        Ok(k)
    }
    fn end(&mut self, how: FoeEnd) {
        self.1.push(how);
    }
}

#[test]
fn reading_a_file() {
    for len in [0, 5, 116, 300, 348] {
        let mut r =
            Rig::new(MailboxConfig::default(), (test_od(), NoHooks), Log(pattern(len, 2), Vec::new()));
        // NUL-terminated names are accepted.
        assert_eq!(soem::foe_read(&mut r, "log.txt\0", 0), Ok(pattern(len, 2)), "{len} bytes");
        assert_eq!(r.files.1, [FoeEnd::Completed]);
    }
    let mut r = Rig::new(MailboxConfig::default(), (test_od(), NoHooks), Log(pattern(300, 2), Vec::new()));
    assert_eq!(soem::foe_read(&mut r, "other", 0), Err(Fail::FoeError(0x8001)));
    // RRQ → DATA 1 (116 bytes); a wrong ACK number ends the transfer.
    let mut rrq = vec![1, 0, 0, 0, 0, 0];
    rrq.extend_from_slice(b"log.txt");
    let c = r.counter();
    let d1 = r.one(&mbx(4, c, &rrq));
    assert_eq!((d1.len(), &body(&d1)[..6]), (128, &[3, 0, 1, 0, 0, 0][..]));
    let c = r.counter();
    assert_eq!(body(&r.one(&mbx(4, c, &[4, 0, 2, 0, 0, 0])))[..6], [5, 0, 0x05, 0x80, 0, 0]);
    assert_eq!(r.files.1, [FoeEnd::Error(FoeError::PACKET_NUMBER_WRONG)]);
}
