//! `drivebus`: the command-line tool of the drivebus CANopen stack.
//!
//! Every command runs on one tokio runtime; errors are printed as
//! `error: ...` on stderr with their causes, and the exit status is 1
//! (2 for usage errors, from clap).

mod args;
mod demo;
mod dump;
mod eds_cmd;
mod fault;
mod link;
mod misc;
mod motion;
mod output;
mod sdo_cmd;
mod serve;
mod sim;
mod vdrive;

use clap::Parser;

use args::{Cli, Command};

fn main() {
    let cli = Cli::parse();
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn"));
    tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).init();
    let rt = match tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("error: cannot start the async runtime: {e}");
            std::process::exit(1);
        }
    };
    let result = rt.block_on(run(cli));
    // Hosted drives and transports are tasks: do not wait for them.
    rt.shutdown_background();
    match result {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::exit(1);
        }
    }
}

/// Runs one command; the exit status on success (some commands report
/// findings with 1).
async fn run(cli: Cli) -> anyhow::Result<i32> {
    let g = &cli.global;
    match &cli.cmd {
        Command::Serve(a) => serve::run(g, a).await.map(|()| 0),
        Command::Demo(a) => demo::run(g, a).await.map(|()| 0),
        Command::Scan(a) => misc::scan(g, a).await.map(|()| 0),
        Command::Sdo(c) => sdo_cmd::run(g, c).await.map(|()| 0),
        Command::Nmt(a) => misc::nmt(g, a).await.map(|()| 0),
        Command::Pdo(c) => misc::pdo(g, c).await.map(|()| 0),
        Command::Drive(c) => motion::run(g, c).await.map(|()| 0),
        Command::Dump(a) => dump::run(g, a).await.map(|()| 0),
        Command::Eds(c) => eds_cmd::run(g, c).await,
        Command::Lss(c) => misc::lss(g, c).await.map(|()| 0),
        Command::SlcanPty(a) => misc::slcan_pty(g, a).await.map(|()| 0),
    }
}
