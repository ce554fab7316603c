//! A CiA 402 drive over EtherCAT process data: the line in OP (DC SYNC0
//! where every slave supports it, else free run), one drive's controlword,
//! target, statusword, position and following error at their offsets in
//! the image its 1C12h/1C13h assignment gives, objects not mapped over
//! CoE. The state machine and bits are `drivebus_cia402::codes`.
//!
//! A motion that fails, times out or is interrupted is halted (controlword
//! bit 8), and quick-stopped if it does not come to rest; the error says
//! which was done.

use super::{
    AlState, LineMaster, MasterError, PdoMapping, PreOpGroup, offset, pdo_assignment, sdo_read, sdo_write,
};
use super::{MAX_PDI, MAX_SUBDEVICES};
use drivebus_can::Duration;
use drivebus_cia402::codes::{EnableStep, ModeNotShown, State, cw, mode, sw};
use ethercrab::subdevice_group::{DcConfiguration, HasDc, NoDc, Op, PreOpPdi};
use ethercrab::{DcSync, DefaultLock, RegisterAddress, SubDeviceGroup};
use std::fmt;
use std::sync::atomic::{AtomicBool, Ordering};

type OpGroup<D> = SubDeviceGroup<MAX_SUBDEVICES, MAX_PDI, DefaultLock, Op, D>;

enum Group {
    Dc(OpGroup<HasDc>),
    Free(OpGroup<NoDc>),
}

/// Why a drive command did not do what it was asked.
#[derive(Debug)]
pub enum CyclicDriveError {
    /// The line or a CoE transfer failed.
    Master(MasterError),
    /// The drive did not get there in time; what the master then did.
    Timeout {
        /// What was waited for.
        what: String,
        /// The time given.
        after: Duration,
        /// What the master did about a motion it had started.
        stopped: Option<Stop>,
    },
    /// Ctrl-C (or the caller's stop flag).
    Interrupted {
        /// What was running.
        what: String,
        /// What the master did about a motion it had started.
        stopped: Option<Stop>,
    },
    /// The drive went to fault.
    Fault {
        /// During what.
        what: String,
        /// Statusword.
        statusword: u16,
        /// 603Fh error code, when it could be read.
        error_code: Option<u16>,
    },
    /// Homing ended with statusword bit 13 (homing error).
    Homing {
        /// Statusword.
        statusword: u16,
        /// What the master did.
        stopped: Option<Stop>,
    },
    /// 6061h did not come to show the mode written to 6060h.
    Mode {
        /// The slave's position.
        slave: usize,
        /// The mode, what 6061h showed, the statusword.
        not_shown: ModeNotShown,
    },
    /// The process data lost the line (working counter wrong for 100 cycles).
    Lost {
        /// Cycles with a wrong working counter in a row.
        cycles: u32,
    },
}

/// What the master did to stop a motion it had started.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// Controlword halt bit; the drive came to rest.
    Halted,
    /// Halt did not bring it to rest within 2 s: quick stop.
    QuickStopped,
    /// Neither was confirmed by the statusword.
    Unconfirmed,
}

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Stop::Halted => "the motion was halted (controlword bit 8) and the drive is at rest",
            Stop::QuickStopped => "halt did not stop it: quick stop sent (controlword 0002h)",
            Stop::Unconfirmed => "halt and quick stop were sent but the statusword never confirmed a stop",
        })
    }
}

fn stopped(s: &Option<Stop>) -> String {
    s.map(|s| format!("; {s}")).unwrap_or_default()
}

impl fmt::Display for CyclicDriveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CyclicDriveError::Master(e) => write!(f, "{e}"),
            CyclicDriveError::Timeout { what, after, stopped: s } => {
                write!(f, "{what}: not done after {:.1} s{}", after.as_secs_f64(), stopped(s))
            }
            CyclicDriveError::Interrupted { what, stopped: s } => {
                write!(f, "{what}: interrupted{}", stopped(s))
            }
            CyclicDriveError::Fault { what, statusword, error_code } => {
                write!(f, "{what}: the drive is in fault (statusword {statusword:04X}h")?;
                match error_code {
                    Some(c) => write!(f, ", 603Fh error code {c:04X}h)"),
                    None => f.write_str(")"),
                }
            }
            CyclicDriveError::Homing { statusword, stopped: s } => {
                write!(f, "homing error (statusword {statusword:04X}h bit 13){}", stopped(s))
            }
            CyclicDriveError::Mode { slave, not_shown } => write!(f, "slave {slave}: {not_shown}"),
            CyclicDriveError::Lost { cycles } => write!(
                f,
                "the process data stopped coming back ({cycles} cycles with a wrong working counter): the line left OP"
            ),
        }
    }
}

