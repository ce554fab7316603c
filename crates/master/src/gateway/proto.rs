//! The CiA 309-3 ASCII command syntax: tokens, numbers, data types and
//! the requests, as CANopenNode's gateway (what `cocomm` talks to) and
//! Lely's `coctl` accept them. Parsing never panics: a bad line is a
//! syntax error (code 101) naming the token.

use crate::DataType;

/// Gateway error codes (CiA 309-3 §"Error codes").
pub mod code {
    /// Request not supported.
    pub const NOT_SUPPORTED: u16 = 100;
    /// Syntax error.
    pub const SYNTAX: u16 = 101;
    /// Request not processed due to internal state.
    pub const INTERNAL_STATE: u16 = 102;
    /// Time-out.
    pub const TIMEOUT: u16 = 103;
    /// No default node set.
    pub const NO_DEFAULT_NODE: u16 = 105;
    /// Unsupported net.
    pub const UNSUPPORTED_NET: u16 = 106;
    /// Unsupported node.
    pub const UNSUPPORTED_NODE: u16 = 107;
    /// LSS implementation- / manufacturer-specific error.
    pub const LSS_MANUFACTURER: u16 = 501;
    /// LSS node-ID not supported.
    pub const LSS_NODE_ID: u16 = 502;
    /// LSS bit-rate not supported.
    pub const LSS_BITRATE: u16 = 503;
    /// LSS parameter storing failed.
    pub const LSS_STORE: u16 = 504;

    /// The description CANopenNode appends after `#`.
    pub fn text(c: u16) -> &'static str {
        match c {
            100 => "Request not supported.",
            101 => "Syntax error.",
            102 => "Request not processed due to internal state.",
            103 => "Time-out.",
            104 => "No default net set.",
            105 => "No default node set.",
            106 => "Unsupported net.",
            107 => "Unsupported node.",
            501 => "LSS implementation- / manufacturer-specific error.",
            502 => "LSS node-ID not supported.",
            503 => "LSS bit-rate not supported.",
            504 => "LSS parameter storing failed.",
            _ => "-",
        }
    }
}

/// A gateway data type token (`u16`, `vs`, ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GwType {
    /// A CiA 301 basic type.
    Basic(DataType),
    /// `x8`..`x64`: unsigned, printed in hex (non-standard, CANopenNode).
    Hex(DataType),
    /// `hex`: raw bytes in hex (non-standard, CANopenNode).
    Raw,
}

impl GwType {
    /// Parses a type token (case-insensitive).
    pub fn parse(t: &str) -> Option<GwType> {
        use DataType::*;
        Some(match t.to_ascii_lowercase().as_str() {
            "b" => GwType::Basic(Boolean),
            "i8" => GwType::Basic(Integer8),
            "i16" => GwType::Basic(Integer16),
            "i24" => GwType::Basic(Integer24),
            "i32" => GwType::Basic(Integer32),
            "i40" => GwType::Basic(Integer40),
            "i48" => GwType::Basic(Integer48),
            "i56" => GwType::Basic(Integer56),
            "i64" => GwType::Basic(Integer64),
            "u8" => GwType::Basic(Unsigned8),
            "u16" => GwType::Basic(Unsigned16),
            "u24" => GwType::Basic(Unsigned24),
            "u32" => GwType::Basic(Unsigned32),
            "u40" => GwType::Basic(Unsigned40),
            "u48" => GwType::Basic(Unsigned48),
            "u56" => GwType::Basic(Unsigned56),
            "u64" => GwType::Basic(Unsigned64),
            "x8" => GwType::Hex(Unsigned8),
            "x16" => GwType::Hex(Unsigned16),
            "x32" => GwType::Hex(Unsigned32),
            "x64" => GwType::Hex(Unsigned64),
            "r32" => GwType::Basic(Real32),
            "r64" => GwType::Basic(Real64),
            "t" => GwType::Basic(TimeOfDay),
            "td" => GwType::Basic(TimeDifference),
            "vs" => GwType::Basic(VisibleString),
            "os" => GwType::Basic(OctetString),
            "us" => GwType::Basic(UnicodeString),
            "d" => GwType::Basic(Domain),
            "hex" => GwType::Raw,
            _ => return None,
        })
    }

    /// The size in bits of a fixed-size type (for PDO mapping).
    pub fn bits(self) -> Option<u8> {
        match self {
            GwType::Basic(t) | GwType::Hex(t) => t.fixed_size().map(|b| (b * 8) as u8),
            GwType::Raw => None,
        }
    }
}

