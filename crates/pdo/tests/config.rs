//! Object layout, defaults and the CiA 301 PDO configuration procedure
//! (7.5.2.35..7.5.2.38) with every abort.
#![allow(missing_docs)]

mod common;
use common::*;
use drivebus_can::{CanId, Frame};
use drivebus_od::{SdoAbort, Value};
use drivebus_pdo::*;

#[test]
fn install_gives_cia301_defaults() {
    let cfg = PdoConfig::new(5);
    let (od, pdo) = setup(&cfg);
    for n in 0..4u16 {
        assert_eq!(od.get_u32(0x1400 + n, 1), Some(0x200 + 0x100 * u32::from(n) + 5));
        assert_eq!(od.get_u32(0x1800 + n, 1), Some(0x180 + 0x100 * u32::from(n) + 5));
        assert_eq!(od.get_u64(0x1400 + n, 2), Some(255));
        assert_eq!(od.get_u64(0x1800 + n, 0), Some(6), "TPDO comm: highest sub 6");
        assert_eq!(od.get_u64(0x1400 + n, 0), Some(5), "RPDO comm: highest sub 5");
        assert_eq!(od.get_u64(0x1600 + n, 0), Some(0));
        assert!(od.get(0x1A00 + n, 64).is_some() && od.get(0x1A00 + n, 65).is_none());
        // Empty mapping: the PDO does not run although its COB-ID is valid.
        assert!(!pdo.is_active(PdoKind::Tpdo, n));
    }
    // Sub 4 is reserved: not implemented → 0609 0011 (CiA 301 v4.2).
    assert_eq!(od.find(0x1800, 4), Err(SdoAbort::NO_SUB_INDEX));
    assert_eq!(od.find(0x1400, 6), Err(SdoAbort::NO_SUB_INDEX));
    // Dummy data type entries 0002h..0007h exist; BOOLEAN is off by default.
    assert_eq!(od.get_u32(0x0005, 0), Some(8));
    assert_eq!(od.get_u32(0x0007, 0), Some(32));
    assert!(od.object(0x0001).is_none());
}

#[test]
fn tpdo_default_cob_id_follows_rtr_support() {
    let mut cfg = PdoConfig::new(3);
    cfg.rtr_supported = false;
    cfg.rpdo_count = 6;
    cfg.tpdo_count = 6;
    let (od, _) = setup(&cfg);
    assert_eq!(od.get_u32(0x1800, 1), Some(0x4000_0183));
    assert_eq!(od.get_u32(0x1805, 1), Some(0xC000_0000));
    assert_eq!(od.get_u32(0x1405, 1), Some(0x8000_0000));
    assert_eq!(od.get_u32(0x1401, 1), Some(0x303));
}

/// 512 RPDOs and 512 TPDOs: every record exists, extended-id PDOs at the
/// top end run.
#[test]
fn five_hundred_twelve_pdos() {
    let mut cfg = PdoConfig::new(1);
    cfg.rpdo_count = 512;
    cfg.tpdo_count = 600; // clamped
    cfg.max_entries = 4;
    let (mut od, mut pdo) = setup(&cfg);
    assert_eq!(pdo.config().tpdo_count, 512);
    for idx in [0x15FF, 0x17FF, 0x19FF, 0x1BFF] {
        assert!(od.object(idx).is_some(), "{idx:04X}");
    }
    assert!(od.object(0x1C00).is_none());
    remap(&mut od, &mut pdo, 0x15FF, 0x2000_1234, 255, &[map_entry(0x2000, 10, 32)]);
    remap(&mut od, &mut pdo, 0x19FF, 0x2000_5678, 1, &[map_entry(0x2000, 10, 32)]);
    let f = Frame::try_new(CanId::Extended(0x1234), &[0xAA, 0xBB, 0xCC, 0xDD]).unwrap();
    assert_eq!(rx(&mut pdo, &mut od, f, ms(0)).0, PdoRx::Handled);
    assert_eq!(od.get_u32(0x2000, 10), Some(0xDDCC_BBAA));
    let out = sync(&mut pdo, &mut od, None, ms(1));
    assert_eq!(out, [Frame::try_new(CanId::Extended(0x5678), &[0xAA, 0xBB, 0xCC, 0xDD]).unwrap()]);
}

