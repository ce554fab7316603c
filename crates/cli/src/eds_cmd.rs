//! `drivebus eds check|show|export`, and EDS helpers for other commands.

use std::path::Path;

use anyhow::{Context, anyhow, bail};
use drivebus_eds::{Eds, EdsVar, Severity};
use drivebus_master::{DataType, Protocol, SdoAbort, SdoError};
use drivebus_personality::Profile;

use crate::args::{EdsCmd, Global};
use crate::conn::{Conn, need_node};
use crate::output::{out, outln};

/// Reads and parses an EDS/DCF file; the error lists the first problems with lines.
pub fn load_eds(path: &Path) -> anyhow::Result<Eds> {
    let text = std::fs::read(path).with_context(|| format!("cannot read EDS file {}", path.display()))?;
    let text = String::from_utf8_lossy(&text);
    parse_text(&text).with_context(|| format!("EDS file {}", path.display()))
}

fn parse_text(text: &str) -> anyhow::Result<Eds> {
    match drivebus_eds::parse(text) {
        Ok(p) => Ok(p.eds),
        Err(e) => {
            let lines: Vec<String> =
                e.errors.iter().take(10).map(|d| format!("line {}: {}", d.line, d.message)).collect();
            Err(anyhow!("does not parse:\n  {}", lines.join("\n  ")))
        }
    }
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
        EdsCmd::Check(a) => {
            let text = std::fs::read(&a.file)
                .with_context(|| format!("cannot read EDS file {}", a.file.display()))?;
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
                Err(e) => {
                    (e.errors.iter().map(|d| (Severity::Error, d.line, d.message.clone())).collect(), true)
                }
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
        EdsCmd::Show(a) => {
            let eds = match (&a.profile, a.file.as_deref().or(g.eds.as_deref())) {
                (Some(p), _) => profile(p)?.parse_eds().eds,
                (None, Some(f)) => load_eds(f)?,
                (None, None) => bail!("give a file, --eds FILE or --profile NAME"),
            };
            show(g, &eds);
            Ok(0)
        }
        EdsCmd::Export(a) => {
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
            deliver(g, a.out.as_deref(), &text)?;
            Ok(0)
        }
        EdsCmd::Dcf(a) => {
            let node = need_node(g)?;
            let conn = Conn::open(g).await?;
            let r = match &conn.dict.eds {
                Some(eds) => conn.master.dump_dcf(node, eds.clone()).await,
                None => conn.master.dump_standard_dcf(node).await,
            };
            let timeout = conn.timeout;
            conn.close().await?;
            let (dcf, report) = r.map_err(|e| crate::error::sdo(node, 0, 0, false, timeout)(e))?;
            let text = drivebus_eds::write(&dcf);
            deliver(g, a.out.as_deref(), &text)?;
            if !g.json {
                let source = if g.eds.is_some() {
                    "the EDS"
                } else {
                    "the CiA 301/402 standard objects (manufacturer objects need --eds)"
                };
                eprintln!(
                    "node {node}: {} values read from {source}, {} refused",
                    report.read,
                    report.refused.len()
                );
                for (index, sub, len) in &report.mismatched {
                    eprintln!(
                        "node {node}: {index:04X}h:{sub:02X} answered {len} bytes, not its data type's size: \
                         value left out (the node's object differs; give its EDS with --eds)"
                    );
                }
            }
            Ok(0)
        }
    }
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
