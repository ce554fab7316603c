//! The CiA 402 `RemoteDrive` handle against a minimal stand-in drive: a state
//! machine on 6040h/6041h with instant motion, an application that asks
//! for TPDO 1 whenever the statusword changes, hosted in real time.

mod common;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use common::bounded;
use drivebus_master::drive::mode;
use drivebus_master::{
    DriveError, DriveState, Master, MoveProfile, NmtCommand, PdoDir, PdoMapEntry, PdoRecord, RemoteDrive,
    RemoteState,
};
use drivebus_node::{AppContext, Application, Node, NodeConfig, NodeDevice};
use drivebus_od::{
    Access, DataType, Object, ObjectCode, ObjectDictionary, SdoAbort, SubObject, Target, Value, WriteOutcome,
};
use drivebus_transport::Hub;
use drivebus_transport::host::{DeviceHost, spawn};

const SOD: u16 = 0x0040;
const RTSO: u16 = 0x0021;
const SO: u16 = 0x0023;
const OE: u16 = 0x0027;
const QS: u16 = 0x0007;
const FAULT: u16 = 0x0008;

/// A CiA 402 device reduced to its state machine: PP/homing moves finish
/// at once, CSP targets are recorded.
#[derive(Default)]
struct StandIn {
    state: u16,
    cw: u16,
    bit12: bool,
    reached: bool,
    homing_error: bool,
    csp_targets: Arc<Mutex<Vec<i32>>>,
    /// The statusword TPDO 1 last carried.
    last_sw: u16,
}

impl StandIn {
    fn statusword(&self) -> u16 {
        self.state
            | 0x0200
            | (u16::from(self.reached) << 10)
            | (u16::from(self.bit12) << 12)
            | (u16::from(self.homing_error) << 13)
    }
    fn publish(&self, od: &mut ObjectDictionary) {
        let _ = od.set_value(0x6041, 0, &Value::U16(self.statusword()));
    }
    fn controlword(&mut self, od: &mut ObjectDictionary, cw: u16) {
        let rising = |bit: u16| cw & bit != 0 && self.cw & bit == 0;
        let mode = od.get_i64(0x6061, 0).unwrap_or(0) as i8;
        let st = self.state;
        self.state = if st == FAULT {
            if rising(0x80) { SOD } else { FAULT }
        } else if cw & 0x82 == 0 {
            SOD
        } else if cw & 0x86 == 0x02 {
            if st == OE { QS } else { SOD }
        } else if cw & 0x87 == 0x06 {
            if matches!(st, SOD | SO | OE) { RTSO } else { st }
        } else if cw & 0x8F == 0x07 {
            if matches!(st, RTSO | OE) { SO } else { st }
        } else if cw & 0x8F == 0x0F {
            if matches!(st, SO | QS) { OE } else { st }
        } else {
            st
        };
        if self.state == OE && rising(0x10) {
            match mode {
                mode::PP => {
                    let target = od.get_i64(0x607A, 0).unwrap_or(0) as i32;
                    let pos = od.get_i64(0x6064, 0).unwrap_or(0) as i32;
                    let new = if cw & 0x40 != 0 { pos.wrapping_add(target) } else { target };
                    let _ = od.set_value(0x6064, 0, &Value::I32(new));
                    self.bit12 = true;
                    self.reached = true;
                }
                mode::HM => {
                    if od.get_i64(0x6098, 0) == Some(-1) {
                        self.homing_error = true;
                    } else {
                        let _ = od.set_value(0x6064, 0, &Value::I32(0));
                        self.bit12 = true;
                        self.reached = true;
                    }
                }
                _ => {}
            }
        }
        if cw & 0x10 == 0 && mode == mode::PP {
            self.bit12 = false;
        }
        self.cw = cw;
        self.publish(od);
    }
}

// The stand-in owns 6040h, 6060h and 607Ah: it stores them itself and
// asks for TPDO 1 when the statusword changed.
impl Application for StandIn {
    fn check_write(
        &mut self,
        cx: &mut AppContext<'_>,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let od = &mut *cx.od;
        od.set_raw(at.r, data);
        match at.index {
            0x6040 => {
                let cw = od.get_u64(0x6040, 0).unwrap_or(0) as u16;
                self.controlword(od, cw);
            }
            0x6060 => {
                let m = od.get_i64(0x6060, 0).unwrap_or(0);
                let _ = od.set_value(0x6061, 0, &Value::I8(m as i8));
                self.bit12 = false;
                self.homing_error = false;
                self.publish(od);
            }
            0x607A if od.get_i64(0x6061, 0) == Some(i64::from(mode::CSP)) => {
                let t = od.get_i64(0x607A, at.sub).unwrap_or(0) as i32;
                self.csp_targets.lock().unwrap().push(t);
            }
            _ => {}
        }
        let sw = self.statusword();
        if sw != self.last_sw {
            self.last_sw = sw;
            cx.request_tpdo(0);
        }
        Ok(WriteOutcome::Handled)
    }
}