/// seed000 KC1 example 1 (§7.3): the free-mapping procedure for TPDO1 of
/// node 1, every request acknowledged; then re-validated it sends 6 bytes.
#[test]
fn kc1_example1_free_mapping_procedure() {
    let cfg = PdoConfig::kollmorgen(1);
    let (mut od, mut pdo) = setup(&cfg);
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0xC000_0181).unwrap();
    sdo8(&mut od, &mut pdo, 0x1A00, 0, 0).unwrap();
    sdo32(&mut od, &mut pdo, 0x1A00, 1, 0x6041_0010).unwrap();
    sdo32(&mut od, &mut pdo, 0x1A00, 2, 0x1002_0020).unwrap();
    sdo8(&mut od, &mut pdo, 0x1A00, 0, 2).unwrap();
    assert!(!pdo.is_active(PdoKind::Tpdo, 0), "as printed TPDO1 stays disabled");
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x4000_0181).unwrap();
    assert_eq!(pdo.mapped_len(PdoKind::Tpdo, 0), Some(6));
    set(&mut od, 0x6041, 0, Value::U16(0x0237));
    set(&mut od, 0x1002, 0, Value::U32(0x1122_3344));
    let (out, _) = poll(&mut pdo, &mut od, ms(0));
    assert_eq!(out, [Frame::new(0x181, &[0x37, 0x02, 0x44, 0x33, 0x22, 0x11])]);
}

#[test]
fn cob_id_rules() {
    let cfg = PdoConfig::new(1);
    let (mut od, mut pdo) = setup(&cfg);
    // Valid → valid with another CAN-ID.
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1800, 1, 0x182), Err(SdoAbort::INVALID_VALUE));
    // Valid → valid switching to 29 bit (bit 29 is part of the id).
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1800, 1, 0x2000_0181), Err(SdoAbort::INVALID_VALUE));
    // Bit 30 may change while valid; rewriting the same value is fine.
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x4000_0181).unwrap();
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x181).unwrap();
    // Invalidate and change the id at once, then revalidate with a new id.
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0190).unwrap();
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x191).unwrap();
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0191).unwrap();
    // Restricted CAN-IDs (CiA 301 Table 36) and malformed 11-bit ids.
    for bad in [0x000, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x6E0, 0x701, 0x7FF, 0x800, 0x1000_0000] {
        assert_eq!(sdo32(&mut od, &mut pdo, 0x1800, 1, bad), Err(SdoAbort::INVALID_VALUE), "{bad:#X}");
    }
    // Restricted ids are fine while the PDO stays invalid, and as 29-bit ids.
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0701).unwrap();
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x2000_0701).unwrap();
    // Wrong size.
    assert_eq!(sdo(&mut od, &mut pdo, 0x1800, 1, &[1, 2]), Err(SdoAbort::DATA_TOO_SHORT));
    // Sub 0 of the communication record is read-only.
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1800, 0, 6), Err(SdoAbort::WRITE_READ_ONLY));
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1800, 4, 0), Err(SdoAbort::NO_SUB_INDEX));
}

#[test]
fn validating_with_unresolvable_mapping_is_refused() {
    let cfg = PdoConfig::new(1);
    let (mut od, mut pdo) = setup(&cfg);
    remap(&mut od, &mut pdo, 0x1400, 0x201, 255, &[map_entry(0x2000, 10, 32)]);
    sdo32(&mut od, &mut pdo, 0x1400, 1, 0x8000_0201).unwrap();
    // The mapped object disappears (e.g. a personality change).
    od.object_mut(0x2000).unwrap().subs_mut()[10].pdo_mappable = false;
    pdo.reload(&od);
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1400, 1, 0x201), Err(SdoAbort::INVALID_VALUE));
}

