//! Whole-node CPU cost, measured the way anchor-measurements.md measured
//! CANopenNode: one request frame in, the node's poll, one response out;
//! client-side frame building inside the loop; synthetic time.
//!
//! Run: `cargo bench -p drivebus-node --bench node`
#![allow(missing_docs)]

use criterion::{BatchSize, Criterion, Throughput, criterion_main};
use drivebus_can::{Frame, Instant, TxSink};
use drivebus_node::{Node, NodeConfig};
use drivebus_od::{Access, DataType, NoHooks, Object, SubObject, Value};
use std::hint::black_box;

/// A transmit sink that keeps the last frame, like the C harness's ring.
#[derive(Default)]
struct Last {
    n: usize,
    f: Option<Frame>,
}

impl TxSink for Last {
    #[inline]
    fn send(&mut self, frame: Frame) {
        self.n += 1;
        self.f = Some(frame);
    }
}

const DOMAIN_LEN: usize = 10_240;

fn node() -> Node {
    let mut cfg = NodeConfig::new(5);
    cfg.device_type = 0x0002_0192;
    cfg.sdo.max_download = 1 << 20;
    let mut n = Node::new(cfg);
    let pattern: Vec<u8> = (0..DOMAIN_LEN).map(|i| (i * 7 + 3) as u8).collect();
    n.insert_object(Object::var(0x2000, "Blob", DataType::Domain, Access::Rw, Value::Bytes(pattern)));
    for (i, acc) in
        [(0x2100u16, Access::Rww), (0x2101, Access::Rww), (0x2110, Access::Rwr), (0x2111, Access::Rwr)]
    {
        n.insert_object(
            Object::var(i, "pdo var", DataType::Unsigned32, acc, Value::U32(0))
                .with_sub(SubObject::new(0, "pdo var", DataType::Unsigned32, acc, Value::U32(0)).mappable()),
        );
    }
    let mut out = Vec::new();
    n.boot(Instant::ZERO, &mut NoHooks, &mut out);
    // RPDO1 205h async (254) ← 2100h, 2101h; TPDO1 185h every SYNC ← 2110h, 2111h.
    let cfg_frames: [[u8; 8]; 16] = [
        [0x23, 0x00, 0x14, 1, 0x05, 0x02, 0, 0x80],
        [0x2F, 0x00, 0x16, 0, 0, 0, 0, 0],
        [0x23, 0x00, 0x16, 1, 0x20, 0, 0x00, 0x21],
        [0x23, 0x00, 0x16, 2, 0x20, 0, 0x01, 0x21],
        [0x2F, 0x00, 0x16, 0, 2, 0, 0, 0],
        [0x2F, 0x00, 0x14, 2, 254, 0, 0, 0],
        [0x23, 0x00, 0x14, 1, 0x05, 0x02, 0, 0],
        [0x23, 0x00, 0x18, 1, 0x85, 0x01, 0, 0x80],
        [0x2F, 0x00, 0x1A, 0, 0, 0, 0, 0],
        [0x23, 0x00, 0x1A, 1, 0x20, 0, 0x10, 0x21],
        [0x23, 0x00, 0x1A, 2, 0x20, 0, 0x11, 0x21],
        [0x2F, 0x00, 0x1A, 0, 2, 0, 0, 0],
        [0x2F, 0x00, 0x18, 2, 1, 0, 0, 0],
        [0x23, 0x00, 0x18, 1, 0x85, 0x01, 0, 0],
        [0x2B, 0x17, 0x10, 0, 0, 0, 0, 0],
        [0x2B, 0x17, 0x10, 0, 0, 0, 0, 0],
    ];
    for d in cfg_frames {
        out.clear();
        n.handle_frame(&Frame::new(0x605, &d), Instant::ZERO, &mut NoHooks, &mut out);
        assert_eq!(out[0].data()[0], 0x60, "configuration write refused: {:?} → {:?}", d, out[0]);
    }
    n.handle_frame(&Frame::new(0x000, &[0x01, 0x05]), Instant::ZERO, &mut NoHooks, &mut out);
    n
}

fn crc16(data: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    for &b in data {
        crc ^= (b as u16) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 { (crc << 1) ^ 0x1021 } else { crc << 1 };
        }
    }
    crc
}

