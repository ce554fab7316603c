//! An EtherCAT master for tools, on ethercrab 0.7.1: open a line (a named
//! interface through ethercrab's raw socket, or a [`Host`] through the
//! in-process [`link`](crate::link)), find the slaves, read their AL
//! state, request a state, read and write CoE objects (whole arrays and
//! records by the slave's SDO Information and complete access:
//! [`LineMaster::read_object`]), read the PDO assignment and mapping, and run a CiA 402 drive over the process data
//! ([`drive`]). `drivebus ethercat scan|sdo|state|pdo|drive` and
//! `drivebus demo --ethercat` are this module; nothing else in the tool
//! talks to ethercrab.
//!
//! Slaves are numbered by line position from 1 (as `drivebus ethercat
//! serve --state-dir` names them, `ecat-1-ipos`).

pub mod drive;
mod objects;

pub use objects::{
    DescribedBy, Entry, EntryDescription, ObjectDescription, ObjectRead, coe_details, read_entries,
};

/// Runs a master future to completion on this thread (ethercrab's timers
/// are async-io's).
pub use async_io::block_on;
/// The CiA 402 tables the drive commands use.
pub use drivebus_cia402::codes;

use crate::host::Host;
use drivebus_can::Duration;
use ethercrab::error::{Error, MailboxError};
use ethercrab::subdevice_group::PreOp;
use ethercrab::{
    Command, DefaultLock, EtherCrabWireRead, EtherCrabWireSized, MainDevice, MainDeviceConfig, PduStorage,
    SubDevice, SubDeviceGroup, SubDeviceRef, Timeouts,
};
use std::fmt;
use std::ops::Deref;

/// Most slaves on a line this master handles.
pub const MAX_SUBDEVICES: usize = 16;
/// Largest process image \[bytes\].
pub const MAX_PDI: usize = 1024;
/// Largest CoE object read \[bytes\].
pub const MAX_SDO: usize = 1024;

/// ethercrab's frame storage for one master.
pub type PduFrames = PduStorage<16, { PduStorage::element_size(1100) }>;

/// A group of every slave on the line, in PRE-OP.
pub type PreOpGroup = SubDeviceGroup<MAX_SUBDEVICES, MAX_PDI, DefaultLock, PreOp>;

/// The storage of [`LineMaster::on_iface`]: ethercrab splits a storage once,
/// so a process opens one interface master.
static IFACE_STORAGE: PduFrames = PduStorage::new();

/// What went wrong, in words a user can act on.
#[derive(Debug)]
pub enum MasterError {
    /// The interface could not be opened.
    Open(String, std::io::Error),
    /// The frame storage was already used (one master per storage).
    InUse,
    /// No frame came back.
    NoLine(String),
    /// Frames come back but no slave answers.
    Empty(String),
    /// No slave at this 1-based position.
    NoSlave {
        /// The position asked for.
        position: usize,
        /// Slaves on the line.
        count: usize,
    },
    /// The slave aborted a CoE transfer.
    Abort {
        /// Position (1-based).
        position: usize,
        /// Object.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Write (download) or read (upload).
        write: bool,
        /// The abort code (CiA 301 §7.2.4.3.17, the same on CoE).
        code: u32,
    },
    /// The slave refused an AL state.
    Refused {
        /// Position (1-based).
        position: usize,
        /// The requested state.
        requested: AlState,
        /// The state it stayed in (the code when it names no state).
        state: Result<AlState, u8>,
        /// The AL status code (0x0134).
        code: u16,
    },
    /// Not possible with ethercrab or this slave (says why).
    Unsupported(String),
    /// Any other ethercrab error, with what was being done.
    Ethercrab(String, Error),
}

