use super::*;
use alloc::vec;
use proptest::prelude::*;

fn dio() -> SiiImage {
    let mut b = SiiImage::builder()
        .identity(0x0000_0F1E, 0x0000_2008, 0x0001_0000, 42)
        .station_alias(7)
        .names("DigIO", "DB-DIO8", "drivebus 8-channel digital I/O")
        .fmmus(&[fmmu_usage::OUTPUTS, fmmu_usage::INPUTS])
        .sync_manager(SiiSyncManager {
            start: 0x1000,
            length: 1,
            control: 0x64,
            enable: 1,
            sm_type: sm_type::OUTPUTS,
        })
        .sync_manager(SiiSyncManager {
            start: 0x1100,
            length: 1,
            control: 0x20,
            enable: 1,
            sm_type: sm_type::INPUTS,
        });
    let s = b.add_string("Output");
    b.rx_pdo(SiiPdo {
        index: 0x1600,
        sync_manager: 0,
        entries: vec![SiiPdoEntry {
            index: 0x7000,
            sub_index: 1,
            name_idx: s,
            data_type: 1,
            bit_len: 8,
            flags: 0,
        }],
        ..SiiPdo::default()
    })
    .build()
}

#[test]
fn crc_is_the_esc_crc8() {
    // The algorithm's check value (CRC of "123456789"), then the first 14
    // bytes and stored CRC of real EEPROM dumps (EL2889, Kollmorgen AKD,
    // EK1100) from ethercrab's test data.
    assert_eq!(config_crc(b"123456789"), 0xFB);
    let dumps: [([u8; 14], u8); 3] = [
        ([0x04, 0x01, 0, 0, 0, 0, 0xFF, 0, 0, 0, 0, 0, 0, 0], 0xE2),
        ([0x09, 0, 0, 0x08, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0], 0x10),
        ([0, 0x0D, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0], 0x46),
    ];
    for (bytes, stored) in dumps {
        assert_eq!(config_crc(&bytes), stored);
    }
    let img = dio();
    assert!(img.checksum_ok());
    assert_eq!(img.bytes()[14], config_crc(&img.bytes()[..14]));
    assert_eq!(img.bytes()[15], 0);
}

#[test]
fn fixed_words_are_where_masters_read_them() {
    let img = dio();
    assert_eq!(img.word(4), 7, "alias at word 4");
    assert_eq!(img.word(8), 0x0F1E);
    assert_eq!(img.word(0x0A), 0x2008);
    assert_eq!(img.word(0x0E), 42);
    assert_eq!(img.word(0x3F), 1, "version");
    let kbit = img.word(0x3E) + 1;
    assert_eq!(usize::from(kbit) * 128, img.bytes().len(), "size word matches the image");
    assert_eq!(img.word(0x40), category::STRINGS);
    // Past the end the EEPROM reads erased.
    assert_eq!(img.word(100_000), 0xFFFF);
}

#[test]
fn general_category_layout_matches_etg1000_6_table_21() {
    let img = dio();
    let b = img.bytes();
    // Find the General category by walking the headers.
    let mut w = 0x40;
    loop {
        let kind = img.word(w);
        let len = usize::from(img.word(w + 1));
        if kind == category::GENERAL {
            assert_eq!(len, 16, "General is 32 bytes");
            let g = &b[(w + 2) * 2..];
            let order = g[2];
            assert_eq!(img.parse().unwrap().strings[usize::from(order) - 1], "DB-DIO8");
            break;
        }
        assert_ne!(kind, category::END);
        w += 2 + len;
    }
}

#[test]
fn parse_rejects_bad_crc_and_overruns() {
    let mut img = dio();
    img.bytes_mut()[8] ^= 1;
    assert!(matches!(img.parse(), Err(SiiError::Checksum { .. })));
    let mut img = dio();
    // Corrupt the first category length so it runs past the end.
    let at = 0x41 * 2;
    img.bytes_mut()[at..at + 2].copy_from_slice(&0x7FFFu16.to_le_bytes());
    assert_eq!(img.parse(), Err(SiiError::CategoryOverrun(category::STRINGS, 0x40)));
    assert_eq!(parse(&[0u8; 16]), Err(SiiError::TooShort));
}

