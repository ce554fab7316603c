//! [`DriveApp`]: a personality's node and drive as the application of an
//! EtherCAT slave ([`drivebus_esc::slave::SlaveApp`]).

use super::access::DriveAccess;
use super::image::{Image, al_code};
use super::sync::SyncParams;
use drivebus_can::{Device, Duration, Frame, Instant, earliest};
use drivebus_coe::{MailboxServer, ObjectAccess};
use drivebus_esc::slave::{
    AlState, AlStatusCode, MailboxOut, ProcessDataSizes, SlaveApp, SyncConfig, SyncMode, SyncSupport,
    Transition,
};
use drivebus_node::MemoryStorage;
use drivebus_od::Value;
use drivebus_personality::ecat::{self, DriveFiles, EcatFacts, EsmEvent};
use drivebus_personality::machine::{Change, MachineError};
use drivebus_personality::{PersonalityDevice, Profile};

/// The CoE emergency service in a CoE header (ETG.1000.6).
const COE_EMERGENCY: u8 = 0x01;

/// Counters of a drive slave.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DriveStats {
    /// Output updates applied to the drive.
    pub outputs_applied: u64,
    /// Input updates sampled.
    pub inputs_sampled: u64,
    /// RxPDO entries the write path refused.
    pub outputs_refused: u64,
    /// CoE emergencies queued.
    pub emergencies: u64,
    /// Emergencies the CoE queue had no room for.
    pub emergencies_lost: u64,
    /// SYNC0 pulses taken in SAFE-OP and OP.
    pub sync0_pulses: u64,
}

/// The application of a drive slave: the personality device (node, CiA 402
/// drive, behaviour), the CoE mailbox server and the FoE policy.
pub struct DriveApp {
    pub(crate) dev: PersonalityDevice,
    profile: Profile,
    facts: &'static EcatFacts,
    mbx: MailboxServer,
    files: Box<dyn DriveFiles>,
    frames: Vec<Frame>,
    emcy_id: u16,
    esm: AlState,
    rx: Image,
    tx: Image,
    sync: SyncConfig,
    params: SyncParams,
    /// `sync` changed at SAFE-OP → OP: the sync objects follow it in OP.
    resync: bool,
    started: bool,
    /// The SYNC0 pulse the drive was last aligned and stepped to.
    pulse: Option<Instant>,
    /// Longest wait between two polls of the drive (its slow loop).
    poll_period: Duration,
    stats: DriveStats,
}

impl core::fmt::Debug for DriveApp {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("DriveApp").field("profile", &self.profile).field("esm", &self.esm).finish()
    }
}

impl DriveApp {
    pub(crate) fn new(
        dev: PersonalityDevice,
        profile: Profile,
        facts: &'static EcatFacts,
        mbx: MailboxServer,
        files: Box<dyn DriveFiles>,
    ) -> DriveApp {
        let emcy_id = 0x80 + u16::from(dev.node.node_id());
        DriveApp {
            dev,
            profile,
            facts,
            mbx,
            files,
            frames: Vec::with_capacity(8),
            emcy_id,
            esm: AlState::Init,
            rx: Image::default(),
            tx: Image::default(),
            sync: SyncConfig::default(),
            params: SyncParams::default(),
            resync: false,
            started: false,
            pulse: None,
            poll_period: Duration::from_millis(1),
            stats: DriveStats::default(),
        }
    }

    /// The personality: node, drive, behaviour.
    pub fn device(&self) -> &PersonalityDevice {
        &self.dev
    }

    /// The personality, mutable (tests, fault injection, a local tool).
    pub fn device_mut(&mut self) -> &mut PersonalityDevice {
        &mut self.dev
    }

    /// The profile.
    pub fn profile(&self) -> Profile {
        self.profile
    }

    /// The ESM state the drive runs in.
    pub fn esm(&self) -> AlState {
        self.esm
    }

