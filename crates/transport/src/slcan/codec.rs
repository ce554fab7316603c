//! slcan (Lawicel) line codec.
//!
//! Frames: `tIIILdd…` (standard data), `TIIIIIIIILdd…` (extended data),
//! `rIIIL` / `RIIIIIIIIL` (remote), each ended by CR, optionally followed
//! by a 4-hex-digit millisecond timestamp before the CR. Adapter answers:
//! CR (ok), BEL (error), `z`/`Z` CR (frame queued).

use drivebus_can::{CanId, Frame};

/// Longest line kept; longer ones are discarded up to the next CR. The
/// longest valid frame line (`T` + 8 + 1 + 16 + 4 timestamp) is 30 bytes.
pub const MAX_LINE: usize = 64;

/// The `S<n>` command for a CAN bit rate (python-can's table, with the
/// classic Lawicel 800k and python-can's 750k both mapped to S7, and 83.3k
/// to S9).
pub fn bitrate_command(bitrate: u32) -> Option<&'static str> {
    Some(match bitrate {
        10_000 => "S0",
        20_000 => "S1",
        50_000 => "S2",
        100_000 => "S3",
        125_000 => "S4",
        250_000 => "S5",
        500_000 => "S6",
        750_000 | 800_000 => "S7",
        1_000_000 => "S8",
        83_300 | 83_333 => "S9",
        _ => return None,
    })
}

/// The bit rate selected by `S<digit>`.
pub fn bitrate_of(digit: u8) -> Option<u32> {
    const TABLE: [u32; 10] =
        [10_000, 20_000, 50_000, 100_000, 125_000, 250_000, 500_000, 800_000, 1_000_000, 83_300];
    TABLE.get(usize::from(digit.checked_sub(b'0')?)).copied()
}

const HEX: &[u8; 16] = b"0123456789ABCDEF";

fn push_hex(out: &mut Vec<u8>, v: u32, digits: u32) {
    for i in (0..digits).rev() {
        out.push(HEX[((v >> (i * 4)) & 0xF) as usize]);
    }
}

/// Appends the line for `frame`, CR included (uppercase hex, always well
/// formed: python-can raises on a malformed line and that kills its reader).
pub fn encode(frame: &Frame, out: &mut Vec<u8>) {
    encode_stamped(frame, None, out)
}

/// Like [`encode`], with a millisecond timestamp (`Z1` mode, 0..60000).
pub fn encode_stamped(frame: &Frame, timestamp_ms: Option<u16>, out: &mut Vec<u8>) {
    match (frame.id(), frame.is_rtr()) {
        (CanId::Standard(id), rtr) => {
            out.push(if rtr { b'r' } else { b't' });
            push_hex(out, u32::from(id), 3);
        }
        (CanId::Extended(id), rtr) => {
            out.push(if rtr { b'R' } else { b'T' });
            push_hex(out, id, 8);
        }
    }
    out.push(b'0' + frame.len() as u8);
    for &b in frame.data() {
        push_hex(out, u32::from(b), 2);
    }
    if let Some(ts) = timestamp_ms {
        push_hex(out, u32::from(ts), 4);
    }
    out.push(b'\r');
}

/// Why a line is not a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineError {
    /// Does not start with t, T, r or R.
    NotAFrame,
    /// Wrong length or a non-hex digit.
    Malformed,
    /// Identifier out of range for its format.
    BadId,
}

fn hex(s: &[u8]) -> Option<u32> {
    if s.is_empty() || s.len() > 8 {
        return None;
    }
    s.iter().try_fold(0u32, |acc, &c| Some((acc << 4) | (c as char).to_digit(16)?))
}

/// Parses a frame line without its CR; a trailing 4-digit timestamp is
/// accepted and ignored.
pub fn parse_frame(line: &[u8]) -> Result<Frame, LineError> {
    let (kind, rest) = line.split_first().ok_or(LineError::NotAFrame)?;
    let (id_len, rtr) = match kind {
        b't' => (3, false),
        b'r' => (3, true),
        b'T' => (8, false),
        b'R' => (8, true),
        _ => return Err(LineError::NotAFrame),
    };
    if rest.len() < id_len + 1 {
        return Err(LineError::Malformed);
    }
    let raw = hex(&rest[..id_len]).ok_or(LineError::Malformed)?;
    let id =
        if id_len == 3 { CanId::standard(raw as u16).filter(|_| raw <= 0x7FF) } else { CanId::extended(raw) }
            .ok_or(LineError::BadId)?;
    let dlc = match rest[id_len] {
        d @ b'0'..=b'8' => usize::from(d - b'0'),
        _ => return Err(LineError::Malformed),
    };
    let body = &rest[id_len + 1..];
    let data_len = if rtr { 0 } else { dlc * 2 };
    if body.len() != data_len && body.len() != data_len + 4 {
        return Err(LineError::Malformed);
    }
    if body.len() == data_len + 4 && hex(&body[data_len..]).is_none() {
        return Err(LineError::Malformed);
    }
    if rtr {
        return Frame::try_remote(id, dlc as u8).map_err(|_| LineError::Malformed);
    }
    let mut data = [0u8; 8];
    for (i, pair) in body[..data_len].chunks_exact(2).enumerate() {
        data[i] = hex(pair).ok_or(LineError::Malformed)? as u8;
    }
    Frame::try_new(id, &data[..dlc]).map_err(|_| LineError::Malformed)
}

