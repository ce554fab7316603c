//! Frame-exact runtime behaviour: transmission types, timers, RTR, length
//! errors, deadline monitoring, packing (CiA 301 7.2.2).
#![allow(missing_docs)]

mod common;
use common::*;
use drivebus_can::{CanId, Frame};
use drivebus_od::{ObjectDictionary, ObjectHooks, SdoAbort, Target, Value, WriteOutcome};
use drivebus_pdo::*;
use proptest::strategy::Strategy;

fn node3() -> (ObjectDictionary, Pdo) {
    setup(&PdoConfig::new(3))
}

/// seed000 KC1 example 7 (§8.2.1.6, torque mode via PDO): RPDO1 = 6071h,
/// TPDO1 = 6077h type 1. `203 12 02` sets 530, SYNC gives `183 19 02`.
#[test]
fn kc1_example7_torque_via_pdo() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1400, 0x203, 255, &[0x6071_0010]);
    remap(&mut od, &mut pdo, 0x1800, 0x183, 1, &[0x6077_0010]);
    let (r, out) = rx(&mut pdo, &mut od, Frame::new(0x203, &[0x12, 0x02]), ms(5260));
    assert_eq!((r, out.len()), (PdoRx::Handled, 0));
    assert_eq!(od.get_i64(0x6071, 0), Some(530));
    set(&mut od, 0x6077, 0, Value::I16(537));
    assert_eq!(sync(&mut pdo, &mut od, None, ms(5266)), [Frame::new(0x183, &[0x19, 0x02])]);
}

/// seed000 KC1 example 6 / seed001 AKD example 6 (jog mode via PDO):
/// TPDO1 = 6064h + 606Ch type 1 → `183 FE 45 01 00 A6 AB 1A 00`. The KC1
/// print of RPDO1 `203 00 40` is 2 bytes for a 32-bit mapping: a length
/// error; the AKD print `203 00 40 00 00` is applied.
#[test]
fn kc1_akd_example6_jog_via_pdo() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1400, 0x203, 255, &[0x60FF_0020]);
    remap(&mut od, &mut pdo, 0x1800, 0x183, 1, &[0x6064_0020, 0x606C_0020]);
    let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x203, &[0x00, 0x40]), ms(0));
    assert_eq!(r, PdoRx::Event(PdoEvent::RpdoLengthError { rpdo: 0, len: 2 }));
    assert_eq!(PdoEvent::RpdoLengthError { rpdo: 0, len: 2 }.emcy_code(), Some(0x8210));
    assert_eq!(od.get_i64(0x60FF, 0), Some(0));
    let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x203, &[0x00, 0x40, 0x00, 0x00]), ms(1));
    assert_eq!(r, PdoRx::Handled);
    assert_eq!(od.get_i64(0x60FF, 0), Some(16384));
    set(&mut od, 0x6064, 0, Value::I32(0x0001_45FE));
    set(&mut od, 0x606C, 0, Value::I32(0x001A_ABA6));
    assert_eq!(
        sync(&mut pdo, &mut od, None, ms(2)),
        [Frame::new(0x183, &[0xFE, 0x45, 0x01, 0x00, 0xA6, 0xAB, 0x1A, 0x00])]
    );
}

/// DDS6-EX2 (seed004) frames 21/23: RPDO2 printed with 7 bytes for a 6-byte
/// mapping: processed, with a length-exceeded event (EMCY 8220h).
#[test]
fn dds6_ex2_rpdo_longer_than_mapping() {
    let (mut od, mut pdo) = setup(&PdoConfig::new(0x0D));
    remap(&mut od, &mut pdo, 0x1401, 0x30D, 255, &[0x6040_0010, 0x607A_0020]);
    let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x30D, &[0x06, 0, 0, 0, 0, 0, 0]), ms(41));
    assert_eq!(r, PdoRx::Event(PdoEvent::RpdoLengthExceeded { rpdo: 1, len: 7 }));
    assert_eq!(od.get_u64(0x6040, 0), Some(6));
    // Frame 31: CW=005Fh, target -60000.
    let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x30D, &[0x5F, 0x00, 0xA0, 0x15, 0xFF, 0xFF]), ms(1767));
    assert_eq!(r, PdoRx::Handled);
    assert_eq!(od.get_i64(0x607A, 0), Some(-60000));
}

