//! `drivebus serve`: virtual drives on a socketcand server, or on any bus.
//!
//! The drives sit on an in-process [`Hub`], each its own participant,
//! hosted in real time by `drivebus_transport::host`. Without `--bus` (or
//! with `--bus virtual`) a socketcand server on `--listen` shares that hub.
//! With `--bus URL` the hub is bridged to that bus (SocketCAN, slcan,
//! socketcand): the drives are stations on it and keep their own timing;
//! the socketcand listener runs only when `--listen` is given.
//!
//! Contract (other tools rely on it): one stdout line once the drives are
//! up — containing `listening on HOST:PORT (channel NAME)` when listening,
//! `serving on URL` otherwise, ending `; control on ADDR` with `--control`
//! (`crate::control`) and `; page on http://ADDR/` with `--http` (`crate::web`); runs until SIGINT or SIGTERM, then exits 0.

use std::io::Write;

use anyhow::{Context, anyhow};
use drivebus_personality::build::BuildOptions;
use drivebus_transport::socketcand::{SocketcandConfig, SocketcandServer};
use drivebus_transport::{BusUrl, Hub, HubConfig};

use crate::args::{DEFAULT_LISTEN, Global, ServeArgs};
use crate::vdevice::DeviceSpec;
use crate::vdrive::{DriveSpec, host_on_hub};