/// One unit of an slcan byte stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Token<'a> {
    /// A line without its CR (may be empty).
    Line(&'a [u8]),
    /// A BEL byte: the adapter's error answer.
    Bell,
}

/// Splits an slcan byte stream into lines with a fixed buffer: reads may
/// cut lines anywhere, LF is ignored, oversized lines are dropped whole.
#[derive(Debug)]
pub struct LineSplitter {
    buf: [u8; MAX_LINE],
    len: usize,
    overflow: bool,
}

impl Default for LineSplitter {
    fn default() -> Self {
        LineSplitter { buf: [0; MAX_LINE], len: 0, overflow: false }
    }
}

impl LineSplitter {
    /// An empty splitter.
    pub fn new() -> Self {
        Self::default()
    }
    /// Feeds bytes, calling `f` for each complete token.
    pub fn feed(&mut self, data: &[u8], mut f: impl FnMut(Token<'_>)) {
        for &b in data {
            match b {
                b'\r' => {
                    if !self.overflow {
                        f(Token::Line(&self.buf[..self.len]));
                    }
                    self.len = 0;
                    self.overflow = false;
                }
                0x07 => f(Token::Bell),
                b'\n' => {}
                _ if self.len < MAX_LINE => {
                    self.buf[self.len] = b;
                    self.len += 1;
                }
                _ => self.overflow = true,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn enc(f: &Frame) -> String {
        let mut v = Vec::new();
        encode(f, &mut v);
        String::from_utf8(v).unwrap()
    }

    #[test]
    fn every_frame_form() {
        let sdo = Frame::new(0x605, &[0x84, 0, 0x10, 0, 0, 0, 0, 0]);
        assert_eq!(enc(&sdo), "t60588400100000000000\r");
        assert_eq!(enc(&Frame::remote(0x705, 1)), "r7051\r");
        assert_eq!(enc(&Frame::new(0x80, &[])), "t0800\r");
        let ext = Frame::try_new(CanId::Extended(0x18FF50E5), &[1, 2]).unwrap();
        assert_eq!(enc(&ext), "T18FF50E520102\r");
        let extr = Frame::try_remote(CanId::Extended(0x1ABCDEF), 8).unwrap();
        assert_eq!(enc(&extr), "R01ABCDEF8\r");
        for f in [sdo, Frame::remote(0x705, 1), Frame::new(0x80, &[]), ext, extr] {
            let line = enc(&f);
            assert_eq!(parse_frame(&line.as_bytes()[..line.len() - 1]), Ok(f));
        }
        // Lowercase hex and a timestamp are accepted.
        assert_eq!(
            parse_frame(b"t60581122334455667788abcd"),
            Ok(Frame::new(0x605, &[0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88]))
        );
        assert_eq!(parse_frame(b"t1ff1ab"), Ok(Frame::new(0x1FF, &[0xAB])));
        assert_eq!(parse_frame(b"r70510000"), Ok(Frame::remote(0x705, 1)));
        let mut v = Vec::new();
        encode_stamped(&Frame::new(1, &[]), Some(0xEA5F), &mut v);
        assert_eq!(v, b"t0010EA5F\r");
    }

    #[test]
    fn malformed_lines() {
        use LineError::*;
        for (line, err) in [
            (&b""[..], NotAFrame),
            (b"x123", NotAFrame),
            (b"t", Malformed),
            (b"t12", Malformed),
            (b"t123", Malformed),
            (b"t1239", Malformed),
            (b"t1232aa", Malformed),
            (b"t1232aabbc", Malformed),
            (b"t1231zz", Malformed),
            (b"t8000", BadId),
            (b"T2000000000", BadId),
            (b"T1234567", Malformed),
            (b"r7051aa", Malformed),
            (b"t12300", Malformed),
            (b"t1230zzzz", Malformed),
        ] {
            assert_eq!(parse_frame(line), Err(err), "{}", String::from_utf8_lossy(line));
        }
    }

    #[test]
    fn splitter_handles_cuts_bells_and_overflow() {
        let mut s = LineSplitter::new();
        let mut got = Vec::new();
        let mut push = |t: Token<'_>| {
            got.push(match t {
                Token::Line(l) => String::from_utf8_lossy(l).into_owned(),
                Token::Bell => "BEL".into(),
            })
        };
        s.feed(b"t08", &mut push);
        s.feed(b"0\r\x07z\r\r\n", &mut push);
        s.feed(&[b'x'; 200], &mut push);
        s.feed(b"\rO\r", &mut push);
        assert_eq!(got, ["t080", "BEL", "z", "", "O"]);
    }

    #[test]
    fn bitrates() {
        assert_eq!(bitrate_command(1_000_000), Some("S8"));
        assert_eq!(bitrate_command(500_000), Some("S6"));
        assert_eq!(bitrate_command(12345), None);
        assert_eq!(bitrate_of(b'8'), Some(1_000_000));
        assert_eq!(bitrate_of(b'x'), None);
    }
}
