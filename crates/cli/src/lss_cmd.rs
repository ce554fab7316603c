//! `drivebus lss scan|set-node-id|assign` (CiA 305) through the master's
//! LSS services. Setting a node-ID never uses "switch state global
//! configuration" blindly: that would configure every slave at once.

use std::time::Duration;

use anyhow::{anyhow, bail};
use drivebus_master::{Identity, LssError, OnlySlave};

use crate::args::{Global, LssCmd, LssSetArgs};
use crate::conn::Conn;
use crate::dict::number;
use crate::error::coded;
use crate::output::emit;

fn addr_json(a: &Identity) -> serde_json::Value {
    serde_json::json!({"vendor_id": a.vendor_id, "product_code": a.product_code, "revision": a.revision, "serial": a.serial})
}

fn addr_text(a: &Identity) -> String {
    format!(
        "vendor 0x{:08X} product 0x{:08X} revision 0x{:08X} serial 0x{:08X}",
        a.vendor_id, a.product_code, a.revision, a.serial
    )
}

fn addr_flags(a: &Identity) -> String {
    format!(
        "--vendor 0x{:X} --product 0x{:X} --revision 0x{:X} --serial 0x{:X}",
        a.vendor_id, a.product_code, a.revision, a.serial
    )
}

/// The default wait for each LSS answer (`--timeout` changes it).
const LSS_ANSWER_MS: u64 = 100;

fn lss_err(e: LssError) -> anyhow::Error {
    coded("lss_error", anyhow!("{e}"))
}

/// Runs an `lss` subcommand.
pub async fn run(g: &Global, c: &LssCmd) -> anyhow::Result<()> {
    let conn = Conn::open(g).await?;
    // Each LSS question (a fastscan asks up to 133) waits this long for
    // the (merged) answers: --timeout, as its help says.
    let answer = Duration::from_millis(g.timeout_ms(LSS_ANSWER_MS));
    let lss = conn.master.lss().timeout(answer);
    let r = match c {
        LssCmd::Scan => match lss.probe_unconfigured().await.map_err(lss_err) {
            Ok(Some((a, more))) => {
                let more_text = if more {
                    "\nmore unconfigured LSS slaves answer: give each an address-based node-ID (lss set-node-id N --vendor ...) or all at once (lss assign --first N)"
                } else {
                    ""
                };
                Ok((
                    serde_json::json!({"found": true, "first": addr_json(&a), "more": more}),
                    format!("unconfigured LSS slave: {}{more_text}", addr_text(&a)),
                ))
            }
            Ok(None) => Ok((
                serde_json::json!({"found": false}),
                format!("no unconfigured LSS slave answered on {}", g.bus),
            )),
            Err(e) => Err(e),
        },
        LssCmd::SetNodeId(a) => set_node_id(g, &conn, a).await,
        LssCmd::Assign(a) => {
            let mut assigned = Vec::new();
            let mut id = a.first;
            loop {
                match lss.configure_only_slave(id, a.store).await {
                    Ok(OnlySlave::Configured(addr)) => {
                        assigned.push((id, addr));
                        break;
                    }
                    Ok(OnlySlave::NoneFound) => break,
                    // Several: give the lowest one this ID, then go on.
                    Ok(OnlySlave::Several(_)) => match lss.assign_node_id(id, a.store).await {
                        Ok(Some(addr)) => assigned.push((id, addr)),
                        Ok(None) => break,
                        Err(e) => return close_with(conn, Err(lss_err(e))).await,
                    },
                    Err(e) => return close_with(conn, Err(lss_err(e))).await,
                }
                if id == 127 {
                    break;
                }
                id += 1;
            }
            let lines: Vec<String> =
                assigned.iter().map(|(id, a)| format!("node-ID {id} assigned to {}", addr_text(a))).collect();
            Ok((
                serde_json::json!({"assigned": assigned.iter().map(|(id, a)| serde_json::json!({"node_id": id, "address": addr_json(a)})).collect::<Vec<_>>(), "stored": a.store}),
                if lines.is_empty() {
                    format!("no unconfigured LSS slave answered on {}", g.bus)
                } else {
                    format!(
                        "{}\n{} slave(s) configured{}",
                        lines.join("\n"),
                        lines.len(),
                        if a.store { " and stored" } else { "" }
                    )
                },
            ))
        }
    };
    close_with(conn, r.map(|(j, t)| emit(g.json, j, || t))).await
}

