//! CiA 301 objects the node would create but a manual does not list are
//! absent from the drive's dictionary (`NodeConfig::emcy_inhibit`,
//! `sync_window`, `sync_counter`, `sdo_server_param`): an SDO upload is
//! refused as for any missing object, where the drive documents them it
//! still works (and without 1200h the default SDO server answers all the
//! same — every upload here goes through it).
//!
//! * KC1 (seed000) §8.1.2 "Communication SDOs": 1005h, 1006h, 1014h, 1016h
//!   … but no 1007h, 1015h, 1019h, 1200h ("EMCY inhibit time is not in the
//!   object dictionary", reference B.7/B.14);
//! * AKD (seed001) §7.1.3 "Kommunikations-SDOs": the same list;
//! * iPOS (seed002): no SYNC/EMCY/SDO communication objects at all
//!   (EtherCAT); served on CAN it answers 1005h/1006h/1014h and the PDO
//!   communication records its EDS describes, not 1007h, 1015h, 1019h,
//!   1200h;
//! * SSD 630 (seed003) §4 object list: 1015h "Inhibit time EMCY" but no
//!   1007h/1019h/1200h; a missing object is answered 0601 0000h (§14.1);
//! * DDS6 (seed004) §6.3.13: 1015h in 0.1 ms, §6.3.18: 1200h;
//! * generic: every CiA 301 object.

mod replay_rig;

use drivebus_personality::Profile;
use replay_rig::*;

/// CiA 301 §7.2.4.3.17: "object does not exist in the object dictionary".
const NO_OBJECT: u32 = 0x0602_0000;

fn upload(p: Profile, index: u16) -> Result<(), u32> {
    let (mut r, _) = Rig::new(p, 2);
    let f = r.sdo_read(2, index, 0);
    let d = f.data();
    if d[0] == 0x80 {
        return Err(u32::from_le_bytes([d[4], d[5], d[6], d[7]]));
    }
    assert_eq!(d[0] & 0xE0, 0x40, "{p} {index:04X}h: {f:?}");
    Ok(())
}

#[test]
fn kc1_has_no_1015h() {
    assert_eq!(upload(Profile::Kc1, 0x1015), Err(NO_OBJECT));
    // The generic drive keeps it (CiA 301 §7.5.2.11).
    assert_eq!(upload(Profile::Generic, 0x1015), Ok(()));
}

#[test]
fn optional_objects_follow_the_manuals() {
    use Profile::*;
    // (profile, 1007h, 1015h, 1019h, 1200h present, abort for a missing object)
    let table = [
        (Kc1, false, false, false, false, NO_OBJECT),
        (Akd, false, false, false, false, NO_OBJECT),
        (Ipos, false, false, false, false, NO_OBJECT),
        (Ssd630, false, true, false, false, 0x0601_0000),
        // 1015h and 1200h listed (§6.3.13, §6.3.18), 1007h and 1019h not.
        (Dds6, false, true, false, true, NO_OBJECT),
        (Generic, true, true, true, true, NO_OBJECT),
    ];
    for (p, window, inhibit, counter, sdo, abort) in table {
        for (index, present) in [(0x1007, window), (0x1015, inhibit), (0x1019, counter), (0x1200, sdo)] {
            let want = if present { Ok(()) } else { Err(abort) };
            assert_eq!(upload(p, index), want, "{p} {index:04X}h");
        }
    }
    // 1006h is absent from the DDS6's §6.3 list too: not answered either
    // (the SYNC consumer never needs it; build/conform.rs).
    assert_eq!(upload(Dds6, 0x1006), Err(NO_OBJECT));
    assert_eq!(upload(Kc1, 0x1006), Ok(()));
}
