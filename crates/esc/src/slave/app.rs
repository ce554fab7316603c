//! The application interface of the slave firmware framework.

use super::esm::{AlState, AlStatusCode};
use super::mailbox::MailboxOut;
use drivebus_base::{Duration, Instant};

/// Process image sizes of the current PDO mapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ProcessDataSizes {
    /// RxPDO bits (master → slave, the outputs sync manager).
    pub output_bits: u32,
    /// TxPDO bits (slave → master, the inputs sync manager).
    pub input_bits: u32,
}

impl ProcessDataSizes {
    /// Outputs in bytes.
    pub const fn output_bytes(&self) -> usize {
        self.output_bits.div_ceil(8) as usize
    }

    /// Inputs in bytes.
    pub const fn input_bytes(&self) -> usize {
        self.input_bits.div_ceil(8) as usize
    }
}

/// Synchronisation modes and cycle limits the application accepts; the
/// framework checks the master's DC registers against them at PRE-OP →
/// SAFE-OP (ETG.1020 "Synchronization").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncSupport {
    /// Free run / SM-synchronous operation without DC (else 0x0027).
    pub free_run: bool,
    /// DC with SYNC0 (else 0x0028).
    pub dc_sync0: bool,
    /// DC with SYNC0 and SYNC1 (else 0x0028).
    pub dc_sync01: bool,
    /// Shortest SYNC0 cycle (else 0x0036).
    pub min_cycle: Duration,
    /// SYNC0 cycle must be a multiple of this (zero: any; else 0x0035),
    /// e.g. the drive's control loop period.
    pub cycle_step: Duration,
}

impl Default for SyncSupport {
    fn default() -> Self {
        SyncSupport {
            free_run: true,
            dc_sync0: true,
            dc_sync01: true,
            min_cycle: Duration::from_micros(50),
            cycle_step: Duration::ZERO,
        }
    }
}

/// How process data is synchronised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SyncMode {
    /// No DC: outputs are applied when their buffer completes (SM2 event),
    /// inputs are produced again each time the master has read them.
    #[default]
    FreeRun,
    /// DC: outputs applied and inputs latched at every SYNC0.
    DcSync0,
    /// DC with SYNC1 as well (the application gets both pulses).
    DcSync01,
}

/// The synchronisation and process data configuration the master set up,
/// as latched at PRE-OP → SAFE-OP (the DC part again at SAFE-OP → OP).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SyncConfig {
    /// Mode derived from 0x0981.
    pub mode: SyncMode,
    /// SYNC0 cycle (0x09A0) in ns.
    pub sync0_cycle: u32,
    /// SYNC1 cycle (0x09A4) in ns.
    pub sync1_cycle: u32,
    /// Outputs sync manager length in bytes.
    pub outputs_len: u16,
    /// Inputs sync manager length in bytes.
    pub inputs_len: u16,
    /// Process-data watchdog time, if enabled on the outputs SM.
    pub watchdog: Option<Duration>,
}

/// A requested state change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transition {
    /// Current state.
    pub from: AlState,
    /// Requested state.
    pub to: AlState,
}

/// What a slave application implements; the framework ([`super::Slave`])
/// does the EtherCAT side.
///
/// All methods but [`SlaveApp::process_data_sizes`] have defaults, so an
/// I/O device implements three or four and a CoE drive implements the
/// mailbox too.
pub trait SlaveApp {
    /// Sizes of the current PDO mapping. Asked at PRE-OP → SAFE-OP to
    /// check the master's SM2/SM3 lengths (0x001D/0x001E otherwise).
    fn process_data_sizes(&self) -> ProcessDataSizes;

    /// Synchronisation the application supports.
    fn sync_support(&self) -> SyncSupport {
        SyncSupport::default()
    }

    /// True if the device has a bootstrap state (else 0x0013).
    fn bootstrap_supported(&self) -> bool {
        false
    }

    /// Last word on an upward transition after the framework's own checks
    /// passed; return an AL status code to refuse it. `config` is the set-up
    /// the slave runs with once the transition is taken: at PRE-OP →
    /// SAFE-OP the one just checked, at SAFE-OP → OP that one with the DC
    /// registers read again (a master such as SOEM activates SYNC0 in
    /// SAFE-OP), else the one in force.
    fn check_transition(&mut self, transition: Transition, config: &SyncConfig) -> Result<(), AlStatusCode> {
        let _ = (transition, config);
        Ok(())
    }

