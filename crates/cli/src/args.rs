//! The command line: global options and every subcommand (clap derive).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// Default socketcand port and address of `drivebus serve`.
pub const DEFAULT_LISTEN: &str = "127.0.0.1:29536";

const TOP_EXAMPLES: &str = "\
Examples:
  drivebus demo                                   the main job, on an in-process virtual bus
  drivebus serve --drive akd:1 --drive dds6:2     virtual drives for python-can (socketcand)
  drivebus --bus socketcand://127.0.0.1:29536/can0 scan
  drivebus --bus socketcand://127.0.0.1:29536/can0 --node 1 sdo read 0x1000 0
  drivebus --bus virtual --sim akd:1 --node 1 drive status
  drivebus --bus slcan:///dev/ttyUSB0?bitrate=1000000 dump --candump

Bus URLs: socketcand://HOST:PORT/CHANNEL, slcan:///dev/ttyUSB0?bitrate=1000000,
socketcan://can0, virtual (in-process; add drives with --sim PROFILE:NODE).
Environment: DRIVEBUS_BUS sets the default --bus; RUST_LOG the log level.";

/// drivebus: a CANopen (CiA 301/402) tool for real and virtual buses.
#[derive(Parser, Debug)]
#[command(name = "drivebus", version, about, after_help = TOP_EXAMPLES)]
pub struct Cli {
    /// Global options.
    #[command(flatten)]
    pub global: Global,
    /// What to do.
    #[command(subcommand)]
    pub cmd: Command,
}

/// Options every command understands.
#[derive(Args, Debug, Clone)]
pub struct Global {
    /// The bus: socketcand://HOST:PORT/CHANNEL, slcan:///dev/ttyUSB0?bitrate=N,
    /// socketcan://IFACE or virtual.
    #[arg(long, global = true, env = "DRIVEBUS_BUS", default_value = "virtual")]
    pub bus: String,
    /// Node-ID (1..127) of the device to talk to.
    #[arg(long, short = 'n', global = true, value_parser = clap::value_parser!(u8).range(1..=127))]
    pub node: Option<u8>,
    /// EDS or DCF file of the device: object names and data types.
    #[arg(long, global = true)]
    pub eds: Option<PathBuf>,
    /// Machine-readable output (JSON) instead of text.
    #[arg(long, global = true)]
    pub json: bool,
    /// SDO and response timeout in milliseconds.
    #[arg(long, global = true, default_value_t = 1000)]
    pub timeout: u64,
    /// On the `virtual` bus: host a virtual drive PROFILE:NODE in this
    /// process (repeatable), e.g. --sim akd:1.
    #[arg(long = "sim", global = true, value_name = "PROFILE:NODE")]
    pub sim: Vec<String>,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Serve virtual drives on a socketcand TCP server (python-can, canopen), or on any bus (--bus).
    #[command(after_help = SERVE_EXAMPLES)]
    Serve(ServeArgs),
    /// Run the demo: two virtual drives, PDOs, homing, a move and a CSP sine; writes an SVG plot.
    #[command(after_help = DEMO_EXAMPLES)]
    Demo(DemoArgs),
    /// Find the nodes on the bus (SDO 1000h sweep).
    #[command(after_help = SCAN_EXAMPLES)]
    Scan(ScanArgs),
    /// Read and write objects (SDO).
    #[command(
        subcommand,
        after_help = "Examples:\n  drivebus --node 1 sdo read 0x1000 0\n  drivebus --node 1 sdo write 0x1017 0 100 --type u16\n  drivebus --node 1 sdo upload 0x1008 0 name.bin"
    )]
    Sdo(SdoCmd),
    /// Network management: start, stop, pre-operational, reset.
    #[command(after_help = NMT_EXAMPLES)]
    Nmt(NmtArgs),
    /// Show or change PDO configuration.
    #[command(
        subcommand,
        after_help = "Examples:\n  drivebus --node 1 pdo show\n  drivebus --node 1 pdo map tpdo 1 0x6041:0:16 0x6064:0:32 --type 1"
    )]
    Pdo(PdoCmd),
    /// Control a CiA 402 drive (state machine, moves).
    #[command(
        subcommand,
        after_help = "Examples:\n  drivebus --node 1 drive enable\n  drivebus --node 1 drive home --method 35\n  drivebus --node 1 drive move 90000\n  drivebus --node 1 drive status --json"
    )]
    Drive(DriveCmd),
    /// Live decoded trace of the bus.
    #[command(after_help = DUMP_EXAMPLES)]
    Dump(DumpArgs),
    /// EDS/DCF files: check, show, export.
    #[command(
        subcommand,
        after_help = "Examples:\n  drivebus eds check drive.eds\n  drivebus eds show --profile akd\n  drivebus eds export --profile akd --out akd.eds"
    )]
    Eds(EdsCmd),
    /// Layer setting services (CiA 305).
    #[command(
        subcommand,
        after_help = "Examples:\n  drivebus lss scan\n  drivebus lss set-node-id 5 --store"
    )]
    Lss(LssCmd),
    /// Emulate an slcan adapter on a pseudo-terminal, with virtual drives behind it.
    #[command(name = "slcan-pty", after_help = SLCAN_EXAMPLES)]
    SlcanPty(SlcanPtyArgs),
}

