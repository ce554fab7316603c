//! socketcand ASCII protocol: message framing, parsing and formatting.
//!
//! Every message is a `<`…`>` token without newline. Bytes outside tokens
//! are garbage and skipped; a token that grows past [`MAX_MESSAGE`] without
//! its `>` is discarded, so buffers stay bounded whatever the peer sends.

use std::fmt::Write as _;

use drivebus_can::{CanId, Frame};

/// Longest message kept while waiting for its `>`; the longest valid one
/// (`< frame 1FFFFFFF SECS.USECS 16 hex >`) is under 64 bytes.
pub const MAX_MESSAGE: usize = 256;

/// Splits a byte stream into `<`…`>` messages, tolerating reads that cut
/// messages anywhere.
#[derive(Debug, Default)]
pub struct Splitter {
    buf: Vec<u8>,
    garbage: u64,
}

impl Splitter {
    /// An empty splitter.
    pub fn new() -> Self {
        Splitter { buf: Vec::with_capacity(MAX_MESSAGE * 2), garbage: 0 }
    }

    /// Bytes skipped as garbage so far.
    pub fn garbage(&self) -> u64 {
        self.garbage
    }

    /// Feeds received bytes and calls `f` with the inside of every complete
    /// message (between `<` and `>`).
    pub fn feed(&mut self, mut data: &[u8], mut f: impl FnMut(&[u8])) {
        while !data.is_empty() {
            if self.buf.is_empty() {
                // Fast path: whole messages straight from the read buffer.
                match data.iter().position(|&b| b == b'<') {
                    None => {
                        self.garbage += data.len() as u64;
                        return;
                    }
                    Some(start) => {
                        self.garbage += start as u64;
                        data = &data[start..];
                    }
                }
                match find_end(data) {
                    End::Close(end) => {
                        f(&data[1..end]);
                        data = &data[end + 1..];
                    }
                    End::Restart(next) => {
                        self.garbage += next as u64;
                        data = &data[next..];
                    }
                    End::Open => {
                        let keep = data.len().min(MAX_MESSAGE);
                        if data.len() > MAX_MESSAGE {
                            self.garbage += data.len() as u64;
                        } else {
                            self.buf.extend_from_slice(&data[..keep]);
                        }
                        return;
                    }
                }
            } else {
                // Complete the pending message with as much as fits.
                let room = MAX_MESSAGE.saturating_sub(self.buf.len());
                let take = match data.iter().position(|&b| b == b'>' || b == b'<') {
                    Some(i) if i < room => i + 1,
                    _ => room.min(data.len()),
                };
                self.buf.extend_from_slice(&data[..take]);
                data = &data[take..];
                match self.buf.last() {
                    Some(b'>') => {
                        f(&self.buf[1..self.buf.len() - 1]);
                        self.buf.clear();
                    }
                    Some(b'<') if self.buf.len() > 1 => {
                        // A new message starts: the pending one was garbage.
                        self.garbage += self.buf.len() as u64 - 1;
                        self.buf.clear();
                        self.buf.push(b'<');
                    }
                    _ if self.buf.len() >= MAX_MESSAGE => {
                        self.garbage += self.buf.len() as u64;
                        self.buf.clear();
                    }
                    _ => {}
                }
            }
        }
    }
}

enum End {
    /// `>` at this index.
    Close(usize),
    /// Another `<` at this index before any `>`.
    Restart(usize),
    /// Not terminated yet.
    Open,
}

fn find_end(data: &[u8]) -> End {
    for (i, &b) in data.iter().enumerate().skip(1) {
        match b {
            b'>' => return End::Close(i),
            b'<' => return End::Restart(i),
            _ => {}
        }
    }
    End::Open
}

