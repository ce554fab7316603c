//! Reader, writer and checker tests on hand-written files (no vendor EDS).

use drivebus_eds::{Severity, check, parse, to_od, write};
use drivebus_od::{Access, DataType, ObjectCode, Value};

const QUIRKS: &str = include_str!("data/quirks.eds");

#[test]
fn every_section_is_read() {
    let p = parse(QUIRKS).expect("parses");
    let e = &p.eds;
    assert_eq!(e.file_info[0], ("FileName".into(), "quirks.eds".into()));
    let d = &e.device_info;
    assert_eq!(d.vendor_name, "drivebus");
    assert_eq!(d.vendor_number, Some(0xABCD));
    assert_eq!(d.revision_number, Some(0x0001_0002));
    assert_eq!(d.baud_rates, vec![125, 250, 500, 1000]);
    assert!(d.simple_boot_up_slave && !d.simple_boot_up_master && d.lss_supported);
    assert_eq!((d.granularity, d.nr_of_rx_pdo, d.nr_of_tx_pdo), (8, 1, 1));
    assert_eq!(d.other, vec![("VendorSpecificKey".into(), "kept".into())]);
    assert_eq!(e.dummy_usage, [false, false, true, true, true, true, true, true]);
    assert_eq!(e.comments, vec!["first comment line".to_string(), "second ; with a semicolon".into()]);
    assert_eq!(e.mandatory, vec![0x1000, 0x1001, 0x1018]);
    assert_eq!(e.manufacturer, vec![0x2000, 0x2001, 0x1F50]);
    assert_eq!(e.other_sections[0].0, "Tools");
    // Lower-case AccessType value, `[1018Sub2]` spelling, octal HighLimit.
    assert_eq!(e.objects[&0x1000].var.as_ref().unwrap().access, Access::Ro);
    assert!(e.objects[&0x1018].subs.contains_key(&2));
    assert_eq!(e.objects[&0x2000].var.as_ref().unwrap().high_limit.as_deref(), Some("01750"));
    assert_eq!(e.objects[&0x1F50].object_type, ObjectCode::Domain);
    assert_eq!(e.objects[&0x1F50].var.as_ref().unwrap().download_file.as_deref(), Some("firmware.bin"));
    // CompactSubObj expands with [xxxxName]/[xxxxValue].
    let ef = &e.objects[&0x1003];
    assert_eq!(ef.subs.len(), 5);
    assert_eq!(ef.subs[&1].name, "Newest error");
    assert_eq!(ef.subs[&3].name, "Pre-defined error field3");
    assert_eq!(ef.subs[&2].default.as_deref(), Some("0x1000"));
}

#[test]
fn quirks_are_warnings_with_lines() {
    let p = parse(QUIRKS).unwrap();
    let w: Vec<String> = p.warnings.iter().map(|d| d.to_string()).collect();
    // 1018h sub 0 says 1 but sub 2 exists; SubNumber=3 matches; [Tools] kept.
    assert!(w.iter().any(|m| m.contains("1018 sub 0 default is below")), "{w:#?}");
    assert!(w.iter().any(|m| m.contains("[Tools] not interpreted")), "{w:#?}");
    assert!(p.warnings.iter().all(|d| d.line > 0 || d.message.contains("missing")));
}

#[test]
fn dictionary_from_eds_with_node_id() {
    let p = parse(QUIRKS).unwrap();
    let od = to_od(&p.eds, 0x22).unwrap();
    assert_eq!(od.get_u32(0x1400, 1), Some(0x222));
    assert_eq!(od.get_u32(0x1800, 1), Some(0x1A2));
    assert!(od.get(0x1800, 1).unwrap().node_id_relative);
    let sp = od.get(0x2000, 0).unwrap();
    assert_eq!(sp.data_type, DataType::Integer16);
    assert_eq!(sp.value(), Value::I16(-10));
    assert_eq!(sp.access, Access::Rww);
    assert!(sp.pdo_mappable);
    assert_eq!(sp.validate(&1001i16.to_le_bytes()), Err(drivebus_od::SdoAbort::VALUE_TOO_HIGH));
    assert_eq!(od.get(0x2001, 0).unwrap().bytes(), b"hello world");
    assert_eq!(od.object(0x2001).unwrap().flags, 1);
    assert_eq!(od.get_u32(0x1003, 2), Some(0x1000));
}

#[test]
fn write_then_read_is_identical() {
    let first = parse(QUIRKS).unwrap().eds;
    let text = write(&first);
    let second = parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}")).eds;
    let (mut a, mut b) = (first.clone(), second.clone());
    a.strip_lines();
    b.strip_lines();
    assert_eq!(a, b);
    assert_eq!(to_od(&first, 5).unwrap(), to_od(&second, 5).unwrap());
}

#[test]
fn checker_accepts_the_file() {
    let p = parse(QUIRKS).unwrap();
    let errors: Vec<_> = check(&p.eds).into_iter().filter(|f| f.severity == Severity::Error).collect();
    assert!(errors.is_empty(), "{errors:#?}");
}

