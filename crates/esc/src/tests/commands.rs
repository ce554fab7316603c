//! Addressing, working counter and frame-level rules.

use super::*;
use crate::esc::FrameTiming;
use crate::fmmu::Fmmu;
use proptest::prelude::*;

#[test]
fn brd_ors_the_type_and_counts() {
    let mut e = esc();
    let (d, wkc, adp) = xfer(&mut e, DatagramCommand::Brd, station_address(0, 0x0000), &[0x80, 0x00], 0);
    assert_eq!(d, [0x84, 0x03], "type 0x04 ORed onto 0x80, revision 3");
    assert_eq!(wkc, 1);
    assert_eq!(adp, 1, "broadcasts increment ADP");
}

#[test]
fn auto_increment_acts_only_at_zero_and_always_increments() {
    let mut e = esc();
    let (_, wkc, adp) = xfer(&mut e, DatagramCommand::Apwr, position_address(1, 0x0010), &[0x34, 0x12], 0);
    assert_eq!((wkc, adp), (0, 0), "position 1: not me, ADP -1 -> 0");
    assert_eq!(e.station_address(), 0);
    let (_, wkc, adp) = xfer(&mut e, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x34, 0x12], 0);
    assert_eq!((wkc, adp), (1, 1));
    assert_eq!(e.station_address(), 0x1234);
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Aprd, position_address(0, 0x0010), &[0, 0], 0);
    assert_eq!((d, wkc), (alloc::vec![0x34, 0x12], 1));
}

#[test]
fn configured_address_and_alias() {
    let mut e = addressed();
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Fprd, station_address(0x1001, 0x0000), &[0xAA], 0);
    assert_eq!((d, wkc), (alloc::vec![0xAA], 0), "other station: untouched");
    // The alias from SII word 4 is loaded but not enabled.
    assert_eq!(rd(&mut e, 0x0012, 2).0, [0x55, 0x00]);
    let (_, wkc, _) = xfer(&mut e, DatagramCommand::Fprd, station_address(0x0055, 0x0000), &[0], 0);
    assert_eq!(wkc, 0);
    assert_eq!(wr(&mut e, 0x0103, &[1]), 1);
    let (_, wkc, _) = xfer(&mut e, DatagramCommand::Fprd, station_address(0x0055, 0x0000), &[0], 0);
    assert_eq!(wkc, 1, "DL control bit 24 enables the alias");
    // The master cannot write the alias register.
    wr(&mut e, 0x0012, &[1, 2]);
    assert_eq!(rd(&mut e, 0x0012, 2).0, [0x55, 0x00]);
}

#[test]
fn read_write_commands_read_old_and_store_new() {
    let mut e = addressed();
    wr(&mut e, 0x0F80, &[1, 2]);
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Fprw, station_address(0x1000, 0x0F80), &[7, 8], 0);
    assert_eq!((d, wkc), (alloc::vec![1, 2], 3));
    assert_eq!(rd(&mut e, 0x0F80, 2).0, [7, 8]);
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Aprw, position_address(0, 0x0F80), &[9, 9], 0);
    assert_eq!((d, wkc), (alloc::vec![7, 8], 3));
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Brw, station_address(0, 0x0F80), &[0x10, 0], 0);
    assert_eq!((d, wkc), (alloc::vec![0x19, 0x09], 3), "BRW ORs the read data");
    assert_eq!(rd(&mut e, 0x0F80, 2).0, [0x10, 0]);
    assert_eq!(xfer(&mut e, DatagramCommand::Bwr, station_address(0, 0x0F80), &[5], 0).1, 1);
}

