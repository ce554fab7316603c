//! Fuzz the SDO server with arbitrary frame sequences and time steps.
//! Mirrors `crates/sdo/tests/server_random.rs` (same input decoding), which
//! runs the same property under proptest on stable.
#![no_main]

use drivebus_can::{CanId, Duration, Frame, Instant};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, SubObject, Value};
use drivebus_sdo::server::{SdoServer, ServerConfig};
use libfuzzer_sys::fuzz_target;

const RX: u16 = 0x605;
const TX: u16 = 0x585;
/// Objects of the test dictionary.
const OBJECTS: [(u16, u8); 6] =
    [(0x1000, 0), (0x1007, 0), (0x2000, 0), (0x2001, 0), (0x2010, 1), (0x2010, 2)];
const COMMANDS: [u8; 24] = [
    0x40, 0x21, 0x20, 0x23, 0x60, 0x70, 0x00, 0x10, 0xA4, 0xA3, 0xA2, 0xA1, 0xC6, 0xC1, 0x80, 0x81, 0x01,
    0x02, 0x03, 0x04, 0x82, 0x83, 0x84, 0xC2,
];

fn od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    od.insert(Object::var(0x1000, "Device type", DataType::Unsigned32, Access::Ro, Value::U32(0x0002_0192)));
    od.insert(Object::var(0x1007, "Window", DataType::Unsigned32, Access::Rw, Value::U32(0)));
    od.insert(Object::var(0x2000, "Blob", DataType::Domain, Access::Rw, Value::Bytes(vec![0x5A; 100])));
    od.insert(Object::var(0x2001, "Text", DataType::VisibleString, Access::Rw, Value::Str("hello".into())));
    od.insert(
        Object::record(0x2010, "Rec")
            .with_sub(SubObject::new(1, "a", DataType::Unsigned8, Access::Rw, Value::U8(7)))
            .with_sub(SubObject::new(2, "b", DataType::Integer64, Access::Rw, Value::I64(-2))),
    );
    od
}

fuzz_target!(|input: &[u8]| {
    let mut od = od();
    let mut s = SdoServer::default_channel(5, ServerConfig { block_size: 4, ..ServerConfig::default() });
    let mut now = Instant::ZERO;
    let mut out: Vec<Frame> = Vec::new();
    for step in input.chunks_exact(12) {
        let sel = step[0];
        let mut data = [0u8; 8];
        data.copy_from_slice(&step[4..12]);
        if sel & 0x80 != 0 {
            // A likely command on an existing object with a small size, so
            // sequences get deep into every protocol instead of stopping at
            // "object does not exist".
            data[0] = COMMANDS[usize::from(data[0]) % COMMANDS.len()];
            if (data[0] & 0xE0 != 0 && data[0] & 0x80 == 0) || matches!(data[0], 0xA4 | 0xC6 | 0xC2) {
                let (index, sub) = OBJECTS[usize::from(data[1]) % OBJECTS.len()];
                [data[1], data[2]] = index.to_le_bytes();
                data[3] = sub;
                data[5..].fill(0);
            }
        }
        let id = match sel & 3 {
            0 | 1 => CanId::Standard(RX),
            2 => CanId::Standard(u16::from_le_bytes([step[1], step[2]]) & 0x7FF),
            _ => CanId::Extended(u32::from_le_bytes([step[1], step[2], 0, 0])),
        };
        let dlc = usize::from((sel >> 3) & 0x0F).min(8);
        let dlc = if sel & 0x40 != 0 { 8 } else { dlc };
        let frame = if sel & 0x24 == 0x24 {
            Frame::try_remote(id, dlc as u8).unwrap()
        } else {
            Frame::try_new(id, &data[..dlc]).unwrap()
        };
        // Mostly bus-speed gaps; one step in 16 jumps up to 2 s (timeouts).
        now += match step[3] {
            t @ 0..=239 => Duration::from_micros(u64::from(t) * 10),
            t => Duration::from_millis(u64::from(t - 239) * 128),
        };
        s.handle_frame(&frame, now, &mut od, &mut NoHooks, &mut out);
        if let Some(deadline) = s.poll(now, &mut out) {
            assert!(deadline > now);
        }
    }
    assert!(out.iter().all(|f| f.id() == CanId::Standard(TX) && f.len() == 8));
    // Never stuck: after the timeout a fresh expedited upload works.
    now += Duration::from_millis(1001);
    s.poll(now, &mut out);
    assert!(s.is_idle());
    out.clear();
    s.handle_frame(&Frame::new8(RX, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), now, &mut od, &mut NoHooks, &mut out);
    assert_eq!(out, [Frame::new8(TX, [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00])]);
});
