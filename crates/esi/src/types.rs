//! ETG.2000 names of the CoE data types, and how values are spelled in an
//! ESI file: `#x` hex, decimal, or hex-encoded little-endian bytes
//! (`DefaultData`).

use drivebus_od::{DataType, NumKind, le_i64, le_u64};

/// The ETG.2000 (IEC 61131-3 style) name of a fixed-size CoE base type,
/// as ESI files and SDO Information name them (ETG.1000.6 Table 64).
/// Strings, octet strings and DOMAIN are named per object by
/// [`type_name`], since their size is part of the name.
pub fn base_name(dt: DataType) -> Option<&'static str> {
    use DataType::*;
    Some(match dt {
        Boolean => "BOOL",
        Integer8 => "SINT",
        Integer16 => "INT",
        Integer24 => "INT24",
        Integer32 => "DINT",
        Integer40 => "INT40",
        Integer48 => "INT48",
        Integer56 => "INT56",
        Integer64 => "LINT",
        Unsigned8 => "USINT",
        Unsigned16 => "UINT",
        Unsigned24 => "UINT24",
        Unsigned32 => "UDINT",
        Unsigned40 => "UINT40",
        Unsigned48 => "UINT48",
        Unsigned56 => "UINT56",
        Unsigned64 => "ULINT",
        Real32 => "REAL",
        Real64 => "LREAL",
        TimeOfDay => "TIME_OF_DAY",
        TimeDifference => "TIME_DIFFERENCE",
        VisibleString | OctetString | UnicodeString | Domain => return None,
    })
}

/// The name of a value's type in an ESI file: the base name, or for
/// variable-size types a sized name: `STRING(n)` (VISIBLE_STRING),
/// `ARRAY [0..n-1] OF BYTE` (OCTET_STRING, the form TwinCAT writes),
/// `UNICODE_STRING(n)` (n characters) and `DOMAIN`.
pub fn type_name(dt: DataType, len: usize) -> String {
    match (base_name(dt), dt) {
        (Some(n), _) => n.to_string(),
        (None, DataType::VisibleString) => format!("STRING({len})"),
        (None, DataType::OctetString) => octet_array_name(len),
        (None, DataType::UnicodeString) => format!("UNICODE_STRING({})", len / 2),
        _ => "DOMAIN".to_string(),
    }
}

/// `ARRAY [0..n-1] OF BYTE`. An empty octet string is written
/// `ARRAY [0..0] OF BYTE` with bit size 0 (there is no `[0..-1]`).
pub fn octet_array_name(len: usize) -> String {
    format!("ARRAY [0..{}] OF BYTE", len.saturating_sub(1))
}

/// The data type and byte length a type name stands for (inverse of
/// [`type_name`]). Also accepts `BIT`/`BOOLEAN` spellings seen in files.
pub fn parse_type_name(name: &str, bit_size: Option<u32>) -> Option<(DataType, usize)> {
    use DataType::*;
    let n = name.trim();
    let bytes_of = |bits: Option<u32>| bits.map_or(0, |b| (b as usize).div_ceil(8));
    if let Some(dt) = drivebus_od::ALL_DATA_TYPES.iter().copied().find(|t| base_name(*t) == Some(n)) {
        return Some((dt, dt.fixed_size().unwrap_or(0)));
    }
    if n == "BIT" || n == "BOOLEAN" {
        return Some((Boolean, 1));
    }
    if n == "BYTE" {
        return Some((Unsigned8, 1));
    }
    if n == "WORD" {
        return Some((Unsigned16, 2));
    }
    if n == "DWORD" {
        return Some((Unsigned32, 4));
    }
    if n == "DOMAIN" {
        return Some((Domain, bytes_of(bit_size)));
    }
    let sized = |prefix: &str| -> Option<usize> {
        n.strip_prefix(prefix)?.strip_prefix('(')?.strip_suffix(')')?.trim().parse().ok()
    };
    if let Some(len) = sized("STRING") {
        return Some((VisibleString, len));
    }
    if let Some(chars) = sized("UNICODE_STRING") {
        // The bit size keeps an odd byte count the name cannot.
        return Some((UnicodeString, bit_size.map_or(chars.saturating_mul(2), |b| b as usize / 8)));
    }
    if let Some(len) = sized("OCTET_STRING") {
        return Some((OctetString, len));
    }
    if let Some(rest) = n.strip_prefix("ARRAY [0..").and_then(|r| r.strip_suffix("] OF BYTE")) {
        let hi: usize = rest.trim().parse().ok()?;
        // ARRAY [0..0] is one byte, or none when the bit size says so.
        let len = if bit_size == Some(0) { 0 } else { hi.checked_add(1)? };
        return Some((OctetString, len));
    }
    None
}

