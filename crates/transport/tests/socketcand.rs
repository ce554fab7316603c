//! socketcand server ↔ clients (raw TCP and our client), loopback only.

use std::time::Duration;

use drivebus_transport::socketcand::proto::{self, Message, Splitter};
use drivebus_transport::socketcand::{SocketcandConfig, SocketcandServer, connect};
use drivebus_transport::{CanBus, CanId, FaultRule, Frame, Hub, HubConfig};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::time::{sleep, timeout};

const T: Duration = Duration::from_secs(5);

async fn server() -> (SocketcandServer, std::net::SocketAddr) {
    SocketcandServer::bind("127.0.0.1:0", "can0").await.unwrap()
}

/// One `recv(256)` as python-can's handshake does it.
async fn recv_once(s: &mut TcpStream) -> Vec<u8> {
    let mut buf = [0u8; 256];
    let n = timeout(T, s.read(&mut buf)).await.unwrap().unwrap();
    buf[..n].to_vec()
}

/// A raw client through the handshake, asserting each answer arrives alone.
async fn raw_client(addr: std::net::SocketAddr) -> TcpStream {
    let mut s = TcpStream::connect(addr).await.unwrap();
    // Give the server time to (wrongly) send more than `< hi >`.
    sleep(Duration::from_millis(30)).await;
    assert_eq!(recv_once(&mut s).await, b"< hi >");
    s.write_all(b"< open can0 >").await.unwrap();
    sleep(Duration::from_millis(10)).await;
    assert_eq!(recv_once(&mut s).await, b"< ok >");
    s.write_all(b"< rawmode >").await.unwrap();
    // Inside the 20 ms grace: nothing may follow `< ok >`.
    sleep(Duration::from_millis(10)).await;
    assert_eq!(recv_once(&mut s).await, b"< ok >");
    sleep(Duration::from_millis(30)).await;
    s
}

/// Reads until `n` messages arrived.
async fn read_messages(s: &mut TcpStream, n: usize) -> Vec<String> {
    let mut split = Splitter::new();
    let mut got = Vec::new();
    let mut buf = [0u8; 4096];
    while got.len() < n {
        let k = timeout(T, s.read(&mut buf)).await.expect("timed out waiting for messages").unwrap();
        assert!(k > 0, "server closed");
        split.feed(&buf[..k], |m| got.push(String::from_utf8_lossy(m).into_owned()));
    }
    got
}

async fn recv(bus: &mut CanBus) -> Frame {
    timeout(T, bus.recv()).await.expect("timed out waiting for a frame").unwrap()
}

async fn assert_silent(bus: &mut CanBus) {
    if let Ok(r) = timeout(Duration::from_millis(100), bus.recv()).await {
        panic!("unexpected {r:?}");
    }
}

fn ext(id: u32, data: &[u8]) -> Frame {
    Frame::try_new(CanId::Extended(id), data).unwrap()
}

#[tokio::test]
async fn handshake_is_exact_even_on_a_busy_bus() {
    let (srv, addr) = server().await;
    // A participant spamming the bus while clients connect (python-can
    // fails if a frame shares a recv with `< ok >`).
    let spam = srv.attach();
    let spammer = tokio::spawn(async move {
        for i in 0..2_000u16 {
            spam.send(Frame::new(0x100 + (i % 16), &[1])).await.unwrap();
            sleep(Duration::from_micros(500)).await;
        }
    });
    for _ in 0..3 {
        let mut s = raw_client(addr).await;
        let msgs = read_messages(&mut s, 3).await;
        assert!(msgs.iter().all(|m| m.starts_with(" frame 10")), "{msgs:?}");
    }
    spammer.abort();
}

#[tokio::test]
async fn wrong_channel_is_refused() {
    let (_srv, addr) = server().await;
    let mut s = TcpStream::connect(addr).await.unwrap();
    assert_eq!(recv_once(&mut s).await, b"< hi >");
    s.write_all(b"< open vcan9 >").await.unwrap();
    assert_eq!(recv_once(&mut s).await, b"< error could not open bus >");
    let e = connect(addr, "vcan9").await.unwrap_err();
    assert!(e.to_string().contains("could not open bus"), "{e}");
}

