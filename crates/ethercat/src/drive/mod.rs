//! CiA 402 drives as EtherCAT slaves: the personality's node, drive and
//! behaviour — the same dictionary and the same drive as on CAN — behind
//! an emulated ESC, with CoE (SDO, complete access, SDO Information,
//! emergencies) and FoE through `drivebus-coe`.
//!
//! ```
//! use drivebus_can::Instant;
//! use drivebus_ethercat::drive::DriveLine;
//! use drivebus_ethercat::Clock;
//! use drivebus_personality::Profile;
//!
//! // Two iPOS and a generic servo on one line, on simulated time.
//! let host = DriveLine::new()
//!     .drive(Profile::Ipos)
//!     .drive(Profile::Ipos)
//!     .drive(Profile::Generic)
//!     .host(Clock::simulated(Instant::ZERO))
//!     .unwrap();
//! let state = drivebus_ethercat::drive::with_drive(&host, 2, |d| d.app().esm()).unwrap();
//! assert_eq!(state, drivebus_coe::AlState::Init);
//! ```
//!
//! The path of a frame: the host ([`crate::Host`]) passes it through the
//! [`Segment`](drivebus_esc::segment::Segment); each slave's
//! [`Esc`] processes its datagrams; the slave firmware
//! ([`drivebus_esc::slave::Slave`]) runs the ESM, the mailbox and the
//! process data and calls [`DriveApp`]: a mailbox request goes to the
//! [`MailboxServer`], which reads and writes through `Node::read_object` /
//! `Node::write_object` (`access.rs`); outputs and inputs go through the
//! node's write path with the CAN PDO packer (`image.rs`); SYNC0 steps
//! the drive (`app.rs`); ESM states and AL errors reach the personality
//! (`drivebus_personality::ecat`).
//!
//! Identity: one [`drivebus_esi::SlaveDescription`] of the running
//! dictionary gives the SII image the ESC serves and the ESI file
//! ([`DriveSlaveExt::esi`]).

mod access;
mod app;
#[doc(hidden)]
pub mod fuzzing;
mod identity;
mod image;
mod sync;

pub use access::object_access;
pub use app::{DriveApp, DriveStats};
pub use identity::{describe, facts};
pub use image::Image;
pub use sync::interpolation_period;

use crate::Clock;
use crate::host::{BoxDevice, Host};
use drivebus_coe::{MailboxConfig, MailboxServer};
use drivebus_esc::sii::SiiImage;
use drivebus_esc::slave::{Slave, SlaveConfig};
use drivebus_esc::{ClockConfig, Esc, EscConfig};
use drivebus_esi::{CoeDetails, SlaveDescription};
use drivebus_node::{FileStorage, MemoryStorage, Storage};
use drivebus_od::Value;
use drivebus_personality::{BuildError, Profile, ecat};
use std::path::{Path, PathBuf};

/// A drive slave: the ESC with the drive's firmware.
pub type DriveSlave = Slave<DriveApp>;

/// Why a drive slave could not be made.
#[derive(Debug)]
pub enum DriveSlaveError {
    /// Not a profile that runs on EtherCAT (`ipos`, `generic`).
    Profile(String),
    /// The personality did not build.
    Build(BuildError),
    /// The state directory could not be used.
    State(PathBuf, std::io::Error),
    /// The SII mailbox sizes do not suit the CoE server.
    Mailbox(drivebus_coe::MailboxSizeError),
}

impl std::fmt::Display for DriveSlaveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DriveSlaveError::Profile(p) => write!(f, "{p}: not an EtherCAT drive (ipos or generic)"),
            DriveSlaveError::Build(e) => write!(f, "building the drive: {e}"),
            DriveSlaveError::State(d, e) => write!(f, "state directory {}: {e}", d.display()),
            DriveSlaveError::Mailbox(e) => write!(f, "mailbox: {e}"),
        }
    }
}

impl std::error::Error for DriveSlaveError {}

/// The profile named `name` if it runs on EtherCAT.
pub fn profile(name: &str) -> Result<Profile, DriveSlaveError> {
    Profile::from_name(name.trim())
        .filter(|p| ecat::facts(*p).is_some())
        .ok_or_else(|| DriveSlaveError::Profile(name.to_owned()))
}

/// One drive slave to make.
#[derive(Debug, Clone)]
pub struct DriveSlaveSpec {
    /// `ipos` or `generic`.
    pub profile: Profile,
    /// 1018h:04 and the SII serial number.
    pub serial: u32,
    /// Where its parameters (1010h stores) and FoE setup files live.
    pub state_dir: Option<PathBuf>,
    /// Its ESC's local clock (offset, drift).
    pub clock: ClockConfig,
    /// The CoE services it offers (SII CoE details and its mailbox
    /// server alike); `None`: the profile's (SDO Information, complete access).
    pub coe: Option<CoeDetails>,
}

impl DriveSlaveSpec {
    /// `profile` with serial number `serial`, no state directory.
    pub fn new(profile: Profile, serial: u32) -> DriveSlaveSpec {
        DriveSlaveSpec { profile, serial, state_dir: None, clock: ClockConfig::default(), coe: None }
    }
}

