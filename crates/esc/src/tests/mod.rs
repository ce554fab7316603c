//! ESC behaviour through frames, register by register.

use crate::frame::{DatagramCommand, FrameBuilder, datagrams, position_address, station_address};
use crate::sii::{SiiImage, SiiSyncManager, fmmu_usage, sm_type};
use crate::{Esc, EscConfig};
use alloc::vec::Vec;
use drivebus_base::Instant;

mod al;
mod commands;
mod dc;
mod eeprom;
mod sync_managers;
mod watchdog;

/// A DIO-like image with a mailbox.
pub(crate) fn image() -> SiiImage {
    SiiImage::builder()
        .identity(0x1A3, 0x2A, 1, 99)
        .station_alias(0x0055)
        .names("Test", "ESC-TEST", "ESC unit test device")
        .fmmus(&[fmmu_usage::OUTPUTS, fmmu_usage::INPUTS])
        .sync_manager(SiiSyncManager {
            start: 0x1000,
            length: 128,
            control: 0x26,
            enable: 1,
            sm_type: sm_type::MAILBOX_OUT,
        })
        .sync_manager(SiiSyncManager {
            start: 0x1080,
            length: 128,
            control: 0x22,
            enable: 1,
            sm_type: sm_type::MAILBOX_IN,
        })
        .build()
}

pub(crate) fn esc() -> Esc {
    Esc::new(EscConfig::with_sii(image()))
}

/// Sends one datagram to `esc` at `t_us` and returns (data, wkc, adp).
pub(crate) fn xfer(
    esc: &mut Esc,
    cmd: DatagramCommand,
    address: u32,
    data: &[u8],
    t_us: u64,
) -> (Vec<u8>, u16, u16) {
    let mut buf = [0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(cmd, 0x42, address, data).unwrap();
    let n = b.finish();
    let r = esc.process_frame(&mut buf[..n], Instant::from_micros(t_us));
    assert!(!r.malformed);
    let d = datagrams(&buf[14..n]).next().unwrap();
    (d.data.to_vec(), d.wkc, d.header.adp())
}

/// FPRD at station 0x1000 (after [`addressed`]).
pub(crate) fn rd(esc: &mut Esc, ado: u16, len: usize) -> (Vec<u8>, u16) {
    let (d, w, _) = xfer(esc, DatagramCommand::Fprd, station_address(0x1000, ado), &alloc::vec![0; len], 0);
    (d, w)
}

/// FPWR at station 0x1000.
pub(crate) fn wr(esc: &mut Esc, ado: u16, data: &[u8]) -> u16 {
    xfer(esc, DatagramCommand::Fpwr, station_address(0x1000, ado), data, 0).1
}

/// An ESC with station address 0x1000.
pub(crate) fn addressed() -> Esc {
    let mut e = esc();
    xfer(&mut e, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10], 0);
    e
}