fn ascii() -> impl Strategy<Value = String> {
    "[ -~]{0,20}"
}

prop_compose! {
    fn pdo()(index: u16, sm in 0u8..8, dc: u8, name: u8, flags: u16,
             entries in proptest::collection::vec((any::<u16>(), any::<u8>(), any::<u8>(), any::<u8>(), any::<u8>(), any::<u16>()), 0..6)) -> SiiPdo {
        SiiPdo { index, sync_manager: sm, dc_sync: dc, name_idx: name, flags,
            entries: entries.into_iter().map(|(i, s, n, t, b, f)| SiiPdoEntry { index: i, sub_index: s, name_idx: n, data_type: t, bit_len: b, flags: f }).collect() }
    }
}

prop_compose! {
    fn content()(
        cfg in any::<[u16; 5]>(), id in any::<[u32; 4]>(), mbx in any::<[u16; 8]>(), protocols: u16,
        strings in proptest::collection::vec(ascii(), 0..6),
        general in proptest::option::of(any::<[u8; 11]>()), ebus: i16, ports: u16, phys: u16,
        fmmus in proptest::collection::vec(0u8..4, 0..5),
        sms in proptest::collection::vec(any::<(u16, u16, u8, u8, u8)>(), 0..5),
        tx in proptest::collection::vec(pdo(), 0..3), rx in proptest::collection::vec(pdo(), 0..3),
        dc in proptest::collection::vec(any::<(u32, u32, u32, i16, u16, i16, u8, u8)>(), 0..3),
        other in proptest::collection::vec((1000u16..2000, proptest::collection::vec(any::<u8>(), 0..5).prop_map(|mut v| { if v.len() % 2 == 1 { v.push(0) } v })), 0..2),
    ) -> SiiContent {
        SiiContent {
            config: ConfigArea { pdi_control: cfg[0], pdi_config: cfg[1], sync_impulse_len: cfg[2], pdi_config2: cfg[3], station_alias: cfg[4] },
            identity: Identity { vendor_id: id[0], product_code: id[1], revision: id[2], serial: id[3] },
            bootstrap_mailbox: MailboxArea { rx_offset: mbx[0], rx_size: mbx[1], tx_offset: mbx[2], tx_size: mbx[3] },
            mailbox: MailboxArea { rx_offset: mbx[4], rx_size: mbx[5], tx_offset: mbx[6], tx_size: mbx[7] },
            mailbox_protocols: protocols,
            size_kbit: 0,
            version: 1,
            strings,
            general: general.map(|g| General { group_idx: g[0], image_idx: g[1], order_idx: g[2], name_idx: g[3], coe_details: g[4], foe_details: g[5], eoe_details: g[6], soe_channels: g[7], ds402_channels: g[8], sysman_class: g[9], flags: g[10], ebus_current: ebus, physical_ports: ports, physical_memory_address: phys }),
            fmmus,
            sync_managers: sms.into_iter().map(|(s, l, c, e, t)| SiiSyncManager { start: s, length: l, control: c, enable: e, sm_type: t }).collect(),
            fmmu_ex: Vec::new(),
            tx_pdos: tx,
            rx_pdos: rx,
            dc: dc.into_iter().map(|(a, b, c, d, e, f, g, h)| SiiDcSync { cycle_time0: a, shift_time0: b, shift_time1: c, sync1_cycle_factor: d, assign_activate: e, sync0_cycle_factor: f, name_idx: g, desc_idx: h }).collect(),
            other,
        }
    }
}

proptest! {
    #[test]
    fn encode_parse_round_trip(c in content()) {
        let img = SiiBuilder::from_content(c.clone()).build();
        let mut back = img.parse().unwrap();
        // The encoder derives the size; everything else must come back as written.
        prop_assert_eq!(usize::from(back.size_kbit) * 128, img.bytes().len());
        back.size_kbit = 0;
        prop_assert_eq!(back, c);
    }

    #[test]
    fn parse_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let _ = parse(&bytes);
    }
}
