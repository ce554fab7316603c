//! `drivebus ethercat …`: the EtherCAT side of the tool. `serve` puts
//! CiA 402 drive twins and real devices (from their SII image or ESI
//! file) on a network interface as software EtherCAT
//! slaves (`drivebus_ethercat::drive`, `drivebus_ethercat::described`); `scan`, `sdo`, `state`, `pdo` and
//! `drive` are an EtherCAT master on an interface
//! (`drivebus_ethercat::master`, on ethercrab), and `demo.rs` is
//! `drivebus demo --ethercat`.

pub mod control;
pub mod demo;
mod drive;
mod http;
mod http_objects;
mod http_stream;
#[cfg(test)]
mod http_tests;
mod line;
mod read;
mod serve;

use clap::{Args, Subcommand};
use std::path::PathBuf;

use crate::args::Global;

/// `drivebus ethercat` subcommands.
#[derive(Subcommand, Debug)]
pub enum EthercatCmd {
    /// Serve drives and real devices (SII EEPROM image, ESI file) as EtherCAT slaves on a network interface (AF_PACKET; root or CAP_NET_RAW).
    #[command(after_help = SERVE_EXAMPLES)]
    Serve(EcatServeArgs),
    /// List the slaves on the line: position, addresses, identity (SII and 1018h), AL state, mailbox.
    #[command(after_help = SCAN_EXAMPLES)]
    Scan(EcatScanArgs),
    /// Read or write a slave's objects over CoE (SDO).
    #[command(subcommand, after_help = SDO_EXAMPLES)]
    Sdo(EcatSdoCmd),
    /// Show the AL state of the slaves, or request one (init, preop, safeop, op, boot).
    #[command(after_help = STATE_EXAMPLES)]
    State(EcatStateArgs),
    /// Show a slave's PDO assignment (1C12h/1C13h) and mapping (16xxh/1Axxh), read over CoE.
    #[command(subcommand, after_help = PDO_EXAMPLES)]
    Pdo(EcatPdoCmd),
    /// Control a CiA 402 drive over the process data in OP (DC SYNC0 where supported).
    #[command(after_help = DRIVE_EXAMPLES)]
    Drive(EcatDriveArgs),
}

const SERVE_EXAMPLES: &str = "\
Examples:
  drivebus ethercat serve --iface veth0 --drive ipos
  drivebus ethercat serve --iface eth1 --drive ipos --drive ipos --drive generic --state-dir ./ecat-state --pcap line.pcapng
  drivebus ethercat serve --iface veth0 --device ek1100.bin --device el2004.hex --device board.xml#1 --drive ipos
  drivebus ethercat serve --iface veth0 --drive ipos --drive ipos --control /tmp/ecat.sock

The slaves sit on the line in the order given (--drive and --device mixed). A --device is a real
device's SII EEPROM image (served byte for byte) or ESI file; its inputs loop its outputs back. Prints one line containing `ready on IFACE` once
the segment answers frames; stops on SIGINT/SIGTERM (exit 0). Any EtherCAT master on the wire
(ethercrab, SOEM/pysoem, TwinCAT) sees them; --pcap records every frame for Wireshark. With
--control ADDR, `drivebus control --connect ADDR ...` sets drive inputs and machine faults, breaks the
line, loses or corrupts frames and power-cycles a slave while it runs (docs/control.md).";

const SCAN_EXAMPLES: &str = "\
Examples:
  drivebus ethercat scan --iface ecat1
  drivebus ethercat scan --iface ecat1 --json

The state shown is the one each slave was in; the scan then initialises the line (ethercrab:
station addresses, SII, mailboxes) and leaves it in PRE-OP. Slaves are numbered by position from 1.
The master commands use ethercrab's raw socket: root or CAP_NET_RAW.";

const SDO_EXAMPLES: &str = "\
Examples:
  drivebus ethercat sdo read --iface ecat1 --slave 1 1018 1
  drivebus ethercat sdo read --iface ecat1 --slave 1 statusword --json
  drivebus ethercat sdo read --iface ecat1 --slave 2 1C13          (the whole array)
  drivebus ethercat sdo read --iface ecat1 --slave 2 1018 --json   (the whole record)
  drivebus ethercat sdo write --iface ecat1 --slave 1 6060 0 8
  drivebus ethercat sdo write --iface ecat1 --slave 1 0x6081 200000 --type u32

