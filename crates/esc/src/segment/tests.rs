use super::*;
use crate::frame::{DatagramCommand, FrameBuilder, datagrams, position_address, station_address};
use crate::tests::image;
use crate::{ClockConfig, EscConfig};
use alloc::vec::Vec;
use drivebus_base::Recurrence;

fn line(n: usize) -> Segment<Esc> {
    let escs = (0..n)
        .map(|i| {
            let clock = ClockConfig { offset_ns: 1_000_000 * i as u64 + 17, drift_ppb: 0 };
            Esc::new(EscConfig { clock, ..EscConfig::with_sii(image()) })
        })
        .collect();
    Segment::with_devices(SegmentConfig::default(), escs)
}

/// One datagram through the segment; returns (data, wkc, report).
fn send(
    s: &mut Segment<Esc>,
    cmd: DatagramCommand,
    addr: u32,
    data: &[u8],
    t_us: u64,
) -> (Vec<u8>, u16, SegmentReport) {
    let mut buf = [0u8; 256];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(cmd, 9, addr, data).unwrap();
    let n = b.finish();
    let r = s.process_frame(&mut buf[..n], Instant::from_micros(t_us));
    let d = datagrams(&buf[14..n]).next().unwrap();
    (d.data.to_vec(), d.wkc, r)
}

fn address_all(s: &mut Segment<Esc>) {
    for i in 0..s.len() as u16 {
        let a = 0x1000 + i;
        assert_eq!(send(s, DatagramCommand::Apwr, position_address(i, 0x0010), &a.to_le_bytes(), 0).1, 1);
    }
}

#[test]
fn every_slave_counts_and_positions_increment() {
    let mut s = line(4);
    let (_, wkc, r) = send(&mut s, DatagramCommand::Brd, station_address(0, 0), &[0], 0);
    assert_eq!((wkc, r.reached), (4, 4));
    address_all(&mut s);
    for i in 0..4 {
        assert_eq!(s.device(i).unwrap().station_address(), 0x1000 + i as u16);
    }
    let (_, wkc, _) = send(&mut s, DatagramCommand::Fprd, station_address(0x1002, 0x0010), &[0, 0], 0);
    assert_eq!(wkc, 1);
}

#[test]
fn dl_status_first_slaves_two_ports_last_one() {
    let mut s = line(3);
    address_all(&mut s);
    let dl = |s: &mut Segment<Esc>, a: u16| {
        let (d, _, _) = send(s, DatagramCommand::Fprd, station_address(a, 0x0110), &[0, 0], 0);
        u16::from_le_bytes([d[0], d[1]])
    };
    assert_eq!(dl(&mut s, 0x1000) & 0x00F0, 0x0030, "ports 0 and 1 linked");
    assert_eq!(dl(&mut s, 0x1001) & 0x00F0, 0x0030);
    assert_eq!(dl(&mut s, 0x1002) & 0x00F0, 0x0010, "last slave: port 0 only");
}

#[test]
fn cable_break_hides_downstream_slaves_and_counts_lost_links() {
    let mut s = line(4);
    address_all(&mut s);
    s.set_cable(1, false);
    let (_, wkc, r) = send(&mut s, DatagramCommand::Brd, station_address(0, 0), &[0], 0);
    assert_eq!((wkc, r.reached), (2, 2));
    let (d, _, _) = send(&mut s, DatagramCommand::Fprd, station_address(0x1001, 0x0311), &[0], 0);
    assert_eq!(d, [1], "slave 1 lost the link on port 1");
    s.set_cable(1, true);
    assert_eq!(send(&mut s, DatagramCommand::Brd, station_address(0, 0), &[0], 0).1, 4);
    // Remove slave 2: the line closes up.
    let removed = s.remove(2).unwrap();
    assert_eq!(removed.station_address(), 0x1002);
    assert_eq!(send(&mut s, DatagramCommand::Brd, station_address(0, 0), &[0], 0).1, 3);
    s.insert(0, Esc::new(EscConfig::with_sii(image())));
    assert_eq!(send(&mut s, DatagramCommand::Fprd, station_address(0x1000, 0), &[0], 0).1, 1);
    assert_eq!(send(&mut s, DatagramCommand::Aprd, position_address(1, 0x0010), &[0, 0], 0).0, [0x00, 0x10]);
}