fn expedited(c: &mut Criterion) {
    let mut g = c.benchmark_group("node");
    let mut n = node();
    let now = Instant::from_millis(1);
    let req = Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
    g.bench_function("a_expedited_upload_1000h", |b| {
        let mut out = Last::default();
        b.iter(|| {
            n.handle_frame(black_box(&req), now, &mut NoHooks, &mut out);
            black_box(n.poll(now, &mut NoHooks, &mut out));
        });
        assert_eq!(out.f.unwrap().data()[0], 0x43);
    });
    g.bench_function("b_expedited_download_1007h", |b| {
        let mut out = Last::default();
        let mut v: u32 = 0;
        b.iter(|| {
            v = v.wrapping_add(1);
            let x = v.to_le_bytes();
            let req = Frame::new8(0x605, [0x23, 0x07, 0x10, 0, x[0], x[1], x[2], x[3]]);
            n.handle_frame(&req, now, &mut NoHooks, &mut out);
            black_box(n.poll(now, &mut NoHooks, &mut out));
        });
        assert_eq!(out.f.unwrap().data()[0], 0x60);
    });
    // The like-for-like of CANopenNode's figure b: a plain variable with no
    // service behind it (1007h above reconfigures the SYNC service).
    g.bench_function("b2_expedited_download_plain", |b| {
        let mut out = Last::default();
        let mut v: u32 = 0;
        b.iter(|| {
            v = v.wrapping_add(1);
            let x = v.to_le_bytes();
            let req = Frame::new8(0x605, [0x23, 0x11, 0x21, 0, x[0], x[1], x[2], x[3]]);
            n.handle_frame(&req, now, &mut NoHooks, &mut out);
            black_box(n.poll(now, &mut NoHooks, &mut out));
        });
        assert_eq!(out.f.unwrap().data()[0], 0x60);
    });
    g.bench_function("e1_rpdo_8_bytes", |b| {
        let mut out = Last::default();
        let mut v: u32 = 0;
        b.iter(|| {
            v = v.wrapping_add(1);
            let x = v.to_le_bytes();
            let f = Frame::new8(0x205, [x[0], x[1], x[2], x[3], 1, 2, 3, 4]);
            n.handle_frame(black_box(&f), now, &mut NoHooks, &mut out);
        });
        assert_eq!(n.od().get_u32(0x2100, 0), Some(v));
    });
    let sync = Frame::new(0x080, &[]);
    g.bench_function("e2_sync_to_tpdo", |b| {
        let mut out = Last::default();
        let mut v: u32 = 0;
        let r = n.od().find(0x2110, 0).unwrap();
        b.iter(|| {
            v = v.wrapping_add(1);
            n.od_mut().set_le(r, &v.to_le_bytes());
            n.handle_frame(black_box(&sync), now, &mut NoHooks, &mut out);
        });
        let f = out.f.unwrap();
        assert_eq!((f.std_id(), &f.data()[..4]), (Some(0x185), &v.to_le_bytes()[..]));
    });
    g.bench_function("idle_poll", |b| {
        let mut out = Last::default();
        b.iter(|| black_box(n.poll(now, &mut NoHooks, &mut out)));
    });
    g.finish();
}