#[test]
fn sync_rpdo_is_applied_at_next_sync_not_before() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1400, 0x203, 1, &[0x6040_0010]);
    rx(&mut pdo, &mut od, Frame::new(0x203, &[0x06, 0x00]), ms(0));
    rx(&mut pdo, &mut od, Frame::new(0x203, &[0x0F, 0x00]), ms(1));
    assert_eq!(od.get_u64(0x6040, 0), Some(0));
    let _ = poll(&mut pdo, &mut od, ms(2));
    assert_eq!(od.get_u64(0x6040, 0), Some(0));
    sync(&mut pdo, &mut od, None, ms(3));
    assert_eq!(od.get_u64(0x6040, 0), Some(0x0F), "last frame before the SYNC wins");
    // Reset drops latched data.
    rx(&mut pdo, &mut od, Frame::new(0x203, &[0x07, 0x00]), ms(4));
    pdo.reset();
    sync(&mut pdo, &mut od, None, ms(5));
    assert_eq!(od.get_u64(0x6040, 0), Some(0x0F));
}

/// At a SYNC the synchronous TPDOs are sampled before the SYNC's RPDO data
/// takes effect: a TPDO mapping the very object the RPDO writes reports
/// the value in force up to the SYNC (DDS6-EX9, seed004 §4.4.5: the
/// controlword sent after SYNC n shows in the TPDO of SYNC n + 2).
#[test]
fn sync_tpdo_is_sampled_before_the_sync_rpdo_applies() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1400, 0x203, 1, &[0x6040_0010]);
    remap(&mut od, &mut pdo, 0x1800, 0x183, 1, &[0x6040_0010]);
    rx(&mut pdo, &mut od, Frame::new(0x203, &[0x06, 0x00]), ms(1));
    assert_eq!(sync(&mut pdo, &mut od, None, ms(2)), [Frame::new(0x183, &[0x00, 0x00])]);
    assert_eq!(od.get_u64(0x6040, 0), Some(6), "applied at that SYNC");
    assert_eq!(sync(&mut pdo, &mut od, None, ms(3)), [Frame::new(0x183, &[0x06, 0x00])]);
}

#[test]
fn cyclic_sync_every_nth() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1800, 0x183, 3, &[0x6041_0010]);
    let sent: Vec<usize> = (1..=9).map(|i| sync(&mut pdo, &mut od, None, ms(i)).len()).collect();
    assert_eq!(sent, [0, 0, 1, 0, 0, 1, 0, 0, 1]);
}

#[test]
fn sync_start_value() {
    let (mut od, mut pdo) = node3();
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0183).unwrap();
    sdo8(&mut od, &mut pdo, 0x1800, 6, 3).unwrap();
    remap(&mut od, &mut pdo, 0x1800, 0x183, 2, &[0x6041_0010]);
    let sent: Vec<usize> =
        (1..=8).map(|c| sync(&mut pdo, &mut od, Some(c), ms(u64::from(c))).len()).collect();
    // First at the SYNC with counter 3, then every 2nd SYNC.
    assert_eq!(sent, [0, 0, 1, 0, 1, 0, 1, 0]);
    // A SYNC without counter ignores the start value.
    pdo.reset();
    let sent: Vec<usize> = (1..=4).map(|i| sync(&mut pdo, &mut od, None, ms(i)).len()).collect();
    assert_eq!(sent, [0, 1, 0, 1]);
}

