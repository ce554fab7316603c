//! The slave firmware framework: what runs on the PDI of an [`Esc`],
//! generic over a [`SlaveApp`].
//!
//! [`Slave`] owns an ESC and an application. Its [`Slave::poll`] takes the
//! ESC's events and does the EtherCAT side of a slave stack:
//!
//! * **EtherCAT state machine** (ETG.1000.6 §6.4.1): INIT, PRE-OP,
//!   SAFE-OP, OP, BOOT with the allowed transitions; refused requests set
//!   the error indicator (AL status bit 4) and an AL status code, and stay
//!   in the current state. With the error indicator set, only a request
//!   with the acknowledge bit (AL control bit 4) or a request for INIT is
//!   processed; others are ignored until acknowledged. Checks: INIT →
//!   PRE-OP validates SM0/SM1 against the SII mailbox (0x0016); INIT → BOOT
//!   needs bootstrap support (0x0013) and the SII bootstrap mailbox
//!   (0x0015); PRE-OP → SAFE-OP validates the outputs/inputs sync managers
//!   against the application's current mapping (enabled, 3-buffer mode,
//!   direction, start address from the SII, length: 0x001D/0x001E/0x0029)
//!   and the DC registers against [`SyncSupport`] (0x0027, 0x0028, 0x0030,
//!   0x0035, 0x0036); then the application decides. SAFE-OP → OP reads
//!   the DC registers again (SOEM activates SYNC0 after its `config_map`
//!   has requested SAFE-OP) with the same checks, then waits for the first
//!   SYNC0 in DC mode and, if configured, for outputs.
//! * **Errors while running**: the process-data watchdog in OP → SAFE-OP +
//!   0x001B; SYNC0 pulses stopping in DC OP → SAFE-OP + 0x002C; an
//!   application error ([`SlaveApp::take_error`]) → the state it names.
//! * **Mailbox**: see [`mailbox`](self::MailboxOut).
//! * **Process data**: in SAFE-OP inputs are produced, in OP outputs are
//!   also consumed. Free run: outputs are applied at the outputs SM event
//!   and inputs are produced again each time the master has read them
//!   (so the master always reads inputs latched before its frame).
//!   DC: at every SYNC0 the latest outputs are applied, then
//!   [`SlaveApp::sync0`] runs, then inputs are latched.
//!
//! **Device emulation** (0x0141 bit 0, set from SII word 0 as on an EK1100
//! or an EL2004 without a microcontroller): the ESC sets the AL status
//! itself; the firmware follows that state without checks and moves the
//! process data of the sync managers as the master configured them (an
//! outputs SM on the digital output register 0x0F00 is read after every
//! frame).
//!
//! Sync managers are found from the SII SyncManager category (types 1–4);
//! without one, SM0/SM1 are the mailbox and SM2/SM3 the process data (or
//! SM0/SM1 for a device without mailbox).

mod app;
mod esm;
mod mailbox;

pub use app::{ProcessDataSizes, SlaveApp, SlaveConfig, SyncConfig, SyncMode, SyncSupport, Transition};
pub use esm::{AlState, AlStatusCode, path_allowed};
pub use mailbox::{HEADER_LEN as MAILBOX_HEADER_LEN, MailboxOut, mailbox_error, mailbox_type};

use crate::esc::Esc;
use crate::events::EscEvent;
use crate::segment::SegmentDevice;
use crate::sii::{MailboxArea, sm_type};
use alloc::vec::Vec;
use drivebus_base::{Instant, earliest};
use mailbox::Mailbox;

/// Where the sync managers are, from the SII.
#[derive(Debug, Clone, Copy, Default)]
struct Layout {
    mbx_out: usize,
    mbx_in: usize,
    outputs: Option<(usize, u16)>,
    inputs: Option<(usize, u16)>,
    mailbox: MailboxArea,
    bootstrap: MailboxArea,
}

impl Layout {
    fn from_esc(esc: &Esc) -> Layout {
        let c = esc.sii_image().parse().unwrap_or_default();
        let find = |t: u8| c.sync_managers.iter().position(|s| s.sm_type == t);
        let start = |i: usize| c.sync_managers.get(i).map_or(0, |s| s.start);
        let has_mbx = c.mailbox.rx_size > 0 && c.mailbox.tx_size > 0;
        let (dout, din) = if has_mbx { (2, 3) } else { (0, 1) };
        let outputs = find(sm_type::OUTPUTS).or(c.sync_managers.is_empty().then_some(dout));
        let inputs = find(sm_type::INPUTS).or(c.sync_managers.is_empty().then_some(din));
        Layout {
            mbx_out: find(sm_type::MAILBOX_OUT).unwrap_or(0),
            mbx_in: find(sm_type::MAILBOX_IN).unwrap_or(1),
            outputs: outputs.map(|i| (i, start(i))),
            inputs: inputs.map(|i| (i, start(i))),
            mailbox: c.mailbox,
            bootstrap: c.bootstrap_mailbox,
        }
    }

