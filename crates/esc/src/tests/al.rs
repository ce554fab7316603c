//! AL control / status (0x0120–0x0135) and DL registers.

use super::*;
use crate::EscEvent;
use crate::sii::ConfigArea;

#[test]
fn al_control_write_raises_event_and_blocks_until_pdi_reads() {
    let mut e = addressed();
    assert_eq!(rd(&mut e, 0x0130, 2).0, [0x01, 0], "INIT after power-on");
    assert_eq!(wr(&mut e, 0x0120, &[0x02, 0]), 1);
    assert_eq!(e.pop_event(), Some(EscEvent::AlControl));
    assert_eq!(rd(&mut e, 0x0220, 4).0[0] & 1, 1, "AL event request bit 0");
    // Like a mailbox: the next master write is refused until the PDI reads.
    assert_eq!(wr(&mut e, 0x0120, &[0x04, 0]), 0);
    let mut b = [0u8; 2];
    assert!(e.pdi_read(0x0120, &mut b));
    assert_eq!(b, [0x02, 0]);
    assert_eq!(rd(&mut e, 0x0220, 4).0[0] & 1, 0, "PDI read clears the event");
    assert_eq!(wr(&mut e, 0x0120, &[0x04, 0]), 1);
}

#[test]
fn al_status_is_written_by_the_pdi_and_signalled_to_the_master() {
    let mut e = addressed();
    assert_eq!(wr(&mut e, 0x0130, &[0x08, 0]), 1, "counts, but read-only for the master");
    assert_eq!(rd(&mut e, 0x0130, 2).0, [0x01, 0]);
    assert!(e.pdi_write(0x0130, &[0x12, 0]));
    assert!(e.pdi_write(0x0134, &[0x16, 0]));
    let (d, wkc) = rd(&mut e, 0x0130, 6);
    assert_eq!((d, wkc), (alloc::vec![0x12, 0, 0, 0, 0x16, 0], 1));
    // ECAT event "AL status changed" set, and cleared by that read.
    assert_eq!(rd(&mut e, 0x0210, 2).0[0] & 0x08, 0);
    e.pdi_write(0x0130, &[0x02, 0]);
    assert_eq!(rd(&mut e, 0x0210, 2).0[0] & 0x08, 0x08);
    // The PDI cannot write AL control.
    assert!(e.pdi_write(0x0120, &[0x08, 0]));
    let mut b = [0u8; 1];
    e.pdi_read(0x0120, &mut b);
    assert_eq!(b[0], 0x01);
}

#[test]
fn device_emulation_copies_al_control_to_al_status() {
    let img = SiiImage::builder().config(ConfigArea { pdi_control: 0x0100, ..Default::default() }).build();
    let mut e = Esc::new(EscConfig::with_sii(img));
    assert!(e.device_emulation());
    xfer(&mut e, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10], 0);
    wr(&mut e, 0x0120, &[0x18, 0]);
    assert_eq!(rd(&mut e, 0x0130, 2).0, [0x08, 0], "state copied, acknowledge bit not");
    assert_eq!(wr(&mut e, 0x0120, &[0x02, 0]), 1, "no mailbox behaviour");
    assert_eq!(e.pop_event(), None);
}

#[test]
fn pdi_control_and_config_come_from_sii_and_are_read_only() {
    let img = SiiImage::builder()
        .config(ConfigArea {
            pdi_control: 0x0005,
            pdi_config: 0x1234,
            sync_impulse_len: 100,
            pdi_config2: 0x5678,
            station_alias: 9,
        })
        .build();
    let mut e = Esc::new(EscConfig::with_sii(img));
    xfer(&mut e, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10], 0);
    assert_eq!(rd(&mut e, 0x0140, 2).0, [0x05, 0x00]);
    assert_eq!(rd(&mut e, 0x0150, 4).0, [0x34, 0x12, 0x78, 0x56]);
    assert_eq!(rd(&mut e, 0x0982, 2).0, [100, 0]);
    wr(&mut e, 0x0140, &[0xFF, 0xFF]);
    assert_eq!(rd(&mut e, 0x0140, 2).0, [0x05, 0x00]);
}

#[test]
fn dl_status_reports_links_loops_and_pdi_state() {
    let mut e = addressed();
    // Port 0 link, ports 1-3 closed, EEPROM loaded, PDI watchdog fine.
    assert_eq!(rd(&mut e, 0x0110, 2).0, [0x13, 0x56]);
    e.set_port_links([true, true, false, false]);
    assert_eq!(e.pop_event(), Some(EscEvent::DlStatusChanged));
    assert_eq!(rd(&mut e, 0x0110, 2).0, [0x33, 0x5A]);
    assert!(e.port_open(1));
    // DL control: force port 1 closed.
    wr(&mut e, 0x0101, &[0b0000_1100]);
    assert!(!e.port_open(1));
    assert_eq!(rd(&mut e, 0x0110, 2).0[1] & 0x04, 0x04);
    // Losing a link counts in the lost link counter; writing clears it.
    e.set_port_links([true, false, false, false]);
    assert_eq!(rd(&mut e, 0x0311, 1).0, [1]);
    wr(&mut e, 0x0311, &[0]);
    assert_eq!(rd(&mut e, 0x0311, 1).0, [0]);
    // Port descriptor: two MII ports.
    assert_eq!(rd(&mut e, 0x0007, 1).0, [0x0F]);
}

#[test]
fn error_counters_clear_as_a_group() {
    let mut e = addressed();
    e.mem[0x0300] = 5;
    e.mem[0x0309] = 7;
    assert_eq!(wr(&mut e, 0x0301, &[0]), 1);
    assert_eq!(rd(&mut e, 0x0300, 12).0, [0; 12]);
}

#[test]
fn esc_reset_needs_r_e_s_in_consecutive_frames() {
    let mut e = addressed();
    wr(&mut e, 0x0F80, &[0x77]);
    wr(&mut e, 0x0040, b"R");
    rd(&mut e, 0x0000, 1); // an unrelated frame breaks the sequence
    wr(&mut e, 0x0040, b"E");
    wr(&mut e, 0x0040, b"S");
    assert_eq!(rd(&mut e, 0x0F80, 1).0, [0x77]);
    wr(&mut e, 0x0040, b"R");
    wr(&mut e, 0x0040, b"E");
    wr(&mut e, 0x0040, b"S");
    assert_eq!(e.station_address(), 0, "registers back to reset values");
    assert_eq!(e.pop_event(), Some(EscEvent::EscReset));
}
