//! `drivebus slcan-pty`: virtual drives behind an slcan adapter emulated
//! on a pseudo-terminal (hosting through `drivebus_transport::host`).

use std::time::Duration;

use anyhow::{Context, bail};

use crate::args::{Global, SlcanPtyArgs};
use crate::vdevice::DeviceSpec;
use crate::vdrive::{DriveSpec, spawn_on_hub};

/// `drivebus slcan-pty`.
pub async fn run(g: &Global, a: &SlcanPtyArgs) -> anyhow::Result<()> {
    #[cfg(unix)]
    {
        use std::io::Write;
        let specs = DriveSpec::parse_all(&a.drives)?;
        let devices = DeviceSpec::parse_all(&a.devices, &specs.iter().map(|s| s.node).collect::<Vec<_>>())?;
        let hub = match drivebus_transport::BusUrl::parse(&g.bus)? {
            drivebus_transport::BusUrl::Virtual { name } => drivebus_transport::hub::virtual_hub(&name),
            _ => bail!("slcan-pty runs on the in-process virtual bus: use --bus virtual (not `{}`)", g.bus),
        };
        crate::fault::install(&hub, &a.faults)?;
        let (_drives, _) =
            spawn_on_hub(&specs, &devices, &hub, None, Default::default(), g.machine.as_deref())?;
        let pty = drivebus_transport::slcan::SlcanPty::spawn(hub.attach())
            .context("cannot open a pseudo-terminal")?;
        {
            let mut out = std::io::stdout().lock();
            writeln!(out, "slcan-pty {}", pty.path().display())?;
            out.flush()?;
        }
        match a.seconds {
            Some(s) => {
                tokio::select! {
                    () = tokio::time::sleep(Duration::from_secs_f64(s.max(0.0))) => {}
                    r = crate::serve::wait_for_signal() => r?,
                }
            }
            None => crate::serve::wait_for_signal().await?,
        }
        for d in _drives {
            d.abort();
        }
        Ok(())
    }
    #[cfg(not(unix))]
    {
        let _ = (g, a);
        bail!("slcan-pty needs a Unix pseudo-terminal")
    }
}
