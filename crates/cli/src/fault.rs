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
}
