//! drivebus side of bench-canopennode, written as a line-by-line mirror of
//! the C harness (bench_main.c), to cross-check the criterion bench
//! (`crates/node/benches/node.rs`), whose loops differ in small ways.
//!
//! run.sh copies this file into the copied project as
//! `crates/node/examples/bench_mirror.rs` and builds it with
//! `cargo build --release -p drivebus-node --example bench_mirror`
//! (release profile: lto = "fat", codegen-units = 1, like the bench profile).
//!
//! Same method as the C harness: one node (id 5) with the anchor's objects
//! (same set-up as node.rs), frames passed to `handle_frame` and the node's
//! processing called back-to-back, every sent frame copied into a 256-entry
//! ring, synthetic time advanced by 100 us per call, the client side (frame
//! building, a check on every response, copying every received segment)
//! inside the timed loops, the same iteration counts, warm-up and
//! CLOCK_MONOTONIC timing of each repetition as a whole.
//!
//! Usage: bench_mirror [-r REPS] [-f fig,fig] [-s SCALE]
//! Output: `RESULT drivebus-mirror <figure> <rep> <ns per iteration> <failures>`.
#![allow(missing_docs)]

use drivebus_can::{Frame, Instant, TxSink};
use drivebus_node::{Node, NodeConfig};
use drivebus_od::{Access, DataType, NoHooks, Object, SubObject, Value};
use std::hint::black_box;

const DOMAIN_LEN: usize = 10_240;
const SDO_RX: u16 = 0x605;
const SDO_TX: u16 = 0x585;
const TD_US: u64 = 100;
const RING: usize = 256;

/// Record-and-return transmit, like CO_CANsend in the C driver.
struct Ring {
    frames: [Frame; RING],
    head: u32,
}

impl TxSink for Ring {
    #[inline]
    fn send(&mut self, frame: Frame) {
        self.frames[self.head as usize % RING] = frame;
        self.head = self.head.wrapping_add(1);
    }
}

impl Ring {
    #[inline]
    fn last(&self) -> &Frame {
        &self.frames[self.head.wrapping_sub(1) as usize % RING]
    }
    #[inline]
    fn at(&self, i: u32) -> &Frame {
        &self.frames[i as usize % RING]
    }
}

struct Bench {
    n: Node,
    out: Ring,
    t_us: u64,
    pat_dl: Vec<u8>,
    upbuf: Vec<u8>,
    up_len: usize,
    crc_dl: u16,
    crc_up_server: u16,
    r2000: drivebus_od::EntryRef,
    r2100: drivebus_od::EntryRef,
    r2110: drivebus_od::EntryRef,
    v_b: u32,
    v_b1007: u32,
    v_e1: u32,
    v_e2: u32,
    v_e3: u32,
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

#[inline]
fn rd32(d: &[u8]) -> u32 {
    u32::from_le_bytes([d[0], d[1], d[2], d[3]])
}

/// The node of crates/node/benches/node.rs: 2000h 10240-byte domain,
/// 2100h/2101h RPDO-mappable u32, 2110h/2111h TPDO-mappable u32,
/// RPDO1 205h type 254 -> 2100h+2101h, TPDO1 185h type 1 -> 2110h+2111h.
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
        assert_eq!(out[0].data()[0], 0x60, "configuration write refused: {:?} -> {:?}", d, out[0]);
    }
    out.clear();
    // NMT start remote node 5
    n.handle_frame(&Frame::new(0x000, &[0x01, 0x05]), Instant::ZERO, &mut NoHooks, &mut out);
    n.poll(Instant::ZERO, &mut NoHooks, &mut out);
    n
}

impl Bench {
    #[inline]
    fn tick(&mut self) -> Instant {
        self.t_us += TD_US;
        Instant::from_micros(self.t_us)
    }
    // Every node call goes through black_box(&mut node), so the compiler
    // cannot hoist the node's state checks out of the timed loops (the C
    // harness calls into separately compiled stack code, which it cannot
    // hoist either). Without it the idle loop folds to ~2 ns.

    /// One request in, the node's poll: the counterpart of inject + CO_process.
    #[inline]
    fn request(&mut self, f: &Frame) {
        let now = self.tick();
        let n = black_box(&mut self.n);
        n.handle_frame(black_box(f), now, &mut NoHooks, &mut self.out);
        n.poll(now, &mut NoHooks, &mut self.out);
    }
    #[inline]
    fn inject_only(&mut self, f: &Frame) {
        let now = self.tick();
        black_box(&mut self.n).handle_frame(black_box(f), now, &mut NoHooks, &mut self.out);
    }
    #[inline]
    fn poll(&mut self) {
        let now = self.tick();
        black_box(&mut self.n).poll(now, &mut NoHooks, &mut self.out);
    }
    fn sdo_abort(&mut self) {
        self.request(&Frame::new8(SDO_RX, [0x80, 0, 0, 0, 0, 0, 0, 0]));
    }

