//! `drivebus dump`: a live decoded trace, candump log lines, CSV of the
//! PDOs or a pcapng capture; filters by node, CAN-ID range and candump
//! filter; PDOs decoded by the mapping read from the devices (or from the
//! EDS).

use std::collections::HashMap;
use std::io::Write;
use std::ops::RangeInclusive;
use std::time::{SystemTime, UNIX_EPOCH};

use anyhow::{Context, anyhow, bail};
use drivebus_can::pcap::{Capture, Direction, LinkType};
use drivebus_master::{Frame, PdoDir, PdoMapEntry, candump};
use tokio::sync::broadcast;

use crate::args::{DumpArgs, Global, TimestampMode};
use crate::canfilter::Filters;
use crate::conn::Conn;
use crate::decode::{PdoMaps, decode, pdo_columns, pdo_numbers};
use crate::error::coded;
use crate::output::outln;

/// Parses `0x181`, `181`, `0x180-0x1FF` (CAN-IDs are hex).
pub fn id_range(s: &str) -> anyhow::Result<RangeInclusive<u32>> {
    let one = |t: &str| {
        crate::dict::hex(t).filter(|v| *v <= 0x1FFF_FFFF).ok_or_else(|| {
            coded("usage", anyhow!("bad CAN-ID range `{s}`: CAN-IDs are hex, e.g. 181, 0x181 or 0x180-0x1FF"))
        })
    };
    let (lo, hi) = match s.split_once('-') {
        Some((a, b)) => (one(a)?, one(b)?),
        None => (one(s)?, one(s)?),
    };
    if lo > hi {
        return Err(coded("usage", anyhow!("bad CAN-ID range `{s}`: {lo:X} is above {hi:X}")));
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

/// Line times per `-t` (candump's zero, delta and absolute).
struct Stamps {
    mode: TimestampMode,
    first: Option<f64>,
    prev: Option<f64>,
}

impl Stamps {
    /// The stamp of a frame received at `t` seconds (master time) and
    /// `unix` seconds (Unix time).
    fn stamp(&mut self, t: f64, unix: f64) -> f64 {
        let first = *self.first.get_or_insert(t);
        let prev = self.prev.replace(t).unwrap_or(t);
        match self.mode {
            TimestampMode::Zero => t - first,
            TimestampMode::Delta => t - prev,
            TimestampMode::Absolute => unix,
        }
    }
}

fn unix_now() -> std::time::Duration {
    SystemTime::now().duration_since(UNIX_EPOCH).unwrap_or_default()
}

/// The CSV columns of `dump --pdo --csv`: every mapped object of every
/// PDO, in COB-ID order; the offset of each PDO's first column.
fn csv_layout(pdos: &PdoMaps, dict: &crate::dict::Dict) -> (Vec<String>, HashMap<u16, usize>) {
    let mut ids: Vec<&u16> = pdos.keys().collect();
    ids.sort();
    let mut header = vec!["time_s".to_owned(), "cob_id".to_owned(), "pdo".to_owned()];
    let mut at = HashMap::new();
    for id in ids {
        at.insert(*id, header.len());
        header.extend(pdo_columns(dict, &pdos[id]));
    }
    (header, at)
}

/// The pcapng writer of `--pcap FILE` (`-`: stdout), if asked for.
fn open_capture(
    g: &Global,
    a: &DumpArgs,
    to_stdout: bool,
) -> anyhow::Result<Option<Capture<Box<dyn Write + Send>>>> {
    Ok(match &a.pcap {
        None => None,
        Some(p) => {
            let w: Box<dyn Write + Send> = if to_stdout {
                Box::new(std::io::stdout())
            } else {
                Box::new(std::io::BufWriter::new(
                    std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
                ))
            };
            let iface = match drivebus_transport::BusUrl::parse(&g.bus) {
                Ok(drivebus_transport::BusUrl::Socketcand { channel, .. }) => channel,
                Ok(drivebus_transport::BusUrl::SocketCan { interface }) => interface,
                _ => "can0".to_owned(),
            };
            Some(Capture::new(w, &iface, LinkType::SocketCan).context("writing the pcapng header")?)
        }
    })
}

/// The PDO mappings `--pdo` decodes with: the EDS's for `--node` when one
/// is given, else read from the node (or from every node a scan finds).
async fn pdo_maps(g: &Global, conn: &Conn) -> PdoMaps {
    if let (Some(eds), Some(node)) = (&conn.dict.eds, g.node) {
        eds_maps(eds, node)
    } else {
        let nodes: Vec<u8> = match g.node {
            Some(n) => vec![n],
            None => {
                let opts = drivebus_master::ScanOptions { identity: false, ..Default::default() };
                conn.master.scan_with(opts).await.iter().map(|n| n.node).collect()
            }
        };
        read_maps(conn, &nodes).await
    }
}

/// One output line of a frame: candump -l, a CSV row of a PDO, JSON, or
/// the decoded trace line.
#[allow(clippy::too_many_arguments)]
fn format_line(
    a: &DumpArgs,
    json: bool,
    f: &Frame,
    t: f64,
    unix: std::time::Duration,
    mode: TimestampMode,
    pdo: Option<(u16, &(String, Vec<PdoMapEntry>))>,
    (header, columns): &(Vec<String>, HashMap<u16, usize>),
    dict: &crate::dict::Dict,
    pdos: &PdoMaps,
) -> String {
    if a.candump {
        let us = unix.as_micros() as u64;
        let mut s = format!("({}.{:06}) can0 ", us / 1_000_000, us % 1_000_000);
        let _ = candump::write_frame(&mut s, f);
        s
    } else if let (true, Some((id, (label, mapping)))) = (a.csv, pdo) {
        let mut row = vec![String::new(); header.len()];
        row[0] = format!("{t:.6}");
        row[1] = format!("{id:03X}");
        row[2] = label.clone();
        for (k, v) in pdo_numbers(f, dict, mapping).into_iter().enumerate() {
            row[columns[&id] + k] = v.unwrap_or_default();
        }
        crate::csv::line(&row)
    } else if json {
        serde_json::json!({"t": t, "id": f.id().raw(), "extended": f.id().is_extended(), "rtr": f.is_rtr(),
            "data": crate::sdo_cmd::hex(f.data()), "decoded": decode(f, dict, pdos)})
        .to_string()
    } else {
        let mut raw = String::new();
        let _ = candump::write_frame(&mut raw, f);
        let t = if mode == TimestampMode::Absolute { format!("{t:>17.6}") } else { format!("{t:>10.6}") };
        format!("{t}  {raw:<24} {}", decode(f, dict, pdos))
    }
}

/// Runs the trace until `--count`, `--seconds`, SIGINT/SIGTERM or the bus closes.
pub async fn run(g: &Global, a: &DumpArgs) -> anyhow::Result<()> {
    let ranges = a.ids.iter().map(|s| id_range(s)).collect::<anyhow::Result<Vec<_>>>()?;
    let filters = Filters::parse(&a.filters)?;
    if a.candump && a.timestamp.is_some_and(|m| m != TimestampMode::Absolute) {
        bail!(coded(
            "usage",
            anyhow!("--candump lines carry absolute times (candump -l; `replay` reads them): leave -t out")
        ));
    }
    let to_stdout = a.pcap.as_deref().is_some_and(|p| p.as_os_str() == "-");
    if to_stdout && (a.candump || a.csv || g.json) {
        bail!(coded(
            "usage",
            anyhow!("--pcap - writes the capture to stdout: no --candump, --csv or --json with it")
        ));
    }
    let mut capture = open_capture(g, a, to_stdout)?;
    let mut stamps = Stamps {
        mode: a.timestamp.unwrap_or(if a.candump { TimestampMode::Absolute } else { TimestampMode::Zero }),
        first: None,
        prev: None,
    };
    let conn = Conn::open(g).await?;
    if !conn.master.carries_rtr() && !g.json {
        eprintln!(
            "dump: this transport (socketcand) carries no remote (RTR) frames: node-guarding requests and other RTR frames on the bus are not shown"
        );
    }
    let pdos = if a.pdo { pdo_maps(g, &conn).await } else { PdoMaps::new() };
    let layout = csv_layout(&pdos, &conn.dict);
    let (header, _) = &layout;
    if a.csv {
        if pdos.is_empty() {
            bail!(coded(
                "no_pdo",
                anyhow!("--csv: no valid PDO mapping found to make columns of (are the nodes there?)")
            ));
        }
        outln!("{}", crate::csv::line(header));
    }
    // From here on: not the answers to the mapping reads above.
    let mut frames = conn.master.subscribe_frames();
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
        if !filters.pass(&f) {
            continue;
        }
        if let Some(node) = g.node
            && !of_node(&f, node, &pdos)
        {
            continue;
        }
        let pdo = f.std_id().and_then(|id| pdos.get(&id).map(|p| (id, p)));
        if a.csv && pdo.is_none() {
            continue;
        }
        n += 1;
        let unix = unix_now();
        let t = stamps.stamp(conn.master.now().as_nanos() as f64 / 1e9, unix.as_secs_f64());
        if let Some(c) = &mut capture {
            c.write_can(&f, unix.as_nanos() as u64, Direction::Inbound).context("writing --pcap")?;
            if to_stdout {
                c.flush().context("writing --pcap")?;
                continue;
            }
        }
        let line = format_line(a, g.json, &f, t, unix, stamps.mode, pdo, &layout, &conn.dict, &pdos);
        // A closed pipe (`| head`) ends the trace quietly.
        if writeln!(out, "{line}").and_then(|()| out.flush()).is_err() {
            break;
        }
    }
    drop(out);
    if let Some(c) = &mut capture {
        c.flush().context("writing --pcap")?;
    }
    conn.close().await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timestamp_modes() {
        let mut z = Stamps { mode: TimestampMode::Zero, first: None, prev: None };
        let mut d = Stamps { mode: TimestampMode::Delta, first: None, prev: None };
        let mut a = Stamps { mode: TimestampMode::Absolute, first: None, prev: None };
        let got: Vec<_> = [(5.0, 100.0), (5.25, 100.25), (6.0, 101.0)]
            .iter()
            .map(|&(t, u)| (z.stamp(t, u), d.stamp(t, u), a.stamp(t, u)))
            .collect();
        assert_eq!(got, [(0.0, 0.0, 100.0), (0.25, 0.25, 100.25), (1.0, 0.75, 101.0)]);
    }

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
