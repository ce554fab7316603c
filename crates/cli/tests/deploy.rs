//! The container files of docs/scale.md (deploy/): every drivebus command
//! the compose file and the Kubernetes manifest run parses with the tool's
//! own command line (`drivebus ARGS --help` fails on an unknown command,
//! option or bad value before it prints the help), and what the
//! Dockerfile copies exists. Docker itself does not run here.

use std::path::{Path, PathBuf};
use std::process::Command;

use yaml_rust2::{Yaml, YamlLoader};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn load(file: &str) -> Vec<Yaml> {
    let text = std::fs::read_to_string(root().join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
    YamlLoader::load_from_str(&text).unwrap_or_else(|e| panic!("{file}: not YAML: {e}"))
}

fn strings(y: &Yaml, what: &str) -> Vec<String> {
    match y {
        Yaml::BadValue => Vec::new(),
        Yaml::Array(a) => a
            .iter()
            .map(|v| match v {
                Yaml::String(s) => s.clone(),
                Yaml::Integer(i) => i.to_string(),
                v => panic!("{what}: not a string: {v:?}"),
            })
            .collect(),
        v => panic!("{what}: expected a list of strings (exec form), got {v:?}"),
    }
}

/// The arguments after `drivebus` in `argv`, `None` when it does not run
/// drivebus (the image's entrypoint is drivebus: `implicit`).
fn drivebus_args(argv: &[String], implicit: bool) -> Option<Vec<String>> {
    match argv.iter().position(|a| a == "drivebus") {
        Some(i) => Some(argv[i + 1..].to_vec()),
        None if implicit => Some(argv.to_vec()),
        None => None,
    }
}

/// `drivebus ARGS --help` succeeds: clap accepted every argument before it.
fn parses(what: &str, args: &[String]) {
    assert!(!args.is_empty(), "{what}: runs drivebus without a command");
    let out = Command::new(env!("CARGO_BIN_EXE_drivebus")).args(args).arg("--help").output().unwrap();
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).contains("Usage: drivebus"),
        "{what}: `drivebus {}` is refused: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_compose_file_runs_commands_drivebus_accepts() {
    let docs = load("deploy/docker-compose.yml");
    let services = docs[0]["services"].as_hash().expect("services");
    let mut checked = 0;
    for (name, s) in services {
        let name = name.as_str().unwrap();
        let entry = strings(&s["entrypoint"], name);
        let argv: Vec<String> = entry.iter().cloned().chain(strings(&s["command"], name)).collect();
        let args = drivebus_args(&argv, entry.is_empty()).unwrap_or_else(|| panic!("{name}: {argv:?}"));
        parses(name, &args);
        if entry.first().is_some_and(|e| e == "with-veth") {
            assert!(s["cap_add"].as_vec().unwrap().contains(&Yaml::from_str("NET_ADMIN")), "{name}");
        }
        if args.iter().any(|a| a == "ethercat") {
            assert!(
                s["cap_add"].as_vec().unwrap().contains(&Yaml::from_str("NET_RAW")),
                "{name}: raw socket"
            );
        }
        assert_eq!(s["cpus"].as_f64(), Some(1.0), "{name}: one CPU per bus or line");
        checked += 1;
    }
    assert_eq!(checked, 3);
}

#[test]
fn the_kubernetes_manifest_runs_commands_drivebus_accepts() {
    let docs = load("deploy/kubernetes.yml");
    let mut checked = 0;
    for doc in &docs {
        let spec = match doc["kind"].as_str() {
            Some("Pod") => &doc["spec"],
            Some("Deployment") => &doc["spec"]["template"]["spec"],
            _ => continue,
        };
        for list in ["initContainers", "containers"] {
            for c in spec[list].as_vec().into_iter().flatten() {
                let name = c["name"].as_str().unwrap();
                let command = strings(&c["command"], name);
                let argv: Vec<String> = command.iter().cloned().chain(strings(&c["args"], name)).collect();
                match drivebus_args(&argv, command.is_empty()) {
                    Some(args) => parses(name, &args),
                    None => assert_eq!(argv, ["with-veth", "ecat0", "ecat1", "true"], "{name}"),
                }
                if list == "containers" {
                    assert_eq!(c["resources"]["limits"]["cpu"].as_str(), Some("1"), "{name}: one CPU each");
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 4);
}

#[test]
fn the_dockerfile_copies_what_the_repository_has() {
    let text = std::fs::read_to_string(root().join("deploy/Dockerfile")).unwrap();
    assert!(text.contains("cargo build --release --locked -p drivebus"), "builds the tool");
    for line in text.lines().filter(|l| l.starts_with("COPY ") && !l.contains("--from=")) {
        let src = line.split_whitespace().nth(1).unwrap();
        assert!(root().join(src).exists(), "{line}: no {src} in the repository");
    }
    let sh = Command::new("sh").arg("-n").arg(root().join("deploy/with-veth.sh")).output().unwrap();
    assert!(sh.status.success(), "with-veth.sh: {}", String::from_utf8_lossy(&sh.stderr));
}