const SERVE_EXAMPLES: &str = "\
Examples:
  drivebus serve --drive akd:1
  drivebus serve --listen 127.0.0.1:29536 --channel can0 --drive kc1:1 --drive dds6:2 --state-dir ./state
  drivebus serve --drive generic:5 --bitrate 1000000
  drivebus serve --drive generic:5 --fault drop:0x185,every=10   (lose every 10th TPDO1)
  drivebus serve --drive akd:1 --eds-object   (then: drivebus --bus socketcand://127.0.0.1:29536/can0 --node 1 eds export)
  drivebus serve --bus socketcan://can0 --drive akd:1            (virtual drive on a real bus)
  drivebus serve --bus 'slcan:///dev/ttyACM0?bitrate=500000' --drive kc1:3
  drivebus serve --bus socketcand://192.0.2.10:29536/can0 --drive dds6:2 --listen 127.0.0.1:29536

Without --bus (or with --bus virtual) the drives sit on an in-process bus served over socketcand at
--listen (default 127.0.0.1:29536). With --bus URL they sit on that bus, keeping their own timing
(heartbeats, SYNC-driven PDOs, EMCY inhibit times); the socketcand listener is then off unless
--listen is given (it shares the drives and the bus traffic).
Prints one line when ready: `listening on HOST:PORT (channel NAME)` when listening, `serving on URL`
otherwise; stops on SIGINT/SIGTERM (exit 0).
python-can: can.Bus(interface='socketcand', host='127.0.0.1', port=29536, channel='can0')";

/// `drivebus serve`.
#[derive(Args, Debug)]
pub struct ServeArgs {
    /// TCP address of the socketcand listener [default: 127.0.0.1:29536 on the virtual bus; off
    /// with --bus URL unless given].
    #[arg(long, value_name = "HOST:PORT")]
    pub listen: Option<String>,
    /// The bus name clients open (`< open NAME >`).
    #[arg(long, default_value = "can0")]
    pub channel: String,
    /// A virtual drive: PROFILE (kc1, akd, ipos, ssd630, dds6, generic) and NODE (1..127).
    #[arg(long = "drive", value_name = "PROFILE:NODE", required = true)]
    pub drives: Vec<String>,
    /// Directory where each drive keeps its stored parameters (1010h).
    #[arg(long)]
    pub state_dir: Option<PathBuf>,
    /// Pace frames like a CAN bus at this bit rate (the in-process bus the drives and the
    /// listener share; a real bus paces itself).
    #[arg(long, value_name = "BPS")]
    pub bitrate: Option<u32>,
    /// Fault injection on the hosting bus (repeatable): `drop:IDS[,every=N][,skip=N][,times=N]`
    /// or `corrupt:IDS:MASK[,...]`; IDS is `0x585` or `0x180-0x1FF`, MASK is hex XORed onto the data.
    #[arg(long = "fault", value_name = "RULE")]
    pub faults: Vec<String>,
    /// Give every drive 1021h "store EDS" and 1022h (CiA 301 §7.5.2.21): its EDS, generated from
    /// its running dictionary, read by SDO upload. Without it only `generic` has them (the other
    /// manuals do not list them).
    #[arg(long)]
    pub eds_object: bool,
}

const DEMO_EXAMPLES: &str = "\
Examples:
  drivebus demo
  drivebus demo --out /tmp/demo.svg --no-progress
  drivebus demo --realtime          (watch it run at 1 kHz SYNC in wall-clock time)";

/// `drivebus demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Where to write the SVG plot.
    #[arg(long, default_value = "drivebus-demo.svg")]
    pub out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    pub no_progress: bool,
    /// Pace the simulation in real time (1 SYNC per wall-clock ms) instead of as fast as possible.
    #[arg(long)]
    pub realtime: bool,
    /// Duration of the CSP sine in seconds.
    #[arg(long, default_value_t = 2.0)]
    pub sine_seconds: f64,
}

