//! The control interface of a running `drivebus serve` (`--control ADDR`,
//! issue 17 §3): a loopback TCP port or a Unix socket taking one JSON
//! request per line and answering one JSON line (docs/control.md), and
//! the `drivebus control` client.
//!
//! Every machine input and fault goes through the drive's machine
//! schedule (`Personality::change_machine`), the mechanism the machine
//! file's `[[node.inputs]]` and `[[node.faults]]` use; bus rules are the
//! hub's `FaultRule`s, the ones `--fault` installs.

use std::collections::BTreeMap;
use std::sync::Arc;

use anyhow::{Context, anyhow, bail};
use drivebus_can::LinkState;
use drivebus_can::timing::{BUS_OFF_RECOVERY_BITS, bits_duration};
use drivebus_personality::PersonalityDevice;
use drivebus_personality::build::EdsDevice;
use drivebus_personality::machine::{Change, InForce, MachineError};
use drivebus_transport::Hub;
use drivebus_transport::host::{Controller, DeviceHost, spawn};

use serde::{Deserialize, Serialize};
use tokio::io::{AsyncBufReadExt, AsyncRead, AsyncWrite, AsyncWriteExt, BufReader};
use tokio::sync::Mutex;

/// The bitrate a bus-off recovery is timed at on an unpaced bus.
const UNPACED_BITRATE: u32 = 125_000;

/// One request line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum ControlRequest {
    /// An input of a drive's machine, named as in `[[node.inputs]]`.
    Input {
        /// Node-ID (CAN) or the slave's position from 1 (EtherCAT).
        node: u8,
        /// `digital`, `analog`, `master_velocity`, `master_position`,
        /// `motor_temperature`, `brake`.
        input: String,
        /// Line (digital 1..16) or channel (analog 1..4).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        line: Option<u8>,
        /// The value (a level 0/1, volts, counts, °C).
        value: f64,
        /// Seconds, then back to the machine's value.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        duration: Option<f64>,
    },
    /// A machine fault, named as in `[[node.faults]]`, or `clear`.
    Fault {
        /// Node-ID (CAN) or the slave's position from 1 (EtherCAT).
        node: u8,
        /// `encoder`, `trip`, `wire_break`, `over_current`, … or `clear`.
        kind: String,
        /// For `trip` and `wire_break`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        switch: Option<String>,
        /// Seconds, then it clears.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        duration: Option<f64>,
    },
    /// A bus fault rule in `--fault` syntax, or `clear` to remove them all.
    Bus {
        /// `drop:IDS[,times=N]…`, `corrupt:IDS:MASK[,…]` or `clear`.
        rule: String,
    },
    /// A drive's CAN controller goes bus-off (it hears and sends nothing)
    /// or recovers.
    Link {
        /// Node-ID (CAN) or the slave's position from 1 (EtherCAT).
        node: u8,
        /// Bus-off (`true`) or back on the bus (`false`).
        bus_off: bool,
        /// Bus-off that ends by itself after 128 × 11 bit times at the
        /// bus's bitrate (125 kbit/s when unpaced), as a controller with
        /// automatic recovery; without it only `bus_off: false` ends it.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        recover: bool,
    },
    /// A drive's power.
    Power {
        /// Node-ID (CAN) or the slave's position from 1 (EtherCAT).
        node: u8,
        /// On (boots from its stored parameters) or off.
        on: bool,
    },
}

/// One answer line: `{"ok":true}` or `{"ok":false,"error":"…"}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Response {
    /// Whether the request was carried out.
    pub ok: bool,
    /// Why not: the cause first, then what to do.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// A served node's host: a drive, or a device from an EDS/DCF.
pub enum NodeHost {
    /// A drive (`--drive`).
    Drive(DeviceHost<Controller<PersonalityDevice>>),
    /// A device from a file (`--device`).
    Device(DeviceHost<Controller<EdsDevice>>),
}

impl NodeHost {
    /// Hosts a drive on `hub`.
    pub fn drive(dev: PersonalityDevice, hub: &Hub) -> NodeHost {
        NodeHost::Drive(spawn(Controller::new(dev), hub.attach()))
    }

    /// Hosts a device from a file on `hub`.
    pub fn device(dev: EdsDevice, hub: &Hub) -> NodeHost {
        NodeHost::Device(spawn(Controller::new(dev), hub.attach()))
    }

    /// What is in force on the node's machine; `None` when the host has stopped.
    async fn in_force(&self) -> Option<Vec<InForce>> {
        match self {
            NodeHost::Drive(h) => h.with(|d, now| d.device.app.machine_in_force(now)).await,
            NodeHost::Device(h) => h.with(|d, now| d.device.app.machine_in_force(now)).await,
        }
    }

