//! `drivebus`: the command-line tool of the drivebus CANopen stack.
//!
//! Every command that talks to a bus is argument parsing and formatting
//! over one `drivebus_master::Master` (`conn.rs`); `demo` runs the same
//! master on the simulated bus. Errors are printed as `error: ...` on
//! stderr with their causes (under `--json`: one `{"error":{...}}` object
//! on stdout), and the exit status is 1 (2 for usage errors).

mod args;
mod args_bus;
mod args_node;
mod canfilter;
mod conn;
mod control;
mod control_cmd;
mod csv;
mod cyclic;
mod decode;
mod demo;
mod dict;
mod drive_cmd;
mod dump;
mod eds_cmd;
mod error;
mod ethercat;
mod fault;
mod gateway;
mod lss_cmd;
mod monitor;
mod nmt_cmd;
mod output;
mod pdo_cmd;
mod plot;
mod replay;
mod sdo_cmd;
mod serve;
mod slcan_pty;
mod stats_cmd;
mod vdevice;
mod vdrive;
mod web;

use clap::parser::ValueSource;
use clap::{CommandFactory, FromArgMatches};

use args::{Cli, Command};

/// The global options a command uses; the others are refused.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Opt {
    Bus,
    Node,
    Eds,
    Json,
    Timeout,
    Retries,
    Sim,
    Machine,
}

const ALL_OPTS: [(Opt, &str); 8] = [
    (Opt::Bus, "bus"),
    (Opt::Node, "node"),
    (Opt::Eds, "eds"),
    (Opt::Json, "json"),
    (Opt::Timeout, "timeout"),
    (Opt::Retries, "retries"),
    (Opt::Sim, "sim"),
    (Opt::Machine, "machine"),
];

/// The global options the command at `path` (`["drive", "move"]`) uses.
fn uses(path: &[&str]) -> &'static [Opt] {
    use Opt::*;
    const NODE_SDO: &[Opt] = &[Bus, Node, Eds, Json, Timeout, Retries, Sim, Machine];
    match path {
        ["serve", ..] => &[Bus, Machine],
        ["demo", ..] => &[Json, Machine],
        ["scan", ..] => &[Bus, Json, Timeout, Retries, Sim, Machine],
        ["sdo" | "pdo", ..] => NODE_SDO,
        ["nmt", ..] | ["drive", ..] => &[Bus, Node, Json, Timeout, Retries, Sim, Machine],
        ["dump", ..] | ["monitor", ..] => NODE_SDO,
        ["send" | "replay" | "produce" | "gen" | "stats", ..] => &[Bus, Json, Sim, Machine],
        ["gateway", ..] => &[Bus, Node, Timeout, Retries, Sim, Machine],
        ["ui", ..] => &[Bus, Eds, Timeout, Retries, Sim, Machine],
        ["eds", "check", ..] => &[Json],
        ["eds", "show", ..] => &[Eds, Json],
        ["eds", ..] => NODE_SDO,
        ["lss", "set-node-id", ..] => &[Bus, Node, Json, Timeout, Retries, Sim, Machine],
        ["lss", ..] => &[Bus, Json, Timeout, Sim, Machine],
        ["slcan-pty", ..] => &[Bus, Machine],
        // EtherCAT commands take their interface (--iface) after the subcommand;
        // the master commands print JSON and use --timeout for a frame's return.
        ["ethercat", "serve", ..] => &[],
        ["ethercat", ..] => &[Json, Timeout],
        _ => &[Bus, Node, Eds, Json, Timeout, Retries, Sim, Machine],
    }
}

/// What `--timeout` means for the command at `path`, with its default.
fn timeout_help(path: &[&str]) -> &'static str {
    match path {
        ["lss", "set-node-id", ..] => {
            "Wait for each LSS answer, and for SDO answers with --node, in ms [default: 100 for LSS, 1000 for SDO]"
        }
        ["lss", ..] => "Wait for each LSS answer in ms (a fastscan asks up to 133 questions) [default: 100]",
        ["ethercat", ..] => "Wait for a frame's return in ms [default: 1000]",
        _ => "SDO and response timeout in milliseconds [default: 1000]",
    }
}

