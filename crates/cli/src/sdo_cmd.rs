//! `drivebus sdo read|write|upload|download|store|restore`.

use std::path::PathBuf;

use anyhow::{Context, anyhow, bail};
use drivebus_master::{DataType, Protocol, SdoError, Value};
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{Global, SdoCmd, SdoFile, SdoRead, SdoWrite, StoreArgs};
use crate::conn::{Conn, need_node};
use crate::error::{coded, sdo};
use crate::output::outln;

/// Runs an `sdo` subcommand.
pub async fn run(g: &Global, c: &SdoCmd) -> anyhow::Result<()> {
    let node = need_node(g)?;
    match c {
        SdoCmd::Read(a) => read_cmd(g, node, a).await,
        SdoCmd::Write(a) => write_cmd(g, node, a).await,
        SdoCmd::Upload(a) => upload_cmd(g, node, a).await,
        SdoCmd::Download(a) => download_cmd(g, node, a).await,
        SdoCmd::Store(a) => store_restore(g, node, a, 0x1010, *b"save", "stored").await,
        SdoCmd::Restore(a) => store_restore(g, node, a, 0x1011, *b"load", "restored to defaults").await,
    }
}

/// `sdo read OBJECT [SUB]`: one entry, or every entry of a record or array.
async fn read_cmd(g: &Global, node: u8, a: &SdoRead) -> anyhow::Result<()> {
    let dict = crate::dict::Dict { eds: crate::eds_cmd::load_global_eds(g)? };
    let (index, sub) = dict.resolve(&a.object, a.sub.as_deref())?;
    let forced = a.ty.as_deref().map(parse_type).transpose()?;
    let conn = Conn::open_with(g, dict).await?;
    let subs = match (sub, conn.dict.entries(index)) {
        (Some(s), _) => vec![s],
        (None, None) => vec![0],
        // A whole record/array: sub 0 says how many entries exist.
        (None, Some(all)) => {
            let n = read(&conn, node, index, 0).await?;
            let highest = n.first().copied().unwrap_or(0);
            all.into_iter().filter(|&s| s <= highest).collect()
        }
    };
    let mut rows = Vec::new();
    for s in subs {
        let data = match read(&conn, node, index, s).await {
            // A record may skip sub-indices; an array entry beyond the
            // count is absent.
            Err(e) if !rows.is_empty() && is_missing(&e) => continue,
            r => r?,
        };
        let dt = forced.or_else(|| conn.dict.data_type(index, s));
        rows.push((s, conn.dict.name(index, s), dt, data));
    }
    conn.close().await?;
    print_values(g, node, index, &rows);
    Ok(())
}

/// `sdo write OBJECT [SUB] VALUE`, typed by the dictionary or `--type`.
async fn write_cmd(g: &Global, node: u8, a: &SdoWrite) -> anyhow::Result<()> {
    let dict = crate::dict::Dict { eds: crate::eds_cmd::load_global_eds(g)? };
    let (obj, sub, value) = match a.args.as_slice() {
        [o, v] => (o, None, v),
        [o, s, v] => (o, Some(s.as_str()), v),
        _ => bail!("give OBJECT [SUB] VALUE"),
    };
    let (index, sub) = dict.resolve(obj, sub)?;
    let sub = sub.unwrap_or(0);
    let dt = match a.ty.as_deref() {
        Some(t) => parse_type(t)?,
        None => dict.data_type(index, sub).ok_or_else(|| {
            coded("usage", anyhow!("the data type of {index:04X}h:{sub:02X} is unknown: give --type (u8, u16, u32, i32, str, ...) or --eds FILE"))
        })?,
    };
    let v = Value::parse(dt, value).map_err(|e| coded("usage", anyhow!("bad value `{value}`: {e}")))?;
    let bytes = v
        .encode(dt)
        .map_err(|e| coded("usage", anyhow!("value `{value}` does not fit {}: {e}", dt.name())))?;
    let conn = Conn::open_with(g, dict).await?;
    let r = conn.master.sdo(node).download(index, sub, &bytes).await;
    let timeout = conn.timeout;
    conn.close().await?;
    r.map_err(sdo(node, index, sub, true, timeout))?;
    crate::output::emit(
        g.json,
        serde_json::json!({"node": node, "index": index, "sub": sub, "type": dt.name(), "written": hex(&bytes)}),
        || format!("node {node}: wrote {index:04X}h:{sub:02X} = {v} ({})", dt.name()),
    );
    Ok(())
}