    /// `None` when the host has stopped.
    async fn change(&self, c: Change, duration: Option<f64>) -> Option<Result<(), MachineError>> {
        // Through the node, so the application is polled after the change
        // (a module polls only when an input or a timer asks).
        match self {
            NodeHost::Drive(h) => {
                h.with_out(move |d, now, out| {
                    let dev = &mut d.device;
                    dev.node.with_app(now, &mut dev.app, out, |app, _| app.change_machine(now, c, duration))
                })
                .await
            }
            NodeHost::Device(h) => {
                h.with_out(move |d, now, out| {
                    let dev = &mut d.device;
                    dev.node.with_app(now, &mut dev.app, out, |app, _| app.change_machine(now, c, duration))
                })
                .await
            }
        }
    }

    /// Bus-off (recovering by itself after `recovery`, if given) or back on.
    async fn set_link(&self, bus_off: bool, recovery: Option<std::time::Duration>) -> Option<()> {
        let state = move |now: drivebus_can::Instant| match bus_off {
            true => LinkState::BusOff { recover_at: recovery.map(|d| now + d) },
            false => LinkState::Active,
        };
        match self {
            NodeHost::Drive(h) => h.with_out(move |d, now, out| d.set_link(state(now), now, out)).await,
            NodeHost::Device(h) => h.with_out(move |d, now, out| d.set_link(state(now), now, out)).await,
        }
    }

    /// Cuts the power: the task ends.
    pub fn stop(&self) {
        match self {
            NodeHost::Drive(h) => h.stop(),
            NodeHost::Device(h) => h.stop(),
        }
    }

    /// The task, to await or abort it.
    pub fn into_join_handle(self) -> tokio::task::JoinHandle<()> {
        match self {
            NodeHost::Drive(h) => h.into_join_handle(),
            NodeHost::Device(h) => h.into_join_handle(),
        }
    }
}

/// Builds a node again as at power-on and hosts it on the hub.
pub type PowerOn = Box<dyn Fn(&Hub) -> anyhow::Result<NodeHost> + Send + Sync>;

/// A served node: its host while it has power, and how to power it on.
pub struct ServedNode {
    /// The running node, `None` while its power is off.
    pub host: Option<NodeHost>,
    /// Powers it on again.
    pub power_on: PowerOn,
}

/// The running server as the control interface sees it (in-process use:
/// the same calls as the socket): a CAN bus (`serve`) or an EtherCAT line
/// (`ethercat serve`, where `node` is a slave's position from 1).
pub enum Control {
    /// Nodes on a CAN hub.
    Can {
        /// The bus.
        hub: Hub,
        /// The nodes by node-ID.
        nodes: Mutex<BTreeMap<u8, ServedNode>>,
    },
    /// An EtherCAT line (`crate::ethercat::control`).
    Ethercat(drivebus_ethercat::Host),
}

impl Control {
    /// Control over the `nodes` served on `hub`.
    pub fn new(hub: Hub, nodes: Vec<(u8, ServedNode)>) -> Control {
        Control::Can { hub, nodes: Mutex::new(nodes.into_iter().collect()) }
    }

    /// Control over an EtherCAT line.
    pub fn ethercat(host: drivebus_ethercat::Host) -> Control {
        Control::Ethercat(host)
    }

    /// Whether `node` is a CAN node this server hosts (powered or not).
    pub async fn serves(&self, node: u8) -> bool {
        match self {
            Control::Can { nodes, .. } => nodes.lock().await.contains_key(&node),
            Control::Ethercat(_) => false,
        }
    }

    /// Stops every node (serve ends).
    pub async fn stop(&self) {
        let Control::Can { nodes, .. } = self else { return };
        for slot in nodes.lock().await.values_mut() {
            if let Some(h) = slot.host.take() {
                h.stop();
            }
        }
    }

    /// Carries out `req`; the error names the cause first, then what to do.
    pub async fn handle(&self, req: ControlRequest) -> anyhow::Result<()> {
        let (hub, nodes) = match self {
            Control::Can { hub, nodes } => (hub, nodes),
            Control::Ethercat(host) => return crate::ethercat::control::handle(host, req),
        };
        match req {
            ControlRequest::Input { node, input, line, value, duration } => {
                let c = Change::input(&input, line, value).map_err(|e| anyhow!("input: {e}"))?;
                self.change(node, c, duration).await
            }
            ControlRequest::Fault { node, kind, switch, duration } => {
                let c = Change::fault(&kind, switch.as_deref()).map_err(|e| anyhow!("fault: {e}"))?;
                self.change(node, c, duration).await
            }
            ControlRequest::Bus { rule } if rule == "clear" => {
                hub.clear_faults();
                Ok(())
            }
            ControlRequest::Bus { rule } => {
                let r = crate::fault::parse(&rule)?;
                hub.add_fault(r)?;
                Ok(())
            }
            ControlRequest::Link { node, bus_off, recover } => {
                let rate = hub.bitrate().unwrap_or(UNPACED_BITRATE);
                let recovery = recover.then(|| bits_duration(BUS_OFF_RECOVERY_BITS, rate));
                let nodes = nodes.lock().await;
                let host = running(&nodes, node)?;
                host.set_link(bus_off, recovery).await.ok_or_else(|| stopped(node))
            }
            ControlRequest::Power { node, on } => Self::power(hub, nodes, node, on).await,
        }
    }

