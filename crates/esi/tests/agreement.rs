//! The ESI agrees with the dictionary it came from and with the EDS of the
//! same profile; what EtherCAT needs and the shipped `ipos.eds` lacks is
//! reported item by item.

mod common;

use drivebus_esi::{
    CheckOptions, Disagreement, SlaveDescription, check_dictionary, check_eds, check_ethercat, ipos,
};
use drivebus_personality::Profile;

fn opts(p: Profile) -> CheckOptions {
    match p {
        Profile::Ipos => ipos::check_options(),
        _ => CheckOptions { state_rules: common::facts(p).state_rules, ..CheckOptions::default() },
    }
}

fn keys(f: &[Disagreement]) -> Vec<(Option<u16>, Option<u8>, String, String)> {
    let mut k: Vec<_> = f.iter().map(|f| (f.index, f.sub, f.field.clone(), f.esi.clone())).collect();
    k.sort();
    k
}

fn show(f: &[Disagreement]) -> String {
    f.iter().map(|f| format!("\n  {f}")).collect()
}

/// The iPOS revision is the firmware ID in the ESI (§1.5.4.6, FA00G →
/// "A00G") and, by the lead's decision, in 1018h:03 and the EDS too (the
/// §4.8.6 table's "0100" is overridden): no disagreement is expected.
#[test]
fn every_profile_round_trips_and_agrees_with_its_dictionary_and_eds() {
    for &p in Profile::all() {
        let (desc, od, eds) = common::build(p);
        let xml = drivebus_esi::write(&desc);
        let errors: Vec<_> = drivebus_esi::validate(&xml).into_iter().filter(|x| x.is_error()).collect();
        assert!(errors.is_empty(), "{p}: {errors:?}");
        let back = common::round_trip(&desc);
        assert!(back == desc, "{p}: the file does not read back to the description");
        let expected: Vec<(Option<u16>, Option<u8>, String, String)> = vec![];
        let d = check_dictionary(&back, &od, &opts(p));
        assert_eq!(keys(&d), expected, "{p} vs dictionary:{}", show(&d));
        let e = check_eds(&back, &eds, &opts(p));
        assert_eq!(keys(&e), expected, "{p} vs EDS:{}", show(&e));
    }
}

#[test]
fn an_esi_of_the_running_twin_agrees_with_the_running_dictionary() {
    // The running drives carry hooks and objects the stack installs beyond
    // the EDS (see the crate report); an ESI built from them must still
    // describe them exactly.
    for &p in Profile::all() {
        let node = p.build(common::NODE_ID).unwrap_or_else(|e| panic!("{p}: {e:?}"));
        let od = node.node.od();
        let desc = SlaveDescription::new(od, &common::facts(p));
        let back = common::round_trip(&desc);
        assert!(back == desc, "{p}");
        let mut o = opts(p);
        o.mapping_entries = None;
        let f = check_dictionary(&back, od, &o);
        assert!(f.is_empty(), "{p}:{}", show(&f));
    }
}

/// The shipped `ipos.eds` has what EtherCAT needs, as the manual means it:
/// 1C00h:04 = 4 (§2.3.9 prints 3, its value range and ETG.1000.6 say 4),
/// 1C12h/1C13h with an entry per PDO and a writable sub 0 (§2.3.10/11,
/// §2.4, E10/E11), mapping records with the 8 entries of §2.4.
#[test]
fn ipos_eds_meets_ethercat_needs() {
    let (desc, od, _) = common::build(Profile::Ipos);
    let f = check_ethercat(&desc, &od, &ipos::check_options());
    assert!(f.is_empty(), "{}", show(&f));
}

