//! PDO frame-path benchmarks: (e1) one 8-byte async RPDO into the
//! dictionary, (e2) SYNC in → one synchronous TPDO out.
#![allow(missing_docs)]

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use drivebus_can::{Frame, Instant, TxSink};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, SubObject, Value};
use drivebus_pdo::{Pdo, PdoConfig, PdoDefaults, PdoKind, install, map_entry, set_defaults};

fn od_with(cfg: &PdoConfig) -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    for i in 0..4u16 {
        od.insert(
            Object::var(0x2000 + i, "v", DataType::Unsigned32, Access::Rw, Value::U32(0)).with_sub(
                SubObject::new(
                    0,
                    "v",
                    DataType::Unsigned32,
                    Access::Rw,
                    Value::U32(0x1111_1111 * u32::from(i)),
                )
                .mappable(),
            ),
        );
    }
    install(&mut od, cfg);
    od
}

struct Count(usize);
impl TxSink for Count {
    #[inline]
    fn send(&mut self, f: Frame) {
        self.0 += black_box(f).len();
    }
}

fn bench(c: &mut Criterion) {
    let cfg = PdoConfig::new(1);

    let mut od = od_with(&cfg);
    let rx = [map_entry(0x2000, 0, 32), map_entry(0x2001, 0, 32)];
    let mut d = PdoDefaults::new(&rx);
    d.transmission_type = 254;
    set_defaults(&mut od, &cfg, PdoKind::Rpdo, 0, &d).unwrap();
    let mut pdo = Pdo::new(&cfg, &od);
    let mut out = Count(0);
    let frame = Frame::new(0x201, &[1, 2, 3, 4, 5, 6, 7, 8]);
    c.bench_function("e1_rpdo_8_bytes_async", |b| {
        b.iter(|| pdo.handle_frame(black_box(&frame), Instant::ZERO, &mut od, &mut NoHooks, &mut out))
    });

    let mut od = od_with(&cfg);
    let tx = [map_entry(0x2002, 0, 32), map_entry(0x2003, 0, 32)];
    let mut d = PdoDefaults::new(&tx);
    d.transmission_type = 1;
    set_defaults(&mut od, &cfg, PdoKind::Tpdo, 0, &d).unwrap();
    let mut pdo = Pdo::new(&cfg, &od);
    c.bench_function("e2_sync_to_tpdo_type1", |b| {
        b.iter(|| pdo.on_sync(black_box(None), Instant::ZERO, &mut od, &mut NoHooks, &mut out))
    });
    assert!(out.0 > 0);
}

criterion_group!(benches, bench);
criterion_main!(benches);
