//! DC SYNC0 set up in SOEM's order (issue 14): `ec_config_map` requests
//! SAFE-OP right after the mapping (the slave enters it SM-synchronous),
//! then `ec_configdc` and `ec_dcsync0` activate SYNC0, then OP. The iPOS
//! runs on SYNC0 from OP on — 1C32h:01 = 2, 60C2h = the SYNC0 cycle, the
//! set-points latched at the pulses — and follows a csp ramp. A SYNC0 the
//! master activates only in OP leaves the SM-synchronous drive latching
//! at the SM2 event alone.

mod drive_rig;

use drive_rig::{Rig, al};
use drivebus_can::Duration;
use drivebus_personality::Profile;

const CYCLE_NS: u32 = 2_000_000;

/// SYNC0 every `cycle` ns, starting 1 ms from now, as `ec_dcsync0` writes
/// it (activation off, start time, cycle, activation on).
fn dcsync0(r: &mut Rig, cycle: u32) {
    r.wr(0x0981, &[0]);
    let now = u64::from_le_bytes(r.rd(0x0910, 8).try_into().unwrap());
    r.wr(0x0990, &(now + 1_000_000).to_le_bytes());
    r.wr(0x09A0, &cycle.to_le_bytes());
    r.wr(0x0981, &[0x03]);
}

/// One master cycle: RxPDO1 (6040h, 607Ah), one SYNC0 period, TxPDO1
/// (6041h, 6064h, ...): (statusword, position).
fn cycle(r: &mut Rig, cw: u16, target: i32) -> (u16, i32) {
    let mut out = vec![0u8; usize::from(r.pd.0)];
    out[..2].copy_from_slice(&cw.to_le_bytes());
    out[2..6].copy_from_slice(&target.to_le_bytes());
    r.outputs(&out);
    r.tick(Duration::from_nanos(u64::from(CYCLE_NS)));
    let i = r.inputs();
    (u16::from_le_bytes([i[0], i[1]]), i32::from_le_bytes([i[2], i[3], i[4], i[5]]))
}

fn enable(r: &mut Rig, at: i32) {
    for (cw, want) in [(0x06u16, 0x21u16), (0x07, 0x23), (0x0F, 0x27)] {
        assert!((0..50).any(|_| cycle(r, cw, at).0 & 0x6F == want), "controlword {cw:04X}h");
    }
}

#[test]
fn soem_order_runs_the_ipos_on_sync0() {
    let mut r = Rig::new(Profile::Ipos);
    r.preop();
    r.down(0x6060, 0, &[8]).unwrap();
    // ec_config_map: mapping, then SAFE-OP requested at once.
    r.safeop();
    assert_eq!(r.up_u32(0x1C32, 1), 1, "SAFE-OP entered SM-synchronous");
    // ec_configdc, ec_dcsync0, then OP.
    dcsync0(&mut r, CYCLE_NS);
    assert_eq!(r.request(al::OP), (0x08, 0));
    assert_eq!((r.up_u32(0x1C32, 1), r.up_u32(0x1C32, 0x0A)), (2, CYCLE_NS), "on SYNC0 (1C32h:01, :0A)");
    assert_eq!((r.up_u32(0x60C2, 1), r.up(0x60C2, 2).unwrap()), (2, vec![(-3i8) as u8]), "60C2h = 2 ms");
    let (_, start) = cycle(&mut r, 0, 0);
    enable(&mut r, start);
    // 4 counts per cycle for 0.5 s, then held.
    let mut target = start;
    for k in 0..250 {
        target += 4;
        let (sw, p) = cycle(&mut r, 0x0F, target);
        assert_eq!(sw & 0x6F, 0x27, "statusword {sw:04X}h");
        if k > 20 {
            // The set-point latched at the next pulse, reached one cycle
            // later, the position loop behind it.
            assert!((target - p).abs() <= 4 * 4, "cycle {k}: 6064h {p}, target {target}");
        }
    }
    let tail: Vec<i32> = (0..250).map(|_| cycle(&mut r, 0x0F, target).1).collect();
    assert!(tail[200..].iter().all(|p| (p - target).abs() <= 3), "held on {target}: {:?}", &tail[240..]);
    let pulses = r.s.app().stats().sync0_pulses;
    assert!(pulses >= 500, "the drive ran on SYNC0: {pulses} pulses");
}

#[test]
fn sync0_activated_in_op_does_not_latch_a_second_time() {
    let mut r = Rig::new(Profile::Ipos);
    r.preop();
    r.down(0x6060, 0, &[8]).unwrap();
    r.safeop();
    assert_eq!(r.request(al::OP), (0x08, 0));
    dcsync0(&mut r, CYCLE_NS);
    let (_, start) = cycle(&mut r, 0, 0);
    enable(&mut r, start);
    for k in 1..=100 {
        cycle(&mut r, 0x0F, start + 4 * k);
    }
    assert_eq!(r.up_u32(0x1C32, 1), 1, "still SM-synchronous");
    assert_eq!(r.s.app().stats().sync0_pulses, 0, "SYNC0 pulses left to the SM2 event");
    let tail: Vec<i32> = (0..100).map(|_| cycle(&mut r, 0x0F, start + 400).1).collect();
    assert!(tail[50..].iter().all(|p| (p - start - 400).abs() <= 3), "{:?}", &tail[90..]);
}
