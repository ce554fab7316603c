//! `drivebus ethercat serve`: a line of drive twins on an interface.

use super::EcatServeArgs;
use anyhow::Context;
use drivebus_ethercat::drive::{self, DriveLine};
use drivebus_ethercat::{Clock, server};
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Serves until SIGINT or SIGTERM.
pub async fn run(a: &EcatServeArgs) -> anyhow::Result<()> {
    let mut line = DriveLine::new();
    for d in &a.drives {
        line = line.drive(drive::profile(d)?);
    }
    if let Some(dir) = &a.state_dir {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create --state-dir {}", dir.display()))?;
        line = line.state_dir(dir);
    }
    let host = line.host(Clock::real())?;
    if let Some(p) = &a.pcap {
        let f = std::fs::File::create(p).with_context(|| format!("cannot create --pcap {}", p.display()))?;
        host.set_capture(Box::new(std::io::BufWriter::new(f)), &a.iface)
            .with_context(|| format!("writing --pcap {}", p.display()))?;
    }
    // Bound before the ready line: a master's first frame is not lost.
    let sock = server::RawSocket::open(&a.iface).with_context(|| {
        format!(
            "cannot open an AF_PACKET socket on {} (needs root or CAP_NET_RAW, and the interface up)",
            a.iface
        )
    })?;
    let signals = Signals::install()?;
    let stop = Arc::new(AtomicBool::new(false));
    let served = {
        let (stop, host) = (stop.clone(), host.clone());
        std::thread::spawn(move || server::serve_socket(&sock, &host, &stop))
    };
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "drivebus ethercat serve: ready on {} (drives {})", a.iface, a.drives.join(" "))?;
        out.flush()?;
    }
    signals.wait().await?;
    stop.store(true, Ordering::Release);
    let stats = served.join().map_err(|_| anyhow::anyhow!("the server thread panicked"))?;
    host.stop_capture().context("flushing --pcap")?;
    let stats = stats.with_context(|| format!("serving on {}", a.iface))?;
    tracing::info!(frames = stats.frames, ignored = stats.ignored, "stopped");
    Ok(())
}

/// SIGINT and SIGTERM, installed before the ready line so a signal right
/// after it ends in a clean exit 0.
struct Signals {
    term: tokio::signal::unix::Signal,
    int: tokio::signal::unix::Signal,
}

impl Signals {
    fn install() -> anyhow::Result<Signals> {
        use tokio::signal::unix::{SignalKind, signal};
        Ok(Signals {
            term: signal(SignalKind::terminate()).context("installing the SIGTERM handler")?,
            int: signal(SignalKind::interrupt()).context("installing the SIGINT handler")?,
        })
    }

    async fn wait(mut self) -> anyhow::Result<()> {
        tokio::select! {
            _ = self.term.recv() => {}
            _ = self.int.recv() => {}
        }
        Ok(())
    }
}