#[test]
fn transmission_type_rules() {
    let cfg = PdoConfig::new(1);
    let (mut od, mut pdo) = setup(&cfg);
    for t in 241..=251 {
        assert_eq!(sdo8(&mut od, &mut pdo, 0x1800, 2, t), Err(SdoAbort::INVALID_VALUE));
        assert_eq!(sdo8(&mut od, &mut pdo, 0x1400, 2, t), Err(SdoAbort::INVALID_VALUE));
    }
    for t in [252, 253] {
        assert_eq!(sdo8(&mut od, &mut pdo, 0x1400, 2, t), Err(SdoAbort::INVALID_VALUE));
        sdo8(&mut od, &mut pdo, 0x1800, 2, t).unwrap();
    }
    for t in [0, 1, 240, 254, 255] {
        sdo8(&mut od, &mut pdo, 0x1400, 2, t).unwrap();
        sdo8(&mut od, &mut pdo, 0x1800, 2, t).unwrap();
    }
    let mut cfg = PdoConfig::new(1);
    cfg.rtr_supported = false;
    let (mut od, mut pdo) = setup(&cfg);
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1800, 2, 252), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1800, 2, 253), Err(SdoAbort::INVALID_VALUE));
    // Without RTR support bit 30 must stay set on TPDOs (CiA 301 7.5.2.37).
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1800, 1, 0x181), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0181), Err(SdoAbort::INVALID_VALUE));
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0xC000_0181).unwrap();
    sdo32(&mut od, &mut pdo, 0x1400, 1, 0x8000_0201).unwrap(); // RPDO: bit 30 ignored
    // Drives that ignore the bit (KC1/AKD) accept it and still never answer RTR.
    let cfg = PdoConfig::kollmorgen(1);
    let (mut od, mut pdo) = setup(&cfg);
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0181).unwrap();
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x181).unwrap();
}

#[test]
fn inhibit_and_sync_start_only_while_invalid() {
    let cfg = PdoConfig::new(1);
    let (mut od, mut pdo) = setup(&cfg);
    assert_eq!(sdo16(&mut od, &mut pdo, 0x1800, 3, 10), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1800, 6, 3), Err(SdoAbort::INVALID_VALUE));
    sdo16(&mut od, &mut pdo, 0x1800, 3, 0).unwrap(); // unchanged value
    sdo16(&mut od, &mut pdo, 0x1800, 5, 100).unwrap(); // event timer: any time
    sdo16(&mut od, &mut pdo, 0x1400, 3, 7).unwrap(); // RPDO sub 3: stored, unused
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0181).unwrap();
    sdo16(&mut od, &mut pdo, 0x1800, 3, 10).unwrap();
    sdo8(&mut od, &mut pdo, 0x1800, 6, 3).unwrap();
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1800, 6, 241), Err(SdoAbort::VALUE_TOO_HIGH));
    assert_eq!(pdo.check_write(&od, 0x1800, 6, &[241]), Err(SdoAbort::VALUE_TOO_HIGH));
}

#[test]
fn mapping_procedure_aborts() {
    let cfg = PdoConfig::new(1);
    let (mut od, mut pdo) = setup(&cfg);
    let e = map_entry(0x2000, 4, 16);
    // PDO valid (bit 31 clear): neither sub 0 nor entries may change;
    // writing back the value held changes nothing and is taken.
    let held = od.get_u64(0x1A00, 0).unwrap() as u8;
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1A00, 0, held + 1), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1A00, 1, e), Err(SdoAbort::INVALID_VALUE));
    sdo8(&mut od, &mut pdo, 0x1A00, 0, held).unwrap();
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0181).unwrap();
    sdo32(&mut od, &mut pdo, 0x1A00, 1, e).unwrap();
    sdo8(&mut od, &mut pdo, 0x1A00, 0, 1).unwrap();
    // Sub 0 ≠ 0: entries are locked.
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1A00, 2, e), Err(SdoAbort::INVALID_VALUE));
    sdo8(&mut od, &mut pdo, 0x1A00, 0, 0).unwrap();
    let cases = [
        (map_entry(0x3000, 0, 8), SdoAbort::NO_OBJECT),
        (map_entry(0x2000, 11, 8), SdoAbort::NO_OBJECT),
        (map_entry(0x2000, 7, 8), SdoAbort::NOT_MAPPABLE), // not mappable
        (map_entry(0x2000, 6, 8), SdoAbort::NOT_MAPPABLE), // variable size
        (map_entry(0x2000, 4, 8), SdoAbort::NOT_MAPPABLE), // wrong length
        (map_entry(0x2000, 4, 0), SdoAbort::NOT_MAPPABLE), // zero length
        (map_entry(0x1000, 0, 32), SdoAbort::NOT_MAPPABLE), // not mappable
        (map_entry(0x0001, 0, 1), SdoAbort::NOT_MAPPABLE), // BOOLEAN dummy unsupported
        (map_entry(0x0005, 1, 8), SdoAbort::NOT_MAPPABLE), // dummy sub ≠ 0
        (map_entry(0x0005, 0, 16), SdoAbort::NOT_MAPPABLE), // dummy length
        (map_entry(0x0009, 0, 8), SdoAbort::NOT_MAPPABLE), // not a usable dummy type
    ];
    for (entry, abort) in cases {
        assert_eq!(sdo32(&mut od, &mut pdo, 0x1A00, 1, entry), Err(abort), "{entry:08X}");
    }
    sdo32(&mut od, &mut pdo, 0x1A00, 1, map_entry(0x2000, 5, 64)).unwrap();
    // A u64 alone fits 8 bytes; with another entry it does not: 0604 0042 at sub 0.
    sdo32(&mut od, &mut pdo, 0x1A00, 2, map_entry(0x2000, 3, 8)).unwrap();
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1A00, 0, 2), Err(SdoAbort::PDO_TOO_LONG));
    // Direction: a read-only object cannot go into an RPDO.
    sdo32(&mut od, &mut pdo, 0x1400, 1, 0x8000_0201).unwrap();
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1600, 1, map_entry(0x6041, 0, 16)), Err(SdoAbort::NOT_MAPPABLE));
    // Sub 0 above the maximum number of entries.
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1600, 0, 65), Err(SdoAbort::VALUE_TOO_HIGH));
    assert_eq!(pdo.check_write(&od, 0x1600, 0, &[65]), Err(SdoAbort::VALUE_TOO_HIGH));
    // Sub 0 = n validates entries 1..n again (entry 1 is still 0).
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1600, 0, 1), Err(SdoAbort::NOT_MAPPABLE));
    // Writes that are not PDO objects pass.
    assert_eq!(pdo.check_write(&od, 0x6040, 0, &[0, 0]), Ok(()));
}