#[test]
fn generic_lacks_only_the_sync_manager_objects() {
    // `generic` is a CAN drive: its dictionary has no 1C00h/1C12h/1C13h.
    let (desc, od, _) = common::build(Profile::Generic);
    let f = check_ethercat(&common::round_trip(&desc), &od, &opts(Profile::Generic));
    let got: Vec<_> = f.iter().map(|f| (f.index, f.sub, f.field.as_str())).collect();
    assert_eq!(
        got,
        [(Some(0x1C00), None, "exists"), (Some(0x1C12), None, "exists"), (Some(0x1C13), None, "exists")],
        "{}",
        show(&f)
    );
    // On CAN the PDOs with a valid COB-ID make the default assignment.
    assert!(desc.rx_pdos.iter().all(|p| p.sm == Some(2)) && desc.tx_pdos.iter().all(|p| p.sm == Some(3)));
}

#[test]
fn sync_manager_sizes_follow_the_default_assignment() {
    // §2.3: RxPDO1 (6040h + 607Ah = 48 bits) assigned; TxPDO1 (64) and TxPDO2 (64).
    let (desc, _, _) = common::build(Profile::Ipos);
    let size = |k| desc.sm(k).and_then(|(_, s)| s.default_size);
    assert_eq!(size(drivebus_esi::SmKind::Outputs), Some(6));
    assert_eq!(size(drivebus_esi::SmKind::Inputs), Some(16));
    let assigned: Vec<_> = desc.tx_pdos.iter().filter(|p| p.sm.is_some()).map(|p| p.index).collect();
    assert_eq!(assigned, [0x1A00, 0x1A01]);
    assert!(desc.ethercrab_min_mailbox_in() <= 512, "{}", desc.ethercrab_min_mailbox_in());
    // 190 of the CoE manual, and served on CAN 1005h, 1006h, 1014h, the PDO
    // communication records 1400h–1403h/1800h–1801h and the dummy types
    // 0002h–0007h (ipos.eds).
    assert_eq!(desc.object_count(), 205);
}

#[test]
fn disagreements_are_itemised_with_both_values() {
    let (desc, od, eds) = common::build(Profile::Ipos);
    let mut bad = desc.clone();
    bad.vendor_id = 2;
    let i = bad.objects.iter().position(|o| o.index == 0x6065).unwrap();
    bad.objects[i].subs[0].default = 1234u32.to_le_bytes().to_vec();
    bad.objects[i].subs[0].access &= !drivebus_coe::access_bits::WRITE;
    let j = bad.objects.iter().position(|o| o.index == 0x6099).unwrap();
    bad.objects[j].subs.pop();
    bad.objects.retain(|o| o.index != 0x2000);
    bad.rx_pdos[0].entries[1].bit_len = 16;
    bad.tx_pdos[1].sm = None;
    bad.sync_managers[3].default_size = Some(8);
    let bad = common::round_trip(&bad);
    let f = check_dictionary(&bad, &od, &ipos::check_options());
    let lines: Vec<String> = f.iter().map(ToString::to_string).collect();
    for want in [
        "1018h:01 vendor ID: ESI #x00000002; dictionary #x000001A3",
        "2000h exists: ESI absent; dictionary present",
        "6065h:00 access: ESI ro; dictionary rw",
        "6065h:00 default: ESI #x000004D2; dictionary #x",
        "6099h:02 exists: ESI absent; dictionary present",
        "1600h RxPdo entries: ESI 6040:00/16, 607A:00/16; dictionary 6040:00/16, 607A:00/32",
        "1A01h TxPdo Sm: ESI not assigned; dictionary SM3",
        "1C13h default assignment: ESI 1A00h; dictionary 1A00h, 1A01h",
        "Sm Inputs DefaultSize: ESI 8; dictionary 16",
    ] {
        assert!(lines.iter().any(|l| l.starts_with(want)), "missing {want:?} in{}", show(&f));
    }
    // The EDS check sees the same object-level differences.
    let e = check_eds(&bad, &eds, &ipos::check_options());
    assert!(e.iter().any(|f| f.to_string().starts_with("6065h:00 default: ESI #x000004D2; EDS #x")));
}
