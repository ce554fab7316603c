//! Frame-exact exchanges with requests packed as ethercrab 0.7.1 packs them
//! (`src/mailbox/coe/services.rs`) and answers derived from ETG.1000.6
//! §5.6. Two answers are checked against the Wireshark captures quoted in
//! ethercrab's own tests (an abort and an AKD's first OD-list fragment).

mod support;

use drivebus_coe::{MailboxConfig, NoFiles};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, Value};
use support::{Dev, Rig, body, ethercrab, test_od};

fn rig() -> Rig<Dev, NoFiles> {
    Rig::new(MailboxConfig::default(), (test_od(), NoHooks), NoFiles)
}

/// Response header: length, address 0, channel/priority 0, CoE with the
/// server's counter.
fn hdr(len: u8, cnt: u8) -> [u8; 6] {
    [len, 0, 0, 0, 0, 0x03 | (cnt << 4)]
}

#[test]
fn pdo_discovery_reads_are_expedited() {
    // ethercrab sizes process data with `sdo_read_expedited`, which fails
    // unless the answer is expedited (ETG.1000.6 §5.6.2.4: 1..=4 bytes,
    // command 43h | (4 - n) << 2).
    let mut r = rig();
    let cases: [(u16, u8, u8, [u8; 4]); 7] = [
        (0x1C12, 0, 0x4F, [0x01, 0, 0, 0]),
        (0x1C12, 1, 0x4B, [0x00, 0x16, 0, 0]),
        (0x1C13, 0, 0x4F, [0x02, 0, 0, 0]),
        (0x1C13, 2, 0x4B, [0x01, 0x1A, 0, 0]),
        (0x1600, 0, 0x4F, [0x02, 0, 0, 0]),
        (0x1600, 1, 0x43, [0x10, 0x00, 0x40, 0x60]),
        (0x1A00, 2, 0x43, [0x20, 0x00, 0x64, 0x60]),
    ];
    for (n, (index, sub, cmd, data)) in cases.into_iter().enumerate() {
        let cnt = r.counter();
        let resp = r.one(&ethercrab::upload(cnt, index, Some(sub)));
        let i = index.to_le_bytes();
        let mut want = hdr(10, n as u8 % 7 + 1).to_vec();
        want.extend_from_slice(&[0x00, 0x30, cmd, i[0], i[1], sub]);
        want.extend_from_slice(&data);
        assert_eq!(resp, want, "{index:04X}:{sub}");
    }
}

#[test]
fn expedited_downloads_as_sdo_write_array_sends_them() {
    // `sdo_write_array(0x1C13, [0x1A00, 0x1A01])`: sub 0 = 0, entries, sub 0 = n.
    let mut r = rig();
    let writes: [(u8, &[u8], u8); 4] =
        [(0, &[0], 0x2F), (1, &[0x00, 0x1A], 0x2B), (2, &[0x01, 0x1A], 0x2B), (0, &[2], 0x2F)];
    for (sub, value, cmd) in writes {
        let cnt = r.counter();
        let req = ethercrab::download(cnt, 0x1C13, Some(sub), value);
        assert_eq!(req[8], cmd, "ethercrab's command byte");
        let resp = r.one(&req);
        // §5.6.2.1: download response 60h, index and sub-index echoed.
        assert_eq!(body(&resp), [0x00, 0x30, 0x60, 0x13, 0x1C, sub, 0, 0, 0, 0]);
    }
    assert_eq!(r.dev.0.get_u64(0x1C13, 0), Some(2));
    // A 4-byte mapping entry (command 23h).
    let cnt = r.counter();
    let resp = r.one(&ethercrab::download(cnt, 0x1600, Some(1), &0x6060_0008u32.to_le_bytes()));
    assert_eq!(body(&resp)[2], 0x60);
    assert_eq!(r.dev.0.get_u32(0x1600, 1), Some(0x6060_0008));
}

#[test]
fn normal_upload_carries_size_and_data() {
    // §5.6.2.5: 41h, complete size, data; mailbox length 10 + n.
    let mut r = rig();
    let cnt = r.counter();
    let resp = r.one(&ethercrab::upload(cnt, 0x1008, Some(0)));
    let name = b"drivebus iPOS twin";
    let mut want = hdr(10 + name.len() as u8, 1).to_vec();
    want.extend_from_slice(&[0x00, 0x30, 0x41, 0x08, 0x10, 0x00, name.len() as u8, 0, 0, 0]);
    want.extend_from_slice(name);
    assert_eq!(resp, want);
    // ethercrab's reading: length - 10 bytes, complete size <= that: normal.
    let data_length = u16::from_le_bytes([resp[0], resp[1]]) - 10;
    assert_eq!(u32::from(data_length), u32::from_le_bytes([resp[12], resp[13], resp[14], resp[15]]));
}