/// A number as C's `strtoul(s, 0)` reads it: `0x` hex, leading `0`
/// octal, else decimal; the whole token must be the number.
pub fn c_number(s: &str) -> Option<u64> {
    let (neg, t) = match s.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, s.strip_prefix('+').unwrap_or(s)),
    };
    let v = if let Some(h) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        u64::from_str_radix(h, 16).ok()?
    } else if t.len() > 1 && t.starts_with('0') {
        u64::from_str_radix(&t[1..], 8).ok()?
    } else {
        t.parse::<u64>().ok()?
    };
    if neg { None } else { Some(v) }
}

/// A signed number, C style.
pub fn c_signed(s: &str) -> Option<i64> {
    match s.strip_prefix('-') {
        Some(r) => c_number(r).and_then(|v| i64::try_from(v).ok()).map(|v| -v),
        None => c_number(s).and_then(|v| i64::try_from(v).ok()),
    }
}

/// Splits a command into tokens: blanks separate, `"..."` keeps blanks
/// (with `""` for a quote), `#` starts a comment. `Err(column)` for an
/// unterminated quote.
pub fn tokens(line: &str) -> Result<Vec<String>, usize> {
    let mut out = Vec::new();
    let mut chars = line.char_indices().peekable();
    while let Some(&(i, c)) = chars.peek() {
        if c.is_whitespace() {
            chars.next();
            continue;
        }
        if c == '#' {
            break;
        }
        let mut tok = String::new();
        if c == '"' {
            chars.next();
            tok.push('"');
            loop {
                match chars.next() {
                    Some((_, '"')) if chars.peek().map(|p| p.1) == Some('"') => {
                        chars.next();
                        tok.push('"');
                    }
                    Some((_, '"')) => break,
                    Some((_, ch)) => tok.push(ch),
                    None => return Err(i + 1),
                }
            }
            tok.push('"');
        } else {
            while let Some(&(_, ch)) = chars.peek() {
                if ch.is_whitespace() {
                    break;
                }
                tok.push(ch);
                chars.next();
            }
        }
        out.push(tok);
    }
    Ok(out)
}

/// A parsed CiA 309-3 service request (one line).
#[derive(Clone, Debug, PartialEq)]
pub enum ServiceRequest {
    /// Empty line or comment.
    Empty,
    /// SDO upload.
    Read {
        /// The node given in the line (else the session's default).
        node: Option<u8>,
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// How to show the value (raw bytes when absent).
        ty: Option<GwType>,
    },
    /// SDO download.
    Write {
        /// The node given in the line (else the session's default).
        node: Option<u8>,
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The value's type.
        ty: GwType,
        /// The rest of the command as tokens.
        value: Vec<String>,
    },
    /// NMT command.
    Nmt {
        /// The node given in the line (else the session's default).
        node: Option<u8>,
        /// NMT command specifier (01h start, 02h stop, 80h, 81h, 82h).
        cs: u8,
    },
    /// `set network N`.
    SetNetwork(u16),
    /// `set node N`.
    SetNode(u8),
    /// `set sdo_timeout MS`.
    SetSdoTimeout(u32),
    /// `set sdo_block 0|1`.
    SetSdoBlock(bool),
    /// `info version`.
    InfoVersion,
    /// `help [datatype|lss]`.
    Help(Option<String>),
    /// LSS commands.
    Lss {
        /// The command word.
        cmd: String,
        /// Its argument tokens.
        args: Vec<String>,
    },
    /// `r[ead] p[do] N`.
    PdoRead(u16),
    /// `w[rite] p[do] N n v1..vn`.
    PdoWrite {
        /// PDO number.
        num: u16,
        /// The mapped values, in order.
        values: Vec<u64>,
    },
    /// `set rpdo|tpdo[x] N COBID TRANS [...] n entries`.
    SetPdo {
        /// `tpdo` (else `rpdo`).
        tx: bool,
        /// The `x` form (Lely's extended syntax).
        ext: bool,
        /// The argument tokens.
        args: Vec<String>,
    },
}

/// A line: sequence number (when bracketed) and the request or an error code.
pub struct Parsed {
    /// The sequence number of the answer.
    pub seq: Option<u32>,
    /// Net given before the command.
    pub net: Option<u16>,
    /// The request, or the error code and why.
    pub request: Result<ServiceRequest, (u16, String)>,
}

fn syntax(why: impl Into<String>) -> (u16, String) {
    (code::SYNTAX, why.into())
}