/// A parsed socketcand message (both directions).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Message<'a> {
    /// `< hi >`
    Hi,
    /// `< ok >`
    Ok,
    /// `< echo >`
    Echo,
    /// `< open NAME >`
    Open(&'a str),
    /// `< rawmode >`
    RawMode,
    /// `< send ID DLC B… >` with a valid frame.
    Send(Frame),
    /// `< frame ID SECS.USECS DATA >`: the frame and its timestamp in µs.
    Frame(Frame, u64),
    /// `< error … >`
    Error(&'a str),
    /// Anything else, or a `send`/`frame` that failed the strict checks.
    Invalid(&'a str),
}

/// Parses the inside of one message.
pub fn parse(msg: &[u8]) -> Message<'_> {
    let Ok(text) = std::str::from_utf8(msg) else { return Message::Invalid("<non-UTF-8>") };
    let mut words = text.split_ascii_whitespace();
    let cmd = words.next().unwrap_or("");
    let parsed = match cmd {
        "hi" if words.next().is_none() => Some(Message::Hi),
        "ok" if words.next().is_none() => Some(Message::Ok),
        "echo" if words.next().is_none() => Some(Message::Echo),
        "rawmode" if words.next().is_none() => Some(Message::RawMode),
        "open" => match (words.next(), words.next()) {
            (Some(name), None) => Some(Message::Open(name)),
            _ => None,
        },
        "error" => Some(Message::Error(text.trim().strip_prefix("error").unwrap_or("").trim())),
        "send" => parse_send(words).map(Message::Send),
        "frame" => parse_frame(words).map(|(f, t)| Message::Frame(f, t)),
        _ => None,
    };
    parsed.unwrap_or(Message::Invalid(text.trim()))
}

/// ID width decides the format, as socketcand and python-can both do:
/// exactly 3 hex digits is standard, any other length (normally 8) extended.
fn parse_id(s: &str) -> Option<CanId> {
    if s.is_empty() || s.len() > 8 || !s.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let v = u32::from_str_radix(s, 16).ok()?;
    if s.len() == 3 { CanId::standard(v as u16).filter(|_| v <= 0x7FF) } else { CanId::extended(v) }
}

/// `ID DLC B0 … B(DLC-1)`: exactly DLC bytes of 1–2 hex digits, nothing more.
/// python-can sends RTR as `< send 705 1  >` (no bytes): rejected, as
/// socketcand does.
fn parse_send<'a>(mut w: impl Iterator<Item = &'a str>) -> Option<Frame> {
    let id = parse_id(w.next()?)?;
    let dlc_s = w.next()?;
    if dlc_s.is_empty() || dlc_s.len() > 2 || !dlc_s.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let dlc: usize = dlc_s.parse().ok()?;
    if dlc > 8 {
        return None;
    }
    let mut data = [0u8; 8];
    for slot in data.iter_mut().take(dlc) {
        let b = w.next()?;
        if b.is_empty() || b.len() > 2 || !b.bytes().all(|c| c.is_ascii_hexdigit()) {
            return None;
        }
        *slot = u8::from_str_radix(b, 16).ok()?;
    }
    if w.next().is_some() {
        return None;
    }
    Frame::try_new(id, &data[..dlc]).ok()
}

/// `ID SECS.USECS [DATA]` with contiguous hex data.
fn parse_frame<'a>(mut w: impl Iterator<Item = &'a str>) -> Option<(Frame, u64)> {
    let id = parse_id(w.next()?)?;
    let ts = w.next()?;
    let (secs, usecs) = ts.split_once('.').unwrap_or((ts, "0"));
    let secs: u64 = secs.parse().ok()?;
    // A fraction of a second: socketcand writes 6 digits; pad shorter ones.
    if usecs.is_empty() || usecs.len() > 9 || !usecs.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let usecs =
        usecs.bytes().chain(std::iter::repeat(b'0')).take(6).fold(0u64, |a, d| a * 10 + u64::from(d - b'0'));
    let hex = w.next().unwrap_or("");
    if w.next().is_some() || !hex.len().is_multiple_of(2) || hex.len() > 16 {
        return None;
    }
    let mut data = [0u8; 8];
    for (i, pair) in hex.as_bytes().chunks(2).enumerate() {
        data[i] = (hex_val(pair[0])? << 4) | hex_val(pair[1])?;
    }
    let f = Frame::try_new(id, &data[..hex.len() / 2]).ok()?;
    Some((f, secs.saturating_mul(1_000_000).saturating_add(usecs)))
}

fn hex_val(c: u8) -> Option<u8> {
    (c as char).to_digit(16).map(|d| d as u8)
}

fn push_id(out: &mut String, id: CanId) {
    let _ = match id {
        CanId::Standard(v) => write!(out, "{v:03X}"),
        CanId::Extended(v) => write!(out, "{v:08X}"),
    };
}

/// Appends `< frame ID SECS.USECS DATA >`. DLC 0 gives two spaces before
/// `>` (python-can indexes the data field and fails on one space).
pub fn write_frame(out: &mut String, frame: &Frame, timestamp_us: u64) {
    out.push_str("< frame ");
    push_id(out, frame.id());
    let _ = write!(out, " {}.{:06} ", timestamp_us / 1_000_000, timestamp_us % 1_000_000);
    for b in frame.data() {
        let _ = write!(out, "{b:02X}");
    }
    out.push_str(" >");
}

