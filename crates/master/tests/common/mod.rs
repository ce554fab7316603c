//! Shared test fixtures: in-process nodes hosted on a hub, and a master.
#![allow(dead_code)]

use std::future::Future;
use std::time::Duration;

use drivebus_master::Master;
use drivebus_node::{Identity, Node, NodeConfig, NodeDevice};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectCode, SubObject, Value};
use drivebus_transport::Hub;
use drivebus_transport::host::{DeviceHost, spawn};

/// Bounds every test: nothing here may hang CI.
pub async fn bounded<T>(f: impl Future<Output = T>) -> T {
    tokio::time::timeout(Duration::from_secs(20), f).await.expect("test timed out")
}

pub fn identity(node: u8) -> Identity {
    Identity {
        vendor_id: 0x0000_0ABC,
        product_code: 0x100 + u32::from(node),
        revision: 0x0001_0002,
        serial: 0x5000 + u32::from(node),
    }
}

/// A generic CiA 301 device with a DOMAIN at 2000h, a VISIBLE_STRING at
/// 2001h and an INTEGER32 at 2002h.
pub fn node(id: u8) -> Node {
    let mut cfg = NodeConfig::new(id);
    cfg.device_type = 0x0002_0192;
    cfg.identity = identity(id);
    cfg.device_name = Some(format!("test node {id}"));
    let mut n = Node::new(cfg);
    n.insert_object(Object::var(0x2000, "Blob", DataType::Domain, Access::Rw, Value::Bytes(Vec::new())));
    n.insert_object(Object::var(
        0x2001,
        "Name",
        DataType::VisibleString,
        Access::Rw,
        Value::Str("drivebus".into()),
    ));
    n.insert_object(Object::var(0x2002, "Signed", DataType::Integer32, Access::Rw, Value::I32(-5)));
    n.insert_object(Object::with_code(0x2003, ObjectCode::Var, "Mappable").with_sub(
        SubObject::new(0, "Mappable", DataType::Unsigned16, Access::Rw, Value::U16(0xBEEF)).mappable(),
    ));
    n.insert_object(Object::with_code(0x2004, ObjectCode::Var, "Mappable32").with_sub(
        SubObject::new(0, "Mappable32", DataType::Integer32, Access::Rw, Value::I32(-5)).mappable(),
    ));
    n
}

pub fn host(hub: &Hub, n: Node) -> DeviceHost<NodeDevice<NoHooks>> {
    spawn(NodeDevice::new(n, NoHooks), hub.attach())
}

/// A master on `hub` with short SDO timeouts.
pub fn master(hub: &Hub) -> Master {
    let cfg = drivebus_master::MasterConfig { sdo_timeout: Duration::from_millis(300), ..Default::default() };
    Master::with_config(hub.attach(), cfg)
}
pub mod dual;
