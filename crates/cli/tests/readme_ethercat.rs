//! The README's EtherCAT blocks, run as written: every `# prints:` line
//! must be in the output of the command above it. The demo block runs
//! anywhere; the master block runs against `drivebus ethercat serve` on
//! a veth pair whose `ecat1` end is in a network namespace the test
//! creates (root needed; the test prints why when it cannot and stops).
//! A command may fail only where the README shows its `error:` line.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_drivebus")
}

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

/// Checks `# prints:` lines against the outputs of the commands before
/// them; `run` runs one command line and gives (success, stdout + stderr).
fn check(lines: &[String], mut run: impl FnMut(&str) -> Option<(bool, String)>) -> usize {
    let mut last: Option<(String, bool, String, bool)> = None;
    let mut ran = 0;
    let settle = |l: &Option<(String, bool, String, bool)>| {
        if let Some((cmd, ok, out, error_shown)) = l {
            assert!(*ok || *error_shown, "`{cmd}` failed and the README does not show it:\n{out}");
        }
    };
    for line in lines {
        if let Some(want) = line.strip_prefix("# prints: ") {
            let (cmd, _, out, shown) = last.as_mut().expect("a command before `# prints:`");
            assert!(out.contains(want), "README promises `{want}` from `{cmd}`; it printed:\n{out}");
            *shown |= want.starts_with("error:");
            continue;
        }
        settle(&last);
        last = run(line).map(|(ok, out)| {
            ran += 1;
            (line.clone(), ok, out, false)
        });
    }
    settle(&last);
    ran
}

#[test]
fn the_ethercat_demo_block_runs_as_written() {
    let lines = block(&readme(), "### The EtherCAT demo");
    let dir = tempfile::tempdir().unwrap();
    let ran = check(&lines, |line| {
        let args = line.strip_prefix("cargo run --release -- ").expect("a cargo run line");
        let out = Command::new(bin()).args(args.split_whitespace()).current_dir(dir.path()).output().unwrap();
        let text =
            format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        Some((out.status.success(), text))
    });
    assert_eq!(ran, 1);
    assert!(dir.path().join("drivebus-demo-ethercat.svg").is_file());
}

mod netns;

fn pair() -> Result<netns::VethPair, String> {
    netns::VethPair::create("dbrm")
}

#[test]
fn the_ethercat_master_block_runs_as_written() {
    let lines = block(&readme(), "### The master side");
    let mut p = match pair() {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED the_ethercat_master_block_runs_as_written: {why}");
            return;
        }
    };
    let (outer, inner, ns) = (p.outer.clone(), p.inner.clone(), p.ns.clone());
    let mut serve = None;
    let ran = check(&lines, |line| {
        let line = line.replace("ecat0", &outer).replace("ecat1", &inner);
        if line == "kill %1" {
            let c: &mut Child = serve.as_mut().expect("serve started");
            let _ = Command::new("kill").args(["-TERM", &c.id().to_string()]).status();
            let st = c.wait().unwrap();
            return Some((st.success(), String::new()));
        }
        let line = line.strip_prefix("sudo ").unwrap_or(&line);
        let args: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(args.first(), Some(&"drivebus"), "unexpected README line `{line}`");
        if args.last() == Some(&"&") {
            let mut c = Command::new(bin())
                .args(&args[1..args.len() - 1])
                .stdout(Stdio::piped())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            let mut first = String::new();
            BufReader::new(c.stdout.take().unwrap()).read_line(&mut first).unwrap();
            assert!(first.contains(&format!("ready on {outer}")), "{first}");
            serve = Some(c);
            return None;
        }
        let out = Command::new("ip").args(["netns", "exec", &ns, bin()]).args(&args[1..]).output().unwrap();
        let text =
            format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        println!("$ {line}\n{text}");
        Some((out.status.success(), text))
    });
    p.serve = serve;
    assert!(ran >= 10, "the block ran {ran} commands");
}
