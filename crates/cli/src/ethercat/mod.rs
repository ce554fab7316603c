//! `drivebus ethercat …`: the EtherCAT side of the tool. `serve` puts
//! CiA 402 drive twins on a network interface as software EtherCAT
//! slaves (`drivebus_ethercat::drive`).

mod serve;

use clap::{Args, Subcommand};
use std::path::PathBuf;

/// `drivebus ethercat` subcommands.
#[derive(Subcommand, Debug)]
pub enum EthercatCmd {
    /// Serve drives as EtherCAT slaves on a network interface (AF_PACKET; root or CAP_NET_RAW).
    #[command(after_help = SERVE_EXAMPLES)]
    Serve(EcatServeArgs),
}

const SERVE_EXAMPLES: &str = "\
Examples:
  drivebus ethercat serve --iface veth0 --drive ipos
  drivebus ethercat serve --iface eth1 --drive ipos --drive ipos --drive generic --state-dir ./ecat-state --pcap line.pcapng

The slaves sit on the line in the order given. Prints one line containing `ready on IFACE` once
the segment answers frames; stops on SIGINT/SIGTERM (exit 0). Any EtherCAT master on the wire
(ethercrab, SOEM/pysoem, TwinCAT) sees them; --pcap records every frame for Wireshark.";

/// `drivebus ethercat serve`.
#[derive(Args, Debug)]
pub struct EcatServeArgs {
    /// Network interface to serve on (a NIC, or one end of a veth pair).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// A drive on the line, in order: ipos or generic (repeatable).
    #[arg(long = "drive", value_name = "PROFILE", required = true)]
    pub drives: Vec<String>,
    /// Keep each drive's parameters (1010h stores) and FoE setup files under
    /// DIR/ecat-<position>-<profile>, so they survive a restart.
    #[arg(long, value_name = "DIR")]
    pub state_dir: Option<PathBuf>,
    /// Record every frame in and out as pcapng.
    #[arg(long, value_name = "FILE")]
    pub pcap: Option<PathBuf>,
}

/// Runs a `drivebus ethercat` command.
pub async fn run(cmd: &EthercatCmd) -> anyhow::Result<i32> {
    match cmd {
        EthercatCmd::Serve(a) => serve::run(a).await.map(|()| 0),
    }
}
