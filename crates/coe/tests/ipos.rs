//! The Technosoft iPOS twin's dictionary over CoE: every object listed,
//! described and read as SOEM and ethercrab do it, and the manual's PDO
//! mapping procedures (§2.4-§2.6, examples E09-E11) against a device that
//! enforces the iPOS rules behind `ObjectAccess` (1C12h/1C13h only in
//! PRE-OP and only while sub-index 0 is 0, §2.3.10/§2.3.11). The rules
//! live in this test device: the CoE server only carries their codes.

mod support;

use drivebus_coe::access_bits::*;
use drivebus_coe::coe::abort;
use drivebus_coe::{AlState, MailboxConfig, NoFiles, ObjectAccess, default_object_access};
use drivebus_od::{Access, DataType, NoHooks, ObjectDictionary, SdoAbort, SubObject, Value};
use support::{Fail, Rig, body, ethercrab, ipos_od, soem};

/// The iPOS as a device: the personality's dictionary plus the EtherCAT
/// PDO rules of the manual.
struct Ipos {
    od: ObjectDictionary,
    esm: AlState,
}

impl Ipos {
    fn new() -> Ipos {
        let mut od = ipos_od();
        // §2.3.10/§2.3.11 and E10/E11 use 1C12h/1C13h sub-indices 1..=4
        // (the personality's EDS lists fewer) and write sub 0 (printed RO).
        for index in [0x1C12u16, 0x1C13] {
            let mut o = od.object(index).unwrap().clone();
            for sub in 1..=4u8 {
                if o.get(sub).is_none() {
                    o = o.with_sub(SubObject::new(
                        sub,
                        "PDO",
                        DataType::Unsigned16,
                        Access::Rw,
                        Value::U16(0),
                    ));
                }
            }
            od.insert(o);
            od.get_mut(index, 0).unwrap().access = Access::Rw;
        }
        // §2.4: a mapping object takes up to 8 entries (the EDS lists only
        // the default ones; E11 maps two objects into 1A03h).
        for index in (0x1600u16..=0x1603).chain(0x1A00..=0x1A03) {
            let mut o = od.object(index).unwrap().clone();
            for sub in 1..=8u8 {
                if o.get(sub).is_none() {
                    o = o.with_sub(SubObject::new(
                        sub,
                        "Mapped object",
                        DataType::Unsigned32,
                        Access::Rw,
                        Value::U32(0),
                    ));
                }
            }
            od.insert(o);
        }
        // §2.3.9: SM3 is process data input (4); the printed default says 3.
        let r = od.find(0x1C00, 4).unwrap();
        od.set_raw(r, &[4]);
        Ipos { od, esm: AlState::PreOp }
    }

    fn is_assign(index: u16) -> bool {
        matches!(index, 0x1C12 | 0x1C13)
    }
    fn is_mapping(index: u16) -> bool {
        matches!(index, 0x1600..=0x1603 | 0x1A00..=0x1A03)
    }

    /// §2.3.10/§2.3.11 and §2.4: assignment and mapping change only in
    /// PRE-OP, entries only while sub 0 is 0, a count only over valid
    /// entries; a PDO carries at most 64 bits (§1.6.3.1).
    fn check(&self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        if self.esm != AlState::PreOp {
            return Err(SdoAbort::DEVICE_STATE);
        }
        let n = self.od.get_u64(index, 0).unwrap_or(0);
        if sub != 0 {
            return if n == 0 { Ok(()) } else { Err(abort::SI0_MUST_BE_ZERO) };
        }
        let count = data.first().copied().unwrap_or(0);
        let mut bits = 0;
        for s in 1..=count {
            let e = self.od.get_u64(index, s).ok_or(SdoAbort::VALUE_TOO_HIGH)?;
            if Self::is_assign(index) {
                let range = if index == 0x1C12 { 0x1600..=0x1603 } else { 0x1A00..=0x1A03 };
                if !range.contains(&e) {
                    return Err(SdoAbort::INVALID_VALUE);
                }
            } else {
                let (i, si) = ((e >> 16) as u16, (e >> 8) as u8);
                let entry = self.od.get(i, si).ok_or(SdoAbort::NO_OBJECT)?;
                if !entry.pdo_mappable || entry.bit_len() != Some(e as u32 & 0xFF) {
                    return Err(SdoAbort::NOT_MAPPABLE);
                }
                bits += e & 0xFF;
            }
        }
        if bits > 64 { Err(SdoAbort::PDO_TOO_LONG) } else { Ok(()) }
    }
}