    /// The state changed (up or down).
    fn state_changed(&mut self, from: AlState, to: AlState, now: Instant) {
        let _ = (from, to, now);
    }

    /// A mailbox request: the whole message from the 6-byte mailbox header
    /// to the end of its payload. Queue responses with
    /// [`MailboxOut::respond`]; they go out in order, one per read.
    fn mailbox(&mut self, request: &[u8], now: Instant, out: &mut MailboxOut<'_>) {
        let _ = (request, now, out);
    }

    /// New outputs (OP only): at their SM event in free run, at SYNC0 in
    /// DC mode.
    fn outputs(&mut self, data: &[u8], now: Instant) {
        let _ = (data, now);
    }

    /// The master wrote a complete outputs buffer (SAFE-OP and OP, every
    /// mode): in DC mode the outputs wait for the next SYNC0, so this is
    /// where an application counts frames per cycle (ETG.1020 "SM event
    /// missed", "cycle time too small").
    fn outputs_received(&mut self, now: Instant) {
        let _ = now;
    }

    /// Fill in the inputs (SAFE-OP and OP).
    fn inputs(&mut self, data: &mut [u8], now: Instant) {
        let _ = (data, now);
    }

    /// A SYNC0 pulse (after outputs were applied, before inputs are
    /// latched). `system_time` is the DC time of the pulse.
    fn sync0(&mut self, now: Instant, system_time: u64) {
        let _ = (now, system_time);
    }

    /// A SYNC1 pulse.
    fn sync1(&mut self, now: Instant, system_time: u64) {
        let _ = (now, system_time);
    }

    /// The process-data watchdog expired or the slave left OP on an
    /// error: put the outputs in their safe state.
    fn watchdog_expired(&mut self, now: Instant) {
        let _ = now;
    }

    /// The AL status error indication changed (ETG.1000.6 §6.4.1.4):
    /// `Some(code)` when a requested transition was refused or the slave
    /// fell back on an error, `None` when the master acknowledged it (AL
    /// control bit 4, or a request for INIT).
    fn al_error(&mut self, code: Option<AlStatusCode>, now: Instant) {
        let _ = (code, now);
    }

    /// Application timers and unsolicited mailbox messages (CoE
    /// emergencies: [`MailboxOut::unsolicited`]). Return the next deadline.
    fn poll(&mut self, now: Instant, out: &mut MailboxOut<'_>) -> Option<Instant> {
        let _ = (now, out);
        None
    }

    /// A local error that must take the slave down (e.g. a drive fault
    /// the profile maps to an AL error): `(code, state to fall back to)`.
    /// Asked once per poll; return `None` when there is none.
    fn take_error(&mut self) -> Option<(AlStatusCode, AlState)> {
        None
    }

    /// Power comes back ([`SegmentDevice::power_on`](crate::segment::SegmentDevice::power_on)):
    /// the firmware starts again from its power-on state (what it keeps
    /// is what non-volatile memory holds). Default: nothing to rebuild.
    fn power_on(&mut self) {}
}

/// Framework options.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlaveConfig {
    /// SAFE-OP → OP waits (no error, state stays SAFE-OP) until outputs
    /// arrived, as ETG.1020 recommends for devices with outputs; after this
    /// time without them the request fails with 0x001B. `None`: no wait
    /// (ethercrab's `into_op` sends no process data while it waits).
    pub op_needs_outputs: Option<Duration>,
    /// In DC mode SAFE-OP → OP waits for the first SYNC0 pulse; after this
    /// time without one it fails with 0x002D (no sync error).
    pub sync_timeout: Duration,
    /// In DC mode in OP, this many SYNC0 cycles without a pulse is a fatal
    /// sync error (0x002C, back to SAFE-OP). 0 disables the check.
    pub sync_loss_cycles: u32,
    /// Unsolicited mailbox messages wait until the mailbox has been idle
    /// this long, so they never land between a master's request and its
    /// response (ethercrab asserts that a response is never an emergency).
    pub unsolicited_quiet: Duration,
    /// Most messages a mailbox queue holds; more are dropped.
    pub queue_depth: usize,
}

impl Default for SlaveConfig {
    fn default() -> Self {
        SlaveConfig {
            op_needs_outputs: None,
            sync_timeout: Duration::from_secs(5),
            sync_loss_cycles: 5,
            unsolicited_quiet: Duration::from_millis(10),
            queue_depth: 16,
        }
    }
}
