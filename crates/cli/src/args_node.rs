//! Arguments of the commands that address one node: sdo, pdo, drive, lss, eds.

use std::path::PathBuf;

use clap::builder::TypedValueParser as _;
use clap::{Args, Subcommand};
use drivebus_master::PdoDir;

pub(crate) const SDO_EXAMPLES: &str = "\
Examples:
  drivebus --node 1 sdo read 1000                 (index in hex; sub-index 0)
  drivebus --node 1 sdo read statusword           (CiA 301/402 objects by name, typed)
  drivebus --node 1 sdo read 1018                 (a whole record: every sub-index)
  drivebus --node 1 sdo read 6041:00 --type u16
  drivebus --node 1 sdo write 1017 0 100          (producer heartbeat time: typed from CiA 301)
  drivebus --node 1 sdo write profile_velocity 360000
  drivebus --node 1 sdo store                     (1010h:1 = \"save\")
  drivebus --node 1 sdo upload 1008 0 name.bin";

/// `drivebus sdo ...`.
#[derive(Subcommand, Debug)]
pub enum SdoCmd {
    /// Read an object (a whole record or array when no sub-index is given).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 sdo read 1000\n  drivebus --node 1 sdo read 0x6041 0 --type u16\n  drivebus --node 1 sdo read identity\n  drivebus --node 1 --eds akd.eds sdo read 1008"
    )]
    Read(SdoRead),
    /// Write a value to an object.
    #[command(
        after_help = "Examples:\n  drivebus --node 1 sdo write 1017 0 100\n  drivebus --node 1 sdo write 1017:00 100 --type u16\n  drivebus --node 1 --eds akd.eds sdo write 6083 0 50000"
    )]
    Write(SdoWrite),
    /// Read an object into a file (progress bar).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 sdo upload 1008 0 name.bin\n  drivebus --node 1 sdo upload 1021 0 device.eds --block"
    )]
    Upload(SdoFile),
    /// Write a file into an object (progress bar).
    #[command(after_help = "Examples:\n  drivebus --node 1 sdo download 1F50 1 firmware.bin --block")]
    Download(SdoFile),
    /// Store parameters in non-volatile memory: writes \"save\" to 1010h (CiA 301 §7.5.2.13).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 sdo store\n  drivebus --node 1 sdo store --what comm"
    )]
    Store(StoreArgs),
    /// Restore default parameters: writes \"load\" to 1011h (active after reset node).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 sdo restore\n  drivebus --node 1 sdo restore --what app"
    )]
    Restore(StoreArgs),
}

/// `sdo read`.
#[derive(Args, Debug)]
pub struct SdoRead {
    /// Object: index in hex (6041, 0x6041, 6041h), INDEX:SUB (6041:00), or a CiA 301/402 name.
    pub object: String,
    /// Sub-index in hex (default: 0, or every entry of a record/array).
    pub sub: Option<String>,
    /// Data type (u8, u16, u32, i16, i32, str, bytes, UNSIGNED16, ...); default: from --eds or the
    /// CiA 301/402 dictionary, else hex bytes.
    #[arg(long = "type", short = 't')]
    pub ty: Option<String>,
}

/// `sdo write`.
#[derive(Args, Debug)]
pub struct SdoWrite {
    /// OBJECT [SUB] VALUE: the object (hex index, INDEX:SUB or a name), an optional
    /// hex sub-index, and the value (decimal, 0x hex, text for strings, hex bytes for bytes).
    #[arg(num_args = 2..=3, required = true, allow_negative_numbers = true, value_name = "OBJECT [SUB] VALUE")]
    pub args: Vec<String>,
    /// Data type; default: from --eds or the CiA 301/402 dictionary.
    #[arg(long = "type", short = 't')]
    pub ty: Option<String>,
}

/// `sdo upload|download`.
#[derive(Args, Debug)]
pub struct SdoFile {
    /// OBJECT [SUB] FILE: the object (hex index, INDEX:SUB or a name), an optional hex
    /// sub-index, and the file.
    #[arg(num_args = 2..=3, required = true, value_name = "OBJECT [SUB] FILE")]
    pub args: Vec<String>,
    /// Use SDO block transfer.
    #[arg(long)]
    pub block: bool,
}

