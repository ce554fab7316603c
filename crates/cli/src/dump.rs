//! `drivebus dump`: a live decoded trace, or candump log lines; filters by
//! node and CAN-ID; PDOs decoded by the mapping read from the devices (or
//! from the EDS).

use std::io::Write;
use std::ops::RangeInclusive;
use std::time::{SystemTime, UNIX_EPOCH};

use anyhow::anyhow;
use drivebus_master::{Frame, PdoDir, PdoMapEntry, candump};
use tokio::sync::broadcast;

use crate::args::{DumpArgs, Global};
use crate::conn::Conn;
use crate::decode::{PdoMaps, decode};
use crate::error::coded;

/// Parses `0x181`, `181`, `0x180-0x1FF` (CAN-IDs are hex).
pub fn id_range(s: &str) -> anyhow::Result<RangeInclusive<u32>> {
    let one = |t: &str| {
        crate::dict::hex(t).filter(|v| *v <= 0x1FFF_FFFF).ok_or_else(|| {
            coded("usage", anyhow!("bad --id `{s}`: CAN-IDs are hex, e.g. 181, 0x181 or 0x180-0x1FF"))
        })
    };
    let (lo, hi) = match s.split_once('-') {
        Some((a, b)) => (one(a)?, one(b)?),
        None => (one(s)?, one(s)?),
    };
    if lo > hi {
        return Err(coded("usage", anyhow!("bad --id `{s}`: {lo:X} is above {hi:X}")));
    }
    Ok(lo..=hi)
}

/// True for the frames of `node` in the pre-defined connection set, NMT
/// commands to it (or to all) and its PDOs in `pdos`.
pub fn of_node(f: &Frame, node: u8, pdos: &PdoMaps) -> bool {
    let Some(id) = f.std_id() else { return false };
    if id == 0x000 {
        return f.data().get(1).is_some_and(|&n| n == 0 || n == node);
    }
    if let Some((label, _)) = pdos.get(&id) {
        return label.ends_with(&format!("node {node}"));
    }
    matches!(
        id & 0x780,
        0x080 | 0x180 | 0x200 | 0x280 | 0x300 | 0x380 | 0x400 | 0x480 | 0x500 | 0x580 | 0x600 | 0x700
    ) && (id & 0x7F) as u8 == node
}

/// The PDO mappings of `nodes`, read by SDO (valid PDOs only).
pub async fn read_maps(conn: &Conn, nodes: &[u8]) -> PdoMaps {
    let mut maps = PdoMaps::new();
    for &node in nodes {
        for dir in [PdoDir::Tx, PdoDir::Rx] {
            for num in 1..=512u16 {
                let Ok(rec) = conn.master.read_pdo(node, dir, num).await else { break };
                if rec.valid() && !rec.mapping.is_empty() {
                    let kind = if dir == PdoDir::Tx { "TPDO" } else { "RPDO" };
                    maps.insert(rec.can_id(), (format!("{kind}{num} node {node}"), rec.mapping));
                }
            }
        }
    }
    maps
}