Indices and sub-indices are hex (6041, 0x6041, 6041h, 6041:00); CiA 301/402 objects go by name and
type. An array or record without SUB is read whole: names and types from the slave's SDO
Information, one complete-access upload where the slave offers it; without SDO Information from
the CiA 301/402 and ETG.1000.6 tables, else by size, with a note. An abort is reported with its code and meaning (exit 1). ethercrab 0.7.1 writes 1 to 4
bytes (expedited download); reads of any length work.";

const STATE_EXAMPLES: &str = "\
Examples:
  drivebus ethercat state --iface ecat1                 (every slave's AL state and status code)
  drivebus ethercat state --iface ecat1 op              (the line through PRE-OP and SAFE-OP to OP)
  drivebus ethercat state --iface ecat1 --slave 1 init
  drivebus ethercat state --iface ecat1 --slave 2 --direct boot

init and --direct write AL control (0120h) of the slave(s) and wait; preop, safeop and op bring
the whole line up as ethercrab does (mailboxes, process data, SM watchdog). A refused request is
reported with its AL status code and text (exit 1) and acknowledged. With no master cycling the
process data, a slave in OP returns to SAFE-OP when its process-data watchdog expires.";

const PDO_EXAMPLES: &str = "\
Examples:
  drivebus ethercat pdo show --iface ecat1 --slave 1
  drivebus ethercat pdo show --iface ecat1 --slave 2 --json";

const DRIVE_EXAMPLES: &str = "\
Examples:
  drivebus ethercat drive --iface ecat1 --slave 1 status
  drivebus ethercat drive --iface ecat1 --slave 1 enable
  drivebus ethercat drive --iface ecat1 --slave 1 home --method 35
  drivebus ethercat drive --iface ecat1 --slave 1 move 5000 --velocity 200000
  drivebus ethercat drive --iface ecat1 --slave 1 csp-sine --amplitude 1000 --seconds 2

Every command but status brings the line to OP (DC SYNC0 at --cycle-us when every slave supports
it and --free-run is not given, else free run) and drives through the process data (6040h, 607Ah, 6041h, 6064h, 60F4h where
mapped; the rest over CoE), then returns the line to SAFE-OP: the drive reacts to that as its
6007h says. A motion it started is halted, or quick-stopped, on timeout, error or Ctrl-C, and it
says so. status reads over CoE in PRE-OP.";

/// The line a master command works on.
#[derive(Args, Debug, Clone)]
pub struct EcatLine {
    /// Network interface with the EtherCAT line (raw socket: root or CAP_NET_RAW).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
}

/// A slave by its line position.
fn position(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n @ 1..=65535) => Ok(n),
        _ => Err(format!("`{s}` is not a slave position: 1 for the first slave on the line")),
    }
}

/// `drivebus ethercat scan`.
#[derive(Args, Debug)]
pub struct EcatScanArgs {
    #[command(flatten)]
    line: EcatLine,
}

/// `drivebus ethercat sdo`.
#[derive(Subcommand, Debug)]
pub enum EcatSdoCmd {
    /// Read an object (a whole record or array without SUB).
    Read(EcatSdoRead),
    /// Write an object (1 to 4 bytes).
    Write(EcatSdoWrite),
}

/// `drivebus ethercat sdo read`.
#[derive(Args, Debug)]
pub struct EcatSdoRead {
    #[command(flatten)]
    line: EcatLine,
    /// The slave (line position from 1).
    #[arg(long, value_parser = position)]
    slave: usize,
    /// Object: hex index (6041, 0x6041, 6041h, 6041:00) or a CiA 301/402 name.
    object: String,
    /// Sub-index in hex.
    sub: Option<String>,
    /// Data type (u8, u16, u32, i32, str, ... or a CiA name) when not a standard object.
    #[arg(long = "type", value_name = "T")]
    ty: Option<String>,
}

/// `drivebus ethercat sdo write`.
#[derive(Args, Debug)]
pub struct EcatSdoWrite {
    #[command(flatten)]
    line: EcatLine,
    /// The slave (line position from 1).
    #[arg(long, value_parser = position)]
    slave: usize,
    /// OBJECT [SUB] VALUE.
    #[arg(num_args = 2..=3, required = true, value_name = "OBJECT [SUB] VALUE", allow_negative_numbers = true)]
    args: Vec<String>,
    /// Data type (u8, u16, u32, i32, ... or a CiA name) when not a standard object.
    #[arg(long = "type", value_name = "T")]
    ty: Option<String>,
}