impl ObjectAccess for Ipos {
    fn dictionary(&self) -> &ObjectDictionary {
        &self.od
    }
    fn read(&mut self, index: u16, sub: u8) -> Result<&[u8], SdoAbort> {
        self.od.read(&mut NoHooks, index, sub)
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        if Self::is_assign(index) || Self::is_mapping(index) {
            self.check(index, sub, data)?;
            let r = self.od.find(index, sub)?;
            return self.od.write_local(&mut NoHooks, r, data);
        }
        self.od.write(&mut NoHooks, index, sub, data)
    }
    fn object_access(&self, index: u16, sub: u8) -> u16 {
        let bits = self.od.get(index, sub).map_or(0, default_object_access);
        if Self::is_assign(index) || Self::is_mapping(index) { (bits & !WRITE) | WRITE_PREOP } else { bits }
    }
}

fn rig(size: usize) -> Rig<Ipos, NoFiles> {
    Rig::new(MailboxConfig::with_sizes(size, size), Ipos::new(), NoFiles)
}

#[test]
fn every_object_listed_described_and_read() {
    let mut r = rig(128);
    let od = r.dev.od.clone();
    let all: Vec<u16> = od.objects().iter().map(|o| o.index).collect();
    assert!(all.len() > 150, "the iPOS has {} objects", all.len());
    // Fragmented through a 128-byte mailbox.
    assert_eq!(soem::od_list(&mut r, 1).unwrap(), all);
    for o in od.objects() {
        let (_, code, max_sub, name) = soem::od_desc(&mut r, o.index).unwrap();
        assert_eq!(name, o.name, "{:04X}", o.index);
        let compound = o.subs().len() > 1 || o.get(0).is_none();
        assert_eq!((code >= 8, max_sub), (compound, if compound { o.subs().last().unwrap().sub } else { 0 }));
        for s in o.subs() {
            let (_, dt, bits, access, name) = soem::oe_desc(&mut r, o.index, s.sub).unwrap();
            assert_eq!((dt, name.as_str()), (s.data_type as u16, &*s.name), "{:04X}:{}", o.index, s.sub);
            if let Some(b) = s.bit_len() {
                assert_eq!(u32::from(bits), b);
            }
            assert_eq!(access & READ != 0, s.access.readable());
            // Every readable entry reads as the CAN side's dictionary holds it.
            let got = soem::sdo_read(&mut r, o.index, s.sub, false);
            if s.access.readable() {
                assert_eq!(got.unwrap(), s.bytes(), "{:04X}:{}", o.index, s.sub);
            } else {
                assert_eq!(got, Err(Fail::Abort(SdoAbort::READ_WRITE_ONLY.0)));
            }
        }
    }
}

