//! EtherCAT state machine vocabulary (ETG.1000.6 §6.4.1, Table 11 "AL
//! status codes"; the iPOS manual §3.1 describes the same machine).

use core::fmt;

/// EtherCAT application-layer states (AL control/status bits 3:0): the one
/// EtherCAT state type of drivebus, used by the slave controller, the CoE
/// server (`drivebus-coe`) and the master (`drivebus-ethercat`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum AlState {
    /// INIT (1): no mailbox.
    Init = 1,
    /// PRE-OPERATIONAL (2): mailbox only.
    PreOp = 2,
    /// BOOTSTRAP (3): mailbox with FoE only, for firmware download.
    Boot = 3,
    /// SAFE-OPERATIONAL (4): mailbox, inputs; outputs held safe.
    SafeOp = 4,
    /// OPERATIONAL (8): mailbox, inputs and outputs.
    Op = 8,
}

impl AlState {
    /// Every state, in code order.
    pub const ALL: [AlState; 5] =
        [AlState::Init, AlState::PreOp, AlState::Boot, AlState::SafeOp, AlState::Op];

    /// Decodes AL control/status bits 3:0 (the error bit 4 is ignored),
    /// `None` for a code that names no state.
    pub const fn from_code(v: u8) -> Option<AlState> {
        Some(match v & 0x0F {
            1 => AlState::Init,
            2 => AlState::PreOp,
            3 => AlState::Boot,
            4 => AlState::SafeOp,
            8 => AlState::Op,
            _ => return None,
        })
    }

    /// The AL control/status code (bits 3:0).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Whether the mailbox runs in this state (every state but INIT).
    pub const fn has_mailbox(self) -> bool {
        !matches!(self, AlState::Init)
    }

    /// As a user types it: `init`, `preop`, `boot` (or `bootstrap`),
    /// `safeop`, `op`; any case, `-` and `_` ignored (`PRE-OP`, `safe_op`).
    pub fn parse(s: &str) -> Option<AlState> {
        let mut buf = [0u8; 9];
        let mut n = 0;
        for b in s.bytes().filter(|b| !matches!(b, b'-' | b'_')) {
            *buf.get_mut(n)? = b.to_ascii_lowercase();
            n += 1;
        }
        match &buf[..n] {
            b"init" => Some(AlState::Init),
            b"preop" => Some(AlState::PreOp),
            b"boot" | b"bootstrap" => Some(AlState::Boot),
            b"safeop" => Some(AlState::SafeOp),
            b"op" => Some(AlState::Op),
            _ => None,
        }
    }

    /// Rank for "going down": INIT < PRE-OP/BOOT < SAFE-OP < OP.
    const fn rank(self) -> u8 {
        match self {
            AlState::Init => 0,
            AlState::PreOp | AlState::Boot => 1,
            AlState::SafeOp => 2,
            AlState::Op => 3,
        }
    }

    /// True if `to` is below `self` (always allowed, except into BOOT).
    pub const fn is_down_to(self, to: AlState) -> bool {
        to.rank() < self.rank()
    }
}

impl fmt::Display for AlState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            AlState::Init => "INIT",
            AlState::PreOp => "PRE-OP",
            AlState::Boot => "BOOT",
            AlState::SafeOp => "SAFE-OP",
            AlState::Op => "OP",
        })
    }
}

/// An AL status code (0x0134), ETG.1000.6 Table 11.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AlStatusCode(pub u16);