/// `drivebus ethercat state`.
#[derive(Args, Debug)]
pub struct EcatStateArgs {
    #[command(flatten)]
    line: EcatLine,
    /// Only this slave (line position from 1); default every slave.
    #[arg(long, value_parser = position)]
    slave: Option<usize>,
    /// Only write AL control (0120h) with the state and report what the slave does.
    #[arg(long, requires = "target")]
    direct: bool,
    /// The state to request: init, preop, safeop, op (boot with --direct); none: show.
    target: Option<String>,
}

/// `drivebus ethercat pdo`.
#[derive(Subcommand, Debug)]
pub enum EcatPdoCmd {
    /// Show the assignment and mapping.
    Show(EcatPdoShow),
}

/// `drivebus ethercat pdo show`.
#[derive(Args, Debug)]
pub struct EcatPdoShow {
    #[command(flatten)]
    line: EcatLine,
    /// The slave (line position from 1).
    #[arg(long, value_parser = position)]
    slave: usize,
}

/// `drivebus ethercat drive`.
#[derive(Args, Debug)]
pub struct EcatDriveArgs {
    /// Network interface with the EtherCAT line (required; before or after the action).
    #[arg(long, value_name = "IFACE", global = true)]
    iface: Option<String>,
    /// The drive (line position from 1; required).
    #[arg(long, value_parser = position, global = true)]
    slave: Option<usize>,
    /// Process-data cycle (and SYNC0 period) in µs.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(250..=100_000), global = true)]
    cycle_us: u64,
    /// Free run (SM-synchronous) even where the slaves support DC.
    #[arg(long, global = true)]
    free_run: bool,
    /// What to do.
    #[command(subcommand)]
    action: EcatDriveAction,
}

/// Drive actions.
#[derive(Subcommand, Debug)]
pub enum EcatDriveAction {
    /// Statusword, state, mode, position, error code (over CoE).
    Status,
    /// Operation enabled (a fault is reset first).
    Enable,
    /// Switch on disabled.
    Disable,
    /// Homing (mode 6) with a method (6098h).
    Home {
        /// Homing method (6098h), e.g. 35 = on the current position.
        #[arg(long, default_value_t = 35, allow_negative_numbers = true)]
        method: i8,
        /// Give up (and halt) after this many seconds.
        #[arg(long, default_value_t = 30.0)]
        wait: f64,
    },
    /// Profile-position move (mode 1) to TARGET.
    Move {
        /// Target position (607Ah) in the drive's position units.
        #[arg(allow_negative_numbers = true)]
        target: i32,
        /// Profile velocity (6081h) to set first.
        #[arg(long)]
        velocity: Option<u32>,
        /// TARGET is relative to the present position.
        #[arg(long)]
        relative: bool,
        /// Give up (and halt) after this many seconds.
        #[arg(long, default_value_t = 30.0)]
        wait: f64,
    },
    /// Cyclic synchronous position (mode 8): a sine around the present position, one target per cycle.
    CspSine {
        /// Amplitude in position units.
        #[arg(long, default_value_t = 1000)]
        amplitude: u32,
        /// Frequency in Hz.
        #[arg(long, default_value_t = 1.0)]
        frequency: f64,
        /// Duration in seconds.
        #[arg(long, default_value_t = 2.0)]
        seconds: f64,
    },
}

/// `drivebus ethercat serve`.
#[derive(Args, Debug)]
pub struct EcatServeArgs {
    /// Network interface to serve on (a NIC, or one end of a veth pair).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// The slaves, in line order (`--drive` and `--device`, repeatable).
    #[command(flatten)]
    pub line: LineArgs,
    /// Keep each drive's parameters (1010h stores) and FoE setup files under
    /// DIR/ecat-<position>-<profile>, so they survive a restart.
    #[arg(long, value_name = "DIR")]
    pub state_dir: Option<PathBuf>,
    /// Record every frame in and out as pcapng.
    #[arg(long, value_name = "FILE")]
    pub pcap: Option<PathBuf>,
    /// Accept control requests (drive inputs and machine faults, faults of the line, a slave's
    /// power) on this loopback address (127.0.0.1:PORT) or Unix socket path: `drivebus control`,
    /// docs/control.md. Off unless given.
    #[arg(long, value_name = "ADDR")]
    pub control: Option<String>,
    /// Serve the line's state over HTTP on this address (`GET /api/ethercat`,
    /// docs/http-api.md); port 0 picks a free one. Off unless given.
    #[arg(long, value_name = "HOST:PORT")]
    pub http: Option<String>,
}

