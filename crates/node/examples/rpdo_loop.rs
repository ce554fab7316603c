//! A fixed-count loop for instruction-level profiling of the RPDO path:
//! `perf stat -e instructions:u,cycles:u target/release/examples/rpdo_loop`.

use drivebus_can::{Frame, Instant};
use drivebus_node::{Node, NodeConfig};
use drivebus_od::{Access, DataType, NoHooks, Object, SubObject, Value};

const N: u32 = 10_000_000;

fn main() {
    let mut n = Node::new(NodeConfig::new(5));
    for i in [0x2100u16, 0x2101] {
        n.insert_object(
            Object::var(i, "v", DataType::Unsigned32, Access::Rww, Value::U32(0)).with_sub(
                SubObject::new(0, "v", DataType::Unsigned32, Access::Rww, Value::U32(0)).mappable(),
            ),
        );
    }
    let mut out = Vec::new();
    n.boot(Instant::ZERO, &mut NoHooks, &mut out);
    for d in [
        [0x23u8, 0x00, 0x14, 1, 0x05, 0x02, 0, 0x80],
        [0x2F, 0x00, 0x16, 0, 0, 0, 0, 0],
        [0x23, 0x00, 0x16, 1, 0x20, 0, 0x00, 0x21],
        [0x23, 0x00, 0x16, 2, 0x20, 0, 0x01, 0x21],
        [0x2F, 0x00, 0x16, 0, 2, 0, 0, 0],
        [0x2F, 0x00, 0x14, 2, 254, 0, 0, 0],
        [0x23, 0x00, 0x14, 1, 0x05, 0x02, 0, 0],
    ] {
        n.handle_frame(&Frame::new(0x605, &d), Instant::ZERO, &mut NoHooks, &mut out);
    }
    n.handle_frame(&Frame::new(0x000, &[0x01, 0x05]), Instant::ZERO, &mut NoHooks, &mut out);
    out.clear();
    let now = Instant::from_millis(1);
    let mut sink = |_f: Frame| {};
    for v in 0..N {
        let x = v.to_le_bytes();
        let f = Frame::new8(0x205, [x[0], x[1], x[2], x[3], 1, 2, 3, 4]);
        n.handle_frame(std::hint::black_box(&f), now, &mut NoHooks, &mut sink);
    }
    assert_eq!(n.od().get_u32(0x2100, 0), Some(N - 1));
}