#[test]
fn ethercrab_reads_every_readable_entry() {
    // ethercrab 0.7.1 reads expedited (<= 4 bytes) and normal uploads (it
    // cannot decode an upload segment response, command specifier 0). With
    // a 128-byte mailbox every iPOS value is expedited or normal.
    let mut r = rig(128);
    let od = r.dev.od.clone();
    for o in od.objects() {
        for s in o.subs().iter().filter(|s| s.access.readable()) {
            let c = r.counter();
            let m = r.one(&ethercrab::upload(c, o.index, Some(s.sub)));
            let b = body(&m);
            let value = if b[2] & 0x02 != 0 {
                &b[6..6 + 4 - usize::from((b[2] >> 2) & 3)]
            } else {
                let size = u32::from_le_bytes([b[6], b[7], b[8], b[9]]) as usize;
                assert!(size <= usize::from(u16::from_le_bytes([m[0], m[1]])) - 10, "normal, not segmented");
                &b[10..10 + size]
            };
            assert_eq!(value, s.bytes(), "{:04X}:{}", o.index, s.sub);
        }
    }
    // ethercrab reads an OD list exactly when it is one fragment: SM1 of at
    // least 6 + 6 + 2 + 2 × objects bytes.
    let need = 14 + 2 * od.objects().len();
    let mut r = rig(need);
    let c = r.counter();
    r.send(&ethercrab::od_list(c, 1));
    let f = r.read().unwrap();
    assert_eq!(r.read(), None, "one fragment in {need} bytes");
    assert_eq!(ethercrab::parse_od_list(&[f]), od.objects().iter().map(|o| o.index).collect::<Vec<_>>());
}

#[test]
fn soem_sizes_process_data_with_complete_access() {
    // `ecx_readPDOmapCA`: 1C00h by CA, then per SM of type 3/4 the
    // assignment by CA and each mapping object by CA.
    let mut r = rig(128);
    let sm = soem::sdo_read(&mut r, 0x1C00, 0, true).unwrap();
    assert_eq!(sm, [4, 0, 1, 2, 3, 4]);
    let (mut outputs, mut inputs) = (0, 0);
    for (i, t) in sm[2..].iter().enumerate().skip(2) {
        let assign = soem::sdo_read(&mut r, 0x1C10 + i as u16, 0, true).unwrap();
        for pdo in assign[2..].chunks(2).take(usize::from(assign[0])) {
            let map = soem::sdo_read(&mut r, u16::from_le_bytes([pdo[0], pdo[1]]), 0, true).unwrap();
            let bits: u32 = map[2..].chunks(4).take(usize::from(map[0])).map(|e| u32::from(e[0])).sum();
            if *t == 3 { outputs += bits } else { inputs += bits }
        }
    }
    // 1600h: 6040h + 607Ah; 1A00h: 6041h + 6064h + 6077h; 1A01h: 60F4h + 60FDh.
    assert_eq!((outputs, inputs), (48, 128));
}

/// Expedited writes as ethercrab sends them; the answer's command byte.
fn write(r: &mut Rig<Ipos, NoFiles>, index: u16, sub: u8, value: &[u8]) -> Result<(), SdoAbort> {
    let c = r.counter();
    let m = r.one(&ethercrab::download(c, index, Some(sub), value));
    let b = body(&m);
    match b[2] {
        0x60 => Ok(()),
        0x80 => Err(SdoAbort(u32::from_le_bytes([b[6], b[7], b[8], b[9]]))),
        other => panic!("unexpected command {other:02X}"),
    }
}

#[test]
fn rxpdo_mapping_example_e10() {
    let mut r = rig(128);
    // §2.5: RxPDO3 = Controlword + Modes of operation, assigned third.
    write(&mut r, 0x1C12, 0, &[0]).unwrap();
    write(&mut r, 0x1602, 0, &[0]).unwrap();
    write(&mut r, 0x1602, 1, &0x6040_0010u32.to_le_bytes()).unwrap();
    write(&mut r, 0x1602, 2, &0x6060_0008u32.to_le_bytes()).unwrap();
    write(&mut r, 0x1602, 0, &[2]).unwrap();
    // E10 leaves 1C12h:02 as it was; it must name an RxPDO for sub 0 = 3.
    write(&mut r, 0x1C12, 2, &0x1601u16.to_le_bytes()).unwrap();
    write(&mut r, 0x1C12, 3, &0x1602u16.to_le_bytes()).unwrap();
    write(&mut r, 0x1C12, 0, &[3]).unwrap();
    // What ethercrab's discovery then reads, all expedited.
    let mut read = |index: u16, sub: u8| {
        let c = r.counter();
        let m = r.one(&ethercrab::upload(c, index, Some(sub)));
        assert_eq!(body(&m)[2] & 0x03, 0x03, "expedited");
        body(&m)[6..10].to_vec()
    };
    assert_eq!(read(0x1C12, 0)[0], 3);
    assert_eq!(read(0x1C12, 3)[..2], [0x02, 0x16]);
    assert_eq!(read(0x1602, 0)[0], 2);
    assert_eq!(read(0x1602, 2), 0x6060_0008u32.to_le_bytes());
}

