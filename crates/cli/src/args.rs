//! The command line: global options and the subcommands (clap derive).
//! Node-level command arguments are in `args_node.rs`.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

pub use crate::args_bus::*;
pub use crate::args_node::*;

/// Default socketcand port and address of `drivebus serve`.
pub const DEFAULT_LISTEN: &str = "127.0.0.1:29536";

const TOP_EXAMPLES: &str = "\
Examples:
  drivebus demo                                   the main job, on an in-process virtual bus
  drivebus demo --ethercat                        the same on EtherCAT: ethercrab master + emulated iPOS
  drivebus serve --drive akd:1 --drive dds6:2     virtual drives for python-can (socketcand)
  drivebus --bus socketcand://127.0.0.1:29536/can0 scan
  drivebus --bus socketcand://127.0.0.1:29536/can0 --node 1 sdo read 1000
  drivebus --bus virtual --sim akd:1 --node 1 drive status
  drivebus --bus slcan:///dev/ttyUSB0?bitrate=1000000 dump --candump
  drivebus ethercat scan --iface eth1             EtherCAT master (root): scan, sdo, state, pdo, drive

Object indices and sub-indices are hexadecimal (6041, 0x6041, 6041h, 6041:00);
CiA 301/402 objects also go by name (statusword, identity/vendor-id).
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

/// Options of the commands that talk to a bus. A command refuses the ones
/// it has no use for.
#[derive(Args, Debug, Clone)]
pub struct Global {
    /// The bus: socketcand://HOST:PORT/CHANNEL, slcan:///dev/ttyUSB0?bitrate=N,
    /// socketcan://IFACE or virtual.
    #[arg(long, global = true, env = "DRIVEBUS_BUS", default_value = "virtual")]
    pub bus: String,
    /// Node-ID (1..127, decimal or 0x hex) of the device to talk to.
    #[arg(long, short = 'n', global = true, value_parser = node_id)]
    pub node: Option<u8>,
    /// EDS or DCF file of the device: object names and data types (CiA 301/402
    /// standard objects are known without it).
    #[arg(long, global = true)]
    pub eds: Option<PathBuf>,
    /// Machine-readable output: one JSON object (errors too: {"error":{"code","message"}}).
    #[arg(long, global = true)]
    pub json: bool,
    /// SDO and response timeout in milliseconds [default: 1000].
    #[arg(long, global = true, value_name = "MS")]
    pub timeout: Option<u64>,
    /// SDO retries after a timeout.
    #[arg(long, global = true, default_value_t = 0)]
    pub retries: u8,
    /// On the `virtual` bus: host a virtual drive PROFILE:NODE in this
    /// process (repeatable), e.g. --sim akd:1, or a device from its EDS or
    /// DCF, FILE:NODE (a name ending in .eds or .dcf), e.g. --sim io16.eds:3.
    #[arg(long = "sim", global = true, value_name = "PROFILE:NODE")]
    pub sim: Vec<String>,
    /// The machine around the virtual drives of --sim, serve, slcan-pty and demo: a TOML file
    /// with a [[node]] table per node that differs from its profile's default machine (limit,
    /// home switch, hard stops, index, load, gear, faults at run time; docs/machine.md).
    #[arg(long, global = true, value_name = "FILE")]
    pub machine: Option<PathBuf>,
}

impl Global {
    /// `--timeout` in ms, or the command's own default.
    pub fn timeout_ms(&self, default: u64) -> u64 {
        self.timeout.unwrap_or(default).max(1)
    }
}