#[test]
fn acyclic_sync_type0() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1800, 0x183, 0, &[0x6041_0010]);
    assert_eq!(
        sync(&mut pdo, &mut od, None, ms(1)),
        [Frame::new(0x183, &[0, 0])],
        "first SYNC: no last data"
    );
    assert!(sync(&mut pdo, &mut od, None, ms(2)).is_empty());
    set(&mut od, 0x6041, 0, Value::U16(0x0237));
    let _ = poll(&mut pdo, &mut od, ms(3)); // poll does not send synchronous TPDOs
    assert_eq!(sync(&mut pdo, &mut od, None, ms(4)), [Frame::new(0x183, &[0x37, 0x02])]);
    assert!(sync(&mut pdo, &mut od, None, ms(5)).is_empty());
    assert!(pdo.request_tpdo(0));
    assert_eq!(sync(&mut pdo, &mut od, None, ms(6)), [Frame::new(0x183, &[0x37, 0x02])]);
    assert!(!pdo.request_tpdo(3), "TPDO4 has no mapping");
}

/// 252: data updated at each SYNC, sent on RTR (CiA 301 Table 71).
#[test]
fn rtr_type_252_sends_data_of_last_sync() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1800, 0x183, 252, &[0x6041_0010]);
    // RTR before any SYNC: answered at the next SYNC with the data sampled there.
    let (r, out) = rx(&mut pdo, &mut od, Frame::remote(0x183, 2), ms(0));
    assert_eq!((r, out.len()), (PdoRx::Handled, 0));
    set(&mut od, 0x6041, 0, Value::U16(7));
    assert_eq!(sync(&mut pdo, &mut od, None, ms(1)), [Frame::new(0x183, &[7, 0])]);
    assert!(sync(&mut pdo, &mut od, None, ms(2)).is_empty(), "no RTR, no frame");
    set(&mut od, 0x6041, 0, Value::U16(1));
    let (_, out) = rx(&mut pdo, &mut od, Frame::remote(0x183, 2), ms(3));
    assert_eq!(out, [Frame::new(0x183, &[7, 0])], "sampled at the SYNC, not now");
    sync(&mut pdo, &mut od, None, ms(4));
    set(&mut od, 0x6041, 0, Value::U16(2));
    let (_, out) = rx(&mut pdo, &mut od, Frame::remote(0x183, 2), ms(5));
    assert_eq!(out, [Frame::new(0x183, &[1, 0])]);
}

#[test]
fn rtr_type_253_and_event_types() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1800, 0x183, 253, &[0x6041_0010]);
    set(&mut od, 0x6041, 0, Value::U16(0x1234));
    assert!(poll(&mut pdo, &mut od, ms(0)).0.is_empty(), "253 is RTR-only");
    assert!(sync(&mut pdo, &mut od, None, ms(0)).is_empty());
    let (_, out) = rx(&mut pdo, &mut od, Frame::remote(0x183, 2), ms(1));
    assert_eq!(out, [Frame::new(0x183, &[0x34, 0x12])]);
    // Event-driven with inhibit 1 ms: RTR is answered at once, a second one
    // inside the inhibit time when it ends.
    sdo32(&mut od, &mut pdo, 0x1801, 1, 0x8000_0283).unwrap();
    sdo16(&mut od, &mut pdo, 0x1801, 3, 10).unwrap();
    remap(&mut od, &mut pdo, 0x1801, 0x283, 254, &[0x6041_0010]);
    let (_, out) = rx(&mut pdo, &mut od, Frame::remote(0x283, 2), us(10_000));
    assert_eq!(out, [Frame::new(0x283, &[0x34, 0x12])]);
    let (_, out) = rx(&mut pdo, &mut od, Frame::remote(0x283, 2), us(10_500));
    assert!(out.is_empty());
    let (out, next) = poll(&mut pdo, &mut od, us(10_600));
    assert_eq!((out.len(), next), (0, Some(us(11_000))));
    let (out, _) = poll(&mut pdo, &mut od, us(11_000));
    assert_eq!(out, [Frame::new(0x283, &[0x34, 0x12])]);
}