/// Which parameters `sdo store`/`restore` address (1010h/1011h sub-index).
#[derive(Args, Debug)]
pub struct StoreArgs {
    /// all (sub 1), comm (2), app (3), or a sub-index number (4..127 manufacturer groups).
    #[arg(long, default_value = "all")]
    pub what: String,
}

pub(crate) const PDO_EXAMPLES: &str = "\
Examples:
  drivebus --node 1 pdo show
  drivebus --node 1 pdo map tpdo 1 statusword position_actual_value --type 1
  drivebus --node 1 pdo map tpdo 1 6041:00:16 6064:00:32 --type 255 --event-timer 20
  drivebus --node 1 pdo map rpdo 2 6040:0:16 607A:0:32

A mapping the device refuses is undone: the previous one stays in force.";

/// `drivebus pdo ...`.
#[derive(Subcommand, Debug)]
pub enum PdoCmd {
    /// Show the RPDO and TPDO configuration of a node.
    #[command(
        after_help = "Examples:\n  drivebus --node 1 pdo show\n  drivebus --node 1 --eds akd.eds pdo show --json"
    )]
    Show,
    /// Map objects into a PDO (invalidate, map, validate; restored on refusal).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 pdo map tpdo 1 6041:0:16 6064:0:32 --type 1\n  drivebus --node 1 pdo map rpdo 2 controlword target_position"
    )]
    Map(PdoMapArgs),
}

/// `rpdo` (master → device) or `tpdo` (device → master), as the master's
/// [`PdoDir`]: clap cannot derive `ValueEnum` for another crate's type.
fn pdo_dir() -> impl clap::builder::TypedValueParser<Value = PdoDir> {
    clap::builder::PossibleValuesParser::new(["rpdo", "tpdo"])
        .map(|s| if s == "rpdo" { PdoDir::Rx } else { PdoDir::Tx })
}

/// `pdo map`.
#[derive(Args, Debug)]
pub struct PdoMapArgs {
    /// rpdo or tpdo.
    #[arg(value_parser = pdo_dir())]
    pub dir: PdoDir,
    /// PDO number, 1-based.
    #[arg(value_parser = clap::value_parser!(u16).range(1..=512))]
    pub number: u16,
    /// Entries INDEX:SUB:BITS (hex index and sub, decimal bits: 6041:0:16), or an object
    /// (6041:00, statusword) whose size comes from --eds or the CiA 301/402 dictionary.
    #[arg(required = true)]
    pub entries: Vec<String>,
    /// Transmission type (0..255).
    #[arg(long = "type")]
    pub transmission: Option<u8>,
    /// Event timer in ms.
    #[arg(long)]
    pub event_timer: Option<u16>,
    /// Inhibit time in 100 µs units.
    #[arg(long)]
    pub inhibit: Option<u16>,
    /// COB-ID (default: keep the current one).
    #[arg(long)]
    pub cob_id: Option<String>,
}

pub(crate) const DRIVE_EXAMPLES: &str = "\
Examples:
  drivebus --node 1 drive enable
  drivebus --node 1 drive home --method 35
  drivebus --node 1 drive move 90000 --velocity 360000
  drivebus --node 1 drive status --json

While a command waits it shows the position and velocity (a progress line on a terminal).
Motion a command started is halted (else quick-stopped) on a timeout, an error or Ctrl-C.";

