//! The drive personalities drivebus emulates: the EDS file of each drive
//! (transcribed from its manual's object table) and the static facts about
//! it that an EDS cannot hold (supported modes, homing methods, EMCY codes,
//! which CiA 301 services exist, quirks).
//!
//! Each personality lives in one module — [`kc1`], [`akd`], [`ipos`],
//! [`ssd630`], [`dds6`], [`generic`] — holding its facts (`facts.rs`:
//! [`ProfileInfo`]), its EMCY table (`emcy.rs`), its [`Behaviour`]
//! (`mod.rs`, submodules where it is large) and its EDS file (included from
//! `eds/`). The framework is apart: [`build`](mod@build) turns a profile into a
//! running drive (EDS dictionary, CiA 402 drive from `drivebus-cia402`,
//! the profile's [`Behaviour`]), [`shared`] holds what several
//! personalities use. `docs/personalities.md` says what each personality
//! emulates and what not.
//!
//! ```
//! use drivebus_personality::Profile;
//! let kc1 = Profile::Kc1.build(3).unwrap(); // a drivebus_can::Device
//! assert_eq!(kc1.node.od().get_u32(0x6502, 0), Some(0xE5));
//! ```
//!
//! ```
//! use drivebus_personality::Profile;
//! let p = Profile::from_name("akd").unwrap();
//! let od = drivebus_eds::to_od(&p.parse_eds().eds, 5).unwrap();
//! assert_eq!(od.get_u32(0x1000, 0), Some(p.info().device_type));
//! assert!(p.info().modes.contains(&-3)); // AKD electronic gearing
//! ```

use std::sync::OnceLock;

pub mod build;
pub mod ecat;
pub mod machine;
pub mod shared;
pub mod spec;

pub mod akd;
pub mod dds6;
pub mod generic;
pub mod ipos;
pub mod kc1;
pub mod ssd630;

pub use build::{
    Behaviour, BuildError, BuildOptions, Context, EmcyFrame, FilterOutcome, Personality, PersonalityDevice,
    Plain, Verdict, build, build_custom, build_on, build_on_machine, build_with, parse_drive_spec,
};

pub use drivebus_eds::ParsedEds;
pub use spec::{drive_spec, drive_specs};

/// One personality.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Profile {
    /// Kollmorgen KC1 servo drive, CANopen, firmware 1.9.
    Kc1,
    /// Kollmorgen AKD servo drive, CANopen, firmware 1.15.
    Akd,
    /// Technosoft iPOS intelligent drive, CiA 402 over EtherCAT (CoE).
    Ipos,
    /// SSD Drives 630 series servo drive, CANopen.
    Ssd630,
    /// LAM Technologies DDS6 stepper drive, CANopen.
    Dds6,
    /// A generic CiA 402 servo with every mode and every CiA 301 service
    /// the stack implements (no vendor manual behind it).
    Generic,
}

const ALL: [Profile; 6] =
    [Profile::Kc1, Profile::Akd, Profile::Ipos, Profile::Ssd630, Profile::Dds6, Profile::Generic];

