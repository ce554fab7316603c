//! Random frame sequences never panic the server and never leave it stuck.
//! `fuzz/fuzz_targets/sdo_server.rs` decodes its input the same way.

mod server_support;

use drivebus_can::{CanId, Duration, Frame, Instant};
use drivebus_od::NoHooks;
use drivebus_sdo::server::{SdoServer, ServerConfig};
use proptest::prelude::*;
use server_support::{NODE, RX, TX, test_od};

/// Objects of the test dictionary.
const OBJECTS: [(u16, u8); 6] =
    [(0x1000, 0), (0x1007, 0), (0x2000, 0), (0x2001, 0), (0x2010, 1), (0x2010, 2)];
/// Command bytes that reach every state quickly (block segments included).
const COMMANDS: [u8; 24] = [
    0x40, 0x21, 0x20, 0x23, 0x60, 0x70, 0x00, 0x10, 0xA4, 0xA3, 0xA2, 0xA1, 0xC6, 0xC1, 0x80, 0x81, 0x01,
    0x02, 0x03, 0x04, 0x82, 0x83, 0x84, 0xC2,
];

/// 12 bytes per step: selector, two id bytes, time step, 8 data bytes.
fn run(input: &[u8], check_recovery: bool) {
    let mut od = test_od(100);
    let mut s = SdoServer::default_channel(NODE, ServerConfig { block_size: 4, ..ServerConfig::default() });
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
    assert!(out.iter().all(|f| f.id() == CanId::Standard(TX) && f.len() == 8 && !f.is_rtr()));
    if !check_recovery {
        return;
    }
    // Whatever state it is in, after the timeout the server is idle and a
    // fresh expedited upload works.
    now += Duration::from_millis(1001);
    s.poll(now, &mut out);
    assert!(s.is_idle());
    assert_eq!(s.poll(now, &mut out), None);
    out.clear();
    s.handle_frame(&Frame::new8(RX, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), now, &mut od, &mut NoHooks, &mut out);
    assert_eq!(out, [Frame::new8(TX, [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00])]);
}

/// Same, but recovering with a client abort instead of the timeout.
fn run_then_abort(input: &[u8]) {
    run(input, false);
    let mut od = test_od(100);
    let mut s = SdoServer::default_channel(NODE, ServerConfig::default());
    let mut out: Vec<Frame> = Vec::new();
    let now = Instant::ZERO;
    for step in input.chunks_exact(8) {
        let mut d = [0u8; 8];
        d.copy_from_slice(step);
        d[0] = COMMANDS[usize::from(d[0]) % COMMANDS.len()];
        s.handle_frame(&Frame::new8(RX, d), now, &mut od, &mut NoHooks, &mut out);
    }
    s.handle_frame(&Frame::new8(RX, [0x80, 0, 0, 0, 0, 0, 0, 0]), now, &mut od, &mut NoHooks, &mut out);
    assert!(s.is_idle());
    out.clear();
    s.handle_frame(&Frame::new8(RX, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), now, &mut od, &mut NoHooks, &mut out);
    assert_eq!(out, [Frame::new8(TX, [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00])]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn random_frames_never_panic_nor_stick(input in proptest::collection::vec(any::<u8>(), 0..12 * 64)) {
        run(&input, true);
    }

    #[test]
    fn random_commands_then_client_abort(input in proptest::collection::vec(any::<u8>(), 0..8 * 64)) {
        run_then_abort(&input);
    }
}

#[test]
fn fixed_sequences() {
    run(&[], true);
    // Start a block download and stop in the middle of a sub-block.
    let mut input = Vec::new();
    let mut step = |sel: u8, dt: u8, d: [u8; 8]| {
        input.extend_from_slice(&[sel, 0, 0, dt]);
        input.extend_from_slice(&d);
    };
    step(0x40, 0, [0xC6, 0x00, 0x20, 0, 50, 0, 0, 0]);
    step(0x40, 0, [0x01, 1, 2, 3, 4, 5, 6, 7]);
    step(0x40, 0, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
    run(&input, true);
    run_then_abort(&input[4..]);
}