    fn mailbox_for(&self, state: AlState, depth: usize) -> Mailbox {
        let m = if state == AlState::Boot { self.bootstrap } else { self.mailbox };
        Mailbox::new((m.rx_offset, m.rx_size), (m.tx_offset, m.tx_size), self.mbx_in, depth)
    }
}

/// An ESC with slave firmware on its PDI.
#[derive(Debug)]
pub struct Slave<A> {
    esc: Esc,
    app: A,
    cfg: SlaveConfig,
    layout: Layout,
    mailbox: Mailbox,
    state: AlState,
    error: Option<AlStatusCode>,
    sync: SyncConfig,
    out_buf: Vec<u8>,
    in_buf: Vec<u8>,
    out_addr: u16,
    in_addr: u16,
    outputs_valid: bool,
    op_pending: Option<Instant>,
    sync0_seen: bool,
    last_sync0: Option<Instant>,
}

impl<A: SlaveApp> Slave<A> {
    /// Puts firmware on `esc`. The slave starts in INIT.
    pub fn new(esc: Esc, app: A, cfg: SlaveConfig) -> Self {
        let layout = Layout::from_esc(&esc);
        let mailbox = layout.mailbox_for(AlState::Init, cfg.queue_depth);
        let mut s = Slave {
            esc,
            app,
            cfg,
            layout,
            mailbox,
            state: AlState::Init,
            error: None,
            sync: SyncConfig::default(),
            out_buf: Vec::new(),
            in_buf: Vec::new(),
            out_addr: 0,
            in_addr: 0,
            outputs_valid: false,
            op_pending: None,
            sync0_seen: false,
            last_sync0: None,
        };
        s.write_status();
        s
    }

    /// The ESC.
    pub fn esc(&self) -> &Esc {
        &self.esc
    }

    /// The ESC, mutable (tests, fault injection).
    pub fn esc_mut(&mut self) -> &mut Esc {
        &mut self.esc
    }

    /// The application.
    pub fn app(&self) -> &A {
        &self.app
    }

    /// The application, mutable.
    pub fn app_mut(&mut self) -> &mut A {
        &mut self.app
    }

    /// Current AL state.
    pub fn state(&self) -> AlState {
        self.state
    }

    /// The error being indicated, if any.
    pub fn error(&self) -> Option<AlStatusCode> {
        self.error
    }

    /// The synchronisation configuration latched at PRE-OP → SAFE-OP.
    pub fn sync_config(&self) -> &SyncConfig {
        &self.sync
    }

    /// Mailbox messages dropped because a queue was full or a message too
    /// long.
    pub fn mailbox_dropped(&self) -> u32 {
        self.mailbox.dropped
    }

    /// Takes ESC events, runs the state machine, mailbox and process data,
    /// and the application's timers. Returns the next deadline.
    pub fn poll(&mut self, now: Instant) -> Option<Instant> {
        self.esc.poll(now);
        self.follow_emulated_state(now);
        while let Some(ev) = self.esc.pop_event() {
            self.handle(ev, now);
        }
        self.follow_emulated_state(now);
        self.emulated_outputs(now);
        if let Some((code, to)) = self.app.take_error() {
            self.fail(code, to, now);
        }
        self.check_pending_op(now);
        self.check_sync_loss(now);
        let mbx = self.mailbox_active();
        if mbx {
            self.mailbox.pump(&mut self.esc, now, self.cfg.unsolicited_quiet);
        }
        let app_deadline = {
            let mut out = self.mailbox.out();
            self.app.poll(now, &mut out)
        };
        let mut deadline = earliest(self.esc.next_deadline(), app_deadline);
        if mbx {
            self.mailbox.pump(&mut self.esc, now, self.cfg.unsolicited_quiet);
            let quiet_end = self.mailbox.last_activity + self.cfg.unsolicited_quiet;
            if self.mailbox.out().pending().1 > 0 && quiet_end > now {
                deadline = earliest(deadline, Some(quiet_end));
            }
        }
        if let Some(since) = self.op_pending {
            let t = match self.cfg.op_needs_outputs {
                Some(d) if !self.outputs_valid && !self.out_buf.is_empty() => d.min(self.cfg.sync_timeout),
                _ => self.cfg.sync_timeout,
            };
            deadline = earliest(deadline, Some(since + t));
        }
        earliest(deadline, self.sync_loss_deadline())
    }