#[test]
fn rmw_addressed_slave_reads_others_write() {
    let mut e = addressed();
    wr(&mut e, 0x0F80, &[0x11; 4]);
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Frmw, station_address(0x1000, 0x0F80), &[0; 4], 0);
    assert_eq!((d, wkc), (alloc::vec![0x11; 4], 1));
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Frmw, station_address(0x2000, 0x0F80), &[0x22; 4], 0);
    assert_eq!((d, wkc), (alloc::vec![0x22; 4], 1));
    assert_eq!(rd(&mut e, 0x0F80, 4).0, [0x22; 4]);
    let (_, wkc, adp) = xfer(&mut e, DatagramCommand::Armw, position_address(0, 0x0F80), &[0; 4], 0);
    assert_eq!((wkc, adp), (1, 1));
    let (_, wkc, _) = xfer(&mut e, DatagramCommand::Armw, position_address(2, 0x0F80), &[0x33; 4], 0);
    assert_eq!(wkc, 1);
    assert_eq!(rd(&mut e, 0x0F80, 4).0, [0x33; 4]);
}

#[test]
fn read_only_writes_count_but_change_nothing() {
    let mut e = addressed();
    assert_eq!(wr(&mut e, 0x0000, &[0xFF; 8]), 1, "register space always counts");
    assert_eq!(rd(&mut e, 0x0000, 1).0, [0x04]);
    // Reserved register: reads 0, writes ignored.
    assert_eq!(wr(&mut e, 0x0020, &[0xFF]), 1);
    assert_eq!(rd(&mut e, 0x0020, 1), (alloc::vec![0], 1));
}

#[test]
fn unimplemented_blocks_do_not_count() {
    let mut e = Esc::new(EscConfig { dc: false, fmmus: 2, ..EscConfig::with_sii(image()) });
    assert_eq!(
        xfer(&mut e, DatagramCommand::Bwr, station_address(0, 0x0900), &[0; 4], 0).1,
        0,
        "no DC: no WKC (ethercrab counts DC slaves so)"
    );
    assert_eq!(
        xfer(&mut e, DatagramCommand::Brd, station_address(0, 0x0008), &[0; 2], 0).0,
        [0, 0],
        "no DC feature bits"
    );
    assert_eq!(
        xfer(&mut e, DatagramCommand::Bwr, station_address(0, 0x0620), &[0xFF; 16], 0).1,
        0,
        "FMMU 2 not implemented"
    );
    assert_eq!(
        xfer(&mut e, DatagramCommand::Bwr, station_address(0, 0x0610), &[0; 32], 0).1,
        1,
        "FMMU 1 exists"
    );
    let mut e = esc();
    assert_eq!(xfer(&mut e, DatagramCommand::Brd, station_address(0, 0x0008), &[0; 2], 0).0, [0x0C, 0x01]);
}

#[test]
fn nop_and_reserved_commands_pass_untouched() {
    let mut e = addressed();
    let mut buf = [0u8; 128];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push_raw(0, 1, station_address(0x1000, 0), &[9, 9], 5).unwrap();
    b.push_raw(0x20, 2, station_address(0x1000, 0), &[9, 9], 5).unwrap();
    let n = b.finish();
    let before = buf;
    let r = e.process_frame(&mut buf[..n], Instant::ZERO);
    assert_eq!(r.datagrams, 2);
    assert_eq!(&buf[14..n], &before[14..n]);
}

fn set_fmmu(e: &mut Esc, n: u16, f: Fmmu) {
    assert_eq!(wr(e, 0x0600 + n * 16, &f.to_registers()), 1);
}

fn byte_fmmu(logical: u32, len: u16, phys: u16, read: bool, write: bool) -> Fmmu {
    Fmmu {
        logical_start: logical,
        length: len,
        logical_start_bit: 0,
        logical_stop_bit: 7,
        physical_start: phys,
        physical_start_bit: 0,
        read,
        write,
        enabled: true,
    }
}