#[test]
fn dl_control_loop_closed_stops_forwarding() {
    let mut s = line(3);
    address_all(&mut s);
    // Close port 1 of slave 0 (0x0101 bits 3:2 = 11).
    send(&mut s, DatagramCommand::Fpwr, station_address(0x1000, 0x0101), &[0x0C], 0);
    assert_eq!(send(&mut s, DatagramCommand::Brd, station_address(0, 0), &[0], 0).1, 1);
}

/// The master's propagation delay computation (ethercrab dc.rs: halve the
/// port 1 − port 0 difference between neighbours) gives link + esc delay.
#[test]
fn port_receive_times_give_consistent_delays() {
    let n = 5;
    let mut s = line(n);
    address_all(&mut s);
    let (_, wkc, r) = send(&mut s, DatagramCommand::Bwr, station_address(0, 0x0900), &[0; 4], 50);
    assert_eq!(wkc, n as u16);
    let cfg = SegmentConfig::default();
    let hop = (cfg.link_delay + cfg.esc_delay).as_nanos() as u64;
    let mut totals = Vec::new();
    let mut rx_pu = Vec::new();
    for i in 0..n as u16 {
        let (d, _, _) =
            send(&mut s, DatagramCommand::Fprd, station_address(0x1000 + i, 0x0900), &[0; 16], 60);
        let p0 = u32::from_le_bytes(d[0..4].try_into().unwrap());
        let p1 = u32::from_le_bytes(d[4..8].try_into().unwrap());
        totals.push(if i + 1 < n as u16 { p1.wrapping_sub(p0) as u64 } else { 0 });
        let (d, _, _) = send(&mut s, DatagramCommand::Fprd, station_address(0x1000 + i, 0x0918), &[0; 8], 60);
        rx_pu.push(u64::from_le_bytes(d.try_into().unwrap()));
    }
    for i in 0..n - 1 {
        assert_eq!((totals[i] - totals[i + 1]) / 2, hop, "slave {i} -> {}", i + 1);
    }
    // Each ESC latched its own local time (offset i ms) of its arrival.
    for (i, t) in rx_pu.iter().enumerate() {
        assert_eq!(*t, 1_000_000 * i as u64 + 17 + 50_000 + 300 + hop * i as u64);
    }
    // n hops out and back, 2n - 1 passes through an ESC.
    let esc = cfg.esc_delay.as_nanos() as u64;
    assert_eq!(r.returns_at.as_nanos(), 50_000 + 2 * (n as u64) * hop - esc, "round trip");
}

#[test]
fn frmw_distributes_the_reference_time_down_the_line() {
    let mut s = line(3);
    address_all(&mut s);
    let (d, wkc, _) = send(&mut s, DatagramCommand::Frmw, station_address(0x1000, 0x0910), &[0; 8], 100);
    assert_eq!(wkc, 3, "reference reads, two followers write");
    let reference = u64::from_le_bytes(d.try_into().unwrap());
    assert_eq!(reference, 17 + 100_000 + 300);
}

fn brd_wkc(s: &mut Segment<Esc>) -> (u16, SegmentReport) {
    let (_, wkc, r) = send(s, DatagramCommand::Brd, station_address(0, 0), &[0], 0);
    (wkc, r)
}

#[test]
fn a_broken_link_fault_hides_the_slaves_behind_it_until_cleared() {
    let mut s = line(4);
    address_all(&mut s);
    s.add_fault(LineFault::Break { after: 1 });
    let (wkc, r) = brd_wkc(&mut s);
    assert_eq!((wkc, r.reached, r.lost), (2, 2, false));
    assert_eq!(send(&mut s, DatagramCommand::Fprd, station_address(0x1001, 0x0311), &[0], 0).0, [1]);
    s.clear_faults();
    assert_eq!(brd_wkc(&mut s).0, 4);
    // The cable itself was never touched.
    s.set_cable(2, false);
    s.clear_faults();
    assert_eq!(brd_wkc(&mut s).0, 3);
}

