use super::*;
use drivebus_can::Instant;
use drivebus_esc::frame::{DatagramCommand, FrameBuilder, datagrams, position_address, station_address};
use drivebus_esc::slave::SlaveApp;

macro_rules! vector {
    ($f:literal) => {
        include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/vectors/ethercat/", $f))
    };
}

fn image(name: &str, bytes: &[u8]) -> Described {
    from_bytes(name, bytes, None).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn real_eeprom_images_describe_their_devices() {
    let ek = image("ek1100.bin", vector!("ek1100.bin"));
    let d = &ek.description;
    assert_eq!((d.vendor_id, d.product_code, d.revision), (2, 0x044C_2C52, 0x0012_0000));
    assert_eq!((ek.type_name(), d.name.as_str()), ("EK1100", "EK1100 EtherCAT-Koppler (2A E-Bus)"));
    assert!(d.sync_managers.is_empty() && d.mailbox.is_none(), "a coupler: no SMs, no mailbox");
    let el = image("el2004.bin", vector!("el2004.bin"));
    assert_eq!((el.type_name(), el.description.product_code), ("EL2004", 0x07D4_3052));
    assert_eq!(process_data(&el.description).unwrap().0.output_bits, 4);
    let el = image("el2828.bin", vector!("el2828.bin"));
    assert_eq!(
        process_data(&el.description).unwrap(),
        (ProcessDataSizes { output_bits: 8, input_bits: 0 }, Some(0), None)
    );
    let akd = image("akd.bin", vector!("akd.bin"));
    assert_eq!((akd.type_name(), akd.description.vendor_id), ("AKD", 0x6A));
    assert!(akd.description.mailbox.is_some_and(|m| m.coe.is_some()));
    let (sizes, out_sm, in_sm) = process_data(&akd.description).unwrap();
    assert_eq!(
        (sizes.output_bits, sizes.input_bits, out_sm, in_sm),
        (48, 48, Some(2), Some(3)),
        "1701h and 1B01h"
    );
}

#[test]
fn intel_hex_gives_the_same_image_byte_for_byte() {
    let hex = image("el2004.hex", vector!("el2004.hex"));
    assert_eq!(hex.format, Format::IntelHex);
    assert_eq!(hex.sii.bytes(), vector!("el2004.bin"));
}

#[test]
fn two_output_sync_managers_are_refused_by_name() {
    let d = image("el2889.bin", vector!("el2889.bin"));
    let e = slave(&d, 1, Box::new(Loopback)).unwrap_err();
    assert_eq!(e.message, "outputs over SM0 and SM1: one sync manager per direction is served");
    assert_eq!(e.file, "EL2889");
}

#[test]
fn esi_device_with_dictionary() {
    let d = from_bytes("k64f.xml", vector!("kickcat-freedom-k64f.xml"), None).unwrap();
    assert_eq!(d.format, Format::Esi);
    assert_eq!(
        (d.type_name(), d.description.vendor_id, d.description.product_code),
        ("Board", 0x6A5, 0x00DE_FEDE)
    );
    let s = slave(&d, 9, Box::new(Loopback)).unwrap();
    assert_eq!(s.app().process_data_sizes(), ProcessDataSizes { output_bits: 24, input_bits: 96 });
    let od = s.app().dictionary().unwrap();
    assert_eq!(od.get(0x6003, 0).map(|e| e.name.as_ref()), Some("mag_x"));
    assert_eq!(od.get_u32(0x1C13, 1), Some(0x1A00));
    let id: Vec<_> = (1..=4).map(|k| od.get_u32(0x1018, k).unwrap()).collect();
    assert_eq!(
        id,
        [0x6A5, 0x00DE_FEDE, 0x5A01, 9],
        "1018h is the device's identity, not the ESI's placeholder"
    );
    let c = s.esc().sii_image().parse().unwrap();
    assert_eq!((c.identity.product_code, c.identity.serial), (0x00DE_FEDE, 9));
    assert_eq!(s.app().coe.as_ref().unwrap().outputs.len(), 3, "LED_R/G/B mirrored");
}

#[test]
fn several_devices_need_a_selector() {
    let f = vector!("kickcat-multi-device.xml");
    let e = from_bytes("m.xml", f, None).unwrap_err();
    assert!(
        e.message.starts_with(
            "describes 3 devices, pick one with FILE#N or FILE#PRODUCT: #1 kickcat_multi_dev_alpha"
        ),
        "{e}"
    );
    let pick =
        |s| from_bytes("m.xml", f, Some(s)).map(|d| (d.description.product_code, d.description.revision));
    assert_eq!(pick("2"), Ok((0x2222, 1)));
    assert_eq!(pick("KICKCAT_MULTI_DEV_ALPHA"), Ok((0x1111, 1)));
    assert_eq!(pick("#x1111"), Ok((0x1111, 1)));
    assert!(pick("0x2222").unwrap_err().message.contains("matches several devices"));
    assert!(pick("4").unwrap_err().message.starts_with("#4: the file describes 3 devices"));
    assert!(pick("nope").unwrap_err().message.starts_with("no device \"nope\""));
    let e = from_bytes("a.bin", vector!("el2004.bin"), Some("1")).unwrap_err();
    assert!(e.message.contains("EEPROM image"), "{e}");
    assert_eq!(split_spec("dir/m.xml#2"), ("dir/m.xml", Some("2")));
}

#[test]
fn malformed_files_say_where() {
    let mut img = vector!("el2004.bin").to_vec();
    img[0x82..0x84].copy_from_slice(&0x7FFFu16.to_le_bytes());
    let e = from_bytes("x.bin", &img, None).unwrap_err();
    assert_eq!(e.at, "SII");
    assert!(e.message.contains("at word 0x0040"), "{e}");
    let e = from_bytes("x.bin", &img[..100], None).unwrap_err();
    assert!(e.message.contains("shorter than 128"), "{e}");
    let e = from_bytes("x.hex", b":0400000001020304F3\n", None).unwrap_err();
    assert_eq!(e.to_string(), "x.hex: line 1: checksum does not match");
    let e = from_bytes("x.xml", b"<EtherCATInfo><Vendor>", None).unwrap_err();
    assert!(e.at.starts_with("byte"), "{e}");
    let e = from_bytes("x.xml", b"<a>\xff</a>", None).unwrap_err();
    assert_eq!((e.at.as_str(), e.message.as_str()), ("byte 3", "not UTF-8"));
}

/// One datagram to the slave at station 0x1000, then a poll.
fn dg(s: &mut DescribedSlave, t: &mut Instant, cmd: DatagramCommand, addr: u32, data: &[u8]) -> Vec<u8> {
    *t += drivebus_can::Duration::from_micros(10);
    let mut buf = [0u8; 128];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(cmd, 1, addr, data).unwrap();
    let n = b.finish();
    s.esc_mut().process_frame(&mut buf[..n], *t);
    s.poll(*t);
    datagrams(&buf[14..n]).next().unwrap().data.to_vec()
}

/// The image is served as it is; a word the master writes stays through a
/// reload, as in a real EEPROM.
#[test]
fn image_served_byte_for_byte_and_keeps_a_write_through_reload() {
    let d = image("el2004.bin", vector!("el2004.bin"));
    let mut s = slave(&d, 1, Box::new(Loopback)).unwrap();
    assert_eq!(s.esc().sii_image().bytes(), vector!("el2004.bin"));
    assert!(s.esc().device_emulation(), "EL2004 word 0: device emulation");
    let mut t = Instant::ZERO;
    dg(&mut s, &mut t, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10]);
    let st = |ado| station_address(0x1000, ado);
    // Word 0x0E (serial number, low half): data, then write enable + write.
    dg(&mut s, &mut t, DatagramCommand::Fpwr, st(0x0508), &[0xCD, 0xAB]);
    dg(&mut s, &mut t, DatagramCommand::Fpwr, st(0x0502), &[0x01, 0x02, 0x0E, 0, 0, 0]);
    dg(&mut s, &mut t, DatagramCommand::Fpwr, st(0x0502), &[0x00, 0x04]);
    dg(&mut s, &mut t, DatagramCommand::Fpwr, st(0x0502), &[0x00, 0x01, 0x0E, 0, 0, 0]);
    assert_eq!(dg(&mut s, &mut t, DatagramCommand::Fprd, st(0x0508), &[0; 2]), [0xCD, 0xAB]);
    let mut want = vector!("el2004.bin").to_vec();
    want[0x1C..0x1E].copy_from_slice(&[0xCD, 0xAB]);
    assert_eq!(s.esc().sii_image().bytes(), want, "only the written word changed");
}

