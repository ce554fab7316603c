//! Property tests: arbitrary input never panics, producer invariants hold.

use drivebus_can::{CanId, Frame, Instant};
use drivebus_emcy::{Emcy, EmcyConsumer, decode, describe, register_bit_for};
use drivebus_od::ObjectDictionary;
use proptest::prelude::*;

fn any_frame() -> impl Strategy<Value = Frame> {
    (0u32..0x2000_0000, any::<bool>(), any::<bool>(), proptest::collection::vec(any::<u8>(), 0..=8)).prop_map(
        |(id, ext, rtr, data)| {
            let id = if ext { CanId::Extended(id) } else { CanId::Standard((id & 0x7FF) as u16) };
            if rtr {
                Frame::try_remote(id, data.len() as u8).unwrap()
            } else {
                Frame::try_new(id, &data).unwrap()
            }
        },
    )
}

proptest! {
    #[test]
    fn consumer_and_decoder_accept_anything(frame in any_frame()) {
        let mut od = ObjectDictionary::new();
        let c = EmcyConsumer::install(&mut od, 127);
        let r = c.handle_frame(&frame);
        let m = decode(&frame);
        if let Some(r) = r {
            let m = m.unwrap();
            prop_assert_eq!((r.code, r.register, r.data), (m.code, m.register, m.data));
            let _ = describe(r.code);
        }
    }

    /// 1001h always equals the OR of the active errors plus the generic bit,
    /// 1003h sub 0 the history length, and the queue never exceeds its bound.
    #[test]
    fn producer_invariants(ops in proptest::collection::vec((0u8..4, 0u16..6, any::<u8>()), 0..60)) {
        let mut od = ObjectDictionary::new();
        let mut e = Emcy::install(&mut od, 7, 4);
        let codes = [0x2310u16, 0x3210, 0x4310, 0x8130, 0xFF01, 0x1000];
        let mut now = Instant::ZERO;
        let mut out = Vec::new();
        for (op, c, reg) in ops {
            let code = codes[c as usize];
            now += drivebus_can::Duration::from_micros(reg as u64 * 37);
            match op {
                0 => { e.raise(&mut od, code, register_bit_for(code) | (reg & 0x80), [reg; 5], now); }
                1 => { e.clear(&mut od, code, now); }
                2 => e.clear_all(&mut od, now),
                _ => { e.poll(now, &mut out); }
            }
            let expect = e.active().iter().fold(0u8, |r, a| r | a.register_bits | 1);
            prop_assert_eq!(e.error_register(), expect);
            prop_assert_eq!(od.get_u32(0x1001, 0), Some(expect as u32));
            prop_assert_eq!(od.get_u32(0x1003, 0), Some(e.history().len() as u32));
            prop_assert!(e.history().len() <= 4);
            prop_assert_eq!(expect & 0x40, 0);
        }
        while let Some(t) = e.poll(now, &mut out) { now = t; }
        prop_assert!(out.iter().all(|f| f.len() == 8 && f.id() == CanId::Standard(0x87)));
    }
}