#[test]
fn real_errors_name_their_lines() {
    let text = "[1000]\nParameterName=x\nObjectType=0x7\nDataType=0x0007\nAccessType=rx\n\n[2000]\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\nDefaultValue=0x1FF\n\n[2001]\nObjectType=0x7\nAccessType=rw\n\n[2002sub1]\nDataType=0x0007\nAccessType=ro\n\n[2003]\nObjectType=0x42\n\n[2004]\nDataType=0x0005\nAccessType=rw\nLowLimit=banana\n";
    let err = parse(text).unwrap_err();
    let lines: Vec<usize> = err.errors.iter().map(|d| d.line).collect();
    let msg = err.to_string();
    assert_eq!(lines, vec![5, 11, 13, 17, 22, 27], "{msg}");
    assert!(msg.contains("line 5: [1000]: AccessType \"rx\""), "{msg}");
    assert!(msg.contains("line 11: [2000]: DefaultValue"), "{msg}");
    assert!(msg.contains("line 13: [2001]: DataType missing"), "{msg}");
    assert!(msg.contains("line 17: [2002sub1] has no object section"), "{msg}");
    assert!(msg.contains("line 22: [2003] ObjectType 0x42 unknown"), "{msg}");
    assert!(msg.contains("line 27: [2004]: LowLimit"), "{msg}");
}

#[test]
fn checker_finds_violations() {
    let text = "[DeviceInfo]\nNrOfRXPDO=0\nNrOfTXPDO=1\n[1000]\nObjectType=0x7\nDataType=0x0006\nAccessType=ro\n[2000]\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\nDefaultValue=9\nLowLimit=10\nHighLimit=5\nPDOMapping=0\n[1800]\nObjectType=0x9\n[1800sub0]\nDataType=0x0005\nAccessType=const\nDefaultValue=1\n[1800sub1]\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x180\n[1A00]\nObjectType=0x9\n[1A00sub0]\nDataType=0x0005\nAccessType=rw\nDefaultValue=2\n[1A00sub1]\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x20000008\n[1A00sub2]\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x00020008\n";
    let p = parse(text).unwrap();
    let f: Vec<String> = check(&p.eds).iter().map(|f| f.to_string()).collect();
    let has = |s: &str| f.iter().any(|m| m.contains(s));
    assert!(has("1001: mandatory object missing"), "{f:#?}");
    assert!(has("1018: mandatory object missing"), "{f:#?}");
    assert!(has("1000sub0: CiA 301/402 defines this as UNSIGNED32, file says UNSIGNED16"), "{f:#?}");
    assert!(has("2000sub0: LowLimit is above HighLimit"), "{f:#?}");
    assert!(has("2000sub0: DefaultValue outside LowLimit..HighLimit"), "{f:#?}");
    assert!(has("1A00sub1: maps 2000sub0, which is not TPDO-mappable"), "{f:#?}");
    assert!(has("1A00sub2: maps dummy 0002 not enabled"), "{f:#?}");
    assert!(has("neither heartbeat"), "{f:#?}");
}

#[test]
fn dcf_parameter_values_and_commissioning() {
    let text = "[DeviceComissioning]\nNodeID=0x05\nNodeName=axis1\nBaudrate=500\nNetNumber=1\nNetworkName=line\nCANopenManager=0\nLSS_SerialNumber=0x1234\n[1017]\nParameterName=HB\nObjectType=0x7\nDataType=0x0006\nAccessType=rw\nDefaultValue=0\nParameterValue=250\n";
    let p = parse(text).unwrap();
    let c = p.eds.commissioning.clone().unwrap();
    assert_eq!((c.node_id, c.baudrate, c.lss_serial_number), (5, 500, Some(0x1234)));
    assert_eq!(c.node_name, "axis1");
    let od = to_od(&p.eds, c.node_id).unwrap();
    let hb = od.get(0x1017, 0).unwrap();
    assert_eq!(hb.value(), Value::U16(250));
    assert_eq!(hb.default_value(), Value::U16(0));
    let mut again = parse(&write(&p.eds)).unwrap().eds;
    let mut orig = p.eds;
    again.strip_lines();
    orig.strip_lines();
    assert_eq!(orig, again);
}

#[test]
fn od_to_eds_and_back() {
    let od = to_od(&parse(QUIRKS).unwrap().eds, 7).unwrap();
    let eds = drivebus_eds::from_od(&od, Default::default(), 7, false);
    let text = write(&eds);
    let back = to_od(&parse(&text).unwrap().eds, 7).unwrap();
    assert_eq!(od, back);
    // Node-relative COB-IDs are written as $NODEID expressions and move with the node.
    assert!(text.contains("DefaultValue=$NODEID+0x200"), "{text}");
    assert_eq!(to_od(&parse(&text).unwrap().eds, 9).unwrap().get_u32(0x1400, 1), Some(0x209));
}
