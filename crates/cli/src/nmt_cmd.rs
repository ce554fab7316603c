//! `drivebus scan` and `drivebus nmt`.

use std::time::Duration;

use anyhow::{anyhow, bail};
use drivebus_master::{MasterEvent, NmtCommand, ScanOptions};
use tokio::sync::broadcast::error::RecvError;

use crate::args::{Global, NmtArgs, NmtKind, ScanArgs};
use crate::conn::Conn;
use crate::error::{coded, sdo};
use crate::output::outln;

/// `drivebus scan`: SDO 1000h sweep, then the identity and name of each node found.
pub async fn scan(g: &Global, a: &ScanArgs) -> anyhow::Result<()> {
    if a.from > a.to {
        return Err(coded("usage", anyhow!("--from {} is above --to {}", a.from, a.to)));
    }
    let conn = Conn::open(g).await?;
    let m = &conn.master;
    let opts = ScanOptions {
        nodes: a.from..=a.to,
        timeout: Duration::from_millis(a.wait.max(1)),
        ..ScanOptions::default()
    };
    let found = m.scan_with(opts).await;
    let mut rows = Vec::new();
    for n in found {
        let name = m.sdo(n.node).read::<String>(0x1008, 0).await.ok().filter(|s| !s.is_empty());
        rows.push((n, name));
    }
    conn.close().await?;
    if g.json {
        let items: Vec<_> = rows
            .iter()
            .map(|(n, name)| {
                serde_json::json!({"node": n.node, "device_type": n.device_type, "name": name,
                    "vendor_id": n.identity.map(|i| i.vendor_id), "product_code": n.identity.map(|i| i.product_code),
                    "revision": n.identity.map(|i| i.revision), "serial": n.identity.map(|i| i.serial)})
            })
            .collect();
        outln!("{}", serde_json::json!({"bus": g.bus, "nodes": items}));
        return Ok(());
    }
    if rows.is_empty() {
        outln!("no node answered on {} (node-IDs {}..{})", g.bus, a.from, a.to);
        return Ok(());
    }
    outln!("{:<5} {:<12} {:<12} {:<12} name", "node", "device type", "vendor", "product");
    for (n, name) in rows {
        let hx = |x: Option<u32>| x.map_or_else(|| "-".to_owned(), |x| format!("0x{x:08X}"));
        outln!(
            "{:<5} {:<12} {:<12} {:<12} {}",
            n.node,
            hx(Some(n.device_type)),
            hx(n.identity.map(|i| i.vendor_id)),
            hx(n.identity.map(|i| i.product_code)),
            name.unwrap_or_else(|| "-".into())
        );
    }
    Ok(())
}

/// `drivebus nmt`: the frame is written before success is reported; reset
/// commands wait for the boot-up, start/preop check the node answers SDO.
pub async fn nmt(g: &Global, a: &NmtArgs) -> anyhow::Result<()> {
    let target = match (a.all, g.node) {
        (true, Some(_)) => return Err(coded("usage", anyhow!("give --node N or --all, not both"))),
        (true, None) => 0,
        (false, Some(n)) => n,
        (false, None) => return Err(coded("usage", anyhow!("give --node N or --all"))),
    };
    let (cmd, what) = match a.command {
        NmtKind::Start => (NmtCommand::Start, "start"),
        NmtKind::Stop => (NmtCommand::Stop, "stop"),
        NmtKind::Preop => (NmtCommand::EnterPreOperational, "enter pre-operational"),
        NmtKind::Reset => (NmtCommand::ResetNode, "reset node"),
        NmtKind::ResetComm => (NmtCommand::ResetCommunication, "reset communication"),
    };
    let conn = Conn::open(g).await?;
    let m = &conn.master;
    let boot_wait = conn.timeout.max(Duration::from_millis(500));
    // Any node's boot-up: a node whose node-ID was changed (LSS, 2000h
    // objects) boots under its new one after a reset.
    let mut events = m.subscribe_events();
    m.nmt(target, cmd).await?;
    let who = if target == 0 { "all nodes".to_owned() } else { format!("node {target}") };
    let confirmed = if target == 0 {
        None
    } else {
        match a.command {
            NmtKind::Reset | NmtKind::ResetComm => {
                let booted = m
                    .timeout(boot_wait, async {
                        let mut other = None;
                        loop {
                            match events.recv().await {
                                Ok(MasterEvent::Bootup { node }) if node == target => return Some(node),
                                // Another node's boot-up: this one under a new node-ID,
                                // unless its own follows at once.
                                Ok(MasterEvent::Bootup { node }) if other.is_none() => other = Some(node),
                                Ok(_) | Err(RecvError::Lagged(_)) => {}
                                Err(RecvError::Closed) => return other,
                            }
                            if let Some(o) = other
                                && m.timeout(Duration::from_millis(100), events.recv()).await.is_err()
                            {
                                return Some(o);
                            }
                        }
                    })
                    .await
                    .ok()
                    .flatten();
                match booted {
                    Some(n) if n == target => Some("boot-up received".to_owned()),
                    Some(n) => Some(format!("boot-up received from node {n} (its new node-ID)")),
                    None => {
                        conn.close().await?;
                        bail!(
                            "node {target}: no boot-up message within {} ms after NMT {what} (is node {target} on the bus?)",
                            boot_wait.as_millis()
                        );
                    }
                }
            }
            NmtKind::Start | NmtKind::Preop => {
                // Both states answer SDO: check the node is there.
                if let Err(e) = m.sdo(target).upload(0x1000, 0).await {
                    let timeout = conn.timeout;
                    conn.close().await?;
                    return Err(sdo(target, 0x1000, 0, false, timeout)(e));
                }
                Some("node answers SDO".to_owned())
            }
            NmtKind::Stop => None,
        }
    };
    // Written by the transport before the report.
    conn.close().await?;
    crate::output::emit(
        g.json,
        serde_json::json!({"command": what, "node": target, "sent": true, "confirmed": confirmed}),
        || match confirmed {
            Some(c) => format!("NMT {what} sent to {who}: {c}"),
            None => format!("NMT {what} sent to {who}"),
        },
    );
    Ok(())
}
