//! Traffic the tool makes on its own schedule: `send --period` (cyclic
//! transmit), `produce` (the master's SYNC, heartbeat and TIME
//! producers) and `gen` (a load generator like cangen).

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use anyhow::{Context, anyhow, bail};
use drivebus_bus::XorShift64;
use drivebus_master::{CanId, Frame, RemoteState, candump};
use tokio::time::{Instant, MissedTickBehavior};

use crate::args::{GenArgs, Global, ProduceArgs};
use crate::conn::Conn;
use crate::error::coded;
use crate::output::outln;

/// A period in milliseconds as a `Duration` (0.05 ms .. a day).
fn period(option: &str, ms: f64) -> anyhow::Result<Duration> {
    if !(0.05..=86_400_000.0).contains(&ms) {
        bail!(coded("usage", anyhow!("{option} {ms}: give milliseconds from 0.05 to a day")));
    }
    Ok(Duration::from_secs_f64(ms / 1000.0))
}

/// Resolves when `--seconds` passed, or never.
async fn until(end: Option<Instant>) {
    match end {
        Some(t) => tokio::time::sleep_until(t).await,
        None => std::future::pending().await,
    }
}

fn end_of(seconds: Option<f64>) -> anyhow::Result<Option<Instant>> {
    Ok(seconds.map(|s| crate::error::seconds("--seconds", s)).transpose()?.map(|d| Instant::now() + d))
}

/// What a cyclic `send` did.
pub struct CyclicSendReport {
    /// Rounds sent.
    pub rounds: u64,
    /// Rounds that started a whole period or more late (skipped ticks).
    pub late: u64,
}

/// `send --period`: `frames` every `period_ms`, `count` times or until Ctrl-C.
pub async fn send_cyclic(
    conn: &Conn,
    frames: &[Frame],
    period_ms: f64,
    count: Option<u64>,
) -> anyhow::Result<CyclicSendReport> {
    let every = period("--period", period_ms)?;
    let mut tick = tokio::time::interval(every);
    // A round that cannot keep the period is counted, not sent in a burst.
    tick.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let stop = crate::serve::wait_for_signal();
    tokio::pin!(stop);
    let mut c = CyclicSendReport { rounds: 0, late: 0 };
    let mut expected = Instant::now();
    while count.is_none_or(|n| c.rounds < n) {
        tokio::select! {
            at = tick.tick() => {
                if at >= expected + every {
                    c.late += 1;
                }
                expected = at + every;
            }
            _ = &mut stop => break,
        }
        for f in frames {
            conn.master.send(*f).await.with_context(|| format!("sending {f}"))?;
        }
        c.rounds += 1;
    }
    Ok(c)
}

/// `drivebus produce`.
pub async fn produce(g: &Global, a: &ProduceArgs) -> anyhow::Result<()> {
    if a.sync.is_none() && a.heartbeat.is_none() && a.time.is_none() {
        bail!(coded(
            "usage",
            anyhow!("nothing to produce: give --sync MS, --heartbeat MS --heartbeat-id N or --time MS")
        ));
    }
    if a.sync_counter == 1 || a.sync_counter > 240 {
        bail!(coded(
            "usage",
            anyhow!("--sync-counter {}: 0 (no counter) or 2..240 (CiA 301 1019h)", a.sync_counter)
        ));
    }
    let sync = a.sync.map(|ms| period("--sync", ms)).transpose()?;
    if a.heartbeat == Some(0) || a.time == Some(0) {
        bail!(coded("usage", anyhow!("a period of 0 ms produces nothing: leave the option out")));
    }
    let end = end_of(a.seconds)?;
    let conn = Conn::open(g).await?;
    let m = &conn.master;
    let t0 = Instant::now();
    let before = m.stats().frames_out;
    let mut what = Vec::new();
    if let Some(p) = sync {
        m.start_sync(p, a.sync_counter);
        what.push(format!("SYNC every {} ms", p.as_secs_f64() * 1000.0));
    }
    if let (Some(ms), Some(node)) = (a.heartbeat, a.heartbeat_id) {
        m.start_heartbeat(node, RemoteState::Operational, ms);
        what.push(format!("heartbeat of node {node} every {ms} ms"));
    }
    if let Some(ms) = a.time {
        let unix_ms = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64);
        m.start_time(Duration::from_millis(ms), unix_ms);
        what.push(format!("TIME every {ms} ms"));
    }
    if !g.json {
        // The producers run in the master's task; say so before waiting.
        eprintln!("produce: {} (Ctrl-C stops)", what.join(", "));
    }
    let stop = crate::serve::wait_for_signal();
    tokio::select! {
        () = until(end) => {}
        _ = stop => {}
    }
    m.stop_sync();
    m.stop_heartbeat();
    m.stop_time();
    let sent = m.stats().frames_out - before;
    let secs = t0.elapsed().as_secs_f64();
    conn.close().await?;
    crate::output::emit(
        g.json,
        serde_json::json!({"frames": sent, "seconds": secs, "producing": what}),
        || format!("produced {sent} frame(s) in {secs:.2} s: {}", what.join(", ")),
    );
    Ok(())
}