/// A node-ID as people write it: `5`, `0x05`, `05h`.
pub fn node_id(s: &str) -> Result<u8, String> {
    match crate::dict::number(s) {
        Ok(n @ 1..=127) => Ok(n as u8),
        _ => Err(format!("`{s}` is not a node-ID 1..127 (decimal, or hex as 0x7F)")),
    }
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Serve virtual drives on a socketcand TCP server (python-can, canopen), or on any bus (--bus).
    #[command(after_help = SERVE_EXAMPLES)]
    Serve(ServeArgs),
    /// Change a running `serve --control` or `ethercat serve --control`: set inputs, trigger and
    /// clear faults, drop or corrupt frames, break an EtherCAT line, switch a node's power.
    #[command(after_help = crate::control_cmd::CONTROL_EXAMPLES)]
    Control(crate::control_cmd::ControlArgs),
    /// Run the demo: two virtual drives, PDOs, homing, a move and a CSP sine; writes an SVG plot.
    #[command(after_help = DEMO_EXAMPLES)]
    Demo(DemoArgs),
    /// Find the nodes on the bus (SDO 1000h sweep).
    #[command(after_help = SCAN_EXAMPLES)]
    Scan(ScanArgs),
    /// Read and write objects (SDO), store/restore parameters, dump a node to a DCF.
    #[command(subcommand, after_help = SDO_EXAMPLES)]
    Sdo(SdoCmd),
    /// Network management: start, stop, pre-operational, reset.
    #[command(after_help = NMT_EXAMPLES)]
    Nmt(NmtArgs),
    /// Show or change PDO configuration.
    #[command(subcommand, after_help = PDO_EXAMPLES)]
    Pdo(PdoCmd),
    /// Control a CiA 402 drive (state machine, moves, homing).
    #[command(subcommand, after_help = DRIVE_EXAMPLES)]
    Drive(DriveCmd),
    /// Live decoded trace of the bus (filters, PDOs decoded by their mapping).
    #[command(after_help = DUMP_EXAMPLES)]
    Dump(DumpArgs),
    /// Live table of the nodes: NMT state, last EMCY, chosen values.
    #[command(after_help = MONITOR_EXAMPLES)]
    Monitor(MonitorArgs),
    /// Send raw frames (cansend syntax: 601#40.00.10.00, 123#R, 1ABCDEF0#11).
    #[command(after_help = SEND_EXAMPLES)]
    Send(SendArgs),
    /// Produce SYNC, heartbeat and TIME from this tool (cyclic, until Ctrl-C or --seconds).
    #[command(after_help = PRODUCE_EXAMPLES)]
    Produce(ProduceArgs),
    /// Load generator: random or counting frames at a given gap (cangen).
    #[command(after_help = GEN_EXAMPLES)]
    Gen(GenArgs),
    /// Bus statistics: load, frames per second per COB-ID, error frames and counters.
    #[command(after_help = STATS_EXAMPLES)]
    Stats(StatsArgs),
    /// Replay a candump log with its timing (canplayer).
    #[command(after_help = REPLAY_EXAMPLES)]
    Replay(ReplayArgs),
    /// CiA 309-3 ASCII gateway on stdin/stdout or TCP (cocomm, coctl lines).
    #[command(after_help = GATEWAY_EXAMPLES)]
    Gateway(GatewayArgs),
    /// The page in the browser: nodes, objects, drive panel and scope over the bus (HTTP API).
    #[command(after_help = UI_EXAMPLES)]
    Ui(UiArgs),
    /// EDS/DCF files: check, show, export.
    #[command(subcommand, after_help = EDS_EXAMPLES)]
    Eds(EdsCmd),
    /// Layer setting services (CiA 305): find unconfigured slaves, set node-IDs.
    #[command(subcommand, after_help = LSS_EXAMPLES)]
    Lss(LssCmd),
    /// Emulate an slcan adapter on a pseudo-terminal, with virtual drives behind it.
    #[command(name = "slcan-pty", after_help = SLCAN_EXAMPLES)]
    SlcanPty(SlcanPtyArgs),
    /// EtherCAT: serve drive twins as software slaves; scan, SDO, AL state, PDOs and drives as a master.
    #[command(subcommand)]
    Ethercat(crate::ethercat::EthercatCmd),
}

