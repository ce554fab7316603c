//! `open(url)`: errors and the virtual bus.

use std::time::Duration;

use drivebus_transport::socketcand::SocketcandServer;
use drivebus_transport::{Cause, Frame, open};
use tokio::time::timeout;

#[tokio::test]
async fn bad_urls_say_what_is_wrong() {
    let e = open("socketcand://localhost").await.unwrap_err();
    assert!(matches!(e.cause, Cause::BadUrl(_)));
    assert_eq!(
        e.to_string(),
        "bad bus URL `socketcand://localhost`: missing channel: expected socketcand://HOST:PORT/CHANNEL"
    );
    let e = open("can0").await.unwrap_err().to_string();
    assert!(e.starts_with("bad bus URL `can0`: expected SCHEME://"), "{e}");
    let e = open("slcan:///dev/does-not-exist-drivebus?bitrate=500000").await.unwrap_err();
    assert!(matches!(e.cause, Cause::Io(_)));
    assert!(
        e.to_string().starts_with("cannot open `slcan:///dev/does-not-exist-drivebus?bitrate=500000`: "),
        "{e}"
    );
}

/// SocketCAN is in the default build on Linux: opening an interface
/// reaches the kernel, whose answer (no AF_CAN, no such device) is the
/// error, never "this build has no SocketCAN".
#[cfg(target_os = "linux")]
#[tokio::test]
async fn socketcan_is_in_the_default_linux_build() {
    match open("socketcan://nosuchcan9").await {
        Ok(_) => panic!("an interface named nosuchcan9 exists"),
        Err(e) => {
            assert!(matches!(e.cause, Cause::Io(_)), "{e}");
            assert!(e.to_string().starts_with("cannot open `socketcan://nosuchcan9`: "), "{e}");
        }
    }
}

#[cfg(not(target_os = "linux"))]
#[tokio::test]
async fn socketcan_is_linux_only() {
    let e = open("socketcan://can0").await.unwrap_err().to_string();
    assert!(e.contains("Linux only"), "{e}");
}

#[tokio::test]
async fn socketcand_url_connects_and_reports_refusal() {
    let (srv, addr) = SocketcandServer::bind("127.0.0.1:0", "vbus0").await.unwrap();
    let mut drive = srv.attach();
    let bus = open(&format!("socketcand://{addr}/vbus0")).await.unwrap();
    tokio::time::sleep(Duration::from_millis(40)).await;
    bus.send(Frame::new(0x701, &[0])).await.unwrap();
    assert_eq!(
        timeout(Duration::from_secs(5), drive.recv()).await.unwrap().unwrap(),
        Frame::new(0x701, &[0])
    );
    let url = format!("socketcand://{addr}/other");
    let e = open(&url).await.unwrap_err().to_string();
    assert!(e.contains(&url) && e.contains("could not open bus"), "{e}");
    drop(srv);
    // Nothing listens any more: connection refused, naming the URL.
    let url = format!("socketcand://{addr}/vbus0");
    let e = open(&url).await.unwrap_err().to_string();
    assert!(e.starts_with(&format!("cannot open `{url}`")), "{e}");
}

#[tokio::test]
async fn virtual_buses_share_by_name_without_echo() {
    let mut a = open("virtual://t1").await.unwrap();
    let mut b = open("virtual://t1").await.unwrap();
    let mut other = open("virtual://t2").await.unwrap();
    a.send(Frame::new(1, &[1])).await.unwrap();
    assert_eq!(b.recv().await.unwrap(), Frame::new(1, &[1]));
    b.send(Frame::remote(2, 0)).await.unwrap();
    assert_eq!(a.recv().await.unwrap(), Frame::remote(2, 0));
    let quiet = Duration::from_millis(50);
    assert!(timeout(quiet, a.recv()).await.is_err(), "echo");
    assert!(timeout(quiet, other.recv()).await.is_err(), "leak between names");
}