/// One of cangen's choices for the identifier, length or data.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Pick<T> {
    Fixed(T),
    Random,
    Increment,
}

fn pick<T>(option: &str, text: &str, fixed: impl Fn(&str) -> Option<T>) -> anyhow::Result<Pick<T>> {
    match text {
        "r" | "R" => Ok(Pick::Random),
        "i" | "I" => Ok(Pick::Increment),
        t => fixed(t).map(Pick::Fixed).ok_or_else(|| {
            coded("usage", anyhow!("bad {option} `{t}`: a value, `r` (random) or `i` (incrementing)"))
        }),
    }
}

/// cangen's frame source: deterministic for a seed.
pub struct Generator {
    id: Pick<u32>,
    len: Pick<u8>,
    data: Pick<Vec<u8>>,
    extended: bool,
    rtr: bool,
    rng: XorShift64,
    n: u64,
}

impl Generator {
    /// From `gen`'s options.
    pub fn new(a: &GenArgs) -> anyhow::Result<Generator> {
        let max_id = if a.extended { 0x1FFF_FFFF } else { 0x7FF };
        let id = pick("-I", &a.id, |t| {
            u32::from_str_radix(t.trim_start_matches("0x"), 16).ok().filter(|&v| v <= max_id)
        })?;
        let len = pick("-L", &a.len, |t| t.parse::<u8>().ok().filter(|&v| v <= 8))?;
        let data = pick::<Vec<u8>>("-D", &a.data, |t| {
            let t: String = t.chars().filter(|c| *c != '.').collect();
            if !t.len().is_multiple_of(2) || t.len() > 16 {
                return None;
            }
            (0..t.len()).step_by(2).map(|i| u8::from_str_radix(&t[i..i + 2], 16).ok()).collect()
        })?;
        // cangen: fixed data sets the length unless -L says otherwise.
        let len = match (&len, &data, a.len.as_str()) {
            (_, Pick::Fixed(d), "r") => Pick::Fixed(d.len() as u8),
            _ => len,
        };
        if let (Pick::Fixed(l), Pick::Fixed(d)) = (&len, &data)
            && usize::from(*l) > d.len()
        {
            bail!(coded("usage", anyhow!("-L {l} is longer than the {} byte(s) of -D", d.len())));
        }
        Ok(Generator { id, len, data, extended: a.extended, rtr: a.rtr, rng: XorShift64::new(a.seed), n: 0 })
    }

    /// The next frame.
    pub fn next_frame(&mut self) -> Frame {
        let n = self.n;
        self.n += 1;
        let max_id: u64 = if self.extended { 0x2000_0000 } else { 0x800 };
        let id = match self.id {
            Pick::Fixed(v) => v,
            Pick::Random => self.rng.below(max_id) as u32,
            Pick::Increment => (n % max_id) as u32,
        };
        let len = match self.len {
            Pick::Fixed(l) => l,
            Pick::Random => self.rng.below(9) as u8,
            Pick::Increment => (n % 9) as u8,
        };
        let mut data = [0u8; 8];
        match &self.data {
            Pick::Fixed(d) => data[..d.len()].copy_from_slice(d),
            Pick::Random => data = self.rng.next_u64().to_le_bytes(),
            Pick::Increment => data = n.to_le_bytes(),
        }
        let id = if self.extended { CanId::Extended(id) } else { CanId::Standard(id as u16) };
        let f =
            if self.rtr { Frame::try_remote(id, len) } else { Frame::try_new(id, &data[..usize::from(len)]) };
        // Every value above is in range by construction.
        f.unwrap_or_else(|_| Frame::new(0, &[]))
    }
}

