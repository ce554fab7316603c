//! `drivebus send` (cansend syntax) and `drivebus replay` (canplayer):
//! raw frames through the master, written by the transport before the
//! command reports.

use std::time::Duration;

use anyhow::{Context, anyhow, bail};
use drivebus_master::{Frame, candump};

use crate::args::{Global, ReplayArgs, SendArgs};
use crate::conn::Conn;
use crate::error::coded;
use crate::output::outln;

/// Parses one cansend frame, the error naming the argument and the column.
fn frame(text: &str) -> anyhow::Result<Frame> {
    candump::parse_frame(text.trim()).map_err(|e| {
        coded(
            "usage",
            anyhow!(
                "bad frame `{text}` at column {}: {:?}; write ID#DATA (601#40.00.10.00), ID#R[LEN] or an 8-digit extended ID",
                e.column,
                e.kind
            ),
        )
    })
}

/// `drivebus send FRAME...`.
pub async fn send(g: &Global, a: &SendArgs) -> anyhow::Result<()> {
    let frames = a.frames.iter().map(|s| frame(s)).collect::<anyhow::Result<Vec<_>>>()?;
    let conn = Conn::open(g).await?;
    let cyclic = match a.period {
        Some(ms) => Some(crate::cyclic::send_cyclic(&conn, &frames, ms, a.count).await?),
        None => {
            for f in &frames {
                conn.master.send(*f).await.with_context(|| format!("sending {f}"))?;
            }
            None
        }
    };
    conn.close().await?;
    let text: Vec<String> = frames
        .iter()
        .map(|f| {
            let mut s = String::new();
            let _ = candump::write_frame(&mut s, f);
            s
        })
        .collect();
    if let (Some(c), Some(ms)) = (cyclic, a.period) {
        crate::output::emit(
            g.json,
            serde_json::json!({"sent": text, "rounds": c.rounds, "period_ms": ms, "late": c.late}),
            || {
                let late = if c.late > 0 {
                    format!(" ({} late by a period or more)", c.late)
                } else {
                    String::new()
                };
                format!(
                    "sent {} frame(s) {} time(s) every {ms} ms{late}: {}",
                    text.len(),
                    c.rounds,
                    text.join(" ")
                )
            },
        );
        return Ok(());
    }
    crate::output::emit(g.json, serde_json::json!({"sent": text}), || {
        format!("sent {} frame(s): {}", text.len(), text.join(" "))
    });
    Ok(())
}

/// The frames of a log with their times (µs since the log's first frame).
fn load(a: &ReplayArgs) -> anyhow::Result<Vec<(u64, Frame)>> {
    let Some(path) = a.file.as_ref().or(a.input.as_ref()) else {
        bail!(coded("usage", anyhow!("give the log FILE (or -I FILE)")));
    };
    let text = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let text = String::from_utf8_lossy(&text);
    let mut out = Vec::new();
    let mut first = None;
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let rec = candump::parse_line(line).map_err(|e| {
            coded(
                "bad_log",
                anyhow!("{}:{}:{}: {:?}: `{}`", path.display(), i + 1, e.column, e.kind, line.trim()),
            )
        })?;
        if a.interface.as_ref().is_some_and(|want| *want != rec.interface) {
            continue;
        }
        let t = rec.timestamp_us();
        let t0 = *first.get_or_insert(t);
        out.push((t.saturating_sub(t0), rec.frame));
    }
    Ok(out)
}

/// `drivebus replay`: the log's frames with their gaps (or --gap), --loop times.
pub async fn run(g: &Global, a: &ReplayArgs) -> anyhow::Result<()> {
    let frames = load(a)?;
    let loops: Option<u64> =
        match a.loops.as_str() {
            "i" => None,
            n => Some(n.parse().ok().filter(|&n| n > 0).ok_or_else(|| {
                coded("usage", anyhow!("bad --loop `{n}`: a count (1, 2, ...) or i for ever"))
            })?),
        };
    let gap = crate::error::seconds("--gap", a.gap / 1000.0)?;
    let skip_gaps = a.skip_gaps.map(|s| crate::error::seconds("--skip-gaps", s)).transpose()?;
    let conn = Conn::open(g).await?;
    let m = &conn.master;
    let stop = crate::serve::wait_for_signal();
    tokio::pin!(stop);
    let mut sent = 0u64;
    let mut round = 0u64;
    'outer: while loops.is_none_or(|n| round < n) {
        round += 1;
        let start = tokio::time::Instant::now();
        let mut skipped = Duration::ZERO;
        let mut prev = 0u64;
        for (k, (t, f)) in frames.iter().enumerate() {
            let wait_until = if a.ignore_timestamps {
                start + gap.saturating_mul(u32::try_from(k).unwrap_or(u32::MAX))
            } else {
                // A log whose time goes backwards sends at once.
                let gap = Duration::from_micros(t.saturating_sub(prev));
                if let Some(max) = skip_gaps
                    && gap > max
                {
                    skipped += gap - max;
                }
                let Some(at) = start.checked_add(Duration::from_micros(*t)) else {
                    bail!(coded("bad_log", anyhow!("the log spans more time than can be replayed")));
                };
                at.checked_sub(skipped).unwrap_or(start)
            };
            prev = *t;
            tokio::select! {
                () = tokio::time::sleep_until(wait_until) => {}
                _ = &mut stop => break 'outer,
            }
            m.send(*f).await.with_context(|| format!("sending {f}"))?;
            sent += 1;
            if a.verbose && !g.json {
                let mut s = String::new();
                let _ = candump::write_frame(&mut s, f);
                outln!("{s}");
            }
        }
    }
    conn.close().await?;
    crate::output::emit(
        g.json,
        serde_json::json!({"sent": sent, "rounds": round, "frames_in_log": frames.len()}),
        || format!("replayed {sent} frame(s) ({} in the log, {round} round(s))", frames.len()),
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cansend_syntax_and_errors() {
        assert_eq!(frame("601#40.00.10.00").unwrap(), Frame::new(0x601, &[0x40, 0, 0x10, 0]));
        assert_eq!(frame("080#").unwrap(), Frame::new(0x080, &[]));
        assert!(frame("701#R1").unwrap().is_rtr());
        assert!(frame("18FF50E5#0102").unwrap().id().is_extended());
        for bad in ["", "601", "6011#00", "601#0", "601#000102030405060708", "601##0", "ZZZ#00"] {
            let e = frame(bad).unwrap_err().to_string();
            assert!(e.contains("bad frame"), "{bad}: {e}");
        }
    }

    proptest::proptest! {
        /// Malformed cansend text is an error naming the column, never a panic.
        #[test]
        fn any_frame_text_parses_or_errs(text in "[0-9A-Fa-f#R.xX ]{0,40}|\\PC{0,40}") {
            let _ = frame(&text);
        }
    }
}
