//! One connection per command: the bus named by `--bus` (with the `--sim`
//! drives hosted on the virtual bus first) and the master on it. Every
//! command talks to the bus through this master, and closes it before it
//! reports: a frame the command sent has been written by the transport
//! when the command says it was sent.

use std::time::Duration;

use anyhow::{Context, anyhow};
use drivebus_master::{Master, MasterConfig};

use crate::args::Global;
use crate::dict::Dict;
use crate::vdevice::DeviceSpec;
use crate::vdrive::{DriveSpec, spawn_on_hub};

/// Virtual drives hosted by this process for `--sim`; stopped on drop.
pub struct Hosted(Vec<tokio::task::JoinHandle<()>>);

impl Drop for Hosted {
    fn drop(&mut self) {
        for d in &self.0 {
            d.abort();
        }
    }
}

/// How long hosted `--sim` devices may take to send their boot-up.
const HOSTED_BOOT_LIMIT: Duration = Duration::from_secs(5);

/// Set when a command opened the in-process bus with nothing on it: a
/// timeout then says so.
static EMPTY_BUS: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// The hint for a timeout on the empty in-process bus, if that is the bus.
pub fn empty_bus_hint() -> Option<&'static str> {
    EMPTY_BUS.get().map(String::as_str)
}

/// The master of one command, with what it needs to explain itself.
pub struct Conn {
    /// The bus URL as given.
    pub url: String,
    /// The master on the bus.
    pub master: Master,
    /// The SDO/response timeout in force.
    pub timeout: Duration,
    /// Object names and types (`--eds`, then CiA 301/402).
    pub dict: Dict,
    _hosted: Hosted,
}

/// The `--node` option, required by this command.
pub fn need_node(g: &Global) -> anyhow::Result<u8> {
    g.node.ok_or_else(|| crate::error::coded("usage", anyhow!("this command needs --node N (1..127)")))
}

impl Conn {
    /// Opens `g.bus` (on a virtual bus, first starts the `--sim` drives)
    /// and starts the master on it.
    pub async fn open(g: &Global) -> anyhow::Result<Conn> {
        let dict = Dict { eds: crate::eds_cmd::load_global_eds(g)? };
        Conn::open_with(g, dict).await
    }