#[tokio::test]
async fn dlc0_frame_has_two_spaces_and_ids_keep_width() {
    let (srv, addr) = server().await;
    let mut raw = raw_client(addr).await;
    let drive = srv.attach();
    drive.send(Frame::new(0x80, &[])).await.unwrap();
    drive.send(Frame::new(0x585, &[0x43, 0, 0x10, 0, 0x92, 1, 2, 0])).await.unwrap();
    drive.send(ext(0x80, &[0xAB])).await.unwrap();
    let m = read_messages(&mut raw, 3).await;
    // ` frame 080 SECS.USECS  ` : two spaces before `>`.
    let (secs, usecs) = m[0].trim_start_matches(" frame 080 ").trim_end().split_once('.').unwrap();
    assert!(secs.len() >= 10 && usecs.len() == 6, "{m:?}");
    assert!(m[0].starts_with(" frame 080 ") && m[0].ends_with("  "), "{:?}", m[0]);
    assert!(m[1].starts_with(" frame 585 ") && m[1].ends_with(" 4300100092010200 "), "{:?}", m[1]);
    assert!(m[2].starts_with(" frame 00000080 ") && m[2].ends_with(" AB "), "{:?}", m[2]);
    assert_eq!(proto::parse(m[2].as_bytes()), Message::Frame(ext(0x80, &[0xAB]), proto_ts(&m[2])));
}

fn proto_ts(m: &str) -> u64 {
    let ts = m.split_whitespace().nth(2).unwrap();
    let (s, u) = ts.split_once('.').unwrap();
    s.parse::<u64>().unwrap() * 1_000_000 + u.parse::<u64>().unwrap()
}

#[tokio::test]
async fn ids_both_ways_and_no_echo() {
    let (srv, addr) = server().await;
    let mut drive = srv.attach();
    let mut raw = raw_client(addr).await;
    let mut ours = connect(addr, "can0").await.unwrap();
    sleep(Duration::from_millis(30)).await;

    // Raw client → drive and our client: 3 digits standard, else extended.
    raw.write_all(b"< send 123 0 >< send 00000123 2 a B >< send 7FF 8 1 2 3 4 5 6 7 ff >").await.unwrap();
    let want =
        [Frame::new(0x123, &[]), ext(0x123, &[0xA, 0xB]), Frame::new(0x7FF, &[1, 2, 3, 4, 5, 6, 7, 0xFF])];
    for w in want {
        assert_eq!(recv(&mut drive).await, w);
        assert_eq!(recv(&mut ours).await, w);
    }
    // Our client → raw client and drive.
    ours.send(Frame::new(0x001, &[9])).await.unwrap();
    ours.send(ext(0x1FFF_FFFF, &[])).await.unwrap();
    assert_eq!(recv(&mut drive).await, Frame::new(1, &[9]));
    assert_eq!(recv(&mut drive).await, ext(0x1FFF_FFFF, &[]));
    let m = read_messages(&mut raw, 2).await;
    assert!(m[0].starts_with(" frame 001 ") && m[0].ends_with(" 09 "), "{m:?}");
    assert!(m[1].starts_with(" frame 1FFFFFFF ") && m[1].ends_with("  "), "{m:?}");
    // No echo to the sender: neither our client nor the drive see their own.
    drive.send(Frame::new(0x181, &[1])).await.unwrap();
    assert_eq!(recv(&mut ours).await, Frame::new(0x181, &[1]));
    assert_silent(&mut ours).await;
    assert_silent(&mut drive).await;
    // `< echo >` is answered, and socketcand cannot carry RTR.
    raw.write_all(b"< echo >").await.unwrap();
    let m = read_messages(&mut raw, 2).await;
    assert!(m[0].starts_with(" frame 181"), "{m:?}");
    assert_eq!(m[1], " echo ");
    let e = ours.send(Frame::remote(0x705, 1)).await.unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::Unsupported);
}

#[tokio::test]
async fn five_clients_relay_everything_in_order() {
    let (srv, addr) = server().await;
    let mut clients = Vec::new();
    for _ in 0..5 {
        clients.push(connect(addr, "can0").await.unwrap());
    }
    sleep(Duration::from_millis(40)).await;
    assert_eq!(srv.client_count(), 5);
    const N: u8 = 40;
    for (i, c) in clients.iter().enumerate() {
        for k in 0..N {
            c.send(Frame::new(0x200 + i as u16, &[k])).await.unwrap();
        }
    }
    for (i, c) in clients.iter_mut().enumerate() {
        let mut next = [0u8; 5];
        for _ in 0..(4 * N as usize) {
            let f = recv(c).await;
            let from = usize::from(f.std_id().unwrap() - 0x200);
            assert_ne!(from, i, "echo");
            assert_eq!(f.data()[0], next[from], "order from client {from}");
            next[from] += 1;
        }
        assert_silent(c).await;
    }
}

