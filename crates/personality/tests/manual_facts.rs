//! The EDS files and the static facts against the values printed in each
//! manual. Every assertion cites the manual section it comes from.

use drivebus_eds::to_od;
use drivebus_od::ObjectDictionary;
use drivebus_personality::{PdoDefault, Profile, ProfileInfo, Transport};

const NODE: u8 = 3;

fn od(p: Profile) -> ObjectDictionary {
    to_od(&p.parse_eds().eds, NODE).unwrap()
}

fn mapping(od: &ObjectDictionary, index: u16) -> Vec<u32> {
    let n = od.get(index, 0).unwrap().bytes()[0];
    (1..=n).map(|s| od.get_u32(index, s).unwrap()).collect()
}

fn identity(od: &ObjectDictionary) -> [Option<u32>; 5] {
    [
        od.get_u32(0x1000, 0),
        od.get_u32(0x1018, 1),
        od.get_u32(0x1018, 2),
        od.get_u32(0x1018, 3),
        od.get_u32(0x6502, 0),
    ]
}

/// RPDO/TPDO n: (COB-ID with node, transmission type, mapping).
fn pdo(od: &ObjectDictionary, rx: bool, n: u16) -> (u32, u8, Vec<u32>) {
    let (comm, map) = if rx { (0x1400 + n, 0x1600 + n) } else { (0x1800 + n, 0x1A00 + n) };
    (od.get_u32(comm, 1).unwrap(), od.get(comm, 2).unwrap().bytes()[0], mapping(od, map))
}

#[test]
fn kc1() {
    let od = od(Profile::Kc1);
    // §7.2.1.1 device type 00020192h; §7.2.1.17 vendor 6Ah, product "M006",
    // revision 00140000h; §7.2.3.10 supported drive modes E5h.
    assert_eq!(
        identity(&od),
        [Some(0x0002_0192), Some(0x6A), Some(0x4D30_3036), Some(0x0014_0000), Some(0xE5)]
    );
    // §7.3.1.3 default RPDO mappings, §7.3.1.1 COB-IDs and type 255.
    assert_eq!(pdo(&od, true, 0), (0x203, 0xFF, vec![0x6040_0010]));
    assert_eq!(pdo(&od, true, 1), (0x303, 0xFF, vec![0x6040_0010, 0x6060_0008]));
    assert_eq!(pdo(&od, true, 2), (0x403, 0xFF, vec![0x6040_0010, 0x607A_0020]));
    assert_eq!(pdo(&od, true, 3), (0x503, 0xFF, vec![0x6040_0010, 0x60FF_0020]));
    // §7.3.2.3 default TPDO mappings, §7.3.2.1.
    assert_eq!(pdo(&od, false, 0), (0x183, 0xFF, vec![0x6041_0010]));
    assert_eq!(pdo(&od, false, 1), (0x283, 0xFF, vec![0x6041_0010, 0x6061_0008]));
    assert_eq!(pdo(&od, false, 2), (0x383, 0xFF, vec![0x6041_0010, 0x6064_0020]));
    assert_eq!(pdo(&od, false, 3), (0x483, 0xFF, vec![0x6041_0010, 0x606C_0020]));
    // §7.3.1.1: RPDO communication records have only COB-ID and type.
    assert_eq!(od.get(0x1400, 0).unwrap().bytes(), [2]);
    // §7.2.1.4: ten history entries; §7.2.1.15: one heartbeat consumer.
    assert!(od.get(0x1003, 10).is_some() && od.get(0x1003, 11).is_none());
    assert_eq!(od.get(0x1016, 0).unwrap().bytes(), [1]);
    // §7.2.1.12/13: 1010h/1011h sub 1 read 1.
    assert_eq!(od.get_u32(0x1010, 1), Some(1));
    // §7.4.2 (C.5): no option codes; §8.1.4: no 605Ah.
    assert!(od.get(0x605A, 0).is_none());
    // §7.9.2.4: 10-entry PVT buffer.
    assert_eq!(od.get_u32(0x60C4, 1), Some(10));
}