/// `drivebus drive ...`.
#[derive(Subcommand, Debug)]
pub enum DriveCmd {
    /// State, mode, position, velocity and errors.
    #[command(
        after_help = "Examples:\n  drivebus --node 1 drive status\n  drivebus --node 1 drive status --json"
    )]
    Status,
    /// Walk the state machine to operation enabled.
    #[command(after_help = "Examples:\n  drivebus --node 1 drive enable")]
    Enable,
    /// Power stage off: shutdown to ready to switch on.
    #[command(after_help = "Examples:\n  drivebus --node 1 drive disable")]
    Disable,
    /// Profile position move (mode 1), waits for target reached.
    #[command(
        after_help = "Examples:\n  drivebus --node 1 drive move 90000 --velocity 360000\n  drivebus --node 1 drive move -45000 --relative --velocity 100000\n\nA move that cannot finish within --wait at the drive's 6081h/6083h/607Fh is refused\nbefore it starts, naming those objects."
    )]
    Move(MoveArgs),
    /// Profile velocity (mode 3): sets the target velocity and returns (the axis keeps turning).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 drive velocity 36000\n  drivebus --node 1 drive velocity 0"
    )]
    Velocity(ValueArg),
    /// Profile torque (mode 4), per mille of rated torque.
    #[command(after_help = "Examples:\n  drivebus --node 1 drive torque 100")]
    Torque(ValueArg),
    /// Homing (mode 6), waits for a fresh homing attained.
    #[command(
        after_help = "Examples:\n  drivebus --node 1 drive home --method 35\n  drivebus --node 1 drive home --method 17 --wait 60"
    )]
    Home(HomeArgs),
    /// Halt the axis (controlword bit 8); quick stop if it does not come to rest.
    #[command(after_help = "Examples:\n  drivebus --node 1 drive stop")]
    Stop,
    /// Quick stop (controlword 02h).
    #[command(after_help = "Examples:\n  drivebus --node 1 drive quickstop")]
    Quickstop,
    /// Fault reset (only when the drive is in fault; a running drive is left alone).
    #[command(after_help = "Examples:\n  drivebus --node 1 drive reset")]
    Reset,
}

/// `drive move`.
#[derive(Args, Debug)]
pub struct MoveArgs {
    /// Target position (position units).
    #[arg(allow_hyphen_values = true)]
    pub target: i32,
    /// Relative to the current target.
    #[arg(long)]
    pub relative: bool,
    /// Profile velocity (writes 6081h).
    #[arg(long)]
    pub velocity: Option<u32>,
    /// Profile acceleration and deceleration (writes 6083h and 6084h).
    #[arg(long)]
    pub acceleration: Option<u32>,
    /// Seconds to wait for target reached.
    #[arg(long, default_value_t = 30.0)]
    pub wait: f64,
}

/// A single signed value.
#[derive(Args, Debug)]
pub struct ValueArg {
    /// The value.
    #[arg(allow_hyphen_values = true)]
    pub value: i32,
}

/// `drive home`.
#[derive(Args, Debug)]
pub struct HomeArgs {
    /// Homing method (6098h); default: keep the drive's.
    #[arg(long, allow_hyphen_values = true)]
    pub method: Option<i8>,
    /// Seconds to wait for homing attained.
    #[arg(long, default_value_t = 30.0)]
    pub wait: f64,
}

pub(crate) const EDS_EXAMPLES: &str = "\
Examples:
  drivebus eds check drive.eds
  drivebus eds show --profile akd
  drivebus eds export --profile akd --out akd.eds
  drivebus --node 1 eds dcf --out node1.dcf        (the node's dictionary with its current values)";

/// `drivebus eds ...`.
#[derive(Subcommand, Debug)]
pub enum EdsCmd {
    /// Check a file: findings with severity and line; exit 1 on errors.
    #[command(
        after_help = "Examples:\n  drivebus eds check drive.eds\n  drivebus eds check drive.eds --json"
    )]
    Check(EdsFileArg),
    /// Show the objects of a file or of a built-in profile.
    #[command(after_help = "Examples:\n  drivebus eds show drive.eds\n  drivebus eds show --profile akd")]
    Show(EdsSource),
    /// Write an EDS: of a profile, of --eds re-written, or read from --node over 1021h.
    #[command(
        after_help = "Examples:\n  drivebus eds export --profile akd --out akd.eds\n  drivebus --eds in.eds eds export\n  drivebus --bus socketcand://127.0.0.1:29536/can0 --node 1 eds export --out node1.eds"
    )]
    Export(EdsExport),
    /// Read a live node's dictionary (--eds, else the CiA 301/402 objects it has) into a DCF
    /// with its current values (ParameterValue) and [DeviceComissioning].
    #[command(
        after_help = "Examples:\n  drivebus --node 1 eds dcf --out node1.dcf\n  drivebus --node 1 --eds akd.eds eds dcf > node1.dcf"
    )]
    Dcf(DcfArgs),
}

