//! SYNC scenarios (CiA 301 §7.2.5; §7.5.2 for 1005h, 1006h, 1007h, 1019h), frame-exact.

use drivebus_can::{CanId, Frame, Instant};
use drivebus_od::{NoHooks, ObjectDictionary, SdoAbort};
use drivebus_sync::{SyncEvent, SyncLengthError, SyncService, SyncTimeout};

fn setup() -> (ObjectDictionary, SyncService) {
    let mut od = ObjectDictionary::new();
    let s = SyncService::install(&mut od, 1);
    (od, s)
}

fn us(v: u64) -> Instant {
    Instant::from_micros(v)
}

/// SDO-style write through the service: check, store, reconfigure.
fn write(od: &mut ObjectDictionary, s: &mut SyncService, index: u16, data: &[u8]) -> Result<(), SdoAbort> {
    s.check_write(od, index, 0, data)?;
    od.write(&mut NoHooks, index, 0, data)?;
    s.reconfigure(od, index, 0);
    Ok(())
}

fn w32(od: &mut ObjectDictionary, s: &mut SyncService, index: u16, v: u32) -> Result<(), SdoAbort> {
    write(od, s, index, &v.to_le_bytes())
}

const SYNC0: SyncEvent = SyncEvent { counter: None, length_error: None };

#[test]
fn defaults() {
    let (od, s) = setup();
    assert_eq!(od.get_u32(0x1005, 0), Some(0x80));
    assert_eq!(od.get_u32(0x1006, 0), Some(0));
    assert_eq!(od.get_u32(0x1007, 0), Some(0));
    assert_eq!(od.get_u32(0x1019, 0), Some(0));
    assert_eq!(s.can_id(), CanId::Standard(0x80));
    assert!(!s.is_producer());
}

#[test]
fn producer_without_counter() {
    let (mut od, mut s) = setup();
    w32(&mut od, &mut s, 0x1006, 1000).unwrap();
    w32(&mut od, &mut s, 0x1005, 0x4000_0080).unwrap();
    assert!(s.is_producing());
    let mut out = Vec::new();
    let p = s.poll(us(500), &mut out);
    assert_eq!(out, [Frame::new(0x080, &[])]);
    assert_eq!(p.produced, Some(SYNC0));
    assert_eq!(p.next, Some(us(1500)));
    // Early polls do nothing observable.
    let p = s.poll(us(1499), &mut out);
    assert_eq!((out.len(), p.produced, p.next), (1, None, Some(us(1500))));
    s.poll(us(1500), &mut out);
    s.poll(us(2500), &mut out);
    assert_eq!(out.len(), 3);
    // A late poll sends one SYNC and keeps the grid: 3500, 4500 missed.
    let p = s.poll(us(4700), &mut out);
    assert_eq!(out.len(), 4);
    assert_eq!(p.next, Some(us(5500)));
    assert_eq!(s.last_sync(), Some(us(4700)));
    // A new 1006h while running counts from the last SYNC.
    w32(&mut od, &mut s, 0x1006, 2000).unwrap();
    assert_eq!(s.poll(us(4800), &mut out).next, Some(us(6700)));
    assert_eq!(out.len(), 4);
}

#[test]
fn producer_counter_overflow_sequence() {
    let (mut od, mut s) = setup();
    write(&mut od, &mut s, 0x1019, &[3]).unwrap();
    w32(&mut od, &mut s, 0x1006, 2000).unwrap();
    w32(&mut od, &mut s, 0x1005, 0x4000_0080).unwrap();
    let mut out = Vec::new();
    let mut t = us(0);
    let mut counters = Vec::new();
    for _ in 0..7 {
        let p = s.poll(t, &mut out);
        counters.push(p.produced.unwrap().counter.unwrap());
        t = p.next.unwrap();
    }
    assert_eq!(counters, [1, 2, 3, 1, 2, 3, 1]);
    assert_eq!(out[0], Frame::new(0x080, &[1]));
    assert_eq!(out[2], Frame::new(0x080, &[3]));
    assert_eq!(out[3], Frame::new(0x080, &[1]));
    assert_eq!(t, us(14_000));
    // The node restarts the counter when the producer resumes.
    s.reset_counter();
    s.poll(t, &mut out);
    assert_eq!(out.last(), Some(&Frame::new(0x080, &[1])));
    // Stopping the producer with 1006h = 0 (then 1019h may change).
    w32(&mut od, &mut s, 0x1006, 0).unwrap();
    assert_eq!(s.poll(us(100_000), &mut out).next, None);
    write(&mut od, &mut s, 0x1019, &[240]).unwrap();
    w32(&mut od, &mut s, 0x1006, 1000).unwrap();
    let mut last = 0;
    let mut t = us(200_000);
    for _ in 0..241 {
        let p = s.poll(t, &mut out);
        last = p.produced.unwrap().counter.unwrap();
        t = p.next.unwrap();
    }
    assert_eq!(last, 1, "240 wraps to 1");
}