/// `drivebus gen`.
pub async fn gen_frames(g: &Global, a: &GenArgs) -> anyhow::Result<()> {
    let mut source = Generator::new(a)?;
    if !(0.0..=86_400_000.0).contains(&a.gap) {
        bail!(coded("usage", anyhow!("-g {}: give milliseconds from 0 to a day", a.gap)));
    }
    let gap = Duration::from_secs_f64(a.gap / 1000.0);
    let end = end_of(a.seconds)?;
    let conn = Conn::open(g).await?;
    if a.rtr && !conn.master.carries_rtr() {
        bail!(coded("usage", anyhow!("-R: this transport cannot carry RTR frames (socketcand)")));
    }
    let stop = crate::serve::wait_for_signal();
    tokio::pin!(stop);
    let deadline = until(end);
    tokio::pin!(deadline);
    let t0 = Instant::now();
    let mut sent = 0u64;
    let mut next = Instant::now();
    while a.count.is_none_or(|n| sent < n) {
        if !gap.is_zero() {
            tokio::select! {
                () = tokio::time::sleep_until(next) => {}
                () = &mut deadline => break,
                _ = &mut stop => break,
            }
            next += gap;
        } else if end.is_some_and(|t| Instant::now() >= t) {
            break;
        }
        let f = source.next_frame();
        conn.master.send(f).await.with_context(|| format!("sending {f}"))?;
        sent += 1;
        if a.verbose && !g.json {
            let mut s = String::new();
            let _ = candump::write_frame(&mut s, &f);
            outln!("{s}");
        }
        if gap.is_zero() && sent.is_multiple_of(256) {
            // Back to back: let the transport drain (and Ctrl-C be seen).
            conn.master.flush().await.context("flushing")?;
            if futures_ready(&mut stop) {
                break;
            }
        }
    }
    let secs = t0.elapsed().as_secs_f64();
    conn.close().await?;
    crate::output::emit(g.json, serde_json::json!({"sent": sent, "seconds": secs}), || {
        format!("gen: sent {sent} frame(s) in {secs:.2} s")
    });
    Ok(())
}

/// True if `f` is ready now (without waiting).
fn futures_ready<F: std::future::Future + Unpin>(f: &mut F) -> bool {
    let waker = std::task::Waker::noop();
    let mut cx = std::task::Context::from_waker(waker);
    std::pin::Pin::new(f).poll(&mut cx).is_ready()
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    fn gen_args(args: &[&str]) -> GenArgs {
        #[derive(Parser)]
        struct T {
            #[command(flatten)]
            a: GenArgs,
        }
        T::parse_from(std::iter::once("gen").chain(args.iter().copied())).a
    }

    #[test]
    fn cangen_choices() {
        let mut g = Generator::new(&gen_args(&["-I", "42A", "-L", "8", "-D", "i"])).unwrap();
        let f: Vec<Frame> = (0..3).map(|_| g.next_frame()).collect();
        assert!(f.iter().all(|f| f.std_id() == Some(0x42A) && f.len() == 8));
        assert_eq!(f[2].data(), [2, 0, 0, 0, 0, 0, 0, 0]);
        let mut g = Generator::new(&gen_args(&["-I", "i", "-D", "1122"])).unwrap();
        let f: Vec<Frame> = (0..2).map(|_| g.next_frame()).collect();
        assert_eq!((f[0].std_id(), f[1].std_id()), (Some(0), Some(1)));
        assert_eq!(f[1].data(), [0x11, 0x22], "fixed data sets the length");
        // Random: in range, and the same sequence for the same seed.
        let a = gen_args(&["-e", "--seed", "7"]);
        let (mut g1, mut g2) = (Generator::new(&a).unwrap(), Generator::new(&a).unwrap());
        for _ in 0..200 {
            let (x, y) = (g1.next_frame(), g2.next_frame());
            assert_eq!(x, y);
            assert!(x.id().is_extended() && x.id().raw() <= 0x1FFF_FFFF && x.len() <= 8);
        }
        let mut g = Generator::new(&gen_args(&["-R", "-L", "1", "-I", "705"])).unwrap();
        assert_eq!(g.next_frame(), Frame::remote(0x705, 1));
        for bad in [&["-I", "800"][..], &["-L", "9"], &["-D", "123"], &["-L", "4", "-D", "11"], &["-I", "zz"]]
        {
            assert!(Generator::new(&gen_args(bad)).is_err(), "{bad:?}");
        }
    }
}
