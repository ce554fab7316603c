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

use drivebus_nmt::RemoteState;
use tokio::sync::{Notify, broadcast};

use crate::master::Master;
use crate::pdo::{PdoDir, PdoMapEntry};
use crate::sdo::{SdoError, SdoHandle};

/// Controlword 6040h.
pub const CONTROLWORD: u16 = 0x6040;
/// Statusword 6041h.
pub const STATUSWORD: u16 = 0x6041;
/// Modes of operation 6060h.
pub const MODES_OF_OPERATION: u16 = 0x6060;
/// Modes of operation display 6061h.
pub const MODES_DISPLAY: u16 = 0x6061;

/// Statusword bit 10: target reached.
pub const SW_TARGET_REACHED: u16 = 1 << 10;
/// Statusword bit 12: set-point acknowledge / homing attained / mode-specific.
pub const SW_BIT12: u16 = 1 << 12;
/// Statusword bit 13: following error / homing error.
pub const SW_BIT13: u16 = 1 << 13;

/// Modes of operation (6060h) values.
pub mod mode {
    /// Profile position.
    pub const PP: i8 = 1;
    /// Velocity (vl).
    pub const VL: i8 = 2;
    /// Profile velocity.
    pub const PV: i8 = 3;
    /// Profile torque.
    pub const TQ: i8 = 4;
    /// Homing.
    pub const HM: i8 = 6;
    /// Interpolated position.
    pub const IP: i8 = 7;
    /// Cyclic synchronous position.
    pub const CSP: i8 = 8;
    /// Cyclic synchronous velocity.
    pub const CSV: i8 = 9;
    /// Cyclic synchronous torque.
    pub const CST: i8 = 10;
}

/// CiA 402 power drive system states (from the statusword, CiA 402-2 table 30).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DriveState {
    /// xxxx xxxx x0xx 0000.
    NotReadyToSwitchOn,
    /// x1xx 0000.
    SwitchOnDisabled,
    /// x01x 0001.
    ReadyToSwitchOn,
    /// x01x 0011.
    SwitchedOn,
    /// x01x 0111.
    OperationEnabled,
    /// x00x 0111.
    QuickStopActive,
    /// x0xx 1111.
    FaultReactionActive,
    /// x0xx 1000.
    Fault,
    /// A pattern the table does not define.
    Unknown,
}

impl DriveState {
    /// Decodes the state bits of a statusword.
    pub fn from_statusword(sw: u16) -> DriveState {
        match (sw & 0x4F, sw & 0x6F) {
            (0x00, _) => DriveState::NotReadyToSwitchOn,
            (0x40, _) => DriveState::SwitchOnDisabled,
            (_, 0x21) => DriveState::ReadyToSwitchOn,
            (_, 0x23) => DriveState::SwitchedOn,
            (_, 0x27) => DriveState::OperationEnabled,
            (_, 0x07) => DriveState::QuickStopActive,
            (0x0F, _) => DriveState::FaultReactionActive,
            (0x08, _) => DriveState::Fault,
            _ => DriveState::Unknown,
        }
    }
}

/// Profile parameters for [`Drive::move_to`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Profile {
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
    /// Homing ended with statusword bit 13 (homing error).
    HomingError {
        /// The statusword.
        statusword: u16,
    },
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
            DriveError::HomingError { statusword } => {
                write!(f, "homing error (statusword {statusword:04X}h)")
            }
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

struct Rpdo {
    cob: u16,
    mapping: Vec<PdoMapEntry>,
    image: Mutex<[u8; 8]>,
    len: usize,
}

/// Byte offset of `index`/`sub` in a byte-aligned mapping.
fn offset_of(mapping: &[PdoMapEntry], index: u16, sub: u8) -> Option<(usize, usize)> {
    let mut bit = 0usize;
    for m in mapping {
        if m.index == index && m.sub == sub {
            return (bit.is_multiple_of(8) && m.bits.is_multiple_of(8))
                .then_some((bit / 8, usize::from(m.bits) / 8));
        }
        bit += usize::from(m.bits);
    }
    None
}

type Latest = Arc<Mutex<HashMap<(u16, u8), Vec<u8>>>>;

/// A CiA 402 drive on the bus; from [`Master::drive`].
pub struct Drive {
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
}

impl Drop for Drive {
    fn drop(&mut self) {
        for id in &self.sinks {
            self.master.remove_pdo_sink(*id);
        }
    }
}

impl fmt::Debug for Drive {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Drive")
            .field("node", &self.node)
            .field("tpdo_objects", &self.tpdo_objects)
            .field("rpdos", &self.rpdos.iter().map(|r| (r.cob, r.mapping.clone())).collect::<Vec<_>>())
            .finish_non_exhaustive()
    }
}

