//! One description, three images: the SII image a drive slave's ESC
//! serves (parsed back), its ESI file (written and read back) and the EDS
//! the personality ships all agree with the running EtherCAT dictionary —
//! identity (1018h), objects, PDO mappings, sync manager sizes. The EDS is
//! the CAN twin's: it differs exactly by the CAN communication objects
//! the EtherCAT dictionary leaves out and the sync manager objects it
//! adds (docs/personalities.md).

use drivebus_esc::sii::{SiiPdo, sm_type};
use drivebus_esi::{CheckOptions, SmKind};
use drivebus_ethercat::drive::{DriveSlaveExt, DriveSlaveSpec, Image, facts, slave};
use drivebus_personality::Profile;
use drivebus_personality::ecat::{self, rules};
use std::collections::BTreeSet;

const PROFILES: [Profile; 2] = [Profile::Ipos, Profile::Generic];

fn entries(p: &SiiPdo) -> Vec<u32> {
    p.entries
        .iter()
        .map(|e| (u32::from(e.index) << 16) | (u32::from(e.sub_index) << 8) | u32::from(e.bit_len))
        .collect()
}

#[test]
fn sii_esi_and_dictionary_agree() {
    for p in PROFILES {
        let s = slave(&DriveSlaveSpec::new(p, 42)).unwrap();
        let od = s.app().device().node.od().clone();
        let id: Vec<u32> = (1..=4).map(|sub| od.get_u32(0x1018, sub).unwrap()).collect();
        assert_eq!(id[3], 42, "{p}: serial");
        let d = s.description();
        assert_eq!(vec![d.vendor_id, d.product_code, d.revision, d.serial], id, "{p}: description = 1018h");
        // The SII as the ESC serves it.
        let img = s.esc().sii_image();
        assert!(img.checksum_ok(), "{p}: configuration-area CRC");
        let c = img.parse().unwrap();
        let sii_id = [c.identity.vendor_id, c.identity.product_code, c.identity.revision, c.identity.serial];
        assert_eq!(sii_id.to_vec(), id, "{p}: SII identity = 1018h");
        let g = c.general.unwrap();
        assert_eq!(c.strings[usize::from(g.order_idx) - 1], p.info().product_name, "{p}");
        assert_eq!(g.coe_details, d.sii_coe_details(), "{p}");
        // Mailbox and sync managers.
        let (_, mo) = d.sm(SmKind::MBoxOut).unwrap();
        let (_, mi) = d.sm(SmKind::MBoxIn).unwrap();
        assert_eq!((c.mailbox.rx_offset, c.mailbox.rx_size), (mo.start, mo.default_size.unwrap()), "{p}");
        assert_eq!((c.mailbox.tx_offset, c.mailbox.tx_size), (mi.start, mi.default_size.unwrap()), "{p}");
        assert!(
            usize::from(c.mailbox.tx_size) >= d.ethercrab_min_mailbox_in(),
            "{p}: SM1 big enough for ethercrab"
        );
        let sm_len = |t: u8| c.sync_managers.iter().find(|s| s.sm_type == t).unwrap().length;
        assert_eq!(u32::from(sm_len(sm_type::OUTPUTS)) * 8, Image::bits_of(&od, 0x1C12), "{p}: SM2 = 1C12h");
        assert_eq!(u32::from(sm_len(sm_type::INPUTS)) * 8, Image::bits_of(&od, 0x1C13), "{p}: SM3 = 1C13h");
        // Every PDO's SII entries are the mapping object's, the assigned
        // ones flagged in 1C12h/1C13h order.
        for (pdos, assign) in [(&c.rx_pdos, 0x1C12u16), (&c.tx_pdos, 0x1C13)] {
            for pdo in pdos.iter() {
                assert_eq!(entries(pdo), rules::entries(&od, pdo.index), "{p}: {:04X}h", pdo.index);
            }
            let flagged: Vec<u16> = pdos.iter().filter(|x| x.flags & 0x0002 != 0).map(|x| x.index).collect();
            assert_eq!(flagged, rules::assigned(&od, assign), "{p}: {assign:04X}h");
            let all: BTreeSet<u16> = pdos.iter().map(|x| x.index).collect();
            let maps: BTreeSet<u16> = od
                .objects()
                .iter()
                .map(|o| o.index)
                .filter(|i| rules::is_mapping(*i) && rules::kind_of(*i) == rules::kind_of(pdos[0].index))
                .collect();
            assert_eq!(all, maps, "{p}: every mapping object described");
        }
        // The ESI: written, valid, read back equal; it describes the
        // running dictionary, as an EtherCAT dictionary must.
        let xml = s.esi();
        let problems: Vec<_> = drivebus_esi::validate(&xml).into_iter().filter(|x| x.is_error()).collect();
        assert!(problems.is_empty(), "{p}: {problems:?}");
        let mut back = drivebus_esi::read(&xml).unwrap();
        back.serial = d.serial;
        assert_eq!(back, d, "{p}: ESI read back");
        let opts = CheckOptions { state_rules: facts(p, &od).state_rules, ..CheckOptions::default() };
        let f = drivebus_esi::check_dictionary(&back, &od, &opts);
        assert!(f.is_empty(), "{p}: ESI vs dictionary: {f:#?}");
        let f: Vec<_> = drivebus_esi::check_ethercat(&back, &od, &opts);
        assert!(f.is_empty(), "{p}: EtherCAT rules: {f:#?}");
    }
}

