//! `drivebus eds check|show|export`, and EDS helpers for other commands.

use std::path::Path;

use anyhow::{Context, anyhow, bail};
use drivebus_eds::{Eds, EdsVar, Severity};
use drivebus_master::{DataType, Protocol, SdoAbort, SdoError};
use drivebus_personality::Profile;

use crate::args::{DcfArgs, EdsCmd, EdsExport, EdsFileArg, Global};
use crate::conn::{Conn, need_node};
use crate::output::{out, outln};

/// Reads and parses an EDS/DCF file; the error lists the first problems with lines.
pub fn load_eds(path: &Path) -> anyhow::Result<Eds> {
    let text = std::fs::read(path).with_context(|| format!("cannot read EDS file {}", path.display()))?;
    let text = String::from_utf8_lossy(&text);
    parse_text(&text).map_err(|e| anyhow!("{}: {e}", path.display()))
}

/// Parses an EDS; the error names the first problem with its line (the
/// cause: the file's errors come in file order, consequences found at the
/// end last), then how many more there are and the next few.
pub(crate) fn parse_text(text: &str) -> anyhow::Result<Eds> {
    match drivebus_eds::parse(text) {
        Ok(p) => Ok(p.eds),
        Err(e) => {
            let at = |d: &drivebus_eds::Diagnostic| {
                if d.line == 0 { d.message.clone() } else { format!("line {}: {}", d.line, d.message) }
            };
            let first = e.errors.first().map(at).unwrap_or_else(|| "does not parse".into());
            let more: Vec<String> = e.errors.iter().skip(1).take(9).map(at).collect();
            let rest = match e.errors.len() {
                0 | 1 => String::new(),
                n => format!(
                    " (the EDS does not parse; {} more error(s){}:\n  {})",
                    n - 1,
                    if n > 10 { ", the next 9" } else { "" },
                    more.join("\n  ")
                ),
            };
            Err(anyhow!("{first}{rest}"))
        }
    }
}

/// `text` with `FileName=` in `[FileInfo]` set to `name` (CiA 306 §4.2:
/// the name of the file it is in), inserted when missing.
pub fn with_file_name(text: &str, name: &str) -> String {
    let mut out = String::with_capacity(text.len() + name.len());
    let mut in_info = false;
    let mut done = false;
    for line in text.split_inclusive('\n') {
        let t = line.trim();
        if t.starts_with('[') {
            if in_info && !done {
                out.push_str(&format!("FileName={name}\r\n"));
                done = true;
            }
            in_info = t.eq_ignore_ascii_case("[FileInfo]");
        } else if in_info
            && !done
            && t.split('=').next().is_some_and(|k| k.trim().eq_ignore_ascii_case("FileName"))
        {
            let eol = if line.ends_with("\r\n") {
                "\r\n"
            } else if line.ends_with('\n') {
                "\n"
            } else {
                ""
            };
            out.push_str(&format!("FileName={name}{eol}"));
            done = true;
            continue;
        }
        out.push_str(line);
    }
    out
}

/// `[FileInfo]` of a DCF read off a node: its file name and what CiA 306
/// §4.2 asks for, keeping what the template had.
fn stamp_file_info(dcf: &mut Eds, name: &str, node: u8) {
    let (date, time) = now_306();
    let set = |fi: &mut Vec<(String, String)>, k: &str, v: String, replace: bool| match fi
        .iter_mut()
        .find(|(key, _)| key.eq_ignore_ascii_case(k))
    {
        Some(e) if replace || e.1.trim().is_empty() => e.1 = v,
        Some(_) => {}
        None => fi.push((k.to_owned(), v)),
    };
    let fi = &mut dcf.file_info;
    set(fi, "FileName", name.to_owned(), true);
    set(fi, "FileVersion", "1".into(), false);
    set(fi, "FileRevision", "0".into(), false);
    set(fi, "EDSVersion", "4.0".into(), false);
    set(fi, "Description", format!("node {node} as read by drivebus eds dcf"), false);
    set(fi, "CreationTime", time.clone(), false);
    set(fi, "CreationDate", date.clone(), false);
    set(fi, "CreatedBy", "drivebus".into(), false);
    set(fi, "ModificationTime", time, true);
    set(fi, "ModificationDate", date, true);
    set(fi, "ModifiedBy", "drivebus".into(), true);
}

/// Today's date and time as CiA 306 writes them: `mm-dd-yyyy`, `hh:mmAM`.
fn now_306() -> (String, String) {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    let (h, min) = (rem / 3600, rem % 3600 / 60);
    let (h12, ampm) = match h {
        0 => (12, "AM"),
        1..=11 => (h, "AM"),
        12 => (12, "PM"),
        _ => (h - 12, "PM"),
    };
    (format!("{m:02}-{d:02}-{y}"), format!("{h12:02}:{min:02}{ampm}"))
}

/// The `--eds` file, if given.
pub fn load_global_eds(g: &Global) -> anyhow::Result<Option<Eds>> {
    g.eds.as_deref().map(load_eds).transpose()
}

