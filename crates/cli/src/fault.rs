//! `--fault` rules for the buses that host virtual drives (serve,
//! slcan-pty): drop or corrupt frames by CAN-ID, to test how a master copes.

use anyhow::{Context, bail};
use drivebus_transport::{FaultRule, Hub};

/// Parse one rule:
///
/// `drop:IDS[,every=N][,skip=N][,times=N]` or
/// `corrupt:IDS:MASK[,every=N][,skip=N][,times=N]`, where IDS is one CAN-ID
/// or a range `LOW-HIGH` (hex with `0x`, or decimal) and MASK is up to 16 hex
/// digits XORed onto the data bytes.
pub fn parse(text: &str) -> anyhow::Result<FaultRule> {
    let bad = || format!("bad --fault `{text}`: expected drop:IDS[,every=N] or corrupt:IDS:MASK[,every=N]");
    let (head, opts) = match text.split_once(',') {
        Some((h, o)) => (h, Some(o)),
        None => (text, None),
    };
    let mut parts = head.split(':');
    let kind = parts.next().unwrap_or_default();
    let ids = ids(parts.next().with_context(bad)?).with_context(bad)?;
    let mut rule = match kind {
        "drop" => FaultRule::drop_frames().ids(ids),
        "corrupt" => {
            let hex = parts.next().with_context(bad)?;
            if hex.is_empty() || hex.len() > 16 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
                bail!("{}: MASK must be 1..16 hex digits", bad());
            }
            let padded = format!("{hex:0<16}");
            let mut mask = [0u8; 8];
            for (i, m) in mask.iter_mut().enumerate() {
                *m = u8::from_str_radix(&padded[2 * i..2 * i + 2], 16).with_context(bad)?;
            }
            FaultRule::corrupt_with(mask).ids(ids)
        }
        _ => bail!("{}", bad()),
    };
    if parts.next().is_some() {
        bail!("{}", bad());
    }
    for opt in opts.into_iter().flat_map(|o| o.split(',')) {
        let (k, v) = opt.split_once('=').with_context(bad)?;
        let n: u32 = v.trim().parse().with_context(bad)?;
        rule = match k.trim() {
            "every" if n > 0 => rule.every(n),
            "skip" => rule.skip(n),
            "times" => rule.times(n),
            _ => bail!("{}", bad()),
        };
    }
    Ok(rule)
}

fn number(s: &str) -> Option<u32> {
    let s = s.trim();
    match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u32::from_str_radix(h, 16).ok(),
        None => s.parse().ok(),
    }
}

fn ids(s: &str) -> Option<std::ops::RangeInclusive<u32>> {
    let (lo, hi) = match s.split_once('-') {
        Some((a, b)) => (number(a)?, number(b)?),
        None => (number(s)?, number(s)?),
    };
    (lo <= hi && hi <= 0x1FFF_FFFF).then_some(lo..=hi)
}

/// Parse every rule and install it on the hub.
pub fn install(hub: &Hub, rules: &[String]) -> anyhow::Result<()> {
    for r in rules {
        hub.add_fault(parse(r)?)?;
    }
    Ok(())
}

/// A fault of an EtherCAT line in text, as `drivebus control bus` sends it
/// to `ethercat serve --control` (slaves are numbered from 1 as in
/// `drivebus ethercat`):
///
/// `break:N` (the link behind slave N), `lose[,OPTS]`,
/// `corrupt[:N][,OPTS]` (damaged in front of slave N, default 1),
/// `wkc:N:SKEW` (slave N adds SKEW to each working counter it counts in),
/// `drift:N:PPM` (slave N's clock runs PPM parts per million fast),
/// `jitter:N:NS[,seed=S]` (slave N's time stamps jitter by up to ±NS ns);
/// OPTS are `every=N`, `skip=N`, `times=N`, `probability=P`, `seed=S`.
/// Returns the fault and the seed to give the line's generator, if any.
/// The seed of a jitter fault given without one.
const JITTER_SEED: u64 = 0x5EED;