    /// The CoE mailbox server.
    pub fn mailbox(&self) -> &MailboxServer {
        &self.mbx
    }

    /// The FoE policy as its concrete type (e.g. the iPOS's files).
    pub fn files_mut<T: core::any::Any>(&mut self) -> Option<&mut T> {
        self.files.as_any_mut().downcast_mut::<T>()
    }

    /// Counters.
    pub fn stats(&self) -> DriveStats {
        self.stats
    }

    /// Sets how long the drive may go unpolled when nothing else is due
    /// (default 1 ms; it then catches up in whole control periods).
    pub fn set_poll_period(&mut self, d: Duration) {
        self.poll_period = d.max(Duration::from_micros(1));
    }

    /// Changes the drive's machine at `now`: an input or a fault, put on
    /// the machine schedule the machine file fills (as `drivebus serve
    /// --control` does on CAN, docs/control.md); the application is
    /// polled right after, through the node.
    pub fn change_machine(
        &mut self,
        now: Instant,
        change: Change,
        duration: Option<f64>,
    ) -> Result<(), MachineError> {
        let dev = &mut self.dev;
        let r = dev.node.with_app(now, &mut dev.app, &mut self.frames, |app, _| {
            app.change_machine(now, change, duration)
        });
        self.take_frames();
        r
    }

    /// Runs `f` on the drive's objects at `now` through the read and write
    /// path its CoE server takes (access rights, limits, hooks, the
    /// EtherCAT rules), for a local tool; EMCYs a write causes become CoE
    /// emergencies as after a mailbox request.
    pub fn with_objects<R>(&mut self, now: Instant, f: impl FnOnce(&mut dyn ObjectAccess) -> R) -> R {
        self.run_to(now);
        let mut access = DriveAccess { dev: &mut self.dev, now, frames: &mut self.frames };
        let r = f(&mut access);
        self.take_frames();
        r
    }

    /// Runs the node and drive up to `now` and takes their frames.
    fn run_to(&mut self, now: Instant) -> Option<Instant> {
        if !self.started {
            self.started = true;
            self.dev.start(now, &mut self.frames);
        }
        let next = self.dev.poll(now, &mut self.frames);
        self.take_frames();
        next
    }

    /// A SYNC0 pulse: the drive's control step is put on it, then the drive
    /// runs up to it (once per pulse).
    fn run_to_pulse(&mut self, at: Instant) {
        if self.pulse != Some(at) {
            self.pulse = Some(at);
            self.dev.app.drive.align_steps(at);
        }
        self.run_to(at);
    }

    /// EMCY frames of the node become CoE emergencies; every other CAN
    /// frame (boot-up) has no meaning on EtherCAT.
    fn take_frames(&mut self) {
        for f in self.frames.drain(..) {
            let d = f.data();
            if f.std_id() == Some(self.emcy_id) && d.len() == 8 {
                self.stats.emergencies += 1;
                let code = u16::from_le_bytes([d[0], d[1]]);
                if self.mbx.queue_emergency(code, d[2], [d[3], d[4], d[5], d[6], d[7]]).is_err() {
                    self.stats.emergencies_lost += 1;
                }
            }
        }
    }

    fn esm_event(&mut self, ev: EsmEvent, now: Instant) {
        ecat::esm_event(&mut self.dev, ev, now, &mut self.frames);
        self.take_frames();
    }

    /// Hands what the CoE server has to the slave's mailbox queues:
    /// responses in order, emergencies as unsolicited messages (they wait
    /// for an idle mailbox, never answering a request).
    fn drain(&mut self, now: Instant, out: &mut MailboxOut<'_>) {
        while out.pending().0 < 8
            && out.pending().1 < 8
            && let Some(m) = self.mbx.next_response(now)
        {
            let emergency = m.get(5).is_some_and(|t| t & 0x0F == 0x03)
                && m.get(7).is_some_and(|s| s >> 4 == COE_EMERGENCY);
            if emergency {
                out.unsolicited(m);
            } else {
                out.respond(m);
            }
        }
    }