    /// [`open`](Self::open) with the dictionary loaded already.
    pub async fn open_with(g: &Global, dict: Dict) -> anyhow::Result<Conn> {
        // `--sim FILE.eds:NODE` is a device from its file, else a drive.
        let (files, drives_given): (Vec<String>, Vec<String>) =
            g.sim.iter().cloned().partition(|s| DeviceSpec::is_file_spec(s));
        let specs = DriveSpec::parse_all(&drives_given)?;
        let devices = DeviceSpec::parse_all(&files, &specs.iter().map(|s| s.node).collect::<Vec<_>>())?;
        // The transport's message already names the URL and the cause.
        let parsed = drivebus_transport::BusUrl::parse(&g.bus).map_err(|e| crate::error::coded("bus", e))?;
        let mut hub = None;
        let none = specs.is_empty() && devices.is_empty();
        if none && g.machine.is_some() {
            return Err(crate::error::coded(
                "usage",
                anyhow!("--machine is the machine around --sim drives: give them with --sim PROFILE:NODE"),
            ));
        }
        if !none {
            let drivebus_transport::BusUrl::Virtual { name } = &parsed else {
                return Err(crate::error::coded(
                    "usage",
                    anyhow!("--sim hosts drives only on the `virtual` bus, not on `{}`", g.bus),
                ));
            };
            hub = Some(drivebus_transport::hub::virtual_hub(name));
        }
        if none && matches!(parsed, drivebus_transport::BusUrl::Virtual { .. }) {
            let _ = EMPTY_BUS.set(format!(
                "; nothing is on the bus: `{}` is this process's own in-process bus and no --sim drive was given. Give --bus URL (or set DRIVEBUS_BUS, e.g. socketcand://127.0.0.1:29536/can0 for `drivebus serve`), or --sim PROFILE:NODE",
                g.bus
            ));
        }
        let bus =
            tokio::time::timeout(Duration::from_secs(10), drivebus_transport::open_parsed(&g.bus, &parsed))
                .await
                .map_err(|_| {
                    crate::error::coded("bus", anyhow!("timed out after 10 s: cannot open `{}`", g.bus))
                })?
                .map_err(|e| crate::error::coded("bus", open_error(&g.bus, e)))?;
        let timeout = Duration::from_millis(g.timeout_ms(1000));
        let master = Master::with_config(
            bus,
            MasterConfig { sdo_timeout: timeout, sdo_retries: g.retries, ..MasterConfig::default() },
        );
        let mut drives = Vec::new();
        if let Some(hub) = &hub {
            // The master listens before the drives start, so their power-on
            // boot-ups are over before the command's first frame and never
            // read as an answer to it (a reset waiting for a boot-up).
            let mut events = master.subscribe_events();
            drives = spawn_on_hub(&specs, &devices, hub, None, Default::default(), g.machine.as_deref())?.0;
            let mut waiting: std::collections::BTreeSet<u8> =
                specs.iter().map(|s| s.node).chain(devices.iter().map(|d| d.node)).collect();
            let booted = tokio::time::timeout(HOSTED_BOOT_LIMIT, async {
                while !waiting.is_empty() {
                    match events.recv().await {
                        Ok(drivebus_master::MasterEvent::Bootup { node }) => {
                            waiting.remove(&node);
                        }
                        Ok(_) | Err(tokio::sync::broadcast::error::RecvError::Lagged(_)) => {}
                        Err(tokio::sync::broadcast::error::RecvError::Closed) => break,
                    }
                }
            })
            .await;
            if booted.is_err() || !waiting.is_empty() {
                let nodes: Vec<String> = waiting.iter().map(u8::to_string).collect();
                return Err(crate::error::coded(
                    "bus",
                    anyhow!(
                        "the --sim device(s) at node {} sent no boot-up within {} s; the virtual bus is not carrying their frames",
                        nodes.join(", "),
                        HOSTED_BOOT_LIMIT.as_secs()
                    ),
                ));
            }
        }
        let hosted = Hosted(drives);
        if let Some(eds) = &dict.eds
            && let Some(node) = g.node
            && let Ok(od) = drivebus_eds::to_od(eds, node)
        {
            master.set_eds(node, od);
        }
        Ok(Conn { url: g.bus.clone(), master, timeout, dict, _hosted: hosted })
    }

    /// The error of a command whose bus went away: what was lost and why.
    pub fn lost(&self, why: &str) -> anyhow::Error {
        crate::error::coded(
            "bus_lost",
            anyhow!("the bus connection was lost: {why} (bus `{}`); the command ended", self.url),
        )
    }

    /// Closes the bus after every frame sent was written (see
    /// `Master::close`); a bus lost meanwhile is this command's error.
    pub async fn close(self) -> anyhow::Result<()> {
        if let Some(why) = self.master.bus_lost() {
            return Err(self.lost(&why));
        }
        self.master.close().await.context("closing the bus")
    }
}

/// A bus that would not open: the cause first, then the URL and, where
/// it helps, what to check.
fn open_error(url: &str, e: drivebus_transport::TransportError) -> anyhow::Error {
    use drivebus_transport::Cause;
    match &e.cause {
        Cause::Io(io) => {
            let hint = match io.kind() {
                std::io::ErrorKind::ConnectionRefused => {
                    " (nothing listens there: is `drivebus serve` or socketcand running? check --bus or DRIVEBUS_BUS)"
                }
                _ => "",
            };
            anyhow!("{io}: cannot open `{url}`{hint}")
        }
        _ => e.into(),
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    /// The hosted drives' power-on boot-ups are over when `open` returns:
    /// a command's first frame is never answered by one (a `nmt reset`
    /// of an absent node once took node 1's late boot-up for its own).
    #[tokio::test]
    async fn open_returns_after_the_hosted_drives_booted() {
        let cli = crate::args::Cli::parse_from([
            "drivebus",
            "--bus",
            "virtual://conn-boot-test",
            "--sim",
            "akd:1",
            "--sim",
            "kc1:2",
            "nmt",
            "start",
            "--all",
        ]);
        let conn = Conn::open(&cli.global).await.unwrap();
        assert_eq!(conn.master.seen_nodes(), vec![1, 2]);
        conn.close().await.unwrap();
    }
}
