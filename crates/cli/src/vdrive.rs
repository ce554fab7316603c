//! Virtual drives: a personality built by `drivebus_personality` (its EDS
//! as the dictionary of a CiA 301 node, the CiA 402 drive on it, the
//! manufacturer's behaviour), hosted in real time by
//! `drivebus_transport::host` like any other device.

use std::path::Path;

use anyhow::{Context, anyhow};
use drivebus_node::{MemoryStorage, Storage};
use drivebus_personality::build::BuildOptions;
use drivebus_personality::machine::{Machine, MachineFile};
use drivebus_personality::{PersonalityDevice, Profile};
use tokio::task::JoinHandle;

use crate::control::{NodeHost, PowerOn, ServedNode};
use crate::vdevice::DeviceSpec;

/// A drive to host, as given on the command line (`akd:1`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DriveSpec {
    /// The personality.
    pub profile: Profile,
    /// Node-ID 1..=127.
    pub node: u8,
}

impl DriveSpec {
    /// Parses every `PROFILE:NODE` and refuses two drives with one
    /// node-ID; the error says which part is wrong
    /// ([`drivebus_personality::drive_specs`]).
    pub fn parse_all(specs: &[String]) -> anyhow::Result<Vec<DriveSpec>> {
        let specs = drivebus_personality::drive_specs(specs).map_err(anyhow::Error::msg)?;
        Ok(specs.into_iter().map(|(profile, node)| DriveSpec { profile, node }).collect())
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

/// The machines around the hosted drives: each profile's default machine
/// ([`Machine::default_for`]), changed per node by `--machine FILE`.
pub struct Machines {
    file: Option<(MachineFile, std::path::PathBuf)>,
}

impl Machines {
    /// Reads `path` (when given) for the drives `specs`: a malformed file,
    /// a table for a node that is not hosted, or a machine that does not
    /// make sense is an error naming the file, line and column.
    pub fn load(path: Option<&Path>, specs: &[DriveSpec]) -> anyhow::Result<Machines> {
        Machines::load_with_devices(path, specs, &[])
    }

    /// [`Machines::load`] for drives and devices from a file
    /// (`devices`: their node-IDs, whose tables take only `io` and digital
    /// and analog `inputs`).
    pub fn load_with_devices(
        path: Option<&Path>,
        specs: &[DriveSpec],
        devices: &[u8],
    ) -> anyhow::Result<Machines> {
        let Some(path) = path else {
            return Ok(Machines { file: None });
        };
        let at = |e: drivebus_personality::machine::MachineFileError| anyhow!("{}: {e}", path.display());
        let file = MachineFile::read(path).map_err(at)?;
        let mut nodes: Vec<u8> = specs.iter().map(|s| s.node).collect();
        nodes.extend_from_slice(devices);
        file.check_nodes(&nodes).map_err(at)?;
        for s in specs {
            file.machine_for(s.profile, s.node).map_err(at)?;
        }
        for &n in devices {
            file.io_machine_for(n).map_err(at)?;
        }
        Ok(Machines { file: Some((file, path.to_owned())) })
    }

    /// The machine of device node `node` (`None`: no machine file, all
    /// inputs low).
    pub fn io_machine_for(&self, node: u8) -> anyhow::Result<Option<Machine>> {
        self.file
            .as_ref()
            .map(|(f, path)| f.io_machine_for(node).map_err(|e| anyhow!("{}: {e}", path.display())))
            .transpose()
    }

    /// The machine of `spec`.
    pub fn machine_for(&self, spec: DriveSpec) -> anyhow::Result<Machine> {
        match &self.file {
            None => Ok(Machine::default_for(spec.profile)),
            Some((f, path)) => {
                f.machine_for(spec.profile, spec.node).map_err(|e| anyhow!("{}: {e}", path.display()))
            }
        }
    }
}

/// Builds the drive `spec` on `machine` with `options` (e.g. the EDS at
/// 1021h); parameters stored with 1010h go to
/// `state_dir/<profile>-<node>/` when given, else to memory.
pub fn build(
    spec: DriveSpec,
    state_dir: Option<&Path>,
    options: BuildOptions,
    machine: &Machine,
) -> anyhow::Result<PersonalityDevice> {
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
    drivebus_personality::build_on(spec.profile, spec.node, storage, options, machine)
        .map_err(|e| anyhow!("cannot build {spec}: {e}"))
}

/// A served node-ID and its slot.
pub type NodeSlot = (u8, ServedNode);

/// Builds and starts `specs` and `devices` on `hub`, each as its own
/// participant, each on its machine (`--machine FILE` or the profile's
/// default). Every file and machine is checked before anything starts.
/// Returns each node's slot (its host and how to power it on again, for
/// `serve --control`) and what each device is (for the ready line).
pub fn host_on_hub(
    specs: &[DriveSpec],
    devices: &[DeviceSpec],
    hub: &drivebus_transport::Hub,
    state_dir: Option<&Path>,
    options: BuildOptions,
    machine_file: Option<&Path>,
) -> anyhow::Result<(Vec<NodeSlot>, Vec<String>)> {
    let nodes: Vec<u8> = devices.iter().map(|d| d.node).collect();
    let machines = Machines::load_with_devices(machine_file, specs, &nodes)?;
    let dir = state_dir.map(Path::to_owned);
    let mut built: Vec<(u8, NodeHost, PowerOn)> = Vec::new();
    let mut drives = Vec::new();
    for s in specs {
        let m = machines.machine_for(*s)?;
        drives.push((*s, build(*s, state_dir, options, &m)?, m));
    }
    let mut described = Vec::new();
    let mut files = Vec::new();
    let eds_options = drivebus_node::EdsOptions { eds_object: options.eds_object };
    for d in devices {
        let m = machines.io_machine_for(d.node)?;
        let dev = d.build(state_dir, eds_options, m.as_ref())?;
        described.push(d.describe(&dev));
        files.push((d.clone(), dev, m));
    }
    for (s, dev, m) in drives {
        let dir = dir.clone();
        let again: PowerOn =
            Box::new(move |hub| Ok(NodeHost::drive(build(s, dir.as_deref(), options, &m)?, hub)));
        built.push((s.node, NodeHost::drive(dev, hub), again));
    }
    for (d, dev, m) in files {
        let (node, dir) = (d.node, dir.clone());
        let again: PowerOn =
            Box::new(move |hub| Ok(NodeHost::device(d.build(dir.as_deref(), eds_options, m.as_ref())?, hub)));
        built.push((node, NodeHost::device(dev, hub), again));
    }
    let slots =
        built.into_iter().map(|(n, host, power_on)| (n, ServedNode { host: Some(host), power_on })).collect();
    Ok((slots, described))
}

/// [`host_on_hub`], keeping only the tasks: returns the hosts and what each
/// device is (for the ready line).
pub fn spawn_on_hub(
    specs: &[DriveSpec],
    devices: &[DeviceSpec],
    hub: &drivebus_transport::Hub,
    state_dir: Option<&Path>,
    options: BuildOptions,
    machine_file: Option<&Path>,
) -> anyhow::Result<(Vec<JoinHandle<()>>, Vec<String>)> {
    let (slots, described) = host_on_hub(specs, devices, hub, state_dir, options, machine_file)?;
    let tasks = slots.into_iter().filter_map(|(_, s)| s.host).map(NodeHost::into_join_handle).collect();
    Ok((tasks, described))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drive_specs() {
        let one = |s: &str| DriveSpec::parse_all(&[s.to_owned()]).map(|v| v[0]);
        assert_eq!(one("akd:1").unwrap(), DriveSpec { profile: Profile::Akd, node: 1 });
        assert_eq!(one("SSD-630:127").unwrap().profile, Profile::Ssd630);
        assert!(one("akd:0").is_err());
        assert!(one("x:1").unwrap_err().to_string().contains("profiles: kc1, akd"));
        let two = ["akd:1".to_owned(), "kc1:1".to_owned()];
        assert!(DriveSpec::parse_all(&two).unwrap_err().to_string().contains("already taken by akd:1"));
        assert_eq!(one("dds6:2").unwrap().dir_name(), "dds6-2");
    }
}
