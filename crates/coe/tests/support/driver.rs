//! The decoding shared by the `coe_mailbox` fuzz target
//! (`fuzz/fuzz_targets/coe_mailbox.rs`) and `tests/random_input.rs`, which
//! runs it under proptest on stable and over every file of
//! `fuzz/seeds/coe_mailbox/`.
//!
//! Input: byte 0 picks the mailbox size and options; then records
//! `[tag, len (u16 LE), payload...]`:
//! - tag % 4 == 0: `payload` is a request mailbox as written into SM0;
//!   ESM state = (tag >> 2) % 5 (PRE-OP, SAFE-OP, OP, BOOT, INIT);
//! - tag % 4 == 1: read up to payload[0] % 8 + 1 responses;
//! - tag % 4 == 2: advance time by payload[0..2] (LE) ms × 16^(payload[2] % 4), poll;
//! - tag % 4 == 3: queue an emergency (payload[0] even) or reset the mailbox.
//!
//! Checked: no panic; every response fits SM1, has a consistent length
//! field, a known type and the next counter; every FoE transfer the file
//! handler accepted is ended exactly once; after every timeout and a reset
//! a fresh expedited upload gets the exact expected answer.

use drivebus_base::{Duration, Instant};
use drivebus_coe::{AlState, FileHandler, FoeEnd, FoeError, FoeProgress, MailboxConfig, MailboxServer};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectCode, ObjectDictionary, SubObject, Value};

const SIZES: [usize; 6] = [32, 40, 64, 128, 256, 1486];
const STATES: [AlState; 5] = [AlState::PreOp, AlState::SafeOp, AlState::Op, AlState::Boot, AlState::Init];

fn od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    od.insert(Object::var(0x1000, "Device type", DataType::Unsigned32, Access::Ro, Value::U32(0x0006_0192)));
    od.insert(Object::var(0x1008, "Name", DataType::VisibleString, Access::Const, Value::Str("iPOS".into())));
    od.insert(
        Object::record(0x1018, "Identity")
            .with_sub(SubObject::new(1, "Vendor", DataType::Unsigned32, Access::Ro, Value::U32(0x1A3)))
            .with_sub(SubObject::new(4, "Serial", DataType::Unsigned32, Access::Ro, Value::U32(7))),
    );
    let mut a = Object::with_code(0x1C12, ObjectCode::Array, "Assign").with_sub(SubObject::new(
        0,
        "n",
        DataType::Unsigned8,
        Access::Rw,
        Value::U8(1),
    ));
    for i in 1..=4u8 {
        a = a.with_sub(SubObject::new(i, "pdo", DataType::Unsigned16, Access::Rw, Value::U16(0x1600)));
    }
    od.insert(a);
    od.insert(Object::var(0x2000, "Blob", DataType::Domain, Access::Rw, Value::Bytes(vec![0x5A; 300])));
    od.insert(Object::var(0x2001, "Text", DataType::VisibleString, Access::Rw, Value::Str("hello".into())));
    od.insert(Object::var(0x2002, "Secret", DataType::Unsigned8, Access::Wo, Value::U8(0)));
    od.insert(
        Object::record(0x2100, "Flags")
            .with_sub(SubObject::new(1, "a", DataType::Unsigned8, Access::Rw, Value::U8(1)))
            .with_sub(SubObject::new(2, "b", DataType::Boolean, Access::Rw, Value::Bool(true)))
            .with_sub(SubObject::new(3, "c", DataType::Integer64, Access::Ro, Value::I64(-1))),
    );
    od.insert(Object::array(0x3000, "Table", DataType::Unsigned32, Access::Rw, 16, Value::U32(3)));
    od.insert(Object::var(0x6040, "Controlword", DataType::Unsigned16, Access::Rww, Value::U16(0)).with_sub(
        SubObject::new(0, "Controlword", DataType::Unsigned16, Access::Rww, Value::U16(0)).mappable(),
    ));
    od
}

/// Accepts files named `F...`, keeps up to 4 KiB, BUSY on every third packet.
#[derive(Default)]
struct Files {
    data: Vec<u8>,
    calls: u32,
    open: bool,
}

