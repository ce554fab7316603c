//! Exchanges driven the way SOEM drives them (`ec_coe.c`): normal and
//! segmented transfers sized from the mailbox, complete-access reads of the
//! PDO objects, the object dictionary through SDO Information. Answers are
//! checked byte by byte against ETG.1000.6 §5.6.2/§5.6.3, and the data
//! against per-sub reads and the dictionary.

mod support;

use drivebus_coe::access_bits::*;
use drivebus_coe::{MailboxConfig, NoFiles};
use drivebus_od::{NoHooks, SdoAbort};
use support::{Dev, Fail, Rig, body, ethercrab, mbx, pattern, soem, test_od};

fn rig(size: usize) -> Rig<Dev, NoFiles> {
    Rig::new(MailboxConfig::with_sizes(size, size), (test_od(), NoHooks), NoFiles)
}

#[test]
fn segmented_download_frames() {
    // 300 bytes through a 128-byte mailbox: SOEM sends 112 bytes in the
    // initiate (SM0 − 16), then segments of up to 119 (SM0 − 9).
    let mut r = rig(128);
    let data = pattern(300, 9);
    let mut init = vec![0x00, 0x20, 0x21, 0x00, 0x20, 0x00];
    init.extend_from_slice(&300u32.to_le_bytes());
    init.extend_from_slice(&data[..112]);
    let c = r.counter();
    let resp = r.one(&mbx(3, c, &init));
    // §5.6.2.2: initiate download response 60h, nothing else.
    assert_eq!(body(&resp), [0x00, 0x30, 0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0]);
    let mut seg = vec![0x00, 0x20, 0x00];
    seg.extend_from_slice(&data[112..231]);
    let c = r.counter();
    let resp = r.one(&mbx(3, c, &seg));
    // §5.6.2.3: download segment response 20h | toggle, 7 reserved bytes.
    assert_eq!(body(&resp), [0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0]);
    let mut seg = vec![0x00, 0x20, 0x11];
    seg.extend_from_slice(&data[231..]);
    let c = r.counter();
    let resp = r.one(&mbx(3, c, &seg));
    assert_eq!(body(&resp), [0x00, 0x30, 0x30, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(r.dev.0.get(0x2000, 0).unwrap().bytes(), data);
    // The same through the SOEM algorithm, with a 7-byte minimum last
    // segment (112 + 119 + 3).
    let data = pattern(234, 3);
    soem::sdo_write(&mut r, 0x2000, 0, false, &data).unwrap();
    assert_eq!(r.dev.0.get(0x2000, 0).unwrap().bytes(), data);
}

#[test]
fn segmented_upload_frames() {
    let mut r = rig(128);
    let data = pattern(234, 5);
    r.dev.0.set_raw(r.dev.0.find(0x2000, 0).unwrap(), &data);
    let c = r.counter();
    let resp = r.one(&mbx(3, c, &[0x00, 0x20, 0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0]));
    // §5.6.2.5: 41h, complete size 234, and as much data as SM1 holds
    // (128 − 16 = 112 bytes).
    assert_eq!(resp.len(), 128);
    assert_eq!(body(&resp)[..10], [0x00, 0x30, 0x41, 0x00, 0x20, 0x00, 234, 0, 0, 0]);
    assert_eq!(body(&resp)[10..], data[..112]);
    // §5.6.2.6: segment requests 60h/70h; responses 00h | toggle | last,
    // sized by the mailbox; the final 3 bytes padded to 7 with n = 4.
    let c = r.counter();
    let resp = r.one(&mbx(3, c, &[0x00, 0x20, 0x60, 0, 0, 0, 0, 0, 0, 0]));
    assert_eq!(resp.len(), 128);
    assert_eq!(body(&resp)[..3], [0x00, 0x30, 0x00]);
    assert_eq!(body(&resp)[3..], data[112..231]);
    let c = r.counter();
    let resp = r.one(&mbx(3, c, &[0x00, 0x20, 0x70, 0, 0, 0, 0, 0, 0, 0]));
    assert_eq!(body(&resp), [0x00, 0x30, 0x19, data[231], data[232], data[233], 0, 0, 0, 0]);
    assert!(r.server.is_idle());
    // SOEM's reading of the same.
    assert_eq!(soem::sdo_read(&mut r, 0x2000, 0, false).unwrap(), data);
}

#[test]
fn complete_access_reads_of_pdo_objects() {
    // `ecx_readPDOassignCA`: CA read at sub 0 into {u8 n; u8 pad; u16[]}.
    let mut r = rig(128);
    let c = r.counter();
    let resp = r.one(&mbx(3, c, &[0x00, 0x20, 0x50, 0x12, 0x1C, 0x00, 0, 0, 0, 0]));
    assert_eq!(body(&resp), [0x00, 0x30, 0x53, 0x12, 0x1C, 0x00, 0x01, 0x00, 0x00, 0x16]);
    let c = r.counter();
    let resp = r.one(&mbx(3, c, &[0x00, 0x20, 0x50, 0x13, 0x1C, 0x00, 0, 0, 0, 0]));
    assert_eq!(
        body(&resp),
        [0x00, 0x30, 0x51, 0x13, 0x1C, 0x00, 6, 0, 0, 0, 0x02, 0x00, 0x00, 0x1A, 0x01, 0x1A]
    );
    // The mapping objects: {u8 n; u8 pad; u32[]}; SOEM sums the low bytes.
    let mut bits = 0;
    for pdo in [0x1A00u16, 0x1A01] {
        let img = soem::sdo_read(&mut r, pdo, 0, true).unwrap();
        let n = usize::from(img[0]);
        assert_eq!(img.len(), 2 + 4 * n);
        bits += img[2..].chunks(4).map(|e| u32::from(e[0])).sum::<u32>();
    }
    assert_eq!(bits, 16 + 32 + 8);
}

#[test]
fn complete_access_equals_per_sub_reads() {
    let mut r = rig(128);
    // 64 u32 entries: 258 bytes, segmented through a 128-byte mailbox.
    let img = soem::sdo_read(&mut r, 0x3000, 0, true).unwrap();
    assert_eq!(img.len(), 2 + 64 * 4);
    assert_eq!(img[..2], [64, 0]);
    for i in 1..=64u8 {
        let v = soem::sdo_read(&mut r, 0x3000, i, false).unwrap();
        let at = 2 + 4 * usize::from(i - 1);
        assert_eq!(img[at..at + 4], v[..], "sub {i}");
    }
}

#[test]
fn complete_access_write_as_soem_sends_it() {
    // `ecx_SDOwrite` with CA: always a normal download (31h).
    let mut r = rig(128);
    soem::sdo_write(&mut r, 0x1C12, 0, true, &[2, 0, 0x00, 0x16, 0x01, 0x16]).unwrap();
    assert_eq!(r.dev.0.get_u64(0x1C12, 0), Some(2));
    assert_eq!(r.dev.0.get_u64(0x1C12, 2), Some(0x1601));
    // A mapping record through the segmented path of a 32-byte mailbox.
    let mut r = rig(32);
    let mut img = vec![3, 0];
    for e in [0x6040_0010u32, 0x6060_0008, 0x607A_0020] {
        img.extend_from_slice(&e.to_le_bytes());
    }
    soem::sdo_write(&mut r, 0x1600, 0, true, &img).unwrap();
    assert_eq!(r.dev.0.get_u32(0x1600, 3), Some(0x607A_0020));
    assert_eq!(soem::sdo_read(&mut r, 0x1600, 0, true).unwrap(), img);
}

#[test]
fn object_dictionary_through_sdo_info() {
    let mut r = rig(128);
    let all: Vec<u16> = r.dev.0.objects().iter().map(|o| o.index).collect();
    assert_eq!(soem::od_list(&mut r, 1).unwrap(), all);
    assert_eq!(soem::od_list(&mut r, 2).unwrap(), [0x2003, 0x6040]);
    assert_eq!(soem::od_list(&mut r, 3).unwrap(), [0x2003, 0x6041]);
    // §5.6.3.5: data type, object code, highest sub-index, name.
    assert_eq!(soem::od_desc(&mut r, 0x1000).unwrap(), (0x0007, 7, 0, "Device type".into()));
    assert_eq!(soem::od_desc(&mut r, 0x1018).unwrap(), (0x0023, 9, 4, "Identity Object".into()));
    assert_eq!(soem::od_desc(&mut r, 0x1C12).unwrap(), (0x0006, 8, 4, "Sync Manager PDO assignment".into()));
    assert_eq!(soem::od_desc(&mut r, 0x1600).unwrap().0, 0x0021);
    assert_eq!(soem::od_desc(&mut r, 0x3000).unwrap(), (0x0007, 8, 64, "Table".into()));
    assert_eq!(soem::od_desc(&mut r, 0x5000), Err(Fail::InfoError(SdoAbort::NO_OBJECT.0)));
    // §5.6.3.6 with value info 07h (SOEM): no optional fields, name last.
    assert_eq!(soem::oe_desc(&mut r, 0x1000, 0).unwrap(), (0x07, 0x0007, 32, READ, "Device type".into()));
    let (_, dt, bits, access, _) = soem::oe_desc(&mut r, 0x2100, 2).unwrap();
    assert_eq!((dt, bits, access), (0x0001, 1, READ | WRITE | BACKUP | SETTINGS));
    assert_eq!(soem::oe_desc(&mut r, 0x1008, 0).unwrap().2, 8 * 18);
    assert_eq!(soem::oe_desc(&mut r, 0x6040, 0).unwrap().3, READ | WRITE | RXPDO | BACKUP | SETTINGS);
    assert_eq!(soem::oe_desc(&mut r, 0x1018, 5), Err(Fail::InfoError(SdoAbort::NO_SUB_INDEX.0)));
}

#[test]
fn entry_description_optional_fields() {
    let mut r = rig(128);
    // Default, minimum and maximum asked (78h; unit type is not known, so
    // bit 3 is not given back).
    let b = soem::oe_raw(&mut r, 0x2003, 0, 0x78).unwrap();
    let mut want = vec![0x00, 0x80, 0x06, 0x00, 0x00, 0x00, 0x03, 0x20, 0x00, 0x70];
    // INTEGER16, 16 bits, read/write in every state, both PDO directions, stored.
    want.extend_from_slice(&[0x03, 0x00, 16, 0, 0xFF, 0x03]);
    want.extend_from_slice(&[5, 0, 0x9C, 0xFF, 100, 0]);
    want.extend_from_slice(b"Limited");
    assert_eq!(b, want);
    // No limits in the dictionary: only the default.
    let b = soem::oe_raw(&mut r, 0x1000, 0, 0x70).unwrap();
    assert_eq!(b[9], 0x10);
    assert_eq!(b[16..20], 0x0006_0192u32.to_le_bytes());
    assert_eq!(&b[20..], b"Device type");
}

#[test]
fn od_list_fragments_in_a_small_mailbox() {
    // 32-byte SM1: 20 bytes of list per fragment.
    let mut r = rig(32);
    let all: Vec<u16> = r.dev.0.objects().iter().map(|o| o.index).collect();
    assert_eq!(soem::od_list(&mut r, 1).unwrap(), all);
    // Frame by frame: "incomplete" and "fragments left" count down.
    let c = r.counter();
    r.send(&ethercrab::od_list(c, 1));
    let mut frags = Vec::new();
    while let Some(m) = r.read() {
        frags.push(m);
    }
    let n = frags.len();
    assert_eq!(n, (2 + 2 * all.len()).div_ceil(20));
    for (k, f) in frags.iter().enumerate() {
        let b = body(f);
        let left = (n - 1 - k) as u16;
        assert_eq!(b[2], 0x02 | if left > 0 { 0x80 } else { 0 });
        assert_eq!(u16::from_le_bytes([b[4], b[5]]), left);
    }
    // ethercrab 0.7.1 reads `length - 8` bytes of every fragment, one
    // index short for each fragment after the first.
    assert_eq!(ethercrab::parse_od_list(&frags).len(), all.len() - (n - 1));
}

#[test]
fn info_fragments_hold_emergencies_and_a_new_request_ends_them() {
    let mut r = rig(32);
    r.server.queue_emergency(0x3210, 0x04, [0; 5]).unwrap();
    let c = r.counter();
    r.send(&ethercrab::od_list(c, 1));
    let first = r.read().unwrap();
    assert_eq!(body(&first)[2], 0x82);
    // The master gives up and asks something else: the rest is dropped,
    // the answer comes, then the emergency.
    let c = r.counter();
    r.send(&ethercrab::upload(c, 0x1000, Some(0)));
    assert_eq!(body(&r.read().unwrap())[2], 0x43);
    assert_eq!(body(&r.read().unwrap())[..4], [0x00, 0x10, 0x10, 0x32]);
    assert_eq!(r.read(), None);
}
