//! `drivebus stats`: bus load, frames per second per COB-ID, and the error
//! frames and counters the transport reports, every `--interval`.

use std::time::Duration;

use anyhow::{anyhow, bail};
use drivebus_master::{CanId, Instant};
use drivebus_transport::{BusUrl, LoadMeter, LoadReport};
use tokio::sync::broadcast;

use crate::args::{Global, StatsArgs};
use crate::conn::Conn;
use crate::error::coded;
use crate::output::outln;

/// What a COB-ID is in the pre-defined connection set (CiA 301 §7.3.5).
pub fn cob_name(id: CanId) -> String {
    let CanId::Standard(id) = id else { return "extended".to_owned() };
    let node = id & 0x7F;
    match (id & 0x780, node) {
        (0x000, 0) => "NMT".to_owned(),
        (0x080, 0) => "SYNC".to_owned(),
        (0x080, n) => format!("EMCY node {n}"),
        (0x100, 0) => "TIME".to_owned(),
        (b @ (0x180 | 0x280 | 0x380 | 0x480), n) if n != 0 => {
            format!("TPDO{} node {n}", ((b - 0x180) >> 8) + 1)
        }
        (b @ (0x200 | 0x300 | 0x400 | 0x500), n) if n != 0 => {
            format!("RPDO{} node {n}", ((b - 0x200) >> 8) + 1)
        }
        (0x580, n) if n != 0 => format!("SDO node {n} → master"),
        (0x600, n) if n != 0 => format!("SDO master → node {n}"),
        (0x700, n) if n != 0 => format!("heartbeat node {n}"),
        _ if (0x7E4..=0x7E5).contains(&id) => "LSS".to_owned(),
        _ => String::new(),
    }
}

/// One report as text: the totals, then the busiest `top` COB-IDs.
fn text(
    r: &LoadReport,
    bitrate: Option<u32>,
    errors: &Option<drivebus_transport::BusErrors>,
    top: usize,
) -> String {
    let load = match (r.load, bitrate) {
        (Some(l), Some(b)) => format!("load {:.1} % of {} kbit/s", l * 100.0, b / 1000),
        _ => "load unknown (give --bitrate)".to_owned(),
    };
    let errors = match errors {
        None => "error frames: not reported by this transport".to_owned(),
        Some(e) => {
            let counters = match (e.tx_errors, e.rx_errors) {
                (Some(t), Some(r)) => format!(", TX/RX error counters {t}/{r}"),
                _ => String::new(),
            };
            let last =
                if e.last.is_empty() { String::new() } else { format!(", last: {}", e.last.join(", ")) };
            format!("error frames {}, bus-off {}{counters}{last}", e.error_frames, e.bus_off)
        }
    };
    let mut s = format!(
        "{:.1} s: {} frames ({:.1}/s), {:.1} kbit/s, {load}; {errors}",
        r.seconds,
        r.frames,
        r.per_second,
        r.bits_per_second / 1000.0
    );
    let mut ids = r.per_id.clone();
    ids.sort_by(|a, b| b.frames.cmp(&a.frames).then(a.id.cmp(&b.id)));
    for i in ids.iter().take(top) {
        let id = match i.id {
            CanId::Standard(v) => format!("{v:03X}"),
            CanId::Extended(v) => format!("{v:08X}"),
        };
        s += &format!("\n  {id:<8} {:>9.1}/s  {:>6} frames  {}", i.per_second, i.frames, cob_name(i.id));
    }
    s
}

fn json(r: &LoadReport, errors: &Option<drivebus_transport::BusErrors>, top: usize) -> serde_json::Value {
    let mut ids = r.per_id.clone();
    ids.sort_by(|a, b| b.frames.cmp(&a.frames).then(a.id.cmp(&b.id)));
    let per_id: Vec<_> = ids
        .iter()
        .take(top)
        .map(|i| {
            serde_json::json!({"id": i.id.raw(), "extended": i.id.is_extended(), "frames": i.frames,
                "per_second": i.per_second, "bits": i.bits, "what": cob_name(i.id)})
        })
        .collect();
    let errors = errors.as_ref().map(|e| {
        serde_json::json!({"error_frames": e.error_frames, "bus_off": e.bus_off, "tx_errors": e.tx_errors,
            "rx_errors": e.rx_errors, "last": e.last})
    });
    serde_json::json!({"seconds": r.seconds, "frames": r.frames, "per_second": r.per_second, "bits": r.bits,
        "bits_per_second": r.bits_per_second, "load": r.load, "errors": errors, "per_id": per_id})
}

/// Runs until `--seconds`, Ctrl-C or the bus closes; a report every `--interval`.
pub async fn run(g: &Global, a: &StatsArgs) -> anyhow::Result<()> {
    if !(0.05..=86_400.0).contains(&a.interval) {
        bail!(coded("usage", anyhow!("--interval {}: give seconds from 0.05 to a day", a.interval)));
    }
    let bitrate = a.bitrate.or_else(|| match BusUrl::parse(&g.bus) {
        Ok(BusUrl::Slcan { bitrate, .. }) => bitrate,
        _ => None,
    });
    let end = a.seconds.map(|s| crate::error::seconds("--seconds", s)).transpose()?;
    let conn = Conn::open(g).await?;
    let m = &conn.master;
    let mut frames = m.subscribe_frames();
    let mut meter = LoadMeter::new(m.now());
    let mut tick = tokio::time::interval(Duration::from_secs_f64(a.interval));
    tick.tick().await;
    let stop = crate::serve::wait_for_signal();
    tokio::pin!(stop);
    let end = end.map(|d| tokio::time::Instant::now() + d);
    let report = |meter: &LoadMeter, now: Instant| {
        let r = meter.report(now, bitrate);
        let errors = m.bus_errors();
        if g.json {
            outln!("{}", json(&r, &errors, a.top));
        } else {
            outln!("{}", text(&r, bitrate, &errors, a.top));
        }
    };
    loop {
        tokio::select! {
            f = frames.recv() => match f {
                Ok(f) => meter.record(&f, m.now()),
                Err(broadcast::error::RecvError::Lagged(k)) => eprintln!("stats: {k} frames not counted (too slow)"),
                Err(broadcast::error::RecvError::Closed) => break,
            },
            _ = tick.tick() => {
                let now = m.now();
                report(&meter, now);
                meter.reset(now);
            }
            () = async { match end { Some(t) => tokio::time::sleep_until(t).await, None => std::future::pending().await } } => {
                // The last, partial interval.
                if meter.report(m.now(), None).frames > 0 {
                    report(&meter, m.now());
                }
                break;
            }
            _ = &mut stop => break,
        }
    }
    drop(frames);
    conn.close().await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cob_ids_named() {
        let n = |id: u16| cob_name(CanId::Standard(id));
        assert_eq!(n(0x000), "NMT");
        assert_eq!(n(0x080), "SYNC");
        assert_eq!(n(0x085), "EMCY node 5");
        assert_eq!(n(0x100), "TIME");
        assert_eq!(n(0x181), "TPDO1 node 1");
        assert_eq!(n(0x4FF), "TPDO4 node 127");
        assert_eq!(n(0x202), "RPDO1 node 2");
        assert_eq!(n(0x505), "RPDO4 node 5");
        assert_eq!(n(0x585), "SDO node 5 → master");
        assert_eq!(n(0x605), "SDO master → node 5");
        assert_eq!(n(0x705), "heartbeat node 5");
        assert_eq!(n(0x7E5), "LSS");
        assert_eq!(n(0x180), "");
    }
}
