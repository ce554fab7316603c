//! The `RemoteDrive` handle against the real virtual drive of `drivebus-cia402`
//! (`generic_drive`: CiA 402-3 pre-defined PDOs, servo model), hosted in
//! real time.

mod common;

use std::time::Duration;

use common::bounded;
use drivebus_cia402::drive::generic_drive;
use drivebus_master::drive::mode;
use drivebus_master::{DriveState, NmtCommand, RemoteState};
use drivebus_transport::Hub;
use drivebus_transport::host::spawn;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn enable_and_move_the_virtual_drive() {
    bounded(async {
        let hub = Hub::default();
        let m = common::master(&hub);
        let _host = spawn(generic_drive(9), hub.attach());
        assert_eq!(m.sdo(9).read::<u32>(0x1000, 0).await.unwrap(), 0x0002_0192);
        m.sdo(9).write::<u16>(0x1017, 0, 20).await.unwrap();
        m.nmt(9, NmtCommand::Start).await.unwrap();
        while m.wait_for_heartbeat(9, Duration::from_secs(1)).await.unwrap() != RemoteState::Operational {}
        let d = m.drive(9).await.unwrap().with_timeout(Duration::from_secs(2));
        assert!(d.statusword_by_pdo() && d.controlword_by_pdo(), "{d:?}");
        d.enable().await.unwrap();
        assert_eq!(d.state().await.unwrap(), DriveState::OperationEnabled);
        d.set_mode(mode::PP).await.unwrap();
        let start = m.sdo(9).read::<i32>(0x6064, 0).await.unwrap();
        d.move_to(2000, true, None, Duration::from_secs(8)).await.unwrap();
        let end = m.sdo(9).read::<i32>(0x6064, 0).await.unwrap();
        // Target reached means inside the position window 6067h.
        let window = m.sdo(9).read::<u32>(0x6067, 0).await.unwrap() as i32;
        assert!((end - (start + 2000)).abs() <= window, "moved from {start} to {end}, window {window}");
        d.disable().await.unwrap();
    })
    .await;
}
