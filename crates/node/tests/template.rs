//! A node made from a [`NodeTemplate`] is the node its constructor makes:
//! the same dictionary (values, owners, node-relative marks) and the same
//! answers on the bus.

use drivebus_can::{Frame, Instant};
use drivebus_node::{MemoryStorage, Node, NodeConfig, NodeTemplate};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, Value};

fn answers(node: &mut Node) -> Vec<Frame> {
    let mut out = Vec::new();
    node.boot(Instant::ZERO, &mut NoHooks, &mut out);
    for f in [
        Frame::new(0x000, &[0x01, 0x00]),
        Frame::new(0x600 + u16::from(node.node_id() & 0x7F), &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]),
        Frame::new(0x600 + u16::from(node.node_id() & 0x7F), &[0x40, 0x14, 0x10, 0, 0, 0, 0, 0]),
    ] {
        node.handle_frame(&f, Instant::ZERO, &mut NoHooks, &mut out);
        node.poll(Instant::ZERO, &mut NoHooks, &mut out);
    }
    out
}

fn configs() -> Vec<NodeConfig> {
    let mut v: Vec<NodeConfig> = [1u8, 5, 127, 0, 0xFF, 200].into_iter().map(NodeConfig::new).collect();
    let mut small = NodeConfig::new(9);
    small.pdo.max_entries = 8;
    small.store_restore = true;
    small.time = true;
    v.push(small);
    v
}

#[test]
fn template_node_is_the_constructed_node() {
    for cfg in configs() {
        let t = NodeTemplate::new(cfg.clone());
        let mut a = Node::new(cfg.clone());
        let mut b = t.node(Box::new(MemoryStorage::new()));
        assert!(a.od() == b.od(), "node {}", cfg.node_id);
        assert_eq!(a.node_id(), b.node_id());
        assert_eq!(answers(&mut a), answers(&mut b), "node {}", cfg.node_id);
    }
}

#[test]
fn template_of_a_dictionary_is_with_dictionary() {
    for cfg in configs() {
        let mut od = ObjectDictionary::new();
        od.insert(Object::var(0x1014, "COB-ID EMCY", DataType::Unsigned32, Access::Rw, Value::U32(0x99)));
        od.insert(Object::var(0x2000, "Manufacturer", DataType::Unsigned16, Access::Rw, Value::U16(7)));
        let t = NodeTemplate::with_dictionary(cfg.clone(), od.clone());
        let mut a = Node::with_dictionary(cfg.clone(), od, Box::new(MemoryStorage::new()));
        let mut b = t.node(Box::new(MemoryStorage::new()));
        assert!(a.od() == b.od(), "node {}", cfg.node_id);
        assert!(a.od().get(0x1014, 0).unwrap().node_id_relative);
        assert_eq!(answers(&mut a), answers(&mut b), "node {}", cfg.node_id);
    }
}

/// The defaults that follow the node-ID (CiA 301 §7.3.5 pre-defined
/// connection set) are marked, and only those: the mapping entries, built
/// without their neighbour's, are not.
#[test]
fn node_relative_marks() {
    let node = Node::new(NodeConfig::new(5));
    let od = node.od();
    let marked: Vec<(u16, u8)> = od
        .objects()
        .iter()
        .flat_map(|o| o.subs().iter().filter(|s| s.node_id_relative).map(move |s| (o.index, s.sub)))
        .collect();
    for e in [(0x1014, 0), (0x1200, 1), (0x1200, 2), (0x1400, 1), (0x1403, 1), (0x1800, 1), (0x1803, 1)] {
        assert!(marked.contains(&e), "{e:04X?} not marked: {marked:04X?}");
    }
    assert!(
        marked
            .iter()
            .all(|&(i, _)| matches!(i, 0x1014 | 0x1200..=0x12FF | 0x1400..=0x15FF | 0x1800..=0x19FF)),
        "{marked:04X?}"
    );
    assert!(!marked.iter().any(|&(i, _)| (0x1600..=0x17FF).contains(&i) || (0x1A00..=0x1BFF).contains(&i)));
}

/// A renewed node forgets everything the previous one went through
/// (values written, NMT state) and answers as a new one.
#[test]
fn renewed_node_is_a_fresh_node() {
    let cfg = NodeConfig::new(5);
    let t = NodeTemplate::new(cfg.clone());
    let mut node = t.node(Box::new(MemoryStorage::new()));
    let mut out = Vec::new();
    node.boot(Instant::ZERO, &mut NoHooks, &mut out);
    // Heartbeat 1017h := 100 ms, then operational.
    node.handle_frame(
        &Frame::new(0x605, &[0x2B, 0x17, 0x10, 0, 100, 0, 0, 0]),
        Instant::ZERO,
        &mut NoHooks,
        &mut out,
    );
    node.handle_frame(&Frame::new(0x000, &[0x01, 0x05]), Instant::ZERO, &mut NoHooks, &mut out);
    assert_eq!(node.od().get_u32(0x1017, 0), Some(100));
    t.renew(&mut node, Box::new(MemoryStorage::new()));
    let mut fresh = Node::new(cfg);
    assert!(node.od() == fresh.od());
    assert_eq!(node.nmt_state(), fresh.nmt_state());
    assert_eq!(answers(&mut node), answers(&mut fresh));
}

/// A template moved to another node-ID is the template built for it: the
/// services' node-relative defaults are the node-ID plus a constant.
#[test]
fn moved_template_is_the_template_of_the_other_node_id() {
    for from in [1u8, 5, 127] {
        for to in [1u8, 2, 64, 127] {
            let mut od = ObjectDictionary::new();
            od.insert(Object::var(0x2000, "Manufacturer", DataType::Unsigned16, Access::Rw, Value::U16(7)));
            let a = NodeTemplate::with_dictionary(NodeConfig::new(from), od.clone()).moved_to(to).unwrap();
            let b = NodeTemplate::with_dictionary(NodeConfig::new(to), od);
            assert!(a.od() == b.od(), "{from} -> {to}");
            assert!(a.config() == b.config(), "{from} -> {to}");
            let mut na = a.node(Box::new(MemoryStorage::new()));
            let mut nb = b.node(Box::new(MemoryStorage::new()));
            assert_eq!(answers(&mut na), answers(&mut nb), "{from} -> {to}");
        }
    }
    assert!(NodeTemplate::new(NodeConfig::new(0xFF)).moved_to(5).is_none());
    assert!(NodeTemplate::new(NodeConfig::new(5)).moved_to(0).is_none());
}
