//! 1003h "pre-defined error field" (CiA 301 §7.5.2.5): after errors,
//! sub 0 is the number of entries and every sub-index from 1 up to it
//! reads an entry, the newest at sub 1, whose low 16 bits are the code of
//! the EMCY frame the drive sent (KC1 §7.2.1.4, AKD §6.2.1.4, SSD 630 §9,
//! DDS6 §6.3.3). Sub-indices above it answer 0800 0024h "no data".
//! Checked on every profile that has 1003h, through its own EMCY path
//! (the Kollmorgen drives send their EMCY frames themselves).

mod replay_rig;

use drivebus_cia402::drive::Injection;
use drivebus_personality::Profile;
use replay_rig::Rig;

const NODE: u8 = 4;

fn abort_of(f: &drivebus_can::Frame) -> Option<u32> {
    let d = f.data();
    (d[0] == 0x80).then(|| u32::from_le_bytes([d[4], d[5], d[6], d[7]]))
}

#[test]
fn every_entry_up_to_sub_0_reads_the_emcy_code() {
    for &p in Profile::all() {
        let depth = p.info().error_history;
        if depth == 0 {
            continue;
        }
        let (mut r, _) = Rig::new(p, NODE);
        // Two faults, one after the other (a reset in between).
        let mut sent = Vec::new();
        for code in [0x5530u16, 0x4310] {
            r.take();
            r.pn_mut().inject(Injection::Fault(code));
            r.run_ms(5);
            let emcy: Vec<u16> = r
                .take()
                .iter()
                .filter(|f| f.std_id() == Some(0x80 + u16::from(NODE)) && f.data()[..2] != [0, 0])
                .map(|f| u16::from_le_bytes([f.data()[0], f.data()[1]]))
                .collect();
            assert_eq!(emcy.len(), 1, "{p}: one EMCY for {code:04X}h, got {emcy:04X?}");
            sent.insert(0, emcy[0]);
            // Fault reset (controlword bit 7 rising edge).
            r.sdo_write(NODE, 0x6040, 0, &[0x00, 0x00]);
            r.sdo_write(NODE, 0x6040, 0, &[0x80, 0x00]);
            r.run_ms(5);
        }
        let n = r.read_u32(NODE, 0x1003, 0) as usize;
        assert_eq!(n, sent.len().min(usize::from(depth)), "{p}: 1003h:00");
        for (i, code) in sent.iter().enumerate().take(n) {
            let sub = i as u8 + 1;
            let f = r.sdo_read(NODE, 0x1003, sub);
            assert_eq!(abort_of(&f), None, "{p}: 1003h:{sub:02X} after {n} errors: {f:?}");
            assert_eq!(r.read_u32(NODE, 0x1003, sub) & 0xFFFF, u32::from(*code), "{p}: 1003h:{sub:02X}");
        }
        let f = r.sdo_read(NODE, 0x1003, n as u8 + 1);
        assert_eq!(abort_of(&f), Some(0x0800_0024), "{p}: 1003h:{:02X}: {f:?}", n + 1);
    }
}