    async fn change(&self, node: u8, change: Change, duration: Option<f64>) -> anyhow::Result<()> {
        let Control::Can { nodes, .. } = self else { bail!("not a CAN server") };
        let nodes = nodes.lock().await;
        let host = running(&nodes, node)?;
        // The machine's refusal stays a `MachineError` (the HTTP API
        // answers it 400, a powered-off node 409).
        host.change(change, duration)
            .await
            .ok_or_else(|| stopped(node))?
            .map_err(|e| anyhow::Error::new(e).context(format!("node {node}")))
    }

    /// The machine's faults and input changes in force on `node`, a CAN
    /// node this server hosts and runs (the machine file's and those made
    /// through this interface).
    pub async fn in_force(&self, node: u8) -> anyhow::Result<Vec<InForce>> {
        let Control::Can { nodes, .. } = self else { bail!("not a CAN server") };
        let nodes = nodes.lock().await;
        running(&nodes, node)?.in_force().await.ok_or_else(|| stopped(node))
    }

    async fn power(
        hub: &Hub,
        nodes: &Mutex<BTreeMap<u8, ServedNode>>,
        node: u8,
        on: bool,
    ) -> anyhow::Result<()> {
        let mut nodes = nodes.lock().await;
        let err = no_node(&nodes, node);
        let slot = nodes.get_mut(&node).ok_or(err)?;
        match (on, slot.host.take()) {
            (false, Some(h)) => h.stop(),
            (true, None) => slot.host = Some((slot.power_on)(hub)?),
            // Already as asked: nothing changes.
            (_, h) => slot.host = h,
        }
        Ok(())
    }

    /// Answers one request line.
    pub async fn answer(&self, line: &str) -> Response {
        let r = match serde_json::from_str::<ControlRequest>(line) {
            Ok(req) => self.handle(req).await,
            Err(e) => Err(anyhow!("bad request: {e}: send one JSON object per line (docs/control.md)")),
        };
        match r {
            Ok(()) => Response { ok: true, error: None },
            Err(e) => Response { ok: false, error: Some(format!("{e:#}")) },
        }
    }
}

/// The host of `node`, or why there is none (the cause, then what to do).
fn running(nodes: &BTreeMap<u8, ServedNode>, node: u8) -> anyhow::Result<&NodeHost> {
    match nodes.get(&node) {
        None => Err(no_node(nodes, node)),
        Some(ServedNode { host: None, .. }) => {
            Err(anyhow!("node {node} is powered off: power it on first (drivebus control power {node} on)"))
        }
        Some(ServedNode { host: Some(h), .. }) => Ok(h),
    }
}

fn no_node(nodes: &BTreeMap<u8, ServedNode>, node: u8) -> anyhow::Error {
    let list = nodes.keys().map(u8::to_string).collect::<Vec<_>>().join(", ");
    anyhow!("no node with node-ID {node} is served: use one of {list}")
}

fn stopped(node: u8) -> anyhow::Error {
    anyhow!("node {node} has stopped running: restart serve")
}

/// Where the control interface listens: a loopback TCP address or a Unix
/// socket path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Addr {
    /// `127.0.0.1:PORT` (loopback only: the interface has no access control).
    Tcp(std::net::SocketAddr),
    /// A Unix socket path.
    Unix(std::path::PathBuf),
}

impl Addr {
    /// Parses `ADDR`: `HOST:PORT` with a loopback host, or a path.
    pub fn parse(s: &str) -> anyhow::Result<Addr> {
        if let Ok(a) = s.parse::<std::net::SocketAddr>() {
            if !a.ip().is_loopback() {
                bail!(
                    "bad control address `{s}`: not a loopback address (the control interface has no access \
                     control): use 127.0.0.1:PORT or a Unix socket path"
                );
            }
            return Ok(Addr::Tcp(a));
        }
        if s.is_empty() || (!s.contains('/') && s.contains(':')) {
            bail!("bad control address `{s}`: expected 127.0.0.1:PORT or a Unix socket path");
        }
        Ok(Addr::Unix(s.into()))
    }
}