    fn mailbox_active(&self) -> bool {
        self.mailbox.present() && self.state != AlState::Init
    }

    fn is_dc(&self) -> bool {
        self.sync.mode != SyncMode::FreeRun
    }

    fn process_data_active(&self) -> bool {
        matches!(self.state, AlState::SafeOp | AlState::Op)
    }

    fn handle(&mut self, ev: EscEvent, now: Instant) {
        match ev {
            EscEvent::EscReset => {
                if self.error.take().is_some() {
                    self.app.al_error(None, now);
                }
                self.op_pending = None;
                self.enter(AlState::Init, now);
            }
            EscEvent::AlControl => {
                let mut b = [0u8; 2];
                self.esc.pdi_read(0x0120, &mut b);
                self.al_control(b[0], now);
            }
            EscEvent::ProcessDataWatchdog => {
                let mut b = [0u8];
                self.esc.pdi_read(0x0440, &mut b); // acknowledges the AL event
                if self.state == AlState::Op {
                    self.app.watchdog_expired(now);
                    self.fail(AlStatusCode::SM_WATCHDOG, AlState::SafeOp, now);
                }
            }
            EscEvent::Sync0 { system_time, at, .. } => self.on_sync0(at, system_time),
            EscEvent::Sync1 { system_time, at, .. }
                if self.process_data_active() && self.sync.mode == SyncMode::DcSync01 =>
            {
                self.app.sync1(at, system_time);
            }
            EscEvent::SmChanged => {
                if self.mailbox_active() {
                    self.mailbox.on_sm_change(&mut self.esc, now);
                } else {
                    let mut b = [0u8];
                    self.esc.pdi_read(0x0806 + 8 * self.layout.mbx_in as u16, &mut b);
                }
            }
            EscEvent::SmWritten(n) => {
                let n = usize::from(n);
                if n == self.layout.mbx_out && self.mailbox_active() {
                    self.on_request(now);
                } else if self.layout.outputs.is_some_and(|(o, _)| o == n) && self.process_data_active() {
                    self.on_outputs(now);
                }
            }
            EscEvent::SmRead(n) => {
                let n = usize::from(n);
                if n == self.layout.mbx_in && self.mailbox_active() {
                    self.mailbox.on_read(now);
                } else if self.layout.inputs.is_some_and(|(i, _)| i == n)
                    && self.process_data_active()
                    && !self.is_dc()
                {
                    self.latch_inputs(now);
                }
            }
            _ => {}
        }
    }

    /// Device emulation (0x0141 bit 0, from SII word 0): the ESC copies AL
    /// control into AL status itself, as on an EL2004 or an EK1100 without
    /// a microcontroller. The firmware does no ESM checks then; it follows
    /// the state the ESC shows and moves the process data of the sync
    /// managers as they are configured.
    fn follow_emulated_state(&mut self, now: Instant) {
        if !self.esc.device_emulation() {
            return;
        }
        let Some(to) = AlState::from_code(self.esc.peek_u16(0x0130) as u8) else { return };
        let from = self.state;
        if to == from {
            return;
        }
        if matches!(to, AlState::SafeOp | AlState::Op) && !self.process_data_active() {
            let sizes = self.app.process_data_sizes();
            let area = |sm: Option<(usize, u16)>, bytes: usize| {
                sm.and_then(|(n, _)| self.esc.sync_manager(n))
                    .filter(|s| s.enabled && bytes > 0)
                    .map_or((0, 0), |s| (s.start, bytes))
            };
            let (out_addr, ob) = area(self.layout.outputs, sizes.output_bytes());
            let (in_addr, ib) = area(self.layout.inputs, sizes.input_bytes());
            (self.out_addr, self.in_addr) = (out_addr, in_addr);
            self.out_buf.clear();
            self.out_buf.resize(ob, 0);
            self.in_buf.clear();
            self.in_buf.resize(ib, 0);
            self.sync = SyncConfig { outputs_len: ob as u16, inputs_len: ib as u16, ..SyncConfig::default() };
        }
        if to != AlState::Op {
            self.outputs_valid = false;
        }
        self.state = to;
        self.app.state_changed(from, to, now);
        if !matches!(from, AlState::SafeOp | AlState::Op) && self.process_data_active() {
            self.latch_inputs(now);
        }
    }