#[test]
fn rtr_refused_when_not_allowed() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1800, 0x4000_0183, 253, &[0x6041_0010]);
    let (r, out) = rx(&mut pdo, &mut od, Frame::remote(0x183, 2), ms(1));
    assert_eq!((r, out.len()), (PdoRx::NotPdo, 0));
    let mut cfg = PdoConfig::new(3);
    cfg.rtr_supported = false;
    let (mut od, mut pdo) = setup(&cfg);
    remap(&mut od, &mut pdo, 0x1800, 0x4000_0183, 255, &[0x6041_0010]);
    let (r, out) = rx(&mut pdo, &mut od, Frame::remote(0x183, 2), ms(1));
    assert_eq!((r, out.len()), (PdoRx::NotPdo, 0));
    // An RTR on an RPDO id is not a PDO request either.
    remap(&mut od, &mut pdo, 0x1400, 0x203, 255, &[0x6040_0010]);
    assert_eq!(rx(&mut pdo, &mut od, Frame::remote(0x203, 2), ms(2)).0, PdoRx::NotPdo);
}

#[test]
fn event_timer_and_change_of_state() {
    let (mut od, mut pdo) = node3();
    sdo16(&mut od, &mut pdo, 0x1800, 5, 100).unwrap();
    remap(&mut od, &mut pdo, 0x1800, 0x183, 255, &[0x6041_0010]);
    let (out, next) = poll(&mut pdo, &mut od, ms(0));
    assert_eq!((out, next), (vec![Frame::new(0x183, &[0, 0])], Some(ms(100))));
    // Nothing changed: polling early is not observable.
    assert_eq!(poll(&mut pdo, &mut od, ms(50)), (vec![], Some(ms(100))));
    assert_eq!(poll(&mut pdo, &mut od, ms(100)), (vec![Frame::new(0x183, &[0, 0])], Some(ms(200))));
    // A change restarts the event timer.
    set(&mut od, 0x6041, 0, Value::U16(0x0250));
    assert_eq!(poll(&mut pdo, &mut od, ms(130)), (vec![Frame::new(0x183, &[0x50, 0x02])], Some(ms(230))));
    // A write of the same value is not a change.
    set(&mut od, 0x6041, 0, Value::U16(0x0250));
    od.set_value(0x1002, 0, &Value::U32(9)).unwrap();
    assert_eq!(poll(&mut pdo, &mut od, ms(131)), (vec![], Some(ms(230))));
}

#[test]
fn inhibit_time_delays_changes() {
    let (mut od, mut pdo) = node3();
    sdo32(&mut od, &mut pdo, 0x1800, 1, 0x8000_0183).unwrap();
    sdo16(&mut od, &mut pdo, 0x1800, 3, 50).unwrap(); // 5 ms
    remap(&mut od, &mut pdo, 0x1800, 0x183, 254, &[0x6041_0010]);
    assert_eq!(poll(&mut pdo, &mut od, ms(10)).0.len(), 1);
    set(&mut od, 0x6041, 0, Value::U16(1));
    assert_eq!(poll(&mut pdo, &mut od, ms(11)), (vec![], Some(ms(15))));
    set(&mut od, 0x6041, 0, Value::U16(2));
    assert_eq!(poll(&mut pdo, &mut od, ms(14)), (vec![], Some(ms(15))));
    // The latest value goes out when the inhibit time ends.
    assert_eq!(poll(&mut pdo, &mut od, ms(15)), (vec![Frame::new(0x183, &[2, 0])], None));
    assert_eq!(poll(&mut pdo, &mut od, ms(30)), (vec![], None));
    // An application event is rate-limited the same way.
    assert!(pdo.request_tpdo(0));
    assert_eq!(poll(&mut pdo, &mut od, ms(31)).0, [Frame::new(0x183, &[2, 0])]);
    assert!(pdo.request_tpdo(0));
    assert_eq!(poll(&mut pdo, &mut od, ms(32)), (vec![], Some(ms(36))));
}

