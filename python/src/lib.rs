//! `drivebus._drivebus`, the Rust half of the Python package `drivebus`
//! (`pip install ./python`): drive twins hosted inside the Python process
//! on the in-process virtual CAN bus, in real time.
//!
//! The drives are what `drivebus serve` hosts: each personality built on
//! its default machine (`Profile::build_on_default_machine`) and run by
//! `drivebus_transport::host` as its own participant of a named
//! `drivebus_transport::hub::virtual_hub`. Python joins the same hub as one more
//! participant ([`bus::VirtualBus`]); `drivebus/can_interface.py` puts
//! python-can's `BusABC` on top of it.
//!
//! `Server` ([`serve`]) puts the same drives on a socketcand server in
//! the process (`drivebus.serve()`), for code that must use TCP.
//!
//! `EthercatServer` ([`ethercat`]) serves an EtherCAT slave line on a
//! network interface (`drivebus.ethercat.serve()`);
//! `EthercatSimulation` ([`ecat_sim`]) the in-process line of `drivebus
//! demo --ethercat` with its master, in simulated time
//! (`drivebus.ethercat.Simulation`).
//!
//! `Simulation` ([`sim`]) hosts the same drives on the virtual bus in
//! simulated time instead (`drivebus_bus::Bus`): deterministic. Its
//! `master()` ([`master`]) is the master of `drivebus_master` (the tool's)
//! as a station of that bus, run in simulated time.
//!
//! The tasks run on one tokio runtime per process; Python threads block on
//! it with the GIL released, so a python-can `Notifier` thread and the
//! drives run while the main thread waits.

use std::sync::LazyLock;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

mod bus;
mod control;
mod ecat_sim;
mod ethercat;
mod lss;
mod master;
mod pdo;
mod serve;
mod sim;
mod state;

/// The runtime the hosted drives run on, started on first use.
static RUNTIME: LazyLock<Result<tokio::runtime::Runtime, String>> = LazyLock::new(|| {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("drivebus")
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the drivebus runtime: {e}"))
});

/// The process's runtime, or the reason it could not start.
fn runtime() -> PyResult<&'static tokio::runtime::Runtime> {
    RUNTIME.as_ref().map_err(|e| PyRuntimeError::new_err(e.clone()))
}

/// The extension module.
#[pymodule]
fn _drivebus(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<bus::VirtualBus>()?;
    m.add_class::<state::DriveState>()?;
    m.add_class::<sim::Simulation>()?;
    m.add_class::<serve::Server>()?;
    m.add_class::<master::Master>()?;
    m.add_class::<master::Drive>()?;
    m.add_class::<pdo::Pdos>()?;
    m.add_class::<lss::Lss>()?;
    m.add_class::<ethercat::EthercatServer>()?;
    m.add_class::<ecat_sim::EthercatSimulation>()?;
    master::add_exceptions(m)?;
    m.add("PROFILES", drivebus_personality::Profile::all().iter().map(|p| p.name()).collect::<Vec<_>>())?;
    Ok(())
}
