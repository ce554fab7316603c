use super::*;

#[test]
fn table_is_sorted_and_runs_do_not_overlap() {
    let all: alloc::vec::Vec<&Def> = defs().collect();
    for w in all.windows(2) {
        assert!(w[0].first <= w[0].last && w[0].last < w[1].first, "{:04X} / {:04X}", w[0].first, w[1].first);
    }
    for d in defs() {
        assert_eq!(d.subs[0].first, 0, "{:04X} starts at sub 0", d.first);
        for w in d.subs.windows(2) {
            assert!(w[0].last < w[1].first, "{:04X} subs ascending", d.first);
        }
        if d.kind == Kind::Var {
            assert_eq!(d.subs.len(), 1, "{:04X}", d.first);
        }
    }
}

#[test]
fn lookups_by_index_and_range() {
    assert_eq!(object(0x1000).unwrap().name(), "Device type");
    assert!(object(0x1004).is_none());
    assert_eq!(object(0x1401).unwrap().name(), "RPDO2 communication parameter");
    assert_eq!(object(0x1A00).unwrap().name(), "TPDO1 mapping parameter");
    let e = entry(0x1A00, 0).unwrap();
    assert_eq!((e.data_type, e.access), (DataType::Unsigned8, Access::Rw));
    assert_eq!(entry(0x1018, 2).unwrap().full_name(), "Identity object / Product code");
    assert_eq!(entry(0x1016, 5).unwrap().name(), "Consumer heartbeat time 5");
    assert!(entry(0x1018, 5).is_none());
    assert_eq!(entry(0x607A, 0).unwrap().data_type, DataType::Integer32);
    assert!(entry(0x6040, 0).unwrap().pdo);
    assert!(object(0x2000).is_none());
    assert_eq!(object(0x1200).unwrap().entries().count(), 3);
    assert_eq!(object(0x1600).unwrap().entries().count(), 65);
}

#[test]
fn names_find_entries() {
    assert_eq!(find("Statusword"), Some((0x6041, Some(0))));
    assert_eq!(find("position_actual_value"), Some((0x6064, Some(0))));
    assert_eq!(find("profile-velocity"), Some((0x6081, Some(0))));
    assert_eq!(find("identity object"), Some((0x1018, None)));
    assert_eq!(find("identity object/serial number"), Some((0x1018, Some(4))));
    // The example of `drivebus --help` (issue 15): the object by the start of its name.
    assert_eq!(find("identity/vendor-id"), Some((0x1018, Some(1))));
    assert_eq!(find("identity/vendor_id"), Some((0x1018, Some(1))));
    // `drivebus sdo --help`: `sdo read identity` reads the record.
    assert_eq!(find("identity"), Some((0x1018, None)));
    // Several objects start so: none.
    assert_eq!(find("tpdo1"), None);
    assert_eq!(find("vendor-id"), Some((0x1018, Some(1))));
    assert_eq!(find("tpdo1 mapping parameter"), Some((0x1A00, None)));
    assert_eq!(find("RPDO3 communication parameter/transmission type"), Some((0x1402, Some(2))));
    // Ambiguous or unknown.
    assert_eq!(find("numerator"), None);
    assert_eq!(find("no such thing"), None);
    assert_eq!(find(""), None);
}

/// Every personality's EDS (written from its manual by the personality
/// crate) agrees on the data type of every standard entry it has, but for
/// what the manuals document otherwise: 60C1h records are "mode
/// dependent" (CiA 402-2 leaves the type to the device; KC1/AKD/iPOS use
/// UNSIGNED32 for PVT records), the SSD 630 manual types 607Dh as
/// UNSIGNED32 and 6080h as UNSIGNED8. An EDS, when given, wins.
#[test]
fn the_personality_eds_files_agree_on_types() {
    let mut checked = 0;
    let mut wrong = alloc::vec::Vec::new();
    for p in drivebus_personality::Profile::all() {
        let eds = p.parse_eds().eds;
        for (index, o) in &eds.objects {
            let vars: alloc::vec::Vec<(u8, &drivebus_eds::EdsVar)> = match &o.var {
                Some(v) if o.subs.is_empty() => alloc::vec![(0, v)],
                _ => o.subs.iter().map(|(s, v)| (*s, v)).collect(),
            };
            for (sub, v) in vars {
                let Some(e) = entry(*index, sub) else { continue };
                checked += 1;
                let documented = *index == 0x60C1
                    || (*p == drivebus_personality::Profile::Ssd630 && matches!(*index, 0x607D | 0x6080));
                if DataType::from_index(v.data_type) != Some(e.data_type) && !documented {
                    wrong.push(alloc::format!(
                        "{p:?} {index:04X}:{sub:02X} EDS {:#06x}, table {:?}",
                        v.data_type,
                        e.data_type
                    ));
                }
            }
        }
    }
    assert!(checked > 500, "{checked} entries compared");
    assert!(wrong.is_empty(), "{wrong:#?}");
}