#[test]
fn logical_wkc_is_one_for_read_two_for_write_at_most_three() {
    let mut e = addressed();
    set_fmmu(&mut e, 0, byte_fmmu(0x100, 2, 0x1400, false, true));
    set_fmmu(&mut e, 1, byte_fmmu(0x102, 2, 0x1500, true, false));
    set_fmmu(&mut e, 2, byte_fmmu(0x104, 2, 0x1600, true, false));
    e.pdi_write(0x1500, &[0xA1, 0xA2]);
    e.pdi_write(0x1600, &[0xB1, 0xB2]);
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Lrw, 0x100, &[1, 2, 0, 0, 0, 0], 0);
    assert_eq!(wkc, 3, "two read FMMUs and a write FMMU still give 3");
    assert_eq!(d, [1, 2, 0xA1, 0xA2, 0xB1, 0xB2]);
    let mut m = [0u8; 2];
    e.pdi_read(0x1400, &mut m);
    assert_eq!(m, [1, 2]);
    assert_eq!(xfer(&mut e, DatagramCommand::Lwr, 0x100, &[3, 4], 0).1, 2);
    assert_eq!(xfer(&mut e, DatagramCommand::Lrd, 0x102, &[0, 0], 0).1, 1);
    assert_eq!(xfer(&mut e, DatagramCommand::Lrd, 0x100, &[0, 0], 0).1, 0, "read of a write-only FMMU");
    assert_eq!(xfer(&mut e, DatagramCommand::Lrw, 0x900, &[0; 4], 0).1, 0, "no FMMU hit");
}

#[test]
fn lrw_reads_memory_as_it_was_before_the_write() {
    let mut e = addressed();
    // Same physical byte mapped for write (logical 0) and read (logical 1).
    set_fmmu(&mut e, 0, byte_fmmu(0, 1, 0x1400, false, true));
    set_fmmu(&mut e, 1, byte_fmmu(1, 1, 0x1400, true, false));
    e.pdi_write(0x1400, &[0x11]);
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Lrw, 0, &[0x22, 0], 0);
    assert_eq!((d, wkc), (alloc::vec![0x22, 0x11], 3));
    let (d, _, _) = xfer(&mut e, DatagramCommand::Lrd, 1, &[0], 0);
    assert_eq!(d, [0x22]);
}

#[test]
fn fmmu_maps_register_space_and_single_bits() {
    let mut e = addressed();
    // SOEM 2.0: the SM1 status byte 0x080D through an FMMU.
    set_fmmu(&mut e, 3, byte_fmmu(0x2000, 1, 0x080D, true, false));
    wr(&mut e, 0x0808, &[0x80, 0x10, 4, 0, 0x22, 0, 1, 0]);
    e.pdi_write(0x1080, &[1, 2, 3, 4]);
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Lrd, 0x2000, &[0], 0);
    assert_eq!((d[0] & 0x08, wkc), (0x08, 1), "mailbox full seen through the FMMU");
    // Logical bits 2..=4 of byte 0x3000 -> 0x0F00 bits 5..=7.
    set_fmmu(
        &mut e,
        4,
        Fmmu {
            logical_start: 0x3000,
            length: 1,
            logical_start_bit: 2,
            logical_stop_bit: 4,
            physical_start: 0x0F00,
            physical_start_bit: 5,
            read: true,
            write: true,
            enabled: true,
        },
    );
    wr(&mut e, 0x0F00, &[0x0F]);
    let (d, wkc, _) = xfer(&mut e, DatagramCommand::Lrw, 0x3000, &[0b0001_0100], 0);
    assert_eq!(wkc, 3);
    assert_eq!(d, [0], "bits 2..=4 read back the old 0x0F00 bits 5..=7 (0)");
    assert_eq!(rd(&mut e, 0x0F00, 1).0, [0b1010_1111]);
}

