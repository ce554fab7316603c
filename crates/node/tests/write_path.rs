//! The write path through a node (DEVELOPERS.md "The write path"): one
//! owner per entry found by its tag, the order of the checks, the
//! application's veto on an object a service owns, one apply per write,
//! the same path for SDO and for `Node::write_object` (CoE and other
//! protocols), and a poll that visits only what a write changed.

use drivebus_can::{Frame, Instant};
use drivebus_node::{
    AppContext, Application, MemoryStorage, Node, NodeConfig, NodeEvent, Owner, SAVE_SIGNATURE, Slot, Target,
    WriteOutcome,
};
use drivebus_od::{Access, DataType, Object, SdoAbort, SubObject, Value};

/// Counts every callback; refuses 13 on its own object and a 1010h store
/// while `locked`.
#[derive(Default)]
struct Counting {
    checks: Vec<(u16, u8, Owner)>,
    applies: Vec<(u16, u8)>,
    reads: u32,
    polls: u32,
    locked: bool,
}

impl Application for Counting {
    fn check_write(
        &mut self,
        cx: &mut AppContext<'_>,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        self.checks.push((at.index, at.sub, at.owner));
        // Nothing is stored before the owner's check.
        if at.index == 0x2000 {
            assert_ne!(cx.od.bytes(at.r), data, "stored before the check");
        }
        if at.index == 0x1010 && self.locked {
            return Err(SdoAbort::DEVICE_STATE);
        }
        if at.index == 0x2000 && data == 13u16.to_le_bytes() {
            return Err(SdoAbort::INVALID_VALUE);
        }
        Ok(WriteOutcome::Store)
    }
    fn apply_write(&mut self, cx: &mut AppContext<'_>, at: &Target) {
        self.applies.push((at.index, at.sub));
        // Applied after the store.
        assert!(cx.od.get_u32(at.index, at.sub).is_some());
    }
    fn on_read(&mut self, cx: &mut AppContext<'_>, at: &Target) -> Result<(), SdoAbort> {
        self.reads += 1;
        cx.od.set_raw(at.r, &777u16.to_le_bytes());
        Ok(())
    }
    fn on_event(&mut self, _: &mut AppContext<'_>, _: NodeEvent) {}
    fn poll(&mut self, _: &mut AppContext<'_>) -> Option<Instant> {
        self.polls += 1;
        None
    }
}

const APP_TAG: Owner = Owner::app(7);

/// Node 5 with 2000h (u16, 0..=1000) owned and live, 2001h plain; 1010h
/// watched by the application.
fn rig() -> (Node, Counting, Vec<Frame>) {
    let mut n = Node::with_storage(NodeConfig::new(5), Box::new(MemoryStorage::new()));
    n.insert_object(
        Object::with_code(0x2000, drivebus_od::ObjectCode::Var, "Owned").with_sub(
            SubObject::new(0, "Owned", DataType::Unsigned16, Access::Rw, Value::U16(0))
                .limits(Value::U16(0), Value::U16(1000))
                .owned(APP_TAG)
                .live()
                .mappable(),
        ),
    );
    n.insert_object(Object::var(0x2001, "Plain", DataType::Unsigned16, Access::Rw, Value::U16(0)));
    n.insert_object(
        Object::with_code(0x2003, drivebus_od::ObjectCode::Var, "Mapped").with_sub(
            SubObject::new(0, "Mapped", DataType::Unsigned16, Access::Rw, Value::U16(0)).mappable(),
        ),
    );
    for s in 1..=4 {
        n.od_mut().get_mut(0x1010, s).unwrap().watched = true;
    }
    let mut app = Counting::default();
    let mut out = Vec::new();
    n.boot(Instant::ZERO, &mut app, &mut out);
    n.poll(Instant::ZERO, &mut app, &mut out);
    out.clear();
    (n, app, out)
}

fn sdo(n: &mut Node, app: &mut Counting, out: &mut Vec<Frame>, index: u16, sub: u8, data: &[u8]) -> Frame {
    let mut d = [0x23 | ((4 - data.len() as u8) << 2), index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0];
    d[4..4 + data.len()].copy_from_slice(data);
    out.clear();
    n.handle_frame(&Frame::new8(0x605, d), Instant::from_millis(1), app, out);
    *out.iter().find(|f| f.std_id() == Some(0x585)).expect("an SDO response")
}

fn abort(index: u16, sub: u8, code: SdoAbort) -> Frame {
    let c = code.0.to_le_bytes();
    Frame::new8(0x585, [0x80, index as u8, (index >> 8) as u8, sub, c[0], c[1], c[2], c[3]])
}

fn ok(index: u16, sub: u8) -> Frame {
    Frame::new8(0x585, [0x60, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0])
}

#[test]
fn the_owner_is_found_by_its_tag_and_called_once() {
    let (mut n, mut app, mut out) = rig();
    assert_eq!(sdo(&mut n, &mut app, &mut out, 0x2000, 0, &5u16.to_le_bytes()), ok(0x2000, 0));
    assert_eq!(app.checks, [(0x2000, 0, APP_TAG)]);
    assert_eq!(app.applies, [(0x2000, 0)], "one apply: no second chain after the store");
    // A plain entry reaches nobody.
    assert_eq!(sdo(&mut n, &mut app, &mut out, 0x2001, 0, &5u16.to_le_bytes()), ok(0x2001, 0));
    // A service's object reaches its service, not the application.
    assert_eq!(sdo(&mut n, &mut app, &mut out, 0x1017, 0, &100u16.to_le_bytes()), ok(0x1017, 0));
    assert_eq!(app.checks.len(), 1);
    assert_eq!(app.applies.len(), 1);
    assert_eq!(n.od().get_u32(0x2001, 0), Some(5));
    // A live entry is refreshed by its owner before a read.
    assert_eq!(n.read_object(0x2000, 0, Instant::from_millis(1), &mut app).unwrap(), 777u16.to_le_bytes());
    assert_eq!(app.reads, 1);
}

#[test]
fn checks_run_in_order_and_the_owner_sees_only_valid_values() {
    let (mut n, mut app, mut out) = rig();
    // 1. find
    assert_eq!(sdo(&mut n, &mut app, &mut out, 0x2002, 0, &[1, 0]), abort(0x2002, 0, SdoAbort::NO_OBJECT));
    // 2. access (1000h is read-only) before anything else
    assert_eq!(
        sdo(&mut n, &mut app, &mut out, 0x1000, 0, &[0; 4]),
        abort(0x1000, 0, SdoAbort::WRITE_READ_ONLY)
    );
    // 3. type/length, limits — before the owner
    assert_eq!(
        sdo(&mut n, &mut app, &mut out, 0x2000, 0, &[1, 0, 0]),
        abort(0x2000, 0, SdoAbort::DATA_TOO_LONG)
    );
    let too_high = 1001u16.to_le_bytes();
    assert_eq!(
        sdo(&mut n, &mut app, &mut out, 0x2000, 0, &too_high),
        abort(0x2000, 0, SdoAbort::VALUE_TOO_HIGH)
    );
    assert!(app.checks.is_empty(), "the owner never saw an invalid value");
    // 5. the owner's check refuses: nothing stored, nothing applied
    assert_eq!(
        sdo(&mut n, &mut app, &mut out, 0x2000, 0, &13u16.to_le_bytes()),
        abort(0x2000, 0, SdoAbort::INVALID_VALUE)
    );
    assert_eq!(app.checks.len(), 1);
    assert!(app.applies.is_empty());
    assert_eq!(n.od().get_u32(0x2000, 0), Some(0));
}

#[test]
fn the_application_vetoes_an_object_a_service_owns() {
    let (mut n, mut app, mut out) = rig();
    let save = SAVE_SIGNATURE.to_le_bytes();
    app.locked = true;
    assert_eq!(sdo(&mut n, &mut app, &mut out, 0x1010, 2, &save), abort(0x1010, 2, SdoAbort::DEVICE_STATE));
    assert_eq!(n.storage_mut().load(Slot::Communication).unwrap(), None, "vetoed: nothing stored");
    // The veto is asked first, with the owner's tag (the store service).
    let (index, sub, owner) = app.checks[0];
    assert_eq!((index, sub), (0x1010, 2));
    assert!(!owner.is_app(), "1010h stays the service's");
    app.locked = false;
    assert_eq!(sdo(&mut n, &mut app, &mut out, 0x1010, 2, &save), ok(0x1010, 2));
    assert!(n.storage_mut().load(Slot::Communication).unwrap().is_some(), "the owner stored");
    // A wrong signature: the owner's own check, after the veto passed.
    assert_eq!(
        sdo(&mut n, &mut app, &mut out, 0x1010, 2, &1u32.to_le_bytes()),
        abort(0x1010, 2, SdoAbort::CANNOT_STORE)
    );
    assert_eq!(app.checks.len(), 3);
    // The store service applied it itself (Handled): nothing to notify.
    assert!(app.applies.is_empty());
}

#[test]
fn write_object_is_the_sdo_path() {
    let (mut n, mut app, mut out) = rig();
    let now = Instant::from_millis(1);
    // The same aborts, by the same path, without a frame.
    assert_eq!(n.write_object(0x1000, 0, &[0; 4], now, &mut app, &mut out), Err(SdoAbort::WRITE_READ_ONLY));
    assert_eq!(
        n.write_object(0x2000, 0, &1001u16.to_le_bytes(), now, &mut app, &mut out),
        Err(SdoAbort::VALUE_TOO_HIGH)
    );
    n.write_object(0x2000, 0, &9u16.to_le_bytes(), now, &mut app, &mut out).unwrap();
    assert_eq!(app.checks, [(0x2000, 0, APP_TAG)]);
    assert_eq!(app.applies, [(0x2000, 0)]);
    // A communication object reconfigures its service: 1017h starts the heartbeat.
    n.write_object(0x1017, 0, &10u16.to_le_bytes(), now, &mut app, &mut out).unwrap();
    out.clear();
    n.poll(Instant::from_millis(11), &mut app, &mut out);
    assert_eq!(out, [Frame::new(0x705, &[0x7F])], "heartbeat, pre-operational");
}

#[test]
fn poll_visits_only_what_changed() {
    let (mut n, mut app, mut out) = rig();
    let now = Instant::from_millis(1);
    n.poll(now, &mut app, &mut out);
    let polls = app.polls;
    // An upload of a plain object changes nothing: the application's poll
    // is not called, and no frame but the answer goes out.
    out.clear();
    n.handle_frame(&Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), now, &mut app, &mut out);
    assert_eq!(n.poll(now, &mut app, &mut out), None);
    assert_eq!(app.polls, polls);
    assert_eq!(out.len(), 1);
    // A write to the application's object: it is polled after.
    sdo(&mut n, &mut app, &mut out, 0x2000, 0, &3u16.to_le_bytes());
    n.poll(now, &mut app, &mut out);
    assert_eq!(app.polls, polls + 1);
    // An event-driven TPDO mapping 2003h: a change of it goes out at the
    // next poll; a change of 2001h (unmapped) is no input of the PDO
    // service: the dictionary does not count it, nothing wakes.
    for (index, sub, v) in [
        (0x1800u16, 1u8, 0x8000_0185u32),
        (0x1A00, 0, 0),
        (0x1A00, 1, 0x2003_0010),
        (0x1A00, 0, 1),
        (0x1800, 2, 255),
        (0x1800, 1, 0x185),
    ] {
        let b = v.to_le_bytes();
        let len = n.od().get(index, sub).unwrap().data_type.fixed_size().unwrap();
        n.write_object(index, sub, &b[..len], now, &mut app, &mut out).unwrap();
    }
    n.handle_frame(&Frame::new(0x000, &[0x01, 5]), now, &mut app, &mut out);
    out.clear();
    n.poll(now, &mut app, &mut out);
    assert_eq!(out, [Frame::new(0x185, &[0, 0])], "first transmission");
    let g = n.od().generation();
    sdo(&mut n, &mut app, &mut out, 0x2001, 0, &4u16.to_le_bytes());
    assert_eq!(n.od().generation(), g, "not mapped: not counted");
    out.clear();
    assert_eq!(n.poll(now, &mut app, &mut out), None);
    assert!(out.is_empty());
    sdo(&mut n, &mut app, &mut out, 0x2003, 0, &4u16.to_le_bytes());
    assert_ne!(n.od().generation(), g, "mapped: counted");
    out.clear();
    n.poll(now, &mut app, &mut out);
    assert_eq!(out, [Frame::new(0x185, &[4, 0])], "change of state");
}