const SCAN_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 scan
  drivebus --bus virtual --sim akd:1 --sim dds6:2 scan --json";

/// `drivebus scan`.
#[derive(Args, Debug)]
pub struct ScanArgs {
    /// First node-ID to probe.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=127))]
    pub from: u8,
    /// Last node-ID to probe.
    #[arg(long, default_value_t = 127, value_parser = clap::value_parser!(u8).range(1..=127))]
    pub to: u8,
    /// Time to wait for answers after the sweep, in ms.
    #[arg(long, default_value_t = 300)]
    pub wait: u64,
}

/// `drivebus sdo ...`.
#[derive(Subcommand, Debug)]
pub enum SdoCmd {
    /// Read an object and print its value.
    #[command(
        after_help = "Examples:\n  drivebus --node 1 sdo read 0x1000 0\n  drivebus --node 1 sdo read 0x6041 0 --type u16\n  drivebus --node 1 --eds akd.eds sdo read 0x1008 0"
    )]
    Read(SdoRead),
    /// Write a value to an object.
    #[command(
        after_help = "Examples:\n  drivebus --node 1 sdo write 0x1017 0 100 --type u16\n  drivebus --node 1 --eds akd.eds sdo write 0x6083 0 50000"
    )]
    Write(SdoWrite),
    /// Read an object into a file (progress bar).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 sdo upload 0x1008 0 name.bin\n  drivebus --node 1 sdo upload 0x1021 0 device.eds --block"
    )]
    Upload(SdoFile),
    /// Write a file into an object (progress bar).
    #[command(after_help = "Examples:\n  drivebus --node 1 sdo download 0x1F50 1 firmware.bin --block")]
    Download(SdoFile),
}

/// `sdo read`.
#[derive(Args, Debug)]
pub struct SdoRead {
    /// Object index (0x6041 or 6041h).
    pub index: String,
    /// Sub-index.
    #[arg(default_value = "0")]
    pub sub: String,
    /// Data type (u8, u16, u32, i16, i32, str, bytes, UNSIGNED16, ...); default: from --eds, else hex bytes.
    #[arg(long = "type", short = 't')]
    pub ty: Option<String>,
}

/// `sdo write`.
#[derive(Args, Debug)]
pub struct SdoWrite {
    /// Object index.
    pub index: String,
    /// Sub-index.
    pub sub: String,
    /// The value (decimal, 0x hex, text for strings, hex bytes for bytes).
    #[arg(allow_hyphen_values = true)]
    pub value: String,
    /// Data type; default: from --eds.
    #[arg(long = "type", short = 't')]
    pub ty: Option<String>,
}

/// `sdo upload|download`.
#[derive(Args, Debug)]
pub struct SdoFile {
    /// Object index.
    pub index: String,
    /// Sub-index.
    pub sub: String,
    /// The file.
    pub file: PathBuf,
    /// Use SDO block transfer.
    #[arg(long)]
    pub block: bool,
}

const NMT_EXAMPLES: &str = "\
Examples:
  drivebus --node 1 nmt start
  drivebus nmt reset --all
  drivebus --node 2 nmt preop";

/// `drivebus nmt`.
#[derive(Args, Debug)]
pub struct NmtArgs {
    /// The command.
    pub command: NmtKind,
    /// Address every node (node-ID 0) instead of --node.
    #[arg(long)]
    pub all: bool,
}

/// NMT commands.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum NmtKind {
    /// Start remote node (operational).
    Start,
    /// Stop remote node.
    Stop,
    /// Enter pre-operational.
    Preop,
    /// Reset node.
    Reset,
    /// Reset communication.
    ResetComm,
}

/// `drivebus pdo ...`.
#[derive(Subcommand, Debug)]
pub enum PdoCmd {
    /// Show the RPDO and TPDO configuration of a node.
    #[command(
        after_help = "Examples:\n  drivebus --node 1 pdo show\n  drivebus --node 1 --eds akd.eds pdo show --json"
    )]
    Show,
    /// Map objects into a PDO (node in pre-operational).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 pdo map tpdo 1 0x6041:0:16 0x6064:0:32 --type 1\n  drivebus --node 1 pdo map rpdo 2 0x6040:0:16 0x607A:0:32"
    )]
    Map(PdoMapArgs),
}

/// Direction of a PDO.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PdoDir {
    /// Receive PDO (master → device).
    Rpdo,
    /// Transmit PDO (device → master).
    Tpdo,
}

