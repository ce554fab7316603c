//! SDO client frame-path benchmarks against scripted server responses:
//! (1) expedited upload (request + response), (2) block download of 889
//! bytes (one 127-segment sub-block, ack, end), (3) block upload of 889 bytes.
#![allow(missing_docs)]

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use drivebus_can::{Frame, Instant, TxSink};
use drivebus_sdo::client::{Protocol, SdoClient, SdoClientConfig};

/// Counts frames instead of storing them, so the bench measures the client.
struct Count(usize);
impl TxSink for Count {
    #[inline]
    fn send(&mut self, f: Frame) {
        self.0 += black_box(f).len();
    }
}

fn bench(c: &mut Criterion) {
    let now = Instant::ZERO;
    let mut client = SdoClient::new(SdoClientConfig::for_node(1));
    let mut out = Count(0);

    let resp = Frame::new8(0x581, [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00]);
    c.bench_function("client expedited upload", |b| {
        b.iter(|| {
            client.start_upload(0x1000, 0, Protocol::Auto, now, &mut out).unwrap();
            client.handle_frame(black_box(&resp), now, &mut out);
            black_box(client.take_result())
        })
    });

    let data = vec![0x5Au8; 889];
    let init = Frame::new8(0x581, [0xA4, 0x00, 0x20, 0x00, 127, 0, 0, 0]);
    let ack = Frame::new8(0x581, [0xA2, 127, 127, 0, 0, 0, 0, 0]);
    let end = Frame::new8(0x581, [0xA1, 0, 0, 0, 0, 0, 0, 0]);
    c.bench_function("client block download 889 B", |b| {
        b.iter(|| {
            client.start_download(0x2000, 0, &data, Protocol::Block, now, &mut out).unwrap();
            client.handle_frame(&init, now, &mut out);
            client.handle_frame(&ack, now, &mut out);
            client.handle_frame(&end, now, &mut out);
            black_box(client.take_result())
        })
    });

    let up_init = Frame::new8(0x581, [0xC6, 0x00, 0x20, 0x00, 0x79, 0x03, 0, 0]);
    let segs: Vec<Frame> = (1..=127u8)
        .map(|s| Frame::new8(0x581, [s | if s == 127 { 0x80 } else { 0 }, 1, 2, 3, 4, 5, 6, 7]))
        .collect();
    let mut payload = Vec::new();
    for _ in 0..127 {
        payload.extend_from_slice(&[1, 2, 3, 4, 5, 6, 7]);
    }
    let [lo, hi] = drivebus_sdo::crc::crc16(&payload).to_le_bytes();
    let up_end = Frame::new8(0x581, [0xC1, lo, hi, 0, 0, 0, 0, 0]);
    c.bench_function("client block upload 889 B", |b| {
        b.iter(|| {
            client.start_upload(0x2000, 0, Protocol::Block, now, &mut out).unwrap();
            client.handle_frame(&up_init, now, &mut out);
            for f in &segs {
                client.handle_frame(f, now, &mut out);
            }
            client.handle_frame(&up_end, now, &mut out);
            black_box(client.take_result())
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
