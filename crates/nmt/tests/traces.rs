//! NMT, boot-up and guarding traces of the five reference drives
//! (/work/shared/reference/seed00*-examples.md), replayed frame by frame.

mod common;

use common::{Dev, ms};
use drivebus_can::Frame;
use drivebus_nmt::{CommandSet, NmtCommand, NmtConfig, NmtEvent, NmtState, RemoteState};

/// KC1 / AKD: no command 80h (KC1 §6.4.1, AKD §5.4.1), one consumer entry
/// (1016h sub 0 = 1), no 1029h.
fn kollmorgen(node: u8) -> Dev {
    let cfg = NmtConfig {
        supported_commands: CommandSet::ALL.without(NmtCommand::EnterPreOperational),
        ..NmtConfig::new(node)
    };
    Dev::new(cfg, 1, 0)
}

/// SSD 630: node guarding only, 100Ch/100Dh not evaluated (§8), no heartbeat.
fn ssd630(node: u8, auto_start: bool) -> Dev {
    let cfg = NmtConfig {
        heartbeat_supported: false,
        life_guarding_honoured: false,
        auto_start,
        ..NmtConfig::new(node)
    };
    Dev::new(cfg, 0, 0)
}

/// KC1 Example 8 (§8.2.1.7) frame 1 and Example 9 (§8.2.1.8) frame 37:
/// `703 00` boot-up, later `000 01 03` starts node 3.
#[test]
fn kc1_boot_up_and_start_node_3() {
    let mut d = kollmorgen(3);
    d.boot(ms(0));
    assert_eq!(d.take(), [Frame::new(0x703, &[0x00])]);
    assert_eq!(
        d.rx(Frame::new(0x000, &[0x01, 0x03]), ms(100)),
        Some(NmtEvent::StateChanged { from: NmtState::PreOperational, to: NmtState::Operational })
    );
    assert!(d.take().is_empty());
    // 80h is not implemented: ignored (KC1 §6.4.1 lists only 1, 2, 129, 130).
    assert_eq!(d.rx(Frame::new(0x000, &[0x80, 0x03]), ms(200)), None);
    assert_eq!(d.nmt.state(), NmtState::Operational);
    // 130 "gives a new bootup-message" (KC1 §6.4.1).
    assert_eq!(d.rx(Frame::new(0x000, &[0x82, 0x03]), ms(300)), Some(NmtEvent::ResetCommunication));
    d.boot(ms(301));
    assert_eq!(d.take(), [Frame::new(0x703, &[0x00])]);
}

/// KC1 Example 12 (§8.2.2.1) frame 47 and AKD §13h (line 6146): the manual
/// prints `000 01 01` for "NMT enable for all axes". As printed it starts
/// node 1 only; the intended broadcast is `000 01 00` (Node-ID 0).
#[test]
fn kc1_akd_start_all_axes_typo() {
    let mut axis1 = kollmorgen(1);
    let mut axis2 = kollmorgen(2);
    for d in [&mut axis1, &mut axis2] {
        d.boot(ms(0));
        d.take();
    }
    let printed = Frame::new(0x000, &[0x01, 0x01]);
    axis1.rx(printed, ms(10));
    axis2.rx(printed, ms(10));
    assert_eq!(axis1.nmt.state(), NmtState::Operational);
    assert_eq!(axis2.nmt.state(), NmtState::PreOperational, "as printed, axis 2 stays pre-operational");
    // Corrected: broadcast.
    let corrected = Frame::new(0x000, &[0x01, 0x00]);
    assert_eq!(axis1.rx(corrected, ms(20)), None, "already operational");
    assert!(axis2.rx(corrected, ms(20)).is_some());
    assert_eq!(axis2.nmt.state(), NmtState::Operational);
}

/// AKD §8a (line 5707): boot-up `703 00`, and §9f (line 5840)
/// `000 01 03` start. The consumer has one entry (1016h sub 0 = 1).
#[test]
fn akd_boot_up_start_and_single_consumer_entry() {
    let mut d = kollmorgen(3);
    assert_eq!(d.od.get_u32(0x1016, 0), Some(1));
    d.boot(ms(5707));
    assert_eq!(d.take(), [Frame::new(0x703, &[0x00])]);
    d.rx(Frame::new(0x000, &[0x01, 0x03]), ms(5840));
    assert_eq!(d.nmt.state(), NmtState::Operational);
    // One entry only: a second sub-index does not exist.
    assert_eq!(
        d.write(0x1016, 2, &0x0001_0064u32.to_le_bytes(), ms(5841)),
        Err(drivebus_od::SdoAbort::NO_SUB_INDEX)
    );
}