/// Parses one line (without its line break).
pub fn parse(line: &str) -> Parsed {
    let toks = match tokens(line) {
        Ok(t) => t,
        Err(col) => {
            return Parsed {
                seq: None,
                net: None,
                request: Err(syntax(format!("unterminated quote at column {col}"))),
            };
        }
    };
    if toks.is_empty() {
        return Parsed { seq: None, net: None, request: Ok(ServiceRequest::Empty) };
    }
    let mut it = toks.into_iter().peekable();
    let first = it.next().unwrap_or_default();
    let seq = match first.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
        Some(s) => match c_number(s).and_then(|v| u32::try_from(v).ok()) {
            Some(v) => v,
            None => {
                return Parsed {
                    seq: None,
                    net: None,
                    request: Err(syntax(format!("bad sequence number `{first}`"))),
                };
            }
        },
        None => {
            return Parsed { seq: None, net: None, request: Err(syntax("a command starts with [sequence]")) };
        }
    };
    // Up to two numbers before the command: [[net] node].
    let mut nums = Vec::new();
    while let Some(t) = it.peek() {
        if !t.starts_with(|c: char| c.is_ascii_digit()) {
            break;
        }
        let t = it.next().unwrap_or_default();
        match c_number(&t) {
            Some(v) if nums.len() < 2 => nums.push(v),
            _ => {
                return Parsed {
                    seq: Some(seq),
                    net: None,
                    request: Err(syntax(format!("unexpected number `{t}`"))),
                };
            }
        }
    }
    let (net, node) = match nums.as_slice() {
        [] => (None, None),
        [n] => (None, Some(*n)),
        [net, n] => (Some(*net), Some(*n)),
        _ => {
            return Parsed {
                seq: Some(seq),
                net: None,
                request: Err(syntax("more than [net] node before the command")),
            };
        }
    };
    let Some(net) = net.map(|n| u16::try_from(n).map_err(|_| ())).transpose().ok() else {
        return Parsed {
            seq: Some(seq),
            net: None,
            request: Err((code::UNSUPPORTED_NET, "net above 65535".into())),
        };
    };
    let node = match node {
        Some(n) if n > 127 => {
            return Parsed {
                seq: Some(seq),
                net,
                request: Err((code::UNSUPPORTED_NODE, format!("node {n} is not 0..127"))),
            };
        }
        n => n.map(|n| n as u8),
    };
    let rest: Vec<String> = it.collect();
    Parsed { seq: Some(seq), net, request: command(node, &rest) }
}

