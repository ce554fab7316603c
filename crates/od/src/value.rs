//! Typed values and their little-endian wire encoding.

use crate::types::{le_i64, le_u64};
use crate::{DataType, SdoAbort};
use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;

/// A decoded object value. Integers of 24..56 bits use the next wider Rust
/// type; the [`DataType`] that goes with the value decides the wire width.
#[derive(Clone, Debug, PartialEq)]
#[allow(missing_docs)]
pub enum Value {
    Bool(bool),
    I8(i8),
    I16(i16),
    I32(i32),
    I64(i64),
    U8(u8),
    U16(u16),
    U32(u32),
    U64(u64),
    F32(f32),
    F64(f64),
    /// VISIBLE_STRING.
    Str(String),
    /// OCTET_STRING and DOMAIN.
    Bytes(Vec<u8>),
    /// UNICODE_STRING as UTF-16 code units.
    Unicode(Vec<u16>),
    /// TIME_OF_DAY / TIME_DIFFERENCE: milliseconds (28 bits) and days.
    Time {
        /// Milliseconds after midnight (or of the difference), 28 bits.
        ms: u32,
        /// Days since 1984-01-01 (or of the difference).
        days: u16,
    },
}

impl Value {
    /// Encode for `dt`. Integer values are range-checked against the wire
    /// width (`0609 0030` if they do not fit); a value of the wrong kind for
    /// the type gives `0607 0010`.
    pub fn encode(&self, dt: DataType) -> Result<Vec<u8>, SdoAbort> {
        use DataType as T;
        let width = dt.fixed_size();
        let int_bytes = |v: i128| -> Result<Vec<u8>, SdoAbort> {
            let n = width.ok_or(SdoAbort::TYPE_MISMATCH)?;
            let bits = 8 * n as u32;
            let signed = matches!(dt.num_kind(), Some(crate::NumKind::Signed));
            let (lo, hi) = if signed {
                (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1)
            } else {
                (0, (1i128 << bits) - 1)
            };
            if v < lo || v > hi {
                return Err(SdoAbort::INVALID_VALUE);
            }
            Ok((v as u64).to_le_bytes()[..n].to_vec())
        };
        match (self, dt) {
            (Value::Bool(b), T::Boolean) => Ok(alloc::vec![*b as u8]),
            (Value::F32(x), T::Real32) => Ok(x.to_le_bytes().to_vec()),
            (Value::F64(x), T::Real64) => Ok(x.to_le_bytes().to_vec()),
            (Value::F32(x), T::Real64) => Ok((*x as f64).to_le_bytes().to_vec()),
            (Value::Str(s), T::VisibleString) => Ok(s.as_bytes().to_vec()),
            (Value::Bytes(b), T::OctetString | T::Domain | T::VisibleString) => Ok(b.clone()),
            (Value::Unicode(u), T::UnicodeString) => Ok(u.iter().flat_map(|c| c.to_le_bytes()).collect()),
            (Value::Time { ms, days }, T::TimeOfDay | T::TimeDifference) => {
                let mut v = (ms & 0x0FFF_FFFF).to_le_bytes().to_vec();
                v.extend_from_slice(&days.to_le_bytes());
                Ok(v)
            }
            (v, _) if dt.num_kind().is_some() && dt != T::Real32 && dt != T::Real64 => {
                let i = v.as_i128().ok_or(SdoAbort::TYPE_MISMATCH)?;
                if dt == T::Boolean && i > 1 {
                    return Err(SdoAbort::INVALID_VALUE);
                }
                int_bytes(i)
            }
            _ => Err(SdoAbort::TYPE_MISMATCH),
        }
    }