const SERVE_EXAMPLES: &str = "\
Examples:
  drivebus serve --drive akd:1
  drivebus serve --listen 127.0.0.1:29536 --channel can0 --drive kc1:1 --drive dds6:2 --state-dir ./state
  drivebus serve --drive generic:5 --bitrate 1000000
  drivebus serve --drive generic:5 --fault drop:0x185,every=10   (lose every 10th TPDO1)
  drivebus serve --drive akd:1 --eds-object   (then: drivebus --bus socketcand://127.0.0.1:29536/can0 --node 1 eds export)
  drivebus serve --drive generic:5 --machine machine.toml   (its switches, stops, load, faults: docs/machine.md)
  drivebus serve --bus socketcan://can0 --drive akd:1            (virtual drive on a real bus)
  drivebus serve --bus 'slcan:///dev/ttyACM0?bitrate=500000' --drive kc1:3
  drivebus serve --bus socketcand://192.0.2.10:29536/can0 --drive dds6:2 --listen 127.0.0.1:29536

Without --bus (or with --bus virtual) the drives sit on an in-process bus served over socketcand at
--listen (default 127.0.0.1:29536). With --bus URL they sit on that bus, keeping their own timing
(heartbeats, SYNC-driven PDOs, EMCY inhibit times); the socketcand listener is then off unless
--listen is given (it shares the drives and the bus traffic).
Every drive moves its profile's default machine (limit and home switches, hard stops, index, load),
changed per node by --machine FILE.
Prints one line when ready: `listening on HOST:PORT (channel NAME)` when listening, `serving on URL`
otherwise (ending `; control on ADDR` with --control); stops on SIGINT/SIGTERM (exit 0).
With --control ADDR, `drivebus control --connect ADDR ...` sets inputs, triggers and clears faults,
drops frames and switches a drive's power while it runs (docs/control.md).
python-can: can.Bus(interface='socketcand', host='127.0.0.1', port=29536, channel='can0')";

const UI_EXAMPLES: &str = "\
Examples:
  drivebus ui --sim akd:1 --sim dds6:2                       two virtual drives, page on 127.0.0.1:8402
  drivebus ui --bus socketcand://127.0.0.1:29536/can0 --http 127.0.0.1:0
  drivebus ui --bus socketcan://can0 --http 0.0.0.0:8402        (beyond loopback: needs the printed token)

Prints one line when ready: `drivebus ui: open http://ADDR/ in a browser (...)`; runs until
SIGINT/SIGTERM. The API (REST + WebSocket) is in docs/http-api.md.";

/// `drivebus ui`.
#[derive(Args, Debug)]
pub struct UiArgs {
    /// Address of the web server (port 0 picks a free one). Beyond loopback every request needs
    /// the token printed at start.
    #[arg(long, value_name = "HOST:PORT", default_value = crate::web::DEFAULT_HTTP)]
    pub http: String,
}

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
    #[arg(long = "drive", value_name = "PROFILE:NODE", required_unless_present = "devices")]
    pub drives: Vec<String>,
    /// A device from its EDS or DCF (repeatable): its objects, defaults and PDOs; a CiA 401 I/O
    /// module when its 1000h says so (inputs from --machine: docs/machine.md). A DCF may leave
    /// :NODE out: its [DeviceComissioning] NodeID.
    #[arg(long = "device", value_name = "FILE:NODE")]
    pub devices: Vec<String>,
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
    /// Accept control requests (inputs, machine faults, bus faults, power) on this loopback
    /// address (127.0.0.1:PORT) or Unix socket path: `drivebus control`, docs/control.md. Off
    /// unless given.
    #[arg(long, value_name = "ADDR")]
    pub control: Option<String>,
    /// Give every drive 1021h "store EDS" and 1022h (CiA 301 §7.5.2.21): its EDS, generated from
    /// its running dictionary, read by SDO upload. Without it only `generic` has them (the other
    /// manuals do not list them).
    #[arg(long)]
    pub eds_object: bool,
    /// Also serve the page and its HTTP API for these drives on HOST:PORT (`drivebus ui`; port 0
    /// picks a free one; beyond loopback every request needs the token printed at start).
    #[arg(long, value_name = "HOST:PORT")]
    pub http: Option<String>,
    /// An unconfigured CiA 301 slave (node-ID FFh, LSS CiA 305) with this LSS address
    /// (repeatable; numbers decimal or 0x hex): `drivebus lss` or the page gives it a node-ID.
    #[arg(long = "lss-slave", value_name = "VENDOR:PRODUCT:REVISION:SERIAL")]
    pub lss_slaves: Vec<String>,
}

