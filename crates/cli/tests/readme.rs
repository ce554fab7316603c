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

#[test]
fn the_workflow_section_runs_as_written() {
    let text = readme();
    let port = common::free_port();
    let sub = |s: &str| s.replace("29536", &port.to_string());
    let lines = block(&text, "## One set of virtual drives, many commands");
    let mut serve: Option<std::process::Child> = None;
    let mut bus = String::new();
    let mut last_out = String::new();
    let mut ran = 0;
    for line in lines {
        let line = sub(&line);
        if let Some(want) = line.strip_prefix("# prints: ") {
            assert!(last_out.contains(want), "README promises `{want}`, the command printed:\n{last_out}");
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
            .env("DRIVEBUS_BUS", &bus)
            .output()
            .unwrap();
        assert!(out.status.success(), "`{line}` failed: {}", String::from_utf8_lossy(&out.stderr));
        last_out = String::from_utf8_lossy(&out.stdout).into_owned();
        ran += 1;
    }
    assert!(ran >= 8, "the workflow ran {ran} commands");
    if let Some(mut c) = serve {
        let _ = c.kill();
    }
    std::thread::sleep(Duration::from_millis(10));
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
    ] {
        assert!(text.contains(&format!("`{cmd}")), "README table lists {cmd}");
        assert!(help.contains(&format!("  {cmd} ")), "`drivebus --help` lists {cmd}");
    }
    // The minimum Rust version the README names is the workspace's.
    let cargo = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../Cargo.toml")).unwrap();
    assert!(cargo.contains("rust-version = \"1.88\"") && text.contains("Rust 1.88"));
}
