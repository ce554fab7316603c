//! No input panics the drive: arbitrary SDO/PDO-style writes to every drive
//! object, interleaved with control periods and controlwords.

use drivebus_cia402::drive::{Drive, DriveConfig};
use drivebus_node::{Node, NodeConfig};
use proptest::prelude::*;

fn drive() -> (Node, Drive) {
    let mut node = Node::new(NodeConfig::new(1));
    let d = Drive::install(&mut node, DriveConfig::default()).unwrap();
    (node, d)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn arbitrary_writes_never_panic(
        ops in proptest::collection::vec((0usize..1000, 0u8..8, proptest::collection::vec(any::<u8>(), 1..5), 0u32..40), 1..60)
    ) {
        let (mut node, mut d) = drive();
        // Every sub-object of the drive's objects (6000h–6FFFh).
        let targets: Vec<(u16, u8, usize)> = node
            .od()
            .objects()
            .iter()
            .filter(|o| (0x6000..0x7000).contains(&o.index))
            .flat_map(|o| o.subs().iter().map(move |s| (o.index, s.sub, s.data_type.fixed_size().unwrap_or(4))))
            .collect();
        for (pick, cw_pick, data, steps) in ops {
            let (index, sub, size) = targets[pick % targets.len()];
            let mut bytes = data.clone();
            bytes.resize(size, 0);
            // The node's write path, as every protocol writes.
            let now = drivebus_can::Instant::ZERO;
            let mut out = Vec::new();
            let _ = node.write_object(index, sub, &bytes, now, &mut d, &mut out);
            let cw = [0x06u16, 0x07, 0x0F, 0x1F, 0x3F, 0x5F, 0x80, 0x10F][usize::from(cw_pick)];
            let _ = node.write_object(0x6040, 0, &cw.to_le_bytes(), now, &mut d, &mut out);
            d.step_n(node.od_mut(), steps);
        }
        // Still a coherent statusword.
        let sw = node.od().get_u64(0x6041, 0).unwrap() as u16;
        prop_assert!(drivebus_cia402::state_machine::State::from_statusword(sw).is_some());
    }
}