/// Makes one drive slave.
pub fn slave(spec: &DriveSlaveSpec) -> Result<DriveSlave, DriveSlaveError> {
    let facts =
        ecat::facts(spec.profile).ok_or_else(|| DriveSlaveError::Profile(spec.profile.to_string()))?;
    let storage: Box<dyn Storage + Send> = match &spec.state_dir {
        Some(d) => Box::new(FileStorage::new(d).map_err(|e| DriveSlaveError::State(d.clone(), e))?),
        None => Box::new(MemoryStorage::new()),
    };
    let mut dev = ecat::build(spec.profile, storage).map_err(DriveSlaveError::Build)?;
    drivebus_personality::build::set_default(dev.node.od_mut(), 0x1018, 4, &Value::U32(spec.serial));
    let mut desc = describe(spec.profile, dev.node.od());
    if let (Some(c), Some(m)) = (spec.coe, desc.mailbox.as_mut()) {
        m.coe = Some(c);
    }
    let (rx, tx) = mailbox_sizes(&desc);
    let mut cfg = MailboxConfig::with_sizes(rx, tx);
    if let Some(c) = desc.mailbox.as_ref().and_then(|m| m.coe) {
        (cfg.sdo_info, cfg.complete_access) = (c.sdo_info, c.complete_access);
    }
    let mbx = MailboxServer::new(cfg).map_err(DriveSlaveError::Mailbox)?;
    let files = ecat::files(spec.profile, spec.state_dir.as_ref().map(|d| d.join("foe")));
    let app = DriveApp::new(dev, spec.profile, facts, mbx, files);
    let esc = Esc::new(EscConfig { clock: spec.clock, ..EscConfig::with_sii(SiiImage::from(&desc)) });
    Ok(Slave::new(esc, app, SlaveConfig::default()))
}

fn mailbox_sizes(d: &SlaveDescription) -> (usize, usize) {
    use drivebus_esi::SmKind;
    let size = |k| d.sm(k).and_then(|(_, s)| s.default_size).map_or(0, usize::from);
    (size(SmKind::MBoxOut), size(SmKind::MBoxIn))
}

/// What a drive slave offers besides the [`Slave`] API.
pub trait DriveSlaveExt {
    /// The description of its running dictionary (the source of its SII).
    fn description(&self) -> SlaveDescription;
    /// Its ESI file (ETG.2000 XML).
    fn esi(&self) -> String;
}

impl DriveSlaveExt for DriveSlave {
    fn description(&self) -> SlaveDescription {
        describe(self.app().profile(), self.app().device().node.od())
    }
    fn esi(&self) -> String {
        drivebus_esi::write(&self.description())
    }
}

/// A line of drives, in the order given: the one way to build a segment
/// of drives, for `drivebus ethercat serve`, the demo and tests.
#[derive(Debug, Clone, Default)]
pub struct DriveLine {
    profiles: Vec<Profile>,
    state_dir: Option<PathBuf>,
}

impl DriveLine {
    /// An empty line.
    pub fn new() -> DriveLine {
        DriveLine::default()
    }

    /// Adds a drive at the end of the line.
    pub fn drive(mut self, profile: Profile) -> DriveLine {
        self.profiles.push(profile);
        self
    }

    /// Keeps every drive's state under `dir`, one directory per slave
    /// ([`DriveLine::slave_dir`]), as `drivebus serve --state-dir` does.
    pub fn state_dir(mut self, dir: impl Into<PathBuf>) -> DriveLine {
        self.state_dir = Some(dir.into());
        self
    }

    /// The directory of the slave at `position` (0-based) under `dir`:
    /// `ecat-<position + 1>-<profile>`.
    pub fn slave_dir(dir: &Path, position: usize, profile: Profile) -> PathBuf {
        dir.join(format!("ecat-{}-{profile}", position + 1))
    }

    /// The slaves to make: serial numbers are the 1-based positions.
    pub fn specs(&self) -> Vec<DriveSlaveSpec> {
        self.profiles
            .iter()
            .enumerate()
            .map(|(i, &p)| DriveSlaveSpec {
                state_dir: self.state_dir.as_deref().map(|d| Self::slave_dir(d, i, p)),
                ..DriveSlaveSpec::new(p, i as u32 + 1)
            })
            .collect()
    }

    /// The slaves as boxed devices for a [`Host`].
    pub fn devices(&self) -> Result<Vec<BoxDevice>, DriveSlaveError> {
        self.specs().iter().map(|s| slave(s).map(|d| Box::new(d) as BoxDevice)).collect()
    }

    /// The line hosted on `clock` (simulated for deterministic tests, real
    /// for a socket server).
    pub fn host(&self, clock: Clock) -> Result<Host, DriveSlaveError> {
        Ok(Host::line(self.devices()?, clock))
    }
}

/// Runs `f` on the drive slave at `position` of `host`'s segment; `None`
/// if there is none there.
pub fn with_drive<R>(host: &Host, position: usize, f: impl FnOnce(&mut DriveSlave) -> R) -> Option<R> {
    host.with_segment(|s| {
        let d = s.device_mut(position)?.as_any_mut()?.downcast_mut::<DriveSlave>()?;
        Some(f(d))
    })
}