    /// Decode `bytes` as `dt` (length must match for fixed-size types).
    pub fn decode(dt: DataType, bytes: &[u8]) -> Result<Value, SdoAbort> {
        use DataType as T;
        crate::types::check_len(dt, bytes.len())?;
        Ok(match dt {
            T::Boolean => Value::Bool(bytes[0] != 0),
            T::Integer8 => Value::I8(bytes[0] as i8),
            T::Integer16 => Value::I16(le_i64(bytes) as i16),
            T::Integer32 => Value::I32(le_i64(bytes) as i32),
            T::Integer24 | T::Integer40 | T::Integer48 | T::Integer56 | T::Integer64 => {
                Value::I64(le_i64(bytes))
            }
            T::Unsigned8 => Value::U8(bytes[0]),
            T::Unsigned16 => Value::U16(le_u64(bytes) as u16),
            T::Unsigned32 => Value::U32(le_u64(bytes) as u32),
            T::Unsigned24 | T::Unsigned40 | T::Unsigned48 | T::Unsigned56 | T::Unsigned64 => {
                Value::U64(le_u64(bytes))
            }
            T::Real32 => Value::F32(f32::from_bits(le_u64(bytes) as u32)),
            T::Real64 => Value::F64(f64::from_bits(le_u64(bytes))),
            T::VisibleString => Value::Str(bytes.iter().map(|&b| b as char).collect()),
            T::OctetString | T::Domain => Value::Bytes(bytes.to_vec()),
            T::UnicodeString => {
                Value::Unicode(bytes.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect())
            }
            T::TimeOfDay | T::TimeDifference => Value::Time {
                ms: (le_u64(&bytes[..4]) as u32) & 0x0FFF_FFFF,
                days: le_u64(&bytes[4..6]) as u16,
            },
        })
    }

    /// The integer value, for integer and boolean variants.
    pub fn as_i128(&self) -> Option<i128> {
        Some(match *self {
            Value::Bool(b) => b as i128,
            Value::I8(v) => v as i128,
            Value::I16(v) => v as i128,
            Value::I32(v) => v as i128,
            Value::I64(v) => v as i128,
            Value::U8(v) => v as i128,
            Value::U16(v) => v as i128,
            Value::U32(v) => v as i128,
            Value::U64(v) => v as i128,
            _ => return None,
        })
    }

    /// Parse a value written by a person or an EDS file for type `dt`:
    /// decimal, `0x` hex or leading-`0` octal integers (negative allowed for
    /// signed types), floats, strings as-is, and bytes as hex (`"01 02"` or
    /// `"0102"`).
    pub fn parse(dt: DataType, text: &str) -> Result<Value, ParseValueError> {
        use DataType as T;
        let s = text.trim();
        let bad = || ParseValueError { dt, text: String::from(text) };
        match dt {
            T::VisibleString => Ok(Value::Str(String::from(text))),
            T::UnicodeString => Ok(Value::Unicode(text.encode_utf16().collect())),
            T::OctetString | T::Domain => parse_hex_bytes(s).map(Value::Bytes).ok_or_else(bad),
            T::Real32 => s.parse::<f32>().map(Value::F32).map_err(|_| bad()),
            T::Real64 => s.parse::<f64>().map(Value::F64).map_err(|_| bad()),
            T::TimeOfDay | T::TimeDifference => {
                let v = parse_int(s).ok_or_else(bad)?;
                if !(0..1 << 48).contains(&v) {
                    return Err(bad());
                }
                Ok(Value::Time { ms: (v as u64 & 0x0FFF_FFFF) as u32, days: (v >> 32) as u16 })
            }
            _ => {
                let v = parse_int(s).ok_or_else(bad)?;
                let val = match dt {
                    T::Boolean => Value::Bool(v != 0),
                    T::Integer8 => Value::I8(i8::try_from(v).map_err(|_| bad())?),
                    T::Integer16 => Value::I16(i16::try_from(v).map_err(|_| bad())?),
                    T::Integer32 => Value::I32(i32::try_from(v).map_err(|_| bad())?),
                    T::Unsigned8 => Value::U8(u8::try_from(v).map_err(|_| bad())?),
                    T::Unsigned16 => Value::U16(u16::try_from(v).map_err(|_| bad())?),
                    T::Unsigned32 => Value::U32(u32::try_from(v).map_err(|_| bad())?),
                    T::Integer24 | T::Integer40 | T::Integer48 | T::Integer56 | T::Integer64 => {
                        Value::I64(i64::try_from(v).map_err(|_| bad())?)
                    }
                    _ => Value::U64(u64::try_from(v).map_err(|_| bad())?),
                };
                // Reject values that do not fit the wire width (e.g. 2^24 for U24).
                val.encode(dt).map_err(|_| bad())?;
                Ok(val)
            }
        }
    }
}

/// Integer in decimal, `0x` hex, or leading-zero octal, optionally negative.
pub fn parse_int(s: &str) -> Option<i128> {
    let s = s.trim();
    let (neg, body) = match s.strip_prefix('-') {
        Some(r) => (true, r.trim_start()),
        None => (false, s.strip_prefix('+').unwrap_or(s)),
    };
    let v = if let Some(h) = body.strip_prefix("0x").or_else(|| body.strip_prefix("0X")) {
        i128::from_str_radix(h, 16).ok()?
    } else if body.len() > 1 && body.starts_with('0') && body.bytes().all(|b| b.is_ascii_digit()) {
        i128::from_str_radix(&body[1..], 8).ok()?
    } else {
        body.parse::<i128>().ok()?
    };
    Some(if neg { -v } else { v })
}