#[test]
fn akd() {
    let od = od(Profile::Akd);
    // §6.2.1.1, §6.2.1.18, §6.2.3.10.
    assert_eq!(
        identity(&od),
        [Some(0x0002_0192), Some(0x6A), Some(0x4D30_3036), Some(0x0014_0000), Some(0xE5)]
    );
    // §6.3.1.3 / §6.3.2.3: same defaults as the KC1.
    assert_eq!(pdo(&od, true, 1), (0x303, 0xFF, vec![0x6040_0010, 0x6060_0008]));
    assert_eq!(pdo(&od, true, 3), (0x503, 0xFF, vec![0x6040_0010, 0x60FF_0020]));
    assert_eq!(pdo(&od, false, 2), (0x383, 0xFF, vec![0x6041_0010, 0x6064_0020]));
    assert_eq!(pdo(&od, false, 3), (0x483, 0xFF, vec![0x6041_0010, 0x606C_0020]));
    // §6.4 (C.5): quick stop option code exists, default 2.
    assert_eq!(od.get(0x605A, 0).unwrap().bytes(), 2i16.to_le_bytes());
    // §6.2.1.14 (edition M): 1012h exists with 100h.
    assert_eq!(od.get_u32(0x1012, 0), Some(0x100));
    // §6.9.2.3: 60C2h defaults 2 × 10^-3 s.
    assert_eq!(od.get(0x60C2, 1).unwrap().bytes(), [2]);
    assert_eq!(od.get(0x60C2, 2).unwrap().bytes(), [(-3i8) as u8]);
}

#[test]
fn ipos() {
    let od = od(Profile::Ipos);
    // §4.8.1 device type 60192h; §4.8.6 vendor 1A3h; §1.5.4.6 product code
    // of the iPOS360x VX-CAT and revision = firmware ID "A00G" (not the
    // §4.8.6 table's "0100": the SII and ESI revision is the firmware ID);
    // §4.8.2 6502h 001C03E5h.
    assert_eq!(
        identity(&od),
        [Some(0x0006_0192), Some(0x1A3), Some(28_002_021), Some(0x4130_3047), Some(0x001C_03E5)]
    );
    // §4.8.3: device name "iPOS".
    assert_eq!(od.get(0x1008, 0).unwrap().bytes(), b"iPOS");
    // §2.3 default mappings.
    assert_eq!(mapping(&od, 0x1600), [0x6040_0010, 0x607A_0020]);
    assert_eq!(mapping(&od, 0x1601), [0x60FE_0120, 0x60FE_0220]);
    assert_eq!(mapping(&od, 0x1602), [0x6060_0008, 0x6071_0010]);
    assert_eq!(mapping(&od, 0x1603), [0x6081_0020, 0x6083_0020]);
    assert_eq!(mapping(&od, 0x1A00), [0x6041_0010, 0x6064_0020, 0x6077_0010]);
    assert_eq!(mapping(&od, 0x1A01), [0x60F4_0020, 0x60FD_0020]);
    assert_eq!(mapping(&od, 0x1A02), [0x606C_0020]);
    assert_eq!(mapping(&od, 0x1A03), [0x6061_0008]);
    // §2.3 / §3 (1C12h, 1C13h): RxPDO1 and TxPDO1+2 assigned.
    assert_eq!(od.get(0x1C12, 0).unwrap().bytes(), [1]);
    assert_eq!(od.get(0x1C12, 1).unwrap().bytes(), 0x1600u16.to_le_bytes());
    assert_eq!(od.get(0x1C13, 0).unwrap().bytes(), [2]);
    assert_eq!(od.get(0x1C13, 2).unwrap().bytes(), 0x1A01u16.to_le_bytes());
    // §2.3.7/2.3.8: TPDO3/4 "disabled by setting bit 31".
    assert_eq!(od.get_u32(0x1802, 1).unwrap() & 0x8000_0000, 0x8000_0000);
    // §6: homing speeds default 1.0 IU (16.16).
    assert_eq!(od.get_u32(0x6099, 1), Some(0x0001_0000));
}

