//! The master's procedures on both drivers: the deterministic virtual bus
//! in simulated time and the tokio driver in real time, with the same
//! devices and the same test bodies.

mod common;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use common::dual::{Station, on_both};
use common::{identity, node};
use drivebus_master::{
    FastScan, Identity, LssField, LssMode, MasterEvent, NmtCommand, PdoDir, PdoMapEntry, PdoRecord, Protocol,
    RemoteState, ScanOptions, SdoAbort, SdoError,
};
use drivebus_node::{Node, NodeConfig};
use tokio::sync::broadcast;

fn plain(ids: &[u8]) -> Vec<Station> {
    ids.iter().map(|&n| Station::Plain(node(n))).collect()
}

async fn next_event(
    m: &drivebus_master::Master,
    rx: &mut broadcast::Receiver<MasterEvent>,
    pred: impl Fn(&MasterEvent) -> bool,
) -> MasterEvent {
    m.timeout(Duration::from_secs(3), async {
        loop {
            let e = rx.recv().await.expect("events open");
            if pred(&e) {
                return e;
            }
        }
    })
    .await
    .expect("event in time")
}

#[test]
fn sdo_expedited_segmented_block_and_aborts() {
    on_both(
        || plain(&[5]),
        |m, which| async move {
            let sdo = m.sdo(5);
            assert_eq!(sdo.read::<u32>(0x1000, 0).await.unwrap(), 0x0002_0192, "{which:?}");
            sdo.write::<i32>(0x2002, 0, -123_456).await.unwrap();
            assert_eq!(sdo.read::<i32>(0x2002, 0).await.unwrap(), -123_456);
            assert_eq!(sdo.read::<String>(0x1008, 0).await.unwrap(), "test node 5");
            let data: Vec<u8> = (0..4000).map(|i| (i * 7 + i / 256) as u8).collect();
            for proto in [Protocol::Segmented, Protocol::Block] {
                let seen: Arc<Mutex<Vec<usize>>> = Arc::default();
                let s2 = seen.clone();
                let s = m.sdo(5).protocol(proto).on_progress(move |d, _| s2.lock().unwrap().push(d));
                s.download(0x2000, 0, &data).await.unwrap();
                assert_eq!(s.upload(0x2000, 0).await.unwrap(), data, "{which:?} {proto:?}");
                assert_eq!(seen.lock().unwrap().last(), Some(&data.len()));
            }
            let e = sdo.upload(0x5555, 0).await.unwrap_err();
            assert_eq!(e.abort_code(), Some(SdoAbort::NO_OBJECT));
            let e = m.sdo(42).timeout(Duration::from_millis(50)).retries(1).upload(0x1000, 0).await;
            assert_eq!(e, Err(SdoError::Timeout));
        },
    );
}

#[test]
fn scan_finds_nodes_with_identities() {
    on_both(
        || plain(&[2, 10, 33]),
        |m, which| async move {
            let found = m.scan().await;
            assert_eq!(found.iter().map(|n| n.node).collect::<Vec<_>>(), vec![2, 10, 33], "{which:?}");
            for n in &found {
                assert_eq!(n.identity, Some(identity(n.node)));
            }
            let some = m
                .scan_with(ScanOptions { nodes: 1..=9, identity: false, parallel: 4, ..Default::default() })
                .await;
            assert_eq!(some.len(), 1);
        },
    );
}