/// The command line with each command's help listing only the global
/// options it uses: each subcommand gets its own copy of every global
/// option (clap then does not copy the top-level one), hidden where the
/// command refuses it, with `--timeout` worded for the command.
fn command() -> clap::Command {
    fn own(cmd: clap::Command, globals: &[clap::Arg], path: &mut Vec<String>) -> clap::Command {
        let names: Vec<String> = cmd.get_subcommands().map(|c| c.get_name().to_owned()).collect();
        let mut cmd = cmd;
        if !path.is_empty() {
            let p: Vec<&str> = path.iter().map(String::as_str).collect();
            let used = uses(&p);
            for (opt, id) in ALL_OPTS {
                let Some(arg) = globals.iter().find(|a| a.get_id() == id) else { continue };
                let mut arg = arg.clone().hide(!used.contains(&opt));
                if opt == Opt::Timeout {
                    arg = arg.help(timeout_help(&p));
                }
                cmd = cmd.arg(arg);
            }
        }
        for n in names {
            path.push(n.clone());
            cmd = cmd.mut_subcommand(&n, |c| own(c, globals, path));
            path.pop();
        }
        cmd
    }
    let cmd = Cli::command();
    let globals: Vec<clap::Arg> = cmd.get_arguments().filter(|a| a.is_global_set()).cloned().collect();
    own(cmd, &globals, &mut Vec::new())
}

/// The subcommand path as typed (`drive move`).
fn path(m: &clap::ArgMatches) -> (Vec<String>, &clap::ArgMatches) {
    let mut names = Vec::new();
    let mut leaf = m;
    while let Some((name, sub)) = leaf.subcommand() {
        names.push(name.to_owned());
        leaf = sub;
    }
    (names, leaf)
}

/// Refuses global options given on the command line that `cmd` ignores.
fn check_options(m: &clap::ArgMatches) -> Result<(), String> {
    let (names, leaf) = path(m);
    let p: Vec<&str> = names.iter().map(String::as_str).collect();
    let used = uses(&p);
    for (opt, id) in ALL_OPTS {
        let given = [m, leaf].iter().any(|mm| mm.value_source(id) == Some(ValueSource::CommandLine));
        if given && !used.contains(&opt) {
            let why = match opt {
                Opt::Sim if names[0] == "serve" => " (serve hosts the drives itself: use --drive)",
                Opt::Bus | Opt::Sim if names[0] == "demo" => " (the demo runs on its own simulated bus)",
                _ => "",
            };
            return Err(format!("--{id} does not apply to `drivebus {}`{why}", names.join(" ")));
        }
    }
    Ok(())
}

fn main() {
    let argv: Vec<String> = std::env::args().collect();
    let json = argv.iter().any(|a| a == "--json");
    let matches = match command().try_get_matches_from(&argv) {
        Ok(m) => m,
        Err(e) if json && e.use_stderr() => {
            let msg = e.to_string();
            let first = msg.lines().next().unwrap_or("").trim_start_matches("error: ").to_owned();
            output::json_error("usage", &first, serde_json::json!({}));
            std::process::exit(2);
        }
        Err(e) => e.exit(),
    };
    let mut cli = match Cli::from_arg_matches(&matches) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    // DRIVEBUS_BUS names the bus clients talk to (often the one `serve`
    // provides): `serve` puts its drives elsewhere only when told so.
    if matches!(cli.cmd, Command::Serve(_)) && matches.value_source("bus") != Some(ValueSource::CommandLine) {
        cli.global.bus = "virtual".to_owned();
    }
    if let Err(msg) = check_options(&matches) {
        if cli.global.json {
            output::json_error("usage", &msg, serde_json::json!({}));
        } else {
            eprintln!("error: {msg}");
        }
        std::process::exit(2);
    }
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        // Every write from the web page is logged (issue 19 §3).
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn,ethercrab=off,drivebus::web=info"));
    tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).init();
    let rt = match tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("error: cannot start the async runtime: {e}");
            std::process::exit(1);
        }
    };
    let json = cli.global.json;
    let result = rt.block_on(run(cli));
    // Hosted drives and transports are tasks: do not wait for them.
    rt.shutdown_background();
    match result {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            let (code, extra) = error::describe(&e);
            let mut msg = error::render(&e);
            if code.ends_with("timeout")
                && let Some(hint) = conn::empty_bus_hint()
            {
                msg.push_str(hint);
            }
            if json {
                output::json_error(code, &msg, extra);
            } else {
                eprintln!("error: {msg}");
            }
            // 130: killed by SIGINT, as shells report Ctrl-C.
            std::process::exit(match code {
                "usage" => 2,
                "interrupted" => 130,
                _ => 1,
            });
        }
    }
}

