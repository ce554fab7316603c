//! `drivebus monitor`: the nodes on the bus in a live table: NMT state
//! from heartbeats (and boot-ups, guarding answers), the last EMCY with
//! its text, and chosen values, from the node's TPDOs when mapped there,
//! else by SDO every `--period`.

use std::collections::{BTreeMap, HashMap};
use std::io::{IsTerminal, Write};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use drivebus_master::{DataType, DriveState, MasterEvent, PdoCallback, PdoDir, RemoteState, Value};
use tokio::sync::broadcast;

use crate::args::{Global, MonitorArgs};
use crate::conn::Conn;
use crate::output::outln;

/// One watched object.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Watch {
    index: u16,
    sub: u8,
}

#[derive(Default, Clone, PartialEq)]
struct Row {
    state: Option<String>,
    emcy: Option<String>,
    values: BTreeMap<usize, String>,
    /// The same values as plain numbers (CSV).
    numbers: BTreeMap<usize, String>,
}

type Latest = Arc<Mutex<HashMap<(u8, usize), Vec<u8>>>>;

fn state_name(s: RemoteState) -> &'static str {
    match s {
        RemoteState::BootUp => "boot-up",
        RemoteState::Stopped => "stopped",
        RemoteState::Operational => "operational",
        RemoteState::PreOperational => "pre-operational",
        _ => "unknown",
    }
}

/// A value as a plain number (a spreadsheet cell), hex bytes for non-numbers.
fn plain_value(dt: Option<DataType>, data: &[u8]) -> String {
    match dt.and_then(|t| Value::decode(t, data).ok()) {
        Some(v) if v.as_i128().is_some() || matches!(v, Value::F32(_) | Value::F64(_)) => v.to_string(),
        _ => crate::sdo_cmd::hex(data),
    }
}

/// The `monitor --csv` header.
fn csv_header(labels: &[String]) -> String {
    let fixed = ["time_s", "node", "state", "emcy"].map(String::from);
    crate::csv::line(fixed.iter().chain(labels))
}

/// One `monitor --csv` row: `t` seconds since the start.
fn csv_row(t: f64, node: u8, row: &Row, n: usize) -> String {
    let mut cells = vec![
        format!("{t:.3}"),
        node.to_string(),
        row.state.clone().unwrap_or_default(),
        row.emcy.clone().unwrap_or_default(),
    ];
    cells.extend((0..n).map(|k| row.numbers.get(&k).cloned().unwrap_or_default()));
    crate::csv::line(&cells)
}

fn format_value(w: Watch, dt: Option<DataType>, data: &[u8]) -> String {
    match dt.and_then(|t| Value::decode(t, data).ok()) {
        Some(Value::U16(sw)) if w.index == 0x6041 => {
            format!("{sw:04X}h {}", DriveState::from_statusword(sw).name())
        }
        Some(v) => v.to_string(),
        None => crate::sdo_cmd::hex(data),
    }
}

/// A watched object's column title: its entry name, else `INDEXh:SUB`.
fn label(conn: &Conn, w: &Watch) -> String {
    let n = conn.dict.name(w.index, w.sub).unwrap_or_else(|| format!("{:04X}h:{:02X}", w.index, w.sub));
    n.rsplit(" / ").next().unwrap_or(&n).to_owned()
}

/// What an event changes in its node's row.
enum Change {
    State(String),
    Emcy(String),
    Nothing,
}

/// The node an event is about and what it changes in its row; a bus
/// error ends the monitor (its reason).
fn row_change(e: MasterEvent) -> Result<(u8, Change), String> {
    Ok(match e {
        MasterEvent::Bootup { node } => (node, Change::State("boot-up".to_owned())),
        MasterEvent::Heartbeat { node, state } => (node, Change::State(state_name(state).to_owned())),
        MasterEvent::HeartbeatLost { node } => (node, Change::State("lost (no heartbeat)".to_owned())),
        MasterEvent::Emcy { node, code, register, text, .. } => {
            let text = text.as_deref().unwrap_or("manufacturer specific");
            (node, Change::Emcy(format!("{code:04X}h {text} (register {register:02X}h)")))
        }
        MasterEvent::BusError { reason } => return Err(reason),
        MasterEvent::HeartbeatRecovered { node } => (node, Change::Nothing),
    })
}