impl fmt::Display for MasterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MasterError::Open(i, e) => write!(
                f,
                "cannot open {i}: {e} (AF_PACKET needs root or CAP_NET_RAW, and an existing interface that is up)"
            ),
            MasterError::InUse => f.write_str("this process already runs a master on that frame storage"),
            MasterError::NoLine(i) => write!(
                f,
                "no EtherCAT frame came back on {i}: is a slave (or `drivebus ethercat serve`) connected and the link up?"
            ),
            MasterError::Empty(i) => write!(
                f,
                "frames come back on {i} but no slave answers: the line is empty (or the slaves are unpowered)"
            ),
            MasterError::NoSlave { position, count } => {
                write!(f, "there is no slave {position}: the line has {count} (give --slave 1..{count})")
            }
            MasterError::Abort { position, index, sub, write, code } => write!(
                f,
                "slave {position}: SDO {} {index:04X}h:{sub:02X} aborted by the device with code 0x{code:08X}: {}",
                if *write { "write" } else { "read" },
                abort_text(*code)
            ),
            MasterError::Refused { position, requested, state, code } => write!(
                f,
                "slave {position}: {requested} refused, stays in {}: AL status code 0x{code:04X} {}",
                state_text(*state),
                al_status_text(*code)
            ),
            MasterError::Unsupported(s) => f.write_str(s),
            MasterError::Ethercrab(what, e) => write!(f, "{what}: {e}"),
        }
    }
}

impl std::error::Error for MasterError {}

/// The text of a CoE/CANopen abort code: the same table as the CAN side.
pub fn abort_text(code: u32) -> &'static str {
    drivebus_od::SdoAbort(code).description().unwrap_or("unknown abort code")
}

/// The ETG.1000.6 text of an AL status code.
pub fn al_status_text(code: u16) -> &'static str {
    drivebus_esc::slave::AlStatusCode(code).description()
}

/// An AL state as in 0x0120/0x0130 (ETG.1000.6 §6.4.1): the one EtherCAT
/// state type, the slave controller's.
pub use drivebus_esc::slave::AlState;

/// How a state read from 0x0130 prints: its name, or the code when bits
/// 3:0 named no state.
pub fn state_text(state: Result<AlState, u8>) -> String {
    match state {
        Ok(s) => s.to_string(),
        Err(x) => format!("state {x:#x}"),
    }
}

/// AL status of one slave (0x0130, 0x0134).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AlStatus {
    /// The state, or the code of bits 3:0 when they name no state.
    pub state: Result<AlState, u8>,
    /// Error indicator (0x0130 bit 4).
    pub error: bool,
    /// AL status code.
    pub code: u16,
}

/// Mailbox protocols of SII word 0x001C (ETG.1000.6 Table 18).
pub fn mailbox_protocols(bits: u16) -> Vec<&'static str> {
    [(0x01, "AoE"), (0x02, "EoE"), (0x04, "CoE"), (0x08, "FoE"), (0x10, "SoE"), (0x20, "VoE")]
        .iter()
        .filter(|(b, _)| bits & b != 0)
        .map(|(_, n)| *n)
        .collect()
}

/// One slave as `scan` reports it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SlaveInfo {
    /// Line position, from 1.
    pub position: usize,
    /// Configured station address (0x0010) ethercrab gave it.
    pub address: u16,
    /// Station alias (0x0012).
    pub alias: u16,
    /// Name (SII General "order" string).
    pub name: String,
    /// Vendor, product, revision, serial from the SII.
    pub identity: [u32; 4],
    /// 1018h:01..04 over CoE, when the slave has CoE.
    pub coe_identity: Option<[u32; 4]>,
    /// The AL status found before the scan initialised the line.
    pub found: AlStatus,
    /// SII mailbox protocol bits (0x001C).
    pub mailbox: u16,
    /// DC support.
    pub dc: bool,
}

/// One PDO: its mapping object and entries (index << 16 | sub << 8 | bits).
pub type PdoMapping = (u16, Vec<u32>);

/// CoE data of any length (up to [`MAX_SDO`]) for ethercrab's reader.
struct Raw(Vec<u8>);

impl EtherCrabWireRead for Raw {
    fn unpack_from_slice(buf: &[u8]) -> Result<Self, ethercrab_wire::WireError> {
        Ok(Raw(buf.to_vec()))
    }
}

impl EtherCrabWireSized for Raw {
    const PACKED_LEN: usize = MAX_SDO;
    type Buffer = [u8; MAX_SDO];
    fn buffer() -> Self::Buffer {
        [0; MAX_SDO]
    }
}

/// How the master waits between cycles: real time, or the simulated time
/// of an in-process host (which moves when the master waits).
#[derive(Debug, Clone)]
pub enum Pace {
    /// The machine's clock.
    Real,
    /// The host's simulated clock.
    Simulated(Host),
}

impl Pace {
    /// Waits `d`.
    pub async fn sleep(&self, d: Duration) {
        match self {
            Pace::Real => {
                async_io::Timer::after(d).await;
            }
            Pace::Simulated(h) => h.advance(d),
        }
    }
}