/// One slave of `ethercat serve`'s line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LineSlave {
    /// `--drive PROFILE`.
    Drive(String),
    /// `--device FILE[#N|#PRODUCT]`.
    Device(String),
}

/// `--drive` and `--device` in the order given on the command line (clap
/// keeps one list per option; their indices give the order).
#[derive(Debug, Default, Clone)]
pub struct LineArgs {
    /// The slaves in line order.
    pub slaves: Vec<LineSlave>,
}

impl clap::FromArgMatches for LineArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut all: Vec<(usize, LineSlave)> = Vec::new();
        for (id, make) in
            [("drive", LineSlave::Drive as fn(String) -> LineSlave), ("device", LineSlave::Device)]
        {
            if let (Some(v), Some(i)) = (m.get_many::<String>(id), m.indices_of(id)) {
                all.extend(i.zip(v.map(|s| make(s.clone()))));
            }
        }
        all.sort_by_key(|(i, _)| *i);
        Ok(LineArgs { slaves: all.into_iter().map(|(_, s)| s).collect() })
    }
    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for LineArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        use clap::{Arg, ArgAction, ArgGroup};
        cmd.arg(
            Arg::new("drive")
                .long("drive")
                .value_name("PROFILE")
                .action(ArgAction::Append)
                .help("A drive twin on the line: ipos or generic (repeatable, in line order with --device)"),
        )
        .arg(
            Arg::new("device")
                .long("device")
                .value_name("FILE[#N]")
                .action(ArgAction::Append)
                .help(
                    "A device from its SII EEPROM image (binary or Intel hex) or ESI file; FILE#N or \
                     FILE#PRODUCT picks one of an ESI file's devices (repeatable, in line order with --drive)",
                ),
        )
        .group(ArgGroup::new("slaves").args(["drive", "device"]).multiple(true).required(true))
    }
    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

/// Runs a `drivebus ethercat` command.
pub async fn run(g: &Global, cmd: &EthercatCmd) -> anyhow::Result<i32> {
    match cmd {
        EthercatCmd::Serve(a) => serve::run(a).await.map(|()| 0),
        EthercatCmd::Scan(a) => line::scan(g, &a.line).await.map(|()| 0),
        EthercatCmd::Sdo(EcatSdoCmd::Read(a)) => read::sdo_read(g, a).await.map(|()| 0),
        EthercatCmd::Sdo(EcatSdoCmd::Write(a)) => line::sdo_write(g, a).await.map(|()| 0),
        EthercatCmd::State(a) => line::state(g, a).await.map(|()| 0),
        EthercatCmd::Pdo(EcatPdoCmd::Show(a)) => line::pdo_show(g, a).await.map(|()| 0),
        EthercatCmd::Drive(a) => drive::run(g, a).await.map(|()| 0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::FromArgMatches as _;

    fn line(args: &[&str]) -> Result<Vec<LineSlave>, clap::Error> {
        let m = LineArgs::augment_args(clap::Command::new("serve")).try_get_matches_from(args)?;
        Ok(LineArgs::from_arg_matches(&m)?.slaves)
    }

    #[test]
    fn drives_and_devices_keep_the_command_line_order() {
        let got = line(&[
            "serve",
            "--device",
            "ek1100.bin",
            "--drive",
            "ipos",
            "--device",
            "b.xml#2",
            "--drive=generic",
        ]);
        assert_eq!(
            got.unwrap(),
            [
                LineSlave::Device("ek1100.bin".into()),
                LineSlave::Drive("ipos".into()),
                LineSlave::Device("b.xml#2".into()),
                LineSlave::Drive("generic".into()),
            ]
        );
        assert_eq!(line(&["serve", "--device", "a.bin"]).unwrap(), [LineSlave::Device("a.bin".into())]);
        assert!(line(&["serve"]).is_err(), "a line needs a slave");
    }
}
