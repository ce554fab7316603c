//! Frame-exact tests of every LSS slave service (CiA 305 v3.0.0), positive
//! and negative. Identities are the 1018h values of the reference drives
//! (none of them documents LSS, see the crate docs): DDS6 vendor 030Ch,
//! product 00604100h "DDS6041" (`seed004-dds6-objects.tsv`, §6.3.16) and
//! Kollmorgen (KC1/AKD) vendor 6Ah (`seed000-kc1-objects.tsv`, §7.2.1.17).

use drivebus_can::{Frame, Instant};
use drivebus_lss::codec::LssField;
use drivebus_lss::{Identity, LssAddressRange, LssEvent, LssMode, LssSlave, StoreStatus, master};

const DDS6: Identity = Identity::new(0x0000_030C, 0x0060_4100, 0x0001_0002, 0x0000_1234);
const KC1: Identity = Identity::new(0x0000_006A, u32::from_le_bytes(*b"M006"), 0x0014_0000, 0x0A21_5678);

const T: Instant = Instant::ZERO;

fn req(bytes: [u8; 8]) -> Frame {
    Frame::new8(0x7E5, bytes)
}

fn rsp(bytes: [u8; 8]) -> Frame {
    Frame::new8(0x7E4, bytes)
}

/// Feed one frame, return (event, frames sent).
fn feed(s: &mut LssSlave, f: Frame) -> (Option<LssEvent>, Vec<Frame>) {
    let mut out = Vec::new();
    let ev = s.handle_frame(&f, T, &mut out);
    (ev, out)
}

fn configured_slave() -> LssSlave {
    let mut s = LssSlave::new(DDS6, 5, 3);
    let (ev, out) = feed(&mut s, master::switch_state_global(LssMode::Configuration));
    assert_eq!(ev, Some(LssEvent::EnteredConfiguration));
    assert!(out.is_empty());
    s
}

#[test]
fn switch_state_global_both_ways_no_response() {
    let mut s = LssSlave::new(DDS6, 5, 3);
    assert_eq!(s.mode(), LssMode::Waiting);
    let (ev, out) = feed(&mut s, req([0x04, 0x01, 0, 0, 0, 0, 0, 0]));
    assert_eq!((ev, out.len(), s.mode()), (Some(LssEvent::EnteredConfiguration), 0, LssMode::Configuration));
    // Repeating the current state is not a transition.
    assert_eq!(feed(&mut s, req([0x04, 0x01, 0, 0, 0, 0, 0, 0])).0, None);
    let (ev, out) = feed(&mut s, req([0x04, 0x00, 0, 0, 0, 0, 0, 0]));
    assert_eq!((ev, out.len(), s.mode()), (Some(LssEvent::EnteredWaiting), 0, LssMode::Waiting));
    // Undefined mode byte: ignored.
    assert_eq!(feed(&mut s, req([0x04, 0x02, 0, 0, 0, 0, 0, 0])), (None, vec![]));
    assert_eq!(s.mode(), LssMode::Waiting);
}

#[test]
fn switch_state_selective_full_match() {
    let mut s = LssSlave::new(DDS6, 5, 3);
    let frames = master::switch_state_selective(&DDS6);
    for f in &frames[..3] {
        assert_eq!(feed(&mut s, *f), (None, vec![]));
    }
    let (ev, out) = feed(&mut s, frames[3]);
    assert_eq!(ev, Some(LssEvent::EnteredConfiguration));
    assert_eq!(out, vec![rsp([0x44, 0, 0, 0, 0, 0, 0, 0])]);
    assert_eq!(s.mode(), LssMode::Configuration);
}

#[test]
fn switch_state_selective_partial_and_wrong_matches() {
    let mut s = LssSlave::new(DDS6, 5, 3);
    let good = master::switch_state_selective(&DDS6);

    // Each single wrong part prevents the switch.
    for field in LssField::ALL {
        let mut wrong = DDS6;
        field.set(&mut wrong, field.get(&DDS6) ^ 1);
        for f in master::switch_state_selective(&wrong) {
            assert_eq!(feed(&mut s, f), (None, vec![]), "{field:?}");
        }
        assert_eq!(s.mode(), LssMode::Waiting);
    }
    // Out of order: serial before revision.
    for f in [good[0], good[1], good[3], good[2]] {
        assert_eq!(feed(&mut s, f), (None, vec![]));
    }
    // Missing the vendor frame.
    for f in &good[1..] {
        assert_eq!(feed(&mut s, *f), (None, vec![]));
    }
    // An interrupted sequence restarts on the next vendor frame and succeeds.
    for f in [good[0], good[1], good[0], good[1], good[2]] {
        assert_eq!(feed(&mut s, f), (None, vec![]));
    }
    assert_eq!(feed(&mut s, good[3]).1, vec![rsp([0x44, 0, 0, 0, 0, 0, 0, 0])]);
    // Another device's address never selects this one.
    let mut other = LssSlave::new(KC1, 7, 3);
    for f in good {
        assert_eq!(feed(&mut other, f), (None, vec![]));
    }
    // Already in configuration: selective is not a configuration service.
    for f in good {
        assert_eq!(feed(&mut s, f), (None, vec![]));
    }
}

