//! Property tests: arbitrary frames never panic the SYNC and TIME consumers.

use drivebus_can::{CanId, Frame, Instant};
use drivebus_od::{NoHooks, ObjectDictionary};
use drivebus_sync::{SyncService, TimeService};
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
    fn consumers_accept_anything(frames in proptest::collection::vec(any_frame(), 1..20), overflow in 0u8..=240) {
        let mut od = ObjectDictionary::new();
        let mut s = SyncService::install(&mut od, 1);
        let mut t = TimeService::install(&mut od);
        let overflow = if overflow == 1 { 0 } else { overflow };
        od.write(&mut NoHooks, 0x1019, 0, &[overflow]).unwrap();
        s.reconfigure(&od, 0x1019, 0);
        od.write(&mut NoHooks, 0x1012, 0, &0x8000_0100u32.to_le_bytes()).unwrap();
        t.reconfigure(&od, 0x1012, 0);
        for (i, f) in frames.iter().enumerate() {
            let now = Instant::from_micros(i as u64 * 100);
            if let Some(e) = s.handle_frame(f, now) {
                prop_assert_eq!(f.std_id(), Some(0x80));
                prop_assert_eq!(e.length_error.is_none(), f.len() == (overflow != 0) as usize);
            }
            if let Some(x) = t.handle_frame(f) {
                prop_assert_eq!(f.len(), 6);
                prop_assert!(x.ms < 1 << 28);
            }
            let _ = s.poll(now, &mut Vec::new());
        }
    }
}