/// Reads `node`'s watched objects into its row: the TPDO copy while the
/// node sends it (`from_pdo`: the watches in its TPDOs), by SDO otherwise
/// (pre-operational, or nothing received yet).
async fn sample(
    conn: &Conn,
    node: u8,
    row: &mut Row,
    watches: &[Watch],
    from_pdo: Option<&Vec<usize>>,
    latest: &Latest,
) {
    let m = &conn.master;
    let operational = m.node_state(node) == Some(RemoteState::Operational);
    for (k, w) in watches.iter().enumerate() {
        let cached = (operational && from_pdo.is_some_and(|v| v.contains(&k)))
            .then(|| latest.lock().unwrap_or_else(|e| e.into_inner()).get(&(node, k)).cloned())
            .flatten();
        let data = match cached {
            Some(d) => Some(d),
            None => m.sdo(node).upload(w.index, w.sub).await.ok(),
        };
        if let Some(d) = data {
            let dt = conn.dict.data_type(w.index, w.sub);
            row.values.insert(k, format_value(*w, dt, &d));
            row.numbers.insert(k, plain_value(dt, &d));
        }
    }
}

/// Runs until `--seconds`, Ctrl-C or the bus closes.
pub async fn run(g: &Global, a: &MonitorArgs) -> anyhow::Result<()> {
    let conn = Conn::open(g).await?;
    let watches = a
        .watch
        .iter()
        .map(|w| Ok(conn.dict.resolve(w, None).map(|(index, sub)| Watch { index, sub: sub.unwrap_or(0) })?))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let labels: Vec<String> = watches.iter().map(|w| label(&conn, w)).collect();
    let m = &conn.master;
    let mut events = m.subscribe_events();
    let mut rows: BTreeMap<u8, Row> = BTreeMap::new();
    let wanted = |n: u8| g.node.is_none_or(|w| w == n);
    if let Some(n) = g.node {
        rows.insert(n, Row::default());
    }
    if a.scan {
        let opts = drivebus_master::ScanOptions { identity: false, ..Default::default() };
        for n in m.scan_with(opts).await.iter().map(|n| n.node).filter(|&n| wanted(n)) {
            rows.entry(n).or_default();
        }
    }
    // Watched objects found in a node's TPDOs come from there.
    let latest: Latest = Arc::default();
    let mut by_pdo: HashMap<u8, Vec<usize>> = HashMap::new();
    let mut callbacks: Vec<PdoCallback> = Vec::new();
    let nodes: Vec<u8> = rows.keys().copied().collect();
    for n in nodes {
        let (ks, cbs) = mapped(m, n, &watches, &latest).await;
        by_pdo.insert(n, ks);
        callbacks.extend(cbs);
    }
    let tty = std::io::stdout().is_terminal() && !g.json && !a.csv;
    if a.csv && g.json {
        anyhow::bail!(crate::error::coded("usage", anyhow::anyhow!("--csv and --json: choose one")));
    }
    let t0 = tokio::time::Instant::now();
    if a.csv {
        outln!("{}", csv_header(&labels));
    }
    let end = a.seconds.map(|s| crate::error::seconds("--seconds", s)).transpose()?;
    let end = end.map(|d| tokio::time::Instant::now() + d);
    let stop = crate::serve::wait_for_signal();
    tokio::pin!(stop);
    let mut tick = tokio::time::interval(Duration::from_millis(a.period.clamp(20, 3_600_000)));
    let mut shown: BTreeMap<u8, Row> = BTreeMap::new();
    loop {
        tokio::select! {
            e = events.recv() => match e {
                Ok(e) => {
                    let (node, change) = match row_change(e) {
                        Ok(c) => c,
                        Err(reason) => return Err(conn.lost(&reason)),
                    };
                    if !wanted(node) {
                        continue;
                    }
                    if let std::collections::btree_map::Entry::Vacant(v) = rows.entry(node) {
                        v.insert(Row::default());
                        let (ks, cbs) = mapped(m, node, &watches, &latest).await;
                        by_pdo.insert(node, ks);
                        callbacks.extend(cbs);
                    }
                    let row = rows.entry(node).or_default();
                    match change {
                        Change::State(s) => row.state = Some(s),
                        Change::Emcy(e) => row.emcy = Some(e),
                        Change::Nothing => {}
                    }
                }
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => break,
            },
            _ = tick.tick() => {
                for (&node, row) in rows.iter_mut() {
                    sample(&conn, node, row, &watches, by_pdo.get(&node), &latest).await;
                }
                if tty {
                    draw(&rows, &labels);
                }
            }
            () = async { match end { Some(t) => tokio::time::sleep_until(t).await, None => std::future::pending().await } } => break,
            _ = &mut stop => break,
        }
        if !tty {
            for (node, row) in &rows {
                if shown.get(node) != Some(row) {
                    if a.csv {
                        outln!("{}", csv_row(t0.elapsed().as_secs_f64(), *node, row, labels.len()));
                    } else {
                        print_change(g.json, *node, row, shown.get(node), &labels);
                    }
                    shown.insert(*node, row.clone());
                }
            }
        }
    }
    drop(callbacks);
    conn.close().await
}

