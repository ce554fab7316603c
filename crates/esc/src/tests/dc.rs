//! Distributed clocks through frames.

use super::*;
use crate::EscEvent;
use crate::dc::ClockConfig;
use crate::esc::FrameTiming;

fn dc_esc(offset: u64, drift_ppb: i32) -> Esc {
    let mut e = Esc::new(EscConfig {
        clock: ClockConfig { offset_ns: offset, drift_ppb },
        ..EscConfig::with_sii(image())
    });
    xfer(&mut e, DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10], 0);
    e
}

fn frame_at(e: &mut Esc, timing: FrameTiming, cmd: DatagramCommand, ado: u16, data: &[u8]) -> (Vec<u8>, u16) {
    let mut buf = [0u8; 128];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(cmd, 1, station_address(0x1000, ado), data).unwrap();
    let n = b.finish();
    e.process_ethercat(&mut buf[14..n], &timing);
    let d = datagrams(&buf[14..n]).next().unwrap();
    (d.data.to_vec(), d.wkc)
}

#[test]
fn write_to_0x0900_latches_port_and_processing_unit_times() {
    let mut e = dc_esc(1_000_000, 0);
    let t0 = Instant::from_micros(100);
    let t1 = Instant::from_nanos(100_000 + 740);
    let timing = FrameTiming { at: t0, port_rx: [Some(t0), Some(t1), None, None] };
    let (_, wkc) = frame_at(&mut e, timing, DatagramCommand::Bwr, 0x0900, &[0; 4]);
    assert_eq!(wkc, 1);
    let (d, _) = rd(&mut e, 0x0900, 16);
    let p0 = u32::from_le_bytes(d[0..4].try_into().unwrap());
    let p1 = u32::from_le_bytes(d[4..8].try_into().unwrap());
    assert_eq!(p0, 1_100_000);
    assert_eq!(p1 - p0, 740);
    assert_eq!(&d[8..16], &[0; 8], "ports 2/3 saw nothing");
    let (d, _) = rd(&mut e, 0x0918, 8);
    assert_eq!(u64::from_le_bytes(d.try_into().unwrap()), 1_100_000);
    // Writes to the receive time registers do not change them.
    wr(&mut e, 0x0904, &[0xFF; 4]);
    assert_eq!(rd(&mut e, 0x0904, 4).0, p1.to_le_bytes());
}

#[test]
fn system_time_is_local_plus_offset() {
    let mut e = dc_esc(500, 0);
    wr(&mut e, 0x0920, &10_000u64.to_le_bytes());
    let (d, _, _) = xfer(&mut e, DatagramCommand::Fprd, station_address(0x1000, 0x0910), &[0; 8], 7);
    assert_eq!(u64::from_le_bytes(d.try_into().unwrap()), 500 + 7_000 + 10_000);
}

/// A reference ESC and a drifting follower `delay` ns downstream, synced
/// by FRMW every `cycle` ns as ethercrab does.
#[test]
fn frmw_samples_make_the_follower_converge() {
    let mut reference = dc_esc(5_000_000, 0);
    let mut follower = dc_esc(123_456_789, -60_000); // 60 ppm slow
    let delay = 850u64;
    // Offsets as a master would set them after the latch: system time ≈ caller ns.
    wr(&mut reference, 0x0920, &(0u64.wrapping_sub(5_000_000)).to_le_bytes());
    let f_local = follower.local_time(Instant::ZERO);
    wr(&mut follower, 0x0920, &(0u64.wrapping_sub(f_local).wrapping_add(3_000)).to_le_bytes());
    wr(&mut follower, 0x0928, &(delay as u32).to_le_bytes());
    let mut t = 1_000_000u64;
    let mut last_err = i64::MAX;
    for i in 0..3000 {
        let at = Instant::from_nanos(t);
        let (sys, w1) = frame_at(&mut reference, FrameTiming::at(at), DatagramCommand::Frmw, 0x0910, &[0; 8]);
        let at_f = Instant::from_nanos(t + delay);
        let mut wrong_station = [0u8; 128];
        let mut b = FrameBuilder::new(&mut wrong_station, [0x10; 6]);
        b.push(DatagramCommand::Frmw, 1, station_address(0x1000 + 1, 0x0910), &sys).unwrap();
        let n = b.finish();
        follower.process_ethercat(&mut wrong_station[14..n], &FrameTiming::at(at_f));
        assert_eq!(w1, 1);
        let r = reference.system_time(at_f);
        let f = follower.system_time(at_f);
        last_err = f as i64 - r as i64;
        if i == 0 {
            assert!(last_err.abs() > 2_000, "starts off by ~3 us: {last_err}");
        }
        t += if i < 1000 { 20_000 } else { 1_000_000 };
    }
    assert!(last_err.abs() < 20, "residual {last_err} ns");
    assert!((follower.clock_correction_ppb() - 60_000).abs() < 2_000, "{}", follower.clock_correction_ppb());
    let (d, _) = rd(&mut follower, 0x092C, 4);
    let diff = u32::from_le_bytes(d.try_into().unwrap());
    assert!(diff & 0x7FFF_FFFF < 50, "filtered difference {diff:#x}");
}