#[test]
fn ssd630() {
    let od = od(Profile::Ssd630);
    // §14.3: device type 00020192h; 1018h values are not given (§11); 6502h
    // not given either, derived (docs/personalities.md).
    assert_eq!(identity(&od), [Some(0x0002_0192), Some(0), Some(0), Some(0), Some(0x67)]);
    // §14.7: device name of a 631.
    assert_eq!(od.get(0x1008, 0).unwrap().bytes(), b"631_402");
    // §7: PDO1/2 enabled, PDO3/4 disabled; all type 255.
    assert_eq!(pdo(&od, true, 0), (0x203, 0xFF, vec![0x6040_0010]));
    assert_eq!(pdo(&od, true, 1), (0x303, 0xFF, vec![0x6040_0010, 0x6060_0008]));
    assert_eq!(pdo(&od, true, 2), (0x8000_0403, 0xFF, vec![0x6040_0010, 0x607A_0020]));
    assert_eq!(pdo(&od, true, 3), (0x8000_0503, 0xFF, vec![0x6040_0010, 0x6081_0020]));
    assert_eq!(pdo(&od, false, 0), (0x183, 0xFF, vec![0x6041_0010]));
    assert_eq!(pdo(&od, false, 1), (0x283, 0xFF, vec![0x6041_0010, 0x6061_0008]));
    assert_eq!(pdo(&od, false, 2), (0x8000_0383, 0xFF, vec![0x6041_0010, 0x6064_0020]));
    assert_eq!(pdo(&od, false, 3), (0x8000_0483, 0xFF, vec![0x6041_0010, 0x606C_0020]));
    // §10: power-on mode is profile position.
    assert_eq!(od.get(0x6060, 0).unwrap().bytes(), [1]);
    // §9: eight history entries; §4: 1015h exists; §6 (B.8): no 1016h/1017h.
    assert!(od.get(0x1003, 8).is_some() && od.get(0x1003, 9).is_none());
    assert!(od.get(0x1015, 0).is_some());
    assert!(od.get(0x1017, 0).is_none() && od.get(0x1016, 0).is_none());
    // §13: 256 BIAS variables, 1500 program lines (two objects each), 2048
    // profile points (two objects each), 16 CAM profiles.
    assert!(od.get(0x41FF, 0).is_some() && od.get(0x5BFF, 0).is_some() && od.get(0x3FFF, 0).is_some());
    assert_eq!(od.get(0x5C1F, 0).unwrap().bytes(), [20]);
    // §11: pre-v4 objects 1004h and 100Bh.
    assert!(od.get(0x1004, 2).is_some() && od.get(0x100B, 0).is_some());
}

