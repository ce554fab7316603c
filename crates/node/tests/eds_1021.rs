//! The device describes itself: 1021h read over SDO (block upload) is an
//! EDS that gives back the same dictionary (CiA 301 §7.5.2.21, CiA 306).

mod common;
use common::*;
use drivebus_bus::{Bus, BusConfig};
use drivebus_can::{Device, Duration, Frame, Instant, TxSink};
use drivebus_node::{Node, NodeDevice};
use drivebus_od::{NoHooks, ObjectDictionary};
use drivebus_sdo::client::{Completed, Protocol, SdoClient, SdoClientConfig};
use std::cell::RefCell;
use std::rc::Rc;

struct Reader {
    client: SdoClient,
    started: bool,
    result: Rc<RefCell<Option<Vec<u8>>>>,
}

impl Device for Reader {
    fn handle_frame(&mut self, frame: &Frame, now: Instant, mut out: &mut dyn TxSink) {
        self.client.handle_frame(frame, now, &mut out);
        if let Some(r) = self.client.take_result() {
            let Completed::Upload(d) = r.expect("upload of 1021h") else { panic!("not an upload") };
            *self.result.borrow_mut() = Some(d);
        }
    }
    fn poll(&mut self, now: Instant, mut out: &mut dyn TxSink) -> Option<Instant> {
        if !std::mem::replace(&mut self.started, true) {
            self.client.start_upload(0x1021, 0, Protocol::Block, now, &mut out).unwrap();
        }
        self.client.poll(now, &mut out)
    }
    fn start(&mut self, _now: Instant, _out: &mut dyn TxSink) {}
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// What an EDS can say about a dictionary: per sub-object the name, type,
/// access, mappability, default and limits (not hooks or live values).
fn described(od: &ObjectDictionary) -> Vec<String> {
    od.objects()
        .iter()
        .filter(|o| o.index != 0x1021)
        .flat_map(|o| {
            o.subs().iter().map(move |s| {
                format!(
                    "{:04X}sub{} {} {:?} {:?} map={} def={:?} lo={:?} hi={:?}",
                    o.index,
                    s.sub,
                    s.name,
                    s.data_type,
                    s.access,
                    s.pdo_mappable,
                    s.default,
                    s.low_limit,
                    s.high_limit
                )
            })
        })
        .collect()
}

#[test]
fn eds_read_from_1021h_gives_the_same_dictionary() {
    let mut cfg = device();
    cfg.eds_object = true;
    let node = Node::new(cfg);
    let original = described(node.od());
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    let dut = bus.attach(NodeDevice::new(node, NoHooks));
    bus.run_for(Duration::from_millis(1));
    let result = Rc::new(RefCell::new(None));
    bus.attach(Reader {
        client: SdoClient::new(SdoClientConfig::for_node(5)),
        started: false,
        result: result.clone(),
    });
    bus.run_for(Duration::from_secs(5));
    let text = String::from_utf8(result.borrow_mut().take().expect("transfer finished")).unwrap();
    let parsed = drivebus_eds::parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert!(drivebus_eds::check(&parsed.eds).iter().all(|f| f.severity != drivebus_eds::Severity::Error));
    let back = drivebus_eds::to_od(&parsed.eds, 5).unwrap();
    assert_eq!(described(&back), original);
    // 1022h: ASCII.
    let node = &bus.node::<NodeDevice>(dut).unwrap().node;
    assert_eq!(node.od().get_u64(0x1022, 0), Some(0));
    // Node-relative COB-IDs are written as $NODEID expressions.
    assert!(text.contains("$NODEID+0x80"), "EMCY COB-ID not node-relative");
}