#[test]
fn configure_node_id_valid_and_out_of_range() {
    let mut s = configured_slave();
    for id in [1u8, 42, 127, 0xFF] {
        let (ev, out) = feed(&mut s, master::configure_node_id(id));
        assert_eq!(ev, Some(LssEvent::NodeIdConfigured(id)));
        assert_eq!(out, vec![rsp([0x11, 0, 0, 0, 0, 0, 0, 0])]);
        assert_eq!(s.pending_node_id(), id);
        // Pending only: the active node-ID changes on reset communication.
        assert_eq!(s.active_node_id(), 5);
    }
    feed(&mut s, master::configure_node_id(9));
    for id in [0u8, 128, 0xFE] {
        let (ev, out) = feed(&mut s, req([0x11, id, 0, 0, 0, 0, 0, 0]));
        assert_eq!(ev, None);
        assert_eq!(out, vec![rsp([0x11, 1, 0, 0, 0, 0, 0, 0])], "node-ID {id}");
        assert_eq!(s.pending_node_id(), 9);
    }
    assert_eq!(s.reset_communication(), 9);
    assert_eq!(s.active_node_id(), 9);
}

#[test]
fn configuration_services_ignored_in_waiting() {
    let mut s = LssSlave::new(DDS6, 5, 3);
    for f in [
        master::configure_node_id(9),
        master::configure_bit_timing(2),
        master::activate_bit_timing(10),
        master::store_configuration(),
        master::inquire_identity(LssField::Vendor),
        master::inquire_node_id(),
    ] {
        assert_eq!(feed(&mut s, f), (None, vec![]), "{f}");
    }
    assert_eq!((s.pending_node_id(), s.pending_bit_timing()), (5, 3));
}

#[test]
fn configure_bit_timing_standard_table() {
    let mut s = configured_slave();
    // CiA 305 table: 0 1000, 1 800, 2 500, 3 250, 4 125, 6 50, 7 20, 8 10 kbit/s.
    for index in [0u8, 1, 2, 3, 4, 6, 7, 8] {
        let (ev, out) = feed(&mut s, master::configure_bit_timing(index));
        assert_eq!(ev, Some(LssEvent::BitTimingConfigured(index)));
        assert_eq!(out, vec![rsp([0x13, 0, 0, 0, 0, 0, 0, 0])]);
        assert_eq!(s.pending_bit_timing(), index);
    }
    // Reserved 5, automatic 9, beyond the table, and a non-standard table selector.
    for (table, index) in [(0u8, 5u8), (0, 9), (0, 10), (0, 0xFF), (1, 2), (0x80, 2)] {
        let (ev, out) = feed(&mut s, req([0x13, table, index, 0, 0, 0, 0, 0]));
        assert_eq!(ev, None);
        assert_eq!(out, vec![rsp([0x13, 1, 0, 0, 0, 0, 0, 0])], "table {table} index {index}");
    }
    assert_eq!(s.pending_bit_timing(), 8);
    assert_eq!(s.active_bit_timing(), 3);
}

#[test]
fn bit_timing_mask_restricts_and_extends() {
    // A device that only does 125..500 kbit/s, plus automatic detection.
    let mut s = LssSlave::new(DDS6, 5, 3).with_bit_timings(0b10_0001_1100);
    feed(&mut s, master::switch_state_global(LssMode::Configuration));
    assert_eq!(feed(&mut s, master::configure_bit_timing(0)).1, vec![rsp([0x13, 1, 0, 0, 0, 0, 0, 0])]);
    assert_eq!(feed(&mut s, master::configure_bit_timing(9)).1, vec![rsp([0x13, 0, 0, 0, 0, 0, 0, 0])]);
    assert_eq!(feed(&mut s, master::configure_bit_timing(4)).1, vec![rsp([0x13, 0, 0, 0, 0, 0, 0, 0])]);
}

