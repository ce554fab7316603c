//! Conformance-style cases, category SDO (CiA 301 §7.2.4), through the whole node.

mod common;
use common::*;
use drivebus_can::Duration;

#[test]
fn sdo_01_expedited_upload_of_every_identity_entry() {
    let mut r = Rig::new(device());
    r.exchange("605#4000100000000000", &["585#4300100092010200"]);
    r.exchange("605#4018100000000000", &["585#4F18100004000000"]);
    r.exchange("605#4018100100000000", &["585#43181001BC0A0000"]);
    r.exchange("605#4018100400000000", &["585#431810042A000000"]);
}

#[test]
fn sdo_02_segmented_upload_of_device_name_with_toggle() {
    let mut r = Rig::new(device());
    // "drivebus test" = 13 bytes: initiate with size, then 7 + 6 bytes.
    r.exchange("605#4008100000000000", &["585#410810000D000000"]);
    r.exchange("605#6000000000000000", &["585#0064726976656275"]);
    r.exchange("605#7000000000000000", &["585#1373207465737400"]);
    // A wrong toggle on a new transfer is refused with 0503 0000.
    r.exchange("605#4008100000000000", &["585#410810000D000000"]);
    r.exchange("605#7000000000000000", &["585#8008100000000305"]);
}

#[test]
fn sdo_03_aborts_for_missing_objects_and_access() {
    let mut r = Rig::new(device());
    r.exchange("605#4000200000000000", &["585#8000200000000206"]);
    r.exchange("605#4018100700000000", &["585#8018100711000906"]);
    r.exchange("605#2300100001000000", &["585#8000100002000106"]);
    // Unknown command specifier.
    r.exchange("605#E000100000000000", &["585#8000100001000405"]);
}

#[test]
fn sdo_04_length_mismatch_codes() {
    let mut r = Rig::new(device());
    // 1017h is UNSIGNED16: 4 bytes are too long, 1 byte too short.
    r.exchange("605#2317100064000000", &["585#8017100012000706"]);
    r.exchange("605#2F17100064000000", &["585#8017100013000706"]);
    r.exchange("605#2B17100064000000", &["585#6017100000000000"]);
}

#[test]
fn sdo_05_server_times_out_a_stalled_segmented_transfer() {
    let mut r = Rig::new(device());
    r.exchange("605#4008100000000000", &["585#410810000D000000"]);
    r.run_for(Duration::from_millis(999));
    assert!(r.take().is_empty());
    r.run_for(Duration::from_millis(2));
    assert_eq!(r.take(), frs(&["585#8008100000000405"]));
    // And the server is free again.
    r.exchange("605#4000100000000000", &["585#4300100092010200"]);
}

#[test]
fn sdo_06_client_abort_ends_the_transfer_silently() {
    let mut r = Rig::new(device());
    r.exchange("605#4008100000000000", &["585#410810000D000000"]);
    r.exchange("605#8008100000000000", &[]);
    r.exchange("605#4000100000000000", &["585#4300100092010200"]);
}

#[test]
fn sdo_07_block_upload_with_crc() {
    let mut r = Rig::new(device());
    // Block upload of 1008h (13 bytes), blksize 127, CRC supported.
    r.exchange("605#A40810007F000000", &["585#C60810000D000000"]);
    r.exchange("605#A300000000000000", &["585#0164726976656275", "585#8273207465737400"]);
    // Ack seq 2, blksize 127 → end frame with n = 7 - 6 = 1 unused byte and the CRC.
    let crc = crc16(b"drivebus test");
    r.take();
    r.send("605#A2027F0000000000");
    let end = r.take();
    assert_eq!(
        end,
        vec![drivebus_can::Frame::new(0x585, &[0xC5, crc as u8, (crc >> 8) as u8, 0, 0, 0, 0, 0])]
    );
    r.exchange("605#A100000000000000", &[]);
    r.exchange("605#4000100000000000", &["585#4300100092010200"]);
}

#[test]
fn sdo_08_block_download_blksize_0_and_128_rejected() {
    let mut r = Rig::new(device());
    // Block upload with blksize 0 and 128 → 0504 0002.
    r.exchange("605#A408100000000000", &["585#8008100002000405"]);
    r.exchange("605#A408100080000000", &["585#8008100002000405"]);
}

#[test]
fn sdo_09_only_in_pre_operational_and_operational() {
    let mut r = Rig::new(device());
    r.exchange("000#0105", &[]);
    r.exchange("605#4000100000000000", &["585#4300100092010200"]);
    r.exchange("000#0205", &[]);
    r.exchange("605#4000100000000000", &[]);
}

fn crc16(data: &[u8]) -> u16 {
    // CRC-16/XMODEM, written out here so the test does not trust the code under test.
    let mut crc: u16 = 0;
    for &b in data {
        crc ^= (b as u16) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 { (crc << 1) ^ 0x1021 } else { crc << 1 };
        }
    }
    crc
}

#[test]
fn crc_helper_matches_the_cia_301_vector() {
    assert_eq!(crc16(b"123456789"), 0x31C3);
}

#[test]
fn sdo_10_additional_server_channel() {
    let mut cfg = device();
    cfg.extra_sdo_servers = 1;
    let mut r = Rig::new(cfg);
    // 1201h starts invalid; give it 690h / 6A0h (outside the restricted ranges).
    Rig::assert_written(r.sdo_write(5, 0x1201, 1, &0x690u32.to_le_bytes()), 5, 0x1201, 1);
    Rig::assert_written(r.sdo_write(5, 0x1201, 2, &0x6A0u32.to_le_bytes()), 5, 0x1201, 2);
    r.exchange("690#4000100000000000", &["6A0#4300100092010200"]);
    // The default channel keeps working alongside.
    r.exchange("605#4000100000000000", &["585#4300100092010200"]);
    // Restricted identifiers are refused (CiA 301 §7.3.5): 0x581 is another node's SDO.
    r.exchange("605#2301120101060000", &["585#8001120130000906"]);
}