impl std::fmt::Display for Addr {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Addr::Tcp(a) => write!(f, "{a}"),
            Addr::Unix(p) => write!(f, "{}", p.display()),
        }
    }
}

/// Binds `addr` and serves requests from every connection until the task
/// is aborted; returns the task and the bound address (the real port for
/// `:0`).
pub async fn listen(
    addr: &Addr,
    control: Arc<Control>,
) -> anyhow::Result<(tokio::task::JoinHandle<()>, Addr)> {
    match addr {
        Addr::Tcp(a) => {
            let l =
                tokio::net::TcpListener::bind(a).await.with_context(|| format!("cannot listen on {a}"))?;
            let bound = Addr::Tcp(l.local_addr()?);
            let task = tokio::spawn(async move {
                while let Ok((s, _)) = l.accept().await {
                    tokio::spawn(session(s, control.clone()));
                }
            });
            Ok((task, bound))
        }
        #[cfg(unix)]
        Addr::Unix(p) => {
            // A socket file left by an earlier run would refuse the bind.
            if std::fs::symlink_metadata(p).is_ok_and(|m| {
                use std::os::unix::fs::FileTypeExt;
                m.file_type().is_socket()
            }) {
                let _ = std::fs::remove_file(p);
            }
            let l = tokio::net::UnixListener::bind(p)
                .with_context(|| format!("cannot listen on the Unix socket {}", p.display()))?;
            let task = tokio::spawn(async move {
                while let Ok((s, _)) = l.accept().await {
                    tokio::spawn(session(s, control.clone()));
                }
            });
            Ok((task, addr.clone()))
        }
        #[cfg(not(unix))]
        Addr::Unix(p) => {
            bail!("cannot listen on {}: Unix sockets need a Unix system; use 127.0.0.1:PORT", p.display())
        }
    }
}

async fn session(s: impl AsyncRead + AsyncWrite + Unpin, control: Arc<Control>) {
    let (r, mut w) = tokio::io::split(s);
    let mut lines = BufReader::new(r).lines();
    while let Ok(Some(line)) = lines.next_line().await {
        if line.trim().is_empty() {
            continue;
        }
        let resp = control.answer(&line).await;
        let mut text = serde_json::to_string(&resp).unwrap_or_else(|_| r#"{"ok":false}"#.to_owned());
        text.push('\n');
        if w.write_all(text.as_bytes()).await.is_err() {
            return;
        }
    }
}

/// Sends `req` to the server at `addr` and returns its answer.
pub async fn request(addr: &Addr, req: &ControlRequest) -> anyhow::Result<Response> {
    let mut line = serde_json::to_string(req)?;
    line.push('\n');
    let what = || {
        format!("cannot reach the control interface at {addr}: is `drivebus serve --control {addr}` running?")
    };
    match addr {
        Addr::Tcp(a) => exchange(tokio::net::TcpStream::connect(a).await.with_context(what)?, &line).await,
        #[cfg(unix)]
        Addr::Unix(p) => exchange(tokio::net::UnixStream::connect(p).await.with_context(what)?, &line).await,
        #[cfg(not(unix))]
        Addr::Unix(_) => bail!("{}", what()),
    }
    .with_context(|| format!("control interface at {addr}"))
}

async fn exchange(s: impl AsyncRead + AsyncWrite + Unpin, line: &str) -> anyhow::Result<Response> {
    let (r, mut w) = tokio::io::split(s);
    w.write_all(line.as_bytes()).await?;
    let answer = BufReader::new(r).lines().next_line().await?.context("the server closed the connection")?;
    serde_json::from_str(&answer).with_context(|| format!("not an answer: {answer}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses() {
        assert_eq!(Addr::parse("127.0.0.1:7000").unwrap(), Addr::Tcp("127.0.0.1:7000".parse().unwrap()));
        assert_eq!(Addr::parse("/tmp/x.sock").unwrap(), Addr::Unix("/tmp/x.sock".into()));
        assert!(Addr::parse("0.0.0.0:7000").unwrap_err().to_string().contains("not a loopback"));
        assert!(Addr::parse("host:7000").is_err());
    }

    #[test]
    fn requests_read_as_documented() {
        let r: ControlRequest =
            serde_json::from_str(r#"{"op":"input","node":5,"input":"digital","line":3,"value":1}"#).unwrap();
        assert_eq!(
            r,
            ControlRequest::Input {
                node: 5,
                input: "digital".into(),
                line: Some(3),
                value: 1.0,
                duration: None
            }
        );
        assert!(serde_json::from_str::<ControlRequest>(r#"{"op":"input","node":5,"valu":1}"#).is_err());
        let p: ControlRequest = serde_json::from_str(r#"{"op":"power","node":5,"on":false}"#).unwrap();
        assert_eq!(p, ControlRequest::Power { node: 5, on: false });
    }
}