/// Appends `< send ID DLC B0 … >` (bytes as `%02X`, either case is accepted).
pub fn write_send(out: &mut String, frame: &Frame) {
    out.push_str("< send ");
    push_id(out, frame.id());
    let _ = write!(out, " {}", frame.len());
    for b in frame.data() {
        let _ = write!(out, " {b:02X}");
    }
    out.push_str(" >");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split_all(chunks: &[&[u8]]) -> Vec<String> {
        let mut s = Splitter::new();
        let mut got = Vec::new();
        for c in chunks {
            s.feed(c, |m| got.push(String::from_utf8_lossy(m).into_owned()));
        }
        got
    }

    #[test]
    fn splits_straddled_and_garbage() {
        assert_eq!(split_all(&[b"< hi >< o", b"k >"]), [" hi ", " ok "]);
        assert_eq!(split_all(&[b"xx< a >yy<", b" b", b" >"]), [" a ", " b "]);
        // An unterminated message is dropped when a new one starts.
        assert_eq!(split_all(&[b"< broken < ok >"]), [" ok "]);
        assert_eq!(split_all(&[b"< broken", b" < ok >"]), [" ok "]);
        // Huge unterminated garbage is discarded, then framing resumes.
        let big = vec![b'x'; 10_000];
        let mut lead = b"<".to_vec();
        lead.extend_from_slice(&big);
        assert_eq!(split_all(&[&lead, &big, b"< echo >"]), [" echo "]);
    }

    #[test]
    fn send_parsing_is_strict() {
        assert_eq!(
            parse(b" send 605 8 40 0 10 0 0 0 0 0 "),
            Message::Send(Frame::new(0x605, &[0x40, 0, 0x10, 0, 0, 0, 0, 0]))
        );
        assert_eq!(parse(b" send 080 0 "), Message::Send(Frame::new(0x80, &[])));
        let ext = Frame::try_new(CanId::Extended(0x18FF50E5), &[0xAB]).unwrap();
        assert_eq!(parse(b" send 18FF50E5 1 aB "), Message::Send(ext));
        // Not 3 digits: extended.
        let ext80 = Frame::try_new(CanId::Extended(0x80), &[]).unwrap();
        assert_eq!(parse(b" send 80 0 "), Message::Send(ext80));
        for bad in [
            &b" send 705 1  "[..], // python-can's RTR: no bytes
            b" send 605 2 1 ",     // too few
            b" send 605 1 1 2 ",   // too many
            b" send 605 9 0 0 0 0 0 0 0 0 0",
            b" send 800 0 ",      // out of 11-bit range
            b" send 20000000 0 ", // out of 29-bit range
            b" send 605 1 100 ",  // 3-digit byte
            b" send 605 1 g ",
            b" send 605 x ",
            b" send ",
        ] {
            assert!(matches!(parse(bad), Message::Invalid(_)), "{}", String::from_utf8_lossy(bad));
        }
    }

    #[test]
    fn frame_format_and_parse() {
        let mut s = String::new();
        write_frame(&mut s, &Frame::new(0x80, &[]), 1_795_315_121_833_813);
        assert_eq!(s, "< frame 080 1795315121.833813  >");
        s.clear();
        write_frame(&mut s, &Frame::new(0x585, &[0x43, 0, 0x10, 0, 0x92, 1, 2, 0]), 5);
        assert_eq!(s, "< frame 585 0.000005 4300100092010200 >");
        s.clear();
        let ext = Frame::try_new(CanId::Extended(0x123), &[1]).unwrap();
        write_frame(&mut s, &ext, 0);
        assert_eq!(s, "< frame 00000123 0.000000 01 >");
        assert_eq!(parse(&s.as_bytes()[1..s.len() - 1]), Message::Frame(ext, 0));
        assert_eq!(parse(b" frame 080 1.5  "), Message::Frame(Frame::new(0x80, &[]), 1_500_000));
        s.clear();
        write_send(&mut s, &ext);
        assert_eq!(s, "< send 00000123 1 01 >");
        assert_eq!(parse(b" hi "), Message::Hi);
        assert_eq!(parse(b" error could not open bus "), Message::Error("could not open bus"));
    }
}
