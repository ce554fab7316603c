//! Process-data and PDI watchdogs (0x0400–0x0443).

use super::*;
use crate::EscEvent;

#[test]
fn sm_write_arms_the_process_data_watchdog_which_expires() {
    let mut e = addressed();
    // Divider 2498 -> 100 us units; 10 units = 1 ms.
    wr(&mut e, 0x0420, &[10, 0]);
    wr(&mut e, 0x0810, &[0x00, 0x11, 1, 0, 0x44, 0, 1, 0]);
    while e.pop_event().is_some() {}
    assert_eq!(e.poll(Instant::ZERO), e.wd.pdi_deadline, "not armed before the first write");
    xfer(&mut e, DatagramCommand::Fpwr, station_address(0x1000, 0x1100), &[1], 1_000);
    assert_eq!(e.wd.pd_deadline, Some(Instant::from_micros(2_000)));
    xfer(&mut e, DatagramCommand::Fpwr, station_address(0x1000, 0x1100), &[1], 1_500);
    e.poll(Instant::from_micros(2_400));
    assert_eq!(rd(&mut e, 0x0440, 1).0, [1]);
    e.poll(Instant::from_micros(2_500));
    let evs: Vec<_> = core::iter::from_fn(|| e.pop_event()).collect();
    assert!(evs.contains(&EscEvent::ProcessDataWatchdog));
    assert_eq!(rd(&mut e, 0x0440, 1).0, [0], "expired");
    assert_eq!(rd(&mut e, 0x0442, 1).0, [1], "counter");
    assert_eq!(rd(&mut e, 0x0220, 1).0[0] & 0x40, 0x40);
    let mut b = [0u8];
    e.pdi_read(0x0440, &mut b);
    assert_eq!(rd(&mut e, 0x0220, 1).0[0] & 0x40, 0, "PDI read clears the AL event");
    wr(&mut e, 0x0443, &[0]);
    assert_eq!(rd(&mut e, 0x0442, 2).0, [0, 0], "writing a counter clears both");
    // A new write re-arms and the status is good again.
    xfer(&mut e, DatagramCommand::Fpwr, station_address(0x1000, 0x1100), &[1], 3_000);
    assert_eq!(rd(&mut e, 0x0440, 1).0, [1]);
    // Time 0 disables it.
    wr(&mut e, 0x0420, &[0, 0]);
    assert_eq!(e.wd.pd_deadline, None);
}

#[test]
fn pdi_watchdog_expires_without_pdi_access() {
    let mut e = addressed();
    wr(&mut e, 0x0410, &[5, 0]); // 500 us
    e.pdi_write(0x0F80, &[0]);
    assert_eq!(e.poll(Instant::ZERO), Some(Instant::from_micros(500)));
    e.poll(Instant::from_micros(500));
    assert_eq!(rd(&mut e, 0x0110, 1).0[0] & 0x02, 0, "DL status: PDI watchdog expired");
    assert_eq!(rd(&mut e, 0x0443, 1).0, [1]);
    let evs: Vec<_> = core::iter::from_fn(|| e.pop_event()).collect();
    assert!(evs.contains(&EscEvent::PdiWatchdog));
    e.pdi_write(0x0F80, &[0]);
    assert_eq!(rd(&mut e, 0x0110, 1).0[0] & 0x02, 0x02);
}