/// `sdo upload OBJECT [SUB] FILE`.
async fn upload_cmd(g: &Global, node: u8, a: &SdoFile) -> anyhow::Result<()> {
    let (index, sub, file) = file_args(g, &a.args)?;
    let conn = Conn::open(g).await?;
    let pb = bar(g, None);
    let proto = if a.block { Protocol::Block } else { Protocol::Auto };
    let p2 = pb.clone();
    let h = conn.master.sdo(node).protocol(proto).on_progress(move |d, t| progress(&p2, d, t));
    let data = h.upload(index, sub).await;
    pb.finish_and_clear();
    let timeout = conn.timeout;
    conn.close().await?;
    let data = data.map_err(sdo(node, index, sub, false, timeout))?;
    std::fs::write(&file, &data).with_context(|| format!("cannot write {}", file.display()))?;
    report_file(g, node, index, sub, data.len(), "read", &file);
    Ok(())
}

/// `sdo download OBJECT [SUB] FILE`.
async fn download_cmd(g: &Global, node: u8, a: &SdoFile) -> anyhow::Result<()> {
    let (index, sub, file) = file_args(g, &a.args)?;
    let data = std::fs::read(&file).with_context(|| format!("cannot read {}", file.display()))?;
    if data.is_empty() {
        bail!("{} is empty: nothing to download", file.display());
    }
    let len = data.len();
    let conn = Conn::open(g).await?;
    let pb = bar(g, Some(len as u64));
    let proto = if a.block {
        Protocol::Block
    } else if len <= 4 {
        Protocol::Expedited
    } else {
        Protocol::Segmented
    };
    let p2 = pb.clone();
    let h = conn.master.sdo(node).protocol(proto).on_progress(move |d, t| progress(&p2, d, t));
    let r = h.download(index, sub, &data).await;
    pb.finish_and_clear();
    let timeout = conn.timeout;
    conn.close().await?;
    r.map_err(sdo(node, index, sub, true, timeout))?;
    report_file(g, node, index, sub, len, "wrote", &file);
    Ok(())
}

async fn read(conn: &Conn, node: u8, index: u16, sub: u8) -> anyhow::Result<Vec<u8>> {
    conn.master.sdo(node).upload(index, sub).await.map_err(sdo(node, index, sub, false, conn.timeout))
}

fn is_missing(e: &anyhow::Error) -> bool {
    e.downcast_ref::<crate::error::SdoFailure>().is_some_and(|f| {
        matches!(f.error, SdoError::Abort { code, .. }
            if code == drivebus_master::SdoAbort::NO_SUB_INDEX || code == drivebus_master::SdoAbort::NO_OBJECT)
    })
}

/// OBJECT [SUB] FILE.
fn file_args(g: &Global, args: &[String]) -> anyhow::Result<(u16, u8, PathBuf)> {
    let dict = crate::dict::Dict { eds: crate::eds_cmd::load_global_eds(g)? };
    let (obj, sub, file) = match args {
        [o, f] => (o, None, f),
        [o, s, f] => (o, Some(s.as_str()), f),
        _ => bail!("give OBJECT [SUB] FILE"),
    };
    let (index, sub) = dict.resolve(obj, sub)?;
    Ok((index, sub.unwrap_or(0), PathBuf::from(file)))
}

/// 1010h/1011h with the CiA 301 signature ("save"/"load", §7.5.2.13/14).
async fn store_restore(
    g: &Global,
    node: u8,
    a: &StoreArgs,
    index: u16,
    signature: [u8; 4],
    done: &str,
) -> anyhow::Result<()> {
    let sub = match a.what.as_str() {
        "all" => 1,
        "comm" | "communication" => 2,
        "app" | "application" => 3,
        n => match n.parse::<u8>() {
            Ok(s @ 1..=127) => s,
            _ => bail!("--what `{n}`: give all, comm, app or a sub-index 1..127"),
        },
    };
    let conn = Conn::open(g).await?;
    let r = conn.master.sdo(node).download(index, sub, &signature).await;
    let timeout = conn.timeout;
    conn.close().await?;
    r.map_err(sdo(node, index, sub, true, timeout))?;
    let what = crate::dict::Dict::default().name(index, sub).unwrap_or_default();
    crate::output::emit(
        g.json,
        serde_json::json!({"node": node, "index": index, "sub": sub, "result": done}),
        || format!("node {node}: {what}: parameters {done}"),
    );
    Ok(())
}