#[test]
fn producer_29_bit() {
    let (mut od, mut s) = setup();
    w32(&mut od, &mut s, 0x1006, 1000).unwrap();
    w32(&mut od, &mut s, 0x1005, 0x6000_1234).unwrap();
    let mut out = Vec::new();
    s.poll(us(0), &mut out);
    assert_eq!(out, [Frame::try_new(CanId::Extended(0x1234), &[]).unwrap()]);
}

#[test]
fn consumer_dlc_acceptance() {
    let (mut od, mut s) = setup();
    assert_eq!(s.handle_frame(&Frame::new(0x080, &[]), us(1)), Some(SYNC0));
    // DLC 1 while 1019h = 0: still a SYNC, flagged for EMCY 8240h.
    assert_eq!(
        s.handle_frame(&Frame::new(0x080, &[7]), us(2)),
        Some(SyncEvent { counter: Some(7), length_error: Some(SyncLengthError { expected: 0, actual: 1 }) })
    );
    write(&mut od, &mut s, 0x1019, &[10]).unwrap();
    assert_eq!(
        s.handle_frame(&Frame::new(0x080, &[4]), us(3)),
        Some(SyncEvent { counter: Some(4), length_error: None })
    );
    assert_eq!(
        s.handle_frame(&Frame::new(0x080, &[]), us(4)),
        Some(SyncEvent { counter: None, length_error: Some(SyncLengthError { expected: 1, actual: 0 }) })
    );
    assert_eq!(
        s.handle_frame(&Frame::new(0x080, &[1, 2]), us(5)),
        Some(SyncEvent { counter: None, length_error: Some(SyncLengthError { expected: 1, actual: 2 }) })
    );
    // Not SYNC: other ids, RTR, extended frame with the same number.
    assert_eq!(s.handle_frame(&Frame::new(0x081, &[]), us(6)), None);
    assert_eq!(s.handle_frame(&Frame::remote(0x080, 0), us(6)), None);
    let x = Frame::try_new(CanId::Extended(0x80), &[]).unwrap();
    assert_eq!(s.handle_frame(&x, us(6)), None);
    assert_eq!(s.last_sync(), Some(us(5)));
    // A producer ignores SYNCs on its own id; a mere "gen" bit with 1006h = 0 does not.
    w32(&mut od, &mut s, 0x1005, 0x4000_0080).unwrap();
    assert!(s.handle_frame(&Frame::new(0x080, &[1]), us(7)).is_some());
    w32(&mut od, &mut s, 0x1006, 1000).unwrap();
    assert_eq!(s.handle_frame(&Frame::new(0x080, &[1]), us(8)), None);
}