fn profile(name: &str) -> anyhow::Result<Profile> {
    Profile::from_name(name).ok_or_else(|| {
        let names = Profile::all().iter().map(|p| p.name()).collect::<Vec<_>>().join(", ");
        anyhow!("unknown profile `{name}` (profiles: {names})")
    })
}

/// Writes `text` to `out` (reporting it) or to stdout.
fn deliver(g: &Global, out_path: Option<&Path>, text: &str) -> anyhow::Result<()> {
    match out_path {
        Some(path) => {
            std::fs::write(path, text.as_bytes())
                .with_context(|| format!("cannot write {}", path.display()))?;
            crate::output::emit(
                g.json,
                serde_json::json!({"file": path.display().to_string(), "bytes": text.len()}),
                || format!("wrote {} ({} bytes)", path.display(), text.len()),
            );
        }
        None if g.json => outln!("{}", serde_json::json!({ "text": text })),
        None => out!("{text}"),
    }
    Ok(())
}

/// Runs an `eds` subcommand; returns the exit status (check: 1 on errors).
pub async fn run(g: &Global, c: &EdsCmd) -> anyhow::Result<i32> {
    match c {
        EdsCmd::Check(a) => check(g, a),
        EdsCmd::Show(a) => {
            let eds = match (&a.profile, a.file.as_deref().or(g.eds.as_deref())) {
                (Some(p), _) => profile(p)?.parse_eds().eds,
                (None, Some(f)) => load_eds(f)?,
                (None, None) => bail!("give a file, --eds FILE or --profile NAME"),
            };
            show(g, &eds);
            Ok(0)
        }
        EdsCmd::Export(a) => export(g, a).await,
        EdsCmd::Dcf(a) => dcf(g, a).await,
    }
}

/// `eds check FILE`: findings with severity and line; 1 on errors.
fn check(g: &Global, a: &EdsFileArg) -> anyhow::Result<i32> {
    let text =
        std::fs::read(&a.file).with_context(|| format!("cannot read EDS file {}", a.file.display()))?;
    let text = String::from_utf8_lossy(&text);
    let (findings, parse_errors) = match drivebus_eds::parse(&text) {
        Ok(p) => {
            let mut f: Vec<(Severity, usize, String)> =
                p.warnings.iter().map(|d| (Severity::Warning, d.line, d.message.clone())).collect();
            f.extend(drivebus_eds::check(&p.eds).into_iter().map(|x| {
                let what = match (x.index, x.sub) {
                    (Some(i), Some(s)) => format!("{i:04X}sub{s:X}: {}", x.message),
                    (Some(i), None) => format!("{i:04X}: {}", x.message),
                    _ => x.message,
                };
                (x.severity, x.line, what)
            }));
            (f, false)
        }
        Err(e) => (e.errors.iter().map(|d| (Severity::Error, d.line, d.message.clone())).collect(), true),
    };
    let errors = findings.iter().filter(|f| f.0 == Severity::Error).count();
    let warnings = findings.len() - errors;
    if g.json {
        let items: Vec<_> = findings
            .iter()
            .map(|(s, l, m)| {
                serde_json::json!({"severity": if *s == Severity::Error {"error"} else {"warning"}, "line": l, "message": m})
            })
            .collect();
        outln!(
            "{}",
            serde_json::json!({"file": a.file.display().to_string(), "errors": errors, "warnings": warnings, "parsed": !parse_errors, "findings": items})
        );
    } else {
        for (s, l, m) in &findings {
            let sev = if *s == Severity::Error { "error" } else { "warning" };
            outln!("{}:{l}: {sev}: {m}", a.file.display());
        }
        outln!("{}: {errors} error(s), {warnings} warning(s)", a.file.display());
    }
    Ok(if errors > 0 { 1 } else { 0 })
}

/// `eds export`: a personality's EDS, a node's 1021h, or `--eds` rewritten.
async fn export(g: &Global, a: &EdsExport) -> anyhow::Result<i32> {
    let text = if let Some(p) = &a.profile {
        profile(p)?.eds_text().to_owned()
    } else if let Some(node) = g.node {
        let conn = Conn::open(g).await?;
        let sdo = conn.master.sdo(node);
        let r = match sdo.clone().protocol(Protocol::Block).upload(0x1021, 0).await {
            // A server without block transfer refuses the command
            // specifier (CiA 301 §7.2.4.3.17 0504 0001h): read it
            // segmented instead.
            Err(SdoError::Abort { code, .. }) if code == SdoAbort::INVALID_COMMAND => {
                sdo.upload(0x1021, 0).await
            }
            r => r,
        };
        let timeout = conn.timeout;
        conn.close().await?;
        let data = r
            .map_err(crate::error::sdo(node, 0x1021, 0, false, timeout))
            .with_context(|| format!("node {node} gives no EDS through 1021h (store EDS)"))?;
        String::from_utf8_lossy(&data).into_owned()
    } else if let Some(f) = &g.eds {
        drivebus_eds::write(&load_eds(f)?)
    } else {
        bail!("nothing to export: give --profile NAME, --node N (reads 1021h) or --eds FILE");
    };
    // The file's own name, not the one it had elsewhere (1021h
    // says drivebus.eds whatever the file is called).
    let text = match a.out.as_deref().and_then(Path::file_name) {
        Some(name) => with_file_name(&text, &name.to_string_lossy()),
        None => text,
    };
    deliver(g, a.out.as_deref(), &text)?;
    Ok(0)
}