fn bar(g: &Global, len: Option<u64>) -> ProgressBar {
    if g.json {
        return ProgressBar::hidden();
    }
    // indicatif draws only on a terminal.
    let pb = ProgressBar::new(len.unwrap_or(0));
    let style =
        ProgressStyle::with_template("{spinner} [{bar:40}] {bytes}/{total_bytes} {bytes_per_sec} {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
    pb.set_style(style);
    pb
}

fn progress(pb: &ProgressBar, done: usize, total: Option<usize>) {
    if let Some(t) = total {
        pb.set_length(t as u64);
    }
    pb.set_position(done as u64);
}

fn report_file(g: &Global, node: u8, index: u16, sub: u8, n: usize, verb: &str, file: &std::path::Path) {
    let dir = if verb == "read" { "into" } else { "from" };
    crate::output::emit(
        g.json,
        serde_json::json!({"node": node, "index": index, "sub": sub, "bytes": n, "file": file.display().to_string()}),
        || format!("node {node}: {verb} {n} bytes of {index:04X}h:{sub:02X} {dir} {}", file.display()),
    );
}

/// A data type as the user names it.
pub fn parse_type(t: &str) -> anyhow::Result<DataType> {
    DataType::from_name(t).ok_or_else(|| {
        coded("usage", anyhow!("unknown type `{t}` (use u8, u16, u32, u64, i8, i16, i32, i64, f32, f64, bool, str, bytes or a CiA name like UNSIGNED16)"))
    })
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

/// One entry read: sub-index, name, data type, bytes.
pub(crate) type Row = (u8, Option<String>, Option<DataType>, Vec<u8>);

fn print_values(g: &Global, node: u8, index: u16, rows: &[Row]) {
    if g.json {
        let items: Vec<serde_json::Value> = rows.iter().map(|r| row_json(node, index, r)).collect();
        match items.as_slice() {
            [one] => outln!("{one}"),
            _ => outln!("{}", serde_json::json!({"node": node, "index": index, "entries": items})),
        }
        return;
    }
    for r in rows {
        outln!("{}", row_text(index, r));
    }
}

pub(crate) fn row_json(node: u8, index: u16, (sub, name, dt, data): &Row) -> serde_json::Value {
    let mut j = serde_json::json!({"node": node, "index": index, "sub": sub, "raw": hex(data)});
    if let Some(n) = name {
        j["name"] = n.clone().into();
    }
    match dt.and_then(|t| Value::decode(t, data).ok().map(|v| (t, v))) {
        Some((t, v)) => {
            j["type"] = t.name().into();
            j["value"] = value_json(&v);
        }
        None if (1..=8).contains(&data.len()) => j["value"] = le_unsigned(data).into(),
        None => {}
    }
    j
}

pub(crate) fn row_text(index: u16, (sub, name, dt, data): &Row) -> String {
    let label = name.as_ref().map(|n| format!(" {n}")).unwrap_or_default();
    let decoded = dt.and_then(|t| Value::decode(t, data).ok());
    match (dt, decoded) {
        (Some(t), Some(v)) => {
            let w = t.fixed_size().unwrap_or(1) * 2;
            let extra = match v.as_i128() {
                Some(i) if i >= 0 && !matches!(t, DataType::Boolean) => format!(" (0x{i:0w$X})"),
                _ => String::new(),
            };
            format!("{index:04X}h:{sub:02X}{label} = {v}{extra} [{}]", t.name())
        }
        (Some(t), None) => format!(
            "{index:04X}h:{sub:02X}{label} = {} (does not decode as {}: {} bytes)",
            hex(data),
            t.name(),
            data.len()
        ),
        (None, _) if (1..=8).contains(&data.len()) => {
            let u = le_unsigned(data);
            format!(
                "{index:04X}h:{sub:02X}{label} = {u} (0x{u:0w$X}) [{} bytes]",
                data.len(),
                w = data.len() * 2
            )
        }
        (None, _) => {
            let text: String =
                data.iter().map(|&b| if (0x20..0x7F).contains(&b) { b as char } else { '.' }).collect();
            format!("{index:04X}h:{sub:02X}{label} = {} \"{text}\" [{} bytes]", hex(data), data.len())
        }
    }
}

fn le_unsigned(d: &[u8]) -> u64 {
    d.iter().take(8).rev().fold(0u64, |a, &b| (a << 8) | u64::from(b))
}