/// Bits a value of `dt` with `len` bytes takes (BOOLEAN: 1).
pub fn bit_size(dt: DataType, len: usize) -> u32 {
    if dt == DataType::Boolean { 1 } else { u32::try_from(len.saturating_mul(8)).unwrap_or(u32::MAX) }
}

/// How a value is written in `Info`: a number (`DefaultValue`, `MinValue`,
/// `MaxValue`), a string (`DefaultString`) or bytes (`DefaultData`,
/// `MinData`, `MaxData`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueForm {
    /// Integers and BOOLEAN: `#x` hex for unsigned, decimal for signed.
    Number,
    /// VISIBLE_STRING whose bytes are all printable ASCII.
    String,
    /// Everything else, little-endian hex bytes.
    Data,
}

/// The form a value of `dt` is written in.
pub fn value_form(dt: DataType, bytes: &[u8]) -> ValueForm {
    match dt.num_kind() {
        Some(NumKind::Signed | NumKind::Unsigned)
            if dt.fixed_size() == Some(bytes.len()) && (dt != DataType::Boolean || bytes[0] <= 1) =>
        {
            ValueForm::Number
        }
        _ if dt == DataType::VisibleString && bytes.iter().all(|b| (0x20..=0x7E).contains(b)) => {
            ValueForm::String
        }
        _ => ValueForm::Data,
    }
}

/// A number as ESI writes it: unsigned types as `#x` with the type's
/// width in digits (`#x00060192`), signed types and BOOLEAN in decimal.
pub fn format_number(dt: DataType, bytes: &[u8]) -> String {
    match dt.num_kind() {
        Some(NumKind::Signed) => le_i64(bytes).to_string(),
        _ if dt == DataType::Boolean => le_u64(bytes).to_string(),
        _ => format!("#x{:0width$X}", le_u64(bytes), width = 2 * bytes.len().max(1)),
    }
}

/// Parse an ETG.2000 `HexDecValue` (`#x1A3`, `0x1A3`, `419`, `-5`) into
/// the little-endian encoding of `dt`; `None` if it is not a number or
/// does not fit.
pub fn parse_number(dt: DataType, text: &str) -> Option<Vec<u8>> {
    let n = dt.fixed_size()?;
    let v = parse_hex_dec(text)?;
    let bits = 8 * n as u32;
    let fits = match dt.num_kind()? {
        NumKind::Signed => v >= -(1i128 << (bits - 1)) && v < (1i128 << (bits - 1)),
        NumKind::Unsigned if dt == DataType::Boolean => (0..=1).contains(&v),
        NumKind::Unsigned => v >= 0 && v < (1i128 << bits),
        NumKind::Float => false,
    };
    fits.then(|| (v as u64).to_le_bytes()[..n].to_vec())
}

/// An integer written `#x..`, `0x..` or in decimal (optionally negative).
pub fn parse_hex_dec(text: &str) -> Option<i128> {
    let t = text.trim();
    let (neg, t) = match t.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, t),
    };
    let hex = t.strip_prefix("#x").or_else(|| t.strip_prefix("#X")).or_else(|| t.strip_prefix("0x"));
    let hex = hex.or_else(|| t.strip_prefix("0X"));
    let v = match hex {
        Some(h) if !h.is_empty() && h.len() <= 32 => i128::from_str_radix(h, 16).ok()?,
        Some(_) => return None,
        None if !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit()) && t.len() <= 38 => t.parse().ok()?,
        None => return None,
    };
    Some(if neg { -v } else { v })
}

/// `#x` and the value's hex digits (no padding): `#x1A3`.
pub fn hex(v: u64) -> String {
    format!("#x{v:X}")
}

/// `#x` and four hex digits, as indices are written: `#x1C12`.
pub fn hex_index(v: u16) -> String {
    format!("#x{v:04X}")
}

/// Bytes as upper-case hex, in order (ETG.2000 `hexBinary`).
pub fn hex_bytes(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02X}")).collect()
}

/// Parse `hexBinary` text; `None` on odd length or a non-hex digit.
pub fn parse_hex_bytes(text: &str) -> Option<Vec<u8>> {
    let t: Vec<u8> = text.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    if !t.len().is_multiple_of(2) {
        return None;
    }
    t.chunks(2)
        .map(|c| {
            let s = std::str::from_utf8(c).ok()?;
            u8::from_str_radix(s, 16).ok()
        })
        .collect()
}

