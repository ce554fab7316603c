//! The README's commands, run as written (on a free port instead of the
//! default 29536): every `# prints:` line must be in the output of the
//! command above it, the banner of `serve` included.

mod common;

use std::process::Stdio;
use std::time::Duration;

fn readme() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).expect("README.md")
}

/// The ```sh block under `heading`.
fn block(text: &str, heading: &str) -> Vec<String> {
    let from = text.find(heading).unwrap_or_else(|| panic!("README has no `{heading}`"));
    let rest = &text[from..];
    let start = rest.find("```sh\n").expect("a sh block") + 6;
    let end = rest[start..].find("```").expect("block end") + start;
    rest[start..end].lines().map(str::to_owned).collect()
}

/// The ```toml block under `heading`.
fn toml_block(text: &str, heading: &str) -> String {
    let from = text.find(heading).unwrap_or_else(|| panic!("README has no `{heading}`"));
    let rest = &text[from..];
    let start = rest.find("```toml\n").expect("a toml block") + 8;
    let end = rest[start..].find("```").expect("block end") + start;
    rest[start..end].to_owned()
}

/// `position N` with the number masked (where the README says it varies).
fn mask_position(s: &str) -> String {
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find("position ") {
        out.push_str(&rest[..i + 9]);
        rest = &rest[i + 9..];
        let digits = rest.find(|c: char| !(c.is_ascii_digit() || c == '-')).unwrap_or(rest.len());
        if digits > 0 {
            out.push('N');
        }
        rest = &rest[digits..];
    }
    out.push_str(rest);
    out
}

/// Runs a README ```sh block as written (serve on `port`, commands in
/// `dir`); `fuzzy` masks the `position` numbers the README says vary.
/// Returns how many commands ran.
fn run_block(lines: Vec<String>, port: u16, dir: &std::path::Path, fuzzy: bool) -> usize {
    let sub = |s: &str| s.replace("29536", &port.to_string());
    let norm = |s: &str| if fuzzy { mask_position(s) } else { s.to_owned() };
    let mut serve: Option<std::process::Child> = None;
    let mut bus = String::new();
    let mut last_out = String::new();
    let mut ran = 0;
    for line in lines {
        let line = sub(&line);
        if let Some(want) = line.strip_prefix("# prints: ") {
            assert!(
                norm(&last_out).contains(&norm(want)),
                "README promises `{want}`, the command printed:\n{last_out}"
            );
            continue;
        }
        if let Some(url) = line.strip_prefix("export DRIVEBUS_BUS=") {
            bus = url.to_owned();
            continue;
        }
        if line == "kill %1" {
            let mut child = serve.take().expect("serve started");
            let _ = std::process::Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
            assert!(child.wait().unwrap().success(), "serve exits 0 on SIGTERM");
            continue;
        }
        let args: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(args.first(), Some(&"drivebus"), "unexpected README line `{line}`");
        if args.last() == Some(&"&") {
            let mut child = std::process::Command::new(common::bin())
                .args(&args[1..args.len() - 1])
                .args(["--listen", &format!("127.0.0.1:{port}")])
                .current_dir(dir)
                .env_remove("DRIVEBUS_BUS")
                .stdout(Stdio::piped())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            let mut first = String::new();
            std::io::BufRead::read_line(
                &mut std::io::BufReader::new(child.stdout.take().unwrap()),
                &mut first,
            )
            .unwrap();
            last_out = first;
            serve = Some(child);
            continue;
        }
        let out = std::process::Command::new(common::bin())
            .args(&args[1..])
            .current_dir(dir)
            .env("DRIVEBUS_BUS", &bus)
            .output()
            .unwrap();
        assert!(out.status.success(), "`{line}` failed: {}", String::from_utf8_lossy(&out.stderr));
        last_out = String::from_utf8_lossy(&out.stdout).into_owned();
        ran += 1;
    }
    if let Some(mut c) = serve {
        let _ = c.kill();
    }
    std::thread::sleep(Duration::from_millis(10));
    ran
}

#[test]
fn the_workflow_section_runs_as_written() {
    let lines = block(&readme(), "## One set of virtual drives, many commands");
    let ran = run_block(lines, common::free_port(), &std::env::temp_dir(), false);
    assert!(ran >= 8, "the workflow ran {ran} commands");
}

