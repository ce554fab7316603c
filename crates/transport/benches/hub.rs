//! Frames per second the socketcand hub relays between 10 TCP clients on
//! loopback. Each iteration: every client sends 200 frames (2000 into the
//! hub) and receives the other 9 clients' 1800; the throughput reported is
//! frames into the hub per second (each is delivered 9 times).
//!
//! `cargo bench -p drivebus-transport --bench hub`

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use drivebus_transport::Frame;
use drivebus_transport::socketcand::{SocketcandServer, connect};

const CLIENTS: usize = 10;
const PER_CLIENT: usize = 200;

fn hub(c: &mut Criterion) {
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let (srv, clients) = rt.block_on(async {
        let (srv, addr) = SocketcandServer::bind("127.0.0.1:0", "can0").await.unwrap();
        let mut v = Vec::new();
        for _ in 0..CLIENTS {
            v.push(connect(addr, "can0").await.unwrap());
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
        (srv, v)
    });
    let mut clients = Some(clients);
    let mut g = c.benchmark_group("socketcand_hub");
    g.throughput(Throughput::Elements((CLIENTS * PER_CLIENT) as u64));
    g.sample_size(10).measurement_time(Duration::from_secs(5)).warm_up_time(Duration::from_secs(1));
    g.bench_function("10_tcp_clients", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let cl = clients.take().unwrap();
                let (back, dt) = rt.block_on(round(cl));
                clients = Some(back);
                total += dt;
            }
            total
        })
    });
    g.finish();
    drop(srv);
}

/// One round: all clients send, all receive everything from the others.
async fn round(clients: Vec<drivebus_transport::CanBus>) -> (Vec<drivebus_transport::CanBus>, Duration) {
    let start = Instant::now();
    let mut tasks = Vec::new();
    for (i, bus) in clients.into_iter().enumerate() {
        tasks.push(tokio::spawn(async move {
            let (tx, mut rx) = bus.split();
            let sender = tokio::spawn(async move {
                for k in 0..PER_CLIENT {
                    tx.send(Frame::new(0x100 + i as u16, &(k as u32).to_le_bytes())).await.unwrap();
                }
                tx
            });
            let want = (CLIENTS - 1) * PER_CLIENT;
            for _ in 0..want {
                tokio::time::timeout(Duration::from_secs(30), rx.recv()).await.expect("hub stalled").unwrap();
            }
            let tx = sender.await.unwrap();
            drivebus_transport::CanBus::from_parts(tx, rx)
        }));
    }
    let mut back = Vec::new();
    for t in tasks {
        back.push(t.await.unwrap());
    }
    (back, start.elapsed())
}

criterion_group!(benches, hub);
criterion_main!(benches);