/// Outputs written through the FMMU appear on the device in OP.
#[test]
fn el2004_outputs_reach_the_device() {
    let d = image("el2004.bin", vector!("el2004.bin"));
    let mut s = slave(&d, 1, Box::new(Loopback)).unwrap();
    let mut t = Instant::ZERO;
    dg(&mut s, &mut t, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10]);
    let st = |ado| station_address(0x1000, ado);
    dg(&mut s, &mut t, DatagramCommand::Fpwr, st(0x0800), &[0x00, 0x0F, 1, 0, 0x44, 0, 1, 0]);
    for state in [2u8, 4, 8] {
        dg(&mut s, &mut t, DatagramCommand::Fpwr, st(0x0120), &[state, 0]);
    }
    assert_eq!(dg(&mut s, &mut t, DatagramCommand::Fprd, st(0x0130), &[0; 2])[0], 8);
    dg(&mut s, &mut t, DatagramCommand::Fpwr, st(0x0F00), &[0x0A]);
    assert_eq!(s.app().outputs(), [0x0A]);
    dg(&mut s, &mut t, DatagramCommand::Fpwr, st(0x0120), &[4, 0]);
    assert_eq!(s.app().outputs(), [0], "outputs off outside OP");
}

/// Truncated and corrupted real files give a slave or an error, never a
/// panic (the fuzz target `device_file` does the same at random).
#[test]
fn damaged_files_never_panic() {
    let files: [&[u8]; 5] = [
        vector!("el2004.bin"),
        vector!("el2004.hex"),
        vector!("akd.bin"),
        vector!("kickcat-freedom-k64f.xml"),
        vector!("kickcat-multi-device.xml"),
    ];
    let mut seed = 0x2545_F491u32;
    for f in files {
        for cut in (0..f.len()).step_by(97) {
            if let Ok(d) = from_bytes("cut", &f[..cut], None) {
                let _ = slave(&d, 1, Box::new(Loopback));
            }
        }
        for _ in 0..200 {
            let mut b = f.to_vec();
            for _ in 0..4 {
                seed ^= seed << 13;
                seed ^= seed >> 17;
                seed ^= seed << 5;
                let i = seed as usize % b.len();
                b[i] = (seed >> 24) as u8;
            }
            if let Ok(d) = from_bytes("flip", &b, Some("1")).or_else(|_| from_bytes("flip", &b, None)) {
                let _ = slave(&d, 1, Box::new(Loopback));
            }
        }
    }
}
