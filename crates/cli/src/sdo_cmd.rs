//! `drivebus sdo read|write|upload|download`.

use anyhow::{Context, anyhow, bail};
use drivebus_od::{DataType, Value};
use drivebus_sdo::client::Protocol;
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{Global, SdoCmd};
use crate::eds_cmd::{load_global_eds, object_name, var_type};
use crate::link::{Link, need_node, parse_index, parse_sub};
use crate::output::outln;

/// Runs an `sdo` subcommand.
pub async fn run(g: &Global, c: &SdoCmd) -> anyhow::Result<()> {
    let node = need_node(g)?;
    let eds = load_global_eds(g)?;
    match c {
        SdoCmd::Read(a) => {
            let (index, sub) = (parse_index(&a.index)?, parse_sub(&a.sub)?);
            let dt = resolve_type(a.ty.as_deref(), eds.as_ref(), index, sub)?;
            let mut link = Link::open(g).await?;
            let data = link.upload(node, index, sub).await?;
            let name = eds.as_ref().and_then(|e| object_name(e, index, sub));
            print_value(g, node, index, sub, name.as_deref(), dt, &data);
            Ok(())
        }
        SdoCmd::Write(a) => {
            let (index, sub) = (parse_index(&a.index)?, parse_sub(&a.sub)?);
            let dt = resolve_type(a.ty.as_deref(), eds.as_ref(), index, sub)?.ok_or_else(|| {
                anyhow!("the data type of {index:04X}h:{sub:02X} is unknown: give --type (u8, u16, u32, i32, str, ...) or --eds FILE")
            })?;
            let v = Value::parse(dt, &a.value).map_err(|e| anyhow!("bad value: {e}"))?;
            let bytes =
                v.encode(dt).map_err(|e| anyhow!("value `{}` does not fit {}: {e}", a.value, dt.name()))?;
            let mut link = Link::open(g).await?;
            link.download(node, index, sub, &bytes).await?;
            if g.json {
                outln!(
                    "{}",
                    serde_json::json!({"node": node, "index": index, "sub": sub, "type": dt.name(), "written": hex(&bytes)})
                );
            } else {
                outln!("node {node}: wrote {index:04X}h:{sub:02X} = {v} ({})", dt.name());
            }
            Ok(())
        }
        SdoCmd::Upload(a) => {
            let (index, sub) = (parse_index(&a.index)?, parse_sub(&a.sub)?);
            let mut link = Link::open(g).await?;
            let pb = bar(g, None);
            let proto = if a.block { Protocol::Block } else { Protocol::Auto };
            let data = link.upload_with(node, index, sub, proto, pb.as_ref()).await;
            if let Some(pb) = &pb {
                pb.finish_and_clear();
            }
            let data = data?;
            std::fs::write(&a.file, &data).with_context(|| format!("cannot write {}", a.file.display()))?;
            report_file(g, node, index, sub, data.len(), "read", &a.file);
            Ok(())
        }
        SdoCmd::Download(a) => {
            let (index, sub) = (parse_index(&a.index)?, parse_sub(&a.sub)?);
            let data = std::fs::read(&a.file).with_context(|| format!("cannot read {}", a.file.display()))?;
            if data.is_empty() {
                bail!("{} is empty: nothing to download", a.file.display());
            }
            let len = data.len();
            let mut link = Link::open(g).await?;
            let pb = bar(g, Some(len as u64));
            let proto = if a.block {
                Protocol::Block
            } else if len <= 4 {
                Protocol::Expedited
            } else {
                Protocol::Segmented
            };
            let r = link.download_with(node, index, sub, data, proto, pb.as_ref()).await;
            if let Some(pb) = &pb {
                pb.finish_and_clear();
            }
            r?;
            report_file(g, node, index, sub, len, "wrote", &a.file);
            Ok(())
        }
    }
}