/// A master on one line.
pub struct LineMaster {
    md: MainDevice<'static>,
    pace: Pace,
    now: &'static (dyn Fn() -> u64 + Sync),
    what: String,
}

impl fmt::Debug for LineMaster {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LineMaster")
            .field("line", &self.what)
            .field("pace", &self.pace)
            .finish_non_exhaustive()
    }
}

fn timeouts(pdu: std::time::Duration) -> Timeouts {
    Timeouts {
        pdu,
        eeprom: std::time::Duration::from_millis(200),
        mailbox_response: std::time::Duration::from_secs(2),
        state_transition: std::time::Duration::from_secs(5),
        ..Timeouts::default()
    }
}

fn config() -> MainDeviceConfig {
    MainDeviceConfig { dc_static_sync_iterations: 1_000, ..MainDeviceConfig::default() }
}

impl LineMaster {
    /// A master on network interface `iface` (ethercrab's raw socket; root
    /// or CAP_NET_RAW). `pdu_timeout` is how long a frame may take to come back.
    pub fn on_iface(iface: &str, pdu_timeout: std::time::Duration) -> Result<LineMaster, MasterError> {
        let (tx, rx, pdu_loop) = IFACE_STORAGE.try_split().map_err(|()| MasterError::InUse)?;
        let task =
            ethercrab::std::tx_rx_task(iface, tx, rx).map_err(|e| MasterError::Open(iface.into(), e))?;
        std::thread::Builder::new()
            .name("ethercat-tx-rx".into())
            .spawn(move || async_io::block_on(task))
            .map_err(|e| MasterError::Open(iface.into(), e))?;
        let md = MainDevice::new(pdu_loop, timeouts(pdu_timeout), config());
        Ok(LineMaster { md, pace: Pace::Real, now: &ethercrab::std::ethercat_now, what: iface.to_owned() })
    }

    /// A master on an in-process `host` (the demo, tests), through
    /// [`link`](crate::link); `storage` must not have been split before.
    /// With a simulated clock the master's waits move the host's time.
    pub fn on_host(storage: &'static PduFrames, host: Host) -> Result<LineMaster, MasterError> {
        let (tx, rx, pdu_loop) = storage.try_split().map_err(|()| MasterError::InUse)?;
        let h = host.clone();
        std::thread::Builder::new()
            .name("ethercat-link".into())
            .spawn(move || async_io::block_on(crate::link::run(h, tx, rx)))
            .map_err(|e| MasterError::Open("the in-process link".into(), e))?;
        let md = MainDevice::new(pdu_loop, timeouts(std::time::Duration::from_secs(1)), config());
        let clock: &'static crate::Clock = Box::leak(Box::new(host.clock().clone()));
        let now: &'static (dyn Fn() -> u64 + Sync) = Box::leak(Box::new(move || clock.ethercat_ns()));
        let pace = if host.clock().is_simulated() { Pace::Simulated(host) } else { Pace::Real };
        Ok(LineMaster { md, pace, now, what: "the in-process link".into() })
    }