/// A file argument.
#[derive(Args, Debug)]
pub struct EdsFileArg {
    /// The EDS or DCF file.
    pub file: PathBuf,
}

/// A file or a built-in profile.
#[derive(Args, Debug)]
pub struct EdsSource {
    /// The EDS or DCF file (default: --eds).
    pub file: Option<PathBuf>,
    /// A built-in profile instead: kc1, akd, ipos, ssd630, dds6, generic.
    #[arg(long)]
    pub profile: Option<String>,
}

/// `eds export`.
#[derive(Args, Debug)]
pub struct EdsExport {
    /// A built-in profile: kc1, akd, ipos, ssd630, dds6, generic.
    #[arg(long)]
    pub profile: Option<String>,
    /// Output file (default: stdout).
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
}

/// `eds dcf`.
#[derive(Args, Debug)]
pub struct DcfArgs {
    /// Output file (default: stdout).
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
}

pub(crate) const LSS_EXAMPLES: &str = "\
Examples:
  drivebus lss scan
  drivebus lss set-node-id 5 --store                       (the only unconfigured slave)
  drivebus lss set-node-id 5 --vendor 0x6A --product 0x1 --revision 1 --serial 1234
  drivebus --node 7 lss set-node-id 5                      (a configured node: its 1018h by SDO)
  drivebus lss assign --first 10 --store                   (every unconfigured slave, 10, 11, ...)";

/// `drivebus lss ...`.
#[derive(Subcommand, Debug)]
pub enum LssCmd {
    /// Find an unconfigured LSS slave (fastscan) and say whether there are more.
    #[command(after_help = "Examples:\n  drivebus lss scan\n  drivebus --json lss scan")]
    Scan,
    /// Give a node-ID to one LSS slave: the only unconfigured one, the one with an LSS
    /// address, or a configured node (--node). Refuses when several slaves would be configured.
    #[command(
        after_help = "Examples:\n  drivebus lss set-node-id 5 --vendor 0x6A --product 0x1 --revision 1 --serial 1234\n  drivebus lss set-node-id 5   (only one unconfigured LSS slave on the bus)\n  drivebus --node 7 lss set-node-id 5"
    )]
    SetNodeId(LssSetArgs),
    /// Give node-IDs to every unconfigured slave, one after the other (fastscan; cocomm's lss_allnodes).
    #[command(after_help = "Examples:\n  drivebus lss assign --first 10 --store")]
    Assign(LssAssignArgs),
}

/// `lss set-node-id`.
#[derive(Args, Debug)]
pub struct LssSetArgs {
    /// The new node-ID.
    #[arg(value_parser = clap::value_parser!(u8).range(1..=127))]
    pub new_id: u8,
    /// 1018h:1 vendor-ID (with --product, --revision and --serial: the slave's LSS address).
    #[arg(long)]
    pub vendor: Option<String>,
    /// 1018h:2 product code.
    #[arg(long)]
    pub product: Option<String>,
    /// 1018h:3 revision number.
    #[arg(long)]
    pub revision: Option<String>,
    /// 1018h:4 serial number.
    #[arg(long)]
    pub serial: Option<String>,
    /// Also store the configuration in the slave.
    #[arg(long)]
    pub store: bool,
}

/// `lss assign`.
#[derive(Args, Debug)]
pub struct LssAssignArgs {
    /// The node-ID for the first slave found; the next ones count up.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=127))]
    pub first: u8,
    /// Also store each node-ID in its slave.
    #[arg(long)]
    pub store: bool,
}
