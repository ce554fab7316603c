//! Every SDO abort the CoE server sends, and the device's own codes passed
//! through unchanged (ETG.1000.6 §5.6.2.7; codes of CiA 301 and the
//! EtherCAT additions).

mod support;

use drivebus_base::Duration;
use drivebus_coe::coe::abort;
use drivebus_coe::{MailboxConfig, NoFiles, ObjectAccess};
use drivebus_od::{NoHooks, ObjectDictionary, SdoAbort};
use support::{Dev, Rig, body, mbx, pattern, test_od};

fn rig() -> Rig<Dev, NoFiles> {
    Rig::new(MailboxConfig::default(), (test_od(), NoHooks), NoFiles)
}

/// An SDO request body: CoE header, command, index, sub-index, 4 bytes.
fn sdo(cmd: u8, index: u16, sub: u8, data: [u8; 4]) -> Vec<u8> {
    let i = index.to_le_bytes();
    vec![0x00, 0x20, cmd, i[0], i[1], sub, data[0], data[1], data[2], data[3]]
}

/// Send a CoE body, return the abort code (panics on anything else).
fn abort_of<A: ObjectAccess>(r: &mut Rig<A, NoFiles>, b: &[u8]) -> (u16, u8, SdoAbort) {
    let c = r.counter();
    let m = r.one(&mbx(3, c, b));
    let b = body(&m);
    assert_eq!((b[0], b[1], b[2]), (0x00, 0x20, 0x80), "an abort: {m:02X?}");
    (u16::from_le_bytes([b[3], b[4]]), b[5], SdoAbort(u32::from_le_bytes([b[6], b[7], b[8], b[9]])))
}

fn ok<A: ObjectAccess>(r: &mut Rig<A, NoFiles>, b: &[u8]) -> Vec<u8> {
    let c = r.counter();
    let m = r.one(&mbx(3, c, b));
    assert_ne!(body(&m)[2], 0x80, "unexpected abort {m:02X?}");
    body(&m).to_vec()
}

/// A normal download initiate: 21h, complete size, data.
fn normal(index: u16, sub: u8, total: u32, data: &[u8]) -> Vec<u8> {
    let mut b = sdo(0x21, index, sub, total.to_le_bytes());
    b.extend_from_slice(data);
    b
}

#[test]
fn access_and_existence() {
    let mut r = rig();
    assert_eq!(abort_of(&mut r, &sdo(0x40, 0x2002, 0, [0; 4])), (0x2002, 0, SdoAbort::READ_WRITE_ONLY));
    assert_eq!(abort_of(&mut r, &sdo(0x23, 0x1000, 0, [0; 4])), (0x1000, 0, SdoAbort::WRITE_READ_ONLY));
    assert_eq!(abort_of(&mut r, &sdo(0x40, 0x1018, 7, [0; 4])).2, SdoAbort::NO_SUB_INDEX);
    assert_eq!(abort_of(&mut r, &sdo(0x40, 0x4321, 0, [0; 4])).2, SdoAbort::NO_OBJECT);
}

#[test]
fn values_and_lengths() {
    let mut r = rig();
    assert_eq!(abort_of(&mut r, &sdo(0x2B, 0x2003, 0, [101, 0, 0, 0])).2, SdoAbort::VALUE_TOO_HIGH);
    assert_eq!(abort_of(&mut r, &sdo(0x2B, 0x2003, 0, [0x9B, 0xFF, 0, 0])).2, SdoAbort::VALUE_TOO_LOW);
    // Expedited with the size indicated: 4 bytes to an INTEGER16, 1 byte.
    assert_eq!(abort_of(&mut r, &sdo(0x23, 0x2003, 0, [1, 0, 0, 0])).2, SdoAbort::DATA_TOO_LONG);
    assert_eq!(abort_of(&mut r, &sdo(0x2F, 0x2003, 0, [1, 0, 0, 0])).2, SdoAbort::DATA_TOO_SHORT);
    // Without the size indicator the object's own size counts.
    ok(&mut r, &sdo(0x22, 0x2003, 0, [7, 0, 0xEE, 0xEE]));
    assert_eq!(r.dev.0.get_i64(0x2003, 0), Some(7));
    // Normal transfer: more data than the complete size says.
    assert_eq!(abort_of(&mut r, &normal(0x2001, 0, 2, b"abc")).2, SdoAbort::TYPE_MISMATCH);
    // Normal transfer whose size does not suit the type.
    assert_eq!(abort_of(&mut r, &normal(0x2003, 0, 3, b"abc")).2, SdoAbort::DATA_TOO_LONG);
    ok(&mut r, &normal(0x2001, 0, 3, b"abc"));
    assert_eq!(r.dev.0.get(0x2001, 0).unwrap().bytes(), b"abc");
}

