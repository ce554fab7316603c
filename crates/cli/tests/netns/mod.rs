//! A network namespace with one end of a veth pair in it, for the EtherCAT
//! CLI tests: the other end stays in the root namespace (where `ethercat
//! serve` runs). Everything, the server included, is removed on drop.

#![allow(dead_code)] // each test binary uses a part

use std::process::{Child, Command, Stdio};

/// Runs `ip ARGS`; the error names the command and what `ip` said.
pub fn ip(args: &[&str]) -> Result<(), String> {
    match Command::new("ip").args(args).stdin(Stdio::null()).output() {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => Err(format!("`ip {}`: {}", args.join(" "), String::from_utf8_lossy(&o.stderr).trim())),
        Err(e) => Err(format!("cannot run `ip`: {e}")),
    }
}

/// The namespace `ns`, the veth pair (`outer` in the root namespace,
/// `inner` in `ns`, both up) and the server a test starts on `outer`.
pub struct VethPair {
    pub ns: String,
    pub outer: String,
    pub inner: String,
    pub serve: Option<Child>,
}

impl VethPair {
    /// Creates the namespace and the pair, named after `prefix` and the
    /// process ID; the error says why (no root, no `ip`).
    pub fn create(prefix: &str) -> Result<VethPair, String> {
        let id = std::process::id() % 100_000;
        let ns = format!("{prefix}{id}");
        ip(&["netns", "add", &ns]).map_err(|e| format!("cannot create a network namespace: {e}"))?;
        let p = VethPair { outer: format!("{ns}a"), inner: format!("{ns}b"), ns, serve: None };
        for step in [
            vec!["link", "add", p.outer.as_str(), "type", "veth", "peer", "name", p.inner.as_str()],
            vec!["link", "set", p.inner.as_str(), "netns", p.ns.as_str()],
            vec!["link", "set", p.outer.as_str(), "up"],
            vec!["netns", "exec", p.ns.as_str(), "ip", "link", "set", p.inner.as_str(), "up"],
        ] {
            ip(&step)?;
        }
        Ok(p)
    }
}

impl Drop for VethPair {
    fn drop(&mut self) {
        if let Some(mut c) = self.serve.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
        let _ = ip(&["link", "del", &self.outer]);
        let _ = ip(&["netns", "del", &self.ns]);
    }
}

/// A veth pair `{prefix}{pid}a`/`…b` in the root namespace, both up;
/// deleted on drop.
pub struct Veth {
    pub a: String,
    pub b: String,
    pub tag: u32,
}

impl Veth {
    /// Creates the pair; the error says why (no root, no `ip`).
    pub fn create(prefix: &str) -> Result<Veth, String> {
        let tag = std::process::id() % 100_000;
        let (a, b) = (format!("{prefix}{tag}a"), format!("{prefix}{tag}b"));
        ip(&["link", "add", &a, "type", "veth", "peer", "name", &b])?;
        let v = Veth { a, b, tag };
        ip(&["link", "set", &v.a, "up"])?;
        ip(&["link", "set", &v.b, "up"])?;
        Ok(v)
    }
}

impl Drop for Veth {
    fn drop(&mut self) {
        let _ = ip(&["link", "del", &self.a]);
    }
}

/// A BRD of register 0x0000 (2 bytes): every slave adds 1 to the WKC.
pub fn count_frame() -> Vec<u8> {
    let mut f = vec![0xFF; 6];
    f.extend_from_slice(&[0x10; 6]);
    f.extend_from_slice(&[0x88, 0xA4]);
    f.extend_from_slice(&(14u16 | 1 << 12).to_le_bytes());
    f.extend_from_slice(&[0x07, 0x42, 0, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0]);
    f
}