#[test]
fn activate_bit_timing_event_without_response() {
    let mut s = configured_slave();
    feed(&mut s, master::configure_bit_timing(2));
    let (ev, out) = feed(&mut s, req([0x15, 0xE8, 0x03, 0, 0, 0, 0, 0]));
    assert_eq!(ev, Some(LssEvent::ActivateBitTiming { delay_ms: 1000 }));
    assert!(out.is_empty());
    assert_eq!(s.active_bit_timing(), 2);
}

#[test]
fn store_configuration_outcomes() {
    let mut s = configured_slave();
    feed(&mut s, master::configure_node_id(12));
    feed(&mut s, master::configure_bit_timing(4));
    let (ev, out) = feed(&mut s, master::store_configuration());
    assert_eq!(ev, Some(LssEvent::StoreRequested { node_id: 12, bit_timing: 4 }));
    assert!(out.is_empty(), "the node answers through complete_store");
    for (status, code) in
        [(StoreStatus::Stored, 0u8), (StoreStatus::NotSupported, 1), (StoreStatus::AccessError, 2)]
    {
        let mut out = Vec::new();
        assert!(s.complete_store(status, &mut out));
        assert_eq!(out, vec![rsp([0x17, code, 0, 0, 0, 0, 0, 0])]);
        // Exactly one answer per request.
        assert!(!s.complete_store(status, &mut out));
        assert_eq!(out.len(), 1);
        feed(&mut s, master::store_configuration());
    }
    // A device without storage answers "not supported" by itself.
    let mut s = LssSlave::new(DDS6, 5, 3).with_store_supported(false);
    feed(&mut s, master::switch_state_global(LssMode::Configuration));
    let (ev, out) = feed(&mut s, master::store_configuration());
    assert_eq!((ev, out), (None, vec![rsp([0x17, 1, 0, 0, 0, 0, 0, 0])]));
}

#[test]
fn inquire_identity_and_node_id() {
    let mut s = configured_slave();
    let expect = [
        (LssField::Vendor, [0x5A, 0x0C, 0x03, 0x00, 0x00, 0, 0, 0]),
        (LssField::Product, [0x5B, 0x00, 0x41, 0x60, 0x00, 0, 0, 0]),
        (LssField::Revision, [0x5C, 0x02, 0x00, 0x01, 0x00, 0, 0, 0]),
        (LssField::Serial, [0x5D, 0x34, 0x12, 0x00, 0x00, 0, 0, 0]),
    ];
    for (field, bytes) in expect {
        assert_eq!(feed(&mut s, master::inquire_identity(field)), (None, vec![rsp(bytes)]));
    }
    // A configured device reports its active node-ID until reset communication.
    feed(&mut s, master::configure_node_id(20));
    assert_eq!(feed(&mut s, master::inquire_node_id()).1, vec![rsp([0x5E, 5, 0, 0, 0, 0, 0, 0])]);
    s.reset_communication();
    assert_eq!(feed(&mut s, master::inquire_node_id()).1, vec![rsp([0x5E, 20, 0, 0, 0, 0, 0, 0])]);
    // An unconfigured one reports FFh, then what the master configured.
    let mut u = LssSlave::new(KC1, 0xFF, 4);
    feed(&mut u, master::switch_state_global(LssMode::Configuration));
    assert_eq!(feed(&mut u, master::inquire_node_id()).1, vec![rsp([0x5E, 0xFF, 0, 0, 0, 0, 0, 0])]);
    feed(&mut u, master::configure_node_id(33));
    assert_eq!(feed(&mut u, master::inquire_node_id()).1, vec![rsp([0x5E, 33, 0, 0, 0, 0, 0, 0])]);
}

fn range(addr: &Identity, rev: (u32, u32), serial: (u32, u32)) -> LssAddressRange {
    LssAddressRange {
        vendor_id: addr.vendor_id,
        product_code: addr.product_code,
        revision_low: rev.0,
        revision_high: rev.1,
        serial_low: serial.0,
        serial_high: serial.1,
    }
}

fn identify(s: &mut LssSlave, r: &LssAddressRange) -> Vec<Frame> {
    let mut all = Vec::new();
    for (i, f) in master::identify_remote_slave(r).into_iter().enumerate() {
        let (ev, out) = feed(s, f);
        assert_eq!(ev, None);
        if i < 5 {
            assert!(out.is_empty());
        }
        all.extend(out);
    }
    all
}

