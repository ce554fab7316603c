//! Property tests of the whole node: arbitrary traffic never panics, the
//! node never gets stuck, and stored parameters always read back.

mod common;
use common::*;
use drivebus_can::{CanId, Duration, Frame, Instant};
use drivebus_node::{Node, NodeConfig};
use drivebus_od::NoHooks;
use proptest::prelude::*;

fn any_frame() -> impl Strategy<Value = Frame> {
    let id = prop_oneof![
        // Bias towards the identifiers the node listens on.
        Just(0x000u16),
        Just(0x080),
        Just(0x100),
        Just(0x605),
        Just(0x705),
        Just(0x7E5),
        0x180u16..0x580,
        0u16..0x800,
    ];
    (id, any::<bool>(), proptest::collection::vec(any::<u8>(), 0..=8), any::<bool>()).prop_map(
        |(id, ext, data, rtr)| {
            let cid = if ext { CanId::Extended(id as u32 | 0x1000) } else { CanId::Standard(id) };
            if rtr {
                Frame::try_remote(cid, data.len() as u8).unwrap()
            } else {
                Frame::try_new(cid, &data).unwrap()
            }
        },
    )
}

fn sdo_like() -> impl Strategy<Value = Frame> {
    // Well-formed length, random command and payload: exercises every SDO state.
    (
        any::<[u8; 8]>(),
        prop_oneof![Just(0x00u8), Just(0x20), Just(0x40), Just(0x60), Just(0xA0), Just(0xC0), Just(0x80)],
    )
        .prop_map(|(mut d, cs)| {
            d[0] = cs | (d[0] & 0x1F);
            Frame::new(0x605, &d)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_traffic_never_panics_and_sdo_recovers(
        frames in proptest::collection::vec(prop_oneof![any_frame(), sdo_like()], 0..64),
        gaps in proptest::collection::vec(0u64..3_000, 64),
    ) {
        let mut node = Node::new(device());
        let mut out = Vec::new();
        let mut now = Instant::ZERO;
        node.boot(now, &mut NoHooks, &mut out);
        for (i, f) in frames.iter().enumerate() {
            now += Duration::from_micros(gaps[i]);
            node.handle_frame(f, now, &mut NoHooks, &mut out);
            node.poll(now, &mut NoHooks, &mut out);
        }
        // Whatever happened: a reset communication and a fresh expedited
        // upload must work (the node is never stuck).
        now += Duration::from_secs(2);
        node.poll(now, &mut NoHooks, &mut out);
        node.handle_frame(&Frame::new(0x000, &[0x82, 0x05]), now, &mut NoHooks, &mut out);
        out.clear();
        node.handle_frame(&Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), now, &mut NoHooks, &mut out);
        prop_assert_eq!(out, vec![fr("585#4300100092010200")]);
    }

    #[test]
    fn every_frame_sent_is_well_formed(frames in proptest::collection::vec(any_frame(), 0..64)) {
        let mut node = Node::new(NodeConfig::new(7));
        let mut out = Vec::new();
        let mut now = Instant::ZERO;
        node.boot(now, &mut NoHooks, &mut out);
        for f in &frames {
            now += Duration::from_millis(1);
            node.handle_frame(f, now, &mut NoHooks, &mut out);
            node.poll(now, &mut NoHooks, &mut out);
        }
        for f in &out {
            // SDO responses are always 8 bytes on 587h.
            if f.std_id() == Some(0x587) { prop_assert_eq!(f.len(), 8); }
            prop_assert!(!f.is_rtr());
        }
    }
}
