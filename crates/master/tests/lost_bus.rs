//! Issue 15 §1: a master whose bus is lost (the socketcand server went
//! away) ended nothing that waited: its timers never fired, its frame and
//! event channels stayed open, so a command waited until Ctrl-C.

use std::time::Duration;

use drivebus_master::{Master, WaitError};
use tokio::io::{AsyncReadExt, AsyncWriteExt};

/// A socketcand server that completes the handshake (`< hi >`, `< ok >`
/// to open and rawmode), then closes the connection after `alive`.
async fn dying_server(alive: Duration) -> String {
    let l = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let port = l.local_addr().unwrap().port();
    tokio::spawn(async move {
        let (mut s, _) = l.accept().await.unwrap();
        s.write_all(b"< hi >").await.unwrap();
        let mut buf = [0u8; 256];
        let mut oks = 0;
        while oks < 2 {
            let n = s.read(&mut buf).await.unwrap();
            oks += buf[..n].windows(2).filter(|w| w == b" >").count();
            for _ in 0..buf[..n].windows(2).filter(|w| w == b" >").count() {
                s.write_all(b"< ok >").await.unwrap();
            }
        }
        tokio::time::sleep(alive).await;
        drop(s);
    });
    format!("socketcand://127.0.0.1:{port}/can0")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_wait_ends_when_the_bus_is_lost() {
    let url = dying_server(Duration::from_millis(300)).await;
    let m = Master::open(&url, Default::default()).await.unwrap();
    let mut frames = m.subscribe_frames();
    let t0 = std::time::Instant::now();
    let limit = Duration::from_secs(5);
    // A sleep and a timeout that started before the loss end with it.
    let forever = Duration::from_secs(3600);
    let ((), waited) = tokio::time::timeout(limit, async {
        tokio::join!(m.sleep(forever), m.timeout(forever, std::future::pending::<()>()))
    })
    .await
    .expect("the waits end when the bus is lost");
    assert_eq!(waited, Err(WaitError::Closed));
    assert!(t0.elapsed() < limit);
    let why = tokio::time::timeout(limit, m.lost()).await.expect("lost() resolves");
    assert!(why.contains("closed the connection"), "{why}");
    assert_eq!(m.bus_lost().as_deref(), Some(why.as_str()));
    // A trace sees its channel close instead of waiting for frames.
    let r = tokio::time::timeout(limit, frames.recv()).await.expect("the frame channel closes");
    assert!(matches!(r, Err(tokio::sync::broadcast::error::RecvError::Closed)), "{r:?}");
    // And so does a subscriber that comes after the loss, and a new wait.
    let r = tokio::time::timeout(limit, m.subscribe_events().recv()).await.expect("closed at once");
    assert!(r.is_err());
    tokio::time::timeout(limit, m.sleep(Duration::from_secs(3600))).await.expect("no timer after the loss");
    let e = m.sdo(5).read::<u32>(0x1000, 0).await.unwrap_err();
    assert!(e.to_string().contains("closed the connection"), "{e}");
    // LSS too: its exchange is not left for a driver that has stopped.
    let e = tokio::time::timeout(limit, m.lss().fastscan()).await.expect("LSS ends").unwrap_err();
    assert!(e.to_string().contains("closed the connection"), "{e}");
}
