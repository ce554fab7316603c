//! CiA 402 drive handle: the state machine walk, modes, profile position,
//! homing and SYNC-aligned cyclic streaming, over PDO when mapped and SDO
//! otherwise.
//!
//! [`Master::drive`] reads the node's TPDO/RPDO 1..4 configuration once.
//! Objects mapped into a valid TPDO are read from the latest received PDO
//! (decoded in the master's receive task; unregistered with the handle);
//! everything else is read by SDO. Objects mapped into a valid RPDO are
//! written by sending the whole RPDO from a shadow image (initialised by
//! SDO reads) while the node is known to be Operational (its heartbeat
//! says so, so enable 1017h); otherwise by SDO.

use std::collections::HashMap;
use std::fmt;
use std::sync::{Arc, Mutex};
use std::time::Duration;

pub use drivebus_cia402::codes::ModeNotShown;
use drivebus_cia402::codes::{EnableStep, State};
use drivebus_nmt::RemoteState;
use tokio::sync::Notify;

use crate::master::Master;

mod motion;
mod outcome;

use crate::pdo::{PdoDir, PdoMapEntry};
use crate::sdo::{SdoError, SdoHandle};
pub use motion::{MotionLimits, StopAction, StopReport, human_secs};
pub use outcome::{
    DI_HOME_SWITCH, DI_INTERLOCK, DI_NEGATIVE_LIMIT, DI_POSITIVE_LIMIT, DriveFlags, MotionEnd, MotionReport,
};

/// Controlword 6040h.
pub const CONTROLWORD: u16 = 0x6040;
/// Statusword 6041h.
pub const STATUSWORD: u16 = 0x6041;
/// Modes of operation 6060h.
pub const MODES_OF_OPERATION: u16 = 0x6060;
/// Modes of operation display 6061h.
pub const MODES_DISPLAY: u16 = 0x6061;

/// Controlword (6040h) commands and bits (`drivebus_cia402::codes::cw`).
pub use drivebus_cia402::codes::cw;
/// Modes of operation (6060h) values (`drivebus_cia402::codes::mode`).
pub use drivebus_cia402::codes::mode;
/// Statusword (6041h) bits (`drivebus_cia402::codes::sw`).
pub use drivebus_cia402::codes::sw;

/// The name of a mode of operation (6060h/6061h), CiA 402-2 §6.3.2.
pub fn mode_name(m: i8) -> &'static str {
    if m == 0 { "no mode" } else { mode::name(m) }
}

/// CiA 402 power drive system states, decoded by the state table of
/// `drivebus_cia402::state_machine` (CiA 402-2 §6.2.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DriveState {
    /// Not ready to switch on.
    NotReadyToSwitchOn,
    /// Switch on disabled.
    SwitchOnDisabled,
    /// Ready to switch on.
    ReadyToSwitchOn,
    /// Switched on.
    SwitchedOn,
    /// Operation enabled.
    OperationEnabled,
    /// Quick stop active.
    QuickStopActive,
    /// Fault reaction active.
    FaultReactionActive,
    /// Fault.
    Fault,
    /// A pattern the table does not define.
    Unknown,
}

impl From<State> for DriveState {
    fn from(s: State) -> Self {
        match s {
            State::NotReadyToSwitchOn => DriveState::NotReadyToSwitchOn,
            State::SwitchOnDisabled => DriveState::SwitchOnDisabled,
            State::ReadyToSwitchOn => DriveState::ReadyToSwitchOn,
            State::SwitchedOn => DriveState::SwitchedOn,
            State::OperationEnabled => DriveState::OperationEnabled,
            State::QuickStopActive => DriveState::QuickStopActive,
            State::FaultReactionActive => DriveState::FaultReactionActive,
            State::Fault => DriveState::Fault,
        }
    }
}

impl DriveState {
    /// Decodes the state bits of a statusword.
    pub fn from_statusword(sw: u16) -> DriveState {
        State::from_statusword(sw).map_or(DriveState::Unknown, DriveState::from)
    }