/// `pdo map`.
#[derive(Args, Debug)]
pub struct PdoMapArgs {
    /// rpdo or tpdo.
    pub dir: PdoDir,
    /// PDO number, 1-based.
    #[arg(value_parser = clap::value_parser!(u16).range(1..=512))]
    pub number: u16,
    /// Entries INDEX:SUB:BITS (e.g. 0x6041:0:16).
    #[arg(required = true)]
    pub entries: Vec<String>,
    /// Transmission type (0..255).
    #[arg(long = "type")]
    pub transmission: Option<u8>,
    /// Event timer in ms (TPDO).
    #[arg(long)]
    pub event_timer: Option<u16>,
    /// COB-ID (default: keep the current one).
    #[arg(long)]
    pub cob_id: Option<String>,
}

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
        after_help = "Examples:\n  drivebus --node 1 drive move 90000\n  drivebus --node 1 drive move -45000 --relative --velocity 100000"
    )]
    Move(MoveArgs),
    /// Profile velocity (mode 3).
    #[command(
        after_help = "Examples:\n  drivebus --node 1 drive velocity 36000\n  drivebus --node 1 drive velocity 0"
    )]
    Velocity(ValueArg),
    /// Profile torque (mode 4), per mille of rated torque.
    #[command(after_help = "Examples:\n  drivebus --node 1 drive torque 100")]
    Torque(ValueArg),
    /// Homing (mode 6), waits for homing attained.
    #[command(after_help = "Examples:\n  drivebus --node 1 drive home --method 35")]
    Home(HomeArgs),
    /// Quick stop.
    #[command(after_help = "Examples:\n  drivebus --node 1 drive quickstop")]
    Quickstop,
    /// Fault reset.
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
    /// Profile velocity (6081h).
    #[arg(long)]
    pub velocity: Option<u32>,
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

const DUMP_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 dump
  drivebus --bus socketcand://127.0.0.1:29536/can0 --eds akd.eds dump --seconds 10
  drivebus dump --candump > bus.log";

/// `drivebus dump`.
#[derive(Args, Debug)]
pub struct DumpArgs {
    /// Print candump log lines instead of the decoded trace.
    #[arg(long)]
    pub candump: bool,
    /// Stop after this many frames.
    #[arg(long)]
    pub count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long)]
    pub seconds: Option<f64>,
}

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

/// `drivebus lss ...`.
#[derive(Subcommand, Debug)]
pub enum LssCmd {
    /// Find unconfigured LSS slaves (fastscan) and print their addresses.
    #[command(after_help = "Examples:\n  drivebus lss scan")]
    Scan,
    /// Give a node-ID to the LSS slave selected by its address (or the only one on the bus).
    #[command(
        after_help = "Examples:\n  drivebus lss set-node-id 5 --vendor 0x6A --product 0x1 --revision 1 --serial 1234\n  drivebus lss set-node-id 5   (only one LSS slave on the bus)"
    )]
    SetNodeId(LssSetArgs),
}

/// `lss set-node-id`.
#[derive(Args, Debug)]
pub struct LssSetArgs {
    /// The new node-ID.
    #[arg(value_parser = clap::value_parser!(u8).range(1..=127))]
    pub new_id: u8,
    /// 1018h:1.
    #[arg(long)]
    pub vendor: Option<String>,
    /// 1018h:2.
    #[arg(long)]
    pub product: Option<String>,
    /// 1018h:3.
    #[arg(long)]
    pub revision: Option<String>,
    /// 1018h:4.
    #[arg(long)]
    pub serial: Option<String>,
    /// Also store the configuration in the slave.
    #[arg(long)]
    pub store: bool,
}

const SLCAN_EXAMPLES: &str = "\
Examples:
  drivebus slcan-pty --drive akd:1
  drivebus slcan-pty --drive kc1:1 --drive dds6:2 --seconds 60

Prints `slcan-pty PATH`; open PATH with python-can: can.Bus(interface='slcan', channel=PATH).";

/// `drivebus slcan-pty`.
#[derive(Args, Debug)]
pub struct SlcanPtyArgs {
    /// A virtual drive PROFILE:NODE behind the adapter (repeatable).
    #[arg(long = "drive", value_name = "PROFILE:NODE")]
    pub drives: Vec<String>,
    /// Stop after this many seconds (default: until SIGINT/SIGTERM).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Fault injection on the hosting bus (repeatable): `drop:IDS[,every=N][,skip=N][,times=N]`
    /// or `corrupt:IDS:MASK[,...]`; IDS is `0x585` or `0x180-0x1FF`, MASK is hex XORed onto the data.
    #[arg(long = "fault", value_name = "RULE")]
    pub faults: Vec<String>,
}
