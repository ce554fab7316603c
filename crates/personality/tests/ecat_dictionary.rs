//! The personalities' EtherCAT dictionaries (`ecat::build`): the CAN
//! communication objects the CoE object list lacks are gone, the sync
//! manager objects are there, and the CoE rules run on the node's write
//! path with the ESM state the EtherCAT layer reports.

use drivebus_can::{Frame, Instant};
use drivebus_coe::AlState;
use drivebus_node::{MemoryStorage, NmtState};
use drivebus_od::SdoAbort;
use drivebus_personality::Profile;
use drivebus_personality::ecat::{self, EsmEvent};

fn build(p: Profile) -> drivebus_personality::PersonalityDevice {
    let mut d = ecat::build(p, Box::new(MemoryStorage::new())).unwrap();
    let mut out: Vec<Frame> = Vec::new();
    drivebus_can::Device::start(&mut d, Instant::ZERO, &mut out);
    d
}

fn state(d: &mut drivebus_personality::PersonalityDevice, from: AlState, to: AlState) -> Vec<Frame> {
    let mut out = Vec::new();
    ecat::esm_event(d, EsmEvent::Changed { from, to }, Instant::from_millis(1), &mut out);
    out
}

#[test]
fn ipos_dictionary_is_appendix_a_plus_sync_parameters() {
    let d = build(Profile::Ipos);
    let od = d.node.od();
    // Appendix A has no CAN communication objects.
    for i in [0x1005u16, 0x1006, 0x1014, 0x1400, 0x1403, 0x1800, 0x1803] {
        assert!(od.object(i).is_none(), "{i:04X}h");
    }
    for i in [0x1C00u16, 0x1C12, 0x1C13, 0x1C32, 0x1C33, 0x1600, 0x1A03] {
        assert!(od.object(i).is_some(), "{i:04X}h");
    }
    // §2.3 default assignment; 1018h:03 is the firmware ID.
    assert_eq!(ecat::rules::assigned(od, 0x1C12), [0x1600]);
    assert_eq!(ecat::rules::assigned(od, 0x1C13), [0x1A00, 0x1A01]);
    assert_eq!(od.get_u32(0x1018, 3), Some(0x4130_3047));
    assert_eq!(od.get_u32(0x1C32, 5), Some(1_000_000), "§3.2: the 1 ms slow loop");
}

#[test]
fn generic_dictionary_has_no_cob_ids() {
    let d = build(Profile::Generic);
    let od = d.node.od();
    for i in [0x1005u16, 0x100C, 0x1012, 0x1014, 0x1017, 0x1200, 0x1400, 0x1800, 0x1029] {
        assert!(od.object(i).is_none(), "{i:04X}h");
    }
    for i in [0x1003u16, 0x1010, 0x1011, 0x1C00, 0x1C12, 0x1C13, 0x1C32] {
        assert!(od.object(i).is_some(), "{i:04X}h");
    }
    assert_eq!(ecat::rules::assigned(od, 0x1C12), [0x1602]);
    assert_eq!(ecat::rules::assigned(od, 0x1C13), [0x1A02]);
}