    /// The state's name as CiA 402 writes it, in lower case.
    pub fn name(self) -> &'static str {
        match self {
            DriveState::NotReadyToSwitchOn => "not ready to switch on",
            DriveState::SwitchOnDisabled => "switch on disabled",
            DriveState::ReadyToSwitchOn => "ready to switch on",
            DriveState::SwitchedOn => "switched on",
            DriveState::OperationEnabled => "operation enabled",
            DriveState::QuickStopActive => "quick stop active",
            DriveState::FaultReactionActive => "fault reaction active",
            DriveState::Fault => "fault",
            DriveState::Unknown => "unknown",
        }
    }
}

impl fmt::Display for DriveState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Profile parameters for [`RemoteDrive::move_to`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MoveProfile {
    /// 6081h profile velocity.
    pub velocity: u32,
    /// 6083h profile acceleration.
    pub acceleration: u32,
    /// 6084h profile deceleration.
    pub deceleration: u32,
}

/// Why a drive operation failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DriveError {
    /// An SDO transfer failed.
    Sdo(SdoError),
    /// The awaited statusword / mode did not come in time.
    Timeout {
        /// What was awaited.
        waiting_for: &'static str,
        /// The last statusword read.
        statusword: u16,
    },
    /// The drive is (or went) into Fault.
    Fault {
        /// The statusword.
        statusword: u16,
    },
    /// A move or homing ended anywhere but its target: a limit switch,
    /// a software limit, a following or homing error, a fault, a quick
    /// stop, a halt. The report says where and why.
    Stopped(Box<MotionReport>),
    /// 6061h did not come to show the mode written to 6060h.
    Mode(ModeNotShown),
    /// Streaming needs the master's SYNC producer ([`Master::start_sync`]).
    NoSync,
    /// The bus failed.
    Transport(String),
}

impl fmt::Display for DriveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DriveError::Sdo(e) => write!(f, "{e}"),
            DriveError::Timeout { waiting_for, statusword } => {
                write!(f, "timeout waiting for {waiting_for} (statusword {statusword:04X}h)")
            }
            DriveError::Fault { statusword } => write!(f, "drive fault (statusword {statusword:04X}h)"),
            DriveError::Stopped(r) => {
                write!(
                    f,
                    "{r} (statusword {:04X}h, {})",
                    r.statusword,
                    DriveState::from_statusword(r.statusword)
                )
            }
            DriveError::Mode(e) => write!(f, "{e}"),
            DriveError::NoSync => f.write_str("no SYNC producer running"),
            DriveError::Transport(s) => write!(f, "bus error: {s}"),
        }
    }
}

impl std::error::Error for DriveError {}

impl From<SdoError> for DriveError {
    fn from(e: SdoError) -> Self {
        DriveError::Sdo(e)
    }
}

/// Where a drive is while a command waits for it (see [`RemoteDrive::on_progress`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MotionProgress {
    /// What the command waits for.
    pub waiting_for: &'static str,
    /// The statusword.
    pub statusword: u16,
    /// Its state.
    pub state: DriveState,
    /// Position actual value 6064h.
    pub position: Option<i32>,
    /// Velocity actual value 606Ch.
    pub velocity: Option<i32>,
}

/// A progress callback.
pub type ProgressFn = Arc<dyn Fn(&MotionProgress) + Send + Sync>;

struct Rpdo {
    cob: u16,
    mapping: Vec<PdoMapEntry>,
    image: Mutex<[u8; 8]>,
    len: usize,
    /// Transmission type 0..240: the drive applies it at the next SYNC.
    synchronous: bool,
}

/// Byte offset of `index`/`sub` in a byte-aligned mapping.
fn offset_of(mapping: &[PdoMapEntry], index: u16, sub: u8) -> Option<(usize, usize)> {
    drivebus_pdo::find_mapped(mapping.iter().copied(), index, sub)?.bytes()
}

type Latest = Arc<Mutex<HashMap<(u16, u8), Vec<u8>>>>;