#[test]
fn segmented_download_refusals() {
    let mut r = rig();
    // Checked at the initiate, before any segment.
    assert_eq!(abort_of(&mut r, &normal(0x1008, 0, 500, &[0; 20])).2, SdoAbort::WRITE_READ_ONLY);
    assert_eq!(abort_of(&mut r, &normal(0x1000, 0, 500, &[0; 20])).2, SdoAbort::WRITE_READ_ONLY);
    assert_eq!(abort_of(&mut r, &normal(0x2003, 0, 500, &[0; 20])).2, SdoAbort::DATA_TOO_LONG);
    assert_eq!(abort_of(&mut r, &normal(0x2000, 0, 2 << 20, &[0; 20])).2, SdoAbort::OUT_OF_MEMORY);
    // Segments beyond the complete size, a short last segment, a toggle.
    ok(&mut r, &normal(0x2000, 0, 150, &pattern(100, 1)));
    let mut seg = vec![0x00, 0x20, 0x01];
    seg.extend_from_slice(&[0; 51]);
    assert_eq!(abort_of(&mut r, &seg), (0x2000, 0, SdoAbort::DATA_TOO_LONG));
    ok(&mut r, &normal(0x2000, 0, 150, &pattern(100, 1)));
    assert_eq!(
        abort_of(&mut r, &[0x00, 0x20, 0x01 | (2 << 1), 1, 2, 3, 4, 5, 0, 0]).2,
        SdoAbort::DATA_TOO_SHORT
    );
    ok(&mut r, &normal(0x2000, 0, 150, &pattern(100, 1)));
    assert_eq!(abort_of(&mut r, &[0x00, 0x20, 0x10, 1, 2, 3, 4, 5, 6, 7]).2, SdoAbort::TOGGLE_NOT_ALTERNATED);
    // None of these stored anything.
    assert_eq!(r.dev.0.get(0x2000, 0).unwrap().bytes(), pattern(300, 1));
}

#[test]
fn commands_out_of_place() {
    let mut r = rig();
    // Block transfer specifiers do not exist in CoE.
    assert_eq!(abort_of(&mut r, &sdo(0xC0, 0x2000, 0, [0; 4])), (0x2000, 0, SdoAbort::INVALID_COMMAND));
    assert_eq!(abort_of(&mut r, &sdo(0xA0, 0x2000, 0, [0; 4])).2, SdoAbort::INVALID_COMMAND);
    assert_eq!(abort_of(&mut r, &sdo(0xE0, 0x2000, 0, [0; 4])).2, SdoAbort::INVALID_COMMAND);
    // Segments with no transfer: for object 0000h:00.
    assert_eq!(abort_of(&mut r, &sdo(0x60, 0x2000, 0, [0; 4])), (0, 0, SdoAbort::INVALID_COMMAND));
    assert_eq!(abort_of(&mut r, &sdo(0x00, 0x2000, 0, [0; 4])), (0, 0, SdoAbort::INVALID_COMMAND));
    // An upload segment request inside a segmented download: the transfer's object.
    ok(&mut r, &normal(0x2000, 0, 150, &pattern(100, 1)));
    assert_eq!(abort_of(&mut r, &sdo(0x60, 0, 0, [0; 4])), (0x2000, 0, SdoAbort::INVALID_COMMAND));
    // Upload toggle.
    ok(&mut r, &sdo(0x40, 0x2000, 0, [0; 4]));
    assert_eq!(abort_of(&mut r, &sdo(0x70, 0, 0, [0; 4])), (0x2000, 0, SdoAbort::TOGGLE_NOT_ALTERNATED));
}

