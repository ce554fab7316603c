//! A transfer future polled once and then left alone (what `scan` does to
//! start 127 probes before awaiting any, what a `select!` does to its
//! losing branches) must not stall the master, even when the transport's
//! queue is full at that moment. (A first version sent from the caller's
//! task under a lock held across the transport's await: one scan in six
//! hung over socketcand.)

mod common;

use std::task::Poll;
use std::time::Duration;

use common::{bounded, node};
use drivebus_master::Master;
use drivebus_node::NodeDevice;
use drivebus_od::NoHooks;
use drivebus_transport::host::spawn_on_hub;
use drivebus_transport::socketcand::SocketcandServer;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn futures_polled_once_and_left_do_not_stall_the_master() {
    bounded(async {
        let (server, addr) = SocketcandServer::bind("127.0.0.1:0", "can0").await.unwrap();
        let devices = [3u8, 90].map(|id| NodeDevice::new(node(id), NoHooks));
        let _hosts = spawn_on_hub(devices, server.hub());
        // A fresh connection per scan, scanning at once (as `drivebus scan`
        // does): the first probes meet the server's rawmode grace.
        for round in 0..30 {
            let m =
                Master::new(drivebus_transport::open(&format!("socketcand://{addr}/can0")).await.unwrap());
            let found = m.scan().await;
            assert_eq!(found.iter().map(|n| n.node).collect::<Vec<_>>(), vec![3, 90], "round {round}");
            m.close().await.unwrap();
        }
        let m = Master::new(drivebus_transport::open(&format!("socketcand://{addr}/can0")).await.unwrap());
        // Many more requests than the transport queue holds, each polled
        // once and parked; then one awaited to the end, then the rest.
        let mut parked: Vec<_> = (0..400u32)
            .map(|i| {
                let sdo = m.sdo(if i % 2 == 0 { 3 } else { 90 }).timeout(Duration::from_secs(2));
                Box::pin(async move { sdo.read::<u32>(0x1000, 0).await })
            })
            .collect();
        let mut early = Vec::new();
        for fut in &mut parked {
            let first = std::future::poll_fn(|cx| Poll::Ready(fut.as_mut().poll(cx))).await;
            early.push(first);
        }
        assert_eq!(m.sdo(3).read::<u32>(0x1018, 1).await.unwrap(), common::identity(3).vendor_id);
        for (fut, first) in parked.into_iter().zip(early) {
            let r = match first {
                Poll::Ready(r) => r,
                Poll::Pending => fut.await,
            };
            assert_eq!(r.unwrap(), 0x0002_0192);
        }
    })
    .await;
}