#[test]
fn lost_frames_reach_no_slave_and_come_back_lost() {
    let mut s = line(2);
    address_all(&mut s);
    s.add_fault(LineFault::Lose(Recurrence::always().every(3)));
    let lost: Vec<bool> = (0..6).map(|_| brd_wkc(&mut s).1.lost).collect();
    assert_eq!(lost, [true, false, false, true, false, false]);
    // A lost write did not happen.
    s.clear_faults();
    s.add_fault(LineFault::Lose(Recurrence::always().times(1)));
    let (_, _, r) = send(&mut s, DatagramCommand::Fpwr, station_address(0x1001, 0x0600), &[0x34, 0x12], 0);
    assert!(r.lost);
    assert_eq!(send(&mut s, DatagramCommand::Fprd, station_address(0x1001, 0x0600), &[0, 0], 0).0, [0, 0]);
}

#[test]
fn seeded_loss_replays_and_takes_about_its_share() {
    let run = |seed| {
        let mut s = line(1);
        s.set_fault_seed(seed);
        s.add_fault(LineFault::Lose(Recurrence::always().probability(0.25)));
        (0..400).map(|_| brd_wkc(&mut s).1.lost).collect::<Vec<_>>()
    };
    let a = run(7);
    assert_eq!(a, run(7));
    let n = a.iter().filter(|l| **l).count();
    assert!((60..140).contains(&n), "{n}");
}

#[test]
fn a_corrupted_frame_is_lost_unexecuted_behind_the_damage_and_counted() {
    let mut s = line(3);
    address_all(&mut s);
    s.add_fault(LineFault::Corrupt { at: 1, pick: Recurrence::always().times(1) });
    let (_, wkc, r) = send(&mut s, DatagramCommand::Bwr, station_address(0, 0x0600), &[0x21, 0x43], 0);
    assert!(r.lost);
    assert_eq!(wkc, 1, "only slave 0 executed it");
    let fmmu =
        |s: &mut Segment<Esc>, a| send(s, DatagramCommand::Fprd, station_address(a, 0x0600), &[0, 0], 0).0;
    assert_eq!(fmmu(&mut s, 0x1000), [0x21, 0x43]);
    assert_eq!(fmmu(&mut s, 0x1001), [0, 0]);
    let counters =
        |s: &mut Segment<Esc>, a| send(s, DatagramCommand::Fprd, station_address(a, 0x0300), &[0; 12], 0).0;
    assert_eq!(counters(&mut s, 0x1000)[8..10], [0, 1], "forwarded on the way back (port 1)");
    assert_eq!(counters(&mut s, 0x1001)[0], 1, "invalid frame on port 0");
    assert_eq!(counters(&mut s, 0x1002)[8], 1, "forwarded RX error on port 0");
    // times=1: the next frame passes.
    assert!(!brd_wkc(&mut s).1.lost);
}

#[test]
fn a_skewed_slave_miscounts_only_where_it_counts() {
    let mut s = line(3);
    address_all(&mut s);
    s.add_fault(LineFault::WkcSkew { slave: 1, skew: 1 });
    assert_eq!(brd_wkc(&mut s).0, 4);
    assert_eq!(send(&mut s, DatagramCommand::Fprd, station_address(0x1000, 0), &[0], 0).1, 1);
    assert_eq!(send(&mut s, DatagramCommand::Fprd, station_address(0x1001, 0), &[0], 0).1, 2);
    s.clear_faults();
    assert_eq!(brd_wkc(&mut s).0, 3);
}