#[test]
fn identify_remote_slave_ranges() {
    let hit = vec![rsp([0x4F, 0, 0, 0, 0, 0, 0, 0])];
    let (rev, ser) = (DDS6.revision, DDS6.serial);
    for mode in [LssMode::Waiting, LssMode::Configuration] {
        let mut s = LssSlave::new(DDS6, 5, 3);
        feed(&mut s, master::switch_state_global(mode));
        // Inside: exact, inclusive bounds, wide.
        assert_eq!(identify(&mut s, &range(&DDS6, (rev, rev), (ser, ser))), hit);
        assert_eq!(identify(&mut s, &range(&DDS6, (rev - 1, rev), (ser, ser + 1))), hit);
        assert_eq!(identify(&mut s, &range(&DDS6, (0, u32::MAX), (0, u32::MAX))), hit);
        // Outside: each bound just missing, wrong vendor or product, empty range.
        for r in [
            range(&DDS6, (rev + 1, u32::MAX), (0, u32::MAX)),
            range(&DDS6, (0, rev - 1), (0, u32::MAX)),
            range(&DDS6, (0, u32::MAX), (ser + 1, u32::MAX)),
            range(&DDS6, (0, u32::MAX), (0, ser - 1)),
            range(&KC1, (0, u32::MAX), (0, u32::MAX)),
            LssAddressRange { product_code: 0x0060_4101, ..range(&DDS6, (0, u32::MAX), (0, u32::MAX)) },
            range(&DDS6, (rev, rev), (ser + 1, ser)),
        ] {
            assert_eq!(identify(&mut s, &r), vec![], "{r:?}");
        }
        assert_eq!(s.mode(), mode, "identify never changes the state");
    }
    // Frames out of order or with a step missing give no answer.
    let mut s = LssSlave::new(DDS6, 5, 3);
    let f = master::identify_remote_slave(&range(&DDS6, (0, u32::MAX), (0, u32::MAX)));
    for order in [[0usize, 1, 2, 3, 5, 5], [1, 2, 3, 4, 5, 5], [0, 1, 3, 2, 4, 5]] {
        let mut out = Vec::new();
        for i in order {
            out.extend(feed(&mut s, f[i]).1);
        }
        assert!(out.is_empty(), "{order:?}");
    }
}

#[test]
fn identify_non_configured_remote_slave() {
    let hit = vec![rsp([0x50, 0, 0, 0, 0, 0, 0, 0])];
    let mut u = LssSlave::new(KC1, 0xFF, 4);
    assert!(u.is_lss_only() && u.is_non_configured());
    assert_eq!(feed(&mut u, master::identify_non_configured()), (None, hit.clone()));
    // In configuration too.
    feed(&mut u, master::switch_state_global(LssMode::Configuration));
    assert_eq!(feed(&mut u, master::identify_non_configured()).1, hit);
    // Once a node-ID is pending the slave is no longer non-configured.
    feed(&mut u, master::configure_node_id(3));
    assert_eq!(feed(&mut u, master::identify_non_configured()).1, vec![]);
    // A configured slave never answers.
    let mut c = LssSlave::new(DDS6, 5, 3);
    assert_eq!(feed(&mut c, master::identify_non_configured()).1, vec![]);
    // Invalid stored node-IDs (0, 128) count as unconfigured.
    for id in [0u8, 128] {
        let mut z = LssSlave::new(DDS6, id, 3);
        assert_eq!(z.active_node_id(), 0xFF);
        assert_eq!(feed(&mut z, master::identify_non_configured()).1.len(), 1);
    }
}

#[test]
fn unconfigured_boot_leaves_lss_only_on_switch_to_waiting() {
    let mut u = LssSlave::new(KC1, 0xFF, 4);
    // Selected, configured, stored...
    for f in &master::switch_state_selective(&KC1)[..3] {
        feed(&mut u, *f);
    }
    assert_eq!(feed(&mut u, master::switch_state_selective(&KC1)[3]).0, Some(LssEvent::EnteredConfiguration));
    assert_eq!(feed(&mut u, master::configure_node_id(45)).0, Some(LssEvent::NodeIdConfigured(45)));
    assert_eq!(
        feed(&mut u, master::store_configuration()).0,
        Some(LssEvent::StoreRequested { node_id: 45, bit_timing: 4 })
    );
    let mut out = Vec::new();
    u.complete_store(StoreStatus::Stored, &mut out);
    assert!(u.is_lss_only());
    // ...then back to waiting: the device must reset communication by itself.
    let (ev, out) = feed(&mut u, master::switch_state_global(LssMode::Waiting));
    assert_eq!(ev, Some(LssEvent::ResetCommunication { node_id: 45 }));
    assert!(out.is_empty());
    assert_eq!(u.reset_communication(), 45);
    assert!(!u.is_lss_only());
    // A configured device just re-enters waiting; its new ID waits for NMT.
    let mut c = configured_slave();
    feed(&mut c, master::configure_node_id(6));
    assert_eq!(feed(&mut c, master::switch_state_global(LssMode::Waiting)).0, Some(LssEvent::EnteredWaiting));
    assert_eq!(c.active_node_id(), 5);
    // Configuring FFh on an unconfigured device keeps it LSS-only.
    let mut v = LssSlave::new(KC1, 0xFF, 4);
    feed(&mut v, master::switch_state_global(LssMode::Configuration));
    feed(&mut v, master::configure_node_id(0xFF));
    assert_eq!(feed(&mut v, master::switch_state_global(LssMode::Waiting)).0, Some(LssEvent::EnteredWaiting));
}