    /// Device emulation with the outputs SM on the digital output register
    /// (0x0F00–0x0F03, an EL2xxx): the ESC has no buffer event there, so
    /// the value is looked at after every frame and handed on when it
    /// changed.
    fn emulated_outputs(&mut self, now: Instant) {
        let n = self.out_buf.len();
        if !self.esc.device_emulation()
            || self.state != AlState::Op
            || n == 0
            || n > 4
            || self.out_addr >= 0x1000
        {
            return;
        }
        let mut v = [0u8; 4];
        self.esc.pdi_read(self.out_addr, &mut v[..n]);
        if !self.outputs_valid || v[..n] != self.out_buf[..] {
            self.out_buf.copy_from_slice(&v[..n]);
            self.outputs_valid = true;
            self.app.outputs(&self.out_buf, now);
        }
    }

    fn on_request(&mut self, now: Instant) {
        if let Some(len) = self.mailbox.take_request(&mut self.esc, now) {
            let (req, mut out) = self.mailbox.request_and_out(len);
            self.app.mailbox(req, now, &mut out);
        }
    }

    fn on_outputs(&mut self, now: Instant) {
        if self.out_buf.is_empty() || !self.esc.pdi_read(self.out_addr, &mut self.out_buf) {
            return;
        }
        self.outputs_valid = true;
        self.app.outputs_received(now);
        if self.state == AlState::Op && !self.is_dc() {
            self.app.outputs(&self.out_buf, now);
        }
    }

    fn on_sync0(&mut self, at: Instant, system_time: u64) {
        self.sync0_seen = true;
        self.last_sync0 = Some(at);
        if !self.process_data_active() {
            return;
        }
        if self.state == AlState::Op && self.is_dc() && self.outputs_valid {
            self.app.outputs(&self.out_buf, at);
        }
        self.app.sync0(at, system_time);
        if self.is_dc() {
            self.latch_inputs(at);
        }
    }

    fn latch_inputs(&mut self, now: Instant) {
        if self.in_buf.is_empty() {
            return;
        }
        self.app.inputs(&mut self.in_buf, now);
        self.esc.pdi_write(self.in_addr, &self.in_buf);
    }

    fn al_control(&mut self, v: u8, now: Instant) {
        let ack = v & 0x10 != 0;
        let requested = AlState::from_code(v);
        if self.error.is_some() {
            if !ack && requested != Some(AlState::Init) {
                return;
            }
            self.error = None;
            self.app.al_error(None, now);
        }
        self.op_pending = None;
        let Some(to) = requested else {
            return self.set_error(AlStatusCode::UNKNOWN_STATE, now);
        };
        if to == self.state {
            return self.write_status();
        }
        if !path_allowed(self.state, to) {
            let code = if to == AlState::Boot && !self.app.bootstrap_supported() {
                AlStatusCode::BOOTSTRAP_NOT_SUPPORTED
            } else {
                AlStatusCode::INVALID_STATE_CHANGE
            };
            return self.set_error(code, now);
        }
        if self.state.is_down_to(to) {
            return self.enter(to, now);
        }
        match self.check_up(to) {
            Ok(()) if to == AlState::Op => {
                self.op_pending = Some(now);
                self.write_status();
                self.check_pending_op(now);
            }
            Ok(()) => self.enter(to, now),
            Err(code) => self.set_error(code, now),
        }
    }

    fn check_up(&mut self, to: AlState) -> Result<(), AlStatusCode> {
        let t = Transition { from: self.state, to };
        match (self.state, to) {
            (AlState::Init, AlState::PreOp) if self.layout.mailbox.rx_size > 0 => {
                self.check_mailbox(self.layout.mailbox, AlStatusCode::INVALID_MAILBOX_CONFIG)?;
            }
            (AlState::Init, AlState::Boot) => {
                if !self.app.bootstrap_supported() {
                    return Err(AlStatusCode::BOOTSTRAP_NOT_SUPPORTED);
                }
                self.check_mailbox(self.layout.bootstrap, AlStatusCode::INVALID_MAILBOX_CONFIG_BOOT)?;
            }
            (AlState::PreOp, AlState::SafeOp) => {
                let cfg = self.check_process_data()?;
                self.app.check_transition(t, &cfg)?;
                self.sync = cfg;
                return Ok(());
            }
            (AlState::SafeOp, AlState::Op) => {
                // SOEM's order: `ec_config_map` already requests SAFE-OP,
                // `ec_configdc` and `ec_dcsync0` follow. A DC set-up made
                // in SAFE-OP is taken here (the application hears it with
                // the new configuration), else the drive would run
                // SM-synchronous beside running SYNC0 pulses.
                let cfg = self.dc_setup(self.sync)?;
                self.app.check_transition(t, &cfg)?;
                self.sync = cfg;
                return Ok(());
            }
            _ => {}
        }
        self.app.check_transition(t, &self.sync)
    }

