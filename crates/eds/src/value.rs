//! Value texts of CiA 306 files: numbers in decimal, hex or octal, and
//! `$NODEID` expressions such as `$NODEID+0x180`.

use drivebus_od::{DataType, Value, parse_int};

/// True if the text refers to the node-ID.
pub fn is_node_relative(text: &str) -> bool {
    // Without an upper-cased copy: every value of every file goes through here.
    text.as_bytes().windows(7).any(|w| w.eq_ignore_ascii_case(b"$NODEID"))
}

/// Evaluate a value text for `dt` with `node_id` substituted, returning the
/// little-endian encoding. Integer expressions are sums and differences of
/// numbers and `$NODEID`.
///
/// Forms other tools write and read are taken as they mean them: a hex
/// number for a signed type or a REAL is the value's bit pattern
/// (`0x80000000` for INTEGER32 is −2³¹, `0x40490FDB` for REAL32 is π, as
/// canopen-python and Lely read them), and a TIME_OF_DAY or
/// TIME_DIFFERENCE may be written `DAYS MS` (Lely).
pub fn eval(text: &str, dt: DataType, node_id: u8) -> Result<Vec<u8>, String> {
    let t = text.trim();
    if let Some(bytes) = bit_pattern(t, dt)? {
        return Ok(bytes);
    }
    if dt.num_kind().is_some() && !matches!(dt, DataType::Real32 | DataType::Real64) || is_node_relative(t) {
        let v = eval_int(t, node_id)?;
        let val = if v < 0 { Value::I64(v as i64) } else { Value::U64(v as u64) };
        let val = if dt == DataType::Boolean { Value::Bool(v != 0) } else { val };
        if v < i64::MIN as i128 || v > u64::MAX as i128 {
            return Err(format!("{t:?} is out of range for {}", dt.name()));
        }
        return val.encode(dt).map_err(|_| format!("{t:?} is out of range for {}", dt.name()));
    }
    if matches!(dt, DataType::Domain) && t.is_empty() {
        return Ok(Vec::new());
    }
    let v = Value::parse(dt, text).map_err(|e| e.to_string())?;
    v.encode(dt).map_err(|e| format!("{t:?}: {e}"))
}

/// A hex number as the bit pattern of a signed or REAL type, or `DAYS MS`
/// of a time type (see [`eval`]); `None`: not such a form.
fn bit_pattern(t: &str, dt: DataType) -> Result<Option<Vec<u8>>, String> {
    use DataType as T;
    if matches!(dt, T::TimeOfDay | T::TimeDifference)
        && let Some((d, ms)) = t.split_once(char::is_whitespace)
    {
        let (d, ms) = (parse_int(d), parse_int(ms.trim()));
        return match (d, ms) {
            (Some(d @ 0..=0xFFFF), Some(ms @ 0..=0x0FFF_FFFF)) => {
                Ok(Some(Value::Time { ms: ms as u32, days: d as u16 }.encode(dt).map_err(|e| e.to_string())?))
            }
            _ => Err(format!("{t:?} is not DAYS MS for {}", dt.name())),
        };
    }
    let signed = matches!(
        dt,
        T::Integer8
            | T::Integer16
            | T::Integer24
            | T::Integer32
            | T::Integer40
            | T::Integer48
            | T::Integer56
            | T::Integer64
    );
    if !(signed || matches!(dt, T::Real32 | T::Real64)) {
        return Ok(None);
    }
    let Some(h) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) else { return Ok(None) };
    let Some(n) = dt.fixed_size() else { return Ok(None) };
    let v = u64::from_str_radix(h, 16).map_err(|_| format!("{t:?} is not a number"))?;
    if n < 8 && v >> (8 * n) != 0 {
        return Err(format!("{t:?} is out of range for {}", dt.name()));
    }
    Ok(Some(v.to_le_bytes()[..n].to_vec()))
}

fn eval_int(t: &str, node_id: u8) -> Result<i128, String> {
    if t.is_empty() {
        return Err("empty number".into());
    }
    let mut total: i128 = 0;
    let mut sign = 1i128;
    // Terms are slices of `t` between the operators (no copy per character).
    let mut start = 0;
    let flush = |term: &str, sign: i128, total: &mut i128| -> Result<(), String> {
        let s = term.trim();
        if s.is_empty() {
            return Err(format!("{t:?}: missing term"));
        }
        let v = if s.eq_ignore_ascii_case("$NODEID") {
            node_id as i128
        } else {
            parse_int(s).ok_or_else(|| format!("{t:?} is not a number"))?
        };
        *total = total.checked_add(sign * v).ok_or_else(|| format!("{t:?} overflows"))?;
        Ok(())
    };
    for (i, c) in t.char_indices() {
        // A leading '-' belongs to the first number.
        if (c == '+' || c == '-') && !(i == 0 && c == '-') {
            flush(&t[start..i], sign, &mut total)?;
            sign = if c == '-' { -1 } else { 1 };
            start = i + 1;
        }
    }
    flush(&t[start..], sign, &mut total)?;
    Ok(total)
}

