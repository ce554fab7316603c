//! Node guarding and life guarding (CiA 301 §7.2.8.3.2.1, 100Ch/100Dh).

mod common;

use common::{Dev, NODE, ms};
use drivebus_can::Frame;
use drivebus_nmt::{NmtConfig, NmtEvent};

fn rtr() -> Frame {
    Frame::remote(0x705, 1)
}

fn answer(byte: u8) -> Frame {
    Frame::new(0x705, &[byte])
}

#[test]
fn toggle_alternates_and_carries_the_state() {
    let mut d = Dev::booted();
    let mut got = Vec::new();
    for (t, cmd) in [(10, None), (20, None), (30, Some(0x01)), (40, None), (50, Some(0x02)), (60, Some(0x80))]
    {
        if let Some(cs) = cmd {
            d.cmd(cs, NODE, ms(t));
        }
        assert_eq!(d.rx(rtr(), ms(t)), None);
        got.extend(d.take());
    }
    assert_eq!(got, [answer(0x7F), answer(0xFF), answer(0x05), answer(0x85), answer(0x04), answer(0xFF)]);
}

#[test]
fn any_rtr_length_is_answered() {
    let mut d = Dev::booted();
    for len in [0, 1, 8] {
        d.rx(Frame::remote(0x705, len), ms(1));
    }
    assert_eq!(d.take(), [answer(0x7F), answer(0xFF), answer(0x7F)]);
    // A request for another node is not ours.
    d.rx(Frame::remote(0x706, 1), ms(1));
    assert!(d.take().is_empty());
}

#[test]
fn toggle_restarts_at_zero_after_reset_communication() {
    let mut d = Dev::booted();
    d.rx(rtr(), ms(1));
    assert_eq!(d.take(), [answer(0x7F)]);
    d.cmd(0x82, 0, ms(2));
    // No answer in Initialisation.
    d.rx(rtr(), ms(3));
    assert!(d.take().is_empty());
    d.boot(ms(4));
    d.rx(rtr(), ms(5));
    assert_eq!(d.take(), [Frame::new(0x705, &[0]), answer(0x7F)]);
}

#[test]
fn life_guarding_lost_and_resolved() {
    let mut d = Dev::booted();
    d.write(0x100C, 0, &100u16.to_le_bytes(), ms(0)).unwrap();
    d.write(0x100D, 0, &[3], ms(0)).unwrap();
    // Not started before the first request.
    assert_eq!(d.poll(ms(10_000)), None);
    assert_eq!(d.rx(rtr(), ms(10_000)), None);
    assert_eq!(d.poll(ms(10_000)), Some(ms(10_300)));
    assert_eq!(d.rx(rtr(), ms(10_250)), None);
    assert_eq!(d.poll(ms(10_549)), Some(ms(10_550)));
    assert!(d.events().is_empty());
    assert_eq!(d.poll(ms(10_550)), None);
    assert_eq!(d.events(), [NmtEvent::LifeGuardingLost]);
    assert!(d.nmt.is_life_guarding_lost());
    assert_eq!(d.poll(ms(20_000)), None);
    assert!(d.events().is_empty(), "reported once");
    assert_eq!(d.rx(rtr(), ms(20_000)), Some(NmtEvent::LifeGuardingResolved));
    assert!(!d.nmt.is_life_guarding_lost());
    assert_eq!(d.poll(ms(20_000)), Some(ms(20_300)));
    assert_eq!(d.take(), [answer(0x7F), answer(0xFF), answer(0x7F)]);
}

#[test]
fn zero_guard_time_or_factor_disables_life_guarding() {
    for (guard, factor) in [(0u16, 3u8), (100, 0)] {
        let mut d = Dev::booted();
        d.write(0x100C, 0, &guard.to_le_bytes(), ms(0)).unwrap();
        d.write(0x100D, 0, &[factor], ms(0)).unwrap();
        d.rx(rtr(), ms(0));
        assert_eq!(d.poll(ms(100_000)), None);
        assert!(d.events().is_empty());
        assert_eq!(d.take(), [answer(0x7F)], "guarding itself still answers");
    }
}

#[test]
fn changing_the_life_time_restarts_a_running_timer() {
    let mut d = Dev::booted();
    d.write(0x100C, 0, &100u16.to_le_bytes(), ms(0)).unwrap();
    d.write(0x100D, 0, &[2], ms(0)).unwrap();
    d.rx(rtr(), ms(0));
    assert_eq!(d.poll(ms(0)), Some(ms(200)));
    d.write(0x100D, 0, &[5], ms(150)).unwrap();
    assert_eq!(d.poll(ms(150)), Some(ms(650)));
    d.write(0x100C, 0, &0u16.to_le_bytes(), ms(160)).unwrap();
    assert_eq!(d.poll(ms(10_000)), None);
    assert!(d.events().is_empty());
}

