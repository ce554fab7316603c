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
    let dummies: Vec<(u16, bool)> = e.dummy_usage.iter().map(|(k, v)| (*k, *v)).collect();
    assert_eq!(dummies, [(1, false), (2, true), (3, true), (4, true), (5, true), (6, true), (7, true)]);
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

const THIRD_PARTY: &str = include_str!("data/third_party.dcf");

/// The lines of section `name` of `text`, in order.
fn section<'a>(text: &'a str, name: &str) -> Vec<&'a str> {
    let head = format!("[{name}]");
    text.lines()
        .skip_while(|l| l.trim() != head)
        .skip(1)
        .take_while(|l| !l.starts_with('['))
        .filter(|l| !l.trim().is_empty())
        .collect()
}

/// Rewriting a third-party DCF keeps its `[DummyUsage]` entries as they
/// are (CiA 306 §4.5; Lely's dcfgen writes 0010h–001Bh too) and adds none
/// (no `Dummy0000`), and keeps the `[DeviceComissioning]` keys it does not
/// interpret (`NodeRefd`, `NetRefd`), `ParameterValue` and `Denotation`.
#[test]
fn third_party_dcf_is_rewritten_faithfully() {
    let p = parse(THIRD_PARTY).expect("parses");
    let text = write(&p.eds);
    assert_eq!(section(&text, "DummyUsage"), section(THIRD_PARTY, "DummyUsage"), "{text}");
    let c = section(&text, "DeviceComissioning");
    for key in ["NodeRefd=", "NetRefd=", "NodeName=master", "Baudrate=500", "NetworkName=line"] {
        assert!(c.contains(&key), "{key} missing: {c:?}");
    }
    let hb = &p.eds.objects[&0x1017].var.as_ref().unwrap();
    assert_eq!(
        (hb.parameter_value.as_deref(), hb.denotation.as_deref()),
        (Some("50"), Some("master heartbeat"))
    );
    let (mut a, mut b) = (p.eds, parse(&text).unwrap().eds);
    a.strip_lines();
    b.strip_lines();
    assert_eq!(a, b);
}

/// The DCF of a device (CiA 306 §5): every readable value as
/// `ParameterValue`, `[DeviceComissioning]` as given, `LastEDS`; read back,
/// it gives the device's values with the EDS's defaults.
#[test]
fn dcf_of_a_device_holds_its_values() {
    let eds = parse(QUIRKS).unwrap().eds;
    let mut od = to_od(&eds, 7).unwrap();
    od.set_value(0x1017, 0, &Value::U16(250)).unwrap();
    let c = drivebus_eds::Commissioning {
        node_id: 7,
        node_name: "axis 7".into(),
        baudrate: 250,
        net_number: 2,
        lss_serial_number: Some(0x1234),
        ..Default::default()
    };
    let d = drivebus_eds::dcf_from_od(&eds, &od, c.clone());
    let text = write(&d);
    assert!(text.contains("LastEDS=quirks.eds"), "{text}");
    let back = parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}")).eds;
    assert_eq!(back.commissioning, Some(c));
    let got = to_od(&back, 7).unwrap();
    for o in od.objects() {
        for s in o.subs().iter().filter(|s| s.access.readable() && s.data_type != DataType::Domain) {
            let g = got.get(o.index, s.sub).unwrap();
            assert_eq!(g.bytes(), s.bytes(), "{:04X}:{}", o.index, s.sub);
            assert_eq!(g.default, s.default, "{:04X}:{} default", o.index, s.sub);
        }
    }
    assert_eq!(got.get_u32(0x1017, 0), Some(250));
    assert!(check(&back).iter().all(|f| f.severity != Severity::Error), "{:#?}", check(&back));
}

/// Sub 0 of an ARRAY/RECORD is the highest sub-index supported (CiA 301
/// §7.4.3): a DefaultValue below the sub-objects described is a warning —
/// except where sub 0 counts something of its own, 1003h (number of
/// errors, §7.5.2.5) and the PDO mapping records (mapped objects,
/// §7.5.2.36/38).
#[test]
fn sub_0_below_the_highest_sub_index() {
    let obj = |index: &str, n: u8| {
        format!(
            "[{index}]\nParameterName=x\nObjectType=0x8\nSubNumber=3\n[{index}sub0]\nParameterName=n\nDataType=0x0005\nAccessType=rw\nDefaultValue={n}\n[{index}sub1]\nParameterName=a\nDataType=0x0007\nAccessType=rw\nDefaultValue=0\n[{index}sub2]\nParameterName=b\nDataType=0x0007\nAccessType=rw\nDefaultValue=0\n"
        )
    };
    let warned = |index: &str, n: u8| {
        let w = parse(&obj(index, n)).unwrap().warnings;
        w.iter().any(|d| d.message.contains("below the highest sub-index"))
    };
    assert!(warned("2000", 1));
    assert!(warned("1016", 0));
    assert!(!warned("2000", 2));
    for index in ["1003", "1600", "17FF", "1A00", "1BFF"] {
        assert!(!warned(index, 0), "{index}");
    }
}

/// Issue 15: a section header that does not close lost its section
/// silently; the error shown first was its consequence, "object 1000 is
/// listed but has no section" at line 0, with the cause nowhere.
#[test]
fn a_broken_section_header_is_the_first_error_with_its_line() {
    let n = QUIRKS.lines().position(|l| l.trim() == "[1000]").expect("[1000] in quirks.eds");
    let broken: String = QUIRKS
        .lines()
        .enumerate()
        .map(|(i, l)| if i == n { "[1000\n".to_owned() } else { format!("{l}\n") })
        .collect();
    let e = parse(&broken).unwrap_err();
    assert_eq!(e.errors[0].line, n + 1, "{e}");
    assert!(e.errors[0].message.contains("section header without ']'"), "{e}");
    assert!(e.errors.iter().any(|d| d.line == 0 && d.message.contains("listed but has no section")), "{e}");
    // Text after the header's `]` is an error too, not silently dropped.
    let trailing = QUIRKS.replacen("[1000]", "[1000]x", 1);
    let e = parse(&trailing).unwrap_err();
    assert!(e.errors[0].message.contains("after the section header"), "{e}");
}

/// Issue 15: `eds dcf` wrote an empty `[FileInfo]` and the checker passed it.
#[test]
fn an_empty_file_info_is_an_error() {
    let empty = QUIRKS.replace("FileName=quirks.eds\n", "").replace("FileVersion=1\n", "");
    let p = parse(&empty).unwrap();
    let errors: Vec<String> =
        check(&p.eds).into_iter().filter(|f| f.severity == Severity::Error).map(|f| f.message).collect();
    assert_eq!(errors, ["[FileInfo] lacks FileName, FileVersion (CiA 306 §4.2)"], "{errors:?}");
}

/// A DCF without `[FileInfo]` (Lely's dcfgen writes master.dcf so): one
/// warning, no error (the interop suite checks dcfgen's output).
#[test]
fn a_missing_file_info_is_one_warning() {
    let start = QUIRKS.find("[FileInfo]").unwrap();
    let end = start + QUIRKS[start..].find("\n[").unwrap() + 1;
    let p = parse(&format!("{}{}", &QUIRKS[..start], &QUIRKS[end..])).unwrap();
    assert!(p.warnings.iter().any(|w| w.message == "[FileInfo] missing"), "{:?}", p.warnings);
    let f = check(&p.eds);
    assert!(!f.iter().any(|f| f.severity == Severity::Error), "{f:?}");
    assert!(!f.iter().any(|f| f.message.contains("[FileInfo]")), "{f:?}");
}