#[test]
fn eds_differs_exactly_by_the_can_objects() {
    for p in PROFILES {
        let s = slave(&DriveSlaveSpec::new(p, 1)).unwrap();
        let od = s.app().device().node.od();
        let eds = p.parse_eds().eds;
        let di = &eds.device_info;
        let id = [1u8, 2, 3].map(|sub| od.get_u32(0x1018, sub));
        assert_eq!(
            id,
            [di.vendor_number, di.product_number, di.revision_number],
            "{p}: EDS [DeviceInfo] = 1018h"
        );
        let in_eds: BTreeSet<u16> = eds.objects.keys().copied().collect();
        let in_od: BTreeSet<u16> = od.objects().iter().map(|o| o.index).collect();
        let facts = ecat::facts(p).unwrap();
        let removed: BTreeSet<u16> = in_eds.difference(&in_od).copied().collect();
        let added: BTreeSet<u16> = in_od.difference(&in_eds).copied().collect();
        assert!(removed.iter().all(|i| (facts.can_only)(*i)), "{p}: only CAN objects go: {removed:04X?}");
        assert!(
            added.iter().all(|i| matches!(i, 0x1C00 | 0x1C12 | 0x1C13 | 0x1C32 | 0x1C33)),
            "{p}: {added:04X?}"
        );
        assert!(added.contains(&0x1C32) && added.contains(&0x1C33), "{p}");
        // Every object both have agrees: the ESI of the EtherCAT
        // dictionary checked against the EDS finds nothing else.
        let d = s.description();
        let opts = CheckOptions { state_rules: facts_rules(p, od), ..CheckOptions::default() };
        let f: Vec<_> = drivebus_esi::check_eds(&d, &eds, &opts)
            .into_iter()
            .filter(|f| f.index.is_none_or(|i| !removed.contains(&i) && !added.contains(&i)))
            // The serial number is the device's own (the EDS has none).
            .filter(|f| (f.index, f.sub) != (Some(0x1018), Some(4)))
            // The EDS has no persistence: the checker takes every
            // writable entry as stored; the drive keeps its encoder
            // resolutions (608Fh/6090h) as facts of the motor, not as
            // parameters it stores.
            .filter(|f| !(matches!(f.index, Some(0x608F | 0x6090)) && f.field == "backup/settings"))
            .collect();
        let brief: Vec<String> = f
            .iter()
            .map(|x| format!("{:04X?}:{:?} {} esi={} eds={}", x.index, x.sub, x.field, x.esi, x.other))
            .collect();
        assert!(f.is_empty(), "{p}: EDS vs ESI: {brief:#?}");
    }
}

fn facts_rules(p: Profile, od: &drivebus_od::ObjectDictionary) -> Vec<drivebus_esi::StateRule> {
    facts(p, od).state_rules
}