#[allow(missing_docs)]
impl AlStatusCode {
    pub const NO_ERROR: Self = Self(0x0000);
    pub const UNSPECIFIED: Self = Self(0x0001);
    pub const NO_MEMORY: Self = Self(0x0002);
    pub const INVALID_DEVICE_SETUP: Self = Self(0x0003);
    pub const INVALID_STATE_CHANGE: Self = Self(0x0011);
    pub const UNKNOWN_STATE: Self = Self(0x0012);
    pub const BOOTSTRAP_NOT_SUPPORTED: Self = Self(0x0013);
    pub const NO_VALID_FIRMWARE: Self = Self(0x0014);
    pub const INVALID_MAILBOX_CONFIG_BOOT: Self = Self(0x0015);
    pub const INVALID_MAILBOX_CONFIG: Self = Self(0x0016);
    pub const INVALID_SM_CONFIG: Self = Self(0x0017);
    pub const NO_VALID_INPUTS: Self = Self(0x0018);
    pub const NO_VALID_OUTPUTS: Self = Self(0x0019);
    pub const SYNC_ERROR: Self = Self(0x001A);
    pub const SM_WATCHDOG: Self = Self(0x001B);
    pub const INVALID_SM_TYPES: Self = Self(0x001C);
    pub const INVALID_OUTPUT_CONFIG: Self = Self(0x001D);
    pub const INVALID_INPUT_CONFIG: Self = Self(0x001E);
    pub const INVALID_WATCHDOG_CONFIG: Self = Self(0x001F);
    pub const NEEDS_COLD_START: Self = Self(0x0020);
    pub const NEEDS_INIT: Self = Self(0x0021);
    pub const NEEDS_PREOP: Self = Self(0x0022);
    pub const NEEDS_SAFEOP: Self = Self(0x0023);
    pub const INVALID_INPUT_MAPPING: Self = Self(0x0024);
    pub const INVALID_OUTPUT_MAPPING: Self = Self(0x0025);
    pub const INCONSISTENT_SETTINGS: Self = Self(0x0026);
    pub const FREE_RUN_NOT_SUPPORTED: Self = Self(0x0027);
    pub const SYNC_MODE_NOT_SUPPORTED: Self = Self(0x0028);
    pub const FREE_RUN_NEEDS_3_BUFFER: Self = Self(0x0029);
    pub const BACKGROUND_WATCHDOG: Self = Self(0x002A);
    pub const NO_VALID_INPUTS_AND_OUTPUTS: Self = Self(0x002B);
    pub const FATAL_SYNC_ERROR: Self = Self(0x002C);
    pub const NO_SYNC_ERROR: Self = Self(0x002D);
    pub const INVALID_DC_SYNC_CONFIG: Self = Self(0x0030);
    pub const INVALID_DC_LATCH_CONFIG: Self = Self(0x0031);
    pub const PLL_ERROR: Self = Self(0x0032);
    pub const DC_SYNC_IO_ERROR: Self = Self(0x0033);
    pub const DC_SYNC_TIMEOUT: Self = Self(0x0034);
    pub const DC_INVALID_SYNC_CYCLE_TIME: Self = Self(0x0035);
    pub const DC_SYNC0_CYCLE_TIME: Self = Self(0x0036);
    pub const DC_SYNC1_CYCLE_TIME: Self = Self(0x0037);
    pub const MBX_AOE: Self = Self(0x0041);
    pub const MBX_EOE: Self = Self(0x0042);
    pub const MBX_COE: Self = Self(0x0043);
    pub const MBX_FOE: Self = Self(0x0044);
    pub const MBX_SOE: Self = Self(0x0045);
    pub const MBX_VOE: Self = Self(0x004F);
    pub const EEPROM_NO_ACCESS: Self = Self(0x0050);
    pub const EEPROM_ERROR: Self = Self(0x0051);
    pub const RESTARTED_LOCALLY: Self = Self(0x0060);