#[test]
fn assignment_changes_only_in_pre_op_with_sub_0_zero() {
    for p in [Profile::Ipos, Profile::Generic] {
        let mut d = build(p);
        let mut out: Vec<Frame> = Vec::new();
        let t = Instant::from_millis(2);
        let mut w = |d: &mut drivebus_personality::PersonalityDevice, i, s, v: &[u8]| {
            d.write_object(i, s, v, t, &mut out)
        };
        // INIT: no writes (no mailbox; a local tool is refused too).
        assert_eq!(w(&mut d, 0x1C12, 0, &[0]), Err(SdoAbort::DEVICE_STATE), "{p}");
        state(&mut d, AlState::Init, AlState::PreOp);
        assert_eq!(d.node.nmt_state(), NmtState::PreOperational);
        assert_eq!(w(&mut d, 0x1C12, 1, &0x1601u16.to_le_bytes()), Err(SdoAbort(0x0601_0003)), "{p}");
        w(&mut d, 0x1C12, 0, &[0]).unwrap();
        w(&mut d, 0x1C12, 1, &0x1601u16.to_le_bytes()).unwrap();
        assert_eq!(w(&mut d, 0x1C12, 2, &0x1A00u16.to_le_bytes()), Err(SdoAbort::INVALID_VALUE), "{p}");
        assert_eq!(w(&mut d, 0x1C12, 0, &[2]), Err(SdoAbort::INVALID_VALUE), "{p}: sub 2 names nothing");
        w(&mut d, 0x1C12, 0, &[1]).unwrap();
        // Mapping: entries only while sub 0 = 0, each one checked.
        assert_eq!(w(&mut d, 0x1601, 1, &0x6040_0010u32.to_le_bytes()), Err(SdoAbort(0x0601_0003)), "{p}");
        w(&mut d, 0x1601, 0, &[0]).unwrap();
        assert_eq!(w(&mut d, 0x1601, 1, &0x6041_0010u32.to_le_bytes()), Err(SdoAbort::NOT_MAPPABLE), "{p}");
        assert_eq!(w(&mut d, 0x1601, 1, &0x6040_0008u32.to_le_bytes()), Err(SdoAbort::NOT_MAPPABLE), "{p}");
        w(&mut d, 0x1601, 1, &0x6040_0010u32.to_le_bytes()).unwrap();
        w(&mut d, 0x1601, 0, &[1]).unwrap();
        state(&mut d, AlState::PreOp, AlState::SafeOp);
        assert_eq!(d.node.nmt_state(), NmtState::Operational);
        assert_eq!(w(&mut d, 0x1C12, 0, &[0]), Err(SdoAbort::DEVICE_STATE), "{p}");
        assert_eq!(w(&mut d, 0x1601, 0, &[0]), Err(SdoAbort::DEVICE_STATE), "{p}");
        assert_eq!(w(&mut d, 0x1C32, 1, &2u16.to_le_bytes()), Err(SdoAbort::DEVICE_STATE), "{p}");
    }
}

#[test]
fn ipos_mapping_over_64_bits_sends_8220h_and_is_ignored() {
    let mut d = build(Profile::Ipos);
    state(&mut d, AlState::Init, AlState::PreOp);
    let mut out: Vec<Frame> = Vec::new();
    let t = Instant::from_millis(2);
    d.write_object(0x1A03, 0, &[0], t, &mut out).unwrap();
    for (s, e) in [(1u8, 0x6064_0020u32), (2, 0x60FD_0020), (3, 0x6041_0010)] {
        d.write_object(0x1A03, s, &e.to_le_bytes(), t, &mut out).unwrap();
    }
    out.clear();
    // §1.6.3.1: confirmed, EMCY 8220h, the count stays.
    d.write_object(0x1A03, 0, &[3], t, &mut out).unwrap();
    assert_eq!(d.node.od().get_u32(0x1A03, 0), Some(0));
    assert!(out.iter().any(|f| f.std_id() == Some(0x81) && f.data()[..2] == [0x20, 0x82]), "{out:?}");
    // The generic servo refuses it.
    let mut g = build(Profile::Generic);
    state(&mut g, AlState::Init, AlState::PreOp);
    g.write_object(0x1A03, 0, &[0], t, &mut out).unwrap();
    for (s, e) in [(1u8, 0x6064_0020u32), (2, 0x606C_0020), (3, 0x6041_0010)] {
        g.write_object(0x1A03, s, &e.to_le_bytes(), t, &mut out).unwrap();
    }
    assert_eq!(g.write_object(0x1A03, 0, &[3], t, &mut out), Err(SdoAbort::PDO_TOO_LONG));
}

#[test]
fn communication_error_reporting() {
    let mut d = build(Profile::Ipos);
    state(&mut d, AlState::Init, AlState::PreOp);
    let mut out: Vec<Frame> = Vec::new();
    // A refused transition: EMCY A0xxh with the AL code.
    ecat::esm_event(&mut d, EsmEvent::Error(0x001D), Instant::from_millis(3), &mut out);
    assert!(out.iter().any(|f| f.data()[..2] == [0x1D, 0xA0]), "{out:?}");
    out.clear();
    // The watchdog: 2000h bit 0 and EMCY 8100h until acknowledged.
    ecat::esm_event(&mut d, EsmEvent::Error(0x001B), Instant::from_millis(4), &mut out);
    assert!(out.iter().any(|f| f.data()[..3] == [0x00, 0x81, 0x11]), "{out:?}");
    assert_eq!(d.node.od().get_u32(0x2000, 0).unwrap() & 1, 1);
    out.clear();
    ecat::esm_event(&mut d, EsmEvent::Acknowledged, Instant::from_millis(5), &mut out);
    assert_eq!(d.node.od().get_u32(0x2000, 0).unwrap() & 1, 0);
    assert!(out.iter().any(|f| f.data()[..2] == [0, 0]), "error reset EMCY: {out:?}");
}