    /// ethercrab's main device.
    pub fn main_device(&self) -> &MainDevice<'static> {
        &self.md
    }

    /// How this master waits.
    pub fn pace(&self) -> &Pace {
        &self.pace
    }

    /// The master's clock for DC, in ns.
    pub fn now_fn(&self) -> impl Fn() -> u64 + Copy + use<> {
        let f = self.now;
        move || f()
    }

    fn err(&self, what: &str) -> impl FnOnce(Error) -> MasterError {
        let line = self.what.clone();
        let what = what.to_owned();
        move |e| match e {
            Error::Timeout(_) => MasterError::NoLine(line),
            e => MasterError::Ethercrab(what, e),
        }
    }

    /// The line this master is on (an interface name).
    pub fn line_name(&self) -> &str {
        &self.what
    }

    /// Slaves on the line (a broadcast read: each adds 1 to the working
    /// counter); does not change any slave.
    pub async fn count(&self) -> Result<usize, MasterError> {
        match Command::brd(0x0000).with_wkc(u16::MAX).receive::<u8>(&self.md).await {
            Err(Error::WorkingCounter { received, .. }) => Ok(usize::from(received)),
            Ok(_) => Ok(usize::from(u16::MAX)),
            Err(e) => Err(self.err("counting the slaves")(e)),
        }
    }

    /// Checks that position `position` (1-based) exists.
    pub async fn check_position(&self, position: usize) -> Result<usize, MasterError> {
        let count = self.count().await?;
        if count == 0 {
            return Err(MasterError::Empty(self.what.clone()));
        }
        if position == 0 || position > count {
            return Err(MasterError::NoSlave { position, count });
        }
        Ok(count)
    }

    /// The AL status of the slave at `position` (1-based), by
    /// auto-increment address: works in any state, changes nothing.
    pub async fn al_status(&self, position: usize) -> Result<AlStatus, MasterError> {
        let p = position.saturating_sub(1) as u16;
        let s: u16 =
            Command::aprd(p, 0x0130).receive(&self.md).await.map_err(self.err("reading the AL status"))?;
        let code: u16 = Command::aprd(p, 0x0134)
            .receive(&self.md)
            .await
            .map_err(self.err("reading the AL status code"))?;
        let bits = s as u8 & 0x0F;
        Ok(AlStatus { state: AlState::from_code(bits).ok_or(bits), error: s & 0x10 != 0, code })
    }

    /// Writes AL control of one slave and waits (up to 5 s) until it is in
    /// `want` or shows an error; an error is acknowledged (ETG.1000.6
    /// §6.4.1.1) and returned as [`MasterError::Refused`] with its code.
    pub async fn request_state(&self, position: usize, want: AlState) -> Result<AlStatus, MasterError> {
        let p = position.saturating_sub(1) as u16;
        let before = self.al_status(position).await?;
        // A pending error is acknowledged with the request.
        let ack = if before.error { 0x10 } else { 0 };
        Command::apwr(p, 0x0120)
            .send(&self.md, u16::from(want.code() | ack))
            .await
            .map_err(self.err("writing AL control"))?;
        let start = std::time::Instant::now();
        loop {
            let s = self.al_status(position).await?;
            if s.error {
                let _ = Command::apwr(p, 0x0120)
                    .send(&self.md, u16::from(s.state.map_or_else(|x| x, AlState::code) | 0x10))
                    .await;
                return Err(MasterError::Refused { position, requested: want, state: s.state, code: s.code });
            }
            if s.state == Ok(want) {
                return Ok(s);
            }
            if start.elapsed() > std::time::Duration::from_secs(5) {
                return Err(MasterError::Refused { position, requested: want, state: s.state, code: s.code });
            }
            async_io::Timer::after(std::time::Duration::from_millis(1)).await;
        }
    }

    /// ethercrab's initialisation: every slave gets its station address,
    /// its SII is read, mailboxes are set up and the line goes to PRE-OP.
    pub async fn init(&self) -> Result<PreOpGroup, MasterError> {
        if self.count().await? == 0 {
            return Err(MasterError::Empty(self.what.clone()));
        }
        self.md
            .init_single_group::<MAX_SUBDEVICES, MAX_PDI>(self.now_fn())
            .await
            .map_err(self.err("initialising the line (INIT -> PRE-OP)"))
    }

    /// Every slave: identity (SII and 1018h), addresses, the AL state found
    /// before, mailbox protocols. Leaves the line in PRE-OP.
    pub async fn scan(&self) -> Result<Vec<SlaveInfo>, MasterError> {
        self.scan_group().await.map(|(found, _)| found)
    }

    /// [`LineMaster::scan`], keeping the line's group for what comes next.
    pub async fn scan_group(&self) -> Result<(Vec<SlaveInfo>, PreOpGroup), MasterError> {
        let n = self.count().await?;
        if n == 0 {
            return Err(MasterError::Empty(self.what.clone()));
        }
        let mut found = Vec::new();
        for p in 1..=n.min(MAX_SUBDEVICES) {
            found.push(self.al_status(p).await?);
        }
        let group = self.init().await?;
        let mut out = Vec::new();
        for (i, sd) in group.iter(&self.md).enumerate() {
            let mut word = [0u8; 2];
            let mailbox = match sd.deref().eeprom_read_raw(&self.md, 0x001C, &mut word).await {
                Ok(_) => u16::from_le_bytes(word),
                Err(_) => 0,
            };
            let coe_identity = if mailbox & 0x04 != 0 {
                let mut id = [0u32; 4];
                let mut ok = true;
                for (k, v) in id.iter_mut().enumerate() {
                    match sd.sdo_read::<u32>(0x1018, k as u8 + 1).await {
                        Ok(x) => *v = x,
                        Err(_) => ok = false,
                    }
                }
                ok.then_some(id)
            } else {
                None
            };
            let id = sd.identity();
            out.push(SlaveInfo {
                position: i + 1,
                address: sd.configured_address(),
                alias: sd.alias_address(),
                name: sd.name().to_owned(),
                identity: [id.vendor_id, id.product_id, id.revision, id.serial],
                coe_identity,
                found: found.get(i).copied().unwrap_or(AlStatus { state: Err(0), error: false, code: 0 }),
                mailbox,
                dc: sd.dc_support().any(),
            });
        }
        Ok((out, group))
    }

    /// Free run: turns DC SYNC generation off (0x0981 = 0) and, where the
    /// slave has it, asks for SM-synchronous operation in 1C32h:01 (ETG.6010
    /// sync type 1), so the DC set-up an earlier master left does not make
    /// a slave refuse SAFE-OP (0x0030).
    pub async fn sync_off(&self, group: &PreOpGroup) -> Result<(), MasterError> {
        for (i, sd) in group.iter(&self.md).enumerate() {
            sd.register_write(0x0981u16, 0u8)
                .await
                .map_err(|e| MasterError::Ethercrab("switching DC SYNC off (0981h)".into(), e))?;
            match sdo_write(&sd, i + 1, 0x1C32, 1, &1u16.to_le_bytes()).await {
                // No mailbox, no 1C32h, or a fixed one: nothing to ask.
                Ok(())
                | Err(MasterError::Abort { .. })
                | Err(MasterError::Ethercrab(
                    _,
                    Error::Mailbox(MailboxError::NoWriteMailbox | MailboxError::NoReadMailbox),
                )) => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    /// After a failed transition: the first slave (of `which`, 1-based)
    /// showing an AL error, as [`MasterError::Refused`], else `e`.
    pub async fn refusal(&self, requested: AlState, which: &[usize], e: MasterError) -> MasterError {
        for &p in which {
            if let Ok(s) = self.al_status(p).await
                && s.error
            {
                return MasterError::Refused { position: p, requested, state: s.state, code: s.code };
            }
        }
        e
    }

    /// The slave at `position` (1-based) of `group`.
    pub fn slave<'g>(
        &'g self,
        group: &'g PreOpGroup,
        position: usize,
    ) -> Result<SubDeviceRef<'g, &'g SubDevice>, MasterError> {
        let count = group.len();
        position
            .checked_sub(1)
            .and_then(|i| group.subdevice(&self.md, i).ok())
            .ok_or(MasterError::NoSlave { position, count })
    }
}

/// Reads `index`:`sub` of a slave as bytes (expedited, normal or segmented).
pub async fn sdo_read<S: Deref<Target = SubDevice>>(
    sd: &SubDeviceRef<'_, S>,
    position: usize,
    index: u16,
    sub: u8,
) -> Result<Vec<u8>, MasterError> {
    let mut tries = 0;
    loop {
        match sd.sdo_read::<Raw>(index, sub).await {
            Ok(r) => return Ok(r.0),
            Err(e) if mailbox_held_another_message(&e) && tries < MAILBOX_RETRIES => tries += 1,
            Err(e) => return Err(coe_error(e, position, index, sub, false)),
        }
    }
}

/// How often an SDO is sent again after the answer read was another message.
const MAILBOX_RETRIES: u32 = 3;

/// Whether ethercrab read something other than the SDO answer from the send
/// mailbox: a slave may put an unsolicited CoE emergency there between
/// ethercrab's check that the mailbox is empty and its request (ETG.1000.6
/// §5.6.4; a drive in DC mode raises one on its SYNC0 step, e.g. at a fault
/// reset), and ethercrab 0.7.1 then fails to decode it as an SDO header.
/// The answer follows it, and ethercrab empties the mailbox before the
/// next request, so the SDO can be sent again.
fn mailbox_held_another_message(e: &Error) -> bool {
    matches!(e, Error::Wire(_) | Error::Mailbox(MailboxError::Emergency { .. }))
}

/// Writes `data` to `index`:`sub` of a slave (ethercrab 0.7.1 downloads
/// expedited only: at most 4 bytes).
pub async fn sdo_write<S: Deref<Target = SubDevice>>(
    sd: &SubDeviceRef<'_, S>,
    position: usize,
    index: u16,
    sub: u8,
    data: &[u8],
) -> Result<(), MasterError> {
    if data.is_empty() || data.len() > 4 {
        return Err(MasterError::Unsupported(format!(
            "slave {position}: writing {} bytes to {index:04X}h:{sub:02X}: ethercrab 0.7.1 writes 1 to 4 bytes (expedited download)",
            data.len()
        )));
    }
    let mut tries = 0;
    loop {
        match sd.sdo_write(index, sub, data).await {
            Ok(()) => return Ok(()),
            // The download was taken (its answer was behind the other
            // message): the same value is written once more.
            Err(e) if mailbox_held_another_message(&e) && tries < MAILBOX_RETRIES => tries += 1,
            Err(e) => return Err(coe_error(e, position, index, sub, true)),
        }
    }
}

fn coe_error(e: Error, position: usize, index: u16, sub: u8, write: bool) -> MasterError {
    match e {
        Error::Mailbox(MailboxError::Aborted { code, .. }) => {
            MasterError::Abort { position, index, sub, write, code: u32::from(code) }
        }
        Error::Mailbox(MailboxError::TooLong { .. }) => MasterError::Unsupported(format!(
            "slave {position}: {index:04X}h:{sub:02X} is longer than {MAX_SDO} bytes"
        )),
        e => MasterError::Ethercrab(
            format!("slave {position}: SDO {} {index:04X}h:{sub:02X}", if write { "write" } else { "read" }),
            e,
        ),
    }
}

/// The PDOs `assign` (1C12h or 1C13h) assigns, with their entries, over CoE.
pub async fn pdo_assignment<S: Deref<Target = SubDevice>>(
    sd: &SubDeviceRef<'_, S>,
    position: usize,
    assign: u16,
) -> Result<Vec<PdoMapping>, MasterError> {
    let u = |d: Vec<u8>| d.iter().take(4).rev().fold(0u32, |a, &b| (a << 8) | u32::from(b));
    let n = u(sdo_read(sd, position, assign, 0).await?);
    let mut out = Vec::new();
    for s in 1..=n.min(254) as u8 {
        let pdo = u(sdo_read(sd, position, assign, s).await?) as u16;
        let m = u(sdo_read(sd, position, pdo, 0).await?);
        let mut entries = Vec::new();
        for e in 1..=m.min(254) as u8 {
            entries.push(u(sdo_read(sd, position, pdo, e).await?));
        }
        out.push((pdo, entries));
    }
    Ok(out)
}

/// Byte offset of the first byte-aligned `(index, sub)` in a direction's image.
pub fn offset(pdos: &[PdoMapping], index: u16, sub: u8) -> Option<usize> {
    image_layout(pdos).find(|m| m.is(index, sub) && m.bit_offset.is_multiple_of(8)).map(|m| m.bit_offset / 8)
}

/// The assigned PDOs' entries with their places in the direction's image.
pub fn image_layout(pdos: &[PdoMapping]) -> impl Iterator<Item = drivebus_pdo::MappedObject> + '_ {
    drivebus_pdo::layout(pdos.iter().flat_map(|(_, entries)| entries.iter().copied()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn states_parse_and_print() {
        assert_eq!(state_text(Ok(AlState::Op)), "OP");
        assert_eq!(state_text(Err(5)), "state 0x5");
        assert_eq!(mailbox_protocols(0x000C), ["CoE", "FoE"]);
        assert_eq!(abort_text(0x0602_0000), "Object does not exist in the object dictionary");
        assert_eq!(al_status_text(0x0011), "Invalid requested state change");
    }

    #[test]
    fn offsets_follow_the_mapping() {
        let tx = vec![(0x1A00, vec![0x6041_0010, 0x6064_0020, 0x6077_0010]), (0x1A01, vec![0x60F4_0020])];
        assert_eq!(offset(&tx, 0x6041, 0), Some(0));
        assert_eq!(offset(&tx, 0x6064, 0), Some(2));
        assert_eq!(offset(&tx, 0x60F4, 0), Some(8));
        assert_eq!(offset(&tx, 0x606C, 0), None);
    }
}
