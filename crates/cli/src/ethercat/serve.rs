//! `drivebus ethercat serve`: a line of drive twins and described devices
//! (SII images, ESI files) on an interface.

use super::{EcatServeArgs, LineSlave};
use anyhow::Context;
use drivebus_ethercat::described::{self, Member};
use drivebus_ethercat::{Clock, Host, drive, server};
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Serves until SIGINT or SIGTERM.
pub async fn run(a: &EcatServeArgs) -> anyhow::Result<()> {
    let members = members(&a.line.slaves)?;
    let control_addr = a.control.as_deref().map(crate::control::Addr::parse).transpose()?;
    if let Some(dir) = &a.state_dir {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create --state-dir {}", dir.display()))?;
    }
    let devices = described::devices(&members, a.state_dir.as_deref()).map_err(anyhow::Error::msg)?;
    let host = Host::line(devices, Clock::real());
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
    let control_task = match &control_addr {
        Some(addr) => {
            let control = Arc::new(crate::control::Control::ethercat(host.clone()));
            Some(crate::control::listen(addr, control).await?)
        }
        None => None,
    };
    let http = match &a.http {
        Some(addr) => Some(super::http::start(host.clone(), addr).await?),
        None => None,
    };
    // Installed before the ready line so a signal right after it ends in a
    // clean exit 0.
    let signals = crate::serve::Signals::install()?;
    let stop = Arc::new(AtomicBool::new(false));
    let served = {
        let (stop, host) = (stop.clone(), host.clone());
        std::thread::spawn(move || server::serve_socket(&sock, &host, &stop))
    };
    {
        let mut out = std::io::stdout().lock();
        let control =
            control_task.as_ref().map_or_else(String::new, |(_, addr)| format!("; control on {addr}"));
        let line = names(&members).join(" ");
        let page = http.as_ref().map_or_else(String::new, |h| {
            let (addr, q) = (h.addr, h.token.as_ref().map_or_else(String::new, |t| format!("?token={t}")));
            format!("; page on http://{addr}/{q}; state on http://{addr}/api/ethercat{q}")
        });
        writeln!(out, "drivebus ethercat serve: ready on {} (line {line}){control}{page}", a.iface)?;
        out.flush()?;
    }
    signals.wait().await?;
    if let Some(h) = http {
        h.task.abort();
    }
    if let Some((task, addr)) = control_task {
        task.abort();
        if let crate::control::Addr::Unix(p) = addr {
            let _ = std::fs::remove_file(p);
        }
    }
    stop.store(true, Ordering::Release);
    let stats = served.join().map_err(|_| anyhow::anyhow!("the server thread panicked"))?;
    host.stop_capture().context("flushing --pcap")?;
    let stats = stats.with_context(|| format!("serving on {}", a.iface))?;
    tracing::info!(frames = stats.frames, ignored = stats.ignored, "stopped");
    Ok(())
}

/// The line's members, files read and checked before anything is served.
fn members(slaves: &[LineSlave]) -> anyhow::Result<Vec<Member>> {
    slaves
        .iter()
        .map(|s| match s {
            LineSlave::Drive(p) => Ok(Member::Drive(drive::profile(p)?)),
            LineSlave::Device(f) => Ok(Member::Device(Box::new(described::load(f)?))),
        })
        .collect()
}

/// What the ready line lists: profiles and device names in line order.
fn names(members: &[Member]) -> Vec<String> {
    members
        .iter()
        .map(|m| match m {
            Member::Drive(p) => p.to_string(),
            Member::Device(d) => d.type_name().to_owned(),
        })
        .collect()
}