fn parse_hex_bytes(s: &str) -> Option<Vec<u8>> {
    let digits: String = s.chars().filter(|c| !c.is_whitespace()).collect();
    let digits = digits.strip_prefix("0x").unwrap_or(&digits);
    if !digits.len().is_multiple_of(2) {
        return None;
    }
    (0..digits.len()).step_by(2).map(|i| u8::from_str_radix(digits.get(i..i + 2)?, 16).ok()).collect()
}

/// A text that is not a valid value of its type.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseValueError {
    /// The type the text was parsed as.
    pub dt: DataType,
    /// The offending text.
    pub text: String,
}

impl fmt::Display for ParseValueError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?} is not a valid {} value", self.text, self.dt.name())
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Bool(v) => write!(f, "{v}"),
            Value::I8(v) => write!(f, "{v}"),
            Value::I16(v) => write!(f, "{v}"),
            Value::I32(v) => write!(f, "{v}"),
            Value::I64(v) => write!(f, "{v}"),
            Value::U8(v) => write!(f, "{v}"),
            Value::U16(v) => write!(f, "{v}"),
            Value::U32(v) => write!(f, "{v}"),
            Value::U64(v) => write!(f, "{v}"),
            Value::F32(v) => write!(f, "{v}"),
            Value::F64(v) => write!(f, "{v}"),
            Value::Str(s) => write!(f, "{s}"),
            Value::Bytes(b) => {
                for (i, x) in b.iter().enumerate() {
                    if i > 0 {
                        f.write_str(" ")?;
                    }
                    write!(f, "{x:02X}")?;
                }
                Ok(())
            }
            Value::Unicode(u) => {
                for c in char::decode_utf16(u.iter().copied()) {
                    write!(f, "{}", c.unwrap_or(char::REPLACEMENT_CHARACTER))?;
                }
                Ok(())
            }
            Value::Time { ms, days } => write!(f, "{days}d {ms}ms"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ALL_DATA_TYPES;

    #[test]
    fn parse_forms() {
        assert_eq!(parse_int("0x1A"), Some(26));
        assert_eq!(parse_int("017"), Some(15));
        assert_eq!(parse_int("-5"), Some(-5));
        assert_eq!(parse_int("0"), Some(0));
        assert_eq!(parse_int("x"), None);
        assert!(Value::parse(DataType::Unsigned24, "0x1000000").is_err());
        assert_eq!(
            Value::parse(DataType::Integer24, "-1").unwrap().encode(DataType::Integer24).unwrap(),
            [0xFF; 3]
        );
        assert_eq!(Value::parse(DataType::OctetString, "01 0a").unwrap(), Value::Bytes(alloc::vec![1, 10]));
    }

    #[test]
    fn encode_rejects_out_of_range() {
        assert_eq!(Value::U32(256).encode(DataType::Unsigned8), Err(SdoAbort::INVALID_VALUE));
        assert_eq!(Value::I8(-1).encode(DataType::Unsigned8), Err(SdoAbort::INVALID_VALUE));
        assert_eq!(Value::Str("x".into()).encode(DataType::Unsigned8), Err(SdoAbort::TYPE_MISMATCH));
    }

    proptest::proptest! {
        #[test]
        fn decode_encode_round_trip(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..16), pick in 0usize..25) {
            let dt = ALL_DATA_TYPES[pick];
            let bytes = match dt.fixed_size() { Some(n) => { let mut b = bytes; b.resize(n, 0); b } None => bytes };
            let mut bytes = bytes;
            if dt == DataType::Boolean { bytes[0] &= 1; }
            if matches!(dt, DataType::TimeOfDay | DataType::TimeDifference) { bytes[3] &= 0x0F; }
            if dt == DataType::UnicodeString && bytes.len() % 2 == 1 { bytes.pop(); }
            if dt == DataType::VisibleString { for b in bytes.iter_mut() { *b &= 0x7F; } }
            let v = Value::decode(dt, &bytes).unwrap();
            let back = v.encode(dt).unwrap();
            // NaN payloads survive as bits; compare bytes, not values.
            proptest::prop_assert_eq!(back, bytes);
        }
    }
}