#[test]
fn dds6() {
    let od = od(Profile::Dds6);
    // §6.3.1 device type 00440192h; §6.3.16 vendor 30Ch, DDS6244 product
    // code; revision not given; §6.5.37 6502h 6Dh.
    assert_eq!(identity(&od), [Some(0x0044_0192), Some(0x30C), Some(0x0062_4400), Some(0), Some(0x6D)]);
    // §6.3.19–6.3.22: only PDO1 valid.
    assert_eq!(pdo(&od, true, 0), (0x203, 0xFF, vec![0x6040_0010]));
    assert_eq!(pdo(&od, true, 1), (0x8000_0303, 0xFF, vec![0x6040_0010, 0x607A_0020]));
    assert_eq!(pdo(&od, true, 2), (0x8000_0403, 0xFF, vec![0x6040_0010, 0x60FF_0020]));
    // RPDO4 as printed: target position and profile velocity, no controlword.
    assert_eq!(pdo(&od, true, 3), (0x8000_0503, 0xFF, vec![0x607A_0020, 0x6081_0020]));
    assert_eq!(pdo(&od, false, 0), (0x183, 0xFF, vec![0x6041_0010]));
    assert_eq!(pdo(&od, false, 1), (0x8000_0283, 0xFF, vec![0x6041_0010, 0x6064_0020]));
    assert_eq!(pdo(&od, false, 2), (0x8000_0383, 0xFF, vec![0x6041_0010, 0x606C_0020]));
    assert_eq!(pdo(&od, false, 3), (0x8000_0483, 0xFF, vec![]));
    // §6.3.20: TPDO2/3 event timer 100 ms; TPDO sub 6 SYNC start value exists.
    assert_eq!(od.get(0x1801, 5).unwrap().bytes(), 100u16.to_le_bytes());
    assert_eq!(od.get(0x1800, 0).unwrap().bytes(), [6]);
    // §6.3.17: 1029h; §6.3.14: four heartbeat consumers (sub 0 printed 2).
    assert!(od.get(0x1029, 1).is_some());
    assert_eq!(od.get(0x1016, 0).unwrap().bytes(), [4]);
    // §6.3.2 SDO server parameter present; §6.5.4: 6060h default 1.
    assert_eq!(od.get_u32(0x1200, 1), Some(0x603));
    assert_eq!(od.get(0x6060, 0).unwrap().bytes(), [1]);
}

#[test]
fn generic() {
    let od = od(Profile::Generic);
    assert_eq!(identity(&od), [Some(0x0002_0192), Some(0), Some(0x402), Some(0x0001_0000), Some(0x3ED)]);
    // CiA 402 pre-defined mappings and 64 mapping entries (bit granularity).
    assert_eq!(pdo(&od, true, 2), (0x403, 0xFF, vec![0x6040_0010, 0x607A_0020]));
    assert_eq!(pdo(&od, false, 3), (0x483, 0xFF, vec![0x6041_0010, 0x606C_0020]));
    assert!(od.get(0x1600, 64).is_some() && od.get(0x1A03, 64).is_some());
    for index in [
        0x1001, 0x1003, 0x1005, 0x1006, 0x1007, 0x1008, 0x1009, 0x100A, 0x100C, 0x100D, 0x1010, 0x1011,
        0x1012, 0x1014, 0x1015, 0x1016, 0x1017, 0x1018, 0x1019, 0x1021, 0x1022, 0x1029, 0x1200, 0x1F50,
        0x1F51, 0x1F56, 0x6007, 0x603F, 0x605A, 0x605E, 0x6088, 0x608F, 0x6097, 0x60A8, 0x60AB, 0x60B0,
        0x60C6, 0x60E3, 0x60FE,
    ] {
        assert!(od.object(index).is_some(), "{index:04X}");
    }
    // 60E3h lists exactly the methods the profile claims.
    let methods: Vec<i8> = (1..=od.get(0x60E3, 0).unwrap().bytes()[0])
        .map(|s| od.get(0x60E3, s).unwrap().bytes()[0] as i8)
        .collect();
    assert_eq!(methods, Profile::Generic.info().homing_methods);
}

fn expected_cob(d: &PdoDefault) -> Option<u32> {
    d.cob_id.map(|c| c + NODE as u32)
}

