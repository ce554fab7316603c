//! A small async master over one [`CanBus`]: SDO transfers with the
//! sans-IO `drivebus_sdo::client`, NMT commands, frame waits. One command
//! runs one thing at a time, so the link owns the receiver; frames that
//! arrive while waiting for something else are dropped.

use std::time::Duration;

use anyhow::{Context, anyhow};
use drivebus_can::{Frame, Instant};
use drivebus_od::SdoAbort;
use drivebus_sdo::client::{ClientError, Completed, Protocol, SdoClient, SdoClientConfig};
use drivebus_transport::CanBus;
use indicatif::ProgressBar;
use tokio::task::JoinHandle;

use crate::args::Global;
use crate::vdrive::{DriveSpec, spawn_on_hub};

/// Why an SDO transfer failed, with everything needed to explain it.
#[derive(Debug)]
pub struct SdoFailure {
    /// Node-ID.
    pub node: u8,
    /// Object.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Read or write.
    pub write: bool,
    /// The client's error.
    pub error: ClientError,
    /// The timeout in force.
    pub timeout: Duration,
}

impl SdoFailure {
    /// The abort code, if the server sent one.
    pub fn abort(&self) -> Option<SdoAbort> {
        match self.error {
            ClientError::ServerAbort(a) => Some(a),
            _ => None,
        }
    }
}

impl std::fmt::Display for SdoFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let what = if self.write { "write" } else { "read" };
        write!(f, "node {}: SDO {what} {:04X}h:{:02X} ", self.node, self.index, self.sub)?;
        match self.error {
            ClientError::ServerAbort(a) => write!(
                f,
                "aborted by the device with code 0x{:08X}: {}",
                a.0,
                a.description().unwrap_or("unknown abort code")
            ),
            ClientError::Timeout => write!(
                f,
                "timed out: no response within {} ms (is node {} on the bus and in pre-operational or operational?)",
                self.timeout.as_millis(),
                self.node
            ),
            e => write!(f, "failed: {e}"),
        }
    }
}

impl std::error::Error for SdoFailure {}

/// An open bus plus the virtual drives this process hosts on it.
pub struct Link {
    bus: CanBus,
    start: tokio::time::Instant,
    /// SDO response timeout.
    pub timeout: Duration,
    /// The URL, for messages.
    pub url: String,
    _drives: Hosted,
}

/// Virtual drives hosted by this process for `--sim`; stopped on drop.
pub struct Hosted(Vec<JoinHandle<()>>);

impl Drop for Hosted {
    fn drop(&mut self) {
        for d in &self.0 {
            d.abort();
        }
    }
}