/// Runs one command; the exit status on success (some commands report
/// findings with 1).
async fn run(cli: Cli) -> anyhow::Result<i32> {
    let g = &cli.global;
    match &cli.cmd {
        Command::Serve(a) => serve::run(g, a).await.map(|()| 0),
        Command::Control(a) => control_cmd::run(g, a).await.map(|()| 0),
        Command::Demo(a) => demo::run(g, a).await.map(|()| 0),
        Command::Scan(a) => nmt_cmd::scan(g, a).await.map(|()| 0),
        Command::Sdo(c) => sdo_cmd::run(g, c).await.map(|()| 0),
        Command::Nmt(a) => nmt_cmd::nmt(g, a).await.map(|()| 0),
        Command::Pdo(c) => pdo_cmd::run(g, c).await.map(|()| 0),
        Command::Drive(c) => drive_cmd::run(g, c).await.map(|()| 0),
        Command::Dump(a) => dump::run(g, a).await.map(|()| 0),
        Command::Monitor(a) => monitor::run(g, a).await.map(|()| 0),
        Command::Send(a) => replay::send(g, a).await.map(|()| 0),
        Command::Replay(a) => replay::run(g, a).await.map(|()| 0),
        Command::Produce(a) => cyclic::produce(g, a).await.map(|()| 0),
        Command::Gen(a) => cyclic::gen_frames(g, a).await.map(|()| 0),
        Command::Stats(a) => stats_cmd::run(g, a).await.map(|()| 0),
        Command::Gateway(a) => gateway::run(g, a).await.map(|()| 0),
        Command::Ui(a) => web::run_ui(g, a).await.map(|()| 0),
        Command::Eds(c) => eds_cmd::run(g, c).await,
        Command::Lss(c) => lss_cmd::run(g, c).await.map(|()| 0),
        Command::SlcanPty(a) => slcan_pty::run(g, a).await.map(|()| 0),
        Command::Ethercat(c) => ethercat::run(g, c).await,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(args: &[&str]) -> Result<(), String> {
        let m = command().try_get_matches_from(args).unwrap();
        check_options(&m)
    }

    /// The help text of the command at `args` (`["drive", "move"]`).
    fn help(args: &[&str]) -> String {
        let mut cmd = command();
        let mut c = &mut cmd;
        for a in args {
            c = c.find_subcommand_mut(a).unwrap();
        }
        c.render_long_help().to_string()
    }

    /// Splits an example line as a shell would (quotes, a `>` redirection
    /// and the comment after two spaces dropped).
    fn words(line: &str) -> Vec<String> {
        let cmd = line.trim_start();
        let cmd = cmd.split("  ").next().unwrap_or(cmd);
        let cmd = cmd.split(" > ").next().unwrap_or(cmd);
        let (mut out, mut cur, mut quote) = (Vec::new(), String::new(), None);
        for c in cmd.chars() {
            match (quote, c) {
                (None, '\'' | '"') => quote = Some(c),
                (Some(q), c) if c == q => quote = None,
                (None, ' ') => {
                    if !cur.is_empty() {
                        out.push(std::mem::take(&mut cur));
                    }
                }
                (_, c) => cur.push(c),
            }
        }
        if !cur.is_empty() {
            out.push(cur);
        }
        out
    }

    /// Every example line of every command's help.
    fn examples(c: &clap::Command, into: &mut Vec<String>) {
        for text in [c.get_after_help(), c.get_after_long_help()].into_iter().flatten() {
            for line in text.to_string().lines() {
                if line.trim_start().starts_with("drivebus ") {
                    into.push(line.to_owned());
                }
            }
        }
        for sc in c.get_subcommands() {
            examples(sc, into);
        }
    }

    /// Issue 15: the examples of `--help` run as written: each parses,
    /// takes only options its command uses, and names objects that resolve.
    #[test]
    fn every_help_example_parses_as_written() {
        let mut all = Vec::new();
        examples(&command(), &mut all);
        assert!(all.len() > 60, "{} examples", all.len());
        for line in all {
            let w = words(&line);
            let m = command().try_get_matches_from(&w).unwrap_or_else(|e| panic!("`{line}`: {e}"));
            check_options(&m).unwrap_or_else(|e| panic!("`{line}`: {e}"));
            let cli = Cli::from_arg_matches(&m).unwrap_or_else(|e| panic!("`{line}`: {e}"));
            if let Command::Sdo(args::SdoCmd::Read(a)) = &cli.cmd {
                dict::Dict::default()
                    .resolve(&a.object, a.sub.as_deref())
                    .unwrap_or_else(|e| panic!("`{line}`: {e}"));
            }
        }
        // The top-level help names an object the same way.
        assert!(dict::Dict::default().resolve("identity/vendor-id", None).is_ok());
    }

    #[test]
    fn each_command_lists_only_its_own_options() {
        let eds = help(&["eds", "check"]);
        assert!(eds.contains("--json") && !eds.contains("--bus") && !eds.contains("--sim"), "{eds}");
        let ecat = help(&["ethercat", "scan"]);
        for o in ["--bus", "--node", "--sim", "--eds", "--retries"] {
            assert!(!ecat.contains(o), "{o} in {ecat}");
        }
        assert!(ecat.contains("--iface") && ecat.contains("--timeout"), "{ecat}");
        let mv = help(&["drive", "move"]);
        assert!(mv.contains("--bus") && mv.contains("--node") && !mv.contains("--eds "), "{mv}");
        assert!(help(&["lss", "scan"]).contains("Wait for each LSS answer in ms"));
        assert!(!help(&["serve"]).contains("--timeout"));
    }

    #[test]
    fn options_that_do_not_apply_are_refused() {
        assert!(check(&["drivebus", "--node", "1", "sdo", "read", "1000"]).is_ok());
        assert!(check(&["drivebus", "sdo", "read", "1000", "--node", "1"]).is_ok());
        let e = check(&["drivebus", "--node", "3", "serve", "--drive", "akd:1"]).unwrap_err();
        assert_eq!(e, "--node does not apply to `drivebus serve`");
        assert!(check(&["drivebus", "serve", "--drive", "akd:1", "--bus", "virtual"]).is_ok());
        let e = check(&["drivebus", "serve", "--drive", "akd:1", "--sim", "akd:1"]).unwrap_err();
        assert!(e.contains("serve hosts the drives itself"), "{e}");
        let e = check(&["drivebus", "--eds", "x.eds", "nmt", "start", "--all"]).unwrap_err();
        assert_eq!(e, "--eds does not apply to `drivebus nmt`");
        let e = check(&["drivebus", "demo", "--timeout", "5"]).unwrap_err();
        assert!(e.contains("--timeout does not apply to `drivebus demo`"), "{e}");
        let e = check(&["drivebus", "eds", "check", "x.eds", "--node", "1"]).unwrap_err();
        assert!(e.contains("`drivebus eds check`"), "{e}");
        assert!(check(&["drivebus", "--json", "demo"]).is_ok());
        let e = check(&["drivebus", "--json", "gateway"]).unwrap_err();
        assert!(e.contains("--json does not apply"), "{e}");
    }
}