pub fn parse_line(text: &str, slaves: usize) -> anyhow::Result<(drivebus_ethercat::LineFault, Option<u64>)> {
    use drivebus_can::Recurrence;
    use drivebus_ethercat::LineFault;
    let bad = || {
        format!(
            "bad EtherCAT fault `{text}`: expected break:N, lose[,every=N][,probability=P][,seed=S], \
             corrupt[:N][,every=N], wkc:N:SKEW, drift:N:PPM or jitter:N:NS[,seed=S] (slaves 1..{slaves})"
        )
    };
    let (head, opts) = match text.split_once(',') {
        Some((h, o)) => (h, Some(o)),
        None => (text, None),
    };
    let mut pick = Recurrence::always();
    let mut seed = None;
    for opt in opts.into_iter().flat_map(|o| o.split(',')) {
        let (k, v) = opt.split_once('=').with_context(bad)?;
        let (k, v) = (k.trim(), v.trim());
        pick = match k {
            "probability" => match v.parse::<f64>() {
                Ok(p) if (0.0..=1.0).contains(&p) => pick.probability(p),
                _ => bail!("{}: probability must be 0..1", bad()),
            },
            "seed" => {
                seed = Some(v.parse().with_context(bad)?);
                pick
            }
            _ => {
                let n: u32 = v.parse().with_context(bad)?;
                match k {
                    "every" if n > 0 => pick.every(n),
                    "skip" => pick.skip(n),
                    "times" => pick.times(n),
                    _ => bail!("{}", bad()),
                }
            }
        };
    }
    let slave = |s: &str, last: usize| -> anyhow::Result<usize> {
        match s.trim().parse::<usize>() {
            Ok(n) if (1..=last).contains(&n) => Ok(n - 1),
            _ => bail!("{}: slave `{s}` is not one of 1..{last}", bad()),
        }
    };
    let parts: Vec<&str> = head.split(':').collect();
    let fault = match parts.as_slice() {
        ["break", n] if opts.is_none() => {
            if slaves < 2 {
                bail!("{}: a line of one slave has no link behind it to break", bad());
            }
            LineFault::Break { after: slave(n, slaves - 1)? }
        }
        ["lose"] => LineFault::Lose(pick),
        ["corrupt"] => LineFault::Corrupt { at: 0, pick },
        ["corrupt", n] => LineFault::Corrupt { at: slave(n, slaves)?, pick },
        ["wkc", n, skew] if opts.is_none() => {
            let skew: i16 = skew.trim().trim_start_matches('+').parse().with_context(bad)?;
            LineFault::WkcSkew { slave: slave(n, slaves)?, skew }
        }
        ["drift", n, ppm] if opts.is_none() => {
            let ppm: f64 = ppm.trim().trim_start_matches('+').parse().with_context(bad)?;
            if !(-100_000.0..=100_000.0).contains(&ppm) {
                bail!("{}: PPM must be within ±100000", bad());
            }
            LineFault::Drift { slave: slave(n, slaves)?, ppb: (ppm * 1000.0).round() as i32 }
        }
        // The seed is the fault's own generator's, not the line's.
        ["jitter", n, ns] if pick == Recurrence::always() => {
            let amplitude_ns: u32 = ns.trim().parse().with_context(bad)?;
            if !(1..=drivebus_ethercat::MAX_JITTER_NS).contains(&amplitude_ns) {
                bail!("{}: NS must be 1..{}", bad(), drivebus_ethercat::MAX_JITTER_NS);
            }
            let fault = LineFault::Jitter {
                slave: slave(n, slaves)?,
                amplitude_ns,
                seed: seed.unwrap_or(JITTER_SEED),
            };
            return Ok((fault, None));
        }
        _ => bail!("{}", bad()),
    };
    Ok((fault, seed))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_parse_and_bad_ones_say_why() {
        assert!(parse("drop:0x585").is_ok());
        assert!(parse("drop:0x180-0x1FF,every=3,times=10").is_ok());
        assert!(parse("corrupt:0x185:FF00,skip=2").is_ok());
        for bad in [
            "",
            "drop",
            "drop:xyz",
            "drop:0x200-0x100",
            "corrupt:0x185",
            "corrupt:0x185:ZZ",
            "drop:1,every=0",
            "drop:1,foo=2",
            "flip:1",
        ] {
            let e = parse(bad).unwrap_err().to_string();
            assert!(e.contains("bad --fault"), "{bad}: {e}");
        }
    }

    #[test]
    fn line_faults_parse_and_bad_ones_say_why() {
        use drivebus_ethercat::LineFault;
        assert_eq!(parse_line("break:2", 3).unwrap(), (LineFault::Break { after: 1 }, None));
        assert_eq!(parse_line("wkc:3:+1", 3).unwrap().0, LineFault::WkcSkew { slave: 2, skew: 1 });
        assert_eq!(parse_line("wkc:1:-2", 3).unwrap().0, LineFault::WkcSkew { slave: 0, skew: -2 });
        assert_eq!(parse_line("drift:2:-1.5", 3).unwrap().0, LineFault::Drift { slave: 1, ppb: -1500 });
        assert!(matches!(parse_line("corrupt:2,every=4", 3).unwrap().0, LineFault::Corrupt { at: 1, .. }));
        assert_eq!(
            parse_line("jitter:2:5000,seed=9", 3).unwrap(),
            (LineFault::Jitter { slave: 1, amplitude_ns: 5000, seed: 9 }, None)
        );
        assert!(matches!(
            parse_line("jitter:1:20", 3).unwrap().0,
            LineFault::Jitter { amplitude_ns: 20, .. }
        ));
        for bad in ["jitter:1:0", "jitter:1:2000000", "jitter:1:20,every=2", "jitter:4:20"] {
            assert!(parse_line(bad, 3).unwrap_err().to_string().contains("bad EtherCAT fault"), "{bad}");
        }
        let (f, seed) = parse_line("lose,probability=0.1,seed=7", 3).unwrap();
        assert!(matches!(f, LineFault::Lose(_)));
        assert_eq!(seed, Some(7));
        for bad in [
            "",
            "break",
            "break:3",
            "break:0",
            "lose,every=0",
            "lose,probability=2",
            "wkc:4:1",
            "drift:1:1e9",
            "flip",
        ] {
            let e = parse_line(bad, 3).unwrap_err().to_string();
            assert!(e.contains("bad EtherCAT fault"), "{bad}: {e}");
        }
        assert!(parse_line("break:1", 1).unwrap_err().to_string().contains("one slave"));
    }
}