fn var(index: u16, dt: DataType, access: Access, v: Value, hooked: bool) -> Object {
    let mut s = SubObject::new(0, "x", dt, access, v).mappable();
    if hooked {
        s = s.hooked();
    }
    Object::with_code(index, ObjectCode::Var, "x").with_sub(s)
}

fn stand_in(id: u8) -> (NodeDevice<StandIn>, Arc<Mutex<Vec<i32>>>) {
    let mut cfg = NodeConfig::new(id);
    cfg.device_type = 0x0002_0192;
    let mut node = Node::new(cfg);
    node.insert_object(var(0x6040, DataType::Unsigned16, Access::Rw, Value::U16(0), true));
    node.insert_object(var(0x6041, DataType::Unsigned16, Access::Ro, Value::U16(SOD), false));
    node.insert_object(var(0x6060, DataType::Integer8, Access::Rw, Value::I8(0), true));
    node.insert_object(var(0x6061, DataType::Integer8, Access::Ro, Value::I8(0), false));
    node.insert_object(var(0x6064, DataType::Integer32, Access::Ro, Value::I32(0), false));
    node.insert_object(var(0x607A, DataType::Integer32, Access::Rw, Value::I32(0), true));
    node.insert_object(var(0x60FF, DataType::Integer32, Access::Rw, Value::I32(0), false));
    node.insert_object(var(0x6071, DataType::Integer16, Access::Rw, Value::I16(0), false));
    node.insert_object(var(0x6081, DataType::Unsigned32, Access::Rw, Value::U32(0), false));
    node.insert_object(var(0x6083, DataType::Unsigned32, Access::Rw, Value::U32(0), false));
    node.insert_object(var(0x6084, DataType::Unsigned32, Access::Rw, Value::U32(0), false));
    node.insert_object(var(0x6098, DataType::Integer8, Access::Rw, Value::I8(0), false));
    let app = StandIn { state: SOD, last_sw: SOD, ..Default::default() };
    let targets = app.csp_targets.clone();
    (NodeDevice::new(node, app), targets)
}

struct Rig {
    hub: Hub,
    m: Master,
    host: DeviceHost<NodeDevice<StandIn>>,
    targets: Arc<Mutex<Vec<i32>>>,
}

fn rig(id: u8) -> Rig {
    let hub = Hub::default();
    let m = common::master(&hub);
    let (dev, targets) = stand_in(id);
    let host = spawn(dev, hub.attach());
    Rig { hub, m, host, targets }
}

/// TPDO1 = statusword + position (event-driven), RPDO1 = controlword +
/// target position; heartbeat on; started.
async fn configure_pdos(m: &Master, id: u8) {
    let t = PdoRecord::new(
        0x180 + u16::from(id),
        255,
        vec![PdoMapEntry::new(0x6041, 0, 16), PdoMapEntry::new(0x6064, 0, 32)],
    );
    m.write_pdo(id, PdoDir::Tx, 1, &t).await.unwrap();
    let r = PdoRecord::new(
        0x200 + u16::from(id),
        255,
        vec![PdoMapEntry::new(0x6040, 0, 16), PdoMapEntry::new(0x607A, 0, 32)],
    );
    m.write_pdo(id, PdoDir::Rx, 1, &r).await.unwrap();
    m.sdo(id).write::<u16>(0x1017, 0, 20).await.unwrap();
    m.nmt(id, NmtCommand::Start).await.unwrap();
    while m.wait_for_heartbeat(id, Duration::from_secs(1)).await.unwrap() != RemoteState::Operational {}
}

