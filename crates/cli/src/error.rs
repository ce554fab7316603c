//! Errors with a machine-readable code (`--json` prints them as
//! `{"error":{"code":...,"message":...}}`), and the explanations of SDO
//! and drive failures.

use std::fmt;
use std::time::Duration;

use drivebus_master::{DriveError, LssError, SdoError};

/// An error with a code for `--json`.
#[derive(Debug)]
pub struct Coded {
    /// Short code: usage, bus, sdo_abort, sdo_timeout, drive_timeout, ...
    pub code: &'static str,
    /// The error.
    pub error: anyhow::Error,
    /// Fields for `--json` besides code and message (a motion's outcome, position, ...).
    pub fields: Option<serde_json::Value>,
}

impl fmt::Display for Coded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#}", self.error)
    }
}

impl std::error::Error for Coded {}

/// Tags `e` with `code`.
pub fn coded(code: &'static str, e: impl Into<anyhow::Error>) -> anyhow::Error {
    anyhow::Error::new(Coded { code, error: e.into(), fields: None })
}

/// Tags `e` with `code` and the `--json` fields `fields`.
pub fn coded_with(code: &'static str, fields: serde_json::Value, e: anyhow::Error) -> anyhow::Error {
    anyhow::Error::new(Coded { code, error: e, fields: Some(fields) })
}

/// A duration option in seconds (`--seconds`, `--wait`), at most a year:
/// NaN, negative or absurd values are usage errors, never a panic.
pub fn seconds(option: &str, secs: f64) -> anyhow::Result<Duration> {
    if !(0.0..=365.0 * 86_400.0).contains(&secs) {
        return Err(coded("usage", anyhow::anyhow!("{option}: give a number of seconds from 0 to a year")));
    }
    Ok(Duration::from_secs_f64(secs))
}

/// An SDO transfer that failed, explained (the master's, so every front end says the same).
pub use drivebus_master::SdoFailure;

/// Wraps an SDO error of `node` at `index`/`sub`.
pub fn sdo(
    node: u8,
    index: u16,
    sub: u8,
    write: bool,
    timeout: Duration,
) -> impl FnOnce(SdoError) -> anyhow::Error {
    move |error| anyhow::Error::new(SdoFailure { node, index, sub, write, error, timeout })
}

/// An error as the user reads it: the root cause first, then what the
/// command was doing, each told once (a cause whose text its wrapper
/// repeats appears once: not "refused: refused").
pub fn render(e: &anyhow::Error) -> String {
    let mut parts: Vec<String> = e
        .chain()
        .map(|c| match c.downcast_ref::<Coded>() {
            Some(k) => render(&k.error),
            None => c.to_string(),
        })
        .collect();
    for i in 0..parts.len().saturating_sub(1) {
        let next = parts[i + 1].clone();
        if let Some(own) = parts[i].strip_suffix(next.as_str()) {
            parts[i] = own.trim_end().trim_end_matches(':').trim_end().to_owned();
        }
    }
    parts.retain(|p| !p.is_empty());
    parts.dedup();
    parts.reverse();
    parts.join(": ")
}

/// The `--json` code and extra fields of an error.
pub fn describe(e: &anyhow::Error) -> (&'static str, serde_json::Value) {
    let mut extra = serde_json::json!({});
    for cause in e.chain() {
        if let Some(c) = cause.downcast_ref::<Coded>() {
            return (c.code, c.fields.clone().unwrap_or(extra));
        }
        if let Some(f) = cause.downcast_ref::<SdoFailure>() {
            extra = serde_json::json!({"node": f.node, "index": format!("{:04X}", f.index), "sub": f.sub});
            return match f.abort() {
                Some(a) => {
                    extra["abort_code"] = format!("0x{:08X}", a.0).into();
                    ("sdo_abort", extra)
                }
                None if f.error == SdoError::Timeout => ("sdo_timeout", extra),
                None if matches!(f.error, SdoError::Transport(_)) => ("bus_lost", extra),
                None => ("sdo_error", extra),
            };
        }
        if let Some(d) = cause.downcast_ref::<DriveError>() {
            return match d {
                DriveError::Timeout { .. } => ("drive_timeout", extra),
                DriveError::Fault { .. } => ("drive_fault", extra),
                DriveError::Stopped(r) => (r.end.code(), extra),
                DriveError::Sdo(SdoError::Timeout) => ("sdo_timeout", extra),
                DriveError::Sdo(SdoError::Transport(_)) | DriveError::Transport(_) => ("bus_lost", extra),
                DriveError::Sdo(_) => ("sdo_abort", extra),
                _ => ("drive_error", extra),
            };
        }
        if cause.downcast_ref::<LssError>().is_some() {
            return ("lss_error", extra);
        }
        if cause.downcast_ref::<drivebus_transport::TransportError>().is_some() {
            return ("bus", extra);
        }
        if cause.downcast_ref::<std::io::Error>().is_some() {
            return ("io", extra);
        }
    }
    ("error", extra)
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_master::SdoAbort;

    #[test]
    fn the_cause_comes_first_and_once() {
        let io =
            std::io::Error::new(std::io::ErrorKind::ConnectionRefused, "Connection refused (os error 111)");
        let e = anyhow::Error::new(io).context("cannot open `x`: Connection refused (os error 111)");
        assert_eq!(render(&e), "Connection refused (os error 111): cannot open `x`");
        let e = coded("bus", anyhow::anyhow!("inner")).context("closing the bus");
        assert_eq!(render(&e), "inner: closing the bus");
    }

    #[test]
    fn sdo_failures_explain_themselves() {
        let f = SdoFailure {
            node: 3,
            index: 0x6041,
            sub: 0,
            write: false,
            error: SdoError::Abort { code: SdoAbort::NO_OBJECT, text: SdoAbort::NO_OBJECT.description() },
            timeout: Duration::from_millis(500),
        };
        assert_eq!(
            f.to_string(),
            "node 3: SDO read 6041h:00 aborted by the device with code 0x06020000: Object does not exist in the object dictionary"
        );
        let e = anyhow::Error::new(f);
        assert_eq!(describe(&e).0, "sdo_abort");
        assert_eq!(describe(&e).1["abort_code"], "0x06020000");
        let t = SdoFailure {
            node: 3,
            index: 0x6041,
            sub: 0,
            write: true,
            error: SdoError::Timeout,
            timeout: Duration::from_millis(500),
        };
        assert!(t.to_string().starts_with("node 3: SDO write 6041h:00 timed out: no response within 500 ms"));
        assert_eq!(describe(&coded("usage", anyhow::anyhow!("x"))).0, "usage");
    }
}