#[tokio::test]
async fn garbage_and_vanishing_clients_do_not_hurt_the_hub() {
    let (srv, addr) = server().await;
    let mut drive = srv.attach();
    let mut raw = raw_client(addr).await;
    let mut junk = vec![b'<'];
    junk.extend(std::iter::repeat_n(b'x', 100_000));
    raw.write_all(&junk).await.unwrap();
    raw.write_all(b"\x00\xff>>>< send 705 1  >< send 123 9 >< send 123 1 100 >< bogus >< send 12")
        .await
        .unwrap();
    sleep(Duration::from_millis(20)).await;
    raw.write_all(b"3 1 42 >").await.unwrap();
    assert_eq!(recv(&mut drive).await, Frame::new(0x123, &[0x42]));
    assert_silent(&mut drive).await;

    // A client that vanishes in the middle of a message.
    let mut half = raw_client(addr).await;
    half.write_all(b"< send 321 2 0").await.unwrap();
    drop(half);
    let mut other = connect(addr, "can0").await.unwrap();
    sleep(Duration::from_millis(40)).await;
    drive.send(Frame::new(0x77, &[7])).await.unwrap();
    assert_eq!(recv(&mut other).await, Frame::new(0x77, &[7]));
    let m = read_messages(&mut raw, 1).await;
    assert!(m[0].starts_with(" frame 077 "), "{m:?}");
    assert_silent(&mut drive).await;
    assert_eq!(srv.client_count(), 2);
}