async fn close_with(conn: Conn, r: anyhow::Result<()>) -> anyhow::Result<()> {
    let closed = conn.close().await;
    r?;
    closed
}

async fn set_node_id(g: &Global, conn: &Conn, a: &LssSetArgs) -> anyhow::Result<(serde_json::Value, String)> {
    let parts = [&a.vendor, &a.product, &a.revision, &a.serial];
    let answer = Duration::from_millis(g.timeout_ms(LSS_ANSWER_MS));
    let lss = conn.master.lss().timeout(answer);
    let stored = if a.store { " and stored" } else { "" };
    let address = if parts.iter().all(|p| p.is_some()) {
        let num = |s: &Option<String>| number(s.as_deref().unwrap_or("0")).map_err(|e| coded("usage", e));
        Some(Identity {
            vendor_id: num(&a.vendor)?,
            product_code: num(&a.product)?,
            revision: num(&a.revision)?,
            serial: num(&a.serial)?,
        })
    } else if parts.iter().any(|p| p.is_some()) {
        bail!(coded(
            "usage",
            anyhow!("give all of --vendor, --product, --revision and --serial (the LSS address), or none")
        ));
    } else if let Some(node) = g.node {
        // A configured node: its LSS address is its identity object.
        let sdo = conn.master.sdo(node);
        let mut v = [0u32; 4];
        for (i, slot) in v.iter_mut().enumerate() {
            let sub = i as u8 + 1;
            *slot = sdo.read::<u32>(0x1018, sub).await.map_err(crate::error::sdo(
                node,
                0x1018,
                sub,
                false,
                conn.timeout,
            ))?;
        }
        Some(Identity::new(v[0], v[1], v[2], v[3]))
    } else {
        None
    };
    if let Some(addr) = address {
        lss.configure_selected(&addr, a.new_id, a.store).await.map_err(|e| match e {
            LssError::Timeout => coded(
                "lss_error",
                anyhow!("no LSS slave with {} answered within {} ms", addr_text(&addr), answer.as_millis()),
            ),
            e => lss_err(e),
        })?;
        let when = if g.node.is_some() {
            format!(
                " (active after NMT reset communication: `drivebus --node {} nmt reset-comm`; the node then boots as node {})",
                g.node.unwrap_or(0),
                a.new_id
            )
        } else {
            " (active after NMT reset communication of a configured slave; an unconfigured one starts with it now)".to_owned()
        };
        return Ok((
            serde_json::json!({"node_id": a.new_id, "stored": a.store, "address": addr_json(&addr)}),
            format!(
                "LSS: node-ID {} configured{stored} on the slave with {}{when}",
                a.new_id,
                addr_text(&addr)
            ),
        ));
    }
    let only = conn.master.lss().timeout(answer);
    match only.configure_only_slave(a.new_id, a.store).await.map_err(lss_err)? {
        OnlySlave::Configured(addr) => Ok((
            serde_json::json!({"node_id": a.new_id, "stored": a.store, "address": addr_json(&addr)}),
            format!(
                "LSS: node-ID {} configured{stored} on the only unconfigured slave ({}); it starts under it now",
                a.new_id,
                addr_text(&addr)
            ),
        )),
        OnlySlave::Several(first) => Err(coded(
            "lss_ambiguous",
            anyhow!(
                "more than one unconfigured LSS slave answers: all of them would get node-ID {id}; nothing was changed.\n  Address one slave: drivebus lss set-node-id {id} {}\n  (the lowest address found; `drivebus lss scan` finds one, `drivebus lss assign --first {id}` numbers them all)",
                addr_flags(&first),
                id = a.new_id
            ),
        )),
        OnlySlave::NoneFound => Err(coded(
            "lss_error",
            anyhow!(
                "no LSS slave answered: no unconfigured slave on {}. For a configured node give --node N (its 1018h is read by SDO) or its LSS address (--vendor --product --revision --serial)",
                g.bus
            ),
        )),
    }
}
