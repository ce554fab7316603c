//! SDO server CPU cost, measured like the CANopenNode anchors
//! (shared/reference/anchor-measurements.md, "What each figure times"):
//! request frame in → server → response frame(s) out, single thread, the
//! scripted client's frame building and checks inside the timed loop,
//! synthetic time (no clock reads), a record-and-return transmit sink.
//!
//! (a) expedited upload 1000h:00; (b) expedited download of a changing u32
//! to 1007h:00; (c) segmented upload and (c') download of a 10240-byte
//! DOMAIN; (d1) block upload with CRC, blksize 127; (d2) block download with
//! CRC (precomputed, as in the anchor harness).
//!
//! Run: `cargo bench -p drivebus-sdo --bench sdo_server -- --warm-up-time 1 --measurement-time 2`

// criterion's macros generate undocumented items.
#![allow(missing_docs)]

use criterion::{Criterion, Throughput, black_box, criterion_group, criterion_main};
use drivebus_can::{Duration, Frame, Instant, TxSink};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, SubObject, Value};
use drivebus_sdo::crc::crc16;
use drivebus_sdo::server::{SdoServer, ServerConfig};

const RX: u16 = 0x605;
const LEN: usize = 10240;

/// Record-and-return transmit: keeps the last frame and a count, like the
/// anchor harness's ring copy with the bus always free.
struct Sink {
    last: Frame,
    n: usize,
}
impl TxSink for Sink {
    #[inline]
    fn send(&mut self, frame: Frame) {
        self.last = frame;
        self.n += 1;
    }
}

/// A dictionary of the size of a small DS301 device, so lookups are not
/// artificially short: communication objects, 4+4 PDO records, 2000h.
fn od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    let u32var = |i, a, v| Object::var(i, "x", DataType::Unsigned32, a, Value::U32(v));
    od.insert(u32var(0x1000, Access::Ro, 0x0002_0192));
    od.insert(Object::var(0x1001, "x", DataType::Unsigned8, Access::Ro, Value::U8(0)));
    for i in [0x1005, 0x1006, 0x1007, 0x1014, 0x1017] {
        od.insert(u32var(i, Access::Rw, 0));
    }
    od.insert(Object::var(
        0x1008,
        "x",
        DataType::VisibleString,
        Access::Const,
        Value::Str("drivebus".into()),
    ));
    let ident = Object::record(0x1018, "Identity")
        .with_sub(SubObject::new(1, "v", DataType::Unsigned32, Access::Ro, Value::U32(1)))
        .with_sub(SubObject::new(2, "p", DataType::Unsigned32, Access::Ro, Value::U32(2)));
    od.insert(ident);
    for base in [0x1400u16, 0x1600, 0x1800, 0x1A00] {
        for k in 0..4 {
            od.insert(Object::array(base + k, "pdo", DataType::Unsigned32, Access::Rw, 8, Value::U32(0)));
        }
    }
    od.insert(Object::var(0x2000, "blob", DataType::Domain, Access::Rw, Value::Bytes(pattern())));
    for i in 0x6040..0x6050 {
        od.insert(Object::var(i, "x", DataType::Unsigned16, Access::Rw, Value::U16(0)));
    }
    od
}

fn pattern() -> Vec<u8> {
    (0..LEN).map(|i| (i * 31 + 7) as u8).collect()
}

struct Bench {
    s: SdoServer,
    od: ObjectDictionary,
    out: Sink,
    now: Instant,
}

impl Bench {
    fn new() -> Bench {
        Bench {
            s: SdoServer::default_channel(5, ServerConfig::default()),
            od: od(),
            out: Sink { last: Frame::new8(0, [0; 8]), n: 0 },
            now: Instant::ZERO,
        }
    }
    /// One request in; returns the last response.
    #[inline(always)]
    fn req(&mut self, data: [u8; 8]) -> [u8; 8] {
        self.s.handle_frame(&Frame::new8(RX, data), self.now, &mut self.od, &mut NoHooks, &mut self.out);
        *self.out.last.raw_data()
    }
}

fn expedited(c: &mut Criterion) {
    let mut b = Bench::new();
    c.bench_function("a_expedited_upload_1000h", |bch| {
        bch.iter(|| {
            let n = b.out.n;
            let r = b.req(black_box([0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]));
            assert!(b.out.n == n + 1 && r[0] == 0x43);
        })
    });
    let mut v = 0u32;
    c.bench_function("b_expedited_download_1007h", |bch| {
        bch.iter(|| {
            v = v.wrapping_add(1);
            let d = v.to_le_bytes();
            let r = b.req(black_box([0x23, 0x07, 0x10, 0x00, d[0], d[1], d[2], d[3]]));
            assert!(r[0] == 0x60);
        })
    });
}

/// Segmented upload of 2000h into the client's buffer.
fn segmented_upload(b: &mut Bench, dst: &mut Vec<u8>) {
    dst.clear();
    let r = b.req([0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0]);
    assert!(r[0] == 0x41);
    let mut toggle = 0u8;
    loop {
        let s = b.req([0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]);
        if s[0] & 1 == 0 {
            // Full segment: a constant-length copy, as a C client would do.
            dst.extend_from_slice(&s[1..8]);
        } else {
            let k = 7 - usize::from((s[0] >> 1) & 7);
            dst.extend_from_slice(&s[1..1 + k]);
        }
        if s[0] & 1 != 0 {
            break;
        }
        toggle ^= 0x10;
    }
}

