//! `drivebus serve`: virtual drives on a socketcand server.
//!
//! Contract (other tools rely on it): one stdout line containing
//! `listening on` once clients can connect; runs until SIGINT or SIGTERM,
//! then exits 0.

use std::io::Write;

use anyhow::Context;
use drivebus_personality::build::BuildOptions;
use drivebus_transport::socketcand::{ServerConfig, SocketcandServer};
use drivebus_transport::{Hub, HubConfig};

use crate::args::ServeArgs;
use crate::vdrive::{DriveSpec, spawn_on_hub};

/// Runs the server until a termination signal.
pub async fn run(a: &ServeArgs) -> anyhow::Result<()> {
    let specs = DriveSpec::parse_all(&a.drives)?;
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
    let hub = Hub::new(HubConfig { bitrate: a.bitrate, ..HubConfig::default() });
    crate::fault::install(&hub, &a.faults)?;
    let (server, addr) =
        SocketcandServer::bind_with(a.listen.as_str(), ServerConfig::new(&a.channel), hub.clone())
            .await
            .with_context(|| format!("cannot listen on {}", a.listen))?;
    let options = BuildOptions { eds_object: a.eds_object };
    let drives = spawn_on_hub(&specs, &hub, a.state_dir.as_deref(), options)?;
    let list = specs.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(" ");
    let pace = a.bitrate.map_or_else(|| "unpaced".to_owned(), |b| format!("{b} bit/s"));
    // Handlers first: a SIGTERM right after the ready line must end in a
    // clean exit 0, not the default action (found by the interop suite).
    let stop = Signals::install()?;
    {
        let mut out = std::io::stdout().lock();
        writeln!(
            out,
            "drivebus serve: socketcand listening on {addr} channel {} ({pace}); drives {list}",
            a.channel
        )?;
        out.flush()?;
    }
    tracing::info!(%addr, "serving");
    stop.wait().await?;
    tracing::info!(clients = server.client_count(), relayed = server.hub().relayed(), "stopping");
    for d in drives {
        d.abort();
    }
    drop(server);
    Ok(())
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
