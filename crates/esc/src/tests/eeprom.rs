//! The SII interface through frames, as ethercrab and SOEM drive it.

use super::*;
use crate::{EscEvent, SiiTiming};
use drivebus_base::Duration;

fn sii_read(e: &mut Esc, word: u16) -> Vec<u8> {
    // ethercrab: control + address + 2 pad bytes in one 6-byte FPWR.
    let w = wr(e, 0x0502, &[0x00, 0x01, word as u8, (word >> 8) as u8, 0, 0]);
    assert_eq!(w, 1);
    let (ctl, _) = rd(e, 0x0502, 2);
    assert_eq!(ctl[1] & 0x80, 0, "not busy with zero read time");
    let len = if ctl[0] & 0x40 != 0 { 8 } else { 4 };
    rd(e, 0x0508, len).0
}

#[test]
fn ethercrab_style_reads_return_image_words() {
    let mut e = addressed();
    // Owner dance: 2 (force ECAT), then 0.
    assert_eq!(wr(&mut e, 0x0500, &[2, 0]), 1);
    assert_eq!(wr(&mut e, 0x0500, &[0]), 1);
    let img = image();
    let got = sii_read(&mut e, 0x0008);
    assert_eq!(got, img.bytes()[16..24].to_vec(), "identity words 8..11");
    assert_eq!(sii_read(&mut e, 0x0040), img.bytes()[0x80..0x88].to_vec());
}

#[test]
fn four_byte_reads_when_configured() {
    let mut e = Esc::new(EscConfig { sii_8_byte_reads: false, ..EscConfig::with_sii(image()) });
    xfer(&mut e, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10], 0);
    assert_eq!(sii_read(&mut e, 0x0004).len(), 4);
    // Bit 6 is read-only: writing it does not change the read size.
    wr(&mut e, 0x0502, &[0x40, 0x00]);
    assert_eq!(rd(&mut e, 0x0502, 1).0[0] & 0x40, 0);
}

#[test]
fn busy_for_the_configured_time_then_data() {
    let t = SiiTiming { read: Duration::from_micros(30), ..SiiTiming::default() };
    let mut e = Esc::new(EscConfig { sii_timing: t, ..EscConfig::with_sii(image()) });
    xfer(&mut e, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10], 0);
    xfer(&mut e, DatagramCommand::Fpwr, station_address(0x1000, 0x0502), &[0, 1, 8, 0, 0, 0], 100);
    let (ctl, _, _) = xfer(&mut e, DatagramCommand::Fprd, station_address(0x1000, 0x0502), &[0, 0], 110);
    assert_eq!(ctl[1], 0x81, "busy, read command");
    assert_eq!(e.poll(Instant::from_micros(110)), Some(Instant::from_micros(130)), "deadline = end of read");
    // Address writes while busy are ignored.
    xfer(&mut e, DatagramCommand::Fpwr, station_address(0x1000, 0x0504), &[0x40, 0], 120);
    let (ctl, _, _) = xfer(&mut e, DatagramCommand::Fprd, station_address(0x1000, 0x0502), &[0, 0], 130);
    assert_eq!(ctl[1] & 0x80, 0);
    let (d, _, _) = xfer(&mut e, DatagramCommand::Fprd, station_address(0x1000, 0x0508), &[0; 4], 130);
    assert_eq!(d, image().bytes()[16..20].to_vec(), "word 8, not 0x40");
}

#[test]
fn alias_write_persists_in_the_image_and_reload_applies_it() {
    let mut e = addressed();
    // ethercrab's write_word: data first, then control (write enable + write) + address.
    assert_eq!(wr(&mut e, 0x0508, &[0x34, 0x12]), 1);
    assert_eq!(wr(&mut e, 0x0502, &[0x01, 0x02, 4, 0, 0, 0]), 1);
    assert_eq!(rd(&mut e, 0x0502, 2).0[1] & 0xF8, 0, "no error, not busy");
    assert!(e.take_sii_dirty());
    assert!(!e.take_sii_dirty());
    assert_eq!(e.sii_image().word(4), 0x1234);
    assert_eq!(e.pop_event(), Some(EscEvent::SiiWritten));
    // The CRC no longer matches until the master rewrites word 7.
    assert_eq!(rd(&mut e, 0x0012, 2).0, [0x55, 0], "alias register unchanged before reload");
    let crc = crate::sii::config_crc(&e.sii_image().bytes()[..14]);
    wr(&mut e, 0x0508, &[crc, 0]);
    wr(&mut e, 0x0502, &[0x01, 0x02, 7, 0, 0, 0]);
    // Reload.
    wr(&mut e, 0x0502, &[0x00, 0x04]);
    assert_eq!(rd(&mut e, 0x0012, 2).0, [0x34, 0x12]);
    assert_eq!(rd(&mut e, 0x0502, 2).0[1] & 0x18, 0, "checksum fine");
    let mut evs = Vec::new();
    while let Some(ev) = e.pop_event() {
        evs.push(ev);
    }
    assert!(evs.contains(&EscEvent::SiiReloaded));
}

#[test]
fn write_without_enable_is_an_error_and_enable_clears_each_frame() {
    let mut e = addressed();
    wr(&mut e, 0x0502, &[0x01]); // enable in one frame…
    wr(&mut e, 0x0502, &[0x00, 0x02, 4, 0]); // …is gone in the next
    assert_eq!(rd(&mut e, 0x0502, 2).0[1] & 0x40, 0x40, "write enable error");
    // "No command" clears the error bits.
    wr(&mut e, 0x0502, &[0x00, 0x00]);
    assert_eq!(rd(&mut e, 0x0502, 2).0[1], 0);
    wr(&mut e, 0x0502, &[0x00, 0x07]);
    assert_eq!(rd(&mut e, 0x0502, 2).0[1] & 0x20, 0x20, "invalid command");
}

#[test]
fn bad_checksum_reports_errors_and_skips_the_alias() {
    let mut img = image();
    img.bytes_mut()[14] ^= 0xFF;
    let mut e = Esc::new(EscConfig::with_sii(img));
    xfer(&mut e, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10], 0);
    assert_eq!(rd(&mut e, 0x0502, 2).0[1] & 0x18, 0x18, "checksum + device info error");
    assert_eq!(rd(&mut e, 0x0012, 2).0, [0, 0]);
    assert_eq!(rd(&mut e, 0x0110, 1).0[0] & 1, 0, "PDI not operational");
}

#[test]
fn pdi_ownership_locks_out_the_master() {
    let mut e = addressed();
    wr(&mut e, 0x0500, &[1]); // offer to PDI
    assert!(e.pdi_write(0x0501, &[1])); // PDI takes it
    wr(&mut e, 0x0502, &[0x00, 0x01, 8, 0]);
    assert_eq!(rd(&mut e, 0x0504, 2).0, [0, 0], "master writes ignored");
    // The PDI can use it.
    assert!(e.pdi_write(0x0504, &[8, 0, 0, 0]));
    assert!(e.pdi_write(0x0502, &[0x00, 0x01]));
    let mut d = [0u8; 4];
    e.pdi_read(0x0508, &mut d);
    assert_eq!(&d[..], &image().bytes()[16..20]);
    // Force ECAT takes it back.
    wr(&mut e, 0x0500, &[2]);
    assert_eq!(rd(&mut e, 0x0501, 1).0, [0]);
    wr(&mut e, 0x0502, &[0x00, 0x01, 9, 0]);
    assert_eq!(rd(&mut e, 0x0504, 2).0, [9, 0]);
}