/// A CiA 402 drive on the bus; from [`Master::drive`].
pub struct RemoteDrive {
    master: Master,
    node: u8,
    sdo: SdoHandle,
    tpdo_objects: Vec<(u16, u8)>,
    latest: Latest,
    updated: Arc<Notify>,
    rpdos: Vec<Rpdo>,
    sinks: Vec<u64>,
    timeout: Duration,
    poll: Duration,
    progress: Option<ProgressFn>,
    progress_every: Duration,
    last_progress: Mutex<Option<drivebus_can::Instant>>,
    /// A mode written to 6060h that 6061h has not been seen to show.
    mode_pending: Mutex<Option<i8>>,
}

impl Drop for RemoteDrive {
    fn drop(&mut self) {
        for id in &self.sinks {
            self.master.remove_pdo_sink(*id);
        }
    }
}

impl fmt::Debug for RemoteDrive {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("RemoteDrive")
            .field("node", &self.node)
            .field("tpdo_objects", &self.tpdo_objects)
            .field("rpdos", &self.rpdos.iter().map(|r| (r.cob, r.mapping.clone())).collect::<Vec<_>>())
            .finish_non_exhaustive()
    }
}

impl Master {
    /// A CiA 402 drive handle for `node`: reads its PDO 1..4 configuration
    /// (PDOs that cannot be read are treated as absent).
    pub async fn drive(&self, node: u8) -> Result<RemoteDrive, SdoError> {
        let sdo = self.sdo(node);
        let latest: Latest = Arc::default();
        let updated = Arc::new(Notify::new());
        let mut sinks = Vec::new();
        let mut tpdo_objects = Vec::new();
        let mut rpdos = Vec::new();
        for num in 1..=4 {
            let Ok(rec) = self.read_pdo(node, PdoDir::Tx, num).await else { break };
            if !rec.valid() || rec.mapping.is_empty() {
                continue;
            }
            let mapping: Vec<PdoMapEntry> = rec.mapping.clone();
            tpdo_objects.extend(mapping.iter().filter(|m| m.index >= 0x1000).map(|m| (m.index, m.sub)));
            let (latest, updated) = (latest.clone(), updated.clone());
            // Decoded in the receive task, in frame order: once an SDO
            // answer is in, every TPDO sent before it is in `latest`.
            let sink = move |f: &drivebus_can::Frame, _: drivebus_can::Instant| {
                let mut l = latest.lock().unwrap_or_else(|e| e.into_inner());
                for m in mapping.iter().filter(|m| m.index >= 0x1000) {
                    if let Some((off, len)) = offset_of(&mapping, m.index, m.sub)
                        && let Some(b) = f.data().get(off..off + len)
                    {
                        l.insert((m.index, m.sub), b.to_vec());
                    }
                }
                drop(l);
                updated.notify_waiters();
            };
            sinks.push(self.add_pdo_sink(rec.can_id(), Arc::new(sink)));
        }
        for num in 1..=4 {
            let Ok(rec) = self.read_pdo(node, PdoDir::Rx, num).await else { break };
            if !rec.valid() || rec.mapping.is_empty() || rec.len_bytes() > 8 {
                continue;
            }
            let mut image = [0u8; 8];
            for m in rec.mapping.iter().filter(|m| m.index >= 0x1000) {
                if let (Some((off, len)), Ok(v)) =
                    (offset_of(&rec.mapping, m.index, m.sub), sdo.upload(m.index, m.sub).await)
                    && v.len() >= len
                {
                    image[off..off + len].copy_from_slice(&v[..len]);
                }
            }
            rpdos.push(Rpdo {
                cob: rec.can_id(),
                len: rec.len_bytes(),
                synchronous: rec.transmission_type <= 240,
                mapping: rec.mapping,
                image: Mutex::new(image),
            });
        }
        Ok(RemoteDrive {
            master: self.clone(),
            node,
            sdo,
            tpdo_objects,
            latest,
            updated,
            rpdos,
            sinks,
            timeout: Duration::from_secs(2),
            poll: Duration::from_millis(10),
            progress: None,
            progress_every: Duration::from_millis(200),
            last_progress: Mutex::new(None),
            mode_pending: Mutex::new(None),
        })
    }
}

impl RemoteDrive {
    /// Timeout for each awaited state change (default 2 s).
    pub fn with_timeout(mut self, t: Duration) -> Self {
        self.timeout = t;
        self
    }

