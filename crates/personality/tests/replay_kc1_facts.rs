//! KC1 (seed000) behaviour beyond the printed examples, against
//! `Profile::Kc1.build(..)`: FBUS.PARAM04 SYNC supervision, the fault codes
//! of the §7.1 table, node-ID 0. The example replays are in `replay_kc1.rs`.

mod replay_rig;

use drivebus_personality::Profile;
use replay_rig::*;

/// Node 3, booted (boot-up `703 00` only).
fn node() -> Rig {
    let (r, boot) = Rig::new(Profile::Kc1, 3);
    assert_eq!(boot, frs(&["703#00"]));
    r
}

/// FBUS.PARAM04 (36E8h, §4.4 parameter table: "0 = arrival of SYNC messages
/// is not supervised"): by default a lost SYNC does nothing; with 1, SYNC
/// loss after the first SYNC is fault F125, EMCY 8780h (§7.1).
#[test]
fn kc1_fbus_param04_sync_supervision() {
    for param04 in [0u32, 1] {
        let mut r = node();
        Rig::assert_written(r.sdo_write(3, 0x36E8, 0, &param04.to_le_bytes()), 3, 0x36E8, 0);
        // 1006h: 1 ms communication cycle.
        Rig::assert_written(r.sdo_write(3, 0x1006, 0, &1000u32.to_le_bytes()), 3, 0x1006, 0);
        r.send("000#01 03");
        r.run_ms(1);
        for _ in 0..5 {
            r.send("080#");
            r.run_ms(1);
        }
        r.take();
        r.run_ms(20);
        let f = r.take();
        let emcy: Vec<_> = f.iter().filter(|f| f.std_id() == Some(0x083)).collect();
        if param04 == 0 {
            assert!(emcy.is_empty(), "{f:?}");
        } else {
            // Code 8780h and the category byte 01h; the manual gives no
            // error register for F125.
            let d = emcy.first().map(|f| f.data().to_vec()).unwrap_or_default();
            assert_eq!((d.first(), d.get(1), d.get(3)), (Some(&0x80), Some(&0x87), Some(&0x01)), "{f:?}");
            assert_eq!(r.statusword() & 0x4F, 0x08, "fault");
        }
    }
}

/// §7.1: drive faults are reported with the KC1's codes — output
/// over-current is FF07h (F525), not CiA 402's generic 2310h; codes the
/// table lists (following error 8611h, F439) are sent as they are.
#[test]
fn kc1_fault_codes_from_the_table() {
    let info = Profile::Kc1.info();
    for (fault, expected) in [(0x2310u16, 0xFF07u16), (0x8611, 0x8611)] {
        assert!(info.emcy_text(expected).is_some(), "{expected:04X}h in §7.1");
        let mut r = node();
        r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Fault(fault));
        r.run_ms(1);
        let f = r.take();
        let [lo, hi] = expected.to_le_bytes();
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(
            (f[0].std_id(), f[0].data()[0], f[0].data()[1], f[0].data()[3]),
            (Some(0x083), lo, hi, 0x01)
        );
    }
}

/// §6.2: node-ID 0 from the rotary switches is used as 1 (quirk
/// `node-id-0-is-1`); a profile without the quirk refuses 0.
#[test]
fn kc1_node_id_0_is_1() {
    let (r, boot) = Rig::new(Profile::Kc1, 0);
    assert_eq!(boot, frs(&["701#00"]));
    assert_eq!(r.node().node_id(), 1);
    assert!(Profile::Generic.build(0).is_err());
}