#[test]
fn rpdo_deadline_monitoring() {
    let (mut od, mut pdo) = node3();
    sdo16(&mut od, &mut pdo, 0x1400, 5, 50).unwrap();
    remap(&mut od, &mut pdo, 0x1400, 0x203, 255, &[0x6040_0010]);
    // Monitoring starts with the first reception.
    assert_eq!(poll(&mut pdo, &mut od, ms(1000)), (vec![], None));
    rx(&mut pdo, &mut od, Frame::new(0x203, &[1, 0]), ms(1000));
    assert_eq!(poll(&mut pdo, &mut od, ms(1049)).1, Some(ms(1050)));
    rx(&mut pdo, &mut od, Frame::new(0x203, &[1, 0]), ms(1040));
    assert_eq!(poll(&mut pdo, &mut od, ms(1050)).1, Some(ms(1090)));
    assert!(events(&mut pdo).is_empty());
    assert_eq!(poll(&mut pdo, &mut od, ms(1090)).1, None);
    assert_eq!(events(&mut pdo), [PdoEvent::RpdoTimeout { rpdo: 0 }]);
    assert_eq!(PdoEvent::RpdoTimeout { rpdo: 0 }.emcy_code(), Some(0x8250));
    let _ = poll(&mut pdo, &mut od, ms(2000));
    assert!(events(&mut pdo).is_empty(), "raised once");
    // A short frame does not re-arm; a good one does and reports recovery.
    let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x203, &[1]), ms(2001));
    assert_eq!(r, PdoRx::Event(PdoEvent::RpdoLengthError { rpdo: 0, len: 1 }));
    let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x203, &[1, 0]), ms(2002));
    assert_eq!(r, PdoRx::Event(PdoEvent::RpdoResumed { rpdo: 0 }));
    assert_eq!(poll(&mut pdo, &mut od, ms(2003)).1, Some(ms(2052)));
}

/// Bit-granular packing: two BOOLEANs (1 bit each), an u16 and an u8 at
/// bit offsets 0, 1, 2 and 18 (4 bytes), both directions; plus dummies.
#[test]
fn bit_granular_mapping_and_dummies() {
    let mut cfg = PdoConfig::new(3);
    cfg.dummy_types |= 1 << 1; // BOOLEAN dummy
    let (mut od, mut pdo) = setup(&cfg);
    let layout =
        [map_entry(0x2000, 1, 1), map_entry(0x2000, 2, 1), map_entry(0x2000, 4, 16), map_entry(0x2000, 3, 8)];
    remap(&mut od, &mut pdo, 0x1400, 0x203, 255, &layout);
    remap(&mut od, &mut pdo, 0x1800, 0x183, 1, &layout);
    assert_eq!(pdo.mapped_len(PdoKind::Rpdo, 0), Some(4));
    // 1 | 0<<1 | 0xBEEF<<2 | 0xA5<<18 = 0x0296_FBBD
    let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x203, &[0xBD, 0xFB, 0x96, 0x02]), ms(0));
    assert_eq!(r, PdoRx::Handled);
    assert_eq!(od.get_value(0x2000, 1), Some(Value::Bool(true)));
    assert_eq!(od.get_value(0x2000, 2), Some(Value::Bool(false)));
    assert_eq!(od.get_u64(0x2000, 4), Some(0xBEEF));
    assert_eq!(od.get_u64(0x2000, 3), Some(0xA5));
    assert_eq!(sync(&mut pdo, &mut od, None, ms(1)), [Frame::new(0x183, &[0xBD, 0xFB, 0x96, 0x02])]);
    // Dummies: skip a BOOLEAN bit and a whole UNSIGNED8 (0005h).
    let dummies =
        [map_entry(0x0001, 0, 1), map_entry(0x2000, 2, 1), map_entry(0x0005, 0, 8), map_entry(0x2000, 3, 8)];
    remap(&mut od, &mut pdo, 0x1400, 0x203, 255, &dummies);
    rx(&mut pdo, &mut od, Frame::new(0x203, &[0xFF, 0x47, 0x00]), ms(2));
    assert_eq!(od.get_value(0x2000, 2), Some(Value::Bool(true)));
    assert_eq!(od.get_u64(0x2000, 3), Some(0x11));
    // In a TPDO a dummy sends zeros (byte-aligned fast path).
    remap(&mut od, &mut pdo, 0x1800, 0x183, 1, &[map_entry(0x0005, 0, 8), map_entry(0x2000, 3, 8)]);
    assert_eq!(sync(&mut pdo, &mut od, None, ms(3)), [Frame::new(0x183, &[0x00, 0x11])]);
}