/// SSD 630 EX-GUARD (§8) and EX-STORE step 9 (§11): guarding requests on
/// 701h are answered with toggle (first 0) + state; `000 01 01` starts node
/// 1, "eventually check ... by Node guarding".
#[test]
fn ssd630_node_guarding_around_start() {
    let mut d = ssd630(1, false);
    d.boot(ms(0));
    // The manual does not mention a boot-up message; CiA 301 requires one.
    assert_eq!(d.take(), [Frame::new(0x701, &[0x00])]);
    d.rx(Frame::remote(0x701, 1), ms(10));
    d.rx(Frame::new(0x000, &[0x01, 0x01]), ms(20));
    d.rx(Frame::remote(0x701, 1), ms(30));
    d.rx(Frame::new(0x000, &[0x02, 0x00]), ms(40));
    d.rx(Frame::remote(0x701, 1), ms(50));
    assert_eq!(
        d.take(),
        [Frame::new(0x701, &[0x7F]), Frame::new(0x701, &[0x85]), Frame::new(0x701, &[0x04])]
    );
    // 100Ch/100Dh "not evaluated": no life guarding, however long.
    d.write(0x100C, 0, &100u16.to_le_bytes(), ms(60)).unwrap();
    d.write(0x100D, 0, &[3], ms(60)).unwrap();
    d.rx(Frame::remote(0x701, 1), ms(70));
    assert_eq!(d.poll(ms(60_000)), None);
    assert!(d.events().is_empty());
    // No heartbeat objects.
    assert!(d.od.get(0x1017, 0).is_none());
}

/// SSD 630 2018h = 1 (§11): Operational by itself after power-on.
#[test]
fn ssd630_auto_start() {
    let mut d = ssd630(1, true);
    d.boot(ms(0));
    assert_eq!(d.nmt.state(), NmtState::Operational);
    d.rx(Frame::remote(0x701, 1), ms(1));
    assert_eq!(d.take(), [Frame::new(0x701, &[0x00]), Frame::new(0x701, &[0x05])]);
}

/// DDS6-EX2 row 19 (`000 01 0D`, node 0Dh) and Appendix A §6.3.14: 1016h:01
/// := 0x000105DC (node 1, 1500 ms) via `60D: 23 16 10 01 DC 05 01 00`.
/// 1016h sub 0 is printed 02h although four entries are described; four
/// are installed here. 1029h:01 = 0 (default): Operational → Pre-operational.
#[test]
fn dds6_start_consumer_and_error_behaviour() {
    let mut d = Dev::new(NmtConfig::new(0x0D), 4, 1);
    d.boot(ms(0));
    assert_eq!(d.take(), [Frame::new(0x70D, &[0x00])]);
    let sdo_data = [0x23, 0x16, 0x10, 0x01, 0xDC, 0x05, 0x01, 0x00];
    d.write(0x1016, sdo_data[3], &sdo_data[4..8], ms(10)).unwrap();
    assert_eq!(d.nmt.consumer_entries().next(), Some(drivebus_nmt::ConsumerEntry { node: 1, time_ms: 1500 }));
    d.rx(Frame::new(0x000, &[0x01, 0x0D]), ms(36));
    assert_eq!(d.nmt.state(), NmtState::Operational);
    assert_eq!(
        d.rx(Frame::new(0x701, &[0x05]), ms(100)),
        Some(NmtEvent::RemoteStateChange { node: 1, state: RemoteState::Operational })
    );
    assert_eq!(d.poll(ms(100)), Some(ms(1600)));
    d.poll(ms(1600));
    assert_eq!(d.events(), [NmtEvent::HeartbeatTimeout { node: 1 }]);
    // The node wires the timeout to 1029h:01 (DDS6 §6.3.17).
    assert_eq!(
        d.nmt.on_error(drivebus_nmt::ErrorClass::COMMUNICATION),
        Some(NmtEvent::StateChanged { from: NmtState::Operational, to: NmtState::PreOperational })
    );
    // A second entry for node 1 is refused.
    assert_eq!(
        d.write(0x1016, 2, &0x0001_0100u32.to_le_bytes(), ms(2000)),
        Err(drivebus_od::SdoAbort::PARAM_INCOMPATIBLE)
    );
}