#[test]
fn txpdo_mapping_example_e11_and_the_device_rules() {
    let mut r = rig(128);
    // Entries cannot change while sub 0 is not 0: the device's code, unchanged.
    assert_eq!(write(&mut r, 0x1C13, 4, &0x1A03u16.to_le_bytes()), Err(abort::SI0_MUST_BE_ZERO));
    assert_eq!(write(&mut r, 0x1A03, 1, &0x6064_0020u32.to_le_bytes()), Err(abort::SI0_MUST_BE_ZERO));
    // §2.6.
    write(&mut r, 0x1C13, 0, &[0]).unwrap();
    write(&mut r, 0x1A03, 0, &[0]).unwrap();
    write(&mut r, 0x1A03, 1, &0x6064_0020u32.to_le_bytes()).unwrap();
    write(&mut r, 0x1A03, 2, &0x60FD_0020u32.to_le_bytes()).unwrap();
    // 64 bits is the limit (§1.6.3.1).
    write(&mut r, 0x1A03, 3, &0x6041_0010u32.to_le_bytes()).unwrap();
    assert_eq!(write(&mut r, 0x1A03, 0, &[3]), Err(SdoAbort::PDO_TOO_LONG));
    write(&mut r, 0x1A03, 0, &[2]).unwrap();
    write(&mut r, 0x1C13, 3, &0x1A02u16.to_le_bytes()).unwrap();
    write(&mut r, 0x1C13, 4, &0x1A03u16.to_le_bytes()).unwrap();
    write(&mut r, 0x1C13, 0, &[4]).unwrap();
    assert_eq!(r.dev.od.get_u64(0x1C13, 0), Some(4));
    // Outside PRE-OP nothing changes.
    r.dev.esm = AlState::SafeOp;
    r.state = AlState::SafeOp;
    assert_eq!(write(&mut r, 0x1C13, 0, &[0]), Err(SdoAbort::DEVICE_STATE));
}

#[test]
fn complete_access_writes_in_the_order_the_rules_need() {
    let mut r = rig(128);
    // Sub 0 = 0, entries, sub 0 = n: accepted although sub 0 was 2.
    soem::sdo_write(&mut r, 0x1C13, 0, true, &[1, 0, 0x01, 0x1A]).unwrap();
    assert_eq!(soem::sdo_read(&mut r, 0x1C13, 0, true).unwrap(), [1, 0, 0x01, 0x1A]);
    soem::sdo_write(&mut r, 0x1A02, 0, true, &[1, 0, 0x20, 0x00, 0x64, 0x60]).unwrap();
    assert_eq!(r.dev.od.get_u32(0x1A02, 1), Some(0x6064_0020));
    // The device's refusal of the final count ends the transfer with its code.
    assert_eq!(
        soem::sdo_write(&mut r, 0x1C13, 0, true, &[1, 0, 0x00, 0x16]),
        Err(Fail::Abort(SdoAbort::INVALID_VALUE.0))
    );
    r.dev.esm = AlState::Op;
    assert_eq!(
        soem::sdo_write(&mut r, 0x1C13, 0, true, &[1, 0, 0x00, 0x1A]),
        Err(Fail::Abort(SdoAbort::DEVICE_STATE.0))
    );
    // SDO Information says so: the assignment is writable in PRE-OP only.
    let (_, _, _, access, _) = soem::oe_desc(&mut r, 0x1C13, 1).unwrap();
    assert_eq!(access, READ | WRITE_PREOP | BACKUP | SETTINGS);
}