#[test]
fn writing_speed_counter_start_resets_the_loop() {
    let mut e = dc_esc(0, 0);
    xfer(&mut e, DatagramCommand::Bwr, station_address(0, 0x0910), &[0; 8], 1_000);
    assert_ne!(rd(&mut e, 0x092C, 4).0, [0; 4]);
    wr(&mut e, 0x0934, &[0x00, 0x0C]);
    wr(&mut e, 0x0930, &[0x00, 0x10]);
    assert_eq!(rd(&mut e, 0x092C, 4).0, [0; 4]);
    assert_eq!(e.clock_correction_ppb(), 0);
    assert_eq!(rd(&mut e, 0x0930, 2).0, [0x00, 0x10]);
}

fn sync0(e: &mut Esc, start: u64, cycle: u32, activation: u8) {
    wr(e, 0x0981, &[0]);
    wr(e, 0x0990, &start.to_le_bytes());
    wr(e, 0x09A0, &u64::from(cycle).to_le_bytes()); // ethercrab writes 8 bytes
    wr(e, 0x0981, &[activation]);
}

#[test]
fn sync0_pulses_at_exact_system_times() {
    let mut e = dc_esc(0, 25_000); // 25 ppm fast, offset 0: system = local
    sync0(&mut e, 2_000_000, 1_000_000, 0x03);
    assert_eq!(rd(&mut e, 0x0990, 8).0, 2_000_000u64.to_le_bytes(), "next SYNC0");
    let d = e.poll(Instant::ZERO).unwrap();
    assert_eq!(e.system_time(d), 2_000_000, "deadline is the exact pulse instant");
    assert!(e.system_time(Instant::from_nanos(d.as_nanos() - 1)) < 2_000_000);
    e.poll(d);
    match e.pop_event() {
        Some(EscEvent::Sync0 { system_time, at, missed }) => {
            assert_eq!((system_time, at, missed), (2_000_000, d, 0));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(rd(&mut e, 0x098E, 1).0, [1]);
    assert_eq!(rd(&mut e, 0x098E, 1).0, [0], "read clears");
    assert_eq!(rd(&mut e, 0x0990, 8).0, 3_000_000u64.to_le_bytes());
    // Start time is locked while active.
    wr(&mut e, 0x0990, &0u64.to_le_bytes());
    wr(&mut e, 0x0981, &[0]);
    assert_eq!(e.poll(Instant::from_millis(10)), e.wd.pdi_deadline);
}

#[test]
fn start_time_in_the_past_waits_for_the_32_bit_wrap() {
    let mut e = dc_esc(10_000_000, 0);
    sync0(&mut e, 1_000, 1_000_000, 0x03);
    assert_eq!(rd(&mut e, 0x0990, 8).0, (1_000u64 + (1 << 32)).to_le_bytes());
    sync0(&mut e, 1_000, 1_000_000, 0x23);
    while e.pop_event().is_some() {}
    assert_eq!(e.poll(Instant::ZERO), Some(Instant::from_millis(1)), "next one a cycle later");
    assert!(
        matches!(e.pop_event(), Some(EscEvent::Sync0 { system_time: 10_000_000, .. })),
        "plausibility check: the first pulse at once"
    );
}

#[test]
fn sync1_follows_sync0_by_its_cycle_time() {
    let mut e = dc_esc(0, 0);
    sync0(&mut e, 1_000_000, 1_000_000, 0);
    // After the 8-byte SYNC0 cycle write (which zeroes 0x09A4), as ethercrab.
    wr(&mut e, 0x09A4, &250_000u32.to_le_bytes());
    wr(&mut e, 0x0981, &[0x07]);
    e.poll(Instant::from_nanos(1_250_000));
    let evs: Vec<_> = core::iter::from_fn(|| e.pop_event()).collect();
    assert!(evs.iter().any(|e| matches!(e, EscEvent::Sync0 { system_time: 1_000_000, .. })));
    assert!(evs.iter().any(|e| matches!(e, EscEvent::Sync1 { system_time: 1_250_000, .. })));
    assert_eq!(rd(&mut e, 0x098F, 1).0, [1]);
}

#[test]
fn writing_the_start_time_activates_with_auto_activation() {
    let mut e = dc_esc(0, 0);
    wr(&mut e, 0x09A0, &500_000u32.to_le_bytes());
    wr(&mut e, 0x0981, &[0x0A]); // auto-activation + SYNC0, cyclic off
    assert_eq!(e.poll(Instant::ZERO), e.wd.pdi_deadline, "nothing scheduled yet");
    wr(&mut e, 0x0990, &1_000_000u64.to_le_bytes());
    assert_eq!(rd(&mut e, 0x0981, 1).0, [0x0B], "activation bit set by the start time write");
    let d = e.poll(Instant::ZERO).unwrap();
    assert_eq!(e.system_time(d), 1_000_000);
    assert_eq!(rd(&mut e, 0x0984, 1).0, [1], "first pulse pending");
    e.poll(d);
    assert_eq!(rd(&mut e, 0x0984, 1).0, [0]);
}
