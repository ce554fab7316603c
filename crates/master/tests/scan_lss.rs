//! Active/passive scan and the LSS master (CiA 305) against hosted nodes.

mod common;

use std::time::Duration;

use common::{bounded, host, identity, master, node};
use drivebus_master::{FastScan, Identity, LssField, LssMode, ScanOptions};
use drivebus_node::{Node, NodeConfig};
use drivebus_transport::Hub;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn scan_finds_three_nodes_with_identities() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _hosts: Vec<_> = [2u8, 10, 33].iter().map(|&n| host(&hub, node(n))).collect();
        let found = m.scan().await;
        assert_eq!(found.iter().map(|n| n.node).collect::<Vec<_>>(), vec![2, 10, 33]);
        for n in &found {
            assert_eq!(n.device_type, 0x0002_0192);
            assert_eq!(n.identity, Some(identity(n.node)));
        }
        // Passive: every node answered an SDO (and booted), so all were seen.
        assert_eq!(m.seen_nodes(), vec![2, 10, 33]);
        // A narrower scan without identities.
        let some = m
            .scan_with(ScanOptions { nodes: 1..=9, identity: false, parallel: 4, ..Default::default() })
            .await;
        assert_eq!(some.len(), 1);
        assert_eq!(some[0].identity, None);
    })
    .await;
}

fn unconfigured(serial: u32) -> Node {
    let mut cfg = NodeConfig::new(0xFF);
    cfg.lss = true;
    cfg.identity = drivebus_node::Identity { vendor_id: 0xABC, product_code: 0x77, revision: 3, serial };
    Node::new(cfg)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fastscan_finds_unconfigured_node_and_assigns_id() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _u = host(&hub, unconfigured(0x1234_5678));
        // Answers come within a millisecond in-process; 20 ms leaves room
        // for a loaded machine (a late answer would flip a bit).
        let lss = m.lss().timeout(Duration::from_millis(20));
        assert!(lss.identify_non_configured().await.unwrap());
        let addr = lss.fastscan().await.unwrap().expect("found");
        assert_eq!(addr, Identity::new(0xABC, 0x77, 3, 0x1234_5678));
        // The found slave is in configuration: inquire and configure it.
        assert_eq!(lss.inquire_node_id().await.unwrap(), 0xFF);
        assert_eq!(lss.inquire_identity().await.unwrap(), addr);
        lss.configure_node_id(20).await.unwrap();
        assert!(lss.configure_node_id(0).await.is_err(), "0 is not configurable");
        // Bit timing index 0 (1 Mbit/s) of the standard table; a slave may
        // refuse timings it cannot do, but it must answer.
        match lss.configure_bit_timing(0).await {
            Ok(()) | Err(drivebus_master::LssError::Refused { .. }) => {}
            Err(e) => panic!("configure bit timing: {e}"),
        }
        lss.store().await.unwrap();
        let boot = m.expect_bootup(20, Duration::from_secs(2));
        lss.switch_global(LssMode::Waiting).await.unwrap();
        // Leaving configuration with a new ID restarts the slave under it (CiA 305).
        boot.await.unwrap();
        assert_eq!(m.sdo(20).read::<u32>(0x1018, 4).await.unwrap(), 0x1234_5678);
        // Now configured: no non-configured slave left.
        assert!(!lss.identify_non_configured().await.unwrap());
        assert_eq!(lss.fastscan().await.unwrap(), None);
        // Selective switch by address, then back to waiting.
        lss.switch_selective(&addr).await.unwrap();
        assert_eq!(lss.inquire_node_id().await.unwrap(), 20);
        lss.switch_global(LssMode::Waiting).await.unwrap();
        assert!(lss.switch_selective(&Identity::new(1, 2, 3, 4)).await.is_err());
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn assign_node_id_helper_one_of_two() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _a = host(&hub, unconfigured(0x20));
        let _b = host(&hub, unconfigured(0x10));
        let lss = m.lss().timeout(Duration::from_millis(30));
        // Known vendor, product and revision: only the serial is scanned.
        let scan = || {
            FastScan::new(Duration::from_millis(30))
                .with_known(LssField::Vendor, 0xABC)
                .with_known(LssField::Product, 0x77)
                .with_known(LssField::Revision, 3)
        };
        // Fastscan converges on the lowest address first.
        let a = lss.assign_node_id_with(scan(), 40, false).await.unwrap().unwrap();
        assert_eq!(a.serial, 0x10);
        let b = lss.assign_node_id_with(scan(), 41, false).await.unwrap().unwrap();
        assert_eq!(b.serial, 0x20);
    })
    .await;
}
