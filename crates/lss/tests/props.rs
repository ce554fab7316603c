//! Property tests: random input never panics, answers stay well-formed,
//! the codec round-trips, and fastscan always finds the lowest address.

use drivebus_can::{CanId, Duration, Frame, Instant};
use drivebus_lss::{FastScan, FastScanOutcome, Identity, LssMode, LssRequest, LssResponse, LssSlave, master};
use proptest::prelude::*;

/// Frames biased towards LSS: mostly 7E5h/7E4h with known command
/// specifiers, sometimes anything at all.
fn frame() -> impl Strategy<Value = Frame> {
    let cs = prop_oneof![
        prop::sample::select(vec![
            0x04u8, 0x11, 0x13, 0x15, 0x17, 0x40, 0x41, 0x42, 0x43, 0x44, 0x46, 0x47, 0x48, 0x49, 0x4A, 0x4B,
            0x4C, 0x4F, 0x50, 0x51, 0x5A, 0x5B, 0x5C, 0x5D, 0x5E,
        ]),
        any::<u8>(),
    ];
    let id = prop_oneof![4 => Just(0x7E5u16), 1 => Just(0x7E4u16), 1 => 0u16..=0x7FF];
    let len = prop_oneof![4 => Just(8usize), 1 => 0usize..=8];
    (id, cs, any::<[u8; 7]>(), len, any::<bool>(), any::<bool>()).prop_map(|(id, cs, rest, len, ext, rtr)| {
        let mut data = [0u8; 8];
        data[0] = cs;
        data[1..].copy_from_slice(&rest);
        let can_id = if ext { CanId::Extended(u32::from(id)) } else { CanId::Standard(id) };
        if rtr {
            Frame::try_remote(can_id, len as u8).unwrap()
        } else {
            Frame::try_new(can_id, &data[..len]).unwrap()
        }
    })
}

fn address() -> impl Strategy<Value = Identity> {
    // Small values too, so slaves share prefixes and parts.
    let part = prop_oneof![any::<u32>(), 0u32..4];
    (part.clone(), part.clone(), part.clone(), part).prop_map(|(v, p, r, s)| Identity::new(v, p, r, s))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn slave_never_panics_and_answers_at_most_once(
        addr in address(),
        node_id in prop_oneof![Just(0xFFu8), any::<u8>()],
        bit_timing in 0u8..10,
        frames in prop::collection::vec(frame(), 0..64),
    ) {
        let mut s = LssSlave::new(addr, node_id, bit_timing);
        let mut t = Instant::ZERO;
        for f in frames {
            let mut out = Vec::new();
            let _ = s.handle_frame(&f, t, &mut out);
            prop_assert!(out.len() <= 1);
            for a in &out {
                prop_assert_eq!(a.std_id(), Some(0x7E4));
                prop_assert_eq!(a.len(), 8);
                prop_assert!(LssResponse::from_frame(a).is_some());
            }
            if LssRequest::from_frame(&f).is_none() {
                prop_assert!(out.is_empty(), "answered a non-request {}", f);
            }
            let mut store = Vec::new();
            s.complete_store(drivebus_lss::StoreStatus::Stored, &mut store);
            prop_assert!(store.len() <= 1);
            prop_assert!(s.pending_node_id() == 0xFF || (1..=127).contains(&s.pending_node_id()));
            t += Duration::from_millis(1);
        }
    }

    #[test]
    fn fastscan_never_panics(frames in prop::collection::vec((frame(), 0u64..30), 0..200), early in any::<bool>()) {
        let mut scan = FastScan::new(Duration::from_millis(10)).with_early_advance(early);
        let mut out = Vec::new();
        let mut now = Instant::ZERO;
        scan.start(now, &mut out);
        for (f, dt) in frames {
            now += Duration::from_millis(dt);
            let _ = scan.handle_frame(&f, now, &mut out);
            if let Some(d) = scan.poll(now, &mut out) {
                prop_assert!(d > now || !scan.is_running());
            }
        }
        prop_assert!(out.len() <= 1 + 4 * 33);
        for f in &out {
            let is_fastscan = matches!(LssRequest::from_frame(f), Some(LssRequest::FastScan { .. }));
            prop_assert!(is_fastscan, "not a fastscan frame: {}", f);
        }
    }

    #[test]
    fn requests_round_trip(data in any::<[u8; 8]>(), cs in prop::sample::select(vec![
        0x04u8, 0x11, 0x13, 0x15, 0x17, 0x40, 0x41, 0x42, 0x43, 0x46, 0x47, 0x48, 0x49, 0x4A, 0x4B, 0x4C,
        0x51, 0x5A, 0x5B, 0x5C, 0x5D, 0x5E,
    ])) {
        let mut d = data;
        d[0] = cs;
        if cs == 0x04 { d[1] &= 1; }
        let req = LssRequest::from_frame(&Frame::new8(0x7E5, d));
        prop_assert!(req.is_some());
        let req = req.unwrap();
        let again = req.to_frame();
        prop_assert_eq!(again.data()[0], cs);
        prop_assert_eq!(LssRequest::from_frame(&again), Some(req));
    }

    #[test]
    fn responses_round_trip(data in any::<[u8; 8]>()) {
        if let Some(rsp) = LssResponse::from_frame(&Frame::new8(0x7E4, data)) {
            let again = rsp.to_frame();
            prop_assert_eq!(again.data()[0], data[0]);
            prop_assert_eq!(LssResponse::from_frame(&again), Some(rsp));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Whatever the addresses, each fastscan finds the lowest remaining one,
    /// and after its node-ID is configured the next scan finds the next.
    #[test]
    fn fastscan_finds_lowest_first(addrs in prop::collection::btree_set(address(), 1..4)) {
        let mut slaves: Vec<LssSlave> = addrs.iter().map(|a| LssSlave::new(*a, 0xFF, 4)).collect();
        let mut now = Instant::ZERO;
        for (k, want) in addrs.iter().enumerate() {
            let mut scan = FastScan::new(Duration::from_millis(5));
            let mut tx = Vec::new();
            scan.start(now, &mut tx);
            loop {
                for f in std::mem::take(&mut tx) {
                    let mut answers = Vec::new();
                    for s in slaves.iter_mut() {
                        s.handle_frame(&f, now, &mut answers);
                    }
                    for a in answers {
                        scan.handle_frame(&a, now, &mut tx);
                    }
                }
                match scan.poll(now, &mut tx) {
                    Some(d) => { now = d; scan.poll(now, &mut tx); }
                    None => break,
                }
            }
            prop_assert_eq!(scan.outcome(), Some(FastScanOutcome::Found(*want)));
            let node_id = k as u8 + 1;
            for f in [master::configure_node_id(node_id), master::switch_state_global(LssMode::Waiting)] {
                let mut sink = Vec::new();
                for s in slaves.iter_mut() {
                    s.handle_frame(&f, now, &mut sink);
                }
            }
            let found = slaves.iter_mut().find(|s| s.identity() == want).unwrap();
            prop_assert_eq!(found.reset_communication(), node_id);
        }
    }
}