/// seed000 KC1 example "common RPDO for two axes" (§8.2.2.1): each axis
/// maps the other half of RPDO2 (301h) to the manufacturer dummy 2100h.
#[test]
fn kc1_shared_rpdo_with_manufacturer_dummy() {
    let (mut od1, mut p1) = setup(&PdoConfig::kollmorgen(1));
    let (mut od2, mut p2) = setup(&PdoConfig::kollmorgen(2));
    remap(&mut od1, &mut p1, 0x1401, 0x301, 1, &[0x607A_0020, 0x2100_0020]);
    remap(&mut od2, &mut p2, 0x1401, 0x301, 1, &[0x2100_0020, 0x607A_0020]);
    let f = Frame::new(0x301, &[0x10, 0x27, 0, 0, 0x20, 0x4E, 0, 0]);
    rx(&mut p1, &mut od1, f, ms(0));
    rx(&mut p2, &mut od2, f, ms(0));
    sync(&mut p1, &mut od1, None, ms(1));
    sync(&mut p2, &mut od2, None, ms(1));
    assert_eq!(od1.get_i64(0x607A, 0), Some(10000));
    assert_eq!(od2.get_i64(0x607A, 0), Some(20000));
}

struct AppHooks {
    live: u16,
}
impl ObjectHooks for AppHooks {
    fn on_read(&mut self, od: &mut ObjectDictionary, at: &Target) -> Result<(), SdoAbort> {
        if self.live == 0xDEAD {
            return Err(SdoAbort::HARDWARE_ERROR);
        }
        od.set_raw(at.r, &self.live.to_le_bytes());
        Ok(())
    }
    fn check_write(
        &mut self,
        _: &mut ObjectDictionary,
        _: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        if data == [0xFF, 0xFF] { Err(SdoAbort::DEVICE_STATE) } else { Ok(WriteOutcome::Store) }
    }
}

#[test]
fn hooks_and_limits_on_the_frame_path() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1400, 0x203, 255, &[map_entry(0x2000, 8, 16), map_entry(0x2000, 9, 8)]);
    remap(&mut od, &mut pdo, 0x1800, 0x183, 1, &[map_entry(0x2000, 8, 16)]);
    let mut h = AppHooks { live: 0x4321 };
    let mut out = Vec::new();
    let f = Frame::new(0x203, &[0xFF, 0xFF, 101]);
    assert_eq!(pdo.handle_frame(&f, ms(0), &mut od, &mut h, &mut out), PdoRx::Handled);
    assert_eq!(
        events(&mut pdo),
        [
            PdoEvent::RpdoWriteFailed { rpdo: 0, index: 0x2000, sub: 8, abort: SdoAbort::DEVICE_STATE },
            PdoEvent::RpdoWriteFailed { rpdo: 0, index: 0x2000, sub: 9, abort: SdoAbort::VALUE_TOO_HIGH },
        ]
    );
    let f = Frame::new(0x203, &[0x01, 0x02, 100]);
    pdo.handle_frame(&f, ms(1), &mut od, &mut h, &mut out);
    assert_eq!((od.get_u64(0x2000, 8), od.get_u64(0x2000, 9)), (Some(0x0201), Some(100)));
    // TPDO sampling calls the read hook: the live value goes out.
    pdo.on_sync(None, ms(2), &mut od, &mut h, &mut out);
    assert_eq!(out, [Frame::new(0x183, &[0x21, 0x43])]);
    h.live = 0xDEAD;
    out.clear();
    pdo.on_sync(None, ms(3), &mut od, &mut h, &mut out);
    assert_eq!(out, [Frame::new(0x183, &[0x21, 0x43])], "stored value sent");
    assert_eq!(
        events(&mut pdo),
        [PdoEvent::TpdoReadFailed { tpdo: 0, index: 0x2000, sub: 8, abort: SdoAbort::HARDWARE_ERROR }]
    );
}