#[test]
fn cob_id_sync_aborts() {
    let (mut od, mut s) = setup();
    // Consumer: the id may change freely.
    w32(&mut od, &mut s, 0x1005, 0x81).unwrap();
    assert_eq!(s.can_id(), CanId::Standard(0x81));
    // Bit 31 is "do not care".
    w32(&mut od, &mut s, 0x1005, 0x8000_0082).unwrap();
    assert_eq!(s.can_id(), CanId::Standard(0x82));
    // Becoming producer and changing the id in the same write: allowed.
    w32(&mut od, &mut s, 0x1005, 0x4000_0080).unwrap();
    // While producer: no id or frame-format change.
    assert_eq!(w32(&mut od, &mut s, 0x1005, 0x4000_0081), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(w32(&mut od, &mut s, 0x1005, 0x6000_0080), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(w32(&mut od, &mut s, 0x1005, 0x0000_0081), Err(SdoAbort::INVALID_VALUE));
    // Stop producing (same id), then change.
    w32(&mut od, &mut s, 0x1005, 0x0000_0080).unwrap();
    w32(&mut od, &mut s, 0x1005, 0x0000_0090).unwrap();
    // 11-bit id with bits above 10, restricted ids (CiA 301 §7.3.5).
    assert_eq!(w32(&mut od, &mut s, 0x1005, 0x0000_0880), Err(SdoAbort::INVALID_VALUE));
    for id in [0x000u32, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x701, 0x7FF] {
        assert_eq!(w32(&mut od, &mut s, 0x1005, id), Err(SdoAbort::INVALID_VALUE), "{id:03X}");
    }
    for id in [0x080u32, 0x100, 0x181, 0x580, 0x600, 0x680, 0x6DF, 0x700] {
        assert_eq!(w32(&mut od, &mut s, 0x1005, id), Ok(()), "{id:03X}");
    }
    assert_eq!(write(&mut od, &mut s, 0x1005, &[0x80]), Err(SdoAbort::DATA_TOO_SHORT));
}

#[test]
fn counter_overflow_aborts() {
    let (mut od, mut s) = setup();
    for v in [1u8, 241, 250, 255] {
        assert_eq!(write(&mut od, &mut s, 0x1019, &[v]), Err(SdoAbort::INVALID_VALUE), "{v}");
    }
    for v in [0u8, 2, 100, 240] {
        assert_eq!(write(&mut od, &mut s, 0x1019, &[v]), Ok(()), "{v}");
    }
    // 1006h != 0: 1019h is locked (§7.5.2 (1019h)), even as a consumer.
    w32(&mut od, &mut s, 0x1006, 10_000).unwrap();
    assert_eq!(write(&mut od, &mut s, 0x1019, &[2]), Err(SdoAbort::DEVICE_STATE));
    assert_eq!(write(&mut od, &mut s, 0x1019, &[1]), Err(SdoAbort::INVALID_VALUE));
    assert_eq!(write(&mut od, &mut s, 0x1019, &[0, 0]), Err(SdoAbort::DATA_TOO_LONG));
    assert_eq!(s.counter_overflow(), 240);
}

#[test]
fn synchronous_window() {
    let (mut od, mut s) = setup();
    // No window configured: always open.
    assert!(s.window_open(us(0)));
    w32(&mut od, &mut s, 0x1007, 300).unwrap();
    assert!(!s.window_open(us(0)), "closed before the first SYNC");
    s.handle_frame(&Frame::new(0x080, &[]), us(1000));
    assert!(s.window_open(us(1000)));
    assert!(s.window_open(us(1299)));
    assert!(!s.window_open(us(1300)));
    assert_eq!(s.window_closes_at(), Some(us(1300)));
    s.handle_frame(&Frame::new(0x080, &[]), us(2000));
    assert!(s.window_open(us(2100)));
    // The producer's own SYNC opens the window too.
    w32(&mut od, &mut s, 0x1006, 1000).unwrap();
    w32(&mut od, &mut s, 0x1005, 0x4000_0080).unwrap();
    s.poll(us(5000), &mut Vec::new());
    assert!(s.window_open(us(5299)) && !s.window_open(us(5300)));
}

#[test]
fn sync_loss() {
    let (mut od, mut s) = setup();
    let mut out = Vec::new();
    w32(&mut od, &mut s, 0x1006, 10_000).unwrap();
    // Not armed before the first SYNC.
    assert_eq!(s.poll(us(100_000), &mut out).next, None);
    s.handle_frame(&Frame::new(0x080, &[]), us(100_000));
    let p = s.poll(us(100_000), &mut out);
    assert_eq!((p.timeout, p.next), (None, Some(us(115_000))));
    assert_eq!(s.poll(us(114_999), &mut out).timeout, None);
    let p = s.poll(us(115_000), &mut out);
    assert_eq!(p.timeout, Some(SyncTimeout { last_sync: us(100_000) }));
    assert_eq!(p.next, None);
    // Reported once per loss; a SYNC re-arms it.
    assert_eq!(s.poll(us(200_000), &mut out).timeout, None);
    s.handle_frame(&Frame::new(0x080, &[]), us(210_000));
    // Factor 3.0.
    s.set_timeout_factor_permille(3000);
    assert_eq!(s.sync_timeout(us(239_999)), None);
    assert!(s.sync_timeout(us(240_000)).is_some());
    // Factor 0 disables.
    s.handle_frame(&Frame::new(0x080, &[]), us(300_000));
    s.set_timeout_factor_permille(0);
    assert_eq!(s.poll(us(1_000_000), &mut out), Default::default());
    assert!(out.is_empty(), "a consumer never sends");
}