#[test]
fn byte_granularity_and_max_entries() {
    let mut cfg = PdoConfig::kollmorgen(1);
    cfg.max_len = 4;
    let (mut od, mut pdo) = setup(&cfg);
    sdo32(&mut od, &mut pdo, 0x1400, 1, 0x8000_0201).unwrap();
    // BOOLEAN takes a whole byte; one bit is refused.
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1600, 1, map_entry(0x2000, 1, 1)), Err(SdoAbort::NOT_MAPPABLE));
    sdo32(&mut od, &mut pdo, 0x1600, 1, map_entry(0x2000, 1, 8)).unwrap();
    // Only 8 entries exist.
    assert_eq!(od.find(0x1600, 9), Err(SdoAbort::NO_SUB_INDEX));
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1600, 0, 9), Err(SdoAbort::VALUE_TOO_HIGH));
    // Max PDO length 4 bytes: a single u64 entry is too long.
    assert_eq!(sdo32(&mut od, &mut pdo, 0x1600, 2, map_entry(0x2000, 5, 64)), Err(SdoAbort::PDO_TOO_LONG));
    for i in 2..=4 {
        sdo32(&mut od, &mut pdo, 0x1600, i, map_entry(0x2000, 3, 8)).unwrap();
    }
    sdo32(&mut od, &mut pdo, 0x1600, 5, map_entry(0x2000, 3, 8)).unwrap();
    sdo8(&mut od, &mut pdo, 0x1600, 0, 4).unwrap();
    sdo8(&mut od, &mut pdo, 0x1600, 0, 0).unwrap();
    assert_eq!(sdo8(&mut od, &mut pdo, 0x1600, 0, 5), Err(SdoAbort::PDO_TOO_LONG));
}