    /// SDO polling interval while waiting without a TPDO (default 10 ms).
    pub fn with_poll_interval(mut self, t: Duration) -> Self {
        self.poll = t;
        self
    }

    /// Calls `f` with the statusword, position and velocity while a call
    /// waits for the drive, at most every `every` of the master's time.
    pub fn on_progress(
        mut self,
        every: Duration,
        f: impl Fn(&MotionProgress) + Send + Sync + 'static,
    ) -> Self {
        self.progress = Some(Arc::new(f));
        self.progress_every = every;
        self
    }

    /// The node-ID.
    pub fn node(&self) -> u8 {
        self.node
    }

    /// True if the statusword arrives by TPDO.
    pub fn statusword_by_pdo(&self) -> bool {
        self.tpdo_objects.contains(&(STATUSWORD, 0))
    }

    /// True if the controlword can go by RPDO.
    pub fn controlword_by_pdo(&self) -> bool {
        self.rpdos.iter().any(|r| offset_of(&r.mapping, CONTROLWORD, 0).is_some())
    }

    fn operational(&self) -> bool {
        self.master.node_state(self.node) == Some(RemoteState::Operational)
    }

    /// Reads an object: from the latest TPDO when mapped (and the node is
    /// not known to have left Operational), else by SDO.
    pub async fn read_raw(&self, index: u16, sub: u8) -> Result<Vec<u8>, DriveError> {
        // A TPDO copy is stale once the bus is gone.
        if let Some(why) = self.master.bus_lost() {
            return Err(DriveError::Transport(why));
        }
        let st = self.master.node_state(self.node);
        if self.tpdo_objects.contains(&(index, sub))
            && !matches!(st, Some(RemoteState::PreOperational | RemoteState::Stopped | RemoteState::BootUp))
            && let Some(v) = self.latest.lock().unwrap_or_else(|e| e.into_inner()).get(&(index, sub))
        {
            return Ok(v.clone());
        }
        Ok(self.sdo.upload(index, sub).await?)
    }

    /// Writes an object: by an event-driven RPDO (transmission type
    /// 254/255) when one maps it and the node is Operational, else by SDO.
    /// A synchronous RPDO is not used here: it takes effect only at the
    /// next SYNC, after later writes by other means (a controlword by an
    /// event RPDO would be overwritten by a stale copy); streams use it
    /// ([`stream_raw`](Self::stream_raw)). Every RPDO image holding the
    /// object is updated, so an RPDO sent later for another object (e.g.
    /// 607Ah next to 6040h) repeats the current value instead of a stale one.
    pub async fn write_raw(&self, index: u16, sub: u8, data: &[u8]) -> Result<(), DriveError> {
        self.write_via(index, sub, data, false).await
    }

    /// [`write_raw`](Self::write_raw), by a synchronous RPDO first when
    /// `cyclic` (then any RPDO mapping the object).
    pub(crate) async fn write_via(
        &self,
        index: u16,
        sub: u8,
        data: &[u8],
        cyclic: bool,
    ) -> Result<(), DriveError> {
        let mut first: Option<(u16, Vec<u8>)> = None;
        let mut fallback: Option<(u16, Vec<u8>)> = None;
        for r in &self.rpdos {
            if let Some((off, len)) = offset_of(&r.mapping, index, sub)
                && data.len() >= len
            {
                let mut img = r.image.lock().unwrap_or_else(|e| e.into_inner());
                img[off..off + len].copy_from_slice(&data[..len]);
                let slot = if r.synchronous == cyclic { &mut first } else { &mut fallback };
                if slot.is_none() {
                    *slot = Some((r.cob, img[..r.len].to_vec()));
                }
            }
        }
        if cyclic {
            first = first.or(fallback);
        }
        match first {
            Some((cob, frame)) if self.operational() => {
                self.master.send_pdo(cob, &frame).await.map_err(|e| DriveError::Transport(e.to_string()))
            }
            _ => Ok(self.sdo.download(index, sub, data).await?),
        }
    }

    /// The statusword.
    pub async fn statusword(&self) -> Result<u16, DriveError> {
        let v = self.read_raw(STATUSWORD, 0).await?;
        Ok(<u16 as crate::SdoValue>::from_sdo(&v).unwrap_or(0))
    }