    fn idle(&mut self, n: u64) -> u64 {
        let h = self.out.head;
        for _ in 0..n {
            self.poll();
        }
        (self.out.head != h) as u64
    }

    fn a(&mut self, n: u64) -> u64 {
        let mut fails = 0;
        for _ in 0..n {
            let h = self.out.head;
            self.request(&Frame::new8(SDO_RX, [0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]));
            let r = self.out.last();
            if self.out.head != h.wrapping_add(1) || r.std_id() != Some(SDO_TX) || r.data()[0] != 0x43 {
                fails += 1;
            }
        }
        fails
    }

    /// b: expedited download of a changing u32 (`idx`: 2111h plain variable, or 1007h).
    fn b_to(&mut self, n: u64, idx: u16) -> u64 {
        let mut fails = 0;
        let [lo, hi] = idx.to_le_bytes();
        for _ in 0..n {
            let h = self.out.head;
            let v = if idx == 0x1007 {
                self.v_b1007 = self.v_b1007.wrapping_add(1);
                self.v_b1007
            } else {
                self.v_b = self.v_b.wrapping_add(1);
                self.v_b
            };
            let x = v.to_le_bytes();
            self.request(&Frame::new8(SDO_RX, [0x23, lo, hi, 0x00, x[0], x[1], x[2], x[3]]));
            let r = self.out.last();
            if self.out.head != h.wrapping_add(1) || r.std_id() != Some(SDO_TX) || r.data()[0] != 0x60 {
                fails += 1;
            }
        }
        fails
    }

    fn c(&mut self, n: u64) -> u64 {
        let mut fails = 0;
        for _ in 0..n {
            let mut h = self.out.head;
            self.request(&Frame::new8(SDO_RX, [0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0]));
            let r = *self.out.last();
            if self.out.head != h.wrapping_add(1)
                || r.data()[0] != 0x41
                || rd32(&r.data()[4..]) as usize != DOMAIN_LEN
            {
                fails += 1;
                self.sdo_abort();
                continue;
            }
            let mut toggle = 0u8;
            let mut off = 0usize;
            loop {
                h = self.out.head;
                self.request(&Frame::new8(SDO_RX, [0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]));
                let d = *self.out.last().raw_data();
                let cmd = d[0];
                if self.out.head != h.wrapping_add(1) || (cmd & 0xF0) != toggle {
                    fails += 1;
                    self.sdo_abort();
                    break;
                }
                let cnt = if cmd & 1 != 0 { 7 - ((cmd >> 1) & 7) as usize } else { 7 };
                if off + cnt > DOMAIN_LEN {
                    fails += 1;
                    self.sdo_abort();
                    break;
                }
                self.upbuf[off..off + cnt].copy_from_slice(&d[1..1 + cnt]);
                off += cnt;
                toggle ^= 0x10;
                if cmd & 1 != 0 {
                    break;
                }
            }
            if off != DOMAIN_LEN {
                fails += 1;
            }
            self.up_len = off;
        }
        fails
    }

    fn c2(&mut self, n: u64) -> u64 {
        let mut fails = 0;
        let size = (DOMAIN_LEN as u32).to_le_bytes();
        for _ in 0..n {
            let h = self.out.head;
            self.request(&Frame::new8(SDO_RX, [0x21, 0x00, 0x20, 0x00, size[0], size[1], size[2], size[3]]));
            if self.out.head != h.wrapping_add(1) || self.out.last().data()[0] != 0x60 {
                fails += 1;
                self.sdo_abort();
                continue;
            }
            let mut toggle = 0u8;
            let mut off = 0usize;
            while off < DOMAIN_LEN {
                let cnt = (DOMAIN_LEN - off).min(7);
                let last = (off + cnt == DOMAIN_LEN) as u8;
                let mut d = [0u8; 8];
                d[0] = toggle | (((7 - cnt) as u8) << 1) | last;
                d[1..1 + cnt].copy_from_slice(&self.pat_dl[off..off + cnt]);
                let h = self.out.head;
                self.request(&Frame::new8(SDO_RX, d));
                if self.out.head != h.wrapping_add(1) || self.out.last().data()[0] != (0x20 | toggle) {
                    fails += 1;
                    self.sdo_abort();
                    break;
                }
                off += cnt;
                toggle ^= 0x10;
            }
        }
        fails
    }