#[tokio::test]
async fn frames_in_the_grace_window_are_held_back_not_lost() {
    let (srv, addr) = server().await;
    let drive = srv.attach();
    let mut s = TcpStream::connect(addr).await.unwrap();
    assert_eq!(recv_once(&mut s).await, b"< hi >");
    s.write_all(b"< open can0 >").await.unwrap();
    assert_eq!(recv_once(&mut s).await, b"< ok >");
    s.write_all(b"< rawmode >").await.unwrap();
    assert_eq!(recv_once(&mut s).await, b"< ok >");
    // Sent within the 20 ms grace: held back, then delivered after it, like
    // the answer to a request a client sends right after `< ok >`. (That
    // `< ok >` arrives alone is checked by the exact read above and by the
    // handshake test under load.)
    drive.send(Frame::new(0x111, &[])).await.unwrap();
    sleep(Duration::from_millis(60)).await;
    drive.send(Frame::new(0x222, &[])).await.unwrap();
    let m = read_messages(&mut s, 2).await;
    assert!(m[0].starts_with(" frame 111 "), "{m:?}");
    assert!(m[1].starts_with(" frame 222 "), "{m:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn slow_client_is_disconnected_not_stalling_the_hub() {
    let hub = Hub::new(HubConfig { capacity: 256, ..HubConfig::default() });
    let (srv, addr) =
        SocketcandServer::bind_with("127.0.0.1:0", SocketcandConfig::new("can0"), hub).await.unwrap();
    // A client with a tiny receive window that stops reading after the handshake.
    let sock = tokio::net::TcpSocket::new_v4().unwrap();
    sock.set_recv_buffer_size(4096).unwrap();
    let mut sleeper = sock.connect(addr).await.unwrap();
    assert_eq!(recv_once(&mut sleeper).await, b"< hi >");
    sleeper.write_all(b"< open can0 >").await.unwrap();
    assert_eq!(recv_once(&mut sleeper).await, b"< ok >");
    sleeper.write_all(b"< rawmode >").await.unwrap();
    assert_eq!(recv_once(&mut sleeper).await, b"< ok >");
    sleep(Duration::from_millis(40)).await;
    assert_eq!(srv.client_count(), 1);
    let drive = srv.attach();
    let frame = Frame::new(0x123, &[0xAA; 8]);
    // Bounded: at most 2M frames; the hub never waits for the sleeper.
    let mut sent = 0u32;
    while srv.client_count() == 1 && sent < 2_000_000 {
        drive.send(frame).await.unwrap();
        sent += 1;
        if sent.is_multiple_of(128) {
            tokio::task::yield_now().await;
        }
    }
    for _ in 0..100 {
        if srv.client_count() == 0 {
            break;
        }
        sleep(Duration::from_millis(10)).await;
    }
    assert_eq!(srv.client_count(), 0, "slow client still connected after {sent} frames");
    // The hub still relays to a new client.
    let mut fresh = connect(addr, "can0").await.unwrap();
    sleep(Duration::from_millis(40)).await;
    drive.send(Frame::new(0x7, &[])).await.unwrap();
    assert_eq!(recv(&mut fresh).await, Frame::new(0x7, &[]));
    drop(sleeper);
}

#[tokio::test]
async fn paced_hub_and_fault_rules() {
    // 125 kbit/s: an 8-byte standard frame is ≥ 111 bits ≈ 0.9 ms.
    let hub = Hub::new(HubConfig { bitrate: Some(125_000), ..HubConfig::default() });
    hub.add_fault(FaultRule::drop_frames().ids(0x700..=0x7FF)).unwrap();
    let (srv, addr) =
        SocketcandServer::bind_with("127.0.0.1:0", SocketcandConfig::new("can0"), hub).await.unwrap();
    let mut client = connect(addr, "can0").await.unwrap();
    sleep(Duration::from_millis(40)).await;
    let drive = srv.attach();
    let start = std::time::Instant::now();
    for i in 0..50u8 {
        drive.send(Frame::new(0x180, &[i, 0, 0, 0, 0, 0, 0, 0])).await.unwrap();
    }
    drive.send(Frame::new(0x705, &[5])).await.unwrap();
    drive.send(Frame::new(0x181, &[])).await.unwrap();
    for i in 0..50u8 {
        assert_eq!(recv(&mut client).await.data()[0], i);
    }
    // Pacing is a lower bound only (a busy machine may be slower still).
    assert!(start.elapsed() >= Duration::from_millis(40), "{:?}", start.elapsed());
    assert_eq!(recv(&mut client).await, Frame::new(0x181, &[]));
    assert_eq!(srv.hub().dropped(), 1);
}

#[tokio::test]
async fn bursts_larger_than_a_write_batch_arrive_complete_and_in_order() {
    let (srv, addr) = server().await;
    let mut client = connect(addr, "can0").await.unwrap();
    sleep(Duration::from_millis(40)).await;
    let drive = srv.attach();
    for i in 0..3_000u16 {
        drive.send(Frame::new(0x180, &i.to_le_bytes())).await.unwrap();
    }
    for i in 0..3_000u16 {
        assert_eq!(recv(&mut client).await, Frame::new(0x180, &i.to_le_bytes()));
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn client_that_stops_reading_is_dropped_after_write_timeout() {
    let cfg = SocketcandConfig { write_timeout: Duration::from_millis(200), ..SocketcandConfig::new("can0") };
    let (srv, addr) = SocketcandServer::bind_with("127.0.0.1:0", cfg, Hub::default()).await.unwrap();
    let sock = tokio::net::TcpSocket::new_v4().unwrap();
    sock.set_recv_buffer_size(4096).unwrap();
    let mut s = sock.connect(addr).await.unwrap();
    assert_eq!(recv_once(&mut s).await, b"< hi >");
    // Flood `< echo >` without ever reading the answers (bounded).
    let chunk = b"< echo >".repeat(1024);
    for _ in 0..2_000 {
        match timeout(Duration::from_millis(100), s.write_all(&chunk)).await {
            Ok(Ok(())) => {}
            _ => break, // the server stopped reading us, or closed
        }
        if srv.client_count() == 0 {
            break;
        }
    }
    for _ in 0..300 {
        if srv.client_count() == 0 {
            break;
        }
        sleep(Duration::from_millis(10)).await;
    }
    assert_eq!(srv.client_count(), 0);
}

/// `close` returns only once the server has every frame: a program that
/// exits right after it loses nothing (the CLI's `nmt stop` contract).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn close_delivers_everything_sent_before_it() {
    let (srv, addr) = server().await;
    let mut spy = srv.attach();
    for round in 0..20u8 {
        let bus = timeout(T, connect(addr, "can0")).await.unwrap().unwrap();
        for k in 0..5u8 {
            bus.send(Frame::new(0x000, &[0x02, round.wrapping_mul(5).wrapping_add(k)])).await.unwrap();
        }
        bus.flush().await.unwrap();
        bus.send(Frame::new(0x000, &[0x02, 0xFF])).await.unwrap();
        bus.close().await.unwrap();
    }
    let mut n = 0;
    while let Ok(Ok(f)) = timeout(Duration::from_millis(300), spy.recv()).await {
        assert_eq!(f.std_id(), Some(0x000));
        n += 1;
    }
    assert_eq!(n, 20 * 6, "every frame sent before close reached the hub");
}

#[tokio::test]
async fn close_returns_with_the_port_closed() {
    let (srv, addr) = server().await;
    let _client = raw_client(addr).await;
    srv.close().await;
    // A blocking connect, no yield to the runtime: the listener must be
    // gone when `close` returns, not at the runtime's next turn.
    let r = std::net::TcpStream::connect(addr);
    assert!(r.is_err(), "connected to {addr} after close");
}