impl Profile {
    /// Every personality, the five drives first.
    pub fn all() -> &'static [Profile] {
        &ALL
    }

    /// The short name used on command lines and in file names (`kc1`, `akd`,
    /// `ipos`, `ssd630`, `dds6`, `generic`).
    pub fn name(&self) -> &'static str {
        match self {
            Profile::Kc1 => "kc1",
            Profile::Akd => "akd",
            Profile::Ipos => "ipos",
            Profile::Ssd630 => "ssd630",
            Profile::Dds6 => "dds6",
            Profile::Generic => "generic",
        }
    }

    /// The personality with this short name (case-insensitive; `ssd-630`
    /// and `ssd_630` are accepted for `ssd630`).
    pub fn from_name(name: &str) -> Option<Profile> {
        let n: String = name.chars().filter(|c| !matches!(c, '-' | '_' | ' ')).collect();
        ALL.iter().copied().find(|p| p.name().eq_ignore_ascii_case(&n))
    }

    /// The EDS file, as committed under `crates/personality/eds/`.
    pub fn eds_text(&self) -> &'static str {
        match self {
            Profile::Kc1 => kc1::EDS,
            Profile::Akd => akd::EDS,
            Profile::Ipos => ipos::EDS,
            Profile::Ssd630 => ssd630::EDS,
            Profile::Dds6 => dds6::EDS,
            Profile::Generic => generic::EDS,
        }
    }

    /// The EDS file read. The files are part of this crate and its tests
    /// prove each one reads without errors, so failure here is a build defect.
    pub fn parse_eds(&self) -> ParsedEds {
        self.eds().clone()
    }

    /// The EDS file read, once per process: every build of a drive needs
    /// it, and reading the text costs more than the rest of a build (the
    /// SSD 630's 73 000-line file: ~100 ms). Same result as [`Profile::parse_eds`].
    pub fn eds(&self) -> &'static ParsedEds {
        static PARSED: [OnceLock<ParsedEds>; ALL.len()] = [const { OnceLock::new() }; ALL.len()];
        PARSED[*self as usize].get_or_init(|| match drivebus_eds::parse(self.eds_text()) {
            Ok(p) => p,
            Err(e) => panic!("embedded {}.eds does not parse: {e}", self.name()),
        })
    }

    /// The static facts about this drive.
    pub fn info(&self) -> &'static ProfileInfo {
        match self {
            Profile::Kc1 => &kc1::INFO,
            Profile::Akd => &akd::INFO,
            Profile::Ipos => &ipos::INFO,
            Profile::Ssd630 => &ssd630::INFO,
            Profile::Dds6 => &dds6::INFO,
            Profile::Generic => &generic::INFO,
        }
    }
}

impl std::fmt::Display for Profile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How the drive is reached.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// CANopen on CAN (CiA 301).
    Can,
    /// CiA 301/402 objects over EtherCAT (CoE): no COB-IDs, no NMT frames,
    /// PDO assignment through 1C12h/1C13h.
    EtherCatCoe,
}

/// One row of a drive's EMCY table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmcyEntry {
    /// The EMCY error code (bytes 0–1 of the frame).
    pub code: u16,
    /// What the manual's table says it means (short, as transcribed).
    pub text: &'static str,
    /// The drive's own classification where the table gives one: fault or
    /// warning number (KC1/AKD `F129`/`n702`), error register (SSD 630),
    /// error class (DDS6). Empty when the table has none.
    pub detail: &'static str,
}

/// The default of one PDO channel (communication and mapping parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PdoDefault {
    /// The COB-ID without the node-ID (node-relative, CiA 301 pre-defined
    /// connection set), bit 31 set when the PDO is invalid by default.
    /// `None` on EtherCAT, where PDOs have no COB-ID.
    pub cob_id: Option<u32>,
    /// Valid (CAN: COB-ID bit 31 clear) or assigned (CoE: listed in
    /// 1C12h/1C13h) by default.
    pub enabled: bool,
    /// Transmission type (`None` on EtherCAT).
    pub transmission_type: Option<u8>,
    /// Event timer in ms (TPDO sub 5; 0 = off).
    pub event_timer_ms: u16,
    /// Mapping entries in order (`index << 16 | sub << 8 | bits`).
    pub mapping: &'static [u32],
}

/// A manufacturer behaviour an emulation must reproduce (or knowingly not),
/// kept as data so tests and the drive model can refer to it by `id`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quirk {
    /// Stable identifier (`kebab-case`).
    pub id: &'static str,
    /// The manual section(s) it comes from.
    pub section: &'static str,
    /// What the drive does, in our words.
    pub what: &'static str,
}