    /// d1: block upload. drivebus sends a whole sub-block from the request
    /// that asks for it, so the client reads the sub-block's segments from
    /// the ring after that request's poll (CANopenNode needs one CO_process
    /// per segment instead).
    fn d1(&mut self, n: u64) -> u64 {
        let mut fails = 0;
        for _ in 0..n {
            let h = self.out.head;
            self.request(&Frame::new8(SDO_RX, [0xA4, 0x00, 0x20, 0x00, 127, 0, 0, 0]));
            let r = *self.out.last();
            if self.out.head != h.wrapping_add(1)
                || r.data()[0] != 0xC6
                || rd32(&r.data()[4..]) as usize != DOMAIN_LEN
            {
                fails += 1;
                self.sdo_abort();
                continue;
            }
            let mut off = 0usize;
            let mut ok = true;
            let mut last_sub = false;
            let mut req = Frame::new8(SDO_RX, [0xA3, 0, 0, 0, 0, 0, 0, 0]);
            while !last_sub {
                let mut h = self.out.head;
                self.request(&req);
                let mut seq = 0u8;
                let mut expect = 0u8;
                while h != self.out.head {
                    let d = *self.out.at(h).raw_data();
                    h = h.wrapping_add(1);
                    seq = d[0] & 0x7F;
                    expect += 1;
                    if seq != expect || off + 7 > self.upbuf.len() {
                        ok = false;
                        break;
                    }
                    self.upbuf[off..off + 7].copy_from_slice(&d[1..8]);
                    off += 7;
                    if d[0] & 0x80 != 0 {
                        last_sub = true;
                        break;
                    }
                    if seq == 127 {
                        break;
                    }
                }
                if !ok || h != self.out.head || seq == 0 {
                    ok = false;
                    break;
                }
                req = Frame::new8(SDO_RX, [0xA2, seq, 127, 0, 0, 0, 0, 0]);
            }
            if !ok {
                fails += 1;
                self.sdo_abort();
                continue;
            }
            // The last ack: the server answers with the end frame (CRC).
            let h = self.out.head;
            self.request(&req);
            let r = *self.out.last();
            if self.out.head != h.wrapping_add(1) || (r.data()[0] & 0xE3) != 0xC1 {
                fails += 1;
                self.sdo_abort();
                continue;
            }
            off -= ((r.data()[0] >> 2) & 7) as usize;
            self.crc_up_server = u16::from_le_bytes([r.data()[1], r.data()[2]]);
            self.request(&Frame::new8(SDO_RX, [0xA1, 0, 0, 0, 0, 0, 0, 0]));
            if off != DOMAIN_LEN {
                fails += 1;
            }
            self.up_len = off;
        }
        fails
    }

    /// d2: block download, segments of a sub-block injected back-to-back
    /// (handle_frame only), then one poll per sub-block; end frame with a
    /// precomputed CRC, 0xA1 response.
    fn d2(&mut self, n: u64) -> u64 {
        let mut fails = 0;
        let size = (DOMAIN_LEN as u32).to_le_bytes();
        let no_data = ((7 - DOMAIN_LEN % 7) % 7) as u8;
        for _ in 0..n {
            let h = self.out.head;
            self.request(&Frame::new8(SDO_RX, [0xC6, 0x00, 0x20, 0x00, size[0], size[1], size[2], size[3]]));
            let r = *self.out.last();
            if self.out.head != h.wrapping_add(1) || r.data()[0] != 0xA4 {
                fails += 1;
                self.sdo_abort();
                continue;
            }
            let mut blksize = r.data()[4];
            let mut off = 0usize;
            let mut ok = true;
            let mut last = false;
            while !last {
                let h = self.out.head;
                let mut seq = 0u8;
                while seq < blksize {
                    let cnt = (DOMAIN_LEN - off).min(7);
                    last = off + cnt == DOMAIN_LEN;
                    seq += 1;
                    let mut d = [0u8; 8];
                    d[0] = seq | if last { 0x80 } else { 0 };
                    d[1..1 + cnt].copy_from_slice(&self.pat_dl[off..off + cnt]);
                    self.inject_only(&Frame::new8(SDO_RX, d));
                    off += cnt;
                    if last {
                        break;
                    }
                }
                self.poll(); // CANopenNode sends the sub-block ack here; drivebus already sent it
                let r = self.out.last();
                if self.out.head != h.wrapping_add(1) || r.data()[0] != 0xA2 || r.data()[1] != seq {
                    ok = false;
                    break;
                }
                blksize = r.data()[2];
            }
            if !ok {
                fails += 1;
                self.sdo_abort();
                continue;
            }
            let c = self.crc_dl.to_le_bytes();
            let h = self.out.head;
            self.request(&Frame::new8(SDO_RX, [0xC1 | (no_data << 2), c[0], c[1], 0, 0, 0, 0, 0]));
            if self.out.head != h.wrapping_add(1) || self.out.last().data()[0] != 0xA1 {
                fails += 1;
                self.sdo_abort();
            }
        }
        fails
    }

