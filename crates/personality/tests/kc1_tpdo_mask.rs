//! KC1 §7.2.2.4 (AKD B.4): the TPDO masks 2014h..2017h decide which bits of
//! an event-driven TPDO count as a change.

mod replay_rig;
use drivebus_personality::Profile;
use replay_rig::*;

/// Send each controlword by SDO; count TPDO1 (183h) frames that follow.
fn walk(r: &mut Rig, cw: &[u16]) -> usize {
    let mut n = 0;
    for c in cw {
        let b = c.to_le_bytes();
        r.take();
        r.send(&format!("603#2B406000{:02X}{:02X}0000", b[0], b[1]));
        r.run_ms(20);
        n += r.take().iter().filter(|f| f.std_id() == Some(0x183)).count();
    }
    n
}

fn mask(r: &mut Rig, lo: u32, hi: u32) {
    Rig::assert_written(r.sdo_write(3, 0x2014, 1, &lo.to_le_bytes()), 3, 0x2014, 1);
    Rig::assert_written(r.sdo_write(3, 0x2014, 2, &hi.to_le_bytes()), 3, 0x2014, 2);
}

#[test]
fn masked_statusword_changes_send_no_tpdo() {
    let (mut r, _) = Rig::new(Profile::Kc1, 3);
    r.send("000#0103");
    r.run_ms(20);
    // Default mask (all bits): each state change of 6041h is sent.
    assert_eq!(walk(&mut r, &[0x06, 0x07]), 2);
    // Nothing monitored: the state changes send nothing.
    mask(&mut r, 0, 0);
    assert_eq!(walk(&mut r, &[0x0F, 0x07]), 0);
    // Only the "operation enabled" bit (bit 2) monitored.
    mask(&mut r, 0x0000_0004, 0);
    assert_eq!(walk(&mut r, &[0x06]), 0, "switched on → ready: bit 2 unchanged");
    assert_eq!(walk(&mut r, &[0x0F]), 1, "→ operation enabled: bit 2 set");
}