/// Opens `g.bus` (on a virtual bus, first starts the `--sim` drives); the
/// bus is ready for requests when this returns.
pub async fn open_bus(g: &Global) -> anyhow::Result<(CanBus, Hosted)> {
    let specs = DriveSpec::parse_all(&g.sim)?;
    // The transport's message already names the URL and the cause.
    let parsed = drivebus_transport::BusUrl::parse(&g.bus).map_err(|e| anyhow!("{e}"))?;
    let mut drives = Vec::new();
    if !specs.is_empty() {
        let drivebus_transport::BusUrl::Virtual { name } = &parsed else {
            anyhow::bail!("--sim hosts drives only on the `virtual` bus, not on `{}`", g.bus);
        };
        let hub = drivebus_transport::hub::virtual_hub(name);
        drives = spawn_on_hub(&specs, &hub, None, Default::default())?;
    }
    let hosted = Hosted(drives);
    let bus = tokio::time::timeout(Duration::from_secs(10), drivebus_transport::open_parsed(&g.bus, &parsed))
        .await
        .map_err(|_| anyhow!("cannot open `{}`: timed out after 10 s", g.bus))?
        .map_err(|e| anyhow!("{e}"))?;
    if !specs.is_empty() {
        // Let the hosted drives boot before the first request.
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    if matches!(parsed, drivebus_transport::BusUrl::Socketcand { .. }) {
        // A socketcand server starts relaying to a client only after a
        // grace time following `< ok >` for rawmode (20 ms on ours):
        // answers to requests sent earlier would be lost.
        tokio::time::sleep(Duration::from_millis(60)).await;
    }
    Ok((bus, hosted))
}

impl Link {
    /// Opens `g.bus`; on a virtual bus, first starts the `--sim` drives.
    pub async fn open(g: &Global) -> anyhow::Result<Link> {
        let (bus, hosted) = open_bus(g).await?;
        Ok(Link {
            bus,
            start: tokio::time::Instant::now(),
            timeout: Duration::from_millis(g.timeout.max(1)),
            url: g.bus.clone(),
            _drives: hosted,
        })
    }

    /// The sans-IO time axis of this link.
    pub fn now(&self) -> Instant {
        Instant::from_nanos(u64::try_from(self.start.elapsed().as_nanos()).unwrap_or(u64::MAX))
    }

    fn at(&self, t: Instant) -> tokio::time::Instant {
        self.start + Duration::from_nanos(t.as_nanos()).min(Duration::from_secs(86_400))
    }

    /// Sends one frame.
    pub async fn send(&self, f: Frame) -> anyhow::Result<()> {
        self.bus.send(f).await.with_context(|| format!("sending on `{}`", self.url))
    }

    /// The next frame, or `None` at `deadline`.
    pub async fn recv_until(&mut self, deadline: tokio::time::Instant) -> anyhow::Result<Option<Frame>> {
        tokio::select! {
            r = self.bus.recv() => {
                let f = r.with_context(|| format!("bus `{}` closed", self.url))?;
                Ok(Some(f))
            }
            () = tokio::time::sleep_until(deadline) => Ok(None),
        }
    }

    /// The next frame satisfying `pred` within `within`.
    pub async fn wait_for(
        &mut self,
        within: Duration,
        mut pred: impl FnMut(&Frame) -> bool,
    ) -> anyhow::Result<Option<Frame>> {
        let deadline = tokio::time::Instant::now() + within;
        while let Some(f) = self.recv_until(deadline).await? {
            if pred(&f) {
                return Ok(Some(f));
            }
        }
        Ok(None)
    }

    /// NMT command `cs` to `node` (0 = all).
    pub async fn nmt(&self, cs: u8, node: u8) -> anyhow::Result<()> {
        self.send(Frame::new(0x000, &[cs, node])).await
    }

    async fn transfer(
        &mut self,
        node: u8,
        index: u16,
        sub: u8,
        download: Option<Vec<u8>>,
        protocol: Protocol,
        progress: Option<&ProgressBar>,
    ) -> Result<Completed, anyhow::Error> {
        let mut cfg = SdoClientConfig::for_node(node);
        cfg.timeout =
            drivebus_can::Duration::from_nanos(u64::try_from(self.timeout.as_nanos()).unwrap_or(u64::MAX));
        cfg.retries = 0;
        let mut client = SdoClient::new(cfg);
        let mut out: Vec<Frame> = Vec::new();
        let write = download.is_some();
        let timeout = self.timeout;
        let fail = |error| SdoFailure { node, index, sub, write, error, timeout };
        let started = match download {
            Some(data) => client.start_download_owned(index, sub, data, protocol, self.now(), &mut out),
            None => client.start_upload(index, sub, protocol, self.now(), &mut out),
        };
        started.map_err(|e| anyhow::Error::new(fail(e)))?;
        loop {
            for f in out.drain(..) {
                self.send(f).await?;
            }
            if let Some(r) = client.take_result() {
                return r.map_err(|e| anyhow::Error::new(fail(e)));
            }
            if let (Some(pb), Some((done, total))) = (progress, client.progress()) {
                if let Some(t) = total {
                    pb.set_length(t as u64);
                }
                pb.set_position(done as u64);
            }
            let deadline = client.deadline().map_or_else(tokio::time::Instant::now, |d| self.at(d));
            match self.recv_until(deadline).await? {
                Some(f) => client.handle_frame(&f, self.now(), &mut out),
                None => {
                    client.poll(self.now(), &mut out);
                }
            }
        }
    }

    /// Reads an object.
    pub async fn upload(&mut self, node: u8, index: u16, sub: u8) -> anyhow::Result<Vec<u8>> {
        Ok(self.transfer(node, index, sub, None, Protocol::Auto, None).await?.into_data())
    }

    /// Reads an object with a protocol and a progress bar.
    pub async fn upload_with(
        &mut self,
        node: u8,
        index: u16,
        sub: u8,
        protocol: Protocol,
        pb: Option<&ProgressBar>,
    ) -> anyhow::Result<Vec<u8>> {
        Ok(self.transfer(node, index, sub, None, protocol, pb).await?.into_data())
    }

    /// Writes an object.
    pub async fn download(&mut self, node: u8, index: u16, sub: u8, data: &[u8]) -> anyhow::Result<()> {
        self.transfer(node, index, sub, Some(data.to_vec()), Protocol::Auto, None).await.map(|_| ())
    }

    /// Writes an object with a protocol and a progress bar.
    pub async fn download_with(
        &mut self,
        node: u8,
        index: u16,
        sub: u8,
        data: Vec<u8>,
        protocol: Protocol,
        pb: Option<&ProgressBar>,
    ) -> anyhow::Result<()> {
        self.transfer(node, index, sub, Some(data), protocol, pb).await.map(|_| ())
    }

    /// Reads an unsigned integer of up to 8 bytes.
    pub async fn read_u64(&mut self, node: u8, index: u16, sub: u8) -> anyhow::Result<u64> {
        let d = self.upload(node, index, sub).await?;
        let mut b = [0u8; 8];
        let n = d.len().min(8);
        b[..n].copy_from_slice(&d[..n]);
        Ok(u64::from_le_bytes(b))
    }
}

/// Parses an index or number: `0x6041`, `6041h`, or decimal.
pub fn parse_num(s: &str) -> anyhow::Result<u32> {
    let t = s.trim();
    let r = if let Some(h) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        u32::from_str_radix(h, 16)
    } else if let Some(h) = t.strip_suffix('h').or_else(|| t.strip_suffix('H')) {
        u32::from_str_radix(h, 16)
    } else {
        t.parse::<u32>()
    };
    r.map_err(|_| anyhow!("`{s}` is not a number (write 0x6041, 6041h or decimal)"))
}