    fn e1(&mut self, n: u64) -> u64 {
        let mut fails = 0;
        for _ in 0..n {
            self.v_e1 = self.v_e1.wrapping_add(1);
            let v = self.v_e1;
            let x = v.to_le_bytes();
            self.inject_only(&Frame::new8(0x205, [x[0], x[1], x[2], x[3], 1, 2, 3, 4]));
            if rd32(self.n.od().bytes(self.r2100)) != v {
                fails += 1;
            }
        }
        fails
    }

    fn e2(&mut self, n: u64) -> u64 {
        let mut fails = 0;
        for _ in 0..n {
            self.v_e2 = self.v_e2.wrapping_add(1);
            let v = self.v_e2;
            self.n.od_mut().set_le(self.r2110, &v.to_le_bytes());
            let h = self.out.head;
            self.inject_only(&Frame::new(0x080, &[]));
            let r = self.out.last();
            if self.out.head != h.wrapping_add(1) || r.std_id() != Some(0x185) || rd32(r.data()) != v {
                fails += 1;
            }
        }
        fails
    }

    fn e3(&mut self, n: u64) -> u64 {
        let mut fails = 0;
        for _ in 0..n {
            self.v_e3 = self.v_e3.wrapping_add(1);
            let v = self.v_e3;
            self.n.od_mut().set_le(self.r2110, &v.to_le_bytes());
            let h = self.out.head;
            let x = v.to_le_bytes();
            self.inject_only(&Frame::new8(0x205, [x[0], x[1], x[2], x[3], 5, 6, 7, 8]));
            self.inject_only(&Frame::new(0x080, &[]));
            let r = self.out.last();
            if self.out.head != h.wrapping_add(1)
                || r.std_id() != Some(0x185)
                || rd32(r.data()) != v
                || rd32(self.n.od().bytes(self.r2100)) != v
            {
                fails += 1;
            }
        }
        fails
    }
}

type Fig = fn(&mut Bench, u64) -> u64;

struct Runner {
    reps: usize,
    scale: f64,
    only: Option<Vec<String>>,
    total_fails: u64,
}

impl Runner {
    fn selected(&self, name: &str) -> bool {
        self.only.as_ref().is_none_or(|o| o.iter().any(|x| x == name))
    }
    fn run(&mut self, b: &mut Bench, name: &str, f: Fig, count: u64, warmup: u64) {
        if !self.selected(name) {
            return;
        }
        let n = ((count as f64 * self.scale) as u64).max(1);
        let w = ((warmup as f64 * self.scale) as u64).max(1);
        let mut fails = f(b, w);
        let mut t = Vec::new();
        for rep in 0..self.reps {
            let t0 = std::time::Instant::now();
            let fl = f(b, n);
            let ns = t0.elapsed().as_nanos() as f64 / n as f64;
            fails += fl;
            t.push(ns);
            println!("RESULT\tdrivebus-mirror\t{name}\t{}\t{ns:.3}\t{fl}", rep + 1);
        }
        t.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let k = t.len();
        let med = if k % 2 == 1 { t[k / 2] } else { 0.5 * (t[k / 2 - 1] + t[k / 2]) };
        if count >= 100_000 {
            println!(
                "# drivebus-mirror {name:<8} best {:9.2} ns  median {med:9.2} ns   ({n} iterations x {k}, fails {fails})",
                t[0]
            );
        } else {
            println!(
                "# drivebus-mirror {name:<8} best {:9.2} us  median {:9.2} us  = {:7.1} / {:7.1} MB/s   ({n} transfers x {k}, fails {fails})",
                t[0] / 1e3,
                med / 1e3,
                DOMAIN_LEN as f64 * 1e3 / t[0],
                DOMAIN_LEN as f64 * 1e3 / med
            );
        }
        self.total_fails += fails;
    }
    fn check(&mut self, cond: bool, what: &str) {
        if !cond {
            println!("# CHECK FAILED: {what}");
            self.total_fails += 1;
        }
    }
}

