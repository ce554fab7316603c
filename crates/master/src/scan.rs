//! Network scan: active (SDO upload of 1000h to every node-ID) and passive
//! ([`Master::seen_nodes`]).

use std::time::Duration;

use drivebus_node::Identity;
use tokio::task::JoinSet;

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

    /// Active scan: uploads 1000h from every node in `opts.nodes` in
    /// parallel, then 1018h from those that answered. An SDO abort on
    /// 1000h still proves the node exists (device type reads as 0).
    /// Sorted by node-ID.
    pub async fn scan_with(&self, opts: ScanOptions) -> Vec<ScannedNode> {
        let mut set = JoinSet::new();
        let mut found = Vec::new();
        let mut pending = opts.nodes.clone().filter(|n| (1..=127).contains(n));
        let parallel = opts.parallel.max(1);
        loop {
            while set.len() < parallel {
                let Some(node) = pending.next() else { break };
                let sdo = self.sdo(node).timeout(opts.timeout).retries(0);
                let identity = opts.identity;
                set.spawn(async move {
                    let device_type = match sdo.read::<u32>(0x1000, 0).await {
                        Ok(v) => v,
                        Err(crate::SdoError::Abort { .. }) => 0,
                        Err(_) => return None,
                    };
                    let identity = if identity { read_identity(&sdo).await } else { None };
                    Some(ScannedNode { node, device_type, identity })
                });
            }
            match set.join_next().await {
                Some(Ok(Some(n))) => found.push(n),
                Some(_) => {}
                None => break,
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