/// Runs the drives until a termination signal.
pub async fn run(g: &Global, a: &ServeArgs) -> anyhow::Result<()> {
    let specs = DriveSpec::parse_all(&a.drives)?;
    // The device files are read and checked before anything starts.
    let devices = DeviceSpec::parse_all(&a.devices, &specs.iter().map(|s| s.node).collect::<Vec<_>>())?;
    let lss_slaves = a.lss_slaves.iter().map(|s| lss_slave(s)).collect::<anyhow::Result<Vec<_>>>()?;
    check_options(a)?;
    let outer = open_outer(g).await?;
    let hub = Hub::new(HubConfig { bitrate: a.bitrate, ..HubConfig::default() });
    crate::fault::install(&hub, &a.faults)?;
    let listen = match (&a.listen, &outer) {
        (Some(l), _) => Some(l.clone()),
        (None, None) => Some(DEFAULT_LISTEN.to_owned()),
        (None, Some(_)) => None,
    };
    let server = match &listen {
        Some(l) => Some(
            SocketcandServer::bind_with(l.as_str(), SocketcandConfig::new(&a.channel), hub.clone())
                .await
                .with_context(|| format!("cannot listen on {l}"))?,
        ),
        None => None,
    };
    // The bridge first: the drives' boot-up messages reach the real bus.
    let bridge = outer.map(|bus| drivebus_transport::host::bridge(&hub, bus));
    if bridge.is_some() {
        // An slcan adapter takes its open command, a socketcand server its
        // rawmode grace time, before frames get through.
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
    let options = BuildOptions { eds_object: a.eds_object };
    // Checked before anything starts.
    let control_addr = a.control.as_deref().map(crate::control::Addr::parse).transpose()?;
    // The page's master listens before the drives start: it hears their boot-ups.
    let web_master = a.http.as_ref().map(|_| drivebus_master::Master::new(hub.attach()));
    let (nodes, described) =
        host_on_hub(&specs, &devices, &hub, a.state_dir.as_deref(), options, g.machine.as_deref())?;
    // Kept until the end: dropping a host stops its slave.
    let _lss_hosts = drivebus_transport::host::spawn_on_hub(lss_slaves, &hub);
    let control = std::sync::Arc::new(crate::control::Control::new(hub.clone(), nodes));
    let control_task = match &control_addr {
        Some(addr) => Some(crate::control::listen(addr, control.clone()).await?),
        None => None,
    };
    let web = match (&a.http, &web_master) {
        (Some(addr), Some(m)) => {
            let profiles = specs.iter().map(|s| (s.node, s.profile)).collect();
            Some(
                crate::web::start(
                    m.clone(),
                    crate::dict::Dict::default(),
                    profiles,
                    Some(control.clone()),
                    a.bitrate,
                    addr,
                )
                .await?,
            )
        }
        _ => None,
    };
    let list = served_list(&specs, &described, &a.lss_slaves);
    let pace = a.bitrate.map_or_else(|| "unpaced".to_owned(), |b| format!("{b} bit/s"));
    // Handlers first: a SIGTERM right after the ready line must end in a
    // clean exit 0, not the default action (found by the interop suite).
    let stop = Signals::install()?;
    {
        let mut out = std::io::stdout().lock();
        let mut on = if bridge.is_some() { format!(" on {}", g.bus) } else { String::new() };
        if let Some((_, addr)) = &control_task {
            on.push_str(&format!("; control on {addr}"));
        }
        if let Some(w) = &web {
            on.push_str(&format!("; page on {}", w.url()));
        }
        match &server {
            Some((_, addr)) => writeln!(
                out,
                "drivebus serve: socketcand listening on {addr} (channel {}) ({pace}); {list}{on}",
                a.channel
            )?,
            None => writeln!(out, "drivebus serve: serving on {} ({pace}); {list}{on}", g.bus)?,
        }
        out.flush()?;
    }
    tracing::info!(bus = %g.bus, "serving");
    stop.wait().await?;
    if let Some((server, _)) = &server {
        tracing::info!(clients = server.client_count(), relayed = server.hub().relayed(), "stopping");
    }
    if let Some((task, addr)) = control_task {
        task.abort();
        if let crate::control::Addr::Unix(p) = addr {
            let _ = std::fs::remove_file(p);
        }
    }
    control.stop().await;
    drop(web);
    if let Some(m) = web_master {
        let _ = m.close().await;
    }
    if let Some(b) = bridge {
        b.abort();
    }
    drop(server);
    Ok(())
}

/// The options checked before anything starts (`--channel`, `--bitrate`,
/// `--state-dir` created).
fn check_options(a: &ServeArgs) -> anyhow::Result<()> {
    if a.channel.is_empty() || a.channel.contains(char::is_whitespace) || a.channel.contains(['<', '>']) {
        anyhow::bail!("bad --channel `{}`: a bus name without spaces or angle brackets", a.channel);
    }
    if let Some(b) = a.bitrate
        && !(1_000..=1_000_000).contains(&b)
    {
        anyhow::bail!("bad --bitrate {b}: expected 1000..1000000 bit/s");
    }
    if let Some(dir) = &a.state_dir {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create --state-dir {}", dir.display()))?;
    }
    Ok(())
}

/// The real bus of `--bus` the drives are bridged to, or `None` on the
/// virtual bus.
async fn open_outer(g: &Global) -> anyhow::Result<Option<drivebus_transport::CanBus>> {
    // The transport's message already names the URL and the cause.
    let parsed = BusUrl::parse(&g.bus).map_err(|e| anyhow!("{e}"))?;
    Ok(match parsed {
        BusUrl::Virtual { .. } => None,
        _ => Some(
            tokio::time::timeout(
                std::time::Duration::from_secs(10),
                drivebus_transport::open_parsed(&g.bus, &parsed),
            )
            .await
            .map_err(|_| anyhow!("cannot open `{}`: timed out after 10 s", g.bus))?
            .map_err(|e| anyhow!("{e}"))?,
        ),
    })
}

/// What the ready line says is served: drives, devices, LSS slaves.
fn served_list(specs: &[DriveSpec], described: &[String], lss_slaves: &[String]) -> String {
    let drive_list = specs.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(" ");
    let list = match (specs.is_empty(), described.is_empty()) {
        (_, true) => format!("drives {drive_list}"),
        (true, false) => format!("devices {}", described.join(" ")),
        (false, false) => format!("drives {drive_list}; devices {}", described.join(" ")),
    };
    if lss_slaves.is_empty() {
        list
    } else {
        format!("{list}; unconfigured LSS slaves {}", lss_slaves.join(" "))
    }
}

/// An unconfigured CiA 301 slave (node-ID FFh) with LSS, at the LSS
/// address `VENDOR:PRODUCT:REVISION:SERIAL` (`--lss-slave`).
fn lss_slave(s: &str) -> anyhow::Result<drivebus_node::NodeDevice<drivebus_od::NoHooks>> {
    let bad = |why: &str| anyhow!("bad --lss-slave `{s}`: {why}");
    let parts: Vec<&str> = s.split(':').collect();
    let [vendor_id, product_code, revision, serial] = parts[..] else {
        return Err(bad("expected VENDOR:PRODUCT:REVISION:SERIAL (4 numbers)"));
    };
    let num = |p: &str| {
        let n = match p.strip_prefix("0x").or_else(|| p.strip_prefix("0X")) {
            Some(h) => u32::from_str_radix(h, 16),
            None => p.parse::<u32>(),
        };
        n.map_err(|_| bad(&format!("`{p}` is not a 32-bit number (decimal or 0x hex)")))
    };
    let mut cfg = drivebus_node::NodeConfig::new(0xFF);
    cfg.lss = true;
    cfg.identity = drivebus_node::Identity {
        vendor_id: num(vendor_id)?,
        product_code: num(product_code)?,
        revision: num(revision)?,
        serial: num(serial)?,
    };
    Ok(drivebus_node::NodeDevice::new(drivebus_node::Node::new(cfg), drivebus_od::NoHooks))
}

/// SIGINT and SIGTERM handlers, installed before they are awaited so no
/// signal between install and wait takes the default action.
pub struct Signals {
    #[cfg(unix)]
    term: tokio::signal::unix::Signal,
    #[cfg(unix)]
    int: tokio::signal::unix::Signal,
}

impl Signals {
    /// Install the handlers now.
    pub fn install() -> anyhow::Result<Signals> {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{SignalKind, signal};
            Ok(Signals {
                term: signal(SignalKind::terminate()).context("installing the SIGTERM handler")?,
                int: signal(SignalKind::interrupt()).context("installing the SIGINT handler")?,
            })
        }
        #[cfg(not(unix))]
        Ok(Signals {})
    }

    /// Wait for SIGINT or SIGTERM (Ctrl-C elsewhere).
    pub async fn wait(mut self) -> anyhow::Result<()> {
        #[cfg(unix)]
        tokio::select! {
            _ = self.term.recv() => {}
            _ = self.int.recv() => {}
        }
        #[cfg(not(unix))]
        tokio::signal::ctrl_c().await.context("waiting for Ctrl-C")?;
        let _ = &mut self;
        Ok(())
    }
}

/// Waits for SIGINT or SIGTERM (Ctrl-C elsewhere).
pub async fn wait_for_signal() -> anyhow::Result<()> {
    Signals::install()?.wait().await
}

#[cfg(test)]
mod tests {
    use super::lss_slave;

    #[test]
    fn lss_slave_addresses_and_their_messages() {
        assert!(lss_slave("0xABC:0x77:3:16").is_ok());
        let e = |s| lss_slave(s).err().map(|e| e.to_string()).unwrap_or_default();
        assert_eq!(
            e("1:2:3"),
            "bad --lss-slave `1:2:3`: expected VENDOR:PRODUCT:REVISION:SERIAL (4 numbers)"
        );
        assert_eq!(e("1:2:3:x"), "bad --lss-slave `1:2:3:x`: `x` is not a 32-bit number (decimal or 0x hex)");
        assert!(e("1:2:3:0x100000000").contains("not a 32-bit number"));
    }
}
