//! candump log format (`candump -l` / `-L`): writer and parser.
//!
//! One frame per line: `(SECONDS.MICROS) IFACE ID#DATA`, e.g.
//! `(1700000000.000000) can0 601#4000100000000000`.
//!
//! - Standard ids are 3 hex digits, extended ids 8 (as can-utils prints them).
//! - Data is two uppercase hex digits per byte, no separator.
//! - A remote frame is `ID#R` followed by its DLC when non-zero (`705#R1`,
//!   `080#R`): what can-utils' `sprint_canframe` prints since it gained DLC
//!   output for RTR frames. The parser also accepts `#R0`, lowercase hex and
//!   `.` between data bytes, as can-utils' `parse_canframe` does.
//! - CAN FD (`ID##F...`) is rejected: this bus is classic CAN.

use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;
use drivebus_can::{CanId, Frame, Instant};

/// One frame as the bus saw it, for the log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogEntry {
    /// When receivers got it (end of frame, plus any injected delay).
    pub time: Instant,
    /// The frame as received (after silent corruption, if any).
    pub frame: Frame,
}

/// Writes one candump line (no newline) for `frame` at simulated `time`,
/// stamped `epoch_us + time` in microseconds.
pub fn write_line(
    out: &mut impl fmt::Write,
    epoch_us: u64,
    iface: &str,
    time: Instant,
    frame: &Frame,
) -> fmt::Result {
    let us = epoch_us.saturating_add(time.as_micros());
    write!(out, "({}.{:06}) {} ", us / 1_000_000, us % 1_000_000, iface)?;
    write_frame(out, frame)
}

/// Writes `ID#DATA` / `ID#R[len]` for one frame.
pub fn write_frame(out: &mut impl fmt::Write, frame: &Frame) -> fmt::Result {
    match frame.id() {
        CanId::Standard(id) => write!(out, "{id:03X}#")?,
        CanId::Extended(id) => write!(out, "{id:08X}#")?,
    }
    if frame.is_rtr() {
        out.write_char('R')?;
        if !frame.is_empty() {
            write!(out, "{}", frame.len())?;
        }
        return Ok(());
    }
    for b in frame.data() {
        write!(out, "{b:02X}")?;
    }
    Ok(())
}

/// A parsed candump line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CandumpRecord {
    /// Whole seconds of the timestamp.
    pub secs: u64,
    /// Microseconds of the timestamp, `0..1_000_000`.
    pub micros: u32,
    /// Interface name (`can0`).
    pub interface: String,
    /// The frame.
    pub frame: Frame,
}

impl CandumpRecord {
    /// The timestamp in microseconds (saturating).
    pub fn timestamp_us(&self) -> u64 {
        self.secs.saturating_mul(1_000_000).saturating_add(u64::from(self.micros))
    }
    /// Simulated time of this record for a log stamped with `epoch_us`;
    /// `None` if it lies before the epoch.
    pub fn instant(&self, epoch_us: u64) -> Option<Instant> {
        self.timestamp_us().checked_sub(epoch_us).map(Instant::from_micros)
    }
}

/// What is wrong with a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParseErrorKind {
    /// A specific character was expected.
    Expected(char),
    /// The timestamp is not `digits.6digits` or overflows.
    BadTimestamp,
    /// No interface name.
    MissingInterface,
    /// The identifier is not 3 or 8 hex digits, or out of range.
    BadId,
    /// `##`: CAN FD frames are not supported.
    CanFd,
    /// A data byte is not two hex digits.
    BadData,
    /// More than 8 data bytes.
    TooLong,
    /// The DLC after `R` is not a digit 0..=8.
    BadRtrLength,
    /// Characters after the frame.
    Trailing,
}

/// A candump parse error with its 1-based line and byte column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParseError {
    /// 1-based line number (1 for [`parse_line`]).
    pub line: usize,
    /// 1-based byte column where the problem starts.
    pub column: usize,
    /// What is wrong.
    pub kind: ParseErrorKind,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}, column {}: ", self.line, self.column)?;
        match self.kind {
            ParseErrorKind::Expected(c) => write!(f, "expected '{c}'"),
            ParseErrorKind::BadTimestamp => f.write_str("bad timestamp"),
            ParseErrorKind::MissingInterface => f.write_str("missing interface name"),
            ParseErrorKind::BadId => f.write_str("bad CAN identifier"),
            ParseErrorKind::CanFd => f.write_str("CAN FD frames are not supported"),
            ParseErrorKind::BadData => f.write_str("bad data byte"),
            ParseErrorKind::TooLong => f.write_str("more than 8 data bytes"),
            ParseErrorKind::BadRtrLength => f.write_str("bad remote frame length"),
            ParseErrorKind::Trailing => f.write_str("unexpected characters after the frame"),
        }
    }
}

impl core::error::Error for ParseError {}

struct Cursor<'a> {
    s: &'a [u8],
    pos: usize,
}