    fn resolve_images(&mut self) -> Result<(), AlStatusCode> {
        let cfg = ecat::pdo_config(self.profile);
        let od = self.dev.node.od();
        for assign in [0x1C12u16, 0x1C13] {
            match Image::resolve(od, &cfg, assign) {
                Ok(i) if assign == 0x1C12 => self.rx = i,
                Ok(i) => self.tx = i,
                Err(_) => return Err(AlStatusCode(al_code(assign))),
            }
        }
        Ok(())
    }

    fn apply_outputs(&mut self, data: &[u8], now: Instant) {
        let rx = &self.rx;
        let refused = self
            .dev
            .node
            .process_data(now, &mut self.dev.app, &mut self.frames, |od, hooks| rx.apply(od, hooks, data));
        self.stats.outputs_refused += u64::from(refused);
        self.stats.outputs_applied += 1;
        self.take_frames();
    }
}

impl SlaveApp for DriveApp {
    /// The drive is built again from its profile as at power-on (state
    /// machine, position, parameters from its non-volatile storage, the
    /// same serial number); it starts at the next poll.
    fn power_on(&mut self) {
        let od = self.dev.node.od();
        let serial =
            od.find(0x1018, 4).ok().and_then(|r| od.bytes(r).try_into().ok()).map(u32::from_le_bytes);
        // The profile built once already; should it fail now, the old drive stays.
        let Ok(mut dev) = ecat::build(self.profile, Box::new(MemoryStorage::new())) else { return };
        if let Some(serial) = serial {
            drivebus_personality::build::set_default(dev.node.od_mut(), 0x1018, 4, &Value::U32(serial));
        }
        let storage = self.dev.node.replace_storage(Box::new(MemoryStorage::new()));
        dev.node.replace_storage(storage);
        self.dev = dev;
        self.frames.clear();
        self.esm = AlState::Init;
        self.rx = Image::default();
        self.tx = Image::default();
        self.sync = SyncConfig::default();
        self.params = SyncParams::default();
        self.resync = false;
        self.started = false;
        self.pulse = None;
        self.mbx.reset(&mut *self.files);
    }

    fn process_data_sizes(&self) -> ProcessDataSizes {
        let od = self.dev.node.od();
        ProcessDataSizes { output_bits: Image::bits_of(od, 0x1C12), input_bits: Image::bits_of(od, 0x1C13) }
    }

    fn sync_support(&self) -> SyncSupport {
        SyncSupport {
            free_run: true,
            dc_sync0: true,
            dc_sync01: false,
            min_cycle: Duration::from_nanos(u64::from(self.facts.min_cycle_ns)),
            cycle_step: Duration::from_nanos(u64::from(self.facts.cycle_step_ns)),
        }
    }

    fn bootstrap_supported(&self) -> bool {
        // iPOS §3.1: BOOT for FoE firmware download (F515F+).
        self.profile == Profile::Ipos
    }

    fn check_transition(&mut self, t: Transition, config: &SyncConfig) -> Result<(), AlStatusCode> {
        match (t.from, t.to) {
            (AlState::PreOp, AlState::SafeOp) => {
                self.resolve_images()?;
                self.params.check(self.dev.node.od(), config)?;
                self.sync = *config;
            }
            // DC set up in SAFE-OP (SOEM's order): taken with OP.
            (AlState::SafeOp, AlState::Op) if *config != self.sync => {
                self.params.check(self.dev.node.od(), config)?;
                self.sync = *config;
                self.resync = true;
            }
            _ => {}
        }
        Ok(())
    }

