//! No input frame can make the client panic: random server frames (any
//! DLC, any bytes, valid-looking command specifiers favoured) in every state
//! of every protocol, interleaved with polls.

use drivebus_can::{Duration, Frame, Instant};
use drivebus_sdo::client::{Protocol, SdoClient, SdoClientConfig};
use proptest::prelude::*;

/// A server frame: mostly 8 bytes with a plausible byte 0 and the expected
/// multiplexer, sometimes anything.
fn server_frame() -> impl Strategy<Value = Vec<u8>> {
    let b0 = prop_oneof![
        any::<u8>(),
        prop::sample::select(vec![
            0x00, 0x01, 0x0F, 0x10, 0x11, 0x1F, 0x20, 0x30, 0x40, 0x41, 0x43, 0x4F, 0x60, 0x80, 0x81, 0xA0,
            0xA1, 0xA2, 0xA4, 0xC0, 0xC1, 0xC4, 0xC6, 0xC9, 0xFD, 0xFF,
        ]),
    ];
    prop_oneof![
        8 => (b0, any::<[u8; 4]>(), any::<bool>()).prop_map(|(b0, d, mux)| {
            let (lo, hi, sub) = if mux { (0x00, 0x20, 0x01) } else { (d[0], d[1], d[2]) };
            vec![b0, lo, hi, sub, d[0], d[1], d[2], d[3]]
        }),
        1 => prop::collection::vec(any::<u8>(), 0..=8),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn random_responses_never_panic(
        upload in any::<bool>(),
        proto in 0usize..4,
        len in prop_oneof![0usize..10, 10usize..2000],
        blksize in 0u8..=255,
        pst in any::<u8>(),
        crc in any::<bool>(),
        max_upload in prop_oneof![Just(usize::MAX), 0usize..100],
        steps in prop::collection::vec((server_frame(), 0u64..1500, any::<bool>()), 1..60),
    ) {
        let mut cfg = SdoClientConfig::for_node(1);
        cfg.block_size = blksize;
        cfg.pst = pst;
        cfg.crc = crc;
        cfg.max_upload = max_upload;
        let mut c = SdoClient::new(cfg);
        let p = [Protocol::Auto, Protocol::Expedited, Protocol::Segmented, Protocol::Block][proto];
        let mut out: Vec<Frame> = Vec::new();
        let mut now = Instant::ZERO;
        let data = vec![0xA5u8; len];
        let started = if upload {
            c.start_upload(0x2000, 1, p, now, &mut out)
        } else {
            c.start_download(0x2000, 1, &data, p, now, &mut out)
        };
        for (bytes, dt, poll) in steps {
            now += Duration::from_millis(dt);
            if poll {
                c.poll(now, &mut out);
            }
            c.handle_frame(&Frame::new(0x581, &bytes), now, &mut out);
            if let Some((done, Some(total))) = c.progress() {
                prop_assert!(done <= total);
            }
            if !c.is_busy() && started.is_ok() {
                // Start again so every state keeps getting exercised.
                c.take_result();
                let _ = c.start_upload(0x2000, 1, Protocol::Block, now, &mut out);
            }
        }
        for f in &out {
            prop_assert_eq!(f.std_id(), Some(0x601));
            prop_assert_eq!(f.len(), 8);
        }
    }
}
