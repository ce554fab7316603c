//! `drivebus pdo show|map`.

use anyhow::anyhow;
use drivebus_master::{ConfigError, PdoDir as Dir, PdoMapEntry, PdoRecord, SdoAbort, SdoError};

use crate::args::{Global, PdoCmd, PdoMapArgs};
use crate::conn::{Conn, need_node};
use crate::dict::Dict;
use crate::error::{coded, sdo};
use crate::output::outln;

/// Runs a `pdo` subcommand.
pub async fn run(g: &Global, c: &PdoCmd) -> anyhow::Result<()> {
    let node = need_node(g)?;
    match c {
        PdoCmd::Show => show(g, node).await,
        PdoCmd::Map(a) => map(g, node, a).await,
    }
}

/// Reads every PDO of `node` up to the first one it lacks.
pub async fn read_all(conn: &Conn, node: u8) -> anyhow::Result<Vec<(Dir, u16, PdoRecord)>> {
    let mut pdos = Vec::new();
    for dir in [Dir::Rx, Dir::Tx] {
        for num in 1..=512u16 {
            match conn.master.read_pdo(node, dir, num).await {
                Ok(r) => pdos.push((dir, num, r)),
                Err(SdoError::Abort { code, .. })
                    if code == SdoAbort::NO_OBJECT || code == SdoAbort::NO_SUB_INDEX =>
                {
                    break;
                }
                Err(e) => return Err(sdo(node, dir.comm_index(num), 1, false, conn.timeout)(e)),
            }
        }
    }
    Ok(pdos)
}

fn dir_name(d: Dir) -> &'static str {
    if d == Dir::Rx { "RPDO" } else { "TPDO" }
}

async fn show(g: &Global, node: u8) -> anyhow::Result<()> {
    let mut conn = Conn::open(g).await?;
    let pdos = read_all(&conn, node).await;
    let dict = std::mem::take(&mut conn.dict);
    conn.close().await?;
    print_pdos(g, node, &pdos?, &dict);
    Ok(())
}

fn print_pdos(g: &Global, node: u8, pdos: &[(Dir, u16, PdoRecord)], dict: &Dict) {
    let name = |m: &PdoMapEntry| dict.name(m.index, m.sub).unwrap_or_default();
    if g.json {
        let items: Vec<_> = pdos
            .iter()
            .map(|(d, n, p)| {
                let m: Vec<_> = p
                    .mapping
                    .iter()
                    .map(|e| serde_json::json!({"index": e.index, "sub": e.sub, "bits": e.bits, "name": name(e)}))
                    .collect();
                serde_json::json!({"dir": dir_name(*d), "number": n, "cob_id": p.cob_id & 0x1FFF_FFFF, "valid": p.valid(),
                    "transmission_type": p.transmission_type, "inhibit_time": p.inhibit_time, "event_timer_ms": p.event_timer, "mapping": m})
            })
            .collect();
        outln!("{}", serde_json::json!({"node": node, "pdos": items}));
        return;
    }
    for (d, n, p) in pdos {
        let valid = if p.valid() { "valid" } else { "invalid" };
        let et = p.event_timer.filter(|&t| t > 0).map(|t| format!(" event timer {t} ms")).unwrap_or_default();
        outln!(
            "{}{n} COB-ID 0x{:03X} {valid}, type {}{et}",
            dir_name(*d),
            p.cob_id & 0x1FFF_FFFF,
            p.transmission_type
        );
        for e in &p.mapping {
            outln!("    {:04X}h:{:02X} {:>2} bits  {}", e.index, e.sub, e.bits, name(e));
        }
    }
}

/// `INDEX:SUB:BITS` (hex, hex, decimal), or an object whose size the
/// dictionary knows.
fn parse_entry(dict: &Dict, s: &str) -> anyhow::Result<PdoMapEntry> {
    let parts: Vec<&str> = s.split(':').collect();
    if let [i, sub, bits] = parts[..] {
        let (index, sub) = dict.resolve(i, Some(sub))?;
        let bits: u8 = bits
            .trim()
            .parse()
            .ok()
            .filter(|b| (1..=64).contains(b))
            .ok_or_else(|| anyhow!("bad mapping entry `{s}`: BITS must be 1..64 (decimal)"))?;
        return Ok(PdoMapEntry::new(index, sub.unwrap_or(0), bits));
    }
    let (index, sub) = dict.resolve(s, None).map_err(|e| {
        anyhow!("bad mapping entry `{s}`: expected INDEX:SUB:BITS, e.g. 6041:0:16, or an object ({e})")
    })?;
    let sub = sub.unwrap_or(0);
    let bits = dict.data_type(index, sub).and_then(|t| t.fixed_size()).ok_or_else(|| {
        anyhow!("bad mapping entry `{s}`: its size is unknown; write INDEX:SUB:BITS, e.g. 6041:0:16")
    })?;
    Ok(PdoMapEntry::new(index, sub, (bits * 8) as u8))
}

async fn map(g: &Global, node: u8, a: &PdoMapArgs) -> anyhow::Result<()> {
    let dict = Dict { eds: crate::eds_cmd::load_global_eds(g)? };
    let entries = a
        .entries
        .iter()
        .map(|e| parse_entry(&dict, e).map_err(|e| coded("usage", e)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let cob = a.cob_id.as_deref().map(crate::dict::number).transpose().map_err(|e| coded("usage", e))?;
    let dir = a.dir;
    let conn = Conn::open_with(g, dict).await?;
    let m = &conn.master;
    let current = m.read_pdo(node, dir, a.number).await;
    let current = match current {
        Ok(c) => c,
        Err(e) => {
            let t = conn.timeout;
            conn.close().await?;
            return Err(sdo(node, dir.comm_index(a.number), 1, false, t)(e));
        }
    };
    let rec = PdoRecord {
        cob_id: cob.unwrap_or(current.cob_id & !0x8000_0000) & !0x8000_0000,
        transmission_type: a.transmission.unwrap_or(current.transmission_type),
        inhibit_time: a.inhibit,
        event_timer: a.event_timer,
        sync_start: None,
        mapping: entries.clone(),
    };
    let r = m.try_write_pdo(node, dir, a.number, &rec).await;
    let timeout = conn.timeout;
    conn.close().await?;
    if let Err(e) = r {
        let cause = match e.cause {
            ConfigError::Sdo { index, sub, error } => sdo(node, index, sub, true, timeout)(error),
            other => anyhow!("{other}"),
        };
        let outcome = match (&e.previous, &e.restored) {
            (None, _) => "nothing was changed".to_owned(),
            (Some(_), Ok(())) => {
                format!("the previous mapping of {}{} is in force again", dir_name(dir), a.number)
            }
            (Some(_), Err(re)) => format!(
                "restoring the previous mapping failed too ({re}): {}{} may be invalid, check with `drivebus --node {node} pdo show`",
                dir_name(dir),
                a.number
            ),
        };
        return Err(cause.context(format!(
            "node {node}: {}{} mapping refused; {outcome}",
            dir_name(dir),
            a.number
        )));
    }
    crate::output::emit(
        g.json,
        serde_json::json!({"node": node, "dir": dir_name(dir), "number": a.number, "cob_id": rec.cob_id,
            "transmission_type": rec.transmission_type,
            "mapping": entries.iter().map(|e| e.raw()).collect::<Vec<_>>()}),
        || {
            format!(
                "node {node}: {}{} mapped {} entries, COB-ID 0x{:03X} valid, type {}",
                dir_name(dir),
                a.number,
                entries.len(),
                rec.cob_id & 0x1FFF_FFFF,
                rec.transmission_type
            )
        },
    );
    Ok(())
}