    fn check_mailbox(&self, m: MailboxArea, code: AlStatusCode) -> Result<(), AlStatusCode> {
        let ok = |n: usize, start: u16, len: u16, ctrl: u8| {
            self.esc
                .sync_manager(n)
                .is_some_and(|s| s.enabled && s.start == start && s.length == len && s.control & 0x0F == ctrl)
        };
        let good = m.rx_size > 0
            && ok(self.layout.mbx_out, m.rx_offset, m.rx_size, 0x06)
            && ok(self.layout.mbx_in, m.tx_offset, m.tx_size, 0x02);
        if good { Ok(()) } else { Err(code) }
    }

    /// The synchronisation the DC registers set up (0x0981 activation,
    /// 0x09A0/0x09A4 cycles), checked against the application's support:
    /// `cfg` with its mode and cycles replaced.
    fn dc_setup(&self, mut cfg: SyncConfig) -> Result<SyncConfig, AlStatusCode> {
        let support = self.app.sync_support();
        let act = self.esc.peek_u16(0x0980).to_le_bytes()[1];
        (cfg.mode, cfg.sync0_cycle, cfg.sync1_cycle) = (SyncMode::FreeRun, 0, 0);
        if act & 0x01 != 0 {
            if act & 0x02 == 0 {
                return Err(AlStatusCode::INVALID_DC_SYNC_CONFIG);
            }
            let sync1 = act & 0x04 != 0;
            cfg.mode = if sync1 { SyncMode::DcSync01 } else { SyncMode::DcSync0 };
            if (sync1 && !support.dc_sync01) || (!sync1 && !support.dc_sync0) {
                return Err(AlStatusCode::SYNC_MODE_NOT_SUPPORTED);
            }
            let mut c = [0u8; 8];
            self.esc.peek(0x09A0, &mut c);
            cfg.sync0_cycle = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            cfg.sync1_cycle = u32::from_le_bytes([c[4], c[5], c[6], c[7]]);
            let cycle = u64::from(cfg.sync0_cycle);
            let step = support.cycle_step.as_nanos() as u64;
            if cycle == 0 || (step > 0 && !cycle.is_multiple_of(step)) {
                return Err(AlStatusCode::DC_INVALID_SYNC_CYCLE_TIME);
            }
            if cycle < support.min_cycle.as_nanos() as u64 {
                return Err(AlStatusCode::DC_SYNC0_CYCLE_TIME);
            }
        } else if !support.free_run {
            return Err(AlStatusCode::FREE_RUN_NOT_SUPPORTED);
        }
        Ok(cfg)
    }

    fn check_process_data(&mut self) -> Result<SyncConfig, AlStatusCode> {
        let sizes = self.app.process_data_sizes();
        let mut cfg = self.dc_setup(SyncConfig::default())?;
        let free_run = cfg.mode == SyncMode::FreeRun;
        let check = |sm: Option<(usize, u16)>,
                     bytes: usize,
                     dir: u8,
                     code: AlStatusCode|
         -> Result<u16, AlStatusCode> {
            let Some((n, sii_start)) = sm else {
                return if bytes == 0 { Ok(0) } else { Err(code) };
            };
            let s = self.esc.sync_manager(n).ok_or(code)?;
            if bytes == 0 {
                return if s.enabled && s.length > 0 { Err(code) } else { Ok(0) };
            }
            if !s.enabled || usize::from(s.length) != bytes || s.control & 0x0C != dir {
                return Err(code);
            }
            if sii_start != 0 && s.start != sii_start {
                return Err(code);
            }
            if s.control & 0x03 != 0 {
                return Err(if free_run { AlStatusCode::FREE_RUN_NEEDS_3_BUFFER } else { code });
            }
            Ok(s.start)
        };
        let ob = sizes.output_bytes();
        let ib = sizes.input_bytes();
        self.out_addr = check(self.layout.outputs, ob, 0x04, AlStatusCode::INVALID_OUTPUT_CONFIG)?;
        self.in_addr = check(self.layout.inputs, ib, 0x00, AlStatusCode::INVALID_INPUT_CONFIG)?;
        cfg.outputs_len = ob as u16;
        cfg.inputs_len = ib as u16;
        if let Some((o, _)) = self.layout.outputs
            && ob > 0
            && self.esc.sync_manager(o).is_some_and(|s| s.control & 0x40 != 0)
        {
            cfg.watchdog = self.esc.watchdog_time(0x0420);
        }
        self.out_buf.clear();
        self.out_buf.resize(ob, 0);
        self.in_buf.clear();
        self.in_buf.resize(ib, 0);
        Ok(cfg)
    }