const DEMO_EXAMPLES: &str = "\
Examples:
  drivebus demo
  drivebus demo --out /tmp/demo.svg --no-progress
  drivebus demo --realtime          (watch it run at 1 kHz SYNC in wall-clock time)
  drivebus demo --ethercat          (ethercrab master + emulated iPOS, DC SYNC0 at 1 ms)

The demo runs the master library (the same code as `drivebus --bus URL drive ...`)
against an AKD (node 1) and a DDS6 (node 2) on the virtual bus in simulated time.
With --ethercat it runs the EtherCAT master of `drivebus ethercat drive` against an emulated iPOS
over the in-process link.";

/// `drivebus demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Where to write the SVG plot [default: drivebus-demo.svg; drivebus-demo-ethercat.svg with
    /// --ethercat].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The EtherCAT demo: an ethercrab master and an emulated iPOS in one process (in-process
    /// link, no root): OP with DC SYNC0 at 1 ms, homing, a move, a CSP sine.
    #[arg(long)]
    pub ethercat: bool,
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
  drivebus --bus virtual --sim akd:1 --sim dds6:2 scan --json
  drivebus scan --from 1 --to 16 --wait 50";

/// `drivebus scan`.
#[derive(Args, Debug)]
pub struct ScanArgs {
    /// First node-ID to probe.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=127))]
    pub from: u8,
    /// Last node-ID to probe.
    #[arg(long, default_value_t = 127, value_parser = clap::value_parser!(u8).range(1..=127))]
    pub to: u8,
    /// Time each node has to answer 1000h, in ms.
    #[arg(long, default_value_t = 300)]
    pub wait: u64,
}

const NMT_EXAMPLES: &str = "\
Examples:
  drivebus --node 1 nmt start
  drivebus nmt reset --all
  drivebus --node 2 nmt preop

The command's frame is on the bus (written by the transport) before it reports success.";

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
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
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

const DUMP_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 dump
  drivebus --bus socketcand://127.0.0.1:29536/can0 --node 1 dump --pdo   (node 1's frames, PDOs decoded)
  drivebus --bus socketcand://127.0.0.1:29536/can0 dump --id 0x180-0x1FF --seconds 10
  drivebus --bus socketcand://127.0.0.1:29536/can0 dump --filter 181:7FF,080:7FF   (candump filters)
  drivebus --bus socketcand://127.0.0.1:29536/can0 dump --filter 080~7FF -t delta  (all but SYNC, delta times)
  drivebus --bus socketcand://127.0.0.1:29536/can0 dump --pcap bus.pcapng --seconds 10   (Wireshark)
  drivebus --bus socketcand://127.0.0.1:29536/can0 --node 1 dump --pdo --csv > pdo.csv  (spreadsheets)
  drivebus dump --candump > bus.log

Filters (candump): ID:MASK passes a frame when id & MASK == ID & MASK, ID~MASK when not; hex;
several (comma-separated or repeated) pass a frame any of them passes, `j` among them: all must.
The id carries SocketCAN's flags (80000000 extended, 40000000 remote): 40000000:40000000 passes RTRs.
Timestamps (-t): zero (since the first frame shown, the default), delta (since the previous one),
absolute (Unix time); --candump lines always carry absolute times (candump -l, `replay` reads them).
Remote (RTR) frames are shown where the transport carries them; socketcand carries none, and dump
says so when it starts.";