/// Characters XML 1.0 cannot carry (C0 controls other than tab, newline
/// and carriage return, and the non-characters U+FFFE/U+FFFF), replaced by
/// U+FFFD so any dictionary name gives a well-formed file. Carriage
/// returns are replaced too: a parser turns them into newlines.
pub fn xml_safe(text: &str) -> std::borrow::Cow<'_, str> {
    let bad = |c: char| matches!(c, '\u{0}'..='\u{8}' | '\u{B}' | '\u{C}' | '\r' | '\u{E}'..='\u{1F}' | '\u{FFFE}' | '\u{FFFF}');
    if text.chars().any(bad) {
        text.chars().map(|c| if bad(c) { '\u{FFFD}' } else { c }).collect::<String>().into()
    } else {
        text.into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_od::ALL_DATA_TYPES;

    #[test]
    fn names_round_trip_for_every_type() {
        for dt in ALL_DATA_TYPES {
            let len = dt.fixed_size().unwrap_or(5);
            let name = type_name(dt, len);
            let (back, blen) = parse_type_name(&name, Some(bit_size(dt, len))).unwrap();
            assert_eq!((back, blen), (dt, len), "{name}");
        }
        assert_eq!(type_name(DataType::Unsigned32, 4), "UDINT");
        assert_eq!(type_name(DataType::OctetString, 4), "ARRAY [0..3] OF BYTE");
        assert_eq!(parse_type_name("ARRAY [0..0] OF BYTE", Some(0)), Some((DataType::OctetString, 0)));
        assert_eq!(type_name(DataType::VisibleString, 4), "STRING(4)");
        assert_eq!(parse_type_name("STRING(4)", Some(32)), Some((DataType::VisibleString, 4)));
        assert_eq!(parse_type_name("FOO", None), None);
    }

    #[test]
    fn numbers_as_esi_writes_them() {
        assert_eq!(format_number(DataType::Unsigned32, &0x60192u32.to_le_bytes()), "#x00060192");
        assert_eq!(format_number(DataType::Integer16, &(-5i16).to_le_bytes()), "-5");
        assert_eq!(format_number(DataType::Boolean, &[1]), "1");
        assert_eq!(parse_number(DataType::Unsigned32, "#x1A3"), Some(0x1A3u32.to_le_bytes().to_vec()));
        assert_eq!(parse_number(DataType::Unsigned16, "0x1600"), Some(vec![0x00, 0x16]));
        assert_eq!(parse_number(DataType::Integer8, "-128"), Some(vec![0x80]));
        assert_eq!(parse_number(DataType::Integer8, "128"), None);
        assert_eq!(parse_number(DataType::Unsigned8, "-1"), None);
        assert_eq!(parse_number(DataType::Unsigned64, "#xFFFFFFFFFFFFFFFF"), Some(vec![0xFF; 8]));
        assert_eq!(parse_number(DataType::Real32, "1"), None);
        assert_eq!(parse_hex_dec("#x"), None);
        assert_eq!(parse_hex_dec("12a"), None);
        for dt in ALL_DATA_TYPES
            .iter()
            .filter(|t| matches!(t.num_kind(), Some(NumKind::Signed | NumKind::Unsigned)))
        {
            let n = dt.fixed_size().unwrap();
            for b in [vec![0u8; n], vec![0xFF; n], (1..=n as u8).collect()] {
                let b = if *dt == DataType::Boolean { vec![b[0] & 1] } else { b };
                assert_eq!(parse_number(*dt, &format_number(*dt, &b)), Some(b.clone()), "{dt:?}");
            }
        }
    }

    #[test]
    fn forms_and_hex_bytes() {
        assert_eq!(value_form(DataType::VisibleString, b"iPOS"), ValueForm::String);
        assert_eq!(value_form(DataType::VisibleString, b"a\x01"), ValueForm::Data);
        assert_eq!(value_form(DataType::Real32, &[0; 4]), ValueForm::Data);
        assert_eq!(value_form(DataType::Unsigned8, &[0; 2]), ValueForm::Data, "wrong length stays exact");
        assert_eq!(value_form(DataType::Boolean, &[2]), ValueForm::Data, "only 0 and 1 are BOOL numbers");
        assert_eq!(hex_bytes(&[0x78, 0x56, 0x0A]), "78560A");
        assert_eq!(parse_hex_bytes("78560a"), Some(vec![0x78, 0x56, 0x0A]));
        assert_eq!(parse_hex_bytes("785"), None);
        assert_eq!(parse_hex_bytes("zz"), None);
        assert_eq!(xml_safe("a\u{1}b\tc\r"), "a\u{FFFD}b\tc\u{FFFD}");
        assert_eq!(hex_index(0x1C12), "#x1C12");
        assert_eq!(hex(0x1A3), "#x1A3");
    }
}