#[test]
fn abort_matches_the_captured_not_found() {
    // ethercrab `error_not_found`, copied from Wireshark: an abort is an SDO
    // *request* (service 2), 80h, index, sub-index, code 0602 0000h
    // (§5.6.2.7.1 Table 40).
    let mut r = rig();
    let cnt = r.counter();
    let resp = r.one(&ethercrab::upload(cnt, 0x1001, Some(0)));
    assert_eq!(body(&resp), [0x00, 0x20, 0x80, 0x01, 0x10, 0x00, 0x00, 0x00, 0x02, 0x06]);
    assert_eq!(&resp[..6], hdr(10, 1));
}

/// The objects of the AKD's first OD-list fragment in ethercrab's
/// `get_object_description_list` capture, then ten more.
fn akd_like() -> ObjectDictionary {
    let mut idx = vec![0x1000u16, 0x1008, 0x1009, 0x100A, 0x1018, 0x1601, 0x1602, 0x1603];
    idx.extend(0x1621..=0x1626);
    idx.extend([0x1630, 0x1631]);
    idx.extend(0x1A00..=0x1A26);
    idx.extend([0x1A30, 0x1A31]);
    assert_eq!(idx.len(), 57);
    idx.extend(0x6040..0x604A);
    let mut od = ObjectDictionary::new();
    for i in idx {
        od.insert(Object::var(i, "x", DataType::Unsigned32, Access::Ro, Value::U32(0)));
    }
    od
}

#[test]
fn od_list_first_fragment_matches_the_akd_capture() {
    // ethercrab `get_object_description_list`, "from Wireshark".
    #[rustfmt::skip]
    let captured: [u8; 128] = [
        0x7a, 0x0, 0x0, 0x0, 0x0, 0x73, 0x0, 0x80, 0x82, 0x0, 0x1, 0x0, 0x1, 0x0, 0x0, 0x10,
        0x8, 0x10, 0x9, 0x10, 0xa, 0x10, 0x18, 0x10, 0x1, 0x16, 0x2, 0x16, 0x3, 0x16, 0x21,
        0x16, 0x22, 0x16, 0x23, 0x16, 0x24, 0x16, 0x25, 0x16, 0x26, 0x16, 0x30, 0x16, 0x31,
        0x16, 0x0, 0x1a, 0x1, 0x1a, 0x2, 0x1a, 0x3, 0x1a, 0x4, 0x1a, 0x5, 0x1a, 0x6, 0x1a, 0x7,
        0x1a, 0x8, 0x1a, 0x9, 0x1a, 0xa, 0x1a, 0xb, 0x1a, 0xc, 0x1a, 0xd, 0x1a, 0xe, 0x1a, 0xf,
        0x1a, 0x10, 0x1a, 0x11, 0x1a, 0x12, 0x1a, 0x13, 0x1a, 0x14, 0x1a, 0x15, 0x1a, 0x16,
        0x1a, 0x17, 0x1a, 0x18, 0x1a, 0x19, 0x1a, 0x1a, 0x1a, 0x1b, 0x1a, 0x1c, 0x1a, 0x1d,
        0x1a, 0x1e, 0x1a, 0x1f, 0x1a, 0x20, 0x1a, 0x21, 0x1a, 0x22, 0x1a, 0x23, 0x1a, 0x24,
        0x1a, 0x25, 0x1a, 0x26, 0x1a, 0x30, 0x1a, 0x31, 0x1a,
    ];

    let mut r = Rig::new(MailboxConfig::default(), (akd_like(), NoHooks), NoFiles);
    // The request bytes of the same capture (counter 7).
    r.send(&[0x8, 0x0, 0x0, 0x0, 0x0, 0x73, 0x0, 0x80, 0x1, 0x0, 0x0, 0x0, 0x1, 0x0]);
    let first = r.read().unwrap();
    assert_eq!(first[5] & 0x0F, 0x03);
    assert_eq!(first[..5], captured[..5]);
    assert_eq!(first[6..], captured[6..], "byte-equal to the AKD's fragment");
    // Fragments left 1: the rest comes unasked, complete, with list type
    // only in the first fragment (SOEM's reading).
    let second = r.read().unwrap();
    assert_eq!(body(&second)[..6], [0x00, 0x80, 0x02, 0x00, 0x00, 0x00]);
    assert_eq!(
        body(&second)[6..],
        [
            0x40, 0x60, 0x41, 0x60, 0x42, 0x60, 0x43, 0x60, 0x44, 0x60, 0x45, 0x60, 0x46, 0x60, 0x47, 0x60,
            0x48, 0x60, 0x49, 0x60
        ]
    );
    assert_eq!(r.read(), None);
}