#[test]
fn nmt_heartbeat_loss_and_recovery() {
    on_both(
        || plain(&[8]),
        |m, which| async move {
            let mut ev = m.subscribe_events();
            m.sdo(8).write::<u16>(0x1017, 0, 20).await.unwrap();
            assert_eq!(
                m.wait_for_heartbeat(8, Duration::from_secs(1)).await.unwrap(),
                RemoteState::PreOperational,
                "{which:?}"
            );
            m.nmt(8, NmtCommand::Start).await.unwrap();
            next_event(&m, &mut ev, |e| {
                *e == MasterEvent::Heartbeat { node: 8, state: RemoteState::Operational }
            })
            .await;
            m.monitor_heartbeat(8, Some(Duration::from_millis(80)));
            m.sdo(8).write::<u16>(0x1017, 0, 0).await.unwrap();
            next_event(&m, &mut ev, |e| *e == MasterEvent::HeartbeatLost { node: 8 }).await;
            assert!(m.node_status(8).unwrap().lost);
            m.sdo(8).write::<u16>(0x1017, 0, 20).await.unwrap();
            next_event(&m, &mut ev, |e| *e == MasterEvent::HeartbeatRecovered { node: 8 }).await;
            m.reset_node(8, Duration::from_secs(2)).await.unwrap();
            assert_eq!(m.node_state(8), Some(RemoteState::BootUp));
        },
    );
}

#[test]
fn emcy_from_an_rpdo_length_error() {
    on_both(
        || plain(&[6]),
        |m, which| async move {
            let rec = PdoRecord::new(0x226, 255, vec![PdoMapEntry::new(0x2004, 0, 32)]);
            m.write_pdo(6, PdoDir::Rx, 1, &rec).await.unwrap();
            m.sdo(6).write::<u16>(0x1017, 0, 10).await.unwrap();
            m.nmt(6, NmtCommand::Start).await.unwrap();
            while m.wait_for_heartbeat(6, Duration::from_secs(1)).await.unwrap() != RemoteState::Operational {
            }
            let mut ev = m.subscribe_events();
            m.send_pdo(0x226, &[1, 2]).await.unwrap();
            let e = next_event(&m, &mut ev, |e| matches!(e, MasterEvent::Emcy { .. })).await;
            let MasterEvent::Emcy { node, code, text, .. } = e else { unreachable!() };
            assert_eq!((node, code), (6, 0x8210), "{which:?}");
            assert!(text.is_some());
        },
    );
}

#[test]
fn sync_producer_counts_in_the_masters_time() {
    on_both(
        || plain(&[3]),
        |m, which| async move {
            let mut ticks = m.subscribe_sync();
            m.start_sync(Duration::from_millis(2), 3);
            let mut counters = Vec::new();
            for _ in 0..7 {
                let t = m.timeout(Duration::from_secs(1), ticks.recv()).await.unwrap().unwrap();
                counters.push(t.counter.unwrap());
            }
            m.stop_sync();
            assert_eq!(counters, [1, 2, 3, 1, 2, 3, 1], "{which:?}");
        },
    );
}

fn unconfigured(serial: u32) -> Station {
    let mut cfg = NodeConfig::new(0xFF);
    cfg.lss = true;
    cfg.identity = drivebus_node::Identity { vendor_id: 0xABC, product_code: 0x77, revision: 3, serial };
    Station::Plain(Node::new(cfg))
}

#[test]
fn lss_fastscan_and_node_id_assignment() {
    on_both(
        || vec![unconfigured(0x20), unconfigured(0x10)],
        |m, which| async move {
            let lss = m.lss().timeout(Duration::from_millis(30));
            assert!(lss.identify_non_configured().await.unwrap(), "{which:?}");
            let scan = || {
                FastScan::new(Duration::from_millis(30))
                    .with_known(LssField::Vendor, 0xABC)
                    .with_known(LssField::Product, 0x77)
            };
            // Fastscan converges on the lowest address first.
            let a = lss.assign_node_id_with(scan(), 40, false).await.unwrap().unwrap();
            assert_eq!(a, Identity::new(0xABC, 0x77, 3, 0x10));
            let b = lss.assign_node_id_with(scan(), 41, false).await.unwrap().unwrap();
            assert_eq!(b.serial, 0x20);
            assert!(!lss.identify_non_configured().await.unwrap());
            m.sleep(Duration::from_millis(20)).await;
            assert_eq!(m.sdo(41).read::<u32>(0x1018, 4).await.unwrap(), 0x20);
            lss.switch_selective(&b).await.unwrap();
            assert_eq!(lss.inquire_node_id().await.unwrap(), 41);
            lss.switch_global(LssMode::Waiting).await.unwrap();
        },
    );
}

