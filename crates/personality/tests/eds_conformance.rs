//! The EDS describes the drive that answers (CiA 306 §4.6): for every
//! profile, the shipped EDS (`eds/<name>.eds`), the EDS the running drive
//! serves at 1021h (CiA 301 §7.5.2.21, generated from its dictionary) and
//! the running dictionary itself agree object by object — existence,
//! object code, and per sub-index existence, data type, access, PDO
//! mappability, default and low/high limits — and the two EDS files have
//! the same `[DeviceInfo]` and `[DummyUsage]`.
//!
//! The only difference allowed: 1021h/1022h, which the drives other than
//! `generic` have only with `BuildOptions::eds_object` (the manuals do not
//! list them), and the default of 1021h itself (an EDS cannot contain
//! itself).

mod replay_rig;

use drivebus_node::MemoryStorage;
use drivebus_od::ObjectDictionary;
use drivebus_personality::Profile;
use drivebus_personality::build::BuildOptions;
use replay_rig::Rig;
use std::collections::BTreeMap;

const NODE: u8 = 9;

/// One line per object and per sub-object: what an EDS can say about it.
fn described(od: &ObjectDictionary, skip_eds_object: bool) -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    for o in od.objects() {
        if skip_eds_object && matches!(o.index, 0x1021 | 0x1022) {
            continue;
        }
        m.insert(format!("{:04X}", o.index), format!("{:?}", o.code));
        for s in o.subs() {
            let default = if o.index == 0x1021 { &[][..] } else { &s.default[..] };
            m.insert(
                format!("{:04X}sub{:X}", o.index, s.sub),
                format!(
                    "{:?} {:?} map={} def={:02X?} lo={:02X?} hi={:02X?}",
                    s.data_type, s.access, s.pdo_mappable, default, s.low_limit, s.high_limit
                ),
            );
        }
    }
    m
}

/// The lines where `a` and `b` differ, named `an` and `bn`.
fn differences(
    an: &str,
    a: &BTreeMap<String, String>,
    bn: &str,
    b: &BTreeMap<String, String>,
) -> Vec<String> {
    let mut v = Vec::new();
    for (k, x) in a {
        match b.get(k) {
            None => v.push(format!("{k}: only in {an}: {x}")),
            Some(y) if y != x => v.push(format!("{k}: {an} {x} / {bn} {y}")),
            _ => {}
        }
    }
    for (k, y) in b {
        if !a.contains_key(k) {
            v.push(format!("{k}: only in {bn}: {y}"));
        }
    }
    v
}

#[test]
fn shipped_served_and_running_agree() {
    let mut bad = Vec::new();
    for &p in Profile::all() {
        let shipped = drivebus_eds::to_od(&p.parse_eds().eds, NODE).unwrap();
        let optional = p != Profile::Generic;
        let shipped = described(&shipped, optional);
        // The running dictionary, as built (no 1021h option).
        let running = described(p.build(NODE).unwrap().node.od(), false);
        bad.extend(
            differences("shipped", &shipped, "running", &running).into_iter().map(|d| format!("{p} {d}")),
        );
        // The served EDS, read off the drive by SDO upload.
        let pn = p
            .build_with_options(NODE, Box::new(MemoryStorage::new()), BuildOptions { eds_object: true })
            .unwrap();
        let (mut r, _) = Rig::with(pn);
        let text = r.upload(NODE, 0x1021, 0).unwrap_or_else(|a| panic!("{p}: 1021h aborts {a:08X}h"));
        let text = String::from_utf8(text).unwrap();
        let parsed = drivebus_eds::parse(&text).unwrap_or_else(|e| panic!("{p}: served EDS: {e}"));
        // Read and checked like the shipped file: no reader warning, the
        // checker's findings those of the shipped file.
        if !parsed.warnings.is_empty() {
            bad.push(format!("{p}: served EDS reader warnings {:?}", parsed.warnings));
        }
        let findings = |e: &drivebus_eds::Eds| -> Vec<String> {
            drivebus_eds::check(e).into_iter().map(|f| format!("{:?} {}", f.severity, f.message)).collect()
        };
        if findings(&parsed.eds) != findings(&p.parse_eds().eds) {
            bad.push(format!(
                "{p}: served EDS checker {:?} / shipped {:?}",
                findings(&parsed.eds),
                findings(&p.parse_eds().eds)
            ));
        }
        let served = parsed.eds;
        // [DeviceInfo] and [DummyUsage] too (CiA 306 §4.4, §4.5): names,
        // numbers, bit rates, PDO counts, granularity, LSS.
        let shipped_eds = p.parse_eds().eds;
        if served.device_info != shipped_eds.device_info {
            bad.push(format!(
                "{p} [DeviceInfo]: shipped {:?} / served {:?}",
                shipped_eds.device_info, served.device_info
            ));
        }
        if served.dummy_usage != shipped_eds.dummy_usage {
            bad.push(format!(
                "{p} [DummyUsage]: shipped {:?} / served {:?}",
                shipped_eds.dummy_usage, served.dummy_usage
            ));
        }
        if shipped_eds.device_info.lss_supported != p.info().lss {
            bad.push(format!("{p}: LSS_Supported is not ProfileInfo::lss"));
        }
        let served = described(&drivebus_eds::to_od(&served, NODE).unwrap(), optional);
        bad.extend(
            differences("shipped", &shipped, "served", &served).into_iter().map(|d| format!("{p} {d}")),
        );
    }
    assert!(bad.is_empty(), "{} differences:\n{}", bad.len(), bad.join("\n"));
}
