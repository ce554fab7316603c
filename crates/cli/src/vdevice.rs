//! Devices from an EDS or DCF (`serve --device FILE:NODE`, `slcan-pty
//! --device`, `--sim FILE:NODE`): the CiA 301 node the file describes, a
//! CiA 401 I/O module when its 1000h says so
//! (`drivebus_personality::build::build_device`), hosted like the drives.

use std::path::{Path, PathBuf};

use anyhow::{Context, anyhow, bail};
use drivebus_eds::Eds;
use drivebus_node::{EdsOptions, MemoryStorage, Storage};
use drivebus_personality::build::{DeviceApp, EdsDevice};

/// A device to host, as given on the command line (`io16.eds:3`), its file
/// read and parsed.
#[derive(Clone, Debug)]
pub struct DeviceSpec {
    /// The file as given.
    pub path: PathBuf,
    /// Node-ID 1..=127.
    pub node: u8,
    /// The file's text (served at 1021h).
    pub text: String,
    /// The file, parsed.
    pub eds: Eds,
}

impl DeviceSpec {
    /// Whether a `--sim` argument names a file rather than a profile
    /// (`FILE.eds:NODE`, `FILE.dcf:NODE`).
    pub fn is_file_spec(s: &str) -> bool {
        let f = s.rsplit_once(':').map_or(s, |(f, _)| f).to_ascii_lowercase();
        let l = s.to_ascii_lowercase();
        f.ends_with(".eds") || f.ends_with(".dcf") || l.ends_with(".dcf")
    }

    /// Parses `FILE:NODE` (or `FILE` alone for a DCF whose
    /// `[DeviceComissioning]` gives its NodeID) and reads the file: a file
    /// that cannot be read or parsed is an error naming the file, the line
    /// and the cause.
    pub fn parse(s: &str) -> anyhow::Result<DeviceSpec> {
        let (f, node) = match s.rsplit_once(':') {
            Some((f, n)) if !n.is_empty() && n.trim().bytes().all(|b| b.is_ascii_digit()) => {
                match n.trim().parse::<u32>() {
                    Ok(v @ 1..=127) => (f, Some(v as u8)),
                    _ => bail!("bad device `{s}`: node-ID `{n}` is not in 1..127"),
                }
            }
            _ => (s, None),
        };
        let path = PathBuf::from(f);
        let bytes = std::fs::read(&path).with_context(|| format!("cannot read device file {f}"))?;
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let eds = crate::eds_cmd::parse_text(&text).map_err(|e| anyhow!("{f}: {e}"))?;
        let from_dcf = eds.commissioning.as_ref().map(|c| c.node_id).filter(|n| (1..=127).contains(n));
        let Some(node) = node.or(from_dcf) else {
            bail!(
                "bad device `{s}`: expected FILE:NODE, e.g. io16.eds:3 (an EDS or DCF; a DCF whose \
                 [DeviceComissioning] NodeID is 1..127 may leave NODE out)"
            );
        };
        Ok(DeviceSpec { path, node, text, eds })
    }

    /// Parses every spec; node-IDs must differ from each other and from
    /// `taken` (the drives').
    pub fn parse_all(specs: &[String], taken: &[u8]) -> anyhow::Result<Vec<DeviceSpec>> {
        let mut out: Vec<DeviceSpec> = Vec::new();
        for s in specs {
            let d = DeviceSpec::parse(s)?;
            if taken.contains(&d.node) || out.iter().any(|o| o.node == d.node) {
                bail!("bad device `{s}`: node-ID {} is already taken", d.node);
            }
            out.push(d);
        }
        Ok(out)
    }

    /// `io16-3`: the directory name under `--state-dir`.
    pub fn dir_name(&self) -> String {
        let stem =
            self.path.file_stem().map_or_else(|| "device".into(), |s| s.to_string_lossy().into_owned());
        format!("{stem}-{}", self.node)
    }

    /// Builds the device on the machine file's `[[node]]` table for its
    /// node (`io` and `[[node.inputs]]`), parameters under
    /// `state_dir/<file>-<node>/` when given. The file's values that do
    /// not fit (with their lines) are errors; what it leaves out is
    /// reported on stderr.
    pub fn build(
        &self,
        state_dir: Option<&Path>,
        options: EdsOptions,
        machine: Option<&drivebus_personality::machine::Machine>,
    ) -> anyhow::Result<EdsDevice> {
        let storage: Box<dyn Storage + Send> = match state_dir {
            Some(dir) => {
                let d = dir.join(self.dir_name());
                Box::new(
                    drivebus_node::FileStorage::new(&d)
                        .with_context(|| format!("state directory {}", d.display()))?,
                )
            }
            None => Box::new(MemoryStorage::new()),
        };
        let (dev, warnings) = drivebus_personality::build::build_device(
            &self.eds, &self.text, self.node, storage, options, machine,
        )
        .map_err(|e| anyhow!("{}: {e}", self.path.display()))?;
        for w in warnings {
            eprintln!("warning: {}: {w}", self.path.display());
        }
        Ok(dev)
    }

    /// What the device is, for the ready line: `io16.eds:3 (CiA 401)`.
    pub fn describe(&self, dev: &EdsDevice) -> String {
        let kind = if matches!(dev.app, DeviceApp::Io(_)) { " (CiA 401)" } else { "" };
        format!("{self}{kind}")
    }
}

impl std::fmt::Display for DeviceSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.path.display(), self.node)
    }
}
