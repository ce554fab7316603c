//! slcan pty emulator ↔ our slcan client and a raw serial host.
#![cfg(unix)]

use std::io::{Read, Write};
use std::time::Duration;

use drivebus_transport::slcan::{SlcanPty, open_serial};
use drivebus_transport::{CanBus, CanId, Frame, Hub};
use tokio::time::{sleep, timeout};

const T: Duration = Duration::from_secs(5);

async fn recv(bus: &mut CanBus) -> Frame {
    timeout(T, bus.recv()).await.expect("timed out waiting for a frame").unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pty_round_trip_with_our_client() {
    let hub = Hub::default();
    let pty = SlcanPty::spawn(hub.attach()).unwrap();
    let mut drive = hub.attach();
    let path = pty.path().to_str().unwrap().to_owned();
    let mut host = open_serial(&path, Some(1_000_000), 115_200).await.unwrap();
    sleep(Duration::from_millis(50)).await; // let `O` reach the emulator
    let frames = [
        Frame::new(0x605, &[0x40, 0, 0x10, 0, 0, 0, 0, 0]),
        Frame::new(0x080, &[]),
        Frame::remote(0x705, 1),
        Frame::try_new(CanId::Extended(0x18FF50E5), &[1, 2]).unwrap(),
        Frame::try_remote(CanId::Extended(0x1ABCDEF), 0).unwrap(),
    ];
    for f in frames {
        host.send(f).await.unwrap();
    }
    for f in frames {
        assert_eq!(recv(&mut drive).await, f);
    }
    for f in frames {
        drive.send(f).await.unwrap();
    }
    for f in frames {
        assert_eq!(recv(&mut host).await, f);
    }
    // A burst larger than the pty buffer arrives complete and in order.
    for i in 0..2_000u16 {
        drive.send(Frame::new(0x180, &i.to_le_bytes())).await.unwrap();
    }
    for i in 0..2_000u16 {
        assert_eq!(recv(&mut host).await, Frame::new(0x180, &i.to_le_bytes()));
    }
    // Leave without reading (frames stay queued), then a new host opens
    // the same path: it must see no stale frames, and work.
    for i in 0..50u16 {
        drive.send(Frame::new(0x190, &i.to_le_bytes())).await.unwrap();
    }
    drop(host);
    sleep(Duration::from_millis(150)).await;
    let mut host = open_serial(&path, None, 115_200).await.unwrap();
    sleep(Duration::from_millis(50)).await;
    drive.send(Frame::new(0x1A0, &[1])).await.unwrap();
    assert_eq!(recv(&mut host).await, Frame::new(0x1A0, &[1]));
    host.send(Frame::new(0x1A1, &[2])).await.unwrap();
    assert_eq!(recv(&mut drive).await, Frame::new(0x1A1, &[2]));
}

/// The exact byte dialogue of python-can's slcan interface.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn python_can_dialogue_on_a_raw_port() {
    let hub = Hub::default();
    let pty = SlcanPty::spawn(hub.attach()).unwrap();
    let mut drive = hub.attach();
    let path = pty.path().to_owned();
    let mut port = tokio::task::spawn_blocking(move || {
        serialport::new(path.to_str().unwrap(), 115_200).timeout(Duration::from_millis(200)).open().unwrap()
    })
    .await
    .unwrap();

    // Reads until `want` bytes came (or a deadline: 5 s, or 200 ms when
    // expecting nothing).
    let read_for = |port: &mut Box<dyn serialport::SerialPort>, want: usize| {
        let mut got = Vec::new();
        let mut buf = [0u8; 256];
        let wait = if want == 0 { Duration::from_millis(200) } else { T };
        let deadline = std::time::Instant::now() + wait;
        while (want == 0 || got.len() < want) && std::time::Instant::now() < deadline {
            if let Ok(n) = port.read(&mut buf) {
                got.extend_from_slice(&buf[..n]);
            }
        }
        got
    };
    // Before O: a bus frame is not forwarded, a host frame is refused.
    drive.send(Frame::new(0x111, &[])).await.unwrap();
    port.write_all(b"t1110\r").unwrap();
    assert_eq!(read_for(&mut port, 1), b"\x07");
    port.write_all(b"C\rS6\r\rO\rO\r").unwrap();
    assert_eq!(read_for(&mut port, 5), b"\r\r\r\r\r");
    port.write_all(b"V\rN\rF\rQ\r").unwrap();
    assert_eq!(read_for(&mut port, 17), b"V1013\rNDB01\rF00\r\x07");
    port.write_all(b"r7051\rt0800\rt08\r").unwrap();
    assert_eq!(read_for(&mut port, 5), b"z\rz\r\x07");
    assert_eq!(recv(&mut drive).await, Frame::remote(0x705, 1));
    assert_eq!(recv(&mut drive).await, Frame::new(0x80, &[]));
    drive.send(Frame::remote(0x705, 1)).await.unwrap();
    drive.send(Frame::new(0x080, &[])).await.unwrap();
    assert_eq!(read_for(&mut port, 11), b"r7051\rt0800\r");
    // After C nothing is forwarded and stale output is flushed.
    port.write_all(b"C\r").unwrap();
    assert_eq!(read_for(&mut port, 1), b"\r");
    drive.send(Frame::new(0x222, &[])).await.unwrap();
    sleep(Duration::from_millis(50)).await;
    assert_eq!(read_for(&mut port, 0), b"");
    // Garbage and an oversized line do not kill the emulator.
    port.write_all(&[b'x'; 300]).unwrap();
    port.write_all(b"\r\x00\xff\rO\r").unwrap();
    assert_eq!(read_for(&mut port, 2), b"\x07\r");
    // Nothing else was sent back (the oversized line is dropped silently).
    assert_eq!(read_for(&mut port, 0), b"");
}

#[tokio::test]
async fn slcan_over_tcp_url_round_trip() {
    use drivebus_transport::slcan::SlcanTcpServer;
    let hub = Hub::default();
    let (_srv, addr) = SlcanTcpServer::bind("127.0.0.1:0", hub.clone()).await.unwrap();
    let mut drive = hub.attach();
    let mut host = drivebus_transport::open(&format!("slcan://tcp:{addr}?bitrate=500000")).await.unwrap();
    sleep(Duration::from_millis(50)).await;
    host.send(Frame::remote(0x705, 1)).await.unwrap();
    assert_eq!(recv(&mut drive).await, Frame::remote(0x705, 1));
    let ext = Frame::try_new(CanId::Extended(0x1234567), &[1, 2, 3]).unwrap();
    drive.send(ext).await.unwrap();
    assert_eq!(recv(&mut host).await, ext);
}

/// `close` writes the frames before the adapter's `C`: one host after
/// another, each sending and closing at once, loses nothing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn close_delivers_everything_sent_before_it() {
    let hub = Hub::default();
    let pty = SlcanPty::spawn(hub.attach()).unwrap();
    let mut spy = hub.attach();
    let path = pty.path().to_str().unwrap().to_owned();
    for round in 0..20u8 {
        let host = open_serial(&path, Some(1_000_000), 115_200).await.unwrap();
        for k in 0..3u8 {
            host.send(Frame::new(0x000, &[0x02, round.wrapping_mul(3).wrapping_add(k)])).await.unwrap();
        }
        host.close().await.unwrap();
    }
    let mut n = 0;
    while let Ok(Ok(f)) = tokio::time::timeout(Duration::from_millis(300), spy.recv()).await {
        assert_eq!(f.std_id(), Some(0x000));
        n += 1;
    }
    assert_eq!(n, 20 * 3);
}
