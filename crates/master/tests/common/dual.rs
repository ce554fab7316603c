//! Runs one test body on both drivers of the master: the deterministic
//! virtual bus in simulated time (`SimBus`) and the tokio driver on an
//! in-process hub with the same devices hosted in real time.

use std::future::Future;
use std::time::Duration;

use drivebus_bus::{Bus, BusConfig};
use drivebus_can::Device;
use drivebus_cia402::drive::Drive;
use drivebus_master::{Master, MasterConfig, SimBus};
use drivebus_node::{Node, NodeDevice};
use drivebus_od::NoHooks;
use drivebus_transport::Hub;
use drivebus_transport::host::spawn;

/// A device of a test world (built, moved once; the size difference is harmless).
#[allow(clippy::large_enum_variant)]
pub enum Station {
    /// A plain CiA 301 node.
    Plain(Node),
    /// A CiA 402 virtual drive.
    Drive(Box<NodeDevice<Drive>>),
    /// Any other device (another master's traffic).
    Other(Box<dyn Device + Send>),
}

impl Station {
    /// The station as a device any host runs.
    fn device(self) -> Box<dyn Device + Send> {
        match self {
            Station::Plain(n) => Box::new(NodeDevice::new(n, NoHooks)),
            Station::Drive(d) => d,
            Station::Other(d) => d,
        }
    }
}

/// Which driver a body runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    /// `SimBus`, simulated time.
    Sim,
    /// `Master::new` on a hub, tokio time.
    Tokio,
}

pub fn config() -> MasterConfig {
    MasterConfig { sdo_timeout: Duration::from_millis(300), ..Default::default() }
}

/// Runs `body` once per driver with the stations `world` builds (called
/// once per driver). Each run is bounded (20 s wall clock for tokio, 10 min
/// simulated for the virtual bus).
pub fn on_both<W, B, F>(world: W, body: B)
where
    W: Fn() -> Vec<Station>,
    B: Fn(Master, Which) -> F,
    F: Future<Output = ()>,
{
    // Simulated time at 1 Mbit/s.
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    for s in world() {
        bus.attach(s.device());
    }
    let mut sim = SimBus::with_config(bus, config());
    sim.set_limit(Duration::from_secs(600));
    let m = sim.master().clone();
    if let Err(e) = sim.block_on(body(m, Which::Sim)) {
        panic!("simulated run: {e}");
    }
    // Real time on the tokio driver.
    let rt = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    rt.block_on(async {
        let hub = Hub::default();
        let mut hosts = Vec::new();
        for s in world() {
            hosts.push(spawn(s.device(), hub.attach()));
        }
        let m = Master::with_config(hub.attach(), config());
        super::bounded(body(m, Which::Tokio)).await;
        drop(hosts);
    });
}
