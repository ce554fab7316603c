//! One description, three images: the [`SlaveDescription`] of a drive's
//! running EtherCAT dictionary gives the SII image its ESC serves and the
//! ESI file a master's tool reads; both say what 1018h says (the EDS the
//! CAN twin ships is the third, `tests/identity.rs` compares all of them).

use drivebus_esi::{DcOpMode, DeviceFacts, PREOP, SlaveDescription, StateRule, SyncSignal, free_run};
use drivebus_od::ObjectDictionary;
use drivebus_personality::Profile;
use drivebus_personality::ecat::rules;

/// The EtherCAT facts (names, ESC layout, protocols, DC, state rules) of a
/// drive whose identity `od`'s 1018h holds.
pub fn facts(profile: Profile, od: &ObjectDictionary) -> DeviceFacts {
    let info = profile.info();
    let id = |sub| od.get_u32(0x1018, sub).unwrap_or(0);
    let (vendor, product, revision, serial) = (id(1), id(2), id(3), id(4));
    let mut f = match profile {
        Profile::Ipos => drivebus_esi::ipos::facts(vendor, info.vendor_name, product, info.product_name),
        _ => {
            let mut f = DeviceFacts::new(vendor, info.vendor_name, product, revision, info.product_name);
            f.name = format!("{} (drivebus EtherCAT twin)", info.product_name);
            f.group_type = "DrivebusDrives".into();
            f.group_name = "drivebus virtual drives".into();
            f.dc = vec![
                free_run(),
                DcOpMode {
                    name: "DC".into(),
                    desc: "DC-Synchron (SYNC0)".into(),
                    assign_activate: 0x0300,
                    sync0: Some(SyncSignal { cycle_ns: 0, factor: 1, shift_ns: 0 }),
                    sync1: None,
                },
            ];
            f
        }
    };
    // 1018h is the one source of the identity (the iPOS revision is the
    // firmware ID there too, §1.5.4.6).
    f.revision = revision;
    f.serial = serial;
    // What the EtherCAT rules allow only in PRE-OP, as SDO Information
    // reports it (`access::object_access`).
    f.state_rules = od
        .objects()
        .iter()
        .flat_map(|o| o.subs().iter().map(move |s| (o.index, s.sub)))
        .filter(|(i, s)| rules::preop_only(*i, *s))
        .map(|(index, sub)| StateRule { index, sub: Some(sub), read: drivebus_esi::ALL_STATES, write: PREOP })
        .collect();
    f
}

/// The description of the running dictionary `od`.
pub fn describe(profile: Profile, od: &ObjectDictionary) -> SlaveDescription {
    SlaveDescription::new(od, &facts(profile, od))
}
