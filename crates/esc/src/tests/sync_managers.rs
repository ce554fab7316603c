//! Sync managers through frames and the PDI.

use super::*;
use crate::EscEvent;

/// SM0 write mailbox at 0x1000/16, SM1 read mailbox at 0x1080/16.
fn mailboxes() -> Esc {
    let mut e = addressed();
    assert_eq!(wr(&mut e, 0x0800, &[0x00, 0x10, 16, 0, 0x26, 0, 1, 0]), 1);
    assert_eq!(wr(&mut e, 0x0808, &[0x80, 0x10, 16, 0, 0x22, 0, 1, 0]), 1);
    while e.pop_event().is_some() {}
    e
}

#[test]
fn write_mailbox_fills_on_last_byte_and_refuses_until_read() {
    let mut e = mailboxes();
    assert_eq!(rd(&mut e, 0x0805, 1).0, [0x00]);
    // A partial write does not fill it.
    assert_eq!(wr(&mut e, 0x1000, &[1; 8]), 1);
    assert_eq!(rd(&mut e, 0x0805, 1).0[0] & 0x08, 0);
    assert_eq!(wr(&mut e, 0x1008, &[2; 8]), 1);
    assert_eq!(rd(&mut e, 0x0805, 1).0[0] & 0x08, 0x08, "full after the last byte");
    assert_eq!(e.pop_event(), Some(EscEvent::SmWritten(0)));
    assert_eq!(rd(&mut e, 0x0220, 4).0[1] & 0x01, 0x01, "AL event SM0 (control bit 5)");
    assert_eq!(wr(&mut e, 0x1000, &[3; 16]), 0, "full: master write refused, no WKC");
    assert_eq!(rd(&mut e, 0x1000, 16).1, 0, "master cannot read a write mailbox");
    let mut m = [0u8; 16];
    assert!(e.pdi_read(0x1000, &mut m));
    assert_eq!(m, [1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2]);
    assert_eq!(rd(&mut e, 0x0805, 1).0[0] & 0x08, 0, "PDI read of last byte empties");
    assert_eq!(wr(&mut e, 0x1000, &[3; 16]), 1);
}

#[test]
fn read_mailbox_needs_full_and_master_read_of_last_byte_empties() {
    let mut e = mailboxes();
    let (d, wkc) = rd(&mut e, 0x1080, 16);
    assert_eq!((d, wkc), (alloc::vec![0; 16], 0), "empty: no data, no WKC");
    assert!(e.pdi_write(0x1080, &[9; 16]));
    assert_eq!(rd(&mut e, 0x080D, 1).0[0] & 0x08, 0x08);
    assert!(!e.pdi_write(0x1080, &[8; 16]), "full: PDI refused");
    let (d, wkc) = rd(&mut e, 0x1080, 16);
    assert_eq!((d, wkc), (alloc::vec![9; 16], 1));
    assert_eq!(e.pop_event(), Some(EscEvent::SmRead(1)));
    assert_eq!(rd(&mut e, 0x080D, 1).0[0] & 0x08, 0);
}

#[test]
fn sm_config_is_locked_while_enabled_and_status_is_read_only() {
    let mut e = mailboxes();
    wr(&mut e, 0x0800, &[0x00, 0x20, 32, 0, 0x22, 0xFF]);
    assert_eq!(rd(&mut e, 0x0800, 8).0, [0x00, 0x10, 16, 0, 0x26, 0, 1, 0]);
    wr(&mut e, 0x0806, &[0]);
    wr(&mut e, 0x0800, &[0x00, 0x20, 32, 0]);
    assert_eq!(rd(&mut e, 0x0800, 4).0, [0x00, 0x20, 32, 0]);
}

#[test]
fn disabled_sm_area_is_plain_memory() {
    let mut e = mailboxes();
    wr(&mut e, 0x0806, &[0]);
    assert_eq!(wr(&mut e, 0x1000, &[5; 4]), 1);
    assert_eq!(rd(&mut e, 0x1000, 4), (alloc::vec![5; 4], 1));
    assert_eq!(rd(&mut e, 0x0805, 1).0, [0]);
}