impl Cursor<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.pos).copied()
    }
    fn err(&self, kind: ParseErrorKind) -> ParseError {
        ParseError { line: 1, column: self.pos + 1, kind }
    }
    fn expect(&mut self, c: u8) -> Result<(), ParseError> {
        if self.peek() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.err(ParseErrorKind::Expected(char::from(c))))
        }
    }
    fn take_while(&mut self, f: impl Fn(u8) -> bool) -> &[u8] {
        let start = self.pos;
        while self.peek().is_some_and(&f) {
            self.pos += 1;
        }
        &self.s[start..self.pos]
    }
    fn skip_spaces(&mut self) {
        self.take_while(|c| c == b' ' || c == b'\t');
    }
}

fn hex(c: u8) -> Option<u8> {
    char::from(c).to_digit(16).map(|d| d as u8)
}

fn decimal(digits: &[u8]) -> Option<u64> {
    digits.iter().try_fold(0u64, |acc, &c| acc.checked_mul(10)?.checked_add(u64::from(c.checked_sub(b'0')?)))
}

/// Parses one candump line (leading/trailing blanks allowed).
pub fn parse_line(line: &str) -> Result<CandumpRecord, ParseError> {
    let mut c = Cursor { s: line.as_bytes(), pos: 0 };
    c.skip_spaces();
    c.expect(b'(')?;
    let ts_start = c.pos;
    let bad_ts = ParseError { line: 1, column: ts_start + 1, kind: ParseErrorKind::BadTimestamp };
    let sec_digits = c.take_while(|b| b.is_ascii_digit());
    let secs = if sec_digits.is_empty() { None } else { decimal(sec_digits) };
    if c.peek() != Some(b'.') {
        return Err(bad_ts);
    }
    c.pos += 1;
    let frac = c.take_while(|b| b.is_ascii_digit());
    // candump always prints exactly six fractional digits.
    let (secs, micros) = match (secs, frac.len()) {
        (Some(s), 6) => (s, decimal(frac).unwrap_or(0) as u32),
        _ => return Err(bad_ts),
    };
    c.expect(b')')?;
    if c.peek() != Some(b' ') && c.peek() != Some(b'\t') {
        return Err(c.err(ParseErrorKind::Expected(' ')));
    }
    c.skip_spaces();
    let iface = c.take_while(|b| !b.is_ascii_whitespace());
    if iface.is_empty() {
        return Err(c.err(ParseErrorKind::MissingInterface));
    }
    let interface = String::from_utf8_lossy(iface).into_owned();
    if c.peek().is_none() {
        return Err(c.err(ParseErrorKind::Expected(' ')));
    }
    c.skip_spaces();
    let frame = parse_frame_at(&mut c)?;
    c.skip_spaces();
    if c.peek().is_some_and(|b| b != b'\r' && b != b'\n') {
        return Err(c.err(ParseErrorKind::Trailing));
    }
    Ok(CandumpRecord { secs, micros, interface, frame })
}

/// Parses `ID#DATA` / `ID#R[len]` alone (the `cansend` syntax).
pub fn parse_frame(text: &str) -> Result<Frame, ParseError> {
    let mut c = Cursor { s: text.as_bytes(), pos: 0 };
    let f = parse_frame_at(&mut c)?;
    if c.peek().is_some() {
        return Err(c.err(ParseErrorKind::Trailing));
    }
    Ok(f)
}

fn parse_frame_at(c: &mut Cursor<'_>) -> Result<Frame, ParseError> {
    let id_start = c.pos;
    let digits = c.take_while(|b| b.is_ascii_hexdigit());
    let value = digits.iter().try_fold(0u32, |acc, &d| acc.checked_mul(16)?.checked_add(u32::from(hex(d)?)));
    let n_digits = digits.len();
    let id = match (n_digits, value) {
        (3, Some(v)) => u16::try_from(v).ok().and_then(CanId::standard),
        (8, Some(v)) => CanId::extended(v),
        _ => None,
    };
    let bad_id = ParseError { line: 1, column: id_start + 1, kind: ParseErrorKind::BadId };
    if c.peek() != Some(b'#') && n_digits != 3 && n_digits != 8 {
        return Err(bad_id);
    }
    c.expect(b'#')?;
    let id = id.ok_or(bad_id)?;
    match c.peek() {
        Some(b'#') => return Err(c.err(ParseErrorKind::CanFd)),
        Some(b'R' | b'r') => {
            c.pos += 1;
            let len = match c.peek() {
                Some(d @ b'0'..=b'8') => {
                    c.pos += 1;
                    d - b'0'
                }
                Some(b'9') => return Err(c.err(ParseErrorKind::BadRtrLength)),
                _ => 0,
            };
            return Frame::try_remote(id, len).map_err(|_| c.err(ParseErrorKind::BadRtrLength));
        }
        _ => {}
    }
    let mut data = [0u8; 8];
    let mut n = 0;
    while let (Some(hi), Some(lo)) = (c.peek().and_then(hex), c.s.get(c.pos + 1).copied()) {
        let Some(lo) = hex(lo) else {
            return Err(ParseError { column: c.pos + 2, ..c.err(ParseErrorKind::BadData) });
        };
        if n == data.len() {
            return Err(c.err(ParseErrorKind::TooLong));
        }
        data[n] = hi << 4 | lo;
        n += 1;
        c.pos += 2;
        // can-utils allows a '.' between bytes for readability.
        if c.peek() == Some(b'.') && c.s.get(c.pos + 1).copied().and_then(hex).is_some() {
            c.pos += 1;
        }
    }
    if c.peek().is_some_and(|b| b.is_ascii_hexdigit()) {
        return Err(c.err(ParseErrorKind::BadData));
    }
    Frame::try_new(id, &data[..n]).map_err(|_| c.err(ParseErrorKind::TooLong))
}

