//! The written files parse with parsers that share no code with ours:
//! `roxmltree` (a strict XML 1.0 parser) and the `ethercat-esi` crate
//! (ETG.2000 via serde-xml-rs), and say what the description says.

mod common;

use drivebus_esi::{SlaveDescription, SmKind};
use drivebus_personality::Profile;

fn hexdec(s: &str) -> u64 {
    match s.strip_prefix("#x") {
        Some(h) => u64::from_str_radix(h, 16).unwrap(),
        None => s.parse().unwrap(),
    }
}

fn text<'a>(n: roxmltree::Node<'a, 'a>, tag: &str) -> Option<&'a str> {
    n.children().find(|c| c.has_tag_name(tag)).and_then(|c| c.text())
}

fn check_with_roxmltree(desc: &SlaveDescription) {
    let xml = drivebus_esi::write(desc);
    let doc = roxmltree::Document::parse(&xml).expect("roxmltree parses the ESI");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "EtherCATInfo");
    let vendor = root.children().find(|c| c.has_tag_name("Vendor")).unwrap();
    assert_eq!(hexdec(text(vendor, "Id").unwrap()), u64::from(desc.vendor_id));
    let device = root.descendants().find(|n| n.has_tag_name("Device")).unwrap();
    let ty = device.children().find(|c| c.has_tag_name("Type")).unwrap();
    assert_eq!(hexdec(ty.attribute("ProductCode").unwrap()), u64::from(desc.product_code));
    assert_eq!(hexdec(ty.attribute("RevisionNo").unwrap()), u64::from(desc.revision));
    assert_eq!(ty.text(), Some(desc.type_name.as_str()));
    let objects: Vec<_> = device.descendants().filter(|n| n.has_tag_name("Object")).collect();
    assert_eq!(objects.len(), desc.objects.len());
    for (o, d) in objects.iter().zip(&desc.objects) {
        assert_eq!(hexdec(text(*o, "Index").unwrap()), u64::from(d.index));
        assert_eq!(text(*o, "Name").unwrap_or(""), d.name);
    }
    let sms: Vec<_> = device.children().filter(|c| c.has_tag_name("Sm")).collect();
    assert_eq!(sms.len(), desc.sync_managers.len());
    for (s, d) in sms.iter().zip(&desc.sync_managers) {
        assert_eq!(hexdec(s.attribute("StartAddress").unwrap()), u64::from(d.start));
        assert_eq!(hexdec(s.attribute("ControlByte").unwrap()), u64::from(d.control));
        assert_eq!(s.text(), Some(d.kind.name()));
    }
    let rx = device.children().filter(|c| c.has_tag_name("RxPdo")).count();
    assert_eq!(rx, desc.rx_pdos.len());
}

#[test]
fn roxmltree_reads_every_profile() {
    for &p in Profile::all() {
        check_with_roxmltree(&common::build(p).0);
    }
}

fn check_with_ethercat_esi(desc: &SlaveDescription, xml: &str) {
    let info = ethercat_esi::EtherCatInfo::from_xml_str(xml).expect("ethercat-esi reads the file");
    assert_eq!(info.vendor.id, desc.vendor_id);
    assert_eq!(info.vendor.name.as_deref(), Some(desc.vendor_name.as_str()));
    assert_eq!(info.description.groups[0].r#type, desc.group_type);
    let dev = &info.description.devices[0];
    assert_eq!((dev.product_code, dev.revision_no), (desc.product_code, desc.revision));
    assert_eq!(dev.name, desc.name);
    assert_eq!(dev.desc, desc.type_name);
    assert_eq!(dev.physics.as_deref(), Some(desc.physics.as_str()));
    assert_eq!(dev.sm.len(), desc.sync_managers.len(), "every Sm element");
    let first_sm = &dev.sm[0];
    let (_, mbx) = desc.sm(SmKind::MBoxOut).unwrap();
    assert_eq!((first_sm.start_address, first_sm.control_byte), (mbx.start, mbx.control));
    assert_eq!(first_sm.default_size, mbx.default_size.map(usize::from));
    for (got, want) in [(&dev.rx_pdo, &desc.rx_pdos), (&dev.tx_pdo, &desc.tx_pdos)] {
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(want) {
            assert_eq!(u16::from(g.idx), w.index);
            assert_eq!((g.fixed, g.mandatory), (w.fixed, w.mandatory));
            assert_eq!(g.entries.len(), w.entries.len());
            for (ge, we) in g.entries.iter().zip(&w.entries) {
                assert_eq!(u16::from(ge.entry_idx.idx), we.index);
                assert_eq!(u8::from(ge.entry_idx.sub_idx), we.sub);
                assert_eq!(ge.bit_len, usize::from(we.bit_len));
            }
        }
    }
}

#[test]
fn ethercat_esi_reads_a_fully_assigned_device() {
    // generic assigns every PDO by default, so each has an `Sm`.
    let (desc, _, _) = common::build(Profile::Generic);
    check_with_ethercat_esi(&desc, &drivebus_esi::write(&desc));
}

#[test]
fn ethercat_esi_needs_sm_on_every_pdo() {
    // ETG.2000 makes `RxPdo@Sm`/`TxPdo@Sm` optional: without it a PDO is
    // not assigned by default, as the iPOS's RxPDO2–4 and TxPDO3–4 are
    // (§2.3). ethercat-esi 0.2.0 declares `Sm` mandatory and refuses such
    // files; everything else in them it reads.
    let (desc, _, _) = common::build(Profile::Ipos);
    let xml = drivebus_esi::write(&desc);
    let err = ethercat_esi::EtherCatInfo::from_xml_str(&xml).expect_err("ethercat-esi 0.2.0 needs Sm");
    assert!(err.to_string().contains("Sm"), "{err}");
    let mut all = desc.clone();
    for p in &mut all.rx_pdos {
        p.sm.get_or_insert(2);
    }
    for p in &mut all.tx_pdos {
        p.sm.get_or_insert(3);
    }
    check_with_ethercat_esi(&all, &drivebus_esi::write(&all));
}
