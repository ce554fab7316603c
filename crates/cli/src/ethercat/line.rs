//! `drivebus ethercat scan|sdo|state|pdo`: formatting over
//! `drivebus_ethercat::master`.

use anyhow::{anyhow, bail};
use drivebus_ethercat::master::{self, AlState, AlStatus, LineMaster, MasterError, block_on};
use drivebus_master::Value;

use super::{EcatLine, EcatPdoShow, EcatSdoWrite, EcatStateArgs};
use crate::args::Global;
use crate::dict::Dict;
use crate::error::coded;
use crate::output::outln;
use crate::sdo_cmd::{hex, parse_type};

/// A master error with its `--json` code.
pub fn master_err(e: MasterError) -> anyhow::Error {
    let code = match &e {
        MasterError::Open(..) | MasterError::NoLine(_) | MasterError::Empty(_) => "bus",
        MasterError::NoSlave { .. } => "no_slave",
        MasterError::Abort { .. } => "sdo_abort",
        MasterError::Refused { .. } => "al_refused",
        MasterError::Unsupported(_) => "unsupported",
        MasterError::InUse | MasterError::Ethercrab(..) => "ethercat",
    };
    coded(code, anyhow::Error::new(e))
}

/// Runs `f` with a master on the interface, on a thread of its own
/// (ethercrab's futures run on async-io, next to its socket thread).
pub async fn with_master<T: Send + 'static>(
    g: &Global,
    line: &EcatLine,
    f: impl AsyncFnOnce(&LineMaster) -> anyhow::Result<T> + Send + 'static,
) -> anyhow::Result<T> {
    let iface = line.iface.clone();
    let timeout = std::time::Duration::from_millis(g.timeout_ms(1000));
    tokio::task::spawn_blocking(move || {
        let m = LineMaster::on_iface(&iface, timeout).map_err(master_err)?;
        block_on(f(&m))
    })
    .await
    .map_err(|e| anyhow!("the master thread failed: {e}"))?
}

fn status_json(s: &AlStatus) -> serde_json::Value {
    serde_json::json!({"state": master::state_text(s.state), "error": s.error, "al_status_code": s.code,
        "al_status_text": master::al_status_text(s.code)})
}

fn status_text(s: &AlStatus) -> String {
    if s.error || s.code != 0 {
        format!(
            "{}{} (AL status code 0x{:04X} {})",
            master::state_text(s.state),
            if s.error { " + ERROR" } else { "" },
            s.code,
            master::al_status_text(s.code)
        )
    } else {
        master::state_text(s.state)
    }
}

/// `drivebus ethercat scan`.
pub async fn scan(g: &Global, line: &EcatLine) -> anyhow::Result<()> {
    let found = with_master(g, line, async |m: &LineMaster| m.scan().await.map_err(master_err)).await?;
    if g.json {
        let slaves: Vec<_> = found
            .iter()
            .map(|s| {
                let coe = s.coe_identity.map(|c| {
                    serde_json::json!({"vendor_id": c[0], "product_code": c[1], "revision": c[2], "serial": c[3]})
                });
                let mut st = status_json(&s.found);
                st["position"] = s.position.into();
                st["address"] = s.address.into();
                st["alias"] = s.alias.into();
                st["name"] = s.name.clone().into();
                st["vendor_id"] = s.identity[0].into();
                st["product_code"] = s.identity[1].into();
                st["revision"] = s.identity[2].into();
                st["serial"] = s.identity[3].into();
                st["coe_identity"] = coe.unwrap_or(serde_json::Value::Null);
                st["mailbox"] = master::mailbox_protocols(s.mailbox).into();
                st["dc"] = s.dc.into();
                st
            })
            .collect();
        outln!("{}", serde_json::json!({"iface": line.iface, "slaves": slaves}));
        return Ok(());
    }
    outln!(
        "{:<4} {:<7} {:<6} {:<10} {:<10} {:<10} {:<10} {:<8} {:<8} name",
        "pos",
        "address",
        "alias",
        "vendor",
        "product",
        "revision",
        "serial",
        "state",
        "mailbox"
    );
    for s in &found {
        let id = s.identity;
        outln!(
            "{:<4} 0x{:04X}  {:<6} 0x{:08X} 0x{:08X} 0x{:08X} 0x{:08X} {:<8} {:<8} {}{}",
            s.position,
            s.address,
            s.alias,
            id[0],
            id[1],
            id[2],
            id[3],
            status_text(&s.found),
            master::mailbox_protocols(s.mailbox).join(","),
            s.name,
            match s.coe_identity {
                Some(c) if c != id => " (1018h differs from the SII)",
                _ => "",
            }
        );
    }
    Ok(())
}

