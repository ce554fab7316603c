//! SYNC traffic printed in the drive manuals (/work/shared/reference/seed00*-examples.md).
//! No manual prints a TIME frame (KC1, AKD and SSD 630 state TIME is not supported).

use drivebus_can::{Frame, Instant};
use drivebus_od::{NoHooks, ObjectDictionary};
use drivebus_sync::{SyncEvent, SyncService};

fn tenth_ms(v: u64) -> Instant {
    Instant::from_micros(v * 100)
}

/// seed000 (KC1) Example 6 frame 39 (src line 5213) and seed001 (AKD) row 5622:
/// `080`, DLC 0, with the default 1005h/1019h.
#[test]
fn kc1_akd_sync_dlc0() {
    let mut od = ObjectDictionary::new();
    let mut s = SyncService::install(&mut od, 3);
    let e = s.handle_frame(&Frame::new(0x080, &[]), Instant::from_millis(5213));
    assert_eq!(e, Some(SyncEvent { counter: None, length_error: None }));
}

/// seed004 (DDS6) EX9 (§4.4.5): the master's SYNCs every 20 ms (60C2h =
/// 20 × 10⁻³ s). Frames 34..49 and 79..91 with their printed times; with
/// 1006h = 20000 µs the 1.5-period loss watch never fires inside a run
/// despite the ±0.1 ms jitter. (The "… …" elisions between runs are gaps in
/// the listing, not on the bus, so they are not replayed as gaps.)
#[test]
fn dds6_ip_sync_run() {
    let mut od = ObjectDictionary::new();
    let mut s = SyncService::install(&mut od, 0x0D);
    s.check_write(&od, 0x1006, 0, &20_000u32.to_le_bytes()).unwrap();
    od.write(&mut NoHooks, 0x1006, 0, &20_000u32.to_le_bytes()).unwrap();
    s.reconfigure(&od, 0x1006, 0);
    for run in
        [&[33612u64, 33811, 34011, 34212, 34411, 34612, 34811][..], &[58652, 58853, 59053, 59253, 59452]]
    {
        let mut sink = Vec::new();
        let mut last = None;
        for &t in run {
            let now = tenth_ms(t);
            if let Some(prev) = last {
                // Nothing due between two SYNCs of the run.
                assert_eq!(s.poll(now, &mut sink).timeout, None);
                assert!(now - prev < drivebus_can::Duration::from_millis(21));
            }
            assert!(s.handle_frame(&Frame::new(0x080, &[]), now).is_some());
            last = Some(now);
        }
        assert!(sink.is_empty());
    }
}

/// seed003 (SSD 630) EX14.13 frame 13: `601: 23 06 10 00 88 13 00 00`,
/// 1006h := 5000 µs (the step title printed there is a TYPO: "Send PDO1 tx
/// enable"). EX14.14's lost picture expects cyclic `080` every 5 ms; a
/// drivebus master producing SYNC with that period emits exactly that.
#[test]
fn ssd630_cycle_period_5ms() {
    let mut od = ObjectDictionary::new();
    let mut s = SyncService::install(&mut od, 1);
    let sdo = [0x23u8, 0x06, 0x10, 0x00, 0x88, 0x13, 0x00, 0x00];
    let index = u16::from_le_bytes([sdo[1], sdo[2]]);
    s.check_write(&od, index, sdo[3], &sdo[4..]).unwrap();
    od.write(&mut NoHooks, index, sdo[3], &sdo[4..]).unwrap();
    s.reconfigure(&od, index, sdo[3]);
    assert_eq!(s.period(), drivebus_can::Duration::from_micros(5000));
    let producer_bit = 0x4000_0080u32.to_le_bytes();
    s.check_write(&od, 0x1005, 0, &producer_bit).unwrap();
    od.write(&mut NoHooks, 0x1005, 0, &producer_bit).unwrap();
    s.reconfigure(&od, 0x1005, 0);
    let mut out = Vec::new();
    let mut times = Vec::new();
    let mut t = Instant::from_millis(100);
    for _ in 0..4 {
        times.push(t.as_micros());
        t = s.poll(t, &mut out).next.unwrap();
    }
    assert_eq!(times, [100_000, 105_000, 110_000, 115_000]);
    assert!(out.iter().all(|f| *f == Frame::new(0x080, &[])));
}