fn drive(id: u8) -> Station {
    use drivebus_cia402::drive::{DriveConfig, ModeHandler, generic_drive_with};
    let handlers: Vec<Box<dyn ModeHandler + Send>> =
        vec![Box::new(drivebus_cia402::homing::HomingMode::default())];
    Station::Drive(Box::new(generic_drive_with(id, DriveConfig::default(), handlers)))
}

#[test]
fn a_refused_pdo_mapping_leaves_the_previous_one_in_force() {
    on_both(
        || plain(&[5]),
        |m, which| async move {
            let before = m.read_pdo(5, PdoDir::Tx, 1).await.unwrap();
            assert!(before.valid());
            // 1000h is not mappable: the device refuses the entry.
            let bad = PdoRecord::new(0x185, 255, vec![PdoMapEntry::new(0x1000, 0, 32)]);
            let e = m.try_write_pdo(5, PdoDir::Tx, 1, &bad).await.unwrap_err();
            assert!(
                matches!(e.cause, drivebus_master::ConfigError::Sdo { index: 0x1A00, sub: 1, .. }),
                "{e}"
            );
            assert_eq!(e.restored, Ok(()), "{which:?}");
            assert!(e.to_string().contains("previous configuration was restored"), "{e}");
            let after = m.read_pdo(5, PdoDir::Tx, 1).await.unwrap();
            assert_eq!(after, before, "{which:?}: the PDO is as it was");
        },
    );
}

#[test]
fn drive_enable_move_and_fault_reset_only_when_faulted() {
    on_both(
        || vec![drive(9)],
        |m, which| async move {
            let d = m.drive(9).await.unwrap().with_timeout(Duration::from_secs(2));
            assert_eq!(d.state().await.unwrap(), drivebus_master::DriveState::SwitchOnDisabled);
            d.enable().await.unwrap();
            // Not faulted: reset leaves the running drive alone.
            assert!(!d.fault_reset().await.unwrap(), "{which:?}");
            assert_eq!(d.state().await.unwrap(), drivebus_master::DriveState::OperationEnabled);
            d.set_mode(drivebus_master::drive::mode::PP).await.unwrap();
            let seen = Arc::new(Mutex::new(0usize));
            let s2 = seen.clone();
            let d = d.on_progress(Duration::from_millis(50), move |_| *s2.lock().unwrap() += 1);
            let start = d.position().await.unwrap();
            d.move_to(20_000, true, None, Duration::from_secs(20)).await.unwrap();
            let end = d.position().await.unwrap();
            assert!((end - start - 20_000).abs() < 100, "{which:?}: {start} -> {end}");
            assert!(*seen.lock().unwrap() > 0, "progress reported");
        },
    );
}

/// A second SDO client (a `monitor --watch` elsewhere): reads 1000h of
/// `node` every `period`, ignoring the answers.
struct OtherSdoClient {
    node: u8,
    period: Duration,
    next: drivebus_can::Instant,
}