fn main() {
    let mut runner = Runner { reps: 5, scale: 1.0, only: None, total_fails: 0 };
    let args: Vec<String> = std::env::args().collect();
    let mut i = 1;
    while i < args.len() {
        match (args[i].as_str(), args.get(i + 1)) {
            ("-r", Some(v)) => runner.reps = v.parse().expect("-r REPS"),
            ("-s", Some(v)) => runner.scale = v.parse().expect("-s SCALE"),
            ("-f", Some(v)) => runner.only = Some(v.split(',').map(str::to_owned).collect()),
            _ => {
                eprintln!("usage: bench_mirror [-r REPS] [-f fig,fig] [-s SCALE]");
                std::process::exit(2);
            }
        }
        i += 2;
    }
    runner.reps = runner.reps.max(1);

    let pat_dl: Vec<u8> = (0..DOMAIN_LEN).map(|i| (i * 13) as u8).collect();
    let n = node();
    let r2000 = n.od().find(0x2000, 0).unwrap();
    let r2100 = n.od().find(0x2100, 0).unwrap();
    let r2110 = n.od().find(0x2110, 0).unwrap();
    let mut b = Bench {
        n,
        out: Ring { frames: [Frame::new(0, &[]); RING], head: 0 },
        t_us: 1000,
        crc_dl: crc16(&pat_dl),
        pat_dl,
        upbuf: vec![0; DOMAIN_LEN + 16],
        up_len: 0,
        crc_up_server: 0,
        r2000,
        r2100,
        r2110,
        v_b: 0,
        v_b1007: 0,
        v_e1: 0,
        v_e2: 0,
        v_e3: 0,
    };
    println!("# build drivebus-mirror: node 5, same objects and PDO set-up as crates/node/benches/node.rs");

    runner.run(&mut b, "idle", Bench::idle, 5_000_000, 500_000);
    runner.run(&mut b, "a", Bench::a, 1_000_000, 100_000);
    runner.run(&mut b, "b", |b, n| b.b_to(n, 0x2111), 1_000_000, 100_000);
    runner.run(&mut b, "b1007", |b, n| b.b_to(n, 0x1007), 1_000_000, 100_000);
    // reset 1007h to 0 before the SYNC figures, as the C harness does
    b.request(&Frame::new8(SDO_RX, [0x23, 0x07, 0x10, 0, 0, 0, 0, 0]));

    b.up_len = 0;
    runner.run(&mut b, "c", Bench::c, 1500, 1);
    if runner.selected("c") {
        let ok = b.up_len == DOMAIN_LEN && b.upbuf[..DOMAIN_LEN] == *b.n.od().bytes(b.r2000);
        runner.check(ok, "c: uploaded bytes equal 2000h");
    }
    runner.run(&mut b, "c2", Bench::c2, 1500, 1);
    if runner.selected("c2") {
        let ok = *b.n.od().bytes(b.r2000) == b.pat_dl[..];
        runner.check(ok, "c2: 2000h holds the downloaded pattern");
    }
    b.upbuf.iter_mut().for_each(|x| *x = 0);
    b.up_len = 0;
    runner.run(&mut b, "d1", Bench::d1, 1500, 1);
    if runner.selected("d1") {
        let ok = b.up_len == DOMAIN_LEN && b.upbuf[..DOMAIN_LEN] == *b.n.od().bytes(b.r2000);
        runner.check(ok, "d1: uploaded bytes equal 2000h");
        let ok = crc16(&b.upbuf[..DOMAIN_LEN]) == b.crc_up_server;
        runner.check(ok, "d1: block-upload CRC");
    }
    let zeros = vec![0u8; DOMAIN_LEN];
    b.n.od_mut().set_raw(b.r2000, &zeros);
    runner.run(&mut b, "d2", Bench::d2, 1500, 1);
    if runner.selected("d2") {
        let ok = *b.n.od().bytes(b.r2000) == b.pat_dl[..];
        runner.check(ok, "d2: 2000h holds the downloaded pattern");
    }
    runner.run(&mut b, "e1", Bench::e1, 5_000_000, 500_000);
    runner.run(&mut b, "e2", Bench::e2, 5_000_000, 500_000);
    runner.run(&mut b, "e3", Bench::e3, 5_000_000, 500_000);
    println!("# drivebus-mirror: total failures {}", runner.total_fails);
    std::process::exit(if runner.total_fails == 0 { 0 } else { 1 });
}