/// `eds dcf`: a live node's values as a DCF.
async fn dcf(g: &Global, a: &DcfArgs) -> anyhow::Result<i32> {
    let node = need_node(g)?;
    let conn = Conn::open(g).await?;
    let r = match &conn.dict.eds {
        Some(eds) => conn.master.dump_dcf(node, eds.clone()).await,
        None => conn.master.dump_standard_dcf(node).await,
    };
    let timeout = conn.timeout;
    conn.close().await?;
    let (mut dcf, report) = r.map_err(|e| crate::error::sdo(node, 0, 0, false, timeout)(e))?;
    let name = a
        .out
        .as_deref()
        .and_then(Path::file_name)
        .map_or_else(|| format!("node{node}.dcf"), |n| n.to_string_lossy().into_owned());
    stamp_file_info(&mut dcf, &name, node);
    let text = drivebus_eds::write(&dcf);
    deliver(g, a.out.as_deref(), &text)?;
    if !g.json {
        let source = if g.eds.is_some() {
            "the EDS"
        } else {
            "the CiA 301/402 standard objects (manufacturer objects need --eds)"
        };
        eprintln!("node {node}: {} values read from {source}, {} refused", report.read, report.refused.len());
        for (index, sub, len) in &report.mismatched {
            eprintln!(
                "node {node}: {index:04X}h:{sub:02X} answered {len} bytes, not its data type's size: \
                 value left out (the node's object differs; give its EDS with --eds)"
            );
        }
    }
    Ok(0)
}

fn show(g: &Global, eds: &Eds) {
    let mut rows = Vec::new();
    for (idx, o) in &eds.objects {
        let entries: Vec<(Option<u8>, &EdsVar)> = match &o.var {
            Some(v) if o.subs.is_empty() => vec![(None, v)],
            _ => o.subs.iter().map(|(s, v)| (Some(*s), v)).collect(),
        };
        if entries.is_empty() {
            rows.push((*idx, None, o.name.clone(), String::new(), String::new(), String::new(), false));
        }
        for (sub, v) in entries {
            let ty = DataType::from_index(v.data_type)
                .map_or_else(|| format!("0x{:04X}", v.data_type), |t| t.name().into());
            let name = if sub.is_some() { format!("{} / {}", o.name, v.name) } else { o.name.clone() };
            rows.push((
                *idx,
                sub,
                name,
                ty,
                v.access.name().to_owned(),
                v.parameter_value.clone().or_else(|| v.default.clone()).unwrap_or_default(),
                v.pdo_mapping,
            ));
        }
    }
    if g.json {
        let items: Vec<_> = rows
            .iter()
            .map(|(i, s, n, t, a, d, p)| {
                serde_json::json!({"index": i, "sub": s.unwrap_or(0), "name": n, "type": t, "access": a, "default": d, "pdo_mapping": p})
            })
            .collect();
        let di = &eds.device_info;
        outln!(
            "{}",
            serde_json::json!({"vendor": di.vendor_name, "product": di.product_name, "objects": eds.objects.len(), "entries": items})
        );
        return;
    }
    let di = &eds.device_info;
    outln!("{} {} — {} objects", di.vendor_name, di.product_name, eds.objects.len());
    outln!("{:<9} {:<44} {:<15} {:<6} {:<4} default", "object", "name", "type", "access", "pdo");
    for (i, s, n, t, a, d, p) in rows {
        let obj = match s {
            Some(s) => format!("{i:04X}:{s:02X}"),
            None => format!("{i:04X}"),
        };
        let n: String = n.chars().take(44).collect();
        outln!("{obj:<9} {n:<44} {t:<15} {a:<6} {:<4} {d}", if p { "yes" } else { "" });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_file_name_is_the_files_own() {
        let t = "; c\r\n[FileInfo]\r\nFileName=drivebus.eds\r\nFileVersion=1\r\n\r\n[DeviceInfo]\r\nX=1\r\n";
        let w = with_file_name(t, "akd-node1.eds");
        assert_eq!(w, t.replace("drivebus.eds", "akd-node1.eds"));
        let none = "[FileInfo]\nFileVersion=1\n[DeviceInfo]\n";
        assert_eq!(
            with_file_name(none, "x.eds"),
            "[FileInfo]\nFileVersion=1\nFileName=x.eds\r\n[DeviceInfo]\n"
        );
        let (date, time) = now_306();
        assert_eq!((date.len(), date.as_bytes()[2], time.len()), (10, b'-', 7), "{date} {time}");
    }

    #[test]
    fn a_broken_eds_names_its_cause_first() {
        let e = parse_text(
            "[FileInfo]\nFileName=x\n[MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n[1000\nDataType=7\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("line 6: section header without ']'"), "{e}");
    }
}