async fn position(m: &Master, id: u8) -> i32 {
    m.sdo(id).read::<i32>(0x6064, 0).await.unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn state_machine_walk_over_sdo() {
    bounded(async {
        let r = rig(3);
        let d: RemoteDrive = r.m.drive(3).await.unwrap().with_timeout(Duration::from_millis(500));
        assert!(!d.statusword_by_pdo());
        assert_eq!(d.state().await.unwrap(), DriveState::SwitchOnDisabled);
        d.enable().await.unwrap();
        assert_eq!(d.state().await.unwrap(), DriveState::OperationEnabled);
        d.enable().await.unwrap(); // already there
        d.disable().await.unwrap();
        assert_eq!(d.state().await.unwrap(), DriveState::ReadyToSwitchOn);
        d.enable().await.unwrap();
        d.quick_stop().await.unwrap();
        assert_eq!(d.state().await.unwrap(), DriveState::QuickStopActive);
        d.enable().await.unwrap();
        // A fault: enable() resets it first.
        r.host
            .with(|dev, _| {
                dev.app.state = FAULT;
                dev.app.publish(dev.node.od_mut());
            })
            .await
            .unwrap();
        assert_eq!(d.state().await.unwrap(), DriveState::Fault);
        assert!(matches!(d.set_mode(mode::PP).await, Ok(())));
        d.enable().await.unwrap();
        assert_eq!(d.state().await.unwrap(), DriveState::OperationEnabled);
        d.move_to(700, false, None, Duration::from_secs(1)).await.unwrap();
        assert_eq!(position(&r.m, 3).await, 700);
        drop(r.hub);
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn enable_move_and_home_over_pdo() {
    bounded(async {
        let r = rig(4);
        configure_pdos(&r.m, 4).await;
        let mut spy = r.hub.attach();
        let d = r.m.drive(4).await.unwrap().with_timeout(Duration::from_millis(500));
        assert!(d.statusword_by_pdo() && d.controlword_by_pdo(), "{d:?}");
        d.enable().await.unwrap();
        d.set_mode(mode::PP).await.unwrap();
        let profile = MoveProfile { velocity: 1000, acceleration: 5000, deceleration: 5000 };
        d.move_to(1000, false, Some(profile), Duration::from_secs(1)).await.unwrap();
        assert_eq!(position(&r.m, 4).await, 1000);
        assert_eq!(r.m.sdo(4).read::<u32>(0x6081, 0).await.unwrap(), 1000);
        d.move_to(-250, true, None, Duration::from_secs(1)).await.unwrap();
        assert_eq!(position(&r.m, 4).await, 750);
        d.home(35, Duration::from_secs(1)).await.unwrap();
        assert_eq!(position(&r.m, 4).await, 0);
        let e = d.home(-1, Duration::from_secs(1)).await.unwrap_err();
        assert!(
            matches!(&e, DriveError::Stopped(r) if r.end == drivebus_master::MotionEnd::HomingError),
            "{e}"
        );
        d.velocity(10).await.unwrap();
        d.torque(-3).await.unwrap();
        assert_eq!(r.m.sdo(4).read::<i16>(0x6071, 0).await.unwrap(), -3);
        // The controlword went by RPDO and the statusword came by TPDO.
        let mut rpdo = 0;
        let mut tpdo = 0;
        let end = tokio::time::Instant::now() + Duration::from_millis(100);
        while let Ok(Ok(f)) = tokio::time::timeout_at(end, spy.recv()).await {
            match f.std_id() {
                Some(0x204) => rpdo += 1,
                Some(0x184) => tpdo += 1,
                _ => {}
            }
        }
        assert!(rpdo >= 10, "{rpdo} RPDOs");
        assert!(tpdo >= 5, "{tpdo} TPDOs");
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn csp_stream_follows_sync() {
    bounded(async {
        let r = rig(5);
        configure_pdos(&r.m, 5).await;
        let d = r.m.drive(5).await.unwrap();
        assert_eq!(d.stream_csp([1]).await.unwrap_err(), DriveError::NoSync);
        d.enable().await.unwrap();
        d.set_mode(mode::CSP).await.unwrap();
        let mut spy = r.hub.attach();
        r.m.start_sync(Duration::from_millis(1), 0);
        let n = d.stream_csp(0..200).await.unwrap();
        r.m.stop_sync();
        assert_eq!(n, 200);
        // Every target arrived, in order.
        tokio::time::sleep(Duration::from_millis(20)).await;
        assert_eq!(*r.targets.lock().unwrap(), (0..200).collect::<Vec<i32>>());
        // Each RPDO follows a SYNC. A busy machine may delay one send past
        // the next SYNC (two RPDOs in one cycle), but the stream never runs
        // ahead of the SYNCs and such slips stay rare.
        let (mut since_sync, mut rpdos, mut syncs, mut slips) = (0, 0, 0, 0);
        let end = tokio::time::Instant::now() + Duration::from_millis(100);
        while let Ok(Ok(f)) = tokio::time::timeout_at(end, spy.recv()).await {
            match f.std_id() {
                Some(0x080) => {
                    since_sync = 0;
                    syncs += 1;
                }
                Some(0x205) => {
                    rpdos += 1;
                    since_sync += 1;
                    slips += usize::from(since_sync > 1);
                    assert!(rpdos <= syncs, "RPDO {rpdos} before SYNC {rpdos}");
                }
                _ => {}
            }
        }
        assert!(slips * 10 <= rpdos, "{slips} of {rpdos} RPDOs shared a SYNC cycle");
        assert_eq!(rpdos, 200);
        d.stream_csv([1, 2, 3]).await.unwrap_err();
    })
    .await;
}
