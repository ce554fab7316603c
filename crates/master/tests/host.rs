//! The device host: several nodes on one hub served over socketcand
//! (loopback TCP), commands into a running device, stopping it; the
//! `virtual://` URL.

mod common;

use std::time::Duration;

use common::{bounded, node};
use drivebus_master::{Master, MasterEvent, Protocol, SdoError};
use drivebus_node::{NmtState, NodeDevice};
use drivebus_od::NoHooks;
use drivebus_transport::host::{spawn, spawn_on_hub};
use drivebus_transport::socketcand::SocketcandServer;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn serve_three_nodes_over_socketcand() {
    bounded(async {
        let (server, addr) = SocketcandServer::bind("127.0.0.1:0", "can0").await.unwrap();
        let devices = [21u8, 22, 23].map(|id| NodeDevice::new(node(id), NoHooks));
        let hosts = spawn_on_hub(devices, server.hub());
        let bus = drivebus_transport::open(&format!("socketcand://{addr}/can0")).await.unwrap();
        let m = Master::new(bus);
        // The server drops frames for 20 ms after `< ok >` (its python-can
        // grace window); `connect` returns before that ends.
        tokio::time::sleep(Duration::from_millis(60)).await;
        let found = m.scan().await;
        assert_eq!(found.iter().map(|n| n.node).collect::<Vec<_>>(), vec![21, 22, 23]);
        // A 10 KiB block transfer through TCP.
        let data: Vec<u8> = (0..10 * 1024).map(|i| (i % 251) as u8).collect();
        let sdo = m.sdo(22).protocol(Protocol::Block).timeout(Duration::from_secs(1));
        sdo.download(0x2000, 0, &data).await.unwrap();
        assert_eq!(sdo.upload(0x2000, 0).await.unwrap(), data);
        // socketcand carries no RTR frames: guarding is refused up front.
        assert!(m.start_guarding(21, Duration::from_millis(50), 3).await.is_err());
        // Reach into a running device.
        let st = hosts[0].with(|d, _| d.node.nmt_state()).await.unwrap();
        assert_eq!(st, NmtState::PreOperational);
        let mut ev = m.subscribe_events();
        hosts[2].with(|d, now| d.node.raise_emcy(0x8110, [0; 5], now)).await.unwrap();
        let e = tokio::time::timeout(Duration::from_secs(2), async {
            loop {
                if let Ok(e @ MasterEvent::Emcy { .. }) = ev.recv().await {
                    return e;
                }
            }
        })
        .await
        .unwrap();
        assert!(matches!(e, MasterEvent::Emcy { node: 23, code: 0x8110, .. }));
        // A stopped device goes silent.
        hosts[1].stop();
        tokio::time::sleep(Duration::from_millis(20)).await;
        assert!(hosts[1].is_finished());
        assert!(hosts[1].with(|_, _| ()).await.is_none());
        assert_eq!(
            m.sdo(22).timeout(Duration::from_millis(50)).upload(0x1000, 0).await,
            Err(SdoError::Timeout)
        );
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn virtual_url_and_boot_order() {
    bounded(async {
        let m = Master::new(drivebus_transport::open("virtual://host-test").await.unwrap());
        let boot = m.expect_bootup(30, Duration::from_secs(2));
        let bus = drivebus_transport::open("virtual://host-test").await.unwrap();
        let h = spawn(NodeDevice::new(node(30), NoHooks), bus);
        boot.await.unwrap();
        assert_eq!(m.sdo(30).read::<String>(0x1008, 0).await.unwrap(), "test node 30");
        h.into_join_handle().abort();
    })
    .await;
}

#[tokio::test(flavor = "current_thread")]
async fn host_runs_on_a_current_thread_runtime() {
    bounded(async {
        let hub = drivebus_transport::Hub::default();
        let m = common::master(&hub);
        let _h = common::host(&hub, node(31));
        assert_eq!(m.sdo(31).read::<u32>(0x1000, 0).await.unwrap(), 0x0002_0192);
    })
    .await;
}
