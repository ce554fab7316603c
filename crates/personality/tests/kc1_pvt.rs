//! KC1 PVT interpolation (60C0h = −2, §7.9.2.2): 60C1h:01 is the target
//! position, :02 the time to reach it (ms, UNSIGNED32) and :03 the target
//! velocity; the record enters the buffer with its last item. A point 36000
//! units (one revolution) away, 1000 ms long, ending at rest: half-way in
//! time the axis is half-way (a cubic with zero end velocities is
//! symmetric), at the end it is there.

mod replay_rig;

use drivebus_personality::Profile;
use replay_rig::Rig;

const NODE: u8 = 1;

fn w(r: &mut Rig, index: u16, sub: u8, v: &[u8]) {
    assert_eq!(r.download(NODE, index, sub, v), Ok(()), "{index:04X}h:{sub}");
}

#[test]
fn a_pvt_point_takes_its_time_and_its_velocity() {
    for p in [Profile::Kc1] {
        let (mut r, _) = Rig::new(p, NODE);
        w(&mut r, 0x6060, 0, &[7]);
        w(&mut r, 0x60C0, 0, &(-2i16).to_le_bytes());
        for cw in [0x06u16, 0x07, 0x0F, 0x1F] {
            w(&mut r, 0x6040, 0, &cw.to_le_bytes());
            r.run_ms(5);
        }
        assert_eq!(r.statusword() & 0x6F, 0x27, "{p}: operation enabled");
        let start = r.position();
        // Position, time, velocity: in the manual's sub-index order.
        w(&mut r, 0x60C1, 1, &(start + 36000).to_le_bytes());
        w(&mut r, 0x60C1, 2, &1000u32.to_le_bytes());
        w(&mut r, 0x60C1, 3, &0i32.to_le_bytes());
        r.run_ms(500);
        let half = r.position() - start;
        assert!((half - 18000).abs() < 1800, "{p}: {half} units after 500 ms, 18000 expected");
        r.run_ms(700);
        let end = r.position() - start;
        assert!((end - 36000).abs() < 200, "{p}: {end} units after 1200 ms, 36000 expected");
    }
}
