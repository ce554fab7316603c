//! Objects and values as the API writes them: indices in hex or by name,
//! values as JSON with their CiA 301 type (the one codec, `Value`).

use drivebus_master::{DataType, Value};

use super::error::{ApiError, ApiResult};
use crate::dict::Dict;

/// Bytes as spaced hex, `01 A2`.
pub fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02X}")).collect::<Vec<_>>().join(" ")
}

/// A node-ID from the path: 1..127.
pub fn node_id(s: &str) -> ApiResult<u8> {
    crate::args::node_id(s).map_err(|e| ApiError::bad(format!("{e}: use /api/nodes/N/... with N in 1..127")))
}

/// The object of `/sdo/{index}[/{sub}]`: hex (`6040`, `0x6040`,
/// `6040h`) or a name from the EDS or CiA 301/402 (`statusword`,
/// `identity/vendor-id`). Without a sub-index: 0 (or the named entry).
pub fn object(dict: &Dict, index: &str, sub: Option<&str>) -> ApiResult<(u16, u8)> {
    let bad = |e: &dyn std::fmt::Display| {
        ApiError::bad(format!("{e}; the URL is /api/nodes/N/sdo/INDEX/SUB with INDEX in hex or a name"))
    };
    match dict.resolve(index, sub) {
        Ok((i, s)) => Ok((i, s.unwrap_or(0))),
        // `statusword/0`: a name that is one entry already, with its own sub.
        Err(e) => match (dict.resolve(index, None), sub.map(crate::dict::sub_index)) {
            (Ok((i, Some(named))), Some(Ok(given))) if named == given => Ok((i, named)),
            _ => Err(bad(&e)),
        },
    }
}

/// A data type as the API names it (`u16`, `i32`, `UNSIGNED16`, `str`...).
pub fn data_type(name: &str) -> ApiResult<DataType> {
    DataType::from_name(name).ok_or_else(|| {
        ApiError::bad(format!(
            "`{name}` is not a data type: use bool, i8, i16, i32, i64, u8, u16, u32, u64, f32, f64, str, bytes or a CiA 301 name (UNSIGNED16)"
        ))
    })
}

/// A value as JSON: numbers, booleans, strings; bytes as spaced hex.
pub fn to_json(v: &Value) -> serde_json::Value {
    use serde_json::json;
    match v {
        Value::Bool(b) => json!(b),
        Value::I8(x) => json!(x),
        Value::I16(x) => json!(x),
        Value::I32(x) => json!(x),
        Value::I64(x) => json!(x),
        Value::U8(x) => json!(x),
        Value::U16(x) => json!(x),
        Value::U32(x) => json!(x),
        Value::U64(x) => json!(x),
        Value::F32(x) => json!(x),
        Value::F64(x) => json!(x),
        Value::Str(s) => json!(s),
        Value::Bytes(b) => json!(hex(b)),
        Value::Unicode(u) => json!(String::from_utf16_lossy(u)),
        Value::Time { .. } => json!(v.to_string()),
    }
}

/// A JSON value as `dt`, range-checked by the type (`Value::parse`).
pub fn from_json(dt: DataType, v: &serde_json::Value) -> ApiResult<Value> {
    let text = match v {
        serde_json::Value::Number(n) if dt.num_kind().is_some() => {
            if n.is_f64() && !matches!(dt, DataType::Real32 | DataType::Real64) {
                return Err(ApiError::bad(format!(
                    "{n} is not an integer and {} takes integers: send a whole number",
                    dt.name()
                )));
            }
            n.to_string()
        }
        serde_json::Value::Bool(b) if dt == DataType::Boolean => u8::from(*b).to_string(),
        serde_json::Value::String(s) => s.clone(),
        other => {
            return Err(ApiError::bad(format!(
                "{other} is not a value of type {}: send a number for numeric types, a string for strings and hex bytes",
                dt.name()
            )));
        }
    };
    Value::parse(dt, &text).map_err(|e| {
        ApiError::bad(format!(
            "{e}: out of range or of the wrong kind for {}; send a value that fits",
            dt.name()
        ))
    })
}

/// The answer to an object read, both servers' (`GET .../sdo/...`): the
/// value decoded as `dt` (null without one) with its name, type, unit and
/// raw bytes; 400 when the bytes do not fit `dt`. `node` is the CAN
/// node-ID or the EtherCAT position; `verb` says where the bytes came
/// from in that error (`answered`, `holds`).
pub fn read_answer(
    node: impl serde::Serialize,
    (index, sub): (u16, u8),
    name: Option<String>,
    dt: Option<DataType>,
    raw: &[u8],
    verb: &str,
) -> ApiResult<serde_json::Value> {
    let value = match dt.map(|dt| Value::decode(dt, raw)) {
        Some(Ok(v)) => to_json(&v),
        Some(Err(a)) => {
            return Err(ApiError::bad(format!(
                "{index:04X}h:{sub:02X}h {verb} {} bytes, not a {}: {a}; give ?type=",
                raw.len(),
                dt.map_or("", |d| d.name())
            )));
        }
        None => serde_json::Value::Null,
    };
    Ok(serde_json::json!({"node": node, "index": format!("{index:04X}"), "sub": sub,
        "name": name, "type": dt.map(|d| d.name()), "value": value,
        "unit": drivebus_objects::unit(index, sub), "raw": hex(raw)}))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_values_are_range_checked_by_type() {
        assert_eq!(from_json(DataType::Unsigned16, &serde_json::json!(6)).unwrap(), Value::U16(6));
        assert_eq!(from_json(DataType::Integer32, &serde_json::json!(-5)).unwrap(), Value::I32(-5));
        assert_eq!(from_json(DataType::Unsigned16, &serde_json::json!("0x10")).unwrap(), Value::U16(16));
        assert!(from_json(DataType::Unsigned16, &serde_json::json!(70000)).is_err());
        assert!(from_json(DataType::Unsigned8, &serde_json::json!(-1)).is_err());
        assert!(from_json(DataType::Unsigned8, &serde_json::json!(1.5)).is_err());
        assert!(from_json(DataType::Unsigned8, &serde_json::json!([1])).is_err());
        assert_eq!(to_json(&Value::Bytes(vec![1, 0xA2])), serde_json::json!("01 A2"));
    }

    #[test]
    fn objects_by_hex_or_name() {
        let d = Dict::default();
        assert_eq!(object(&d, "6040", Some("0")).unwrap(), (0x6040, 0));
        assert_eq!(object(&d, "0x1018", Some("4")).unwrap(), (0x1018, 4));
        assert_eq!(object(&d, "statusword", Some("0")).unwrap(), (0x6041, 0));
        assert_eq!(object(&d, "statusword", None).unwrap(), (0x6041, 0));
        assert_eq!(object(&d, "identity", Some("1")).unwrap(), (0x1018, 1));
        assert_eq!(object(&d, "zz", Some("0")).unwrap_err().status, axum::http::StatusCode::BAD_REQUEST);
        assert!(object(&d, "statusword", Some("1")).is_err());
        assert!(object(&d, "6040", Some("100")).is_err());
    }
}