impl FileHandler for Files {
    fn begin_write(&mut self, name: &[u8], _: u32, _: AlState, _: Instant) -> Result<(), FoeError> {
        assert!(!self.open, "end() before a new transfer");
        if name.first() != Some(&b'F') {
            return Err(FoeError::NOT_FOUND);
        }
        self.open = true;
        self.data.clear();
        Ok(())
    }
    fn write(&mut self, offset: u32, data: &[u8], _: Instant) -> Result<FoeProgress, FoeError> {
        self.calls += 1;
        if self.calls.is_multiple_of(3) {
            return Ok(FoeProgress::Busy { done: 1, entire: 2 });
        }
        assert_eq!(offset as usize, self.data.len());
        if self.data.len() + data.len() > 4096 {
            return Err(FoeError::DISK_FULL);
        }
        self.data.extend_from_slice(data);
        Ok(FoeProgress::Ready)
    }
    fn finish_write(&mut self, _: Instant) -> Result<FoeProgress, FoeError> {
        self.calls += 1;
        if self.calls.is_multiple_of(3) {
            Ok(FoeProgress::Busy { done: 2, entire: 2 })
        } else {
            Ok(FoeProgress::Ready)
        }
    }
    fn begin_read(&mut self, name: &[u8], _: u32, _: AlState, _: Instant) -> Result<(), FoeError> {
        assert!(!self.open, "end() before a new transfer");
        if name.first() != Some(&b'F') {
            return Err(FoeError::NOT_FOUND);
        }
        self.open = true;
        Ok(())
    }
    fn read(&mut self, offset: u32, buf: &mut [u8], _: Instant) -> Result<usize, FoeError> {
        let k = 500usize.saturating_sub(offset as usize).min(buf.len());
        buf[..k].fill(0xA5);
        Ok(k)
    }
    fn end(&mut self, _: FoeEnd) {
        assert!(self.open, "end() without a transfer");
        self.open = false;
    }
}

/// Run one input (format in the module documentation); returns every
/// response read, in order.
pub fn drive(input: &[u8]) -> Vec<Vec<u8>> {
    let mut seen = Vec::new();
    let Some((&cfg, mut rest)) = input.split_first() else { return seen };
    let size = SIZES[usize::from(cfg) % SIZES.len()];
    let config = MailboxConfig {
        response_slots: 2 + usize::from(cfg >> 6),
        complete_access: cfg & 0x08 == 0,
        sdo_info: cfg & 0x10 == 0,
        ..MailboxConfig::with_sizes(size, size)
    };
    let mut s = MailboxServer::new(config).unwrap();
    let mut dev = (od(), NoHooks);
    let mut files = Files::default();
    let mut now = Instant::ZERO;
    let mut counter = 0u8;
    while let [tag, lo, hi, tail @ ..] = rest {
        let n = usize::from(u16::from_le_bytes([*lo, *hi])).min(tail.len());
        let (payload, next) = tail.split_at(n);
        rest = next;
        match tag % 4 {
            0 => {
                let state = STATES[usize::from(tag >> 2) % STATES.len()];
                now += Duration::from_micros(20);
                s.handle_request(payload, now, state, &mut dev, &mut files);
            }
            1 => {
                for _ in 0..=payload.first().map_or(0, |b| b % 8) {
                    let Some(m) = s.next_response(now) else { break };
                    assert!(m.len() <= size && m.len() >= 6);
                    assert_eq!(usize::from(u16::from_le_bytes([m[0], m[1]])) + 6, m.len());
                    assert!(matches!(m[5] & 0x0F, 0 | 3 | 4));
                    counter = if counter >= 7 { 1 } else { counter + 1 };
                    assert_eq!(m[5] >> 4, counter, "response counter");
                    seen.push(m.to_vec());
                }
            }
            2 => {
                let ms = u64::from(u16::from_le_bytes([
                    payload.first().copied().unwrap_or(0),
                    payload.get(1).copied().unwrap_or(0),
                ]));
                now += Duration::from_millis(ms << (4 * u32::from(payload.get(2).map_or(0, |b| b % 4))));
                if let Some(d) = s.poll(now, &mut files) {
                    assert!(d > now);
                }
            }
            _ => {
                if payload.first().is_some_and(|b| b % 2 == 0) {
                    let _ = s.queue_emergency(0x8210, 0x11, [1, 2, 3, 4, 5]);
                } else {
                    s.reset(&mut files);
                    counter = 0;
                }
            }
        }
    }
    // Never stuck: after every timeout and a reset, a fresh upload works.
    now += Duration::from_secs(3600);
    assert_eq!(s.poll(now, &mut files), None);
    assert!(!files.open);
    s.reset(&mut files);
    let req = [0x0a, 0, 0, 0, 0, 0x13, 0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0];
    s.handle_request(&req, now, AlState::PreOp, &mut dev, &mut files);
    let want = [0x0a, 0, 0, 0, 0, 0x13, 0x00, 0x30, 0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x06, 0x00];
    assert_eq!(s.next_response(now), Some(&want[..]));
    seen
}