#[test]
fn extended_and_unknown_ids() {
    let (mut od, mut pdo) = node3();
    remap(&mut od, &mut pdo, 0x1400, 0x2000_0203, 255, &[0x6040_0010]);
    assert_eq!(rx(&mut pdo, &mut od, Frame::new(0x203, &[1, 0]), ms(0)).0, PdoRx::NotPdo);
    let f = Frame::try_new(CanId::Extended(0x203), &[5, 0]).unwrap();
    assert_eq!(rx(&mut pdo, &mut od, f, ms(0)).0, PdoRx::Handled);
    assert_eq!(od.get_u64(0x6040, 0), Some(5));
    assert_eq!(rx(&mut pdo, &mut od, Frame::new(0x701, &[5]), ms(0)).0, PdoRx::NotPdo);
}

proptest::proptest! {
    /// Random frames (any id, length, RTR) and SYNCs never panic, whatever
    /// the mapping.
    #[test]
    fn random_frames_never_panic(
        frames in proptest::collection::vec((0u32..0x800, proptest::bool::ANY, proptest::collection::vec(proptest::num::u8::ANY, 0..=8), proptest::bool::ANY), 1..40),
        tt in proptest::sample::select(vec![0u8, 1, 2, 252, 253, 254, 255]),
        bits in proptest::bool::ANY,
    ) {
        let mut cfg = PdoConfig::new(3);
        cfg.dummy_types |= 2;
        let (mut od, mut pdo) = setup(&cfg);
        let layout: &[u32] = if bits {
            &[map_entry(0x2000, 1, 1), map_entry(0x0001, 0, 1), map_entry(0x2000, 4, 16), map_entry(0x2000, 9, 8)]
        } else {
            &[map_entry(0x2000, 10, 32), map_entry(0x2000, 9, 8)]
        };
        sdo16(&mut od, &mut pdo, 0x1400, 5, 3).unwrap();
        remap(&mut od, &mut pdo, 0x1400, 0x203, tt.min(240).max(if tt >= 252 { 255 } else { 0 }), layout);
        remap(&mut od, &mut pdo, 0x1800, 0x183, tt, layout);
        let mut out = Vec::new();
        for (i, (id, rtr, data, is_sync)) in frames.into_iter().enumerate() {
            let now = ms(i as u64);
            let id = if id & 1 == 0 { 0x203 } else if id & 2 == 0 { 0x183 } else { id as u16 };
            let f = if rtr { Frame::remote(id, data.len() as u8) } else { Frame::new(id, &data) };
            let _ = pdo.handle_frame(&f, now, &mut od, &mut drivebus_od::NoHooks, &mut out);
            if is_sync {
                pdo.on_sync(Some(i as u8), now, &mut od, &mut drivebus_od::NoHooks, &mut out);
            }
            let _ = pdo.poll(now, &mut od, &mut drivebus_od::NoHooks, &mut out);
            while pdo.pop_event().is_some() {}
        }
        for f in &out {
            proptest::prop_assert_eq!(f.std_id(), Some(0x183));
        }
    }

    /// Random SDO downloads to the PDO objects never panic and leave a
    /// consistent service.
    #[test]
    fn random_config_writes_never_panic(writes in proptest::collection::vec((0u16..4, 0u8..8, proptest::collection::vec(proptest::num::u8::ANY, 0..=4)), 1..60)) {
        let (mut od, mut pdo) = node3();
        for (which, sub, data) in writes {
            let index = [0x1400, 0x1600, 0x1800, 0x1A00][usize::from(which)];
            let _ = sdo(&mut od, &mut pdo, index, sub, &data);
            let _ = rx(&mut pdo, &mut od, Frame::new(0x203, &[1, 2, 3, 4, 5, 6, 7, 8]), ms(0));
            let _ = sync(&mut pdo, &mut od, None, ms(0));
        }
    }
}