/// `drivebus dump`.
#[derive(Args, Debug)]
pub struct DumpArgs {
    /// Print candump log lines instead of the decoded trace.
    #[arg(long)]
    pub candump: bool,
    /// Stop after this many frames (after filtering).
    #[arg(long)]
    pub count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Only frames with these CAN-IDs (repeatable): 0x181, 181, 0x180-0x1FF.
    #[arg(long = "id", value_name = "RANGE")]
    pub ids: Vec<String>,
    /// Decode PDOs by their mapping, read from the device(s) by SDO at start
    /// (with --eds: the EDS default mapping instead).
    #[arg(long)]
    pub pdo: bool,
    /// candump filters (repeatable, or comma-separated): ID:MASK, ID~MASK (inverted), j (join).
    #[arg(long = "filter", value_name = "ID:MASK")]
    pub filters: Vec<String>,
    /// Timestamps: zero (since the first frame shown), delta (since the previous one), absolute
    /// (Unix time) [default: zero; absolute with --candump].
    #[arg(long, short = 't', value_enum, value_name = "MODE")]
    pub timestamp: Option<TimestampMode>,
    /// Also write the frames shown as pcapng (SocketCAN link type) for Wireshark; `-` writes it to
    /// stdout instead of the trace (`| wireshark -k -i -`).
    #[arg(long, value_name = "FILE")]
    pub pcap: Option<PathBuf>,
    /// With --pdo: CSV, one row per PDO and a column per mapped object (spreadsheets, plotting).
    #[arg(long, requires = "pdo", conflicts_with = "candump")]
    pub csv: bool,
}

const MONITOR_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 monitor
  drivebus --bus socketcand://127.0.0.1:29536/can0 monitor --watch statusword --watch 6064 --period 200
  drivebus --bus socketcand://127.0.0.1:29536/can0 --json monitor --seconds 5   (JSON lines)
  drivebus --bus socketcand://127.0.0.1:29536/can0 monitor --watch 6064 --csv > nodes.csv

On a terminal the table is redrawn in place; otherwise one line per change is printed.";

/// `drivebus monitor`.
#[derive(Args, Debug)]
pub struct MonitorArgs {
    /// An object to show per node (repeatable): index[:sub] in hex or a name.
    /// Read from the node's TPDOs when mapped, else by SDO every --period.
    #[arg(long = "watch", value_name = "OBJECT")]
    pub watch: Vec<String>,
    /// SDO refresh period in ms for watched objects not in a TPDO.
    #[arg(long, default_value_t = 500)]
    pub period: u64,
    /// Stop after this many seconds (default: until Ctrl-C).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Scan for nodes at start (SDO 1000h sweep) instead of only listening.
    #[arg(long)]
    pub scan: bool,
    /// CSV: a header, then a row per change (time, node, state, EMCY, watched values as numbers).
    #[arg(long)]
    pub csv: bool,
}

const SEND_EXAMPLES: &str = "\
Examples:
  drivebus send 601#40.00.10.00.00.00.00.00     SDO read of 1000h from node 1
  drivebus send 000#0100                        NMT start all nodes
  drivebus send 701#R1                          node guarding request (RTR, DLC 1)
  drivebus send 18FF50E5#0102                   extended (29-bit) identifier
  drivebus send 080# 080# 080#                  three SYNCs (several frames in order)
  drivebus send 201#0F00 --period 10            RPDO1 every 10 ms until Ctrl-C (cyclic transmit)
  drivebus send 080# 181#01 --period 1 --count 500   both frames every ms, 500 times

With --period the frames go out again every period (as a group, in order), --count times or until
Ctrl-C; a period the transport could not keep is reported.";

/// `drivebus send`.
#[derive(Args, Debug)]
pub struct SendArgs {
    /// Frames in cansend syntax: ID#DATA (3 hex digits standard, 8 extended),
    /// data bytes in hex with optional '.', ID#R[LEN] for a remote frame.
    #[arg(required = true, value_name = "FRAME")]
    pub frames: Vec<String>,
    /// Send the frames again every MS milliseconds (fractions allowed) until --count or Ctrl-C.
    #[arg(long, value_name = "MS")]
    pub period: Option<f64>,
    /// How many times to send the frames (with --period).
    #[arg(long, requires = "period")]
    pub count: Option<u64>,
}

const REPLAY_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 replay bus.log
  drivebus replay -I bus.log -l 3 -g 1            (three times, 1 ms between frames)
  drivebus replay bus.log -t                      (ignore timestamps: as fast as possible)
  drivebus replay bus.log -s 2                    (skip gaps longer than 2 s)

The log is candump -l format: (SECONDS.MICROS) IFACE ID#DATA; a bad line is named with its number.";

