//! Frame-exact unit tests of the server: request bytes in, response bytes out.

use super::*;
use crate::crc::crc16;
use alloc::vec;
use drivebus_od::{Access, Object, SubObject, Target, Value, WriteOutcome};

const NODE: u16 = 5;
const RX: u16 = 0x600 + NODE;
const TX: u16 = 0x580 + NODE;

/// Hooks that give 2006h's writes the abort named by the written value and
/// refuse reads of 2007h, so every dictionary/hook abort can reach the wire.
struct Hooks;
impl ObjectHooks for Hooks {
    fn on_read(&mut self, _: &mut ObjectDictionary, at: &Target) -> Result<(), SdoAbort> {
        if at.index == 0x2007 { Err(SdoAbort::DEVICE_STATE) } else { Ok(()) }
    }
    fn check_write(
        &mut self,
        _: &mut ObjectDictionary,
        _: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let v = u32::from_le_bytes([data[0], data[1], data[2], data[3]]);
        if v == 0 { Ok(WriteOutcome::Store) } else { Err(SdoAbort(v)) }
    }
}

fn od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    let var = |i, dt, a, v| Object::var(i, "x", dt, a, v);
    od.insert(var(0x1000, DataType::Unsigned32, Access::Ro, Value::U32(0x0002_0192)));
    od.insert(var(0x1007, DataType::Unsigned32, Access::Rw, Value::U32(0)));
    od.insert(var(0x1008, DataType::VisibleString, Access::Const, Value::Str("drivebus".into())));
    od.insert(var(0x2000, DataType::Domain, Access::Rw, Value::Bytes(vec![0; 100])));
    od.insert(var(0x2001, DataType::Unsigned8, Access::Wo, Value::U8(0)));
    od.insert(
        Object::var(0x2002, "x", DataType::Integer16, Access::Rw, Value::I16(0)).with_sub(
            SubObject::new(0, "x", DataType::Integer16, Access::Rw, Value::I16(0))
                .limits(Value::I16(-100), Value::I16(100)),
        ),
    );
    od.insert(var(0x2003, DataType::Unsigned64, Access::Rw, Value::U64(0)));
    od.insert(Object::var(0x2004, "x", DataType::VisibleString, Access::Rw, Value::Str("".into())).with_sub(
        SubObject::new(0, "x", DataType::VisibleString, Access::Rw, Value::Str("".into())).max_len(10),
    ));
    od.insert(var(0x2005, DataType::OctetString, Access::Ro, Value::Bytes(vec![])));
    od.insert(
        Object::var(0x2006, "x", DataType::Unsigned32, Access::Rw, Value::U32(0))
            .with_sub(SubObject::new(0, "x", DataType::Unsigned32, Access::Rw, Value::U32(0)).hooked()),
    );
    od.insert(
        Object::var(0x2007, "x", DataType::Unsigned16, Access::Ro, Value::U16(0))
            .with_sub(SubObject::new(0, "x", DataType::Unsigned16, Access::Ro, Value::U16(0)).hooked()),
    );
    od.insert(var(0x2008, DataType::Unsigned16, Access::Rw, Value::U16(0x1234)));
    od.insert(var(0x2009, DataType::Boolean, Access::Rw, Value::Bool(false)));
    od.insert(Object::record(0x2010, "r").with_sub(SubObject::new(
        1,
        "a",
        DataType::Unsigned8,
        Access::Rw,
        Value::U8(0),
    )));
    od
}

struct Rig {
    s: SdoServer,
    od: ObjectDictionary,
    now: Instant,
}

impl Rig {
    fn new() -> Rig {
        Rig::with(ServerConfig::default())
    }
    fn with(config: ServerConfig) -> Rig {
        Rig { s: SdoServer::default_channel(NODE as u8, config), od: od(), now: Instant::from_millis(10) }
    }
    /// Send one 8-byte request, return the data of every response.
    fn req(&mut self, data: [u8; 8]) -> Vec<[u8; 8]> {
        self.frame(Frame::new8(RX, data))
    }
    fn frame(&mut self, f: Frame) -> Vec<[u8; 8]> {
        let mut out = Vec::new();
        let mut sink = |f: Frame| out.push(f);
        self.s.handle_frame(&f, self.now, &mut self.od, &mut Hooks, &mut sink);
        out.iter()
            .map(|f| {
                assert_eq!(f.std_id(), Some(TX));
                assert_eq!(f.len(), 8);
                *f.raw_data()
            })
            .collect()
    }
    /// Exactly one response expected.
    fn one(&mut self, data: [u8; 8]) -> [u8; 8] {
        let r = self.req(data);
        assert_eq!(r.len(), 1, "responses to {data:02X?}: {r:02X?}");
        r[0]
    }
    fn poll(&mut self) -> (Option<Instant>, Vec<[u8; 8]>) {
        let mut out = Vec::new();
        let mut sink = |f: Frame| out.push(*f.raw_data());
        let d = self.s.poll(self.now, &mut sink);
        (d, out)
    }
}

fn abort(index: u16, sub: u8, code: SdoAbort) -> [u8; 8] {
    let i = index.to_le_bytes();
    let c = code.0.to_le_bytes();
    [0x80, i[0], i[1], sub, c[0], c[1], c[2], c[3]]
}