fn command(node: Option<u8>, t: &[String]) -> Result<ServiceRequest, (u16, String)> {
    let Some(cmd) = t.first() else { return Err(syntax("missing command")) };
    let cmd = cmd.to_ascii_lowercase();
    let args = &t[1..];
    let num = |i: usize, what: &str| -> Result<u64, (u16, String)> {
        args.get(i).and_then(|s| c_number(s)).ok_or_else(|| syntax(format!("expected {what}")))
    };
    let done = |n: usize, r: ServiceRequest| -> Result<ServiceRequest, (u16, String)> {
        if args.len() > n { Err(syntax(format!("unexpected `{}`", args[n]))) } else { Ok(r) }
    };
    let pdo_kw =
        |s: Option<&String>| s.is_some_and(|s| matches!(s.to_ascii_lowercase().as_str(), "p" | "pdo"));
    match cmd.as_str() {
        "r" | "read" if pdo_kw(args.first()) => {
            let n = num(1, "a PDO number")?;
            if !(1..=512).contains(&n) {
                return Err(syntax("PDO number must be 1..512"));
            }
            done(2, ServiceRequest::PdoRead(n as u16))
        }
        "w" | "write" if pdo_kw(args.first()) => {
            let n = num(1, "a PDO number")?;
            let count = num(2, "the number of values")? as usize;
            if !(1..=512).contains(&n) || count > 64 || args.len() != 3 + count {
                return Err(syntax("expected w p N COUNT VALUE..."));
            }
            let values = (0..count).map(|i| num(3 + i, "a value")).collect::<Result<Vec<_>, _>>()?;
            Ok(ServiceRequest::PdoWrite { num: n as u16, values })
        }
        "r" | "read" => {
            let index = num(0, "an index")?;
            let sub = num(1, "a sub-index")?;
            if index > 0xFFFF || sub > 0xFF {
                return Err(syntax("index or sub-index out of range"));
            }
            let ty = match args.get(2) {
                Some(t) => Some(GwType::parse(t).ok_or_else(|| syntax(format!("unknown data type `{t}`")))?),
                None => None,
            };
            done(3, ServiceRequest::Read { node, index: index as u16, sub: sub as u8, ty })
        }
        "w" | "write" => {
            let index = num(0, "an index")?;
            let sub = num(1, "a sub-index")?;
            if index > 0xFFFF || sub > 0xFF {
                return Err(syntax("index or sub-index out of range"));
            }
            let ty =
                args.get(2).and_then(|t| GwType::parse(t)).ok_or_else(|| syntax("expected a data type"))?;
            if args.len() < 4 {
                return Err(syntax("expected a value"));
            }
            Ok(ServiceRequest::Write {
                node,
                index: index as u16,
                sub: sub as u8,
                ty,
                value: args[3..].to_vec(),
            })
        }
        "start" => done(0, ServiceRequest::Nmt { node, cs: 0x01 }),
        "stop" => done(0, ServiceRequest::Nmt { node, cs: 0x02 }),
        "preop" | "preoperational" => done(0, ServiceRequest::Nmt { node, cs: 0x80 }),
        "reset" => match args.first().map(|s| s.to_ascii_lowercase()).as_deref() {
            Some("node") => done(1, ServiceRequest::Nmt { node, cs: 0x81 }),
            Some("comm" | "communication") => done(1, ServiceRequest::Nmt { node, cs: 0x82 }),
            _ => Err(syntax("expected reset node or reset comm[unication]")),
        },
        "set" => {
            let what = args.first().map(|s| s.to_ascii_lowercase()).unwrap_or_default();
            let args2 = &args[1.min(args.len())..];
            let v = || {
                args2
                    .first()
                    .and_then(|s| c_number(s))
                    .ok_or_else(|| syntax(format!("expected a value after set {what}")))
            };
            let end =
                |r| if args2.len() > 1 { Err(syntax(format!("unexpected `{}`", args2[1]))) } else { Ok(r) };
            match what.as_str() {
                "network" => {
                    let n = v()?;
                    u16::try_from(n)
                        .map_err(|_| syntax("network must be 0..65535"))
                        .and_then(|n| end(ServiceRequest::SetNetwork(n)))
                }
                "node" => match v()? {
                    n @ 1..=127 => end(ServiceRequest::SetNode(n as u8)),
                    _ => Err(syntax("node must be 1..127")),
                },
                "sdo_timeout" => match v()? {
                    n @ 1..=0xFFFF => end(ServiceRequest::SetSdoTimeout(n as u32)),
                    _ => Err(syntax("sdo_timeout must be 1..65535 ms")),
                },
                "sdo_block" => match v()? {
                    n @ 0..=1 => end(ServiceRequest::SetSdoBlock(n == 1)),
                    _ => Err(syntax("sdo_block must be 0 or 1")),
                },
                "rpdo" => Ok(ServiceRequest::SetPdo { tx: false, ext: false, args: args2.to_vec() }),
                "tpdo" => Ok(ServiceRequest::SetPdo { tx: true, ext: false, args: args2.to_vec() }),
                "tpdox" => Ok(ServiceRequest::SetPdo { tx: true, ext: true, args: args2.to_vec() }),
                _ => Err((code::NOT_SUPPORTED, format!("set {what} is not supported"))),
            }
        }
        "info" => match args.first().map(|s| s.to_ascii_lowercase()).as_deref() {
            Some("version") => done(1, ServiceRequest::InfoVersion),
            _ => Err(syntax("expected info version")),
        },
        "help" => done(1, ServiceRequest::Help(args.first().map(|s| s.to_ascii_lowercase()))),
        c if c.starts_with("lss_") || c == "_lss_fastscan" => {
            Ok(ServiceRequest::Lss { cmd: c.to_owned(), args: args.to_vec() })
        }
        c => Err((code::NOT_SUPPORTED, format!("unknown command `{c}`"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_as_strtoul_reads_them() {
        assert_eq!(c_number("0x1017"), Some(0x1017));
        assert_eq!(c_number("4119"), Some(4119));
        assert_eq!(c_number("010"), Some(8));
        assert_eq!(c_number("0"), Some(0));
        assert_eq!(c_number("0x"), None);
        assert_eq!(c_number("12a"), None);
        assert_eq!(c_signed("-300"), Some(-300));
        assert_eq!(c_signed("-0x10"), Some(-16));
    }

    #[test]
    fn tokens_quotes_and_comments() {
        assert_eq!(
            tokens("[1] 4 w 0x2001 0 vs \"a b\"\"c\" # x").unwrap(),
            ["[1]", "4", "w", "0x2001", "0", "vs", "\"a b\"c\""]
        );
        assert!(tokens("[1] w 1 2 vs \"open").is_err());
        assert!(tokens("  # only a comment").unwrap().is_empty());
    }

    #[test]
    fn requests() {
        let p = parse("[1] 4 read 0x1017 0 u16");
        assert_eq!(p.seq, Some(1));
        assert_eq!(
            p.request,
            Ok(ServiceRequest::Read {
                node: Some(4),
                index: 0x1017,
                sub: 0,
                ty: Some(GwType::Basic(DataType::Unsigned16))
            })
        );
        let p = parse("[2] 1 4 w 0x1017 0 u16 500");
        assert_eq!(p.net, Some(1));
        assert!(matches!(p.request, Ok(ServiceRequest::Write { node: Some(4), index: 0x1017, .. })));
        assert_eq!(
            parse("[3] r 0x1000 0").request,
            Ok(ServiceRequest::Read { node: None, index: 0x1000, sub: 0, ty: None })
        );
        assert_eq!(parse("[4] 5 reset comm").request, Ok(ServiceRequest::Nmt { node: Some(5), cs: 0x82 }));
        assert_eq!(parse("[5] 0 start").request, Ok(ServiceRequest::Nmt { node: Some(0), cs: 0x01 }));
        assert_eq!(parse("[6] set node 4").request, Ok(ServiceRequest::SetNode(4)));
        assert_eq!(parse("[7] info version").request, Ok(ServiceRequest::InfoVersion));
        assert_eq!(parse("[8] r p 1").request, Ok(ServiceRequest::PdoRead(1)));
        assert_eq!(
            parse("[9] w p 1 2 0x1 5").request,
            Ok(ServiceRequest::PdoWrite { num: 1, values: vec![1, 5] })
        );
        assert_eq!(parse("").request, Ok(ServiceRequest::Empty));
        // Errors with their codes.
        assert_eq!(parse("4 read 0x1017 0").request.unwrap_err().0, code::SYNTAX);
        assert_eq!(parse("[1] 200 start").request.unwrap_err().0, code::UNSUPPORTED_NODE);
        assert_eq!(parse("[1] 4 frobnicate").request.unwrap_err().0, code::NOT_SUPPORTED);
        assert_eq!(parse("[1] 4 r 0x10000 0").request.unwrap_err().0, code::SYNTAX);
        assert_eq!(parse("[1] 4 r 0x1000 0 u17").request.unwrap_err().0, code::SYNTAX);
        assert_eq!(parse("[1] 1 2 3 start").request.unwrap_err().0, code::SYNTAX);
        assert_eq!(parse("[x] start").request.unwrap_err().0, code::SYNTAX);
    }

    #[test]
    fn garbage_never_panics() {
        for line in [
            "[",
            "]",
            "[]",
            "[1",
            "[1]]",
            "[1] \"",
            "[1] w",
            "[1] w 1",
            "[1] w 1 2 u8",
            "[1] set",
            "[1] set node",
            "[1] r p",
            "[1] w p 1 5 1",
            "[1] reset",
            "[1] 99999999999999999999 start",
            "\u{0}\u{ff}",
            "[1] lss_set_node",
        ] {
            let _ = parse(line);
        }
    }

    proptest::proptest! {
        /// Any line, printable or not, gives a request or a 309-3 error.
        #[test]
        fn any_line_parses_or_errs(line in "\\PC{0,60}", raw in proptest::collection::vec(proptest::num::u8::ANY, 0..60)) {
            let _ = parse(&line);
            let _ = parse(&String::from_utf8_lossy(&raw));
        }

        /// Lines built from the gateway's own words in random order.
        #[test]
        fn shuffled_words_never_panic(words in proptest::collection::vec(proptest::sample::select(vec![
            "[1]", "[", "]", "4", "0x1017", "0", "-1", "65536", "r", "w", "read", "write", "u8", "i64", "vs", "d",
            "r32", "\"", "start", "reset", "comm", "node", "set", "sdo_timeout", "network", "lss_switch_glob",
            "lss_set_node", "lss_fastscan", "info", "version", "p", "tpdo", "rpdo", "#",
        ]), 0..8)) {
            let _ = parse(&words.join(" "));
        }
    }
}