/// Parses a whole log; blank lines are skipped, errors carry their line number.
pub fn parse_log(text: &str) -> impl Iterator<Item = Result<CandumpRecord, ParseError>> + '_ {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| parse_line(l).map_err(|e| ParseError { line: i + 1, ..e }))
}

/// Parses a whole log, stopping at the first error.
pub fn parse_log_all(text: &str) -> Result<Vec<CandumpRecord>, ParseError> {
    parse_log(text).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::string::ToString;

    fn line(f: &Frame, t: Instant) -> String {
        let mut s = String::new();
        write_line(&mut s, 1_700_000_000_000_000, "can0", t, f).unwrap();
        s
    }

    #[test]
    fn exact_lines() {
        let sdo = Frame::new(0x601, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
        assert_eq!(line(&sdo, Instant::ZERO), "(1700000000.000000) can0 601#4000100000000000");
        assert_eq!(
            line(&Frame::remote(0x705, 1), Instant::from_micros(1_234_567)),
            "(1700000001.234567) can0 705#R1"
        );
        assert_eq!(line(&Frame::remote(0x080, 0), Instant::ZERO), "(1700000000.000000) can0 080#R");
        let ext = Frame::try_new(CanId::Extended(0x18FF50E5), &[1, 2]).unwrap();
        assert_eq!(line(&ext, Instant::from_nanos(999)), "(1700000000.000000) can0 18FF50E5#0102");
        assert_eq!(line(&Frame::new(0x080, &[]), Instant::ZERO), "(1700000000.000000) can0 080#");
    }

    #[test]
    fn errors_have_columns() {
        let e = parse_line("(1.000000) can0 6010#00").unwrap_err();
        assert_eq!((e.column, e.kind), (17, ParseErrorKind::BadId));
        let e = parse_line("(1.00000) can0 601#00").unwrap_err();
        assert_eq!((e.column, e.kind), (2, ParseErrorKind::BadTimestamp));
        let e = parse_line("(1.000000) can0 601#0G").unwrap_err();
        assert_eq!((e.column, e.kind), (22, ParseErrorKind::BadData));
        let e = parse_line("(1.000000) can0 601#000").unwrap_err();
        assert_eq!((e.column, e.kind), (23, ParseErrorKind::BadData));
        let e = parse_line("(1.000000) can0 601#000000000000000000").unwrap_err();
        assert_eq!((e.column, e.kind), (37, ParseErrorKind::TooLong));
        let e = parse_line("(1.000000) can0 601##100").unwrap_err();
        assert_eq!(e.kind, ParseErrorKind::CanFd);
        let e = parse_line("(1.000000) can0 800#").unwrap_err();
        assert_eq!(e.kind, ParseErrorKind::BadId);
        let e = parse_line("(1.000000) can0 705#R9").unwrap_err();
        assert_eq!(e.kind, ParseErrorKind::BadRtrLength);
        let e = parse_line("(1.000000) can0 705#12 x").unwrap_err();
        assert_eq!((e.column, e.kind), (24, ParseErrorKind::Trailing));
        let e = parse_line("(1.000000)").unwrap_err();
        assert_eq!(e.kind, ParseErrorKind::Expected(' '));
        let errs: Vec<_> = parse_log("\n(1.000000) can0 123#\nbad\n").collect();
        assert!(errs[0].is_ok());
        assert_eq!(errs[1].as_ref().unwrap_err().line, 3);
        assert_eq!(errs[1].as_ref().unwrap_err().to_string(), "line 3, column 1: expected '('");
    }

    #[test]
    fn accepts_can_utils_variants() {
        let r = parse_line("  (0.000001) vcan0 7e5#r0  ").unwrap();
        assert_eq!(r.frame, Frame::remote(0x7E5, 0));
        assert_eq!(r.interface, "vcan0");
        assert_eq!(r.timestamp_us(), 1);
        let r = parse_line("(0.000001) can0 123#de.ad.BE.ef").unwrap();
        assert_eq!(r.frame.data(), &[0xDE, 0xAD, 0xBE, 0xEF]);
    }
}