#[test]
fn life_guarding_runs_in_stopped() {
    let mut d = Dev::booted();
    d.write(0x100C, 0, &10u16.to_le_bytes(), ms(0)).unwrap();
    d.write(0x100D, 0, &[2], ms(0)).unwrap();
    d.cmd(0x02, NODE, ms(0));
    d.rx(rtr(), ms(0));
    assert_eq!(d.take(), [answer(0x04)]);
    d.poll(ms(20));
    assert_eq!(d.events(), [NmtEvent::LifeGuardingLost]);
}

#[test]
fn heartbeat_replaces_node_guarding() {
    // CiA 301 §7.2.8.3.2: heartbeat or guarding, not both; 1017h ≠ 0 wins.
    let mut d = Dev::booted();
    d.write(0x100C, 0, &100u16.to_le_bytes(), ms(0)).unwrap();
    d.write(0x100D, 0, &[2], ms(0)).unwrap();
    d.rx(rtr(), ms(0));
    assert_eq!(d.take(), [answer(0x7F)]);
    d.write(0x1017, 0, &1000u16.to_le_bytes(), ms(50)).unwrap();
    assert!(d.nmt.heartbeat_active());
    assert_eq!(d.rx(rtr(), ms(60)), None);
    assert!(d.take().is_empty(), "no guarding answer while the heartbeat runs");
    // Life guarding stopped too: no loss at 200.
    assert_eq!(d.poll(ms(500)), Some(ms(1_050)));
    assert!(d.events().is_empty());
    // Back to guarding when 1017h = 0: the toggle continues.
    d.write(0x1017, 0, &0u16.to_le_bytes(), ms(600)).unwrap();
    d.rx(rtr(), ms(700));
    assert_eq!(d.take(), [answer(0xFF)]);
    assert_eq!(d.poll(ms(700)), Some(ms(900)));
}

#[test]
fn guarding_not_supported() {
    let cfg = NmtConfig { guarding_supported: false, ..NmtConfig::new(NODE) };
    let mut d = Dev::new(cfg, 0, 0);
    d.boot(ms(0));
    d.take();
    assert!(d.od.get(0x100C, 0).is_none());
    assert_eq!(d.rx(rtr(), ms(1)), None);
    assert!(d.take().is_empty());
}

#[test]
fn life_guarding_not_honoured() {
    // SSD 630 §8: 100Ch/100Dh exist but are not evaluated.
    let cfg = NmtConfig { life_guarding_honoured: false, heartbeat_supported: false, ..NmtConfig::new(1) };
    let mut d = Dev::new(cfg, 0, 0);
    d.boot(ms(0));
    d.take();
    d.write(0x100C, 0, &10u16.to_le_bytes(), ms(0)).unwrap();
    d.write(0x100D, 0, &[2], ms(0)).unwrap();
    d.rx(Frame::remote(0x701, 1), ms(0));
    assert_eq!(d.take(), [Frame::new(0x701, &[0x7F])]);
    assert_eq!(d.poll(ms(10_000)), None);
    assert!(d.events().is_empty());
}

#[test]
fn ending_life_guarding_resolves_an_outstanding_loss() {
    for (index, data) in [(0x1017u16, 100u16.to_le_bytes().to_vec()), (0x100D, vec![0u8])] {
        let mut d = Dev::booted();
        d.write(0x100C, 0, &10u16.to_le_bytes(), ms(0)).unwrap();
        d.write(0x100D, 0, &[2], ms(0)).unwrap();
        d.rx(rtr(), ms(0));
        d.poll(ms(20));
        assert_eq!(d.events(), [NmtEvent::LifeGuardingLost]);
        d.write(index, 0, &data, ms(30)).unwrap();
        assert_eq!(d.reconfigure_events, [NmtEvent::LifeGuardingResolved], "{index:04X}h");
        assert!(!d.nmt.is_life_guarding_lost());
    }
}

#[test]
fn configure_keeps_running_timers() {
    let mut d = Dev::booted();
    d.write(0x1017, 0, &100u16.to_le_bytes(), ms(0)).unwrap();
    d.write(0x100C, 0, &100u16.to_le_bytes(), ms(0)).unwrap();
    d.write(0x100D, 0, &[2], ms(0)).unwrap();
    d.write(0x1016, 1, &0x0009_0064u32.to_le_bytes(), ms(0)).unwrap();
    d.rx(Frame::new(0x709, &[5]), ms(10));
    // Re-reading unchanged values (e.g. after a 1011h restore) restarts
    // nothing but the life-guarding timer, which follows the new "now".
    assert_eq!(d.nmt.configure(&d.od, ms(50)), None);
    assert_eq!(d.poll(ms(50)), Some(ms(100)));
    assert_eq!(d.run(51, 100), [(100, answer(0x7F))]);
    d.poll(ms(110));
    assert_eq!(d.events(), [NmtEvent::HeartbeatTimeout { node: 9 }]);
}