#[test]
fn master_abort_new_initiate_and_timeout() {
    let mut r = rig();
    // A master abort ends the transfer and is not answered.
    ok(&mut r, &sdo(0x40, 0x2000, 0, [0; 4]));
    let c = r.counter();
    r.send(&mbx(3, c, &sdo(0x80, 0x2000, 0, 0x0800_0000u32.to_le_bytes())));
    assert_eq!(r.read(), None);
    assert!(r.server.is_idle());
    // A new initiate in the middle of a transfer starts over.
    ok(&mut r, &sdo(0x40, 0x2000, 0, [0; 4]));
    assert_eq!(ok(&mut r, &sdo(0x40, 0x1000, 0, [0; 4]))[2], 0x43);
    assert_eq!(abort_of(&mut r, &sdo(0x60, 0, 0, [0; 4])).2, SdoAbort::INVALID_COMMAND);
    // A timeout drops the transfer with no message.
    ok(&mut r, &sdo(0x40, 0x2000, 0, [0; 4]));
    let deadline = r.server.poll(r.now, &mut r.files).expect("a deadline");
    assert_eq!(deadline - r.now, Duration::from_secs(2) - Duration::from_micros(50));
    r.now = deadline;
    assert_eq!(r.server.poll(r.now, &mut r.files), None);
    assert_eq!(r.read(), None);
    assert_eq!(abort_of(&mut r, &sdo(0x60, 0, 0, [0; 4])).2, SdoAbort::INVALID_COMMAND);
}

#[test]
fn complete_access_refusals() {
    let mut r = rig();
    assert_eq!(abort_of(&mut r, &sdo(0x50, 0x1C12, 2, [0; 4])).2, SdoAbort::UNSUPPORTED_ACCESS);
    assert_eq!(abort_of(&mut r, &sdo(0x50, 0x2001, 0, [0; 4])).2, abort::CA_VARIABLE_LENGTH);
    assert_eq!(abort_of(&mut r, &sdo(0x50, 0x1000, 1, [0; 4])).2, SdoAbort::NO_SUB_INDEX);
    // Complete access not offered at all.
    let cfg = MailboxConfig { complete_access: false, ..MailboxConfig::default() };
    let mut r = Rig::new(cfg, (test_od(), NoHooks), NoFiles);
    assert_eq!(abort_of(&mut r, &sdo(0x50, 0x1C12, 0, [0; 4])).2, SdoAbort::UNSUPPORTED_ACCESS);
    assert_eq!(abort_of(&mut r, &sdo(0x33, 0x1C12, 1, [0; 4])).2, SdoAbort::UNSUPPORTED_ACCESS);
}

#[test]
fn empty_value_uploads_as_normal_with_size_zero() {
    let mut r = rig();
    ok(&mut r, &normal(0x2001, 0, 0, &[]));
    assert_eq!(ok(&mut r, &sdo(0x40, 0x2001, 0, [0; 4])), [0x00, 0x30, 0x41, 0x01, 0x20, 0x00, 0, 0, 0, 0]);
}

/// A device whose own rules refuse with codes the server must not change.
struct Picky(Dev);
impl ObjectAccess for Picky {
    fn dictionary(&self) -> &ObjectDictionary {
        &self.0.0
    }
    fn read(&mut self, index: u16, sub: u8) -> Result<&[u8], SdoAbort> {
        if index == 0x2001 {
            return Err(SdoAbort::DEVICE_STATE);
        }
        self.0.read(index, sub)
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        match index {
            0x2003 => Err(SdoAbort(0x1234_5678)),
            0x1C12 if sub == 1 => Err(abort::SI0_MUST_BE_ZERO),
            _ => self.0.write(index, sub, data),
        }
    }
}

#[test]
fn device_codes_pass_through_unchanged() {
    let mut r = Rig::new(MailboxConfig::default(), Picky((test_od(), NoHooks)), NoFiles);
    assert_eq!(abort_of(&mut r, &sdo(0x40, 0x2001, 0, [0; 4])).2, SdoAbort::DEVICE_STATE);
    assert_eq!(abort_of(&mut r, &sdo(0x2B, 0x2003, 0, [1, 0, 0, 0])).2, SdoAbort(0x1234_5678));
    // From inside a complete download, and from the end of a segmented one.
    assert_eq!(abort_of(&mut r, &sdo(0x3B, 0x1C12, 1, [0x00, 0x16, 0, 0])).2, abort::SI0_MUST_BE_ZERO);
    let mut r = Rig::new(MailboxConfig::with_sizes(32, 32), Picky((test_od(), NoHooks)), NoFiles);
    ok(&mut r, &{
        let mut b = sdo(0x31, 0x1C12, 0, 10u32.to_le_bytes());
        b.extend_from_slice(&[4, 0, 0x00, 0x16, 0x01, 0x16]);
        b
    });
    let seg = [0x00, 0x20, 0x01 | (3 << 1), 0x02, 0x16, 0x03, 0x16, 0, 0, 0];
    assert_eq!(abort_of(&mut r, &seg), (0x1C12, 0, abort::SI0_MUST_BE_ZERO));
}