    /// The drive state.
    pub async fn state(&self) -> Result<DriveState, DriveError> {
        Ok(DriveState::from_statusword(self.statusword().await?))
    }

    /// Writes the controlword.
    pub async fn controlword(&self, cw: u16) -> Result<(), DriveError> {
        self.write_raw(CONTROLWORD, 0, &cw.to_le_bytes()).await
    }

    /// Waits until `pred(statusword)`; a Fault fails early unless `allow_fault`.
    pub(crate) async fn wait_sw(
        &self,
        what: &'static str,
        allow_fault: bool,
        pred: impl Fn(u16) -> bool,
    ) -> Result<u16, DriveError> {
        self.wait_sw_for(what, allow_fault, self.timeout, pred).await
    }

    pub(crate) async fn wait_sw_for(
        &self,
        what: &'static str,
        allow_fault: bool,
        timeout: Duration,
        pred: impl Fn(u16) -> bool,
    ) -> Result<u16, DriveError> {
        let deadline = self.master.now() + timeout;
        loop {
            // Register for the next TPDO before reading, so none is missed.
            let notified = self.updated.notified();
            let sw = self.statusword().await?;
            if pred(sw) {
                return Ok(sw);
            }
            if !allow_fault && DriveState::from_statusword(sw) == DriveState::Fault {
                return Err(DriveError::Fault { statusword: sw });
            }
            let now = self.master.now();
            if self.progress.is_some() {
                let due = {
                    let mut last = self.last_progress.lock().unwrap_or_else(|e| e.into_inner());
                    let due = last.is_none_or(|t| now.saturating_duration_since(t) >= self.progress_every);
                    if due {
                        *last = Some(now);
                    }
                    due
                };
                if due {
                    self.report(what, sw).await;
                }
            }
            if now >= deadline {
                return Err(DriveError::Timeout { waiting_for: what, statusword: sw });
            }
            let wake = deadline.saturating_duration_since(now).min(self.poll);
            tokio::select! {
                () = notified => {}
                () = self.master.sleep(wake) => {}
            }
        }
    }

    async fn transition(&self, cw: u16, target: DriveState, what: &'static str) -> Result<u16, DriveError> {
        self.controlword(cw).await?;
        self.wait_sw(what, false, |sw| DriveState::from_statusword(sw) == target).await
    }

    /// Fault reset, only when the drive is in Fault (or fault reaction):
    /// controlword bit 7 rising edge, then waits for the drive to leave
    /// Fault. A drive that is not faulted is left alone (writing a
    /// controlword would change its state). True if a fault was reset.
    pub async fn fault_reset(&self) -> Result<bool, DriveError> {
        let sw = self.statusword().await?;
        if !matches!(DriveState::from_statusword(sw), DriveState::Fault | DriveState::FaultReactionActive) {
            return Ok(false);
        }
        // In Fault the drive ignores every command but the bit 7 edge.
        self.controlword(cw::DISABLE_VOLTAGE).await?;
        self.controlword(cw::FAULT_RESET).await?;
        self.wait_sw("fault reset", true, |sw| {
            !matches!(DriveState::from_statusword(sw), DriveState::Fault | DriveState::FaultReactionActive)
        })
        .await?;
        Ok(true)
    }

    /// Walks the state machine to Operation enabled: fault reset if
    /// faulted, shutdown → switch on → enable operation, waiting for each
    /// state; then waits for 6061h to show a mode
    /// [`set_mode`](Self::set_mode) wrote before.
    pub async fn enable(&self) -> Result<(), DriveError> {
        // The one enable sequence (`cia402::codes::EnableStep`), one
        // confirmed step at a time.
        for _ in 0..8 {
            let sw = self.statusword().await?;
            match EnableStep::from_statusword(sw) {
                EnableStep::Done => return self.confirm_mode().await,
                EnableStep::FaultReset => {
                    self.fault_reset().await?;
                }
                EnableStep::Wait => {
                    let from = State::from_statusword(sw);
                    let what = match from {
                        Some(State::FaultReactionActive) => "leaving fault reaction active",
                        _ => "leaving not ready to switch on",
                    };
                    self.wait_sw(what, true, move |now| State::from_statusword(now) != from).await?;
                }
                EnableStep::Write { controlword, expect } => {
                    self.transition(controlword, expect.into(), expect.name()).await?;
                }
            }
        }
        let sw = self.statusword().await?;
        Err(DriveError::Timeout { waiting_for: "operation enabled", statusword: sw })
    }