#[test]
fn a_power_cycled_slave_comes_back_reset_with_its_eeprom() {
    let mut s = line(3);
    address_all(&mut s);
    s.power_off(1);
    assert!(!s.is_powered(1));
    assert_eq!(brd_wkc(&mut s).0, 1, "the line ends before the unpowered slave");
    s.power_on(1);
    assert_eq!(brd_wkc(&mut s).0, 3);
    // Its station address is back at the reset value; the others kept theirs.
    assert_eq!(send(&mut s, DatagramCommand::Aprd, position_address(1, 0x0010), &[0, 0], 0).0, [0, 0]);
    assert_eq!(send(&mut s, DatagramCommand::Aprd, position_address(2, 0x0010), &[0, 0], 0).0, [0x02, 0x10]);
    // The EEPROM's configured station alias (word 4) loaded again.
    let alias = send(&mut s, DatagramCommand::Aprd, position_address(1, 0x0012), &[0, 0], 0).0;
    assert_eq!(alias, send(&mut s, DatagramCommand::Aprd, position_address(0, 0x0012), &[0, 0], 0).0);
}

#[test]
fn a_drift_fault_changes_the_rate_of_one_clock_until_cleared() {
    let mut s = line(2);
    address_all(&mut s);
    let time = |s: &mut Segment<Esc>, a, us| {
        let d = send(s, DatagramCommand::Fprd, station_address(a, 0x0910), &[0; 8], us).0;
        u64::from_le_bytes(d.try_into().unwrap())
    };
    let rate = |s: &mut Segment<Esc>, a, from| {
        let t0 = time(s, a, from);
        time(s, a, from + 1000) - t0
    };
    assert_eq!(rate(&mut s, 0x1001, 0), 1_000_000);
    s.add_fault(LineFault::Drift { slave: 1, ppb: 1_000_000 });
    assert_eq!(rate(&mut s, 0x1001, 2000), 1_001_000, "1000 ppm fast");
    assert_eq!(rate(&mut s, 0x1000, 4000), 1_000_000, "the other clock as before");
    s.clear_faults();
    assert_eq!(rate(&mut s, 0x1001, 6000), 1_000_000);
}

#[test]
fn a_jitter_fault_scatters_one_clock_within_its_bound_replayably_until_cleared() {
    let stamps = |seed| {
        let mut s = line(2);
        address_all(&mut s);
        s.add_fault(LineFault::Jitter { slave: 1, amplitude_ns: 500, seed });
        let mut out = Vec::new();
        for k in 0..50u64 {
            for a in [0x1000, 0x1001] {
                let d =
                    send(&mut s, DatagramCommand::Fprd, station_address(a, 0x0910), &[0; 8], 1000 + k * 1000)
                        .0;
                out.push((a, k, u64::from_le_bytes(d.try_into().unwrap())));
            }
        }
        (s, out)
    };
    let (mut s, got) = stamps(7);
    // Each read 1 ms apart: the clean clock advances by exactly 1 ms,
    // the jittering one by 1 ms ± 2 × 500 ns, not always the same.
    let steps = |a| -> Vec<i64> {
        let t: Vec<u64> = got.iter().filter(|(x, ..)| *x == a).map(|(.., t)| *t).collect();
        t.windows(2).map(|w| w[1] as i64 - w[0] as i64 - 1_000_000).collect()
    };
    assert!(steps(0x1000).iter().all(|&d| d == 0));
    let j = steps(0x1001);
    assert!(j.iter().all(|d| d.abs() <= 1000), "{j:?}");
    assert!(j.iter().filter(|&&d| d != 0).count() > 40, "{j:?}");
    assert_eq!(stamps(7).1, got, "the same seed replays");
    assert_ne!(stamps(8).1, got, "another seed, other stamps");
    s.clear_faults();
    let t = |s: &mut Segment<Esc>, us| {
        let d = send(s, DatagramCommand::Fprd, station_address(0x1001, 0x0910), &[0; 8], us).0;
        u64::from_le_bytes(d.try_into().unwrap())
    };
    let t0 = t(&mut s, 100_000);
    assert_eq!(t(&mut s, 101_000) - t0, 1_000_000, "exact again");
}
