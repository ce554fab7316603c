//! candump log lines, sink, parser round trip, replay.

use std::cell::RefCell;
use std::rc::Rc;

use drivebus_bus::candump::{parse_frame, parse_line, parse_log_all, write_line};
use drivebus_bus::{Bus, BusConfig};
use drivebus_can::{CanId, Frame, Instant};
use proptest::prelude::*;

fn cfg() -> BusConfig {
    BusConfig { log_epoch_us: 1_700_000_000_000_000, ..BusConfig::with_bitrate(125_000) }
}

fn traffic(bus: &mut Bus) {
    let p = bus.attach_probe();
    bus.attach_probe();
    bus.send_from(p, Frame::new(0x601, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]));
    bus.send_at(p, Frame::remote(0x705, 1), Instant::from_millis(2));
    bus.send_at(p, Frame::try_new(CanId::Extended(0x18FF50E5), &[1, 2]).unwrap(), Instant::from_millis(3));
    bus.send_at(p, Frame::remote(0x080, 0), Instant::from_millis(4));
    bus.run_until(Instant::from_millis(10));
}

#[test]
fn bus_log_lines_are_exact() {
    let mut bus = Bus::new(cfg());
    let lines = Rc::new(RefCell::new(Vec::new()));
    let sink = lines.clone();
    bus.set_log_sink(move |l| sink.borrow_mut().push(l.to_string()));
    traffic(&mut bus);
    // Times are end of EOF at 8 µs per bit: 121 bits after 0 (601#: 124
    // bits), 46 after 2 ms (705#R1: 49), 85 after 3 ms (18FF50E5#0102: 88),
    // 48 after 4 ms (080#R: 51; bit counts as in tests/timing.rs).
    let expected = [
        "(1700000000.000968) can0 601#4000100000000000",
        "(1700000000.002368) can0 705#R1",
        "(1700000000.003680) can0 18FF50E5#0102",
        "(1700000000.004384) can0 080#R",
    ];
    assert_eq!(bus.log_lines(), expected);
    assert_eq!(*lines.borrow(), expected);
    let mut text = String::new();
    bus.format_log(&mut text).unwrap();
    assert_eq!(text, expected.join("\n") + "\n");
}

#[test]
fn replaying_a_log_reproduces_it() {
    let mut bus = Bus::new(BusConfig { log_epoch_us: 5_000_000, ..BusConfig::zero_time() });
    traffic(&mut bus);
    let mut text = String::new();
    bus.format_log(&mut text).unwrap();
    let records = parse_log_all(&text).unwrap();
    assert_eq!(records.len(), 4);
    let mut replay = Bus::new(BusConfig { log_epoch_us: 5_000_000, ..BusConfig::zero_time() });
    assert_eq!(replay.replay(&records, 5_000_000), 4);
    replay.run_until(Instant::from_millis(10));
    assert_eq!(replay.log(), bus.log());
}

#[test]
fn save_log_writes_a_file() {
    let mut bus = Bus::new(cfg());
    traffic(&mut bus);
    let path = std::env::temp_dir().join(format!("drivebus-bus-log-{}.log", std::process::id()));
    bus.save_log(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let _ = std::fs::remove_file(&path);
    assert_eq!(text.lines().collect::<Vec<_>>(), bus.log_lines());
}

fn any_frame() -> impl Strategy<Value = Frame> {
    (any::<bool>(), any::<u32>(), any::<bool>(), proptest::collection::vec(any::<u8>(), 0..=8)).prop_map(
        |(is_ext, id, rtr, data)| {
            let id =
                if is_ext { CanId::Extended(id & 0x1FFF_FFFF) } else { CanId::Standard((id & 0x7FF) as u16) };
            if rtr {
                Frame::try_remote(id, data.len() as u8).unwrap()
            } else {
                Frame::try_new(id, &data).unwrap()
            }
        },
    )
}

proptest! {
    #[test]
    fn write_parse_round_trip(f in any_frame(), us in 0u64..1 << 50, epoch in 0u64..1 << 52, iface in "[a-z][a-z0-9]{0,10}") {
        let mut line = String::new();
        write_line(&mut line, epoch, &iface, Instant::from_micros(us), &f).unwrap();
        let r = parse_line(&line).unwrap();
        prop_assert_eq!(r.frame, f);
        prop_assert_eq!(&r.interface, &iface);
        prop_assert_eq!(r.timestamp_us(), epoch + us);
        prop_assert_eq!(r.instant(epoch), Some(Instant::from_micros(us)));
        let frame_text = line.rsplit(' ').next().unwrap();
        prop_assert_eq!(parse_frame(frame_text), Ok(f));
    }

    #[test]
    fn parser_never_panics(s in "\\PC{0,60}") {
        let _ = parse_line(&s);
        let _ = parse_frame(&s);
    }

    #[test]
    fn parser_never_panics_on_mangled_lines(f in any_frame(), pos in 0usize..60, c in any::<char>()) {
        let mut line = String::new();
        write_line(&mut line, 0, "can0", Instant::ZERO, &f).unwrap();
        let mut chars: Vec<char> = line.chars().collect();
        let at = pos.min(chars.len());
        chars.insert(at, c);
        let s: String = chars.into_iter().collect();
        let _ = parse_line(&s);
        let _ = parse_log_all(&s);
    }
}