    fn state_changed(&mut self, from: AlState, to: AlState, now: Instant) {
        self.run_to(now);
        self.esm = to;
        // ETG.1000.6: the mailbox stops and starts with INIT.
        if from == AlState::Init || to == AlState::Init {
            self.mbx.reset(&mut *self.files);
        }
        let resync = core::mem::take(&mut self.resync) && to == AlState::Op;
        if (from == AlState::PreOp && to == AlState::SafeOp) || resync {
            let (dev, frames) = (&mut self.dev, &mut self.frames);
            self.params.enter_safe_op(dev, &self.sync, now, frames);
        }
        if !matches!(to, AlState::SafeOp | AlState::Op) {
            self.pulse = None;
        }
        self.esm_event(EsmEvent::Changed { from, to }, now);
    }

    fn al_error(&mut self, code: Option<AlStatusCode>, now: Instant) {
        self.run_to(now);
        let ev = match code {
            Some(c) => EsmEvent::Error(c.0),
            None => EsmEvent::Acknowledged,
        };
        self.esm_event(ev, now);
    }

    fn mailbox(&mut self, request: &[u8], now: Instant, out: &mut MailboxOut<'_>) {
        self.run_to(now);
        self.files.refresh(self.dev.node.od());
        let mut access = DriveAccess { dev: &mut self.dev, now, frames: &mut self.frames };
        self.mbx.handle_request(request, now, self.esm, &mut access, &mut *self.files);
        self.take_frames();
        self.drain(now, out);
    }

    fn outputs(&mut self, data: &[u8], now: Instant) {
        if self.sync.mode == SyncMode::FreeRun {
            // SM-synchronous (1C32h:01 = 1): the outputs are taken at the
            // SM2 event, then the drive's SYNC: cyclic set-points latch.
            self.run_to(now);
            self.params.sm_event(&mut self.dev, now);
            self.apply_outputs(data, now);
            self.dev.node.foreign_sync(now, &mut self.dev.app, &mut self.frames);
            self.take_frames();
        } else {
            // DC: the frame's outputs, latched by the slave since the last
            // pulse, are applied at this SYNC0 (iPOS Fig. 3.2.1 moment 5
            // for the next moment 1); `sync0` follows.
            self.run_to_pulse(now);
            self.apply_outputs(data, now);
        }
    }

    fn outputs_received(&mut self, _now: Instant) {
        self.params.received();
    }

    fn inputs(&mut self, data: &mut [u8], now: Instant) {
        if self.sync.mode == SyncMode::FreeRun {
            self.run_to(now);
        } else {
            self.run_to_pulse(now);
        }
        let tx = &self.tx;
        self.dev
            .node
            .process_data(now, &mut self.dev.app, &mut self.frames, |od, hooks| tx.sample(od, hooks, data));
        self.stats.inputs_sampled += 1;
        self.take_frames();
    }

    fn sync0(&mut self, now: Instant, _system_time: u64) {
        if self.sync.mode == SyncMode::FreeRun {
            // SM-synchronous: the SM2 event latches the set-points; pulses
            // the master activated after OP do not latch them a second time.
            return;
        }
        // iPOS §3.2 / Fig. 3.2.1: SYNC0 starts the control loop, which
        // takes the set-points copied after the last frame; the inputs
        // the slave latches next are its actual values.
        self.run_to_pulse(now);
        self.stats.sync0_pulses += 1;
        if self.esm == AlState::Op {
            self.params.pulse(&mut self.dev);
            self.dev.node.foreign_sync(now, &mut self.dev.app, &mut self.frames);
            self.take_frames();
        }
    }

    fn watchdog_expired(&mut self, now: Instant) {
        // The reaction (6007h, EMCY 8100h) runs at the state change and the
        // AL error that follow (`state_changed`, `al_error`).
        self.run_to(now);
    }

    fn poll(&mut self, now: Instant, out: &mut MailboxOut<'_>) -> Option<Instant> {
        let drive = self.run_to(now);
        let mbx = self.mbx.poll(now, &mut *self.files);
        self.drain(now, out);
        // The drive catches up in whole control periods when polled: no
        // need to wake it more often than its slow loop.
        let drive = drive.map(|d| d.max(now + self.poll_period));
        earliest(drive, mbx)
    }
}