impl std::error::Error for CyclicDriveError {}

impl From<MasterError> for CyclicDriveError {
    fn from(e: MasterError) -> Self {
        CyclicDriveError::Master(e)
    }
}

/// Where one drive's objects sit in its process image.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Layout {
    /// RxPDOs (1C12h).
    pub rx: Vec<PdoMapping>,
    /// TxPDOs (1C13h).
    pub tx: Vec<PdoMapping>,
    controlword: Option<usize>,
    target: Option<usize>,
    mode: Option<usize>,
    statusword: Option<usize>,
    position: Option<usize>,
    following: Option<usize>,
}

impl Layout {
    /// From the assignment and mapping.
    pub fn new(rx: Vec<PdoMapping>, tx: Vec<PdoMapping>) -> Layout {
        Layout {
            controlword: offset(&rx, 0x6040, 0),
            target: offset(&rx, 0x607A, 0),
            mode: offset(&rx, 0x6060, 0),
            statusword: offset(&tx, 0x6041, 0),
            position: offset(&tx, 0x6064, 0),
            following: offset(&tx, 0x60F4, 0),
            rx,
            tx,
        }
    }
}

/// One cycle's view of the drive.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Feedback {
    /// 6041h.
    pub statusword: u16,
    /// 6064h (0 when not mapped).
    pub position: i32,
    /// 60F4h, when mapped.
    pub following: Option<i32>,
}

impl Feedback {
    /// The CiA 402 state.
    pub fn state(&self) -> Option<State> {
        State::from_statusword(self.statusword)
    }
}

fn rd(b: &[u8], at: Option<usize>, n: usize) -> Option<i64> {
    let s = b.get(at?..at? + n)?;
    Some(match n {
        2 => i64::from(u16::from_le_bytes([s[0], s[1]])),
        _ => i64::from(i32::from_le_bytes([s[0], s[1], s[2], s[3]])),
    })
}

fn wr(b: &mut [u8], at: Option<usize>, v: &[u8]) {
    if let Some(s) = at.and_then(|o| b.get_mut(o..o + v.len())) {
        s.copy_from_slice(v);
    }
}

/// The line in OP with one drive under control.
pub struct CyclicDrive<'m> {
    m: &'m LineMaster,
    group: Group,
    position: usize,
    layout: Layout,
    cycle: Duration,
    expected_wkc: u16,
    bad_in_row: u32,
    /// Cycles exchanged in OP.
    pub cycles: u64,
    /// Cycles whose working counter was not the expected one (lost
    /// frames included).
    pub bad_wkc: u64,
    /// Cycles whose frame never came back (ethercrab's PDU timeout).
    pub lost: u64,
    /// What the last cycle read.
    pub fb: Feedback,
    controlword: u16,
    target: i32,
    mode_out: i8,
    /// A mode written to 6060h that 6061h has not been seen to show.
    mode_pending: Option<i8>,
    stop: Option<&'m AtomicBool>,
}

impl fmt::Debug for CyclicDrive<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CyclicDrive").field("position", &self.position).field("fb", &self.fb).finish()
    }
}

/// Reads a CoE value as an integer.
fn le(d: &[u8]) -> i64 {
    let u = d.iter().take(8).rev().fold(0u64, |a, &b| (a << 8) | u64::from(b));
    match d.len() {
        1 => i64::from(u as u8 as i8),
        2 => i64::from(u as u16 as i16),
        4 => i64::from(u as u32 as i32),
        _ => u as i64,
    }
}

