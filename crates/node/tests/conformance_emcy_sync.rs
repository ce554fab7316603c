//! Conformance-style cases, categories EMCY (CiA 301 §7.2.7) and SYNC (§7.2.5).

mod common;
use common::*;
use drivebus_can::Duration;

#[test]
fn emcy_01_raise_history_and_reset() {
    let mut r = Rig::new(device());
    r.raise_emcy(0x2310, [1, 2, 3, 4, 5]);
    // 2xxx is a current error: 1001h = generic | current.
    assert_eq!(r.take(), frs(&["085#1023030102030405"]));
    assert_eq!(r.sdo_read(5, 0x1001, 0), fr("585#4F01100003000000"));
    assert_eq!(r.sdo_read(5, 0x1003, 0), fr("585#4F03100001000000"));
    assert_eq!(r.sdo_read(5, 0x1003, 1), fr("585#4303100110230000"));
    r.clear_emcy(0x2310);
    assert_eq!(r.take(), frs(&["085#0000000000000000"]));
    // Writing 0 to 1003h sub 0 clears the history; other values are refused.
    Rig::assert_abort(r.sdo_write(5, 0x1003, 0, &[1]), 5, 0x1003, 0, 0x0609_0030);
    Rig::assert_written(r.sdo_write(5, 0x1003, 0, &[0]), 5, 0x1003, 0);
    assert_eq!(r.sdo_read(5, 0x1003, 0), fr("585#4F03100000000000"));
}

#[test]
fn emcy_02_invalid_cob_id_suppresses_and_inhibit_spaces() {
    let mut r = Rig::new(device());
    Rig::assert_written(r.sdo_write(5, 0x1014, 0, &0x8000_0085u32.to_le_bytes()), 5, 0x1014, 0);
    r.raise_emcy(0x4310, [0; 5]);
    r.run_for(Duration::from_millis(1));
    assert!(r.take().is_empty());
    Rig::assert_written(r.sdo_write(5, 0x1014, 0, &0x85u32.to_le_bytes()), 5, 0x1014, 0);
    // Inhibit 10 × 100 µs = 1 ms between EMCYs.
    Rig::assert_written(r.sdo_write(5, 0x1015, 0, &10u16.to_le_bytes()), 5, 0x1015, 0);
    let t0 = r.now();
    r.raise_emcy(0x3210, [0; 5]);
    r.raise_emcy(0x3220, [0; 5]);
    r.run_for(Duration::from_millis(3));
    let got: Vec<_> = r.take_timed_ms(t0).into_iter().map(|(t, f)| ((t * 10.0).round() / 10.0, f)).collect();
    assert_eq!(got.len(), 2, "{got:?}");
    assert_eq!(got[0].1, fr("085#10320D0000000000"));
    assert_eq!(got[1].1, fr("085#20320D0000000000"));
    assert!((got[1].0 - got[0].0 - 1.0).abs() < 0.01, "{got:?}");
}

#[test]
fn sync_01_producer_with_counter_overflow() {
    let mut r = Rig::new(device());
    Rig::assert_written(r.sdo_write(5, 0x1019, 0, &[3]), 5, 0x1019, 0);
    Rig::assert_written(r.sdo_write(5, 0x1006, 0, &1000u32.to_le_bytes()), 5, 0x1006, 0);
    // 1019h may not change while a cycle period is set.
    Rig::assert_abort(r.sdo_write(5, 0x1019, 0, &[4]), 5, 0x1019, 0, 0x0800_0022);
    // Becoming the producer sends the first SYNC at once, then one per ms.
    r.exchange("605#2305100080000040", &["585#6005100000000000", "080#01"]);
    r.run_for(Duration::from_micros(4500));
    assert_eq!(r.take(), frs(&["080#02", "080#03", "080#01", "080#02"]));
}

#[test]
fn sync_02_counter_overflow_values() {
    let mut r = Rig::new(device());
    Rig::assert_abort(r.sdo_write(5, 0x1019, 0, &[1]), 5, 0x1019, 0, 0x0609_0030);
    Rig::assert_abort(r.sdo_write(5, 0x1019, 0, &[241]), 5, 0x1019, 0, 0x0609_0030);
    Rig::assert_written(r.sdo_write(5, 0x1019, 0, &[240]), 5, 0x1019, 0);
}