fn transfers(c: &mut Criterion) {
    let mut g = c.benchmark_group("node_10KiB");
    g.throughput(Throughput::Bytes(DOMAIN_LEN as u64));
    let now = Instant::from_millis(1);
    g.bench_function("c_segmented_upload", |b| {
        let mut n = node();
        let mut out = Last::default();
        b.iter(|| {
            n.handle_frame(
                &Frame::new8(0x605, [0x40, 0x00, 0x20, 0, 0, 0, 0, 0]),
                now,
                &mut NoHooks,
                &mut out,
            );
            let mut toggle = 0u8;
            loop {
                n.handle_frame(
                    &Frame::new8(0x605, [0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]),
                    now,
                    &mut NoHooks,
                    &mut out,
                );
                n.poll(now, &mut NoHooks, &mut out);
                toggle ^= 0x10;
                if out.f.unwrap().data()[0] & 1 != 0 {
                    break;
                }
            }
        });
    });
    let data: Vec<u8> = (0..DOMAIN_LEN).map(|i| (i * 13) as u8).collect();
    g.bench_function("c2_segmented_download", |b| {
        let mut n = node();
        let mut out = Last::default();
        let size = (DOMAIN_LEN as u32).to_le_bytes();
        b.iter(|| {
            n.handle_frame(
                &Frame::new8(0x605, [0x21, 0x00, 0x20, 0, size[0], size[1], size[2], size[3]]),
                now,
                &mut NoHooks,
                &mut out,
            );
            let mut toggle = 0u8;
            for chunk in data.chunks(7) {
                let last = chunk.as_ptr() == data.chunks(7).last().unwrap().as_ptr();
                let mut d = [0u8; 8];
                d[0] = toggle | (((7 - chunk.len()) as u8) << 1) | last as u8;
                d[1..1 + chunk.len()].copy_from_slice(chunk);
                n.handle_frame(&Frame::new8(0x605, d), now, &mut NoHooks, &mut out);
                n.poll(now, &mut NoHooks, &mut out);
                toggle ^= 0x10;
            }
            // The last response echoes the last request's toggle.
            assert_eq!(out.f.unwrap().data()[0], 0x20 | (toggle ^ 0x10));
        });
    });
    let crc = crc16(&data);
    g.bench_function("d2_block_download_crc", |b| {
        let mut n = node();
        let mut out = Last::default();
        let size = (DOMAIN_LEN as u32).to_le_bytes();
        let segs: Vec<[u8; 8]> = {
            let chunks: Vec<&[u8]> = data.chunks(7).collect();
            let mut v = Vec::new();
            let mut seq = 0u8;
            for (i, ch) in chunks.iter().enumerate() {
                seq = if seq == 127 { 1 } else { seq + 1 };
                let mut d = [0u8; 8];
                d[0] = seq | if i + 1 == chunks.len() { 0x80 } else { 0 };
                d[1..1 + ch.len()].copy_from_slice(ch);
                v.push(d);
            }
            v
        };
        let n_unused = (7 - (DOMAIN_LEN % 7) % 7) % 7;
        b.iter(|| {
            n.handle_frame(
                &Frame::new8(0x605, [0xC6, 0x00, 0x20, 0, size[0], size[1], size[2], size[3]]),
                now,
                &mut NoHooks,
                &mut out,
            );
            for s in &segs {
                n.handle_frame(&Frame::new8(0x605, *s), now, &mut NoHooks, &mut out);
            }
            n.poll(now, &mut NoHooks, &mut out);
            let c = crc.to_le_bytes();
            n.handle_frame(
                &Frame::new8(0x605, [0xC1 | ((n_unused as u8) << 2), c[0], c[1], 0, 0, 0, 0, 0]),
                now,
                &mut NoHooks,
                &mut out,
            );
            assert_eq!(out.f.unwrap().data()[0], 0xA1);
        });
    });
    g.bench_function("d1_block_upload_crc", |b| {
        let mut n = node();
        b.iter_batched_ref(
            Last::default,
            |out| {
                n.handle_frame(
                    &Frame::new8(0x605, [0xA4, 0x00, 0x20, 0, 127, 0, 0, 0]),
                    now,
                    &mut NoHooks,
                    out,
                );
                n.handle_frame(&Frame::new8(0x605, [0xA3, 0, 0, 0, 0, 0, 0, 0]), now, &mut NoHooks, out);
                loop {
                    let last = out.f.unwrap();
                    let seq = last.data()[0];
                    if last.data()[0] & 0xE3 == 0xC1 {
                        break;
                    }
                    n.handle_frame(
                        &Frame::new8(0x605, [0xA2, seq & 0x7F, 127, 0, 0, 0, 0, 0]),
                        now,
                        &mut NoHooks,
                        out,
                    );
                }
                n.handle_frame(&Frame::new8(0x605, [0xA1, 0, 0, 0, 0, 0, 0, 0]), now, &mut NoHooks, out);
            },
            BatchSize::SmallInput,
        );
    });
    g.finish();
}

criterion::criterion_group!(benches, expedited, transfers);
criterion_main!(benches);
