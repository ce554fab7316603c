//! The interactive gateway shell in a pseudo-terminal (issue 15 §1): it
//! panicked on every terminal (`thread 'gateway-shell' panicked ...
//! not implemented`: rustyline's history without its file feature).
#![cfg(unix)]

mod common;

use std::io::{Read, Write};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Reads the terminal until `want` appears (or 20 s pass); everything read.
fn read_until(rx: &mpsc::Receiver<Vec<u8>>, seen: &mut String, want: &str) -> bool {
    let end = Instant::now() + Duration::from_secs(20);
    while !seen.contains(want) {
        let Some(left) = end.checked_duration_since(Instant::now()) else { return false };
        match rx.recv_timeout(left) {
            Ok(b) => seen.push_str(&String::from_utf8_lossy(&b)),
            Err(_) => return false,
        }
    }
    true
}

/// The shell's process, killed when the test ends.
struct Shell(Option<std::process::Child>);

impl Drop for Shell {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

#[test]
fn the_shell_answers_on_a_terminal_and_keeps_its_history() {
    let home = tempfile::tempdir().unwrap();
    let pty = nix::pty::openpty(None, None).expect("openpty");
    let slave = std::fs::File::from(pty.slave);
    let child = Command::new(common::bin())
        .args(["--bus", "virtual", "--sim", "generic:5", "--node", "5", "gateway"])
        .env_remove("DRIVEBUS_BUS")
        .env("HOME", home.path())
        .stdin(Stdio::from(slave.try_clone().unwrap()))
        .stdout(Stdio::from(slave.try_clone().unwrap()))
        .stderr(Stdio::from(slave))
        .spawn()
        .expect("spawn drivebus gateway");
    // Killed if the test fails while it runs.
    let mut guard = Shell(Some(child));
    let child = guard.0.as_mut().expect("running");
    let mut term = std::fs::File::from(pty.master);
    let mut reader = term.try_clone().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = [0u8; 1024];
        // EIO once the child closed the terminal.
        while let Ok(n) = reader.read(&mut buf) {
            if n == 0 || tx.send(buf[..n].to_vec()).is_err() {
                break;
            }
        }
    });
    let mut seen = String::new();
    assert!(read_until(&rx, &mut seen, "gateway> "), "no prompt: {seen}");
    term.write_all(b"r 0x1000 0 u32\r").unwrap();
    assert!(read_until(&rx, &mut seen, "[1] 131474"), "no answer: {seen}");
    // Ctrl-D at the next prompt ends the shell (sent earlier, a loaded
    // machine may deliver it while the line editor is not reading).
    let answered = seen.find("[1] 131474").unwrap_or(0);
    let mut rest = seen.split_off(answered);
    assert!(read_until(&rx, &mut rest, "gateway> "), "no second prompt: {seen}{rest}");
    seen.push_str(&rest);
    term.write_all(b"\x04").unwrap();
    let end = Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        assert!(Instant::now() <= end, "the shell did not end on Ctrl-D: {seen}");
        std::thread::sleep(Duration::from_millis(20));
    };
    // What the terminal showed after the answer (a panic would be there).
    while let Ok(b) = rx.recv_timeout(Duration::from_millis(200)) {
        seen.push_str(&String::from_utf8_lossy(&b));
    }
    assert!(!seen.contains("panicked"), "{seen}");
    assert!(status.success(), "{status}: {seen}");
    let history = std::fs::read_to_string(home.path().join(".drivebus_gateway_history")).unwrap();
    assert!(history.contains("r 0x1000 0 u32"), "{history}");
}