#[test]
fn ethercrab_reads_a_single_fragment_list_whole() {
    // ethercrab copies `length - 8` bytes of every fragment; exact for a
    // one-fragment answer (see the crate report about later fragments).
    let mut r = Rig::new(MailboxConfig::with_sizes(512, 512), (test_od(), NoHooks), NoFiles);
    let cnt = r.counter();
    r.send(&ethercrab::od_list(cnt, 1));
    let f = r.read().unwrap();
    assert_eq!(r.read(), None);
    let all: Vec<u16> = r.dev.0.objects().iter().map(|o| o.index).collect();
    assert_eq!(ethercrab::parse_od_list(&[f]), all);
}

#[test]
fn object_quantities() {
    // List type 0: five UNSIGNED16 counts after the list type (ethercrab's
    // `ObjectDescriptionListQueryCounts`, 10 bytes).
    let mut r = rig();
    let cnt = r.counter();
    let resp = r.one(&ethercrab::od_list(cnt, 0));
    let all = r.dev.0.objects().len() as u16;
    // RxPDO: 2003h (rw, mappable), 6040h (rww). TxPDO: 2003h, 6041h.
    // Backup/settings: every object with a stored writable entry.
    let stored =
        r.dev.0.objects().iter().filter(|o| o.subs().iter().any(|s| s.access.writable())).count() as u16;
    let mut want = vec![0x00, 0x80, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00];
    for n in [all, 2, 2, stored, stored] {
        want.extend_from_slice(&n.to_le_bytes());
    }
    assert_eq!(body(&resp), want);
    assert_eq!(u16::from_le_bytes([resp[0], resp[1]]) - 8, 10);
}

#[test]
fn complete_access_read_at_sub_1() {
    // `SubIndex::Complete` is complete access at sub-index 1: the entries
    // without sub 0; 4 bytes here, so expedited with the CA bit (53h).
    let mut r = rig();
    let cnt = r.counter();
    let resp = r.one(&ethercrab::upload(cnt, 0x1C13, None));
    assert_eq!(body(&resp), [0x00, 0x30, 0x53, 0x13, 0x1C, 0x01, 0x00, 0x1A, 0x01, 0x1A]);
    // And a CA expedited write at sub 1 replaces entries 1..=sub 0.
    let cnt = r.counter();
    let resp = r.one(&ethercrab::download(cnt, 0x1C13, None, &[0x01, 0x1A, 0x00, 0x1A]));
    assert_eq!(body(&resp), [0x00, 0x30, 0x70, 0x13, 0x1C, 0x01, 0, 0, 0, 0]);
    assert_eq!((r.dev.0.get_u64(0x1C13, 1), r.dev.0.get_u64(0x1C13, 2)), (Some(0x1A01), Some(0x1A00)));
}

#[test]
fn emergency_never_answers_a_request() {
    // ethercrab asserts the mailbox read after a request is not an
    // emergency: the SDO answer goes first, the emergency after it.
    let mut r = rig();
    r.server.queue_emergency(0x8210, 0x11, [1, 2, 3, 4, 5]).unwrap();
    let cnt = r.counter();
    r.send(&ethercrab::upload(cnt, 0x1000, Some(0)));
    let first = r.read().unwrap();
    assert_eq!(body(&first)[1] >> 4, 3, "SDO response first");
    let second = r.read().unwrap();
    assert_eq!(body(&second), [0x00, 0x10, 0x10, 0x82, 0x11, 1, 2, 3, 4, 5]);
    assert_eq!((first[5] >> 4, second[5] >> 4), (1, 2), "server counter");
}