/// The facts in `ProfileInfo` and the EDS agree (one source can't drift).
#[test]
fn info_agrees_with_eds() {
    for p in Profile::all() {
        let info = p.info();
        let od = od(*p);
        assert_eq!(od.get_u32(0x6502, 0), Some(info.supported_drive_modes), "{p}");
        for (n, d) in info.rpdo.iter().enumerate() {
            assert_eq!(mapping(&od, 0x1600 + n as u16), d.mapping, "{p} RPDO{}", n + 1);
            if info.transport == Transport::Can {
                assert_eq!(od.get_u32(0x1400 + n as u16, 1), expected_cob(d), "{p} RPDO{}", n + 1);
            }
        }
        for (n, d) in info.tpdo.iter().enumerate() {
            assert_eq!(mapping(&od, 0x1A00 + n as u16), d.mapping, "{p} TPDO{}", n + 1);
            if info.transport == Transport::Can {
                assert_eq!(od.get_u32(0x1800 + n as u16, 1), expected_cob(d), "{p} TPDO{}", n + 1);
                let timer =
                    od.get(0x1800 + n as u16, 5).map(|s| u16::from_le_bytes([s.bytes()[0], s.bytes()[1]]));
                assert_eq!(timer, Some(d.event_timer_ms), "{p} TPDO{}", n + 1);
            }
        }
        // Every standard mode the drive accepts has a dictionary entry to select it.
        assert!(od.get(0x6060, 0).is_some() && od.get(0x6061, 0).is_some(), "{p}");
        assert_eq!(info.heartbeat_producer, od.get(0x1017, 0).is_some(), "{p}");
        assert_eq!(info.error_behaviour, od.get(0x1029, 0).is_some(), "{p}");
        assert_eq!(info.emcy_inhibit, od.get(0x1015, 0).is_some(), "{p}");
        let hist =
            od.get(0x1003, 1).map_or(0, |_| (1..=254u8).take_while(|s| od.get(0x1003, *s).is_some()).count());
        assert_eq!(hist, info.error_history as usize, "{p}");
        assert!(!info.emcy.is_empty(), "{p}");
    }
}

/// Where 6502h and the accepted modes disagree, it is a recorded quirk.
#[test]
fn mode_bits_or_quirk() {
    for p in Profile::all() {
        let info = p.info();
        let from_modes: u32 =
            info.modes.iter().filter_map(|m| ProfileInfo::mode_bit(*m)).fold(0, |acc, b| acc | 1 << b);
        let reported = info.supported_drive_modes & 0xFFFF;
        if from_modes != reported {
            assert!(
                info.quirks.iter().any(|q| q.id.starts_with("6502-")),
                "{p}: {from_modes:#x} vs {reported:#x}"
            );
        }
    }
    // KC1/AKD §7.2.3.10/§6.2.3.10: tq (4) accepted, bit 3 missing.
    assert!(Profile::Kc1.info().modes.contains(&4) && Profile::Kc1.info().supported_drive_modes & 8 == 0);
    // AKD §6.4.2.4: manufacturer modes -3..-1; §6.10: methods -7..-3.
    assert!([-3, -2, -1].iter().all(|m| Profile::Akd.info().modes.contains(m)));
    assert!((-7..=-3).all(|m| Profile::Akd.info().homing_methods.contains(&m)));
    // iPOS §11/§12: -1 gearing, -2 camming.
    assert!(Profile::Ipos.info().modes.starts_with(&[-2, -1]));
    // SSD 630 §12: homing modes 0..23 written as -24..-1.
    assert_eq!(Profile::Ssd630.info().homing_methods, (-24..=-1).collect::<Vec<i8>>());
    // DDS6 §4.4.4: 37 instead of 35.
    assert!(
        Profile::Dds6.info().homing_methods.contains(&37)
            && !Profile::Dds6.info().homing_methods.contains(&35)
    );
}

#[test]
fn emcy_tables_have_the_manual_sizes() {
    // KC1 §7.1: 158 rows; AKD §6.1: 209; SSD 630 §9 Table 1: 22; DDS6 §5: 31.
    assert_eq!(Profile::Kc1.info().emcy.len(), 158);
    assert_eq!(Profile::Akd.info().emcy.len(), 209);
    assert_eq!(Profile::Ssd630.info().emcy.len(), 22);
    assert_eq!(Profile::Dds6.info().emcy.len(), 31);
    // iPOS Table 3.1.3: the bus-off and PDO length codes.
    assert!(Profile::Ipos.info().emcy_text(0x8210).is_some());
    // SSD 630 §9: 8700h sync controller, error register 21h.
    let e = Profile::Ssd630.info().emcy.iter().find(|e| e.code == 0x8700).unwrap();
    assert_eq!(e.detail, "error register 21h");
}