fn bar(g: &Global, len: Option<u64>) -> Option<ProgressBar> {
    if g.json {
        return None;
    }
    let pb = ProgressBar::new(len.unwrap_or(0));
    let style =
        ProgressStyle::with_template("{spinner} [{bar:40}] {bytes}/{total_bytes} {bytes_per_sec} {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
    pb.set_style(style);
    Some(pb)
}

fn report_file(g: &Global, node: u8, index: u16, sub: u8, n: usize, verb: &str, file: &std::path::Path) {
    if g.json {
        outln!(
            "{}",
            serde_json::json!({"node": node, "index": index, "sub": sub, "bytes": n, "file": file.display().to_string()})
        );
    } else {
        let dir = if verb == "read" { "into" } else { "from" };
        outln!("node {node}: {verb} {n} bytes of {index:04X}h:{sub:02X} {dir} {}", file.display());
    }
}

/// The type from `--type`, else from the EDS, else unknown.
pub fn resolve_type(
    ty: Option<&str>,
    eds: Option<&drivebus_eds::Eds>,
    index: u16,
    sub: u8,
) -> anyhow::Result<Option<DataType>> {
    if let Some(t) = ty {
        return DataType::from_name(t).map(Some).ok_or_else(|| {
            anyhow!("unknown type `{t}` (use u8, u16, u32, u64, i8, i16, i32, i64, f32, f64, bool, str, bytes or a CiA name like UNSIGNED16)")
        });
    }
    Ok(eds.and_then(|e| var_type(e, index, sub)))
}

/// Hex bytes without separators.
pub fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02X}")).collect()
}

/// The value as JSON.
pub fn value_json(v: &Value) -> serde_json::Value {
    match v {
        Value::Bool(b) => (*b).into(),
        Value::F32(x) => f64::from(*x).into(),
        Value::F64(x) => (*x).into(),
        Value::Str(s) => s.clone().into(),
        Value::Bytes(b) => hex(b).into(),
        other => match other.as_i128() {
            Some(i) => i64::try_from(i).map_or_else(|_| i.to_string().into(), Into::into),
            None => other.to_string().into(),
        },
    }
}

fn print_value(
    g: &Global,
    node: u8,
    index: u16,
    sub: u8,
    name: Option<&str>,
    dt: Option<DataType>,
    data: &[u8],
) {
    let decoded = dt.and_then(|t| Value::decode(t, data).ok());
    if g.json {
        let mut j = serde_json::json!({"node": node, "index": index, "sub": sub, "raw": hex(data)});
        if let Some(n) = name {
            j["name"] = n.into();
        }
        if let (Some(t), Some(v)) = (dt, &decoded) {
            j["type"] = t.name().into();
            j["value"] = value_json(v);
        } else if (1..=8).contains(&data.len()) {
            j["value"] = le_unsigned(data).into();
        }
        outln!("{j}");
        return;
    }
    let label = name.map(|n| format!(" {n}")).unwrap_or_default();
    match (dt, decoded) {
        (Some(t), Some(v)) => {
            let extra = match v.as_i128() {
                Some(i) if i >= 0 && !matches!(t, DataType::Boolean) => format!(" (0x{i:X})"),
                _ => String::new(),
            };
            outln!("{index:04X}h:{sub:02X}{label} = {v}{extra} [{}]", t.name());
        }
        (Some(t), None) => {
            outln!(
                "{index:04X}h:{sub:02X}{label} = {} (does not decode as {}: {} bytes)",
                hex(data),
                t.name(),
                data.len()
            );
        }
        (None, _) if (1..=8).contains(&data.len()) => {
            let u = le_unsigned(data);
            outln!(
                "{index:04X}h:{sub:02X}{label} = {u} (0x{u:0w$X}) [{} bytes]",
                data.len(),
                w = data.len() * 2
            );
        }
        (None, _) => {
            let text: String =
                data.iter().map(|&b| if (0x20..0x7F).contains(&b) { b as char } else { '.' }).collect();
            outln!("{index:04X}h:{sub:02X}{label} = {} \"{text}\" [{} bytes]", hex(data), data.len());
        }
    }
}

fn le_unsigned(d: &[u8]) -> u64 {
    d.iter().take(8).rev().fold(0u64, |a, &b| (a << 8) | u64::from(b))
}
