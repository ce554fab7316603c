//! The LAM DDS6 manual's §4.4.5 interpolated-position trace (seed004,
//! DDS6-EX9 of `seed004-dds6-examples.md`: RPDO2 remapped to controlword +
//! 60C1h:1, RPDO2 and TPDO2 synchronous, 20 ms SYNC) replayed against the
//! built `dds6` personality on the virtual bus, node-ID 0Dh, every request
//! at its printed time on simulated time; the checking rule is in
//! `dds6_rig` and `replay_report.md`.
//!
//! The only corrections are the examples file's DLC flags (PDO rows printed
//! with 7 data bytes for a 6-byte mapping), made in the trace file.

mod dds6_rig;

use dds6_rig::{Rig, count, trace};

// EX9: the printed trace, shared with the node-level replay.
const EX9: &str = include_str!("../traces/dds6_ex9.txt");

/// EX9 (§4.4.5): one clockwise and one counter-clockwise revolution with a
/// sinusoidal profile, set-points every 20 ms SYNC. The DDS6 has no
/// set-point buffer (one set-point per period): the set-point sent after
/// SYNC n is applied at SYNC n + 1 and reached at SYNC n + 2, where TPDO2
/// (sampled before that SYNC's RPDO takes effect) shows it.
#[test]
fn ex9_interpolated_position_sync_pdo() {
    let mut r = Rig::new();
    let t = trace(EX9, 402);
    let o = r.replay(&t);
    o.report("EX9", count(&t).1);
    assert_eq!(o.extra, 0);
    assert!(o.value_differs.is_empty(), "positions within 40 units: {:?}", o.value_differs);
    // KNOWN DIFFERENCE (replay_report.md): around the two turning points
    // the print shows bit 10 "target reached" (1716h) while the axis is
    // still moving; the rule behind it is not documented (probably the
    // 3490h micro-interpolator's lag against 6067h) and is not emulated:
    // the emulation shows 1716h at standstill only. Everything else in
    // those frames is as printed.
    for (p, g) in &o.statusword_differs {
        let (ps, gs) =
            (u16::from_le_bytes([p.data()[0], p.data()[1]]), u16::from_le_bytes([g.data()[0], g.data()[1]]));
        assert_eq!((ps, gs), (0x1637, 0x1237), "only bit 10 at the turning points: {p:?} vs {g:?}");
    }
    assert!(o.statusword_differs.len() <= 17, "{}", o.statusword_differs.len());
    assert_eq!(r.i64(0x6061, 0), 7);
    assert_eq!(r.state(), 0x27);
    // The trace stops 5 ms after the last SYNC (8005.4 ms, "repeated
    // polling elided"): the axis is on its way from the last printed
    // position, 8Bh = 139, to the set-point in force, 02FFh = 767.
    let p = r.i64(0x6064, 0);
    assert!((139..767).contains(&p), "§4.4.5: between 139 and 767, at {p}");
}