#[test]
fn non_lss_frames_are_ignored() {
    let mut s = configured_slave();
    for f in [
        Frame::new(0x7E5, &[0x5E]),                            // DLC 1
        Frame::new(0x7E5, &[0x5E, 0, 0, 0, 0, 0, 0]),          // DLC 7
        Frame::remote(0x7E5, 8),                               // RTR
        Frame::new8(0x7E4, [0x5E, 0, 0, 0, 0, 0, 0, 0]),       // response id
        Frame::new8(0x605, [0x40, 0x18, 0x10, 1, 0, 0, 0, 0]), // SDO
        Frame::new8(0x7E5, [0x99, 0, 0, 0, 0, 0, 0, 0]),       // unknown cs
    ] {
        assert_eq!(feed(&mut s, f), (None, vec![]), "{f}");
    }
}

#[test]
fn fastscan_slave_rules() {
    let hit = vec![rsp([0x4F, 0, 0, 0, 0, 0, 0, 0])];
    let fs = master::fastscan;
    let mut u = LssSlave::new(DDS6, 0xFF, 4);
    // Reset / confirm presence.
    assert_eq!(feed(&mut u, master::fastscan_reset()), (None, hit.clone()));
    // Vendor 030Ch: bits 31..10 are 0 -> match; bit 9 tested as 0 -> mismatch (it is 1).
    assert_eq!(feed(&mut u, fs(0, 10, 0, 0)).1, hit);
    assert_eq!(feed(&mut u, fs(0, 9, 0, 0)).1, vec![]);
    assert_eq!(feed(&mut u, fs(0x200, 9, 0, 0)).1, hit);
    // Invalid BitChecked, LSSSub or LSSNext, or a part other than LSSPos: silence.
    for f in
        [fs(0x30C, 32, 0, 0), fs(0x30C, 0x7F, 0, 0), fs(0x30C, 0, 4, 0), fs(0x30C, 0, 0, 4), fs(0, 31, 1, 1)]
    {
        assert_eq!(feed(&mut u, f), (None, vec![]), "{f}");
    }
    // Full vendor match moves LSSPos to product; vendor questions are then ignored.
    assert_eq!(feed(&mut u, fs(0x30C, 0, 0, 1)), (None, hit.clone()));
    assert_eq!(feed(&mut u, fs(0x30C, 0, 0, 1)), (None, vec![]));
    assert_eq!(feed(&mut u, fs(0x0060_4100, 0, 1, 2)), (None, hit.clone()));
    assert_eq!(feed(&mut u, fs(0x0001_0002, 0, 2, 3)), (None, hit.clone()));
    // Bit 0 with LSSNext = LSSSub: a match, but not the end of the scan.
    assert_eq!(feed(&mut u, fs(0x1234, 0, 3, 3)), (None, hit.clone()));
    assert_eq!(u.mode(), LssMode::Waiting);
    // Serial confirmed with LSSNext wrapping to 0: configuration.
    assert_eq!(feed(&mut u, fs(0x1234, 0, 3, 0)), (Some(LssEvent::EnteredConfiguration), hit.clone()));
    assert_eq!(u.mode(), LssMode::Configuration);
    // In configuration fastscan is ignored, even the reset.
    assert_eq!(feed(&mut u, master::fastscan_reset()), (None, vec![]));
    // A reset mid-scan starts over at the vendor-ID.
    let mut v = LssSlave::new(DDS6, 0xFF, 4);
    feed(&mut v, fs(0x30C, 0, 0, 1));
    assert_eq!(feed(&mut v, fs(0x30C, 0, 0, 1)).1, vec![]);
    feed(&mut v, master::fastscan_reset());
    assert_eq!(feed(&mut v, fs(0x30C, 0, 0, 1)).1, hit);
    // A configured slave never takes part.
    let mut c = LssSlave::new(DDS6, 5, 4);
    assert_eq!(feed(&mut c, master::fastscan_reset()), (None, vec![]));
    assert_eq!(feed(&mut c, fs(0x30C, 0, 0, 1)), (None, vec![]));
}
