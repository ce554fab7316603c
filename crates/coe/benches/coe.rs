//! Mailbox server CPU cost: request mailbox in → server → response mailbox
//! out, single thread, synthetic time, the request built outside the timed
//! loop and only its counter changed inside.
//!
//! (a) expedited upload 1000h:00; (b) complete-access read of a 64-entry
//! UNSIGNED32 array (258 bytes) in a 1486-byte mailbox (one normal
//! response) and (b') in a 128-byte mailbox (initiate + 2 segments).
//!
//! Run: `cargo bench -p drivebus-coe --bench coe -- --warm-up-time 1 --measurement-time 2`

// criterion's macros generate undocumented items.
#![allow(missing_docs)]

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use drivebus_base::{Duration, Instant};
use drivebus_coe::{AlState, MailboxConfig, MailboxServer, NoFiles};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, Value};

/// A dictionary of a small drive's size, so lookups are not trivially short.
fn od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    od.insert(Object::var(0x1000, "Device type", DataType::Unsigned32, Access::Ro, Value::U32(0x0006_0192)));
    for i in 0..150u16 {
        od.insert(Object::var(0x2000 + i, "p", DataType::Unsigned32, Access::Rw, Value::U32(u32::from(i))));
    }
    od.insert(Object::array(0x3000, "Table", DataType::Unsigned32, Access::Rw, 64, Value::U32(0x0102_0304)));
    od
}

struct Bench {
    server: MailboxServer,
    dev: (ObjectDictionary, NoHooks),
    now: Instant,
    cnt: u8,
}

impl Bench {
    fn new(size: usize) -> Bench {
        Bench {
            server: MailboxServer::new(MailboxConfig::with_sizes(size, size)).unwrap(),
            dev: (od(), NoHooks),
            now: Instant::ZERO,
            cnt: 0,
        }
    }
    /// One request with the next counter; returns the response's length.
    fn exchange(&mut self, req: &mut [u8]) -> usize {
        self.cnt = if self.cnt >= 7 { 1 } else { self.cnt + 1 };
        req[5] = (req[5] & 0x0F) | (self.cnt << 4);
        self.now += Duration::from_micros(100);
        self.server.handle_request(req, self.now, AlState::Op, &mut self.dev, &mut NoFiles);
        self.server.next_response(self.now).map_or(0, <[u8]>::len)
    }
}

fn sdo(cmd: u8, index: u16, sub: u8) -> [u8; 16] {
    let i = index.to_le_bytes();
    [0x0a, 0, 0, 0, 0, 0x03, 0x00, 0x20, cmd, i[0], i[1], sub, 0, 0, 0, 0]
}

fn benches(c: &mut Criterion) {
    let mut b = Bench::new(128);
    let mut req = sdo(0x40, 0x1000, 0);
    c.bench_function("coe expedited upload 1000h", |bench| {
        bench.iter(|| assert_eq!(black_box(b.exchange(&mut req)), 16));
    });

    let mut b = Bench::new(1486);
    let mut req = sdo(0x50, 0x3000, 0);
    c.bench_function("coe complete access 64 x u32, 1486-byte mailbox", |bench| {
        bench.iter(|| assert_eq!(black_box(b.exchange(&mut req)), 16 + 258));
    });

    let mut b = Bench::new(128);
    let mut init = sdo(0x50, 0x3000, 0);
    let mut seg = [sdo(0x60, 0, 0), sdo(0x70, 0, 0)];
    c.bench_function("coe complete access 64 x u32, 128-byte mailbox (segmented)", |bench| {
        bench.iter(|| {
            let mut n = b.exchange(&mut init);
            n += b.exchange(&mut seg[0]);
            n += b.exchange(&mut seg[1]);
            assert_eq!(black_box(n), 128 + 128 + 6 + 3 + (258 - 112 - 119));
        });
    });
}

criterion_group!(group, benches);
criterion_main!(group);