impl drivebus_can::Device for OtherSdoClient {
    fn start(&mut self, now: drivebus_can::Instant, _out: &mut dyn drivebus_can::TxSink) {
        self.next = now + self.period;
    }
    fn handle_frame(
        &mut self,
        _: &drivebus_can::Frame,
        _: drivebus_can::Instant,
        _: &mut dyn drivebus_can::TxSink,
    ) {
    }
    fn poll(
        &mut self,
        now: drivebus_can::Instant,
        out: &mut dyn drivebus_can::TxSink,
    ) -> Option<drivebus_can::Instant> {
        if now >= self.next {
            out.send(drivebus_can::Frame::new(
                0x600 + u16::from(self.node),
                &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0],
            ));
            self.next = now + self.period;
        }
        Some(self.next)
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// Issue 15: with a second SDO client on the node, its answers were taken
/// for a protocol violation (abort 0604 0043, which broke its transfer
/// too). They are ignored, a disturbed transfer is started again, and
/// every read and write goes through.
#[test]
fn another_sdo_client_on_the_node_does_not_break_transfers() {
    on_both(
        || {
            let other = OtherSdoClient {
                node: 5,
                period: Duration::from_millis(2),
                next: drivebus_can::Instant::ZERO,
            };
            vec![Station::Plain(node(5)), Station::Other(Box::new(other))]
        },
        |m, which| async move {
            let sdo = m.sdo(5);
            for i in 0..150 {
                let v =
                    sdo.read::<u32>(0x1018, 1).await.unwrap_or_else(|e| panic!("{which:?} read {i}: {e}"));
                assert_eq!(v, identity(5).vendor_id);
                sdo.write::<i32>(0x2002, 0, i).await.unwrap_or_else(|e| panic!("{which:?} write {i}: {e}"));
                if i % 10 == 0 {
                    let name = sdo
                        .read::<String>(0x1008, 0)
                        .await
                        .unwrap_or_else(|e| panic!("{which:?} name {i}: {e}"));
                    assert_eq!(name, "test node 5");
                }
            }
            assert_eq!(sdo.read::<i32>(0x2002, 0).await.unwrap(), 149);
        },
    );
}

/// A generic drive whose axis has a positive limit switch a tenth of a
/// revolution (36 of the model's 360 feed units) from its start.
fn drive_with_limit(id: u8) -> Station {
    use drivebus_cia402::drive::{DriveConfig, ModeHandler, generic_drive_with};
    let handlers: Vec<Box<dyn ModeHandler + Send>> =
        vec![Box::new(drivebus_cia402::homing::HomingMode::default())];
    let mut cfg = DriveConfig::default();
    cfg.params.axis.positive_limit = Some(36.0);
    Station::Drive(Box::new(generic_drive_with(id, cfg, handlers)))
}

/// Issue 15: a move stopped by a limit switch was "target reached"; the
/// homing with 6098h = 0 a bare "homing error".
#[test]
fn a_move_that_ends_on_a_limit_switch_says_so() {
    on_both(
        || vec![drive_with_limit(9)],
        |m, which| async move {
            use drivebus_master::{DriveError, MotionEnd};
            let d = m.drive(9).await.unwrap().with_timeout(Duration::from_secs(2));
            d.enable().await.unwrap();
            d.set_mode(drivebus_master::drive::mode::PP).await.unwrap();
            let ok = d.move_to(10_000, false, None, Duration::from_secs(20)).await.unwrap();
            assert_eq!(ok.end, MotionEnd::TargetReached, "{which:?}");
            assert_eq!(ok.target, Some(10_000));
            let e = d.move_to(1_000_000, false, None, Duration::from_secs(60)).await.unwrap_err();
            let DriveError::Stopped(r) = &e else { panic!("{which:?}: {e}") };
            assert_eq!(r.end, MotionEnd::LimitSwitch { positive: true }, "{which:?}: {e}");
            let p = r.position.unwrap();
            assert!((10_000..500_000).contains(&p), "{which:?}: stopped at {p}");
            assert_eq!(r.inputs.map(|i| i & 2), Some(2), "60FDh bit 1");
            let text = e.to_string();
            assert!(
                text.contains("short of the target 1000000") && text.contains("positive limit switch"),
                "{text}"
            );
            let e = d.home(0, Duration::from_secs(5)).await.unwrap_err();
            let DriveError::Stopped(r) = &e else { panic!("{which:?}: {e}") };
            assert_eq!(r.end, MotionEnd::HomingError, "{which:?}: {e}");
            let text = e.to_string();
            assert!(
                text.contains("6098h homing method is 0") && text.contains("60E3h offers methods"),
                "{text}"
            );
        },
    );
}

#[test]
fn homing_waits_for_a_fresh_attained_and_a_runaway_is_halted() {
    on_both(
        || vec![drive(9)],
        |m, which| async move {
            let d = m.drive(9).await.unwrap().with_timeout(Duration::from_secs(2));
            d.enable().await.unwrap();
            d.home(35, Duration::from_secs(5)).await.unwrap();
            assert_ne!(d.statusword().await.unwrap() & 0x1000, 0, "attained, bit 12 stays set");
            // Method 17 (negative limit switch): the generic axis has none,
            // so it never finishes; the stale bit 12 of the first homing
            // must not count.
            let e = d.home(17, Duration::from_millis(500)).await.unwrap_err();
            assert!(matches!(e, drivebus_master::DriveError::Timeout { .. }), "{which:?}: {e}");
            let stop = d.stop_motion(Duration::from_secs(5)).await.unwrap();
            assert_eq!(stop.action, drivebus_master::StopAction::Halted, "{which:?}");
            let v = d.actual_velocity().await.unwrap();
            assert!(v.abs() <= 100, "{which:?}: at rest, velocity {v}");
            let limits = d.motion_limits().await;
            assert!(limits.homing_speeds.is_some());
            assert!(!limits.describe(stop.position, None, true).is_empty());
        },
    );
}

#[test]
fn lss_set_node_id_refuses_two_unconfigured_slaves() {
    on_both(
        || vec![unconfigured(0x20), unconfigured(0x10)],
        |m, which| async move {
            let lss = m.lss().timeout(Duration::from_millis(30));
            let r = lss.configure_only_slave(9, false).await.unwrap();
            assert_eq!(
                r,
                drivebus_master::OnlySlave::Several(Identity::new(0xABC, 0x77, 3, 0x10)),
                "{which:?}"
            );
            // Nothing changed: both still unconfigured, no node 9.
            m.sleep(Duration::from_millis(20)).await;
            assert!(m.sdo(9).timeout(Duration::from_millis(50)).upload(0x1000, 0).await.is_err());
            let (first, more) = lss.probe_unconfigured().await.unwrap().unwrap();
            assert_eq!((first.serial, more), (0x10, true));
            // The selective path configures exactly one.
            lss.configure_selected(&Identity::new(0xABC, 0x77, 3, 0x20), 9, false).await.unwrap();
            m.sleep(Duration::from_millis(20)).await;
            assert_eq!(m.sdo(9).read::<u32>(0x1018, 4).await.unwrap(), 0x20);
            // One unconfigured slave left: now the global path works.
            let r = lss.configure_only_slave(10, false).await.unwrap();
            assert_eq!(r, drivebus_master::OnlySlave::Configured(Identity::new(0xABC, 0x77, 3, 0x10)));
            m.sleep(Duration::from_millis(20)).await;
            assert_eq!(m.sdo(10).read::<u32>(0x1018, 4).await.unwrap(), 0x10);
            assert_eq!(
                lss.configure_only_slave(11, false).await.unwrap(),
                drivebus_master::OnlySlave::NoneFound
            );
        },
    );
}

#[test]
fn dictionary_dump_of_standard_objects() {
    on_both(
        || plain(&[5]),
        |m, which| async move {
            let (eds, report) = m.dump_standard_dcf(5).await.unwrap();
            assert!(report.read > 20, "{which:?}: {report:?}");
            assert_eq!(eds.commissioning.as_ref().unwrap().node_id, 5);
            let id = &eds.objects[&0x1018].subs[&1];
            assert_eq!(id.parameter_value.as_deref(), Some("0x00000ABC"));
            assert!(eds.objects.contains_key(&0x1800) && !eds.objects.contains_key(&0x6041));
            let text = drivebus_eds::write(&eds);
            assert!(
                text.contains("[DeviceComissioning]") && text.contains("ParameterValue=0x00000ABC"),
                "{text}"
            );
        },
    );
}