#[test]
fn irq_field_carries_masked_ecat_events() {
    let mut e = addressed();
    e.set_port_links([true, true, false, false]); // DL status change event
    let mut buf = [0u8; 64];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(DatagramCommand::Nop, 0, 0, &[]).unwrap();
    let n = b.finish();
    e.process_frame(&mut buf[..n], Instant::ZERO);
    assert_eq!(u16::from_le_bytes([buf[24], buf[25]]), 0, "masked off by default");
    wr(&mut e, 0x0200, &[0x04, 0]);
    let mut buf = [0u8; 64];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(DatagramCommand::Nop, 0, 0, &[]).unwrap();
    let n = b.finish();
    e.process_frame(&mut buf[..n], Instant::ZERO);
    assert_eq!(u16::from_le_bytes([buf[24], buf[25]]), 0x0004);
    // Reading DL status clears the event.
    rd(&mut e, 0x0110, 2);
    assert_eq!(rd(&mut e, 0x0210, 2).0, [0, 0]);
}

#[test]
fn truncated_frame_stops_at_the_bad_datagram() {
    let mut e = addressed();
    let mut buf = [0u8; 128];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(DatagramCommand::Fpwr, 1, station_address(0x1000, 0x0F80), &[0xAB]).unwrap();
    b.push(DatagramCommand::Fpwr, 2, station_address(0x1000, 0x0F81), &[0xCD]).unwrap();
    b.finish();
    // Claim the second datagram is 100 bytes long: it no longer fits.
    let second = 14 + 2 + 13;
    buf[second + 6] = 100;
    let before = buf;
    let mut payload = buf[14..14 + 2 + 26].to_vec();
    let r = e.process_ethercat(&mut payload, &FrameTiming::at(Instant::ZERO));
    assert!(r.malformed);
    assert_eq!(r.datagrams, 1);
    assert_eq!(&payload[15..], &before[29..14 + 28], "second datagram untouched");
    assert_eq!(rd(&mut e, 0x0F80, 2).0, [0xAB, 0]);
    assert_eq!(rd(&mut e, 0x030C, 1).0, [1], "processing unit error counter");
    assert_eq!(wr(&mut e, 0x030C, &[0]), 1);
    assert_eq!(rd(&mut e, 0x030C, 1).0, [0], "written: cleared");
}

#[test]
fn non_ethercat_frames_are_ignored() {
    let mut e = esc();
    let mut f = [0u8; 60];
    f[12] = 0x08;
    let r = e.process_frame(&mut f, Instant::ZERO);
    assert!(r.ignored);
    assert_eq!(f[6], 0, "source MAC untouched");
    // EtherCAT header type other than 1.
    let mut p = [0x00, 0x40, 0, 0];
    assert!(e.process_ethercat(&mut p, &FrameTiming::at(Instant::ZERO)).ignored);
}

proptest! {
    #[test]
    fn arbitrary_payloads_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let mut e = addressed();
        let mut p = bytes.clone();
        let _ = e.process_ethercat(&mut p, &FrameTiming::at(Instant::ZERO));
        let mut f = alloc::vec![0u8; 14];
        f[12] = 0x88;
        f[13] = 0xA4;
        f.extend_from_slice(&bytes);
        let _ = e.process_frame(&mut f, Instant::from_millis(1));
        e.poll(Instant::from_millis(2));
    }
}

/// The traffic counters: every frame and datagram, and the working
/// counter increments exactly as the frames carry them.
#[test]
fn traffic_counts_frames_datagrams_and_working_counter() {
    let mut e = addressed();
    let before = e.traffic();
    let (_, w1, _) = xfer(&mut e, DatagramCommand::Fprd, station_address(0x1001, 0x0000), &[0], 0);
    let (_, w2, _) = xfer(&mut e, DatagramCommand::Fprw, station_address(0x1000, 0x0F80), &[7, 8], 0);
    let (_, w3, _) = xfer(&mut e, DatagramCommand::Brd, station_address(0, 0x0000), &[0], 0);
    assert_eq!((w1, w2, w3), (0, 3, 1));
    let t = e.traffic();
    assert_eq!(t.frames - before.frames, 3);
    assert_eq!(t.datagrams - before.datagrams, 3);
    assert_eq!(t.wkc - before.wkc, 4);
}
