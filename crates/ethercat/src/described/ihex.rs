//! Intel hex (as `objcopy -O ihex` and EEPROM tools dump an SII image):
//! data records (00) at 16-bit addresses, extended segment (02) and
//! linear (04) address records, end of file (01); start address records
//! (03, 05) are accepted and ignored. Gaps read as 0xFF (erased EEPROM).

use std::fmt;

/// Why a file is not Intel hex: the 1-based line and the cause.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HexError {
    /// Line number, from 1.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for HexError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl std::error::Error for HexError {}

/// Largest image taken: 64 KiB, the largest SII EEPROM (512 Kbit).
pub const MAX_LEN: usize = 64 * 1024;

/// True if `text` looks like Intel hex (its first non-blank character is `:`).
pub fn is_hex(bytes: &[u8]) -> bool {
    bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b':')
}

fn nibble(c: u8) -> Option<u8> {
    (c as char).to_digit(16).map(|d| d as u8)
}

/// The bytes `text` describes, from address 0.
pub fn parse(text: &[u8]) -> Result<Vec<u8>, HexError> {
    let mut out: Vec<u8> = Vec::new();
    let mut base = 0usize;
    let mut ended = false;
    for (i, raw) in text.split(|b| *b == b'\n').enumerate() {
        let line = i + 1;
        let fail = |message: String| Err(HexError { line, message });
        let rec = raw.trim_ascii();
        if rec.is_empty() {
            continue;
        }
        if ended {
            return fail("data after the end-of-file record".into());
        }
        let Some(hex) = rec.strip_prefix(b":") else {
            return fail("a record must start with ':'".into());
        };
        if hex.len() % 2 != 0 || hex.len() < 10 {
            return fail(format!("{} hex digits: a record has an even number, at least 10", hex.len()));
        }
        let mut bytes = Vec::with_capacity(hex.len() / 2);
        for (k, pair) in hex.chunks_exact(2).enumerate() {
            match (nibble(pair[0]), nibble(pair[1])) {
                (Some(h), Some(l)) => bytes.push(h << 4 | l),
                _ => return fail(format!("column {}: not a hex digit", 2 + 2 * k)),
            }
        }
        let n = usize::from(bytes[0]);
        if bytes.len() != n + 5 {
            return fail(format!("byte count {n} but {} data bytes", bytes.len() - 5));
        }
        if bytes.iter().fold(0u8, |a, b| a.wrapping_add(*b)) != 0 {
            return fail("checksum does not match".into());
        }
        let addr = usize::from(u16::from_be_bytes([bytes[1], bytes[2]]));
        let data = &bytes[4..4 + n];
        match bytes[3] {
            0x00 => {
                let at = base + addr;
                if at + n > MAX_LEN {
                    return fail(format!("data at {at:#x} beyond {MAX_LEN} bytes"));
                }
                if out.len() < at + n {
                    out.resize(at + n, 0xFF);
                }
                out[at..at + n].copy_from_slice(data);
            }
            0x01 => ended = true,
            0x02 | 0x04 if n == 2 => {
                let v = usize::from(u16::from_be_bytes([data[0], data[1]]));
                base = if bytes[3] == 0x02 { v << 4 } else { v << 16 };
            }
            0x03 | 0x05 => {}
            t @ (0x02 | 0x04) => return fail(format!("record type {t:02X} needs 2 data bytes, has {n}")),
            t => return fail(format!("unknown record type {t:02X}")),
        }
    }
    if !ended {
        return Err(HexError {
            line: text.split(|b| *b == b'\n').count(),
            message: "no end-of-file record".into(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_data_gaps_and_extended_addresses() {
        let t = b":0400000001020304F2\r\n:020006000506ED\n:00000001FF\n";
        assert_eq!(parse(t).unwrap(), [1, 2, 3, 4, 0xFF, 0xFF, 5, 6]);
        let seg = b":020000020001FB\n:01000000AA55\n:00000001FF\n";
        let v = parse(seg).unwrap();
        assert_eq!((v.len(), v[16]), (17, 0xAA), "segment base 1 << 4");
    }

    #[test]
    fn errors_name_line_and_cause() {
        let e = |t: &[u8]| parse(t).unwrap_err();
        assert_eq!(e(b":0400000001020304F3\n").line, 1);
        assert!(e(b":0400000001020304F3\n").message.contains("checksum"));
        let x = e(b":00000001FF\n:00000001FF\n");
        assert_eq!((x.line, x.message.as_str()), (2, "data after the end-of-file record"));
        assert!(e(b"\n:04000000010203G4F2\n").to_string().starts_with("line 2: column 16"));
        assert!(e(b":0500000001020304F2\n").message.contains("byte count 5"));
        assert!(e(b":0400000001020304F2\n").message.contains("end-of-file"));
        assert!(e(b":00000007F9\n").message.contains("unknown record type 07"));
        assert!(e(b":02000004FFFFFC\n:01000000AA55\n:00000001FF\n").message.contains("beyond"));
        assert!(e(b"0400\n").message.contains("':'"));
    }
}
