//! Virtual drives: a personality built by `drivebus_personality` (its EDS
//! as the dictionary of a CiA 301 node, the CiA 402 drive on it, the
//! manufacturer's behaviour), and a real-time host that runs one on an
//! async bus.

use std::path::Path;

use anyhow::{Context, anyhow, bail};
use drivebus_can::{Frame, Instant, TxSink};
use drivebus_node::{MemoryStorage, Storage};
use drivebus_personality::build::BuildOptions;
use drivebus_personality::{PersonalityNode, Profile};
use drivebus_transport::CanBus;
use tokio::task::JoinHandle;

/// A drive to host, as given on the command line (`akd:1`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DriveSpec {
    /// The personality.
    pub profile: Profile,
    /// Node-ID 1..=127.
    pub node: u8,
}

impl DriveSpec {
    /// Parses `PROFILE:NODE`; the error says which part is wrong.
    pub fn parse(s: &str) -> anyhow::Result<DriveSpec> {
        let names = Profile::all().iter().map(|p| p.name()).collect::<Vec<_>>().join(", ");
        let Some((p, n)) = s.split_once(':') else {
            bail!("bad drive `{s}`: expected PROFILE:NODE, e.g. akd:1 (profiles: {names})");
        };
        let Some(profile) = Profile::from_name(p) else {
            bail!("bad drive `{s}`: unknown profile `{p}` (profiles: {names})");
        };
        let node = match n.trim().parse::<u32>() {
            Ok(v @ 1..=127) => v as u8,
            _ => bail!("bad drive `{s}`: node-ID `{n}` is not in 1..127"),
        };
        Ok(DriveSpec { profile, node })
    }

    /// Parses every spec and refuses two drives with one node-ID.
    pub fn parse_all(specs: &[String]) -> anyhow::Result<Vec<DriveSpec>> {
        let mut out: Vec<DriveSpec> = Vec::new();
        for s in specs {
            let d = DriveSpec::parse(s)?;
            if let Some(o) = out.iter().find(|o| o.node == d.node) {
                bail!("bad drive `{s}`: node-ID {} is already taken by {}:{}", d.node, o.profile, o.node);
            }
            out.push(d);
        }
        Ok(out)
    }

    /// `akd-1`: the directory name under `--state-dir`.
    pub fn dir_name(&self) -> String {
        format!("{}-{}", self.profile, self.node)
    }
}

impl std::fmt::Display for DriveSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.profile, self.node)
    }
}

/// A virtual drive: the personality's node (EDS dictionary, CiA 402
/// drive, manufacturer behaviour) from `drivebus_personality::build`.
pub struct VDrive {
    /// The drive station (node, drive, behaviour).
    pub pn: PersonalityNode,
    /// Which personality.
    pub spec: DriveSpec,
}

impl VDrive {
    /// Builds the drive `spec` with `options` (e.g. the EDS at 1021h);
    /// parameters stored with 1010h go to `state_dir/<profile>-<node>/`
    /// when given, else to memory.
    pub fn build(spec: DriveSpec, state_dir: Option<&Path>, options: BuildOptions) -> anyhow::Result<VDrive> {
        let storage: Box<dyn Storage + Send> = match state_dir {
            Some(dir) => {
                let d = dir.join(spec.dir_name());
                Box::new(
                    drivebus_node::FileStorage::new(&d)
                        .with_context(|| format!("state directory {}", d.display()))?,
                )
            }
            None => Box::new(MemoryStorage::new()),
        };
        let pn = spec
            .profile
            .build_with_options(spec.node, storage, options)
            .map_err(|e| anyhow!("cannot build {spec}: {e}"))?;
        Ok(VDrive { pn, spec })
    }

    /// Boot: boot-up message, pre-operational (the first poll boots).
    pub fn boot(&mut self, now: Instant, out: &mut impl TxSink) {
        self.pn.poll_into(now, out);
    }

    /// A frame from the bus.
    pub fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut impl TxSink) {
        self.pn.handle_frame_into(frame, now, out);
    }

    /// Due work; the next deadline.
    pub fn poll(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        self.pn.poll_into(now, out)
    }
}

/// Runs `vd` in real time on `bus` until the bus closes or the task is
/// aborted: boots it, then handles frames and deadlines as they come.
pub fn spawn_realtime(mut vd: VDrive, mut bus: CanBus) -> JoinHandle<()> {
    tokio::spawn(async move {
        let start = tokio::time::Instant::now();
        let now = || Instant::from_nanos(u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX));
        let at = |t: Instant| {
            start
                + std::time::Duration::from_nanos(t.as_nanos())
                    .min(std::time::Duration::from_secs(86_400 * 365))
        };
        let mut out: Vec<Frame> = Vec::new();
        vd.boot(now(), &mut out);
        loop {
            let next = vd.poll(now(), &mut out);
            for f in out.drain(..) {
                if let Err(e) = bus.send(f).await {
                    tracing::warn!(drive = %vd.spec, error = %e, "bus send failed, drive stops");
                    return;
                }
            }
            let deadline =
                next.map_or_else(|| tokio::time::Instant::now() + std::time::Duration::from_secs(3600), at);
            tokio::select! {
                r = bus.recv() => match r {
                    Ok(f) => vd.handle_frame(&f, now(), &mut out),
                    Err(e) => {
                        tracing::info!(drive = %vd.spec, error = %e, "bus closed, drive stops");
                        return;
                    }
                },
                () = tokio::time::sleep_until(deadline) => {}
            }
        }
    })
}

/// Builds and starts `specs` on `hub`, each as its own participant.
pub fn spawn_on_hub(
    specs: &[DriveSpec],
    hub: &drivebus_transport::Hub,
    state_dir: Option<&Path>,
    options: BuildOptions,
) -> anyhow::Result<Vec<JoinHandle<()>>> {
    let mut drives = Vec::new();
    for s in specs {
        drives.push(VDrive::build(*s, state_dir, options)?);
    }
    Ok(drives.into_iter().map(|d| spawn_realtime(d, hub.attach())).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drive_specs() {
        assert_eq!(DriveSpec::parse("akd:1").unwrap(), DriveSpec { profile: Profile::Akd, node: 1 });
        assert_eq!(DriveSpec::parse("SSD-630:127").unwrap().profile, Profile::Ssd630);
        assert!(DriveSpec::parse("akd:0").is_err());
        assert!(DriveSpec::parse("x:1").unwrap_err().to_string().contains("profiles: kc1, akd"));
        let two = ["akd:1".to_owned(), "kc1:1".to_owned()];
        assert!(DriveSpec::parse_all(&two).unwrap_err().to_string().contains("already taken by akd:1"));
        assert_eq!(DriveSpec::parse("dds6:2").unwrap().dir_name(), "dds6-2");
    }
}
