//! Network scan: active (SDO upload of 1000h to every node-ID) and passive
//! ([`Master::seen_nodes`]).

use std::time::Duration;

use drivebus_can::Identity;

use crate::master::Master;

/// A node that answered the scan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScannedNode {
    /// Node-ID.
    pub node: u8,
    /// 1000h device type.
    pub device_type: u32,
    /// 1018h:1..4 when readable (vendor-ID is mandatory; absent parts read as 0).
    pub identity: Option<Identity>,
}

/// How to scan.
#[derive(Clone, Debug)]
pub struct ScanOptions {
    /// Node-IDs to probe.
    pub nodes: std::ops::RangeInclusive<u8>,
    /// SDO timeout per probe (short: absent nodes cost exactly this).
    pub timeout: Duration,
    /// Probes in flight at once.
    pub parallel: usize,
    /// Also read 1018h.
    pub identity: bool,
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions { nodes: 1..=127, timeout: Duration::from_millis(100), parallel: 127, identity: true }
    }
}

impl Master {
    /// Active scan with [`ScanOptions::default`].
    pub async fn scan(&self) -> Vec<ScannedNode> {
        self.scan_with(ScanOptions::default()).await
    }

    /// Active scan: uploads 1000h from every node in `opts.nodes`,
    /// `opts.parallel` at a time (each to its own SDO server, so they run
    /// side by side on the bus), then 1018h from those that answered. An
    /// SDO abort on 1000h still proves the node exists (device type reads
    /// as 0). Sorted by node-ID.
    pub async fn scan_with(&self, opts: ScanOptions) -> Vec<ScannedNode> {
        let nodes: Vec<u8> = opts.nodes.clone().filter(|n| (1..=127).contains(n)).collect();
        let mut found = Vec::new();
        for chunk in nodes.chunks(opts.parallel.max(1)) {
            // Start every probe of the chunk before awaiting any.
            let probes: Vec<_> = chunk
                .iter()
                .map(|&node| {
                    let sdo = self.sdo(node).timeout(opts.timeout).retries(0);
                    (node, Box::pin(async move { sdo.read::<u32>(0x1000, 0).await }))
                })
                .collect();
            let mut started = Vec::with_capacity(probes.len());
            for (node, mut fut) in probes {
                // One poll queues the request in the core.
                let first = std::future::poll_fn(|cx| match fut.as_mut().poll(cx) {
                    std::task::Poll::Ready(v) => std::task::Poll::Ready(Some(v)),
                    std::task::Poll::Pending => std::task::Poll::Ready(None),
                })
                .await;
                started.push((node, first, fut));
            }
            for (node, first, fut) in started {
                let r = match first {
                    Some(r) => r,
                    None => fut.await,
                };
                let device_type = match r {
                    Ok(v) => v,
                    Err(crate::SdoError::Abort { .. }) => 0,
                    Err(_) => continue,
                };
                found.push(ScannedNode { node, device_type, identity: None });
            }
        }
        if opts.identity {
            for n in &mut found {
                n.identity = read_identity(&self.sdo(n.node).timeout(opts.timeout)).await;
            }
        }
        found.sort_by_key(|n| n.node);
        found
    }
}

async fn read_identity(sdo: &crate::SdoHandle) -> Option<Identity> {
    let vendor_id = sdo.read::<u32>(0x1018, 1).await.ok()?;
    let part = |sub| async move { sdo.read::<u32>(0x1018, sub).await.unwrap_or(0) };
    Some(Identity { vendor_id, product_code: part(2).await, revision: part(3).await, serial: part(4).await })
}