/// Segment payload into bytes 1..8, fixed-size for full segments.
#[inline(always)]
fn put(f: &mut [u8; 8], c: &[u8]) {
    match c.first_chunk::<7>() {
        Some(full) => f[1..8].copy_from_slice(full),
        None => f[1..1 + c.len()].copy_from_slice(c),
    }
}

/// Segmented download of `src` to 2000h.
fn segmented_download(b: &mut Bench, src: &[u8]) {
    let s = (src.len() as u32).to_le_bytes();
    assert!(b.req([0x21, 0x00, 0x20, 0x00, s[0], s[1], s[2], s[3]])[0] == 0x60);
    let mut toggle = 0u8;
    let chunks = src.len().div_ceil(7);
    for (k, c) in src.chunks(7).enumerate() {
        let last = k + 1 == chunks;
        let mut f = [toggle | (((7 - c.len()) as u8) << 1) | u8::from(last), 0, 0, 0, 0, 0, 0, 0];
        put(&mut f, c);
        let r = b.req(f);
        assert!(r[0] == 0x20 | toggle);
        toggle ^= 0x10;
    }
}

/// Block upload of 2000h with CRC, blksize 127.
fn block_upload(b: &mut Bench, dst: &mut Vec<u8>, crc: u16) {
    dst.clear();
    let r = b.req([0xA4, 0x00, 0x20, 0x00, 127, 0, 0, 0]);
    assert!(r[0] == 0xC6);
    // The server emits a whole sub-block per call: collect it with a sink
    // that appends the data to the client's buffer.
    struct Collect<'a> {
        dst: &'a mut Vec<u8>,
        seqs: u8,
        last: [u8; 8],
    }
    impl TxSink for Collect<'_> {
        #[inline]
        fn send(&mut self, f: Frame) {
            let d = f.raw_data();
            self.dst.extend_from_slice(&d[1..8]);
            self.seqs += 1;
            self.last = *d;
        }
    }
    let mut cmd = [0xA3, 0, 0, 0, 0, 0, 0, 0];
    loop {
        let mut col = Collect { dst, seqs: 0, last: [0; 8] };
        b.s.handle_frame(&Frame::new8(RX, cmd), b.now, &mut b.od, &mut NoHooks, &mut col);
        let (seqs, last) = (col.seqs, col.last);
        assert!(last[0] & 0x7F == seqs);
        cmd = [0xA2, seqs, 127, 0, 0, 0, 0, 0];
        if last[0] & 0x80 != 0 {
            break;
        }
    }
    let end = b.req(cmd);
    assert!(end[0] & 0xE3 == 0xC1 && u16::from_le_bytes([end[1], end[2]]) == crc);
    let n = usize::from((end[0] >> 2) & 7);
    dst.truncate(dst.len() - n);
    let before = b.out.n;
    b.req([0xA1, 0, 0, 0, 0, 0, 0, 0]);
    assert!(b.out.n == before);
}

/// Block download of `src` to 2000h with a precomputed CRC.
fn block_download(b: &mut Bench, src: &[u8], crc: u16) {
    let s = (src.len() as u32).to_le_bytes();
    let r = b.req([0xC6, 0x00, 0x20, 0x00, s[0], s[1], s[2], s[3]]);
    assert!(r[0] == 0xA4);
    let blksize = usize::from(r[4]);
    let total = src.len().div_ceil(7);
    for (k, c) in src.chunks(7).enumerate() {
        let seq = (k % blksize + 1) as u8;
        let last = k + 1 == total;
        let mut f = [seq | (u8::from(last) << 7), 0, 0, 0, 0, 0, 0, 0];
        put(&mut f, c);
        b.s.handle_frame(&Frame::new8(RX, f), b.now, &mut b.od, &mut NoHooks, &mut b.out);
    }
    assert!(b.out.last.raw_data()[0] == 0xA2);
    let n = (total * 7 - src.len()) as u8;
    let c = crc.to_le_bytes();
    assert!(b.req([0xC1 | (n << 2), c[0], c[1], 0, 0, 0, 0, 0])[0] == 0xA1);
}

fn transfers(c: &mut Criterion) {
    let mut g = c.benchmark_group("sdo_server_10k");
    g.throughput(Throughput::Bytes(LEN as u64));
    let mut b = Bench::new();
    let src = pattern();
    let crc = crc16(&src);
    let mut dst = Vec::with_capacity(LEN + 7);

    segmented_upload(&mut b, &mut dst);
    assert_eq!(dst, src);
    g.bench_function("c_segmented_upload", |bch| bch.iter(|| segmented_upload(&mut b, &mut dst)));
    g.bench_function("c2_segmented_download", |bch| bch.iter(|| segmented_download(&mut b, &src)));
    assert_eq!(b.od.get(0x2000, 0).unwrap().bytes(), &src[..]);
    block_upload(&mut b, &mut dst, crc);
    assert_eq!(dst, src);
    g.bench_function("d1_block_upload_crc", |bch| bch.iter(|| block_upload(&mut b, &mut dst, crc)));
    g.bench_function("d2_block_download_crc", |bch| bch.iter(|| block_download(&mut b, &src, crc)));
    assert_eq!(b.od.get(0x2000, 0).unwrap().bytes(), &src[..]);
    g.finish();
    // Time never moves in these loops; keep the deadline logic honest anyway.
    b.now += Duration::from_millis(1);
}

criterion_group!(benches, expedited, transfers);
criterion_main!(benches);