impl Master {
    /// A CiA 402 drive handle for `node`: reads its PDO 1..4 configuration
    /// (PDOs that cannot be read are treated as absent).
    pub async fn drive(&self, node: u8) -> Result<Drive, SdoError> {
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
                mapping: rec.mapping,
                image: Mutex::new(image),
            });
        }
        Ok(Drive {
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
        })
    }
}

impl Drive {
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
        let st = self.master.node_state(self.node);
        if self.tpdo_objects.contains(&(index, sub))
            && !matches!(st, Some(RemoteState::PreOperational | RemoteState::Stopped | RemoteState::BootUp))
            && let Some(v) = self.latest.lock().unwrap_or_else(|e| e.into_inner()).get(&(index, sub))
        {
            return Ok(v.clone());
        }
        Ok(self.sdo.upload(index, sub).await?)
    }

    /// Writes an object: by RPDO when mapped and the node is Operational,
    /// else by SDO. Every RPDO image holding the object is updated, so an
    /// RPDO sent later for another object (e.g. 607Ah next to 6040h)
    /// repeats the current value instead of a stale one.
    pub async fn write_raw(&self, index: u16, sub: u8, data: &[u8]) -> Result<(), DriveError> {
        let mut first: Option<(u16, Vec<u8>)> = None;
        for r in &self.rpdos {
            if let Some((off, len)) = offset_of(&r.mapping, index, sub)
                && data.len() >= len
            {
                let mut img = r.image.lock().unwrap_or_else(|e| e.into_inner());
                img[off..off + len].copy_from_slice(&data[..len]);
                if first.is_none() {
                    first = Some((r.cob, img[..r.len].to_vec()));
                }
            }
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
    async fn wait_sw(
        &self,
        what: &'static str,
        allow_fault: bool,
        pred: impl Fn(u16) -> bool,
    ) -> Result<u16, DriveError> {
        self.wait_sw_for(what, allow_fault, self.timeout, pred).await
    }

    async fn wait_sw_for(
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

    /// Fault reset: controlword bit 7 rising edge, then waits for Switch
    /// on disabled.
    pub async fn fault_reset(&self) -> Result<(), DriveError> {
        self.controlword(0x0000).await?;
        self.controlword(0x0080).await?;
        self.wait_sw("fault reset", true, |sw| {
            !matches!(DriveState::from_statusword(sw), DriveState::Fault | DriveState::FaultReactionActive)
        })
        .await?;
        Ok(())
    }

    /// Walks the state machine to Operation enabled: fault reset if
    /// faulted, shutdown → switch on → enable operation, waiting for each
    /// state.
    pub async fn enable(&self) -> Result<(), DriveError> {
        for _ in 0..8 {
            let sw = self.statusword().await?;
            match DriveState::from_statusword(sw) {
                DriveState::OperationEnabled => return Ok(()),
                DriveState::Fault | DriveState::FaultReactionActive => self.fault_reset().await?,
                DriveState::NotReadyToSwitchOn | DriveState::Unknown => {
                    self.wait_sw("leaving not ready to switch on", true, |sw| {
                        !matches!(
                            DriveState::from_statusword(sw),
                            DriveState::NotReadyToSwitchOn | DriveState::Unknown
                        )
                    })
                    .await?;
                }
                DriveState::SwitchOnDisabled => {
                    self.transition(0x06, DriveState::ReadyToSwitchOn, "ready to switch on").await?;
                }
                DriveState::ReadyToSwitchOn => {
                    self.transition(0x07, DriveState::SwitchedOn, "switched on").await?;
                }
                DriveState::SwitchedOn => {
                    self.transition(0x0F, DriveState::OperationEnabled, "operation enabled").await?;
                }
                DriveState::QuickStopActive => {
                    self.transition(0x00, DriveState::SwitchOnDisabled, "switch on disabled").await?;
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
        self.controlword(0x02).await?;
        self.wait_sw("quick stop", false, |sw| {
            matches!(
                DriveState::from_statusword(sw),
                DriveState::QuickStopActive | DriveState::SwitchOnDisabled
            )
        })
        .await
        .map(|_| ())
    }

    /// Writes 6060h and waits for 6061h to show `mode`.
    pub async fn set_mode(&self, mode: i8) -> Result<(), DriveError> {
        self.write_raw(MODES_OF_OPERATION, 0, &mode.to_le_bytes()).await?;
        let deadline = self.master.now() + self.timeout;
        loop {
            let v = self.read_raw(MODES_DISPLAY, 0).await?;
            if v.first().map(|b| *b as i8) == Some(mode) {
                return Ok(());
            }
            if self.master.now() >= deadline {
                let sw = self.statusword().await.unwrap_or(0);
                return Err(DriveError::Timeout {
                    waiting_for: "modes of operation display",
                    statusword: sw,
                });
            }
            self.master.sleep(self.poll).await;
        }
    }

    /// Profile position move (mode must be PP): optional profile
    /// (6081h/6083h/6084h), target 607Ah, new set-point (bit 4, change
    /// immediately bit 5, relative bit 6), waits for the acknowledge (bit
    /// 12), clears bit 4, then waits for target reached (bit 10) within
    /// `timeout`.
    pub async fn move_to(
        &self,
        target: i32,
        relative: bool,
        profile: Option<Profile>,
        timeout: Duration,
    ) -> Result<(), DriveError> {
        if let Some(p) = profile {
            self.sdo.write(0x6081, 0, p.velocity).await?;
            self.sdo.write(0x6083, 0, p.acceleration).await?;
            self.sdo.write(0x6084, 0, p.deceleration).await?;
        }
        self.write_raw(0x607A, 0, &target.to_le_bytes()).await?;
        let base = 0x0F | 0x20 | if relative { 0x40 } else { 0 };
        self.controlword(base).await?;
        self.controlword(base | 0x10).await?;
        self.wait_sw("set-point acknowledge", false, |sw| sw & SW_BIT12 != 0).await?;
        self.controlword(base).await?;
        self.wait_sw_for("target reached", false, timeout, |sw| {
            sw & SW_BIT12 == 0 && sw & SW_TARGET_REACHED != 0
        })
        .await
        .map(|_| ())
    }

    /// Target velocity 60FFh (profile velocity / CSV).
    pub async fn velocity(&self, v: i32) -> Result<(), DriveError> {
        self.write_raw(0x60FF, 0, &v.to_le_bytes()).await
    }

    /// Target torque 6071h (profile torque / CST).
    pub async fn torque(&self, t: i16) -> Result<(), DriveError> {
        self.write_raw(0x6071, 0, &t.to_le_bytes()).await
    }

    /// Homing: writes 6098h, switches to homing mode, starts (bit 4) and
    /// waits for homing attained (bit 12) or error (bit 13).
    pub async fn home(&self, method: i8, timeout: Duration) -> Result<(), DriveError> {
        self.sdo.write(0x6098, 0, method).await?;
        self.set_mode(mode::HM).await?;
        self.controlword(0x0F).await?;
        self.controlword(0x1F).await?;
        let sw =
            self.wait_sw_for("homing attained", false, timeout, |sw| sw & (SW_BIT12 | SW_BIT13) != 0).await?;
        self.controlword(0x0F).await?;
        if sw & SW_BIT13 != 0 {
            return Err(DriveError::HomingError { statusword: sw });
        }
        Ok(())
    }

    /// Streams values of `index`/`sub`, one right after each SYNC the
    /// master produces (RPDO when mapped, else SDO, which cannot keep up
    /// with short cycles). Returns how many were sent.
    pub async fn stream_raw(
        &self,
        index: u16,
        sub: u8,
        values: impl IntoIterator<Item = Vec<u8>>,
    ) -> Result<usize, DriveError> {
        if !self.master.sync_running() {
            return Err(DriveError::NoSync);
        }
        let mut ticks = self.master.subscribe_sync();
        let mut n = 0;
        for v in values {
            loop {
                match self.master.timeout(Duration::from_secs(1), ticks.recv()).await {
                    Ok(Ok(_)) => {
                        // Behind by whole cycles: align to the latest SYNC
                        // rather than sending a burst for the old ones.
                        while !matches!(
                            ticks.try_recv(),
                            Err(broadcast::error::TryRecvError::Empty
                                | broadcast::error::TryRecvError::Closed)
                        ) {}
                        break;
                    }
                    // Behind by several cycles: send now, aligned to the latest.
                    Ok(Err(broadcast::error::RecvError::Lagged(_))) => {}
                    Ok(Err(broadcast::error::RecvError::Closed)) | Err(_) => return Err(DriveError::NoSync),
                }
            }
            self.write_raw(index, sub, &v).await?;
            n += 1;
        }
        Ok(n)
    }

    /// Cyclic synchronous position: target positions 607Ah, one per SYNC.
    pub async fn stream_csp(&self, positions: impl IntoIterator<Item = i32>) -> Result<usize, DriveError> {
        self.stream_raw(0x607A, 0, positions.into_iter().map(|p| p.to_le_bytes().to_vec())).await
    }

    /// Cyclic synchronous velocity: target velocities 60FFh, one per SYNC.
    pub async fn stream_csv(&self, velocities: impl IntoIterator<Item = i32>) -> Result<usize, DriveError> {
        self.stream_raw(0x60FF, 0, velocities.into_iter().map(|p| p.to_le_bytes().to_vec())).await
    }

    /// Cyclic synchronous torque: target torques 6071h, one per SYNC.
    pub async fn stream_cst(&self, torques: impl IntoIterator<Item = i16>) -> Result<usize, DriveError> {
        self.stream_raw(0x6071, 0, torques.into_iter().map(|p| p.to_le_bytes().to_vec())).await
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
