//! Homing on the current position (CiA 402-2 methods 35 and 37) sets the
//! position actual value 6064h to the home offset 607Ch exactly, in the
//! drive's own position units (CiA 402-2 homing mode: "the home position
//! … is the home offset"), whatever the factor group: the DDS6's fixed
//! 1/10000 rev is finer than its 4000-count encoder (§4.4), the
//! Kollmorgen 36000 units per revolution are coarser than 2^20 counts,
//! the generic servo's 0.001° too. Every profile offering 35 or 37 is
//! checked with offsets that are not a whole number of increments, after
//! a first homing that left the axis off zero.

mod replay_rig;

use drivebus_personality::Profile;
use replay_rig::Rig;

const NODE: u8 = 3;

fn write(r: &mut Rig, index: u16, sub: u8, v: &[u8]) {
    assert_eq!(r.download(NODE, index, sub, v), Ok(()), "{index:04X}h:{sub} ← {v:02X?}");
}

/// Home with `method` and offset `offset`; returns 6064h after completion.
fn home(r: &mut Rig, method: i8, offset: i32) -> i32 {
    write(r, 0x607C, 0, &offset.to_le_bytes());
    write(r, 0x6098, 0, &[method as u8]);
    write(r, 0x6040, 0, &0x0Fu16.to_le_bytes());
    r.run_ms(2);
    write(r, 0x6040, 0, &0x1Fu16.to_le_bytes());
    for _ in 0..500 {
        r.run_ms(2);
        // Statusword bits 12 (homing attained) and 10 (target reached).
        if r.statusword() & 0x1400 == 0x1400 {
            break;
        }
    }
    assert_eq!(r.statusword() & 0x3400, 0x1400, "homing {method} did not complete");
    i32::from_le_bytes(r.upload(NODE, 0x6064, 0).unwrap().try_into().unwrap())
}

#[test]
fn home_position_is_the_home_offset_exactly() {
    let mut checked = 0;
    for &p in Profile::all() {
        let info = p.info();
        for method in [35i8, 37] {
            if !info.homing_methods.contains(&method) {
                continue;
            }
            let (mut r, _) = Rig::new(p, NODE);
            r.send(&format!("000#01 {NODE:02X}"));
            write(&mut r, 0x6060, 0, &[6]);
            for cw in [0x06u16, 0x07, 0x0F] {
                write(&mut r, 0x6040, 0, &cw.to_le_bytes());
                r.run_ms(20);
            }
            assert_eq!(r.statusword() & 0x6F, 0x27, "{p}: operation enabled");
            for offset in [1234, -777, 1, 98_765, 3] {
                let got = home(&mut r, method, offset);
                assert_eq!(got, offset, "{p}: method {method}, 607Ch = {offset}");
                write(&mut r, 0x6040, 0, &0x0Fu16.to_le_bytes());
            }
            checked += 1;
        }
    }
    assert!(checked >= 5, "{checked} profile/method pairs");
}