/// The machine file and the limit-switch homing of "The machine around a
/// drive", with the file written as printed.
#[test]
fn the_machine_section_runs_as_written() {
    let text = readme();
    let heading = "### The machine around a drive";
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("machine.toml"), toml_block(&text, heading)).unwrap();
    let lines = block(&text, heading);
    assert!(lines.iter().any(|l| l.contains("--machine machine.toml")), "{lines:?}");
    assert!(lines.iter().any(|l| l.contains("drive home --method 17")), "{lines:?}");
    let ran = run_block(lines, common::free_port(), dir.path(), true);
    assert_eq!(ran, 3);
    assert_eq!(mask_position("at position 232 (x), position -5"), "at position N (x), position N");
}

/// "A CiA 401 I/O module beside the drives": the module of
/// `crates/cia401/eds/io16.eds` next to a drive, its machine file as
/// printed, inputs, an output wired back and an analog input read as written.
#[test]
fn the_io_module_section_runs_as_written() {
    let text = readme();
    let heading = "### A CiA 401 I/O module beside the drives";
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("io.toml"), toml_block(&text, heading)).unwrap();
    let eds = concat!(env!("CARGO_MANIFEST_DIR"), "/../cia401/eds/io16.eds");
    std::fs::copy(eds, dir.path().join("io16.eds")).unwrap();
    let lines = block(&text, heading);
    assert!(lines.iter().any(|l| l.contains("--device io16.eds:3")), "{lines:?}");
    let ran = run_block(lines, common::free_port(), dir.path(), false);
    assert_eq!(ran, 5);
}

/// "Inputs and faults while it runs": `serve --control` on a Unix socket
/// and `drivebus control`, as written.
#[test]
fn the_control_section_runs_as_written() {
    let lines = block(&readme(), "### Inputs and faults while it runs");
    assert!(lines.iter().any(|l| l.contains("--control control.sock")), "{lines:?}");
    let dir = tempfile::tempdir().unwrap();
    let ran = run_block(lines, common::free_port(), dir.path(), false);
    assert_eq!(ran, 9);
}

#[test]
fn the_install_section_and_the_command_table_match_the_tool() {
    let text = readme();
    let lines = block(&text, "## Installing the `drivebus` tool");
    assert!(lines[0].starts_with("cargo install --path crates/cli"), "{lines:?}");
    let help = std::process::Command::new(common::bin()).arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    // Every command in the README's table exists.
    for cmd in [
        "scan",
        "sdo",
        "nmt",
        "pdo",
        "drive",
        "dump",
        "monitor",
        "send",
        "replay",
        "gateway",
        "lss",
        "eds",
        "demo",
        "serve",
        "slcan-pty",
        "produce",
        "gen",
        "stats",
        "control",
        "ui",
    ] {
        assert!(text.contains(&format!("`{cmd}")), "README table lists {cmd}");
        assert!(help.contains(&format!("  {cmd} ")), "`drivebus --help` lists {cmd}");
    }
    // The minimum Rust version the README names is the workspace's.
    let cargo = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../Cargo.toml")).unwrap();
    assert!(cargo.contains("rust-version = \"1.88\"") && text.contains("Rust 1.88"));
}

/// "Watching and loading a bus": filters, timestamps, capture, CSV,
/// cyclic send, producers, generator and statistics, as written; the
/// capture it writes is a pcapng of the SocketCAN link type.
#[test]
fn the_bus_traffic_section_runs_as_written() {
    let text = readme();
    let dir = tempfile::tempdir().unwrap();
    let lines = block(&text, "## Watching and loading a bus");
    for want in ["--filter", "-t delta", "--pcap", "--csv", "--period", "produce", "gen ", "stats"] {
        assert!(lines.iter().any(|l| l.contains(want)), "the block shows {want}");
    }
    let ran = run_block(lines, common::free_port(), dir.path(), false);
    assert_eq!(ran, 11);
    let pcap = std::fs::read(dir.path().join("bus.pcapng")).unwrap();
    // Section header block, then an interface description with link type 227.
    assert_eq!(&pcap[..4], &[0x0A, 0x0D, 0x0D, 0x0A]);
    let shb_len = u32::from_le_bytes([pcap[4], pcap[5], pcap[6], pcap[7]]) as usize;
    assert_eq!(&pcap[shb_len..shb_len + 4], &[1, 0, 0, 0], "interface description block");
    assert_eq!(u16::from_le_bytes([pcap[shb_len + 8], pcap[shb_len + 9]]), 227, "LINKTYPE_CAN_SOCKETCAN");
    assert!(pcap.len() > shb_len + 100, "frames captured");
}