/// `drivebus ethercat sdo write`.
pub async fn sdo_write(g: &Global, a: &EcatSdoWrite) -> anyhow::Result<()> {
    let dict = Dict::default();
    let (obj, sub, value) = match a.args.as_slice() {
        [o, v] => (o, None, v),
        [o, s, v] => (o, Some(s.as_str()), v),
        _ => bail!(coded("usage", anyhow!("give OBJECT [SUB] VALUE"))),
    };
    let (index, sub) = dict.resolve(obj, sub).map_err(|e| coded("usage", e))?;
    let sub = sub.unwrap_or(0);
    let dt = match a.ty.as_deref() {
        Some(t) => parse_type(t)?,
        None => dict.data_type(index, sub).ok_or_else(|| {
            coded(
                "usage",
                anyhow!(
                    "the data type of {index:04X}h:{sub:02X} is unknown: give --type (u8, u16, u32, i32, ...)"
                ),
            )
        })?,
    };
    let v = Value::parse(dt, value).map_err(|e| coded("usage", anyhow!("bad value `{value}`: {e}")))?;
    let bytes = v
        .encode(dt)
        .map_err(|e| coded("usage", anyhow!("value `{value}` does not fit {}: {e}", dt.name())))?;
    let pos = a.slave;
    let data = bytes.clone();
    with_master(g, &a.line, async move |m: &LineMaster| {
        m.check_position(pos).await.map_err(master_err)?;
        let group = m.init().await.map_err(master_err)?;
        let sd = m.slave(&group, pos).map_err(master_err)?;
        master::sdo_write(&sd, pos, index, sub, &data).await.map_err(master_err)
    })
    .await?;
    crate::output::emit(
        g.json,
        serde_json::json!({"slave": pos, "index": index, "sub": sub, "type": dt.name(), "written": hex(&bytes)}),
        || format!("slave {pos}: wrote {index:04X}h:{sub:02X} = {v} ({})", dt.name()),
    );
    Ok(())
}

/// `drivebus ethercat state`.
pub async fn state(g: &Global, a: &EcatStateArgs) -> anyhow::Result<()> {
    let target = match a.target.as_deref() {
        None => None,
        Some(t) => match AlState::parse(t) {
            Some(AlState::Boot) if !a.direct => {
                bail!(coded(
                    "usage",
                    anyhow!("boot is requested with --direct (from INIT, as ETG.1000.6 allows)")
                ))
            }
            Some(s) => Some(s),
            None => bail!(coded(
                "usage",
                anyhow!("`{t}` is not a state: init, preop, safeop, op (boot with --direct)")
            )),
        },
    };
    let (only, direct) = (a.slave, a.direct);
    let states = with_master(g, &a.line, async move |m: &LineMaster| {
        let count = m.count().await.map_err(master_err)?;
        if count == 0 {
            return Err(master_err(MasterError::Empty(m.line_name().to_owned())));
        }
        if let Some(p) = only {
            m.check_position(p).await.map_err(master_err)?;
        }
        let which: Vec<usize> = match only {
            Some(p) => vec![p],
            None => (1..=count.min(master::MAX_SUBDEVICES)).collect(),
        };
        match target {
            None => {}
            Some(t) if direct || t == AlState::Init => {
                for &p in &which {
                    m.request_state(p, t).await.map_err(master_err)?;
                }
            }
            Some(t) => bring_up(m, t, &(1..=count.min(master::MAX_SUBDEVICES)).collect::<Vec<_>>()).await?,
        }
        let mut out = Vec::new();
        for &p in &which {
            out.push((p, m.al_status(p).await.map_err(master_err)?));
        }
        Ok(out)
    })
    .await?;
    if g.json {
        let items: Vec<_> = states
            .iter()
            .map(|(p, s)| {
                let mut j = status_json(s);
                j["position"] = (*p).into();
                j
            })
            .collect();
        outln!("{}", serde_json::json!({"slaves": items}));
    } else {
        for (p, s) in &states {
            outln!("slave {p}: {}", status_text(s));
        }
    }
    Ok(())
}

