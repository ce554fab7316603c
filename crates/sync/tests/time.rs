//! TIME scenarios (CiA 301 §7.2.6, §7.5.2 (1012h)) and TIME_OF_DAY vectors.

use drivebus_can::{CanId, Frame};
use drivebus_od::{NoHooks, ObjectDictionary, SdoAbort};
use drivebus_sync::{CivilTime, TimeOfDay, TimeService, UNIX_DAYS_AT_1984};

fn setup() -> (ObjectDictionary, TimeService) {
    let mut od = ObjectDictionary::new();
    let t = TimeService::install(&mut od);
    (od, t)
}

fn w32(od: &mut ObjectDictionary, t: &mut TimeService, v: u32) -> Result<(), SdoAbort> {
    t.check_write(od, 0x1012, 0, &v.to_le_bytes())?;
    od.write(&mut NoHooks, 0x1012, 0, &v.to_le_bytes())?;
    t.reconfigure(od, 0x1012, 0);
    Ok(())
}

fn civil(year: u16, month: u8, day: u8, hour: u8, minute: u8, second: u8, millis: u16) -> CivilTime {
    CivilTime { year, month, day, hour, minute, second, millis }
}

#[test]
fn epoch_is_all_zeros() {
    let t = TimeOfDay::from_civil(&civil(1984, 1, 1, 0, 0, 0, 0)).unwrap();
    assert_eq!(t, TimeOfDay { days: 0, ms: 0 });
    assert_eq!(t.to_bytes(), [0; 6]);
    assert_eq!(t.to_unix_ms(), 441_763_200_000, "1984-01-01T00:00:00Z");
    assert_eq!(UNIX_DAYS_AT_1984, 5113);
}

#[test]
fn known_dates() {
    // 2000-01-01 00:00:00: 16 years incl. 4 leap years = 5844 days.
    let t = TimeOfDay::from_civil(&civil(2000, 1, 1, 0, 0, 0, 0)).unwrap();
    assert_eq!(t, TimeOfDay { days: 5844, ms: 0 });
    assert_eq!(t.to_bytes(), [0, 0, 0, 0, 0xD4, 0x16]);
    assert_eq!(t.to_unix_ms(), 946_684_800_000);
    // 2024-02-29 13:45:30.250 (a leap day): Unix 1709214330.250 s.
    let t = TimeOfDay::from_civil(&civil(2024, 2, 29, 13, 45, 30, 250)).unwrap();
    assert_eq!(t.days, 14_669);
    assert_eq!(t.ms, 49_530_250);
    assert_eq!(t.to_bytes(), [0x8A, 0xC5, 0xF3, 0x02, 0x4D, 0x39]);
    assert_eq!(t.to_unix_ms(), 1_709_214_330_250);
    assert_eq!(TimeOfDay::from_unix_ms(1_709_214_330_250), Some(t));
    assert_eq!(t.to_civil(), civil(2024, 2, 29, 13, 45, 30, 250));
    // Last representable day and the last millisecond of a day.
    let last = TimeOfDay::from_civil(&civil(2163, 6, 6, 23, 59, 59, 999)).unwrap();
    assert_eq!(last, TimeOfDay { days: 65_535, ms: 86_399_999 });
    assert_eq!(last.to_civil(), civil(2163, 6, 6, 23, 59, 59, 999));
    assert_eq!(TimeOfDay::from_civil(&civil(2163, 6, 7, 0, 0, 0, 0)), None);
    assert_eq!(TimeOfDay::from_civil(&civil(1983, 12, 31, 23, 59, 59, 999)), None);
    assert_eq!(TimeOfDay::from_civil(&civil(2023, 2, 29, 0, 0, 0, 0)), None);
    assert_eq!(TimeOfDay::from_civil(&civil(2100, 2, 29, 0, 0, 0, 0)), None, "2100 is not a leap year");
    assert!(TimeOfDay::from_civil(&civil(2000, 2, 29, 0, 0, 0, 0)).is_some(), "2000 is");
    assert_eq!(TimeOfDay::from_unix_ms(441_763_199_999), None);
}

#[test]
fn reserved_bits_ignored_and_lengths_checked() {
    let t = TimeOfDay::from_bytes(&[0xFF, 0xFF, 0xFF, 0xFF, 0x01, 0x00]).unwrap();
    assert_eq!(t, TimeOfDay { days: 1, ms: 0x0FFF_FFFF });
    assert_eq!(t.to_bytes()[3], 0x0F);
    assert_eq!(TimeOfDay::from_bytes(&[0; 5]), None);
    assert_eq!(TimeOfDay::from_bytes(&[0; 7]), None);
}

#[test]
fn producer_and_consumer_bits() {
    let (mut od, mut t) = setup();
    assert_eq!(od.get_u32(0x1012, 0), Some(0x100));
    let stamp = Frame::new(0x100, &[0x8A, 0xC5, 0xF3, 0x02, 0x4D, 0x39]);
    let mut out = Vec::new();
    // Neither bit: nothing sent, nothing consumed.
    assert!(!t.transmit_time(49_530_250, 14_669, &mut out));
    assert_eq!(t.handle_frame(&stamp), None);
    w32(&mut od, &mut t, 0x4000_0100).unwrap();
    assert!(t.transmit_time(49_530_250, 14_669, &mut out));
    assert_eq!(out, [stamp]);
    assert_eq!(t.handle_frame(&stamp), None, "producer only");
    w32(&mut od, &mut t, 0x8000_0100).unwrap();
    assert_eq!(t.handle_frame(&stamp), Some(TimeOfDay { days: 14_669, ms: 49_530_250 }));
    assert_eq!(t.handle_frame(&Frame::new(0x100, &[0; 5])), None);
    assert_eq!(t.handle_frame(&Frame::new(0x101, &[0; 6])), None);
    assert_eq!(t.handle_frame(&Frame::remote(0x100, 6)), None);
}

#[test]
fn cob_id_time_aborts() {
    let (mut od, mut t) = setup();
    // Inactive: the id may change, also to 29 bits.
    w32(&mut od, &mut t, 0x0000_0190).unwrap();
    w32(&mut od, &mut t, 0x2000_0100).unwrap();
    w32(&mut od, &mut t, 0xE000_0100).unwrap();
    let mut out = Vec::new();
    assert!(t.transmit_time(1, 2, &mut out));
    assert_eq!(out, [Frame::try_new(CanId::Extended(0x100), &[1, 0, 0, 0, 2, 0]).unwrap()]);
    // Active: bits 0..29 are frozen.
    assert_eq!(w32(&mut od, &mut t, 0xE000_0190), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(w32(&mut od, &mut t, 0x0000_0100), Err(SdoAbort::INVALID_VALUE));
    w32(&mut od, &mut t, 0x2000_0100).unwrap();
    w32(&mut od, &mut t, 0x0000_0100).unwrap();
    assert_eq!(w32(&mut od, &mut t, 0x0000_0900), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(w32(&mut od, &mut t, 0x8000_0701), Err(SdoAbort::INVALID_VALUE));
}

proptest::proptest! {
    #[test]
    fn unix_round_trip(days in 0u16..=u16::MAX, ms in 0u32..86_400_000) {
        let t = TimeOfDay { days, ms };
        proptest::prop_assert_eq!(TimeOfDay::from_unix_ms(t.to_unix_ms()), Some(t));
        proptest::prop_assert_eq!(TimeOfDay::from_bytes(&t.to_bytes()), Some(t));
        proptest::prop_assert_eq!(TimeOfDay::from_civil(&t.to_civil()), Some(t));
    }
}