    /// Shutdown (controlword 06h): power stage off, Ready to switch on.
    pub async fn disable(&self) -> Result<(), DriveError> {
        self.transition(0x06, DriveState::ReadyToSwitchOn, "ready to switch on").await.map(|_| ())
    }

    /// Quick stop (controlword 02h); waits for Quick stop active or Switch on disabled.
    pub async fn quick_stop(&self) -> Result<(), DriveError> {
        self.controlword(cw::QUICK_STOP).await?;
        self.wait_sw("quick stop", false, |sw| {
            matches!(
                DriveState::from_statusword(sw),
                DriveState::QuickStopActive | DriveState::SwitchOnDisabled
            )
        })
        .await
        .map(|_| ())
    }

    /// Writes 6060h. In Operation enabled, waits for 6061h to show
    /// `mode`; before it a drive may take the mode only once enabled (iPOS
    /// §4.2.4), so [`enable`](Self::enable), and every motion command
    /// before it starts, waits for 6061h instead.
    pub async fn set_mode(&self, mode: i8) -> Result<(), DriveError> {
        self.write_raw(MODES_OF_OPERATION, 0, &mode.to_le_bytes()).await?;
        *self.mode_pending.lock().unwrap_or_else(|e| e.into_inner()) = Some(mode);
        if drivebus_cia402::codes::mode::shown_at_once(self.statusword().await?) {
            self.confirm_mode().await?;
        }
        Ok(())
    }

    /// Waits for 6061h to show the mode [`set_mode`](Self::set_mode)
    /// wrote, unless it was seen already.
    pub(crate) async fn confirm_mode(&self) -> Result<(), DriveError> {
        let Some(want) = *self.mode_pending.lock().unwrap_or_else(|e| e.into_inner()) else {
            return Ok(());
        };
        let deadline = self.master.now() + self.timeout;
        loop {
            // By SDO: a mode change need not trigger an event TPDO, so a
            // TPDO copy of 6061h may be stale.
            let shown = self.sdo.upload(MODES_DISPLAY, 0).await?.first().map(|b| *b as i8);
            if shown == Some(want) {
                let mut p = self.mode_pending.lock().unwrap_or_else(|e| e.into_inner());
                if *p == Some(want) {
                    *p = None;
                }
                return Ok(());
            }
            if self.master.now() >= deadline {
                let statusword = self.statusword().await.unwrap_or(0);
                let display = shown.unwrap_or(0);
                return Err(DriveError::Mode(ModeNotShown { mode: want, display, statusword }));
            }
            self.master.sleep(self.poll).await;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statusword_states_cia402_table() {
        use DriveState::*;
        let cases = [
            (0x0000, NotReadyToSwitchOn),
            (0x0250, SwitchOnDisabled),
            (0x0231, ReadyToSwitchOn),
            (0x0233, SwitchedOn),
            (0x1637, OperationEnabled),
            (0x0217, QuickStopActive),
            (0x021F, FaultReactionActive),
            (0x0218, Fault),
        ];
        for (sw, st) in cases {
            assert_eq!(DriveState::from_statusword(sw), st, "{sw:04X}");
        }
    }

    #[test]
    fn offsets_in_byte_aligned_mappings_only() {
        let m = [PdoMapEntry::new(0x6040, 0, 16), PdoMapEntry::new(0x607A, 0, 32)];
        assert_eq!(offset_of(&m, 0x607A, 0), Some((2, 4)));
        assert_eq!(offset_of(&m, 0x6060, 0), None);
        let odd = [PdoMapEntry::new(0x2000, 0, 1), PdoMapEntry::new(0x2001, 0, 8)];
        assert_eq!(offset_of(&odd, 0x2001, 0), None);
    }
}