    fn check_pending_op(&mut self, now: Instant) {
        let Some(since) = self.op_pending else { return };
        if self.state != AlState::SafeOp {
            self.op_pending = None;
            return;
        }
        let need_outputs =
            self.cfg.op_needs_outputs.is_some() && !self.out_buf.is_empty() && !self.outputs_valid;
        let need_sync = self.is_dc() && !self.sync0_seen;
        if !need_outputs && !need_sync {
            self.op_pending = None;
            self.enter(AlState::Op, now);
        } else if need_outputs && self.cfg.op_needs_outputs.is_some_and(|d| now >= since + d) {
            self.op_pending = None;
            self.set_error(AlStatusCode::SM_WATCHDOG, now);
        } else if need_sync && now >= since + self.cfg.sync_timeout {
            self.op_pending = None;
            self.set_error(AlStatusCode::NO_SYNC_ERROR, now);
        }
    }

    fn sync_loss_deadline(&self) -> Option<Instant> {
        if self.state != AlState::Op || !self.is_dc() || self.cfg.sync_loss_cycles == 0 {
            return None;
        }
        let cycle = drivebus_base::Duration::from_nanos(u64::from(self.sync.sync0_cycle));
        self.last_sync0.map(|t| t + cycle * self.cfg.sync_loss_cycles)
    }

    fn check_sync_loss(&mut self, now: Instant) {
        if self.sync_loss_deadline().is_some_and(|d| now >= d) {
            self.app.watchdog_expired(now);
            self.fail(AlStatusCode::FATAL_SYNC_ERROR, AlState::SafeOp, now);
        }
    }

    /// Goes down to `to` (if below the current state) and indicates `code`.
    fn fail(&mut self, code: AlStatusCode, to: AlState, now: Instant) {
        self.op_pending = None;
        if self.state.is_down_to(to) {
            self.enter(to, now);
        }
        self.set_error(code, now);
    }

    fn enter(&mut self, to: AlState, now: Instant) {
        let from = self.state;
        if to == AlState::Init || (to == AlState::Boot) != (from == AlState::Boot) {
            self.mailbox = self.layout.mailbox_for(to, self.cfg.queue_depth);
        }
        if !matches!(to, AlState::SafeOp | AlState::Op) {
            self.outputs_valid = false;
            self.sync0_seen = false;
            self.last_sync0 = None;
        }
        self.state = to;
        self.write_status();
        self.app.state_changed(from, to, now);
        if from == AlState::PreOp && to == AlState::SafeOp {
            self.latch_inputs(now);
        }
    }

    fn set_error(&mut self, code: AlStatusCode, now: Instant) {
        self.app.al_error(Some(code), now);
        self.error = Some(code);
        self.write_status();
    }

    fn write_status(&mut self) {
        let err = u8::from(self.error.is_some()) << 4;
        self.esc.pdi_write(0x0130, &[self.state as u8 | err, 0]);
        let code = self.error.unwrap_or(AlStatusCode::NO_ERROR).0;
        self.esc.pdi_write(0x0134, &code.to_le_bytes());
    }
}

impl<A: SlaveApp + 'static> SegmentDevice for Slave<A> {
    fn esc(&self) -> &Esc {
        &self.esc
    }
    fn esc_mut(&mut self) -> &mut Esc {
        &mut self.esc
    }
    fn poll(&mut self, now: Instant) -> Option<Instant> {
        Slave::poll(self, now)
    }
    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }
    fn power_on(&mut self) {
        self.esc.reset();
        self.app.power_on();
    }
}

#[cfg(test)]
mod tests;