/// `drivebus replay`.
#[derive(Args, Debug)]
pub struct ReplayArgs {
    /// The candump log.
    #[arg(value_name = "FILE", required_unless_present = "input", conflicts_with = "input")]
    pub file: Option<PathBuf>,
    /// The candump log (canplayer's -I).
    #[arg(short = 'I', value_name = "FILE")]
    pub input: Option<PathBuf>,
    /// Play the log this many times; `i` for ever (canplayer's -l).
    #[arg(short = 'l', long = "loop", value_name = "N|i", default_value = "1")]
    pub loops: String,
    /// Ignore the timestamps: send the frames back to back, or --gap apart (canplayer's -t).
    #[arg(short = 't', long = "ignore-timestamps")]
    pub ignore_timestamps: bool,
    /// Milliseconds between frames when timestamps are ignored (canplayer's -g).
    #[arg(short = 'g', long = "gap", value_name = "MS", default_value_t = 0.0)]
    pub gap: f64,
    /// Shorten gaps in the log longer than this many seconds to it (canplayer's -s).
    #[arg(short = 's', long = "skip-gaps", value_name = "SECS")]
    pub skip_gaps: Option<f64>,
    /// Only frames of this log interface (e.g. can0); default: every line.
    #[arg(long, value_name = "IFACE")]
    pub interface: Option<String>,
    /// Print each frame as it is sent (canplayer's -v).
    #[arg(short = 'v', long)]
    pub verbose: bool,
}

const GATEWAY_EXAMPLES: &str = "\
Examples:
  drivebus --bus socketcand://127.0.0.1:29536/can0 gateway                (stdin/stdout; a shell on a terminal)
  drivebus --bus socketcand://127.0.0.1:29536/can0 gateway --listen 127.0.0.1:60000
  cocomm -t 127.0.0.1 -p 60000 \"1 read 0x1017 0 u16\"                      (CANopenLinux's client)

Lines (CiA 309-3): [seq] [[net] node] r[ead] INDEX SUB [TYPE] | w[rite] INDEX SUB TYPE VALUE
| start | stop | preop | reset node | reset comm | set node N | set sdo_timeout MS | set network N
| lss_* | info version | r[ead] p[do] N | w[rite] p[do] N ... | set rpdo/tpdo ... | help.
Answers: [seq] OK | [seq] VALUE | [seq] ERROR:CODE (100..600) | [seq] ERROR:0xABORTCODE.";

/// `drivebus gateway`.
#[derive(Args, Debug)]
pub struct GatewayArgs {
    /// Serve on TCP instead of stdin/stdout (cocomm's -t/-p), e.g. 127.0.0.1:60000.
    #[arg(long, value_name = "HOST:PORT")]
    pub listen: Option<String>,
    /// No line editing/history even on a terminal (plain stdin lines).
    #[arg(long)]
    pub no_shell: bool,
}

const SLCAN_EXAMPLES: &str = "\
Examples:
  drivebus slcan-pty --drive akd:1
  drivebus slcan-pty --drive kc1:1 --drive dds6:2 --seconds 60

Prints `slcan-pty PATH`; open PATH with python-can: can.Bus(interface='slcan', channel=PATH).";

/// `drivebus slcan-pty`.
#[derive(Args, Debug)]
pub struct SlcanPtyArgs {
    /// A virtual drive: PROFILE (kc1, akd, ipos, ssd630, dds6, generic) and NODE (1..127).
    #[arg(long = "drive", value_name = "PROFILE:NODE")]
    pub drives: Vec<String>,
    /// A device from its EDS or DCF (repeatable): its objects, defaults and PDOs; a CiA 401 I/O
    /// module when its 1000h says so (inputs from --machine: docs/machine.md). A DCF may leave
    /// :NODE out: its [DeviceComissioning] NodeID.
    #[arg(long = "device", value_name = "FILE:NODE")]
    pub devices: Vec<String>,
    /// Stop after this many seconds (default: until SIGINT/SIGTERM).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Fault injection on the hosting bus (repeatable): `drop:IDS[,every=N][,skip=N][,times=N]`
    /// or `corrupt:IDS:MASK[,...]`; IDS is `0x585` or `0x180-0x1FF`, MASK is hex XORed onto the data.
    #[arg(long = "fault", value_name = "RULE")]
    pub faults: Vec<String>,
}