/// The default mappings an EDS gives node `node` (ParameterValue, else DefaultValue).
fn eds_maps(eds: &drivebus_eds::Eds, node: u8) -> PdoMaps {
    let mut maps = PdoMaps::new();
    let value = |v: &drivebus_eds::EdsVar, dt| {
        let text = v.parameter_value.as_ref().or(v.default.as_ref())?;
        drivebus_eds::eval(text, dt, node).ok()
    };
    for (kind, comm, map) in [("RPDO", 0x1400u16, 0x1600u16), ("TPDO", 0x1800, 0x1A00)] {
        for n in 0..512u16 {
            let (Some(c), Some(m)) = (eds.objects.get(&(comm + n)), eds.objects.get(&(map + n))) else {
                continue;
            };
            let Some(cob) = c.subs.get(&1).and_then(|v| value(v, drivebus_master::DataType::Unsigned32))
            else {
                continue;
            };
            let cob = u32::from_le_bytes([cob[0], cob[1], cob[2], cob[3]]);
            let count = m
                .subs
                .get(&0)
                .and_then(|v| value(v, drivebus_master::DataType::Unsigned8))
                .map_or(0, |b| b[0]);
            let entries: Vec<PdoMapEntry> = (1..=count)
                .filter_map(|s| m.subs.get(&s).and_then(|v| value(v, drivebus_master::DataType::Unsigned32)))
                .map(|b| PdoMapEntry::from_raw(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
                .collect();
            if cob & 0x8000_0000 == 0 && !entries.is_empty() {
                maps.insert((cob & 0x7FF) as u16, (format!("{kind}{} node {node}", n + 1), entries));
            }
        }
    }
    maps
}

/// Runs the trace until `--count`, `--seconds`, SIGINT/SIGTERM or the bus closes.
pub async fn run(g: &Global, a: &DumpArgs) -> anyhow::Result<()> {
    let ranges = a.ids.iter().map(|s| id_range(s)).collect::<anyhow::Result<Vec<_>>>()?;
    let conn = Conn::open(g).await?;
    let pdos = if !a.pdo {
        PdoMaps::new()
    } else if let (Some(eds), Some(node)) = (&conn.dict.eds, g.node) {
        eds_maps(eds, node)
    } else {
        let nodes: Vec<u8> = match g.node {
            Some(n) => vec![n],
            None => {
                let opts = drivebus_master::ScanOptions { identity: false, ..Default::default() };
                conn.master.scan_with(opts).await.iter().map(|n| n.node).collect()
            }
        };
        read_maps(&conn, &nodes).await
    };
    // From here on: not the answers to the mapping reads above.
    let mut frames = conn.master.subscribe_frames();
    let start = conn.master.now();
    let end = a.seconds.map(|s| crate::error::seconds("--seconds", s)).transpose()?;
    let stop = crate::serve::wait_for_signal();
    tokio::pin!(stop);
    let deadline = async {
        match end {
            Some(d) => tokio::time::sleep(d).await,
            None => std::future::pending().await,
        }
    };
    tokio::pin!(deadline);
    let mut out = std::io::stdout().lock();
    let mut n = 0u64;
    loop {
        if a.count.is_some_and(|c| n >= c) {
            break;
        }
        let f = tokio::select! {
            r = frames.recv() => match r {
                Ok(f) => f,
                Err(broadcast::error::RecvError::Lagged(k)) => {
                    eprintln!("dump: {k} frames lost (output too slow)");
                    continue;
                }
                Err(broadcast::error::RecvError::Closed) => break,
            },
            () = &mut deadline => break,
            _ = &mut stop => break,
        };
        if !ranges.is_empty() && !ranges.iter().any(|r| r.contains(&f.id().raw())) {
            continue;
        }
        if let Some(node) = g.node
            && !of_node(&f, node, &pdos)
        {
            continue;
        }
        n += 1;
        let t = conn.master.now().saturating_duration_since(start).as_secs_f64();
        let line = if a.candump {
            let us = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_micros() as u64);
            let mut s = format!("({}.{:06}) can0 ", us / 1_000_000, us % 1_000_000);
            let _ = candump::write_frame(&mut s, &f);
            s
        } else if g.json {
            serde_json::json!({"t": t, "id": f.id().raw(), "extended": f.id().is_extended(), "rtr": f.is_rtr(),
                "data": crate::sdo_cmd::hex(f.data()), "decoded": decode(&f, &conn.dict, &pdos)})
            .to_string()
        } else {
            let mut raw = String::new();
            let _ = candump::write_frame(&mut raw, &f);
            format!("{t:>10.6}  {raw:<24} {}", decode(&f, &conn.dict, &pdos))
        };
        // A closed pipe (`| head`) ends the trace quietly.
        if writeln!(out, "{line}").and_then(|()| out.flush()).is_err() {
            break;
        }
    }
    drop(out);
    conn.close().await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn id_ranges_and_node_filter() {
        assert_eq!(id_range("181").unwrap(), 0x181..=0x181);
        assert_eq!(id_range("0x180-0x1FF").unwrap(), 0x180..=0x1FF);
        assert!(id_range("0x200-0x100").is_err());
        assert!(id_range("zz").is_err());
        let none = PdoMaps::new();
        assert!(of_node(&Frame::new(0x185, &[1]), 5, &none));
        assert!(of_node(&Frame::new(0x605, &[0x40, 0, 0x10, 0, 0, 0, 0, 0]), 5, &none));
        assert!(of_node(&Frame::new(0x000, &[0x01, 0]), 5, &none));
        assert!(of_node(&Frame::new(0x000, &[0x01, 5]), 5, &none));
        assert!(!of_node(&Frame::new(0x000, &[0x01, 6]), 5, &none));
        assert!(!of_node(&Frame::new(0x186, &[1]), 5, &none));
        assert!(!of_node(&Frame::new(0x080, &[]), 5, &none));
        let mut maps = PdoMaps::new();
        maps.insert(0x1C0, ("TPDO1 node 5".into(), vec![]));
        assert!(of_node(&Frame::new(0x1C0, &[1]), 5, &maps));
    }
}