/// Write a value for a file: unsigned as `0x..` hex, signed in decimal,
/// floats in shortest round-trip form, strings verbatim, octets in hex.
pub fn format(dt: DataType, bytes: &[u8]) -> String {
    match Value::decode(dt, bytes) {
        Ok(Value::Bool(b)) => (b as u8).to_string(),
        Ok(Value::U8(v)) => format!("0x{v:02X}"),
        Ok(Value::U16(v)) => format!("0x{v:04X}"),
        Ok(Value::U32(v)) => format!("0x{v:08X}"),
        Ok(Value::U64(v)) => format!("0x{v:X}"),
        Ok(Value::I8(v)) => v.to_string(),
        Ok(Value::I16(v)) => v.to_string(),
        Ok(Value::I32(v)) => v.to_string(),
        Ok(Value::I64(v)) => v.to_string(),
        Ok(Value::F32(v)) => format!("{v:?}"),
        Ok(Value::F64(v)) => format!("{v:?}"),
        Ok(Value::Str(s)) => s,
        Ok(Value::Time { ms, days }) => format!("0x{:X}", ((days as u64) << 32) | ms as u64),
        Ok(v @ Value::Unicode(_)) => v.to_string(),
        Ok(Value::Bytes(_)) | Err(_) => hex(bytes),
    }
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02X}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_id_expressions() {
        assert_eq!(eval("$NODEID+0x180", DataType::Unsigned32, 5).unwrap(), 0x185u32.to_le_bytes());
        assert_eq!(eval("0x180 + $nodeid", DataType::Unsigned32, 5).unwrap(), 0x185u32.to_le_bytes());
        assert_eq!(eval("$NODEID", DataType::Unsigned8, 127).unwrap(), [127]);
        assert_eq!(
            eval("0x80000000+$NODEID", DataType::Unsigned32, 1).unwrap(),
            0x8000_0001u32.to_le_bytes()
        );
        assert_eq!(eval("-5", DataType::Integer16, 1).unwrap(), (-5i16).to_le_bytes());
        assert_eq!(eval("010", DataType::Unsigned8, 1).unwrap(), [8]);
        assert!(eval("0x100", DataType::Unsigned8, 1).is_err());
        assert!(eval("$NODEID+", DataType::Unsigned8, 1).is_err());
        assert!(eval("abc", DataType::Unsigned8, 1).is_err());
    }

    #[test]
    fn other_tools_forms() {
        // canopen-python's sample.eds: limits of INTEGER32/64 as bit patterns.
        assert_eq!(eval("0x80000000", DataType::Integer32, 1).unwrap(), i32::MIN.to_le_bytes());
        assert_eq!(eval("0xFFFFFFFF", DataType::Integer32, 1).unwrap(), (-1i32).to_le_bytes());
        assert_eq!(eval("0xFFFFFFFFFFFFFFF6", DataType::Integer64, 1).unwrap(), (-10i64).to_le_bytes());
        assert_eq!(eval("0x7F", DataType::Integer8, 1).unwrap(), [0x7F]);
        assert!(eval("0x100", DataType::Integer8, 1).is_err());
        assert_eq!(eval("-5", DataType::Integer8, 1).unwrap(), [0xFB]);
        // Lely's co-sdev.dcf: REALs as bit patterns, times as DAYS MS.
        assert_eq!(eval("0x40490FDB", DataType::Real32, 1).unwrap(), 0x4049_0FDBu32.to_le_bytes());
        assert_eq!(
            eval("0x400921FB54442D18", DataType::Real64, 1).unwrap(),
            core::f64::consts::PI.to_le_bytes()
        );
        assert_eq!(eval("1.5", DataType::Real32, 1).unwrap(), 1.5f32.to_le_bytes());
        assert_eq!(
            eval("365 43200000", DataType::TimeOfDay, 1).unwrap(),
            [0x00, 0x2E, 0x93, 0x02, 0x6D, 0x01]
        );
        assert!(eval("365 0x10000000", DataType::TimeDifference, 1).is_err());
    }

    #[test]
    fn format_then_eval_is_identity() {
        for (dt, b) in [
            (DataType::Unsigned32, vec![1, 2, 3, 4]),
            (DataType::Integer16, vec![0xFF, 0xFF]),
            (DataType::Real32, 1.5f32.to_le_bytes().to_vec()),
            (DataType::VisibleString, b"drive".to_vec()),
            (DataType::OctetString, vec![0xAB, 0x01]),
            (DataType::Unsigned48, vec![1, 2, 3, 4, 5, 6]),
        ] {
            assert_eq!(eval(&format(dt, &b), dt, 1).unwrap(), b, "{dt:?}");
        }
    }
}