/// Static facts about a personality. The values in `src/<name>/facts.rs` cite
/// the manual section each comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProfileInfo {
    /// Manufacturer.
    pub vendor_name: &'static str,
    /// 1018h sub 1, if the manual gives it.
    pub vendor_id: Option<u32>,
    /// Product (the model the EDS describes).
    pub product_name: &'static str,
    /// 1018h sub 2 as written in the EDS, if the manual gives one.
    pub product_code: Option<u32>,
    /// 1018h sub 3 as written in the EDS, if the manual gives one.
    pub revision: Option<u32>,
    /// 1000h.
    pub device_type: u32,
    /// CAN or EtherCAT.
    pub transport: Transport,
    /// CAN bit rates in kbit/s (an EtherCAT drive: those it takes when
    /// served on CAN).
    pub baud_rates_kbit: &'static [u32],
    /// 6502h supported drive modes as the drive reports it (which may
    /// disagree with `modes`; the quirks say so).
    pub supported_drive_modes: u32,
    /// 6060h values the drive accepts, manufacturer modes (negative) included.
    pub modes: &'static [i8],
    /// 6098h values the drive accepts, manufacturer methods (negative) included.
    pub homing_methods: &'static [i8],
    /// RPDO1..4 defaults.
    pub rpdo: [PdoDefault; 4],
    /// TPDO1..4 defaults.
    pub tpdo: [PdoDefault; 4],
    /// Mapping granularity in bits (8 = whole bytes, 1 = bits).
    pub granularity: u8,
    /// Most entries one mapping object takes.
    pub max_mapped_entries: u8,
    /// Standard dummy objects (0001h–0007h) accepted in RPDO mappings.
    pub dummy_mapping: bool,
    /// EMCY codes the drive sends.
    pub emcy: &'static [EmcyEntry],
    /// SDO block transfer.
    pub sdo_block: bool,
    /// TIME consumer (1012h used).
    pub time: bool,
    /// NMT "enter pre-operational" (80h) accepted.
    pub nmt_enter_preoperational: bool,
    /// Heartbeat producer (1017h).
    pub heartbeat_producer: bool,
    /// Heartbeat consumer entries (1016h sub 0; 0 = no consumer).
    pub heartbeat_consumers: u8,
    /// Node guarding answered (RTR on 700h + node).
    pub node_guarding: bool,
    /// Life guarding evaluated (100Ch × 100Dh supervises the master).
    pub life_guarding: bool,
    /// 1029h error behaviour.
    pub error_behaviour: bool,
    /// EMCY inhibit time (1015h).
    pub emcy_inhibit: bool,
    /// 1003h history length (0 = no 1003h).
    pub error_history: u8,
    /// LSS slave (CiA 305). None of the five drives supports it; `generic` does.
    pub lss: bool,
    /// Manufacturer behaviours to reproduce.
    pub quirks: &'static [Quirk],
}

impl ProfileInfo {
    /// The manual's text for an EMCY code, if the table lists it.
    pub fn emcy_text(&self, code: u16) -> Option<&'static str> {
        self.emcy.iter().find(|e| e.code == code).map(|e| e.text)
    }

    /// The 6502h bit of a standard mode (CiA 402: pp 0, vl 1, pv 2, tq 3,
    /// hm 5, ip 6, csp 7, csv 8, cst 9); `None` for manufacturer modes.
    pub fn mode_bit(mode: i8) -> Option<u32> {
        let bit = drivebus_cia402::codes::mode::supported_bit(mode);
        (bit != 0).then(|| bit.trailing_zeros())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for p in Profile::all() {
            assert_eq!(Profile::from_name(p.name()), Some(*p));
            assert_eq!(Profile::from_name(&p.name().to_uppercase()), Some(*p));
        }
        assert_eq!(Profile::from_name("SSD-630"), Some(Profile::Ssd630));
        assert_eq!(Profile::from_name("ecat"), None);
    }

    #[test]
    fn emcy_lookup() {
        // KC1 §7.1: 8130h is life guard or heartbeat error (F129).
        assert!(Profile::Kc1.info().emcy_text(0x8130).unwrap().contains("Heartbeat"));
        assert_eq!(ProfileInfo::mode_bit(8), Some(7));
        assert_eq!(ProfileInfo::mode_bit(-1), None);
    }
}