/// Parses an object index (16 bits).
pub fn parse_index(s: &str) -> anyhow::Result<u16> {
    let v = parse_num(s)?;
    u16::try_from(v).map_err(|_| anyhow!("index `{s}` is above 0xFFFF"))
}

/// Parses a sub-index (8 bits).
pub fn parse_sub(s: &str) -> anyhow::Result<u8> {
    let v = parse_num(s)?;
    u8::try_from(v).map_err(|_| anyhow!("sub-index `{s}` is above 0xFF"))
}

/// The `--node` option, required by this command.
pub fn need_node(g: &Global) -> anyhow::Result<u8> {
    g.node.ok_or_else(|| anyhow!("this command needs --node N (1..127)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_every_spelling() {
        assert_eq!(parse_num("0x6041").unwrap(), 0x6041);
        assert_eq!(parse_num("6041h").unwrap(), 0x6041);
        assert_eq!(parse_num("24641").unwrap(), 0x6041);
        assert!(parse_num("zz").unwrap_err().to_string().contains("is not a number"));
        assert_eq!(parse_index("0x1000").unwrap(), 0x1000);
        assert!(parse_index("0x10000").is_err());
        assert_eq!(parse_sub("0x7F").unwrap(), 0x7F);
        assert!(parse_sub("256").is_err());
    }

    #[test]
    fn sdo_failures_explain_themselves() {
        let f = SdoFailure {
            node: 3,
            index: 0x6041,
            sub: 0,
            write: false,
            error: ClientError::ServerAbort(SdoAbort::NO_OBJECT),
            timeout: Duration::from_millis(500),
        };
        assert_eq!(
            f.to_string(),
            "node 3: SDO read 6041h:00 aborted by the device with code 0x06020000: Object does not exist in the object dictionary"
        );
        let t = SdoFailure { error: ClientError::Timeout, write: true, ..f };
        assert!(t.to_string().starts_with("node 3: SDO write 6041h:00 timed out: no response within 500 ms"));
    }
}