#[test]
fn repeat_request_raises_sm_changed_and_pdi_acknowledges() {
    let mut e = mailboxes();
    wr(&mut e, 0x080E, &[0x03]);
    assert_eq!(e.pop_event(), Some(EscEvent::SmChanged));
    assert_eq!(rd(&mut e, 0x0220, 1).0[0] & 0x10, 0x10);
    let mut a = [0u8];
    e.pdi_read(0x080E, &mut a);
    assert_eq!(a[0], 0x03);
    assert_eq!(rd(&mut e, 0x0220, 1).0[0] & 0x10, 0, "PDI read of the activate register clears it");
    assert!(e.pdi_write(0x080F, &[0x02]));
    assert_eq!(rd(&mut e, 0x080F, 1).0, [0x02], "repeat acknowledge visible to the master");
    assert_eq!(wr(&mut e, 0x080F, &[0x00]), 1);
    assert_eq!(rd(&mut e, 0x080F, 1).0, [0x02], "PDI control is read-only for the master");
}

#[test]
fn pdi_deactivation_blocks_the_master_and_empties_the_buffer() {
    let mut e = mailboxes();
    e.pdi_write(0x1080, &[1; 16]);
    assert!(e.pdi_write(0x080F, &[0x01]));
    assert_eq!(rd(&mut e, 0x1080, 16).1, 0, "deactivated by PDI");
    assert!(e.pdi_write(0x080F, &[0x00]));
    assert_eq!(rd(&mut e, 0x080D, 1).0[0] & 0x08, 0, "buffer state reset");
}

#[test]
fn three_buffer_outputs_through_fpwr_and_pdi() {
    let mut e = addressed();
    // SM2: 3-buffer, master writes, watchdog trigger, AL event.
    wr(&mut e, 0x0810, &[0x00, 0x11, 4, 0, 0x64, 0, 1, 0]);
    while e.pop_event().is_some() {}
    assert_eq!(rd(&mut e, 0x0815, 1).0[0] >> 4 & 3, 3, "no buffer written");
    assert_eq!(wr(&mut e, 0x1100, &[1, 2, 3, 4]), 1);
    assert_eq!(e.pop_event(), Some(EscEvent::SmWritten(2)));
    assert_eq!(wr(&mut e, 0x1100, &[5, 6, 7, 8]), 1);
    assert_eq!(wr(&mut e, 0x1100, &[9, 9]), 1, "incomplete write");
    let mut m = [0u8; 4];
    assert!(e.pdi_read(0x1100, &mut m));
    assert_eq!(m, [5, 6, 7, 8], "newest complete buffer");
    // The shadow buffers are not addressable.
    assert_eq!(wr(&mut e, 0x1104, &[0; 8]), 0);
    // Reads of a master-written 3-buffer are refused for the master.
    assert_eq!(rd(&mut e, 0x1100, 4).1, 0);
}

#[test]
fn three_buffer_inputs_always_readable() {
    let mut e = addressed();
    wr(&mut e, 0x0818, &[0x00, 0x12, 2, 0, 0x20, 0, 1, 0]);
    assert_eq!(rd(&mut e, 0x1200, 2), (alloc::vec![0, 0], 1), "nothing written yet: still readable");
    assert!(e.pdi_write(0x1200, &[0xAA, 0xBB]));
    assert_eq!(rd(&mut e, 0x1200, 2), (alloc::vec![0xAA, 0xBB], 1));
    assert!(e.pdi_write(0x1200, &[0xCC, 0xDD]));
    assert!(e.pdi_write(0x1200, &[0xEE, 0xFF]));
    assert_eq!(rd(&mut e, 0x1200, 2).0, [0xEE, 0xFF]);
    assert_eq!(rd(&mut e, 0x1200, 2).0, [0xEE, 0xFF], "no new data: same buffer again");
}

#[test]
fn sm1_full_is_mirrored_in_ecat_events_when_enabled() {
    let mut e = addressed();
    wr(&mut e, 0x0808, &[0x80, 0x10, 16, 0, 0x32, 0, 1, 0]); // control bit 4: ECAT event
    e.pdi_write(0x1080, &[1; 16]);
    assert_eq!(rd(&mut e, 0x0210, 2).0[0] & 0x20, 0x20, "SM1 bit 5");
    rd(&mut e, 0x1080, 16);
    assert_eq!(rd(&mut e, 0x0210, 2).0[0] & 0x20, 0);
}