/// PRE-OP, SAFE-OP or OP the way ethercrab brings a line up; a refusal is
/// reported with the AL status code of the slave that refused.
async fn bring_up(m: &LineMaster, target: AlState, which: &[usize]) -> anyhow::Result<()> {
    let md = m.main_device();
    let result: Result<(), MasterError> = async {
        let group = m.init().await?;
        if target == AlState::PreOp {
            return Ok(());
        }
        // Free run: no DC SYNC an earlier master may have left on.
        m.sync_off(&group).await?;
        let e = |what: &'static str| move |e| MasterError::Ethercrab(what.into(), e);
        let group = group.into_pre_op_pdi(md).await.map_err(e("mapping the process data"))?;
        let group = group.into_safe_op(md).await.map_err(e("PRE-OP -> SAFE-OP"))?;
        if target == AlState::Op {
            group.into_op(md).await.map_err(e("SAFE-OP -> OP"))?;
        }
        Ok(())
    }
    .await;
    match result {
        // Name the slave that refused, with its code, rather than ethercrab's summary.
        Err(e) => Err(master_err(m.refusal(target, which, e).await)),
        Ok(()) => Ok(()),
    }
}

/// `drivebus ethercat pdo show`.
pub async fn pdo_show(g: &Global, a: &EcatPdoShow) -> anyhow::Result<()> {
    let pos = a.slave;
    let (rx, tx) = with_master(g, &a.line, async move |m: &LineMaster| {
        m.check_position(pos).await.map_err(master_err)?;
        let group = m.init().await.map_err(master_err)?;
        let sd = m.slave(&group, pos).map_err(master_err)?;
        let rx = master::pdo_assignment(&sd, pos, 0x1C12).await.map_err(master_err)?;
        let tx = master::pdo_assignment(&sd, pos, 0x1C13).await.map_err(master_err)?;
        Ok((rx, tx))
    })
    .await?;
    let dict = Dict::default();
    let name = |e: u32| dict.name((e >> 16) as u16, (e >> 8) as u8).unwrap_or_default();
    let bytes = |m: &[master::PdoMapping]| master::image_layout(m).last().map_or(0, |e| e.end()) / 8;
    if g.json {
        let dir = |m: &[master::PdoMapping]| -> Vec<serde_json::Value> {
            m.iter()
                .map(|(pdo, entries)| {
                    let e: Vec<_> = entries
                        .iter()
                        .map(|e| {
                            serde_json::json!({"index": e >> 16, "sub": (e >> 8) & 0xFF, "bits": e & 0xFF, "name": name(*e)})
                        })
                        .collect();
                    serde_json::json!({"pdo": pdo, "entries": e})
                })
                .collect()
        };
        outln!(
            "{}",
            serde_json::json!({"slave": pos, "rx": dir(&rx), "tx": dir(&tx), "output_bytes": bytes(&rx), "input_bytes": bytes(&tx)})
        );
        return Ok(());
    }
    for (label, assign, pdos) in [("RxPDO", 0x1C12, &rx), ("TxPDO", 0x1C13, &tx)] {
        for (k, (pdo, entries)) in pdos.iter().enumerate() {
            outln!("{label} {pdo:04X}h ({assign:04X}h:{:02X})", k + 1);
            for e in entries {
                outln!("    {:04X}h:{:02X} {:>2} bits  {}", e >> 16, (e >> 8) & 0xFF, e & 0xFF, name(*e));
            }
        }
    }
    outln!("outputs {} bytes (RxPDOs), inputs {} bytes (TxPDOs)", bytes(&rx), bytes(&tx));
    Ok(())
}