    /// The ETG.1000.6 description.
    pub fn description(self) -> &'static str {
        match self.0 {
            0x0000 => "No error",
            0x0001 => "Unspecified error",
            0x0002 => "No memory",
            0x0003 => "Invalid device setup",
            0x0011 => "Invalid requested state change",
            0x0012 => "Unknown requested state",
            0x0013 => "Bootstrap not supported",
            0x0014 => "No valid firmware",
            0x0015 => "Invalid mailbox configuration (BOOT)",
            0x0016 => "Invalid mailbox configuration (PRE-OP)",
            0x0017 => "Invalid sync manager configuration",
            0x0018 => "No valid inputs available",
            0x0019 => "No valid outputs",
            0x001A => "Synchronization error",
            0x001B => "Sync manager watchdog",
            0x001C => "Invalid sync manager types",
            0x001D => "Invalid output configuration",
            0x001E => "Invalid input configuration",
            0x001F => "Invalid watchdog configuration",
            0x0020 => "Slave needs cold start",
            0x0021 => "Slave needs INIT",
            0x0022 => "Slave needs PRE-OP",
            0x0023 => "Slave needs SAFE-OP",
            0x0024 => "Invalid input mapping",
            0x0025 => "Invalid output mapping",
            0x0026 => "Inconsistent settings",
            0x0027 => "Free run not supported",
            0x0028 => "Sync mode not supported",
            0x0029 => "Free run needs 3-buffer mode",
            0x002A => "Background watchdog",
            0x002B => "No valid inputs and outputs",
            0x002C => "Fatal sync error",
            0x002D => "No sync error",
            0x0030 => "Invalid DC SYNC configuration",
            0x0031 => "Invalid DC latch configuration",
            0x0032 => "PLL error",
            0x0033 => "DC sync IO error",
            0x0034 => "DC sync timeout",
            0x0035 => "DC invalid sync cycle time",
            0x0036 => "DC SYNC0 cycle time",
            0x0037 => "DC SYNC1 cycle time",
            0x0041..=0x004F => "Mailbox protocol error",
            0x0050 => "EEPROM no access",
            0x0051 => "EEPROM error",
            0x0060 => "Slave restarted locally",
            0x8000..=0xFFFF => "Vendor specific",
            _ => "Reserved",
        }
    }
}

impl fmt::Display for AlStatusCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#06x} {}", self.0, self.description())
    }
}

/// Whether the path `from → to` exists at all (before any configuration
/// check): INIT reaches only PRE-OP and BOOT, PRE-OP cannot jump to OP,
/// BOOT leaves only to INIT, and BOOT is entered only from INIT; every
/// step down is allowed.
pub fn path_allowed(from: AlState, to: AlState) -> bool {
    use AlState::*;
    match (from, to) {
        (a, b) if a == b => true,
        (_, Boot) => from == Init,
        (Boot, b) => b == Init,
        (Init, PreOp) => true,
        (Init, _) => false,
        (PreOp, SafeOp) => true,
        (PreOp, Op) => false,
        (SafeOp, Op) => true,
        (a, b) => a.is_down_to(b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use AlState::*;

    #[test]
    fn transition_table() {
        let all = [Init, PreOp, Boot, SafeOp, Op];
        let allowed = [
            (Init, PreOp),
            (Init, Boot),
            (PreOp, Init),
            (PreOp, SafeOp),
            (Boot, Init),
            (SafeOp, Init),
            (SafeOp, PreOp),
            (SafeOp, Op),
            (Op, Init),
            (Op, PreOp),
            (Op, SafeOp),
        ];
        for a in all {
            for b in all {
                let want = a == b || allowed.contains(&(a, b));
                assert_eq!(path_allowed(a, b), want, "{a} -> {b}");
            }
        }
    }

    #[test]
    fn states_parse_as_users_type_them() {
        for (t, s) in
            [("init", Init), ("PRE-OP", PreOp), ("bootstrap", Boot), ("safe_op", SafeOp), ("Op", Op)]
        {
            assert_eq!(AlState::parse(t), Some(s), "{t}");
        }
        for t in ["run", "", "preoperational", "o-p-x"] {
            assert_eq!(AlState::parse(t), None, "{t}");
        }
    }

    #[test]
    fn codes_and_states_decode() {
        assert_eq!(AlState::from_code(0x18), Some(Op));
        assert_eq!(AlState::from_code(5), None);
        for s in AlState::ALL {
            assert_eq!(AlState::from_code(s.code()), Some(s));
            assert_eq!(s.has_mailbox(), s != Init);
        }
        assert_eq!(AlStatusCode::SM_WATCHDOG.0, 0x001B);
        assert_eq!(AlStatusCode(0x0029).description(), "Free run needs 3-buffer mode");
        assert_eq!(
            alloc::format!("{}", AlStatusCode::INVALID_STATE_CHANGE),
            "0x0011 Invalid requested state change"
        );
    }
}
