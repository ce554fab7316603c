//! The whole node's frame handler: any sequence of frames and time steps
//! must never panic, and an expedited upload must work afterwards.
//!
//! The node's dictionary is built once per process ([`NodeTemplate`]);
//! each input gets a fresh node made from it, the same node
//! `Node::new(NodeConfig::new(5))` builds, at a fraction of the cost: the
//! previous input's node is renewed, reusing its dictionary's buffers.
#![no_main]

use drivebus_can::{CanId, Duration, Frame, Instant};
use drivebus_node::{MemoryStorage, Node, NodeConfig, NodeTemplate};
use drivebus_od::NoHooks;
use libfuzzer_sys::fuzz_target;
use std::cell::RefCell;
use std::sync::OnceLock;

static TEMPLATE: OnceLock<NodeTemplate> = OnceLock::new();

thread_local! {
    /// The node of the previous input, renewed for the next.
    static NODE: RefCell<Option<Node>> = const { RefCell::new(None) };
}

fn fresh_node() -> Node {
    let t = TEMPLATE.get_or_init(|| NodeTemplate::new(NodeConfig::new(5)));
    match NODE.with(|n| n.borrow_mut().take()) {
        Some(mut node) => {
            t.renew(&mut node, Box::new(MemoryStorage::new()));
            node
        }
        None => t.node(Box::new(MemoryStorage::new())),
    }
}

fuzz_target!(|data: &[u8]| {
    let mut node = fresh_node();
    let mut out = Vec::new();
    let mut now = Instant::ZERO;
    node.boot(now, &mut NoHooks, &mut out);
    // Records of 12 bytes: id (2), flags (1), dlc (1), data (8).
    for rec in data.chunks_exact(12) {
        let id = u16::from_le_bytes([rec[0], rec[1]]) & 0x7FF;
        let flags = rec[2];
        let len = (rec[3] % 9) as usize;
        let cid = if flags & 1 != 0 { CanId::Extended(id as u32) } else { CanId::Standard(id) };
        let frame = if flags & 2 != 0 {
            Frame::try_remote(cid, len as u8).unwrap()
        } else {
            Frame::try_new(cid, &rec[4..4 + len]).unwrap()
        };
        now += Duration::from_micros(u64::from(flags >> 2) * 100);
        node.handle_frame(&frame, now, &mut NoHooks, &mut out);
        node.poll(now, &mut NoHooks, &mut out);
        out.clear();
    }
    now += Duration::from_secs(2);
    node.poll(now, &mut NoHooks, &mut out);
    node.handle_frame(&Frame::new(0x000, &[0x82, 0x05]), now, &mut NoHooks, &mut out);
    out.clear();
    node.handle_frame(&Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), now, &mut NoHooks, &mut out);
    assert_eq!(out.len(), 1);
    NODE.with(|n| *n.borrow_mut() = Some(node));
});