impl<'m> CyclicDrive<'m> {
    /// Reads the drive's mapping, brings the line to OP (DC SYNC0 at
    /// `cycle` when `dc` is asked for and every slave supports it, else
    /// free run) and exchanges a first cycle. The drive must map 6040h and
    /// 6041h (the iPOS default does).
    pub async fn start(
        m: &'m LineMaster,
        mut group: PreOpGroup,
        position: usize,
        cycle: Duration,
        dc: bool,
        stop: Option<&'m AtomicBool>,
    ) -> Result<CyclicDrive<'m>, CyclicDriveError> {
        let md = m.main_device();
        let layout = {
            let sd = m.slave(&group, position)?;
            let rx = pdo_assignment(&sd, position, 0x1C12).await?;
            let tx = pdo_assignment(&sd, position, 0x1C13).await?;
            Layout::new(rx, tx)
        };
        if layout.controlword.is_none() || layout.statusword.is_none() {
            return Err(MasterError::Unsupported(format!(
                "slave {position} maps no controlword (6040h) in its RxPDOs or no statusword (6041h) in its TxPDOs: \
                 assign a PDO with them (1C12h/1C13h) in PRE-OP"
            ))
            .into());
        }
        let dc = dc && group.iter(md).all(|sd| sd.dc_support().enhanced());
        if !dc {
            m.sync_off(&group).await?;
        }
        let count = group.len();
        for mut sd in group.iter_mut(md) {
            if dc {
                sd.set_dc_sync(DcSync::Sync0);
            }
            // 100 ms process-data watchdog: a stalled master on a loaded
            // machine is not a lost connection.
            sd.register_write(RegisterAddress::SyncManagerWatchdog, 1000u16)
                .await
                .map_err(|e| MasterError::Ethercrab("setting the process-data watchdog".into(), e))?;
        }
        let e =
            |what: &'static str| move |e| CyclicDriveError::Master(MasterError::Ethercrab(what.into(), e));
        let group = group.into_pre_op_pdi(md).await.map_err(e("mapping the process data"))?;
        let mut expected_wkc = 0u16;
        for sd in group.iter(md) {
            let io = sd.io_raw();
            expected_wkc += if io.outputs().is_empty() { 0 } else { 2 } + u16::from(!io.inputs().is_empty());
        }
        let group = Self::to_op(m, group, dc, cycle).await;
        let group = match group {
            Ok(g) => g,
            Err(e) => {
                let all: Vec<usize> = (1..=count).collect();
                let to = if e.1 { AlState::Op } else { AlState::SafeOp };
                return Err(m.refusal(to, &all, e.0).await.into());
            }
        };
        let mut d = CyclicDrive {
            m,
            group,
            position,
            layout,
            cycle,
            expected_wkc,
            bad_in_row: 0,
            cycles: 0,
            bad_wkc: 0,
            lost: 0,
            fb: Feedback::default(),
            controlword: 0,
            target: 0,
            mode_out: 0,
            mode_pending: None,
            stop,
        };
        d.read_inputs();
        d.target = d.fb.position;
        d.cycle().await?;
        d.target = d.fb.position;
        Ok(d)
    }

    /// PRE-OP with PDI -> OP, DC or free run; on error, whether OP (not
    /// SAFE-OP) was being requested.
    async fn to_op(
        m: &LineMaster,
        group: SubDeviceGroup<MAX_SUBDEVICES, MAX_PDI, DefaultLock, PreOpPdi>,
        dc: bool,
        cycle: Duration,
    ) -> Result<Group, (MasterError, bool)> {
        let md = m.main_device();
        let e = |what: &'static str, op: bool| move |e| (MasterError::Ethercrab(what.into(), e), op);
        if dc {
            let cfg = DcConfiguration {
                start_delay: Duration::from_millis(100),
                sync0_period: cycle,
                sync0_shift: cycle / 2,
            };
            let g = group.configure_dc_sync(md, cfg).await.map_err(e("configuring DC SYNC0", false))?;
            let g = g.into_safe_op(md).await.map_err(e("PRE-OP -> SAFE-OP", false))?;
            let g = g.request_into_op(md).await.map_err(e("SAFE-OP -> OP", true))?;
            // Cycles until every slave reports OP (SYNC0 must run first).
            let mut n = 0u32;
            loop {
                let r = g.tx_rx_dc(md).await.map_err(e("process data", true))?;
                if r.all_op() {
                    break;
                }
                n += 1;
                if n > 5_000 {
                    let why = format!("the line did not reach OP within {n} DC cycles");
                    return Err((MasterError::Unsupported(why), true));
                }
                m.pace().sleep(r.extra.next_cycle_wait).await;
            }
            Ok(Group::Dc(g))
        } else {
            let g = group.into_safe_op(md).await.map_err(e("PRE-OP -> SAFE-OP", false))?;
            Ok(Group::Free(g.into_op(md).await.map_err(e("SAFE-OP -> OP", true))?))
        }
    }

    /// True when the line runs with DC SYNC0.
    pub fn dc(&self) -> bool {
        matches!(self.group, Group::Dc(..))
    }

    /// The image layout.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The working counter every cycle should have.
    pub fn expected_wkc(&self) -> u16 {
        self.expected_wkc
    }

    fn with_io<R>(&self, f: impl FnOnce(&[u8], &mut [u8]) -> R) -> Option<R> {
        let md = self.m.main_device();
        let i = self.position - 1;
        match &self.group {
            Group::Dc(g) => {
                let sd = g.subdevice(md, i).ok()?;
                let mut io = sd.io_raw_mut();
                let inputs = io.inputs().to_vec();
                Some(f(&inputs, io.outputs()))
            }
            Group::Free(g) => {
                let sd = g.subdevice(md, i).ok()?;
                let mut io = sd.io_raw_mut();
                let inputs = io.inputs().to_vec();
                Some(f(&inputs, io.outputs()))
            }
        }
    }

    fn read_inputs(&mut self) {
        let l = &self.layout;
        let (sw, pos, fe) = (l.statusword, l.position, l.following);
        if let Some(fb) = self.with_io(|i, _| Feedback {
            statusword: rd(i, sw, 2).unwrap_or(0) as u16,
            position: rd(i, pos, 4).unwrap_or(0) as i32,
            following: rd(i, fe, 4).map(|v| v as i32),
        }) {
            self.fb = fb;
        }
    }

    /// Sets the controlword sent from the next cycle on.
    pub fn set_controlword(&mut self, c: u16) {
        self.controlword = c;
    }

    /// Sets the target position (607Ah) sent from the next cycle on.
    pub fn set_target(&mut self, t: i32) {
        self.target = t;
    }

    /// One process-data cycle: outputs, exchange, inputs, then the wait
    /// until the next cycle.
    pub async fn cycle(&mut self) -> Result<Feedback, CyclicDriveError> {
        let (cwo, to, mo) = (self.layout.controlword, self.layout.target, self.layout.mode);
        let (c, t, m) = (self.controlword, self.target, self.mode_out);
        self.with_io(|_, o| {
            wr(o, cwo, &c.to_le_bytes());
            wr(o, to, &t.to_le_bytes());
            if m != 0 {
                wr(o, mo, &[m as u8]);
            }
        });
        let md = self.m.main_device();
        let r = match &self.group {
            Group::Dc(g) => g.tx_rx_dc(md).await.map(|r| (r.working_counter, r.extra.next_cycle_wait)),
            Group::Free(g) => g.tx_rx(md).await.map(|r| (r.working_counter, self.cycle)),
        };
        let (wkc, wait) = match r {
            Ok(r) => r,
            // A frame lost on the line is one bad cycle, not the end of
            // the line: the next cycle sends the outputs again.
            Err(ethercrab::error::Error::Timeout(ethercrab::error::TimeoutError::Pdu)) => {
                self.lost += 1;
                (0, self.cycle)
            }
            Err(e) => return Err(CyclicDriveError::Master(MasterError::Ethercrab("process data".into(), e))),
        };
        self.cycles += 1;
        if wkc == self.expected_wkc {
            self.bad_in_row = 0;
            self.read_inputs();
        } else {
            self.bad_wkc += 1;
            self.bad_in_row += 1;
            if self.bad_in_row >= 100 {
                return Err(CyclicDriveError::Lost { cycles: self.bad_in_row });
            }
        }
        self.m.pace().sleep(wait).await;
        Ok(self.fb)
    }

    fn interrupted(&self) -> bool {
        self.stop.is_some_and(|s| s.load(Ordering::Relaxed))
    }

    /// Reads an object of this drive over CoE (in OP too).
    pub async fn read(&self, index: u16, sub: u8) -> Result<i64, CyclicDriveError> {
        let md = self.m.main_device();
        let data = match &self.group {
            Group::Dc(g) => {
                let sd = g
                    .subdevice(md, self.position - 1)
                    .map_err(|e| MasterError::Ethercrab("slave".into(), e))?;
                sdo_read(&sd, self.position, index, sub).await?
            }
            Group::Free(g) => {
                let sd = g
                    .subdevice(md, self.position - 1)
                    .map_err(|e| MasterError::Ethercrab("slave".into(), e))?;
                sdo_read(&sd, self.position, index, sub).await?
            }
        };
        Ok(le(&data))
    }

    /// Writes an object of this drive over CoE.
    pub async fn write(&self, index: u16, sub: u8, data: &[u8]) -> Result<(), CyclicDriveError> {
        let md = self.m.main_device();
        match &self.group {
            Group::Dc(g) => {
                let sd = g
                    .subdevice(md, self.position - 1)
                    .map_err(|e| MasterError::Ethercrab("slave".into(), e))?;
                sdo_write(&sd, self.position, index, sub, data).await?;
            }
            Group::Free(g) => {
                let sd = g
                    .subdevice(md, self.position - 1)
                    .map_err(|e| MasterError::Ethercrab("slave".into(), e))?;
                sdo_write(&sd, self.position, index, sub, data).await?;
            }
        }
        Ok(())
    }

    /// Sets the mode of operation (6060h: in the image when mapped, else
    /// over CoE). In Operation enabled, waits for 6061h to show it; before
    /// it a drive may take the mode only once enabled (iPOS §4.2.4), so
    /// [`enable`](Self::enable) waits for 6061h instead.
    pub async fn set_mode(&mut self, m: i8) -> Result<(), CyclicDriveError> {
        if self.layout.mode.is_some() {
            self.mode_out = m;
        } else {
            self.write(0x6060, 0, &[m as u8]).await?;
        }
        self.mode_pending = Some(m);
        if mode::shown_at_once(self.fb.statusword) {
            self.confirm_mode().await?;
        }
        Ok(())
    }

    /// Waits up to 200 cycles for 6061h to show the mode
    /// [`set_mode`](Self::set_mode) wrote, unless it was seen already.
    async fn confirm_mode(&mut self) -> Result<(), CyclicDriveError> {
        let Some(m) = self.mode_pending else { return Ok(()) };
        let mut display = 0;
        for _ in 0..200 {
            self.cycle().await?;
            display = self.read(0x6061, 0).await? as i8;
            if display == m {
                self.mode_pending = None;
                return Ok(());
            }
        }
        let not_shown = ModeNotShown { mode: m, display, statusword: self.fb.statusword };
        Err(CyclicDriveError::Mode { slave: self.position, not_shown })
    }

    async fn fault(&self, what: &str) -> CyclicDriveError {
        CyclicDriveError::Fault {
            what: what.to_owned(),
            statusword: self.fb.statusword,
            error_code: self.read(0x603F, 0).await.ok().map(|c| c as u16),
        }
    }

    /// Brings the drive to operation enabled (a fault is reset first),
    /// holding the present position as the target; then waits for 6061h
    /// to show a mode [`set_mode`](Self::set_mode) wrote before.
    pub async fn enable(&mut self, timeout: Duration) -> Result<(), CyclicDriveError> {
        let limit = (timeout.as_nanos() / self.cycle.as_nanos().max(1)).max(1) as u64;
        let mut reset_tried = false;
        for k in 0..limit {
            if self.interrupted() {
                return Err(CyclicDriveError::Interrupted { what: "enable".into(), stopped: None });
            }
            let state = self.fb.state();
            self.target = self.fb.position;
            // The one enable sequence (`cia402::codes::EnableStep`), one
            // controlword per cycle; a fault reset is a rising edge of bit 7.
            let step = EnableStep::from(state);
            match step {
                EnableStep::Done => return self.confirm_mode().await,
                EnableStep::FaultReset => reset_tried = true,
                _ => {}
            }
            let c = step.cyclic_controlword(k % 2 == 0);
            self.controlword = c;
            self.cycle().await?;
        }
        if self.fb.state() == Some(State::Fault) && reset_tried {
            return Err(self.fault("enable (fault reset did not clear the fault)").await);
        }
        Err(CyclicDriveError::Timeout {
            what: format!("enable (statusword {:04X}h)", self.fb.statusword),
            after: timeout,
            stopped: None,
        })
    }

    /// Disables the drive (CiA 402 "disable voltage": switch on disabled).
    pub async fn disable(&mut self, timeout: Duration) -> Result<(), CyclicDriveError> {
        let limit = (timeout.as_nanos() / self.cycle.as_nanos().max(1)).max(1) as u64;
        self.controlword = cw::DISABLE_VOLTAGE;
        for _ in 0..limit {
            self.cycle().await?;
            if matches!(self.fb.state(), Some(State::SwitchOnDisabled) | Some(State::Fault)) {
                return Ok(());
            }
        }
        Err(CyclicDriveError::Timeout { what: "disable".into(), after: timeout, stopped: None })
    }

    /// Halts a motion (bit 8), then quick-stops if it does not come to
    /// rest within 2 s; says which.
    pub async fn halt(&mut self) -> Stop {
        self.controlword |= cw::HALT;
        self.controlword &= !cw::NEW_SET_POINT;
        let limit = (2_000_000_000 / self.cycle.as_nanos().max(1)).max(2) as u32;
        let mut still = 0u32;
        let mut last = self.fb.position;
        for _ in 0..limit {
            if self.cycle().await.is_err() {
                break;
            }
            // At rest: target reached (halt reached, CiA 402-2 §6.2.2) or no
            // movement for 20 cycles.
            still = if self.fb.position == last { still + 1 } else { 0 };
            last = self.fb.position;
            if self.fb.statusword & sw::TARGET_REACHED != 0 && still >= 2 || still >= 20 {
                return Stop::Halted;
            }
        }
        self.controlword = cw::QUICK_STOP;
        for _ in 0..limit {
            if self.cycle().await.is_err() {
                break;
            }
            if matches!(self.fb.state(), Some(State::QuickStopActive) | Some(State::SwitchOnDisabled)) {
                return Stop::QuickStopped;
            }
        }
        Stop::Unconfirmed
    }

    /// Homing with `method` (6098h) in homing mode; returns the position
    /// when homing is attained. `progress` sees every cycle.
    pub async fn home(
        &mut self,
        method: i8,
        timeout: Duration,
        mut progress: impl FnMut(&Feedback),
    ) -> Result<i32, CyclicDriveError> {
        self.set_mode(mode::HM).await?;
        self.write(0x6098, 0, &[method as u8]).await?;
        self.enable(Duration::from_secs(2)).await?;
        self.controlword = cw::ENABLE_OPERATION;
        self.cycle().await?;
        // Bit 4 starts homing (CiA 402-2 §6.6).
        self.controlword = cw::ENABLE_OPERATION | cw::NEW_SET_POINT;
        let limit = (timeout.as_nanos() / self.cycle.as_nanos().max(1)).max(1) as u64;
        let mut started = false;
        for k in 0..limit {
            self.cycle().await?;
            progress(&self.fb);
            let s = self.fb.statusword;
            if self.interrupted() {
                let stopped = Some(self.halt().await);
                return Err(CyclicDriveError::Interrupted {
                    what: format!("homing (method {method})"),
                    stopped,
                });
            }
            if self.fb.state() == Some(State::Fault) {
                return Err(self.fault(&format!("homing (method {method})")).await);
            }
            if s & sw::MODE_13 != 0 {
                let stopped = Some(self.halt().await);
                return Err(CyclicDriveError::Homing { statusword: s, stopped });
            }
            // Homing attained and target reached, seen after the bits left
            // that state or (a homing done within a cycle) three cycles on.
            started |= s & sw::MODE_12 == 0 || s & sw::TARGET_REACHED == 0;
            if s & sw::MODE_12 != 0 && s & sw::TARGET_REACHED != 0 && (started || k >= 3) {
                self.controlword = cw::ENABLE_OPERATION;
                self.cycle().await?;
                return Ok(self.fb.position);
            }
        }
        let stopped = Some(self.halt().await);
        Err(CyclicDriveError::Timeout { what: format!("homing (method {method})"), after: timeout, stopped })
    }

    /// A profile-position move to `target` (absolute, or relative), at
    /// `velocity` (6081h) if given; returns the position at target reached.
    pub async fn move_to(
        &mut self,
        target: i32,
        relative: bool,
        velocity: Option<u32>,
        timeout: Duration,
        mut progress: impl FnMut(&Feedback),
    ) -> Result<i32, CyclicDriveError> {
        if let Some(v) = velocity {
            self.write(0x6081, 0, &v.to_le_bytes()).await?;
        }
        if self.read(0x6081, 0).await? == 0 {
            return Err(MasterError::Unsupported(format!(
                "slave {}: profile velocity 6081h is 0, the move would never end: give --velocity",
                self.position
            ))
            .into());
        }
        self.set_mode(mode::PP).await?;
        self.enable(Duration::from_secs(2)).await?;
        let goal = if relative { self.fb.position.saturating_add(target) } else { target };
        if self.layout.target.is_some() {
            self.target = target;
        } else {
            self.write(0x607A, 0, &target.to_le_bytes()).await?;
        }
        let base = cw::ENABLE_OPERATION | if relative { cw::RELATIVE } else { 0 };
        let window = self.read(0x6067, 0).await.unwrap_or(u32::MAX.into());
        self.controlword = base | cw::NEW_SET_POINT;
        let limit = (timeout.as_nanos() / self.cycle.as_nanos().max(1)).max(1) as u64;
        let mut acked = false;
        for _ in 0..limit {
            self.cycle().await?;
            progress(&self.fb);
            let s = self.fb.statusword;
            if self.interrupted() {
                let stopped = Some(self.halt().await);
                return Err(CyclicDriveError::Interrupted { what: format!("move to {goal}"), stopped });
            }
            if self.fb.state() == Some(State::Fault) {
                return Err(self.fault(&format!("move to {goal}")).await);
            }
            if !acked {
                // Set-point acknowledge (bit 12), then the new-set-point bit back to 0.
                if s & sw::MODE_12 != 0 {
                    acked = true;
                    self.controlword = base;
                }
                continue;
            }
            // A relative target counts from the drive's own reference (60F2h):
            // only its target-reached bit says where that is.
            let close = relative
                || window >= i64::from(u32::MAX)
                || (i64::from(self.fb.position) - i64::from(goal)).abs() <= window.max(0);
            if s & sw::MODE_12 == 0 && s & sw::TARGET_REACHED != 0 && close {
                return Ok(self.fb.position);
            }
        }
        let stopped = Some(self.halt().await);
        Err(CyclicDriveError::Timeout { what: format!("move to {goal}"), after: timeout, stopped })
    }

    /// Cyclic synchronous position: one target per cycle from `targets`;
    /// `sample` sees each cycle's target and feedback. Returns the cycles run.
    pub async fn csp(
        &mut self,
        targets: impl IntoIterator<Item = i32>,
        mut sample: impl FnMut(i32, &Feedback),
    ) -> Result<u64, CyclicDriveError> {
        self.target = self.fb.position;
        self.set_mode(mode::CSP).await?;
        self.enable(Duration::from_secs(2)).await?;
        self.controlword = cw::ENABLE_OPERATION;
        let mut n = 0;
        for t in targets {
            if self.interrupted() {
                // Hold where it is: no more set-points.
                self.target = self.fb.position;
                let stopped = Some(self.halt().await);
                return Err(CyclicDriveError::Interrupted { what: "csp".into(), stopped });
            }
            self.target = t;
            self.cycle().await?;
            if self.fb.state() == Some(State::Fault) {
                return Err(self.fault("csp").await);
            }
            sample(t, &self.fb);
            n += 1;
        }
        Ok(n)
    }

    /// Leaves OP for SAFE-OP (the drive reacts as its 6007h says).
    pub async fn stop(self) -> Result<(), CyclicDriveError> {
        let md = self.m.main_device();
        let e = |e| CyclicDriveError::Master(MasterError::Ethercrab("OP -> SAFE-OP".into(), e));
        match self.group {
            Group::Dc(g) => {
                g.into_safe_op(md).await.map_err(e)?;
            }
            Group::Free(g) => {
                g.into_safe_op(md).await.map_err(e)?;
            }
        }
        Ok(())
    }
}