proptest::proptest! {
    /// Random bit-granular layouts of BOOLEAN/u8/u16/u32 objects: an RPDO
    /// frame unpacked into the dictionary and packed again by a TPDO with the
    /// same mapping gives the same bits back (unmapped tail bits zero).
    #[test]
    fn rpdo_tpdo_round_trip(order in proptest::sample::subsequence(vec![1u8, 2, 3, 4, 10], 1..=5).prop_shuffle(), data in proptest::array::uniform8(proptest::num::u8::ANY)) {
        let (mut od, mut pdo) = node3();
        let bits = |s: u8| match s { 1 | 2 => 1u8, 3 => 8, 4 => 16, _ => 32 };
        let layout: Vec<u32> = order.iter().map(|&s| map_entry(0x2000, s, bits(s))).collect();
        let total: usize = order.iter().map(|&s| usize::from(bits(s))).sum();
        remap(&mut od, &mut pdo, 0x1400, 0x203, 255, &layout);
        remap(&mut od, &mut pdo, 0x1800, 0x183, 1, &layout);
        let len = total.div_ceil(8);
        let (r, _) = rx(&mut pdo, &mut od, Frame::new(0x203, &data[..len]), ms(0));
        proptest::prop_assert_eq!(r, PdoRx::Handled);
        let out = sync(&mut pdo, &mut od, None, ms(1));
        let mut want = [0u8; 8];
        pack_bits(&mut want, 0, total, unpack_bits(&data, 0, total));
        proptest::prop_assert_eq!(out, vec![Frame::new(0x183, &want[..len])]);
    }
}

#[test]
fn change_mask_limits_change_of_state() {
    let (mut od, mut pdo) = node3();
    // TPDO1: statusword only counts in its low byte (a drive's "send on
    // state change", KC1/AKD masks 2014h..2017h).
    remap(&mut od, &mut pdo, 0x1800, 0x183, 254, &[0x6041_0010]);
    assert!(pdo.set_change_mask(0, Some([0xFF, 0, 0, 0, 0, 0, 0, 0])));
    assert!(!pdo.set_change_mask(99, None));
    assert_eq!(poll(&mut pdo, &mut od, ms(10)).0.len(), 1);
    // A change in the high byte alone is not a change of state.
    let v0 = od.get_u64(0x6041, 0).unwrap() as u16;
    set(&mut od, 0x6041, 0, Value::U16(v0 ^ 0x0600));
    let before = od.get_u64(0x6041, 0).unwrap();
    assert_eq!(poll(&mut pdo, &mut od, ms(11)).0, vec![]);
    // A change in the masked byte is, and carries the whole value.
    set(&mut od, 0x6041, 0, Value::U16(before as u16 ^ 0x0001));
    let v = (before as u16 ^ 0x0001).to_le_bytes();
    assert_eq!(poll(&mut pdo, &mut od, ms(12)).0, vec![Frame::new(0x183, &v)]);
    // The mask survives reconfiguration.
    remap(&mut od, &mut pdo, 0x1800, 0x183, 254, &[0x6041_0010]);
    poll(&mut pdo, &mut od, ms(20));
    set(&mut od, 0x6041, 0, Value::U16((before as u16 ^ 0x0001) ^ 0x0100));
    assert_eq!(poll(&mut pdo, &mut od, ms(21)).0, vec![]);
}