/// Personality defaults are values and defaults: a 1011h-style restore
/// brings them back.
#[test]
fn custom_defaults_survive_restore() {
    let cfg = PdoConfig::new(1);
    let (mut od, _) = setup(&cfg);
    let entries = [map_entry(0x6041, 0, 16), map_entry(0x6064, 0, 32)];
    let mut d = PdoDefaults::new(&entries);
    d.transmission_type = 1;
    set_defaults(&mut od, &cfg, PdoKind::Tpdo, 1, &d).unwrap();
    let bad = [map_entry(0x6041, 0, 8)];
    assert_eq!(
        set_defaults(&mut od, &cfg, PdoKind::Tpdo, 1, &PdoDefaults::new(&bad)),
        Err(SdoAbort::NOT_MAPPABLE)
    );
    let mut pdo = Pdo::new(&cfg, &od);
    assert_eq!(pdo.mapped_len(PdoKind::Tpdo, 1), Some(6));
    remap(&mut od, &mut pdo, 0x1801, 0x281, 255, &[map_entry(0x6041, 0, 16)]);
    assert_eq!(pdo.mapped_len(PdoKind::Tpdo, 1), Some(2));
    od.restore_defaults(|i, s| (0x1400..0x1C00).contains(&i) && s.access.writable());
    pdo.reload(&od);
    assert_eq!(od.get_u64(0x1801, 2), Some(1));
    assert_eq!(od.get_u32(0x1A01, 2), Some(0x6064_0020));
    assert_eq!(pdo.mapped_len(PdoKind::Tpdo, 1), Some(6));
}

/// DDS6-EX6 (seed004): remap RPDO4/TPDO4 of node 0Dh with the transmission
/// type set while invalid; then the PDO frames of the example.
#[test]
fn dds6_ex6_remap_and_frames() {
    let cfg = PdoConfig::new(0x0D);
    let (mut od, mut pdo) = setup(&cfg);
    let w = [
        (0x1800, 1, 0x8000_018Du32, 4),
        (0x1403, 1, 0x8000_050D, 4),
        (0x1403, 2, 0xFF, 1),
        (0x1603, 0, 0, 1),
        (0x1603, 1, 0x6040_0010, 4),
        (0x1603, 2, 0x6071_0010, 4),
        (0x1603, 0, 2, 1),
        (0x1403, 1, 0x0000_050D, 4),
        (0x1803, 1, 0x8000_048D, 4),
        (0x1803, 2, 0xFF, 1),
        (0x1A03, 0, 0, 1),
        (0x1A03, 1, 0x6041_0010, 4),
        (0x1A03, 2, 0x6077_0010, 4),
        (0x1A03, 0, 2, 1),
        (0x1803, 1, 0x0000_048D, 4),
    ];
    for (i, s, v, n) in w {
        sdo(&mut od, &mut pdo, i, s, &v.to_le_bytes()[..n]).unwrap();
    }
    // Frame 40: after NMT start the event-driven TPDO4 sends SW 0250h.
    set(&mut od, 0x6041, 0, Value::U16(0x0250));
    pdo.reset();
    let (out, _) = poll(&mut pdo, &mut od, ms(113));
    assert!(out.contains(&Frame::new(0x48D, &[0x50, 0x02, 0x00, 0x00])));
    // Frame 46: RPDO4 CW=000Fh, target torque 200.
    let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x50D, &[0x0F, 0x00, 0xC8, 0x00]), ms(638));
    assert_eq!(r, PdoRx::Handled);
    assert_eq!(od.get_u64(0x6040, 0), Some(0x000F));
    assert_eq!(od.get_i64(0x6071, 0), Some(200));
    // Frame 48: SW 0637h, torque 200 → TPDO4 on change of state.
    set(&mut od, 0x6041, 0, Value::U16(0x0637));
    set(&mut od, 0x6077, 0, Value::I16(200));
    let (out, _) = poll(&mut pdo, &mut od, ms(1039));
    assert_eq!(out, [Frame::new(0x48D, &[0x37, 0x06, 0xC8, 0x00])]);
}

#[test]
fn node_id_change_moves_predefined_cob_ids() {
    let cfg = PdoConfig::new(3);
    let (mut od, mut pdo) = setup(&cfg);
    sdo32(&mut od, &mut pdo, 0x1801, 1, 0xC000_0283).unwrap(); // disabled by the master
    sdo32(&mut od, &mut pdo, 0x1802, 1, 0x8000_0390).unwrap(); // own id
    let cfg = PdoConfig::new(0x0D);
    update_node_id(&mut od, &cfg, 3);
    pdo.reload(&od);
    assert_eq!(od.get_u32(0x1400, 1), Some(0x20D));
    assert_eq!(od.get_u32(0x1800, 1), Some(0x18D));
    assert_eq!(od.get_u32(0x1801, 1), Some(0xC000_028D));
    assert_eq!(od.get_u32(0x1802, 1), Some(0x8000_0390));
    assert_eq!(od.get(0x1802, 1).unwrap().default, 0x38Du32.to_le_bytes());
}