#[test]
fn expedited_upload_sizes() {
    let mut r = Rig::new();
    assert_eq!(r.one([0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00]);
    assert_eq!(r.one([0x40, 0x08, 0x20, 0, 0, 0, 0, 0]), [0x4B, 0x08, 0x20, 0x00, 0x34, 0x12, 0, 0]);
    assert_eq!(r.one([0x40, 0x09, 0x20, 0, 0, 0, 0, 0]), [0x4F, 0x09, 0x20, 0x00, 0, 0, 0, 0]);
    assert!(r.s.is_idle());
}

#[test]
fn expedited_download_sizes() {
    let mut r = Rig::new();
    assert_eq!(r.one([0x23, 0x07, 0x10, 0, 0x78, 0x56, 0x34, 0x12]), [0x60, 0x07, 0x10, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get_u32(0x1007, 0), Some(0x1234_5678));
    assert_eq!(r.one([0x2B, 0x08, 0x20, 0, 0xCD, 0xAB, 0xFF, 0xFF]), [0x60, 0x08, 0x20, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get_u32(0x2008, 0), Some(0xABCD));
    // e=1, s=0: size not indicated, the object's size (2 bytes) is taken.
    assert_eq!(r.one([0x22, 0x08, 0x20, 0, 0x11, 0x22, 0x33, 0x44]), [0x60, 0x08, 0x20, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get_u32(0x2008, 0), Some(0x2211));
    assert_eq!(r.one([0x2F, 0x09, 0x20, 0, 1, 0, 0, 0]), [0x60, 0x09, 0x20, 0, 0, 0, 0, 0]);
    // Expedited into a variable-size object: the 2 bytes indicated.
    assert_eq!(r.one([0x2B, 0x04, 0x20, 0, b'o', b'k', 0, 0]), [0x60, 0x04, 0x20, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get(0x2004, 0).unwrap().bytes(), b"ok");
    // e=1, s=0 into a variable-size object: all 4 bytes.
    assert_eq!(r.one([0x22, 0x04, 0x20, 0, b'a', b'b', b'c', b'd']), [0x60, 0x04, 0x20, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get(0x2004, 0).unwrap().bytes(), b"abcd");
    // e=1, s=0 into an 8-byte object: 4 bytes cannot fill it.
    assert_eq!(r.one([0x22, 0x03, 0x20, 0, 1, 2, 3, 4]), abort(0x2003, 0, SdoAbort::DATA_TOO_SHORT));
}

#[test]
fn dictionary_aborts_reach_the_wire() {
    let mut r = Rig::new();
    let cases: [([u8; 8], SdoAbort); 13] = [
        ([0x40, 0x00, 0x30, 0, 0, 0, 0, 0], SdoAbort::NO_OBJECT),
        ([0x40, 0x10, 0x20, 2, 0, 0, 0, 0], SdoAbort::NO_SUB_INDEX),
        ([0x40, 0x01, 0x20, 0, 0, 0, 0, 0], SdoAbort::READ_WRITE_ONLY),
        ([0x23, 0x00, 0x10, 0, 0, 0, 0, 0], SdoAbort::WRITE_READ_ONLY),
        ([0x23, 0x02, 0x20, 0, 0, 0, 0, 0], SdoAbort::DATA_TOO_LONG),
        ([0x2F, 0x02, 0x20, 0, 0, 0, 0, 0], SdoAbort::DATA_TOO_SHORT),
        ([0x23, 0x03, 0x20, 0, 0, 0, 0, 0], SdoAbort::DATA_TOO_SHORT),
        ([0x2B, 0x02, 0x20, 0, 101, 0, 0, 0], SdoAbort::VALUE_TOO_HIGH),
        ([0x2B, 0x02, 0x20, 0, 0x9B, 0xFF, 0, 0], SdoAbort::VALUE_TOO_LOW),
        ([0x2F, 0x09, 0x20, 0, 2, 0, 0, 0], SdoAbort::INVALID_VALUE),
        ([0x40, 0x07, 0x20, 0, 0, 0, 0, 0], SdoAbort::DEVICE_STATE),
        // Segmented initiate with a size that cannot fit the type.
        ([0x21, 0x07, 0x10, 0, 5, 0, 0, 0], SdoAbort::DATA_TOO_LONG),
        ([0x21, 0x04, 0x20, 0, 11, 0, 0, 0], SdoAbort::DATA_TOO_LONG),
    ];
    for (req, code) in cases {
        let idx = u16::from_le_bytes([req[1], req[2]]);
        assert_eq!(r.one(req), abort(idx, req[3], code), "{req:02X?}");
        assert!(r.s.is_idle());
    }
    // Every code a write hook may give is sent unchanged.
    for code in [
        SdoAbort::TYPE_MISMATCH,
        SdoAbort::INVALID_VALUE,
        SdoAbort::VALUE_TOO_HIGH,
        SdoAbort::VALUE_TOO_LOW,
        SdoAbort::MAX_LESS_THAN_MIN,
        SdoAbort::CANNOT_STORE,
        SdoAbort::LOCAL_CONTROL,
        SdoAbort::DEVICE_STATE,
        SdoAbort::NOT_MAPPABLE,
        SdoAbort::PDO_TOO_LONG,
        SdoAbort::PARAM_INCOMPATIBLE,
        SdoAbort::INTERNAL_INCOMPATIBLE,
    ] {
        let c = code.0.to_le_bytes();
        assert_eq!(r.one([0x23, 0x06, 0x20, 0, c[0], c[1], c[2], c[3]]), abort(0x2006, 0, code));
    }
    assert_eq!(r.od.get_u32(0x2006, 0), Some(0));
}

#[test]
fn segmented_upload_frame_exact_and_toggle() {
    let mut r = Rig::new();
    assert_eq!(r.one([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]), [0x41, 0x08, 0x10, 0, 8, 0, 0, 0]);
    assert_eq!(r.one([0x60, 0, 0, 0, 0, 0, 0, 0]), [0x00, b'd', b'r', b'i', b'v', b'e', b'b', b'u']);
    // t=1, n=6, c=1.
    assert_eq!(r.one([0x70, 0, 0, 0, 0, 0, 0, 0]), [0x1D, b's', 0, 0, 0, 0, 0, 0]);
    assert!(r.s.is_idle());
    // Wrong toggle on the second request.
    r.one([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]);
    r.one([0x60, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0x60, 0, 0, 0, 0, 0, 0, 0]), abort(0x1008, 0, SdoAbort::TOGGLE_NOT_ALTERNATED));
    assert!(r.s.is_idle());
    // An empty value goes segmented: size 0, one segment with n=7, c=1.
    assert_eq!(r.one([0x40, 0x05, 0x20, 0, 0, 0, 0, 0]), [0x41, 0x05, 0x20, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0x60, 0, 0, 0, 0, 0, 0, 0]), [0x0F, 0, 0, 0, 0, 0, 0, 0]);
}

#[test]
fn segmented_download_frame_exact() {
    let mut r = Rig::new();
    assert_eq!(r.one([0x21, 0x04, 0x20, 0, 9, 0, 0, 0]), [0x60, 0x04, 0x20, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0x00, b'a', b'b', b'c', b'd', b'e', b'f', b'g']), [0x20, 0, 0, 0, 0, 0, 0, 0]);
    assert!(r.od.get(0x2004, 0).unwrap().bytes().is_empty(), "written once, at the end");
    // t=1, n=5, c=1.
    assert_eq!(r.one([0x1B, b'h', b'i', 0, 0, 0, 0, 0]), [0x30, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get(0x2004, 0).unwrap().bytes(), b"abcdefghi");
    // Size not indicated (s=0).
    r.one([0x20, 0x04, 0x20, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0x09, b'x', b'y', b'z', 0, 0, 0, 0]), [0x20, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get(0x2004, 0).unwrap().bytes(), b"xyz");
}

#[test]
fn segmented_download_aborts() {
    let mut r = Rig::new();
    // Toggle not alternated.
    r.one([0x21, 0x04, 0x20, 0, 9, 0, 0, 0]);
    r.one([0x00, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(r.one([0x00, 1, 2, 3, 4, 5, 6, 7]), abort(0x2004, 0, SdoAbort::TOGGLE_NOT_ALTERNATED));
    // More data than indicated.
    r.one([0x21, 0x04, 0x20, 0, 9, 0, 0, 0]);
    r.one([0x00, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(r.one([0x11, 1, 2, 3, 4, 5, 6, 7]), abort(0x2004, 0, SdoAbort::DATA_TOO_LONG));
    // Less data than indicated.
    r.one([0x21, 0x04, 0x20, 0, 9, 0, 0, 0]);
    assert_eq!(r.one([0x01, 1, 2, 3, 4, 5, 6, 7]), abort(0x2004, 0, SdoAbort::DATA_TOO_SHORT));
    // No size indicated, more than max_len: caught as the data arrives.
    r.one([0x20, 0x04, 0x20, 0, 0, 0, 0, 0]);
    r.one([0x00, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(r.one([0x10, 1, 2, 3, 4, 5, 6, 7]), abort(0x2004, 0, SdoAbort::DATA_TOO_LONG));
    // Into a read-only object: refused at initiate.
    assert_eq!(r.one([0x21, 0x08, 0x10, 0, 9, 0, 0, 0]), abort(0x1008, 0, SdoAbort::WRITE_READ_ONLY));
    // Segmented download of a u64 with the right size works.
    r.one([0x21, 0x03, 0x20, 0, 8, 0, 0, 0]);
    r.one([0x00, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(r.one([0x1D, 8, 0, 0, 0, 0, 0, 0]), [0x30, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get_u64(0x2003, 0), Some(0x0807_0605_0403_0201));
}

#[test]
fn out_of_memory_above_max_download() {
    let mut r = Rig::with(ServerConfig { max_download: 16, ..ServerConfig::default() });
    assert_eq!(r.one([0x21, 0x00, 0x20, 0, 17, 0, 0, 0]), abort(0x2000, 0, SdoAbort::OUT_OF_MEMORY));
    assert_eq!(r.one([0xC6, 0x00, 0x20, 0, 17, 0, 0, 0]), abort(0x2000, 0, SdoAbort::OUT_OF_MEMORY));
    r.one([0x20, 0x00, 0x20, 0, 0, 0, 0, 0]);
    r.one([0x00, 1, 2, 3, 4, 5, 6, 7]);
    r.one([0x10, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(r.one([0x00, 1, 2, 3, 4, 5, 6, 7]), abort(0x2000, 0, SdoAbort::OUT_OF_MEMORY));
}

/// 9-byte block download to 2004h, returning the end frame's response.
fn block_download_9(r: &mut Rig, init: u8, crc: u16) -> [u8; 8] {
    assert_eq!(r.one([init, 0x04, 0x20, 0, 9, 0, 0, 0])[..5], [0xA4, 0x04, 0x20, 0, 127]);
    assert!(r.req([0x01, b'a', b'b', b'c', b'd', b'e', b'f', b'g']).is_empty());
    assert_eq!(r.one([0x82, b'h', b'i', 0, 0, 0, 0, 0]), [0xA2, 2, 127, 0, 0, 0, 0, 0]);
    // n=5 unused bytes in the last segment.
    let c = crc.to_le_bytes();
    r.one([0xC1 | (5 << 2), c[0], c[1], 0, 0, 0, 0, 0])
}

#[test]
fn block_download_frame_exact() {
    let mut r = Rig::new();
    assert_eq!(block_download_9(&mut r, 0xC6, crc16(b"abcdefghi")), [0xA1, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get(0x2004, 0).unwrap().bytes(), b"abcdefghi");
    assert_eq!(block_download_9(&mut r, 0xC6, 0xBEEF), abort(0x2004, 0, SdoAbort::CRC_ERROR));
    // Client without CRC support (cc=0): the CRC field is not checked.
    r.od.set_value(0x2004, 0, &Value::Str("".into())).unwrap();
    assert_eq!(block_download_9(&mut r, 0xC2, 0xBEEF), [0xA1, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.od.get(0x2004, 0).unwrap().bytes(), b"abcdefghi");
    // Server without CRC support: sc=0 in the response, CRC not checked.
    let mut r = Rig::with(ServerConfig { crc: false, block_size: 4, ..ServerConfig::default() });
    assert_eq!(r.one([0xC6, 0x04, 0x20, 0, 9, 0, 0, 0]), [0xA0, 0x04, 0x20, 0, 4, 0, 0, 0]);
    r.req([0x01, 1, 2, 3, 4, 5, 6, 7]);
    r.one([0x82, 8, 9, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0xD5, 0xEF, 0xBE, 0, 0, 0, 0, 0]), [0xA1, 0, 0, 0, 0, 0, 0, 0]);
}

#[test]
fn block_download_sequence_and_size_errors() {
    let mut r = Rig::with(ServerConfig { block_size: 4, ..ServerConfig::default() });
    let init = [0xC6, 0x00, 0x20, 0, 40, 0, 0, 0];
    assert_eq!(r.one(init), [0xA4, 0x00, 0x20, 0, 4, 0, 0, 0]);
    assert_eq!(r.one([0x00, 0, 0, 0, 0, 0, 0, 0]), abort(0x2000, 0, SdoAbort::INVALID_SEQUENCE));
    r.one(init);
    assert_eq!(r.one([0x05, 0, 0, 0, 0, 0, 0, 0]), abort(0x2000, 0, SdoAbort::INVALID_SEQUENCE));
    // Full sub-block of 4 acknowledged, then a gap (3 after 1) gives a
    // partial ack; stale segments are ignored until the client restarts at 1.
    for (size, end) in [(54u8, [0xA1, 0, 0, 0, 0, 0, 0, 0]), (50, abort(0x2000, 0, SdoAbort::DATA_TOO_LONG))]
    {
        // No CRC (cc=0): this test is about sequence numbers.
        assert_eq!(r.one([0xC2, 0x00, 0x20, 0, size, 0, 0, 0])[0], 0xA4);
        for s in 1..=3u8 {
            assert!(r.req([s, s, 0, 0, 0, 0, 0, 0]).is_empty());
        }
        assert_eq!(r.one([0x04, 4, 0, 0, 0, 0, 0, 0]), [0xA2, 4, 4, 0, 0, 0, 0, 0]);
        assert!(r.req([0x01, 5, 0, 0, 0, 0, 0, 0]).is_empty());
        assert_eq!(r.one([0x03, 7, 0, 0, 0, 0, 0, 0]), [0xA2, 1, 4, 0, 0, 0, 0, 0]);
        assert!(r.req([0x04, 8, 0, 0, 0, 0, 0, 0]).is_empty());
        // The client restarts at ackseq+1 = logical segment 6, numbered 1.
        assert!(r.req([0x01, 6, 0, 0, 0, 0, 0, 0]).is_empty());
        assert!(r.req([0x02, 7, 0, 0, 0, 0, 0, 0]).is_empty());
        // Duplicate of an accepted segment: ignored.
        assert!(r.req([0x02, 9, 9, 9, 9, 9, 9, 9]).is_empty());
        assert_eq!(r.one([0x83, 8, 0, 0, 0, 0, 0, 0]), [0xA2, 3, 4, 0, 0, 0, 0, 0]);
        // 8 segments * 7 = 56 bytes, n=2 leaves 54.
        assert_eq!(r.one([0xC1 | (2 << 2), 0, 0, 0, 0, 0, 0, 0]), end);
    }
    let got = r.od.get(0x2000, 0).unwrap().bytes();
    assert_eq!(got.len(), 54);
    assert_eq!(got.iter().step_by(7).copied().collect::<Vec<_>>(), [1, 2, 3, 4, 5, 6, 7, 8]);
    // Too short: indicated 40, one segment.
    r.one(init);
    r.one([0x81, 1, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0xC1, 0, 0, 0, 0, 0, 0, 0]), abort(0x2000, 0, SdoAbort::DATA_TOO_SHORT));
    // More segments than the indicated size can hold.
    r.one([0xC6, 0x00, 0x20, 0, 8, 0, 0, 0]);
    r.req([0x01, 1, 0, 0, 0, 0, 0, 0]);
    r.req([0x02, 1, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0x03, 1, 0, 0, 0, 0, 0, 0]), abort(0x2000, 0, SdoAbort::DATA_TOO_LONG));
}

#[test]
fn block_upload_frame_exact() {
    let mut r = Rig::new();
    // cc=1, blksize 127, pst 0.
    assert_eq!(r.one([0xA4, 0x08, 0x10, 0, 127, 0, 0, 0]), [0xC6, 0x08, 0x10, 0, 8, 0, 0, 0]);
    assert_eq!(
        r.req([0xA3, 0, 0, 0, 0, 0, 0, 0]),
        vec![[0x01, b'd', b'r', b'i', b'v', b'e', b'b', b'u'], [0x82, b's', 0, 0, 0, 0, 0, 0]]
    );
    let c = crc16(b"drivebus").to_le_bytes();
    // n = 6 unused bytes.
    assert_eq!(r.one([0xA2, 2, 127, 0, 0, 0, 0, 0]), [0xD9, c[0], c[1], 0, 0, 0, 0, 0]);
    assert!(r.req([0xA1, 0, 0, 0, 0, 0, 0, 0]).is_empty());
    assert!(r.s.is_idle());
    // Client without CRC: the field is 0.
    r.one([0xA0, 0x08, 0x10, 0, 127, 0, 0, 0]);
    r.req([0xA3, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0xA2, 2, 127, 0, 0, 0, 0, 0]), [0xD9, 0, 0, 0, 0, 0, 0, 0]);
    r.req([0xA1, 0, 0, 0, 0, 0, 0, 0]);
    // Empty value: one padding segment, n = 7.
    assert_eq!(r.one([0xA4, 0x05, 0x20, 0, 127, 0, 0, 0]), [0xC6, 0x05, 0x20, 0, 0, 0, 0, 0]);
    assert_eq!(r.req([0xA3, 0, 0, 0, 0, 0, 0, 0]), vec![[0x81, 0, 0, 0, 0, 0, 0, 0]]);
    assert_eq!(r.one([0xA2, 1, 127, 0, 0, 0, 0, 0]), [0xDD, 0, 0, 0, 0, 0, 0, 0]);
}

#[test]
fn block_upload_blksize_ack_and_retransmission() {
    let mut r = Rig::new();
    for bad in [0u8, 128, 255] {
        assert_eq!(
            r.one([0xA4, 0x00, 0x10, 0, bad, 0, 0, 0]),
            abort(0x1000, 0, SdoAbort::INVALID_BLOCK_SIZE)
        );
    }
    // 100-byte DOMAIN with blksize 4: 15 segments.
    let pattern: Vec<u8> = (0..100u8).collect();
    r.od.set_value(0x2000, 0, &Value::Bytes(pattern.clone())).unwrap();
    assert_eq!(r.one([0xA4, 0x00, 0x20, 0, 4, 0, 0, 0]), [0xC6, 0x00, 0x20, 0, 100, 0, 0, 0]);
    let sb = r.req([0xA3, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(sb.iter().map(|s| s[0]).collect::<Vec<_>>(), [1, 2, 3, 4]);
    assert_eq!(sb[3][1..], pattern[21..28]);
    // Partial ack: segment 3 lost; next sub-block starts with byte 14, size 2.
    let sb = r.req([0xA2, 2, 2, 0, 0, 0, 0, 0]);
    assert_eq!(sb.len(), 2);
    assert_eq!(sb[0][0], 1);
    assert_eq!(sb[0][1..], pattern[14..21]);
    // ackseq beyond what was sent.
    assert_eq!(r.one([0xA2, 3, 4, 0, 0, 0, 0, 0]), abort(0x2000, 0, SdoAbort::INVALID_SEQUENCE));
    r.one([0xA4, 0x00, 0x20, 0, 4, 0, 0, 0]);
    r.req([0xA3, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0xA2, 4, 0, 0, 0, 0, 0, 0]), abort(0x2000, 0, SdoAbort::INVALID_BLOCK_SIZE));
    r.one([0xA4, 0x00, 0x20, 0, 4, 0, 0, 0]);
    r.req([0xA3, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0xA2, 4, 128, 0, 0, 0, 0, 0]), abort(0x2000, 0, SdoAbort::INVALID_BLOCK_SIZE));
}

#[test]
fn block_upload_protocol_switch_threshold() {
    let mut r = Rig::new();
    // pst=16 ≥ 8 bytes: answered as a segmented upload.
    assert_eq!(r.one([0xA4, 0x08, 0x10, 0, 127, 16, 0, 0]), [0x41, 0x08, 0x10, 0, 8, 0, 0, 0]);
    assert_eq!(r.one([0x60, 0, 0, 0, 0, 0, 0, 0])[0], 0x00);
    assert_eq!(r.one([0x70, 0, 0, 0, 0, 0, 0, 0])[0], 0x1D);
    // 4 bytes: expedited.
    assert_eq!(r.one([0xA4, 0x00, 0x10, 0, 127, 4, 0, 0]), [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00]);
    // pst=7 < 8: block.
    assert_eq!(r.one([0xA4, 0x08, 0x10, 0, 127, 7, 0, 0])[0], 0xC6);
}

#[test]
fn block_transfer_disabled() {
    let mut r = Rig::with(ServerConfig { block_transfer: false, ..ServerConfig::default() });
    assert_eq!(r.one([0xA4, 0x08, 0x10, 0, 127, 0, 0, 0]), abort(0x1008, 0, SdoAbort::INVALID_COMMAND));
    assert_eq!(r.one([0xC6, 0x04, 0x20, 0, 9, 0, 0, 0]), abort(0x2004, 0, SdoAbort::INVALID_COMMAND));
}

#[test]
fn unknown_and_unexpected_commands() {
    let mut r = Rig::new();
    assert_eq!(r.one([0xE0, 0x00, 0x10, 0, 0, 0, 0, 0]), abort(0x1000, 0, SdoAbort::INVALID_COMMAND));
    assert_eq!(r.one([0x60, 0x00, 0x10, 0, 0, 0, 0, 0]), abort(0x1000, 0, SdoAbort::INVALID_COMMAND));
    assert_eq!(r.one([0x00, 0x00, 0x10, 0, 0, 0, 0, 0]), abort(0x1000, 0, SdoAbort::INVALID_COMMAND));
    assert_eq!(r.one([0xA3, 0x00, 0x10, 0, 0, 0, 0, 0]), abort(0x1000, 0, SdoAbort::INVALID_COMMAND));
    assert_eq!(r.one([0xC1, 0x00, 0x10, 0, 0, 0, 0, 0]), abort(0x1000, 0, SdoAbort::INVALID_COMMAND));
    // An abort while idle is never answered.
    assert!(r.req(abort(0x1000, 0, SdoAbort::TIMEOUT)).is_empty());
    // Upload segment request during a segmented download: transfer's mux.
    r.one([0x21, 0x04, 0x20, 0, 9, 0, 0, 0]);
    assert_eq!(r.one([0x60, 0, 0, 0, 0, 0, 0, 0]), abort(0x2004, 0, SdoAbort::INVALID_COMMAND));
    assert!(r.s.is_idle());
}

#[test]
fn ignored_frames() {
    let mut r = Rig::new();
    // DLC < 8 is ignored (design choice, see the module documentation).
    assert!(r.frame(Frame::new(RX, &[0x40, 0x00, 0x10, 0x00])).is_empty());
    assert!(r.frame(Frame::new(RX, &[])).is_empty());
    assert!(r.frame(Frame::remote(RX, 8)).is_empty());
    assert!(r.frame(Frame::new8(0x606, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0])).is_empty());
    let ext = Frame::try_new(CanId::Extended(u32::from(RX)), &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap();
    assert!(r.frame(ext).is_empty());
    // A short frame in the middle of a transfer does not disturb it.
    r.one([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]);
    assert!(r.frame(Frame::new(RX, &[0x70])).is_empty());
    assert_eq!(r.one([0x60, 0, 0, 0, 0, 0, 0, 0])[0], 0x00);
}

#[test]
fn timeout_through_poll_exact_deadline() {
    let mut r = Rig::new();
    assert_eq!(r.poll(), (None, vec![]));
    let t0 = r.now;
    r.one([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]);
    let deadline = t0 + Duration::from_millis(1000);
    assert_eq!(r.poll(), (Some(deadline), vec![]));
    r.now = t0 + Duration::from_millis(400);
    r.one([0x60, 0, 0, 0, 0, 0, 0, 0]);
    // Re-armed by the segment.
    let deadline = r.now + Duration::from_millis(1000);
    r.now = Instant::from_nanos(deadline.as_nanos() - 1);
    assert_eq!(r.poll(), (Some(deadline), vec![]));
    r.now = deadline;
    assert_eq!(r.poll(), (None, vec![abort(0x1008, 0, SdoAbort::TIMEOUT)]));
    assert!(r.s.is_idle());
    assert_eq!(r.poll(), (None, vec![]));
}

#[test]
fn timeout_detected_by_a_late_frame() {
    let mut r = Rig::with(ServerConfig { timeout: Duration::from_millis(50), ..ServerConfig::default() });
    r.one([0x21, 0x04, 0x20, 0, 9, 0, 0, 0]);
    r.now += Duration::from_millis(50);
    // The deadline passed unpolled: the abort goes first, then the segment
    // is handled as in the idle state.
    assert_eq!(
        r.req([0x00, 1, 2, 3, 4, 5, 6, 7]),
        vec![abort(0x2004, 0, SdoAbort::TIMEOUT), [0x80, 1, 2, 3, 1, 0, 4, 5]]
    );
    // Block download timeout while receiving a sub-block.
    r.one([0xC6, 0x04, 0x20, 0, 9, 0, 0, 0]);
    r.now += Duration::from_millis(60);
    assert_eq!(r.poll(), (None, vec![abort(0x2004, 0, SdoAbort::TIMEOUT)]));
}

#[test]
fn client_abort_then_fresh_initiate() {
    let mut r = Rig::new();
    for init in [
        [0x40, 0x08, 0x10, 0, 0, 0, 0, 0],
        [0x21, 0x04, 0x20, 0, 9, 0, 0, 0],
        [0xC6, 0x04, 0x20, 0, 9, 0, 0, 0],
        [0xA4, 0x08, 0x10, 0, 127, 0, 0, 0],
    ] {
        r.one(init);
        assert!(!r.s.is_idle());
        assert!(r.req(abort(0x1234, 5, SdoAbort::GENERAL_ERROR)).is_empty());
        assert!(r.s.is_idle());
        assert_eq!(r.poll(), (None, vec![]));
        assert_eq!(r.one([0x40, 0x00, 0x10, 0, 0, 0, 0, 0])[0], 0x43);
    }
    // Abort in the middle of block upload (after the start).
    r.one([0xA4, 0x08, 0x10, 0, 127, 0, 0, 0]);
    r.req([0xA3, 0, 0, 0, 0, 0, 0, 0]);
    assert!(r.req([0x80, 0x08, 0x10, 0, 0, 0, 0, 0]).is_empty());
    assert!(r.s.is_idle());
}

#[test]
fn new_initiate_replaces_running_transfer() {
    let mut r = Rig::new();
    r.one([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]);
    r.one([0x60, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0x40, 0x00, 0x10, 0, 0, 0, 0, 0])[0], 0x43);
    assert!(r.s.is_idle());
    r.one([0x21, 0x04, 0x20, 0, 9, 0, 0, 0]);
    assert_eq!(r.one([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]), [0x41, 0x08, 0x10, 0, 8, 0, 0, 0]);
    assert_eq!(r.one([0x60, 0, 0, 0, 0, 0, 0, 0])[1], b'd');
    // Block upload waiting for its ack: a block download initiate restarts.
    r.one([0xA4, 0x08, 0x10, 0, 127, 0, 0, 0]);
    r.req([0xA3, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.one([0xC6, 0x04, 0x20, 0, 9, 0, 0, 0])[0], 0xA4);
}

#[test]
fn reset_and_cob_id_changes_drop_silently() {
    let mut r = Rig::new();
    r.one([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]);
    r.s.reset();
    assert!(r.s.is_idle());
    assert_eq!(r.poll(), (None, vec![]));
    r.one([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]);
    r.s.disable();
    assert_eq!(r.s.rx_cob_id(), None);
    assert!(r.req([0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).is_empty());
    r.s.set_cob_ids(CanId::Standard(RX), CanId::Standard(TX));
    assert_eq!(r.one([0x40, 0x00, 0x10, 0, 0, 0, 0, 0])[0], 0x43);
    r.s.set_cob_ids(CanId::Standard(0x800), CanId::Standard(TX));
    assert_eq!(r.s.rx_cob_id(), None);
}

#[test]
fn extended_cob_ids() {
    let mut od = od();
    let (rx, tx) = (CanId::Extended(0x1234_5678), CanId::Extended(0x1234_5679));
    let mut s = SdoServer::new(rx, tx, ServerConfig::default());
    assert_eq!((s.rx_cob_id(), s.tx_cob_id()), (Some(rx), tx));
    let mut out = Vec::new();
    let f = Frame::try_new(rx, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap();
    s.handle_frame(&f, Instant::ZERO, &mut od, &mut Hooks, &mut |f: Frame| out.push(f));
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].id(), tx);
    assert_eq!(out[0].data(), [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00]);
}

#[test]
fn server_params_install_and_check() {
    let mut od = ObjectDictionary::new();
    install_server_params(&mut od, 5, 3);
    assert_eq!(od.get_u32(0x1200, 0), Some(2));
    assert_eq!(od.get_u32(0x1200, 1), Some(0x605));
    assert_eq!(od.get_u32(0x1200, 2), Some(0x585));
    assert_eq!(od.get_u32(0x1201, 0), Some(3));
    assert_eq!(od.get_u32(0x1202, 1), Some(0x8000_0000));
    assert!(od.object(0x1203).is_none());
    let h = &mut ParamHooks;
    assert_eq!(od.write(h, 0x1200, 1, &0x606u32.to_le_bytes()), Err(SdoAbort::WRITE_READ_ONLY));
    assert_eq!(check_write(&od, 0x1200, 1, &0x606u32.to_le_bytes()), Err(SdoAbort::WRITE_READ_ONLY));
    assert_eq!(check_write(&od, 0x1000, 0, &[]), Ok(()));
    // Restricted CAN-IDs (CiA 301 §7.3.5).
    for id in
        [0x000u32, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x6FF, 0x701, 0x77F, 0x780, 0x7FF]
    {
        assert!(is_restricted_can_id(id), "{id:#x}");
        assert_eq!(od.write(h, 0x1201, 1, &id.to_le_bytes()), Err(SdoAbort::INVALID_VALUE), "{id:#x}");
    }
    for id in [0x080u32, 0x100, 0x181, 0x580, 0x600, 0x680, 0x6DF, 0x700] {
        assert!(!is_restricted_can_id(id), "{id:#x}");
    }
    // 11-bit COB-ID with bits above 10 set.
    assert_eq!(od.write(h, 0x1201, 1, &0x800u32.to_le_bytes()), Err(SdoAbort::INVALID_VALUE));
    od.write(h, 0x1201, 1, &0x6C1u32.to_le_bytes()).unwrap();
    od.write(h, 0x1201, 2, &0x6C2u32.to_le_bytes()).unwrap();
    // Valid → other valid: refused; same value: accepted; invalidate first.
    assert_eq!(od.write(h, 0x1201, 1, &0x6C3u32.to_le_bytes()), Err(SdoAbort::INVALID_VALUE));
    od.write(h, 0x1201, 1, &0x6C1u32.to_le_bytes()).unwrap();
    od.write(h, 0x1201, 1, &0x8000_06C1u32.to_le_bytes()).unwrap();
    od.write(h, 0x1201, 1, &0x6C3u32.to_le_bytes()).unwrap();
    // 29-bit COB-ID (bit 29).
    od.write(h, 0x1202, 1, &0x2012_3456u32.to_le_bytes()).unwrap();
    assert_eq!(parse_cob_id(0x2012_3456), Some(CanId::Extended(0x0012_3456)));
    assert_eq!(od.write(h, 0x1201, 3, &[0]), Err(SdoAbort::VALUE_TOO_LOW));
    assert_eq!(od.write(h, 0x1201, 3, &[128]), Err(SdoAbort::VALUE_TOO_HIGH));
    assert_eq!(check_write(&od, 0x1201, 3, &[0]), Err(SdoAbort::VALUE_TOO_LOW));
    assert_eq!(check_write(&od, 0x1201, 3, &[200]), Err(SdoAbort::VALUE_TOO_HIGH));
    assert_eq!(check_write(&od, 0x1201, 1, &[1, 2]), Err(SdoAbort::DATA_TOO_SHORT));
    assert_eq!(check_write(&od, 0x1201, 4, &[1]), Err(SdoAbort::NO_SUB_INDEX));
    od.write(h, 0x1201, 3, &[0x10]).unwrap();

    // One server per record; 1202h is half-configured, hence disabled.
    let mut servers = SdoServer::servers_from_od(&od, ServerConfig::default());
    assert_eq!(servers.len(), 3);
    assert_eq!(servers[0].rx_cob_id(), Some(CanId::Standard(0x605)));
    assert_eq!(servers[0].tx_cob_id(), CanId::Standard(0x585));
    assert_eq!(servers[1].rx_cob_id(), Some(CanId::Standard(0x6C3)));
    assert_eq!(servers[1].tx_cob_id(), CanId::Standard(0x6C2));
    assert_eq!(servers[2].rx_cob_id(), None);
    od.write(h, 0x1202, 2, &0x2012_3457u32.to_le_bytes()).unwrap();
    servers[2].reconfigure(&od, 0x1201);
    assert_eq!(servers[2].rx_cob_id(), None, "not its record");
    servers[2].reconfigure(&od, 0x1202);
    assert_eq!(servers[2].rx_cob_id(), Some(CanId::Extended(0x0012_3456)));
    assert_eq!(servers[2].tx_cob_id(), CanId::Extended(0x0012_3457));
    od.write(h, 0x1201, 1, &0x8000_06C3u32.to_le_bytes()).unwrap();
    servers[1].reconfigure(&od, 0x1201);
    assert_eq!(servers[1].rx_cob_id(), None);
    assert!(SdoServer::from_od(&od, 0x1210, ServerConfig::default()).is_none());
}

#[test]
fn additional_channel_serves_requests() {
    let mut od = od();
    install_server_params(&mut od, 5, 2);
    let h = &mut ParamHooks;
    od.write(h, 0x1201, 1, &0x6C1u32.to_le_bytes()).unwrap();
    od.write(h, 0x1201, 2, &0x6C2u32.to_le_bytes()).unwrap();
    let mut s = SdoServer::from_od(&od, 0x1201, ServerConfig::default()).unwrap();
    let mut out = Vec::new();
    s.handle_frame(
        &Frame::new8(0x6C1, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0]),
        Instant::ZERO,
        &mut od,
        &mut ParamHooks,
        &mut |f: Frame| out.push(f),
    );
    assert_eq!(out, [Frame::new8(0x6C2, [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00])]);
}

#[test]
fn lookup_cache_survives_dictionary_changes() {
    let mut r = Rig::new();
    let up = |r: &mut Rig, i: u16, s: u8| {
        let b = i.to_le_bytes();
        r.one([0x40, b[0], b[1], s, 0, 0, 0, 0])
    };
    assert_eq!(up(&mut r, 0x2008, 0)[..6], [0x4B, 0x08, 0x20, 0, 0x34, 0x12]);
    assert_eq!(up(&mut r, 0x2010, 1)[0], 0x4F);
    // Positions shift: the remembered slot no longer holds 2008h.
    r.od.remove(0x2002);
    r.od.remove(0x1000);
    assert_eq!(up(&mut r, 0x2008, 0)[..6], [0x4B, 0x08, 0x20, 0, 0x34, 0x12]);
    r.od.remove(0x2008);
    assert_eq!(up(&mut r, 0x2008, 0), abort(0x2008, 0, SdoAbort::NO_OBJECT));
    // Same index, replaced by an object with other sub-objects.
    r.od.insert(Object::record(0x2010, "r").with_sub(SubObject::new(
        2,
        "b",
        DataType::Unsigned8,
        Access::Rw,
        Value::U8(9),
    )));
    assert_eq!(up(&mut r, 0x2010, 1), abort(0x2010, 1, SdoAbort::NO_SUB_INDEX));
    assert_eq!(up(&mut r, 0x2010, 2)[..5], [0x4F, 0x10, 0x20, 2, 9]);
    // Everything removed: remembered positions are out of range.
    let all: Vec<u16> = r.od.objects().iter().map(|o| o.index).collect();
    for i in all {
        r.od.remove(i);
    }
    assert_eq!(up(&mut r, 0x2010, 2), abort(0x2010, 2, SdoAbort::NO_OBJECT));
    assert_eq!(r.one([0x23, 0x07, 0x10, 0, 1, 0, 0, 0]), abort(0x1007, 0, SdoAbort::NO_OBJECT));
}

/// Counts read hooks and changes the value's length on every read, so a
/// server reading per segment would tear the transfer.
struct Growing {
    reads: usize,
}
impl ObjectHooks for Growing {
    fn on_read(&mut self, od: &mut ObjectDictionary, at: &Target) -> Result<(), SdoAbort> {
        self.reads += 1;
        let len = 20 + 7 * self.reads;
        od.set_raw(at.r, &vec![self.reads as u8; len]);
        Ok(())
    }
}

#[test]
fn read_hook_runs_once_per_upload() {
    let mut od = od();
    od.get_mut(0x2000, 0).unwrap().live = true;
    let mut s = SdoServer::default_channel(NODE as u8, ServerConfig::default());
    let mut h = Growing { reads: 0 };
    let mut got = Vec::new();
    let req = |s: &mut SdoServer, od: &mut ObjectDictionary, h: &mut Growing, d: [u8; 8]| {
        let mut out = Vec::new();
        s.handle_frame(&Frame::new8(RX, d), Instant::ZERO, od, h, &mut |f: Frame| out.push(*f.raw_data()));
        out
    };
    assert_eq!(
        req(&mut s, &mut od, &mut h, [0x40, 0x00, 0x20, 0, 0, 0, 0, 0])[0],
        [0x41, 0x00, 0x20, 0, 27, 0, 0, 0]
    );
    let mut t = 0;
    loop {
        let r = req(&mut s, &mut od, &mut h, [0x60 | t, 0, 0, 0, 0, 0, 0, 0])[0];
        got.extend_from_slice(&r[1..8 - usize::from((r[0] >> 1) & 7)]);
        if r[0] & 1 != 0 {
            break;
        }
        t ^= 0x10;
    }
    assert_eq!((h.reads, got), (1, vec![1; 27]));
    // Block upload: once as well.
    assert_eq!(
        req(&mut s, &mut od, &mut h, [0xA4, 0x00, 0x20, 0, 2, 0, 0, 0])[0][..5],
        [0xC6, 0x00, 0x20, 0, 34]
    );
    let mut segs = req(&mut s, &mut od, &mut h, [0xA3, 0, 0, 0, 0, 0, 0, 0]);
    while segs.len() == 2 {
        segs = req(&mut s, &mut od, &mut h, [0xA2, 2, 2, 0, 0, 0, 0, 0]);
    }
    assert_eq!(h.reads, 2);
}

#[test]
fn missing_object_abort_is_configurable() {
    let mut r =
        Rig::with(ServerConfig { missing_object: SdoAbort::UNSUPPORTED_ACCESS, ..ServerConfig::default() });
    // Upload of a missing index: the personality's code (SSD 630: 0601 0000).
    assert_eq!(r.one([0x40, 0x34, 0x12, 0x00, 0, 0, 0, 0]), abort(0x1234, 0, SdoAbort::UNSUPPORTED_ACCESS));
    // A missing sub-index of an existing object keeps 0609 0011.
    assert_eq!(r.one([0x40, 0x00, 0x10, 0x07, 0, 0, 0, 0]), abort(0x1000, 7, SdoAbort::NO_SUB_INDEX));
}
