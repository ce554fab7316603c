//! Every personality EDS reads cleanly, passes the CiA 306 checker, builds a
//! dictionary and survives a write → read round trip.

use drivebus_eds::{Severity, check, parse, to_od, write};
use drivebus_personality::Profile;

#[test]
fn every_eds_parses_without_errors() {
    for p in Profile::all() {
        let parsed = parse(p.eds_text()).unwrap_or_else(|e| panic!("{p}: {e}"));
        // No warnings at all: sub 0 of 1003h and of the mapping records is
        // a count of its own (CiA 301 §7.5.2.5/36/38), not the highest
        // sub-index, and every other sub 0 reaches its sub-objects.
        assert!(parsed.warnings.is_empty(), "{p}: {:#?}", parsed.warnings);
    }
}

#[test]
fn checker_finds_no_errors() {
    for p in Profile::all() {
        let findings = check(&p.parse_eds().eds);
        let errors: Vec<_> = findings.iter().filter(|f| f.severity == Severity::Error).collect();
        assert!(errors.is_empty(), "{p}: {errors:#?}");
        let warnings: Vec<String> = findings.iter().map(|f| f.message.clone()).collect();
        let expected: &[&str] = match p {
            // iPOS is an EtherCAT (CoE) device: no heartbeat or guarding.
            Profile::Ipos => &["neither heartbeat (1017h) nor node guarding (100Ch) is described"],
            _ => &[],
        };
        assert_eq!(warnings, expected, "{p}");
    }
}

#[test]
fn dictionary_for_lowest_and_highest_node() {
    for p in Profile::all() {
        let eds = p.parse_eds().eds;
        for node in [1u8, 127] {
            let od = to_od(&eds, node).unwrap_or_else(|e| panic!("{p} node {node}: {e}"));
            assert_eq!(od.get_u32(0x1000, 0), Some(p.info().device_type), "{p}");
            if p.info().transport == drivebus_personality::Transport::Can {
                // Pre-defined connection set (CiA 301 §7.3.5): EMCY 80h + node.
                assert_eq!(od.get_u32(0x1014, 0).map(|v| v & 0x7FF), Some(0x80 + node as u32), "{p}");
                assert_eq!(od.get_u32(0x1800, 1).map(|v| v & 0x7FF), Some(0x180 + node as u32), "{p}");
            }
        }
    }
}

#[test]
fn write_then_read_is_identical() {
    for p in Profile::all() {
        let first = p.parse_eds().eds;
        let text = write(&first);
        let second = parse(&text).unwrap_or_else(|e| panic!("{p}: {e}")).eds;
        let (mut a, mut b) = (first.clone(), second);
        a.strip_lines();
        b.strip_lines();
        assert!(a == b, "{p}: round trip differs");
        // Writing the re-read file gives the same text again.
        assert_eq!(write(&b), text, "{p}");
    }
}

#[test]
fn device_info_matches_the_profile() {
    for p in Profile::all() {
        let eds = p.parse_eds().eds;
        let d = &eds.device_info;
        let info = p.info();
        assert_eq!(d.vendor_number, info.vendor_id, "{p}");
        assert_eq!(d.product_number, info.product_code, "{p}");
        assert_eq!(d.revision_number, info.revision, "{p}");
        assert_eq!(d.granularity, info.granularity, "{p}");
        // LSS (CiA 305): only `generic` is an LSS slave.
        assert_eq!(d.lss_supported, info.lss, "{p}: LSS_Supported");
        assert_eq!((d.nr_of_rx_pdo, d.nr_of_tx_pdo), (4, 4), "{p}");
        let mut bauds: Vec<u32> = info.baud_rates_kbit.iter().copied().filter(|b| *b != 100).collect();
        bauds.sort_unstable();
        assert_eq!(d.baud_rates, bauds, "{p}");
        assert_eq!(eds.dummy_usage.values().any(|d| *d), info.dummy_mapping, "{p}");
    }
}

#[test]
fn object_counts() {
    // Guards against an accidental regeneration dropping objects.
    let counts: Vec<(Profile, usize)> =
        Profile::all().iter().map(|p| (*p, p.parse_eds().eds.objects.len())).collect();
    assert_eq!(
        counts,
        vec![
            (Profile::Kc1, 342),
            (Profile::Akd, 407),
            (Profile::Ipos, 205),
            (Profile::Ssd630, 7604),
            (Profile::Dds6, 98),
            (Profile::Generic, 132),
        ]
    );
}

/// Every PDO an EDS counts (NrOfRXPDO/NrOfTXPDO) has its communication and
/// its mapping record (CiA 301 §7.5.2.35–38), so a master tool can
/// configure it from the EDS (Lely's dcfgen refuses "Receive-PDO n not
/// available" otherwise). For the iPOS, a CoE drive served on CAN, a PDO
/// is valid (COB-ID bit 31 clear) exactly where 1C12h/1C13h assign its
/// mapping (§2.3.10, §2.3.11): the CAN and the EtherCAT view agree.
#[test]
fn every_counted_pdo_has_its_records() {
    for p in Profile::all() {
        let eds = p.parse_eds().eds;
        let od = to_od(&eds, 1).unwrap();
        for (count, comm, map) in [
            (eds.device_info.nr_of_rx_pdo, 0x1400u16, 0x1600u16),
            (eds.device_info.nr_of_tx_pdo, 0x1800, 0x1A00),
        ] {
            for n in 0..count {
                for (index, subs) in [(comm + n, &[0u8, 1, 2][..]), (map + n, &[0u8][..])] {
                    for &sub in subs {
                        assert!(od.get(index, sub).is_some(), "{p}: {index:04X}h:{sub} missing");
                    }
                }
            }
        }
        if p.info().transport != drivebus_personality::Transport::EtherCatCoe {
            continue;
        }
        for (assign, comm, map) in [(0x1C12u16, 0x1400u16, 0x1600u16), (0x1C13, 0x1800, 0x1A00)] {
            let n = od.get_u64(assign, 0).unwrap() as u8;
            let assigned: Vec<u64> = (1..=n).map(|s| od.get_u64(assign, s).unwrap()).collect();
            for k in 0..4u16 {
                let valid = od.get_u32(comm + k, 1).unwrap() & 0x8000_0000 == 0;
                assert_eq!(valid, assigned.contains(&u64::from(map + k)), "{p}: {:04X}h", comm + k);
            }
        }
    }
}