/// The watched objects `node` sends in its TPDOs 1..4, decoded into
/// `latest` as they arrive: (their positions in `watches`, the callbacks).
async fn mapped(
    m: &drivebus_master::Master,
    node: u8,
    watches: &[Watch],
    latest: &Latest,
) -> (Vec<usize>, Vec<PdoCallback>) {
    let mut ks = Vec::new();
    let mut cbs = Vec::new();
    for num in 1..=4u16 {
        let Ok(rec) = m.read_pdo(node, PdoDir::Tx, num).await else { break };
        if !rec.valid() {
            continue;
        }
        let mut hits = Vec::new();
        for place in drivebus_master::pdo_layout(rec.mapping.iter().copied()) {
            if let Some(k) = watches.iter().position(|w| place.is(w.index, w.sub))
                && let Some((at, len)) = place.bytes()
            {
                hits.push((k, at, len));
            }
        }
        if hits.is_empty() {
            continue;
        }
        ks.extend(hits.iter().map(|h| h.0));
        let l = latest.clone();
        cbs.push(m.on_pdo(rec.can_id(), move |f, _| {
            let mut l = l.lock().unwrap_or_else(|e| e.into_inner());
            for &(k, off, len) in &hits {
                if let Some(b) = f.data().get(off..off + len) {
                    l.insert((node, k), b.to_vec());
                }
            }
        }));
    }
    (ks, cbs)
}

fn draw(rows: &BTreeMap<u8, Row>, labels: &[String]) {
    let mut o = std::io::stdout().lock();
    let mut s = String::from("\x1b[H\x1b[2J");
    s += &format!("{:<5} {:<22} {:<40}", "node", "NMT state", "last EMCY");
    for l in labels {
        s += &format!(" {l:<24}");
    }
    s.push('\n');
    for (node, r) in rows {
        s += &format!(
            "{node:<5} {:<22} {:<40}",
            r.state.as_deref().unwrap_or("-"),
            r.emcy.as_deref().unwrap_or("-")
        );
        for k in 0..labels.len() {
            s += &format!(" {:<24}", r.values.get(&k).map_or("-", String::as_str));
        }
        s.push('\n');
    }
    if o.write_all(s.as_bytes()).and_then(|()| o.flush()).is_err() {
        std::process::exit(0);
    }
}

fn print_change(json: bool, node: u8, row: &Row, before: Option<&Row>, labels: &[String]) {
    if json {
        let values: serde_json::Map<String, serde_json::Value> =
            row.values.iter().map(|(k, v)| (labels[*k].clone(), v.clone().into())).collect();
        outln!(
            "{}",
            serde_json::json!({"node": node, "state": row.state, "emcy": row.emcy, "values": values})
        );
        return;
    }
    let mut parts = Vec::new();
    if before.is_none_or(|b| b.state != row.state)
        && let Some(s) = &row.state
    {
        parts.push(format!("state {s}"));
    }
    if before.is_none_or(|b| b.emcy != row.emcy)
        && let Some(e) = &row.emcy
    {
        parts.push(format!("EMCY {e}"));
    }
    for (k, v) in &row.values {
        if before.is_none_or(|b| b.values.get(k) != Some(v)) {
            parts.push(format!("{} {v}", labels[*k]));
        }
    }
    if !parts.is_empty() {
        outln!("node {node}: {}", parts.join(", "));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_rows_hold_numbers() {
        let labels = vec!["Statusword".to_owned(), "Position actual value".to_owned()];
        assert_eq!(csv_header(&labels), "time_s,node,state,emcy,Statusword,Position actual value");
        let mut row = Row { state: Some("operational".into()), ..Row::default() };
        row.numbers.insert(0, plain_value(Some(DataType::Unsigned16), &[0x37, 0x02]));
        row.numbers.insert(1, plain_value(Some(DataType::Integer32), &[0xFE, 0xFF, 0xFF, 0xFF]));
        assert_eq!(csv_row(1.5, 3, &row, 2), "1.500,3,operational,,567,-2");
        row.emcy = Some("8611h Following error, too high (register 80h)".into());
        assert!(csv_row(2.0, 3, &row, 2).contains(",\"8611h Following error, too high (register 80h)\","));
    }
}
