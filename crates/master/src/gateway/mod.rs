//! The CiA 309-3 ASCII gateway as a master service: [`Session`] parses a
//! request line ([`proto`]), executes it on the master and words the answer
//! the way CANopenNode's gateway does (so `cocomm` reads them): `[seq] OK`,
//! `[seq] VALUE`, `[seq] ERROR:CODE #text`, `[seq] ERROR:0xABORT #text`,
//! each ending in CR LF. Where the lines come from (stdin, TCP, a shell) is
//! the caller's: `drivebus gateway` (`cli/src/gateway.rs`).

pub mod proto;

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::{
    DataType, FastScan, Frame, Identity, LssError, LssField, LssMode, Master, PdoCallback, Protocol,
    SdoError, Value,
};

use proto::{GwType, ServiceRequest, c_number, c_signed, code, parse};

/// A PDO of the gateway itself (Lely's `set rpdo`/`set tpdo`).
struct LocalPdo {
    cob: u16,
    /// Mapped lengths in bits.
    bits: Vec<u8>,
    latest: Arc<Mutex<Option<Frame>>>,
    _callback: Option<PdoCallback>,
}

/// One client's gateway state: default node, SDO settings, local PDOs.
pub struct Session {
    master: Master,
    node: Option<u8>,
    net: u16,
    sdo_timeout: Duration,
    retries: u8,
    block: bool,
    rpdo: BTreeMap<u16, LocalPdo>,
    tpdo: BTreeMap<u16, LocalPdo>,
}

fn ok(seq: u32) -> String {
    format!("[{seq}] OK\r\n")
}

fn value(seq: u32, v: &str) -> String {
    format!("[{seq}] {v}\r\n")
}

/// `[seq] ERROR:CODE #text`.
pub fn error(seq: u32, c: u16) -> String {
    format!("[{seq}] ERROR:{c} #{}\r\n", code::text(c))
}

fn sdo_error(seq: u32, e: &SdoError) -> String {
    let abort = match e {
        SdoError::Abort { code, .. } | SdoError::Protocol(code) | SdoError::LocalAbort(code) => code.0,
        // The client sent 0504 0000h when it gave up (CiA 301).
        SdoError::Timeout => 0x0504_0000,
        SdoError::InvalidRequest(_) | SdoError::Decode(_) => return error(seq, code::SYNTAX),
        SdoError::Transport(_) => return error(seq, code::INTERNAL_STATE),
        // The last attempt's failure, as a lone client would have seen it.
        SdoError::OtherClient { cause, .. } => return sdo_error(seq, cause),
    };
    let text = crate::SdoAbort(abort).description().unwrap_or("-");
    format!("[{seq}] ERROR:0x{abort:08X} #{text}\r\n")
}

fn lss_error(seq: u32, e: LssError, refused: u16) -> String {
    match e {
        LssError::Timeout => error(seq, code::TIMEOUT),
        LssError::Refused { error: 0xFF, .. } => error(seq, code::LSS_MANUFACTURER),
        LssError::Refused { .. } => error(seq, refused),
        LssError::InvalidArgument(_) => error(seq, code::SYNTAX),
        LssError::Transport(_) => error(seq, code::INTERNAL_STATE),
    }
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// MIME base64 (RFC 2045) in one line, as CiA 309-3 writes octet strings.
pub fn base64(data: &[u8]) -> String {
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for i in 0..4 {
            if i <= c.len() {
                s.push(B64[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Decodes base64; `None` for a character outside the alphabet.
pub fn unbase64(s: &str) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    let (mut acc, mut n) = (0u32, 0);
    for c in s.bytes().filter(|c| *c != b'=') {
        let v = B64.iter().position(|&b| b == c)? as u32;
        acc = acc << 6 | v;
        n += 6;
        if n >= 8 {
            n -= 8;
            out.push((acc >> n) as u8);
        }
    }
    Some(out)
}

/// The answer text of an upload in `ty` (no type: hex bytes).
fn show(ty: Option<GwType>, data: &[u8]) -> Option<String> {
    Some(match ty {
        None | Some(GwType::Raw) => data.iter().map(|b| format!("{b:02X}")).collect::<Vec<_>>().join(" "),
        Some(GwType::Hex(t)) => {
            let w = t.fixed_size()?;
            let v = Value::decode(t, data).ok()?.as_i128()?;
            format!("0x{v:0w$X}", w = w * 2)
        }
        Some(GwType::Basic(t)) => match t {
            DataType::VisibleString => {
                let end = data.iter().rposition(|&b| b != 0).map_or(0, |p| p + 1);
                let s = String::from_utf8_lossy(&data[..end]).replace('\r', "");
                format!("\"{}\"", s.replace('"', "\"\""))
            }
            DataType::OctetString | DataType::UnicodeString | DataType::Domain => base64(data),
            _ => match Value::decode(t, data).ok()? {
                Value::Bool(b) => u8::from(b).to_string(),
                v => v.to_string(),
            },
        },
    })
}

/// The bytes of a download value in `ty`; `None` for a bad value.
fn encode(ty: GwType, tokens: &[String]) -> Option<Vec<u8>> {
    let one = || match tokens {
        [t] => Some(t.as_str()),
        _ => None,
    };
    match ty {
        GwType::Raw => {
            let hex: String = tokens.concat();
            if !hex.len().is_multiple_of(2) {
                return None;
            }
            (0..hex.len()).step_by(2).map(|i| u8::from_str_radix(hex.get(i..i + 2)?, 16).ok()).collect()
        }
        GwType::Hex(t) => Value::U64(c_number(one()?)?).encode(t).ok(),
        GwType::Basic(t) => match t {
            DataType::VisibleString => {
                let text = tokens.join(" ");
                let inner = text.strip_prefix('"').and_then(|s| s.strip_suffix('"')).unwrap_or(&text);
                Some(inner.as_bytes().to_vec())
            }
            DataType::OctetString | DataType::UnicodeString | DataType::Domain => unbase64(one()?),
            DataType::Real32 => Some(one()?.parse::<f32>().ok()?.to_le_bytes().to_vec()),
            DataType::Real64 => Some(one()?.parse::<f64>().ok()?.to_le_bytes().to_vec()),
            DataType::Boolean => match c_number(one()?)? {
                v @ 0..=1 => Some(vec![v as u8]),
                _ => None,
            },
            t => {
                let text = one()?;
                let signed = t.name().starts_with("INTEGER");
                let v = if signed { Value::I64(c_signed(text)?) } else { Value::U64(c_number(text)?) };
                v.encode(t).ok()
            }
        },
    }
}

const HELP: &str = "\nCommand strings start with \"[\"<sequence>\"]\" followed by:\n\
[[<net>] <node>] r[ead] <index> <subindex> [<datatype>]        # SDO upload.\n\
[[<net>] <node>] w[rite] <index> <subindex> <datatype> <value> # SDO download.\n\
[[<net>] <node>] start|stop|preop[erational]|reset node|reset comm[unication]  # NMT.\n\
[<net>] set network|node|sdo_timeout|sdo_block <value>\n\
[<net>] r[ead] p[do] <n> | w[rite] p[do] <n> <count> <values...>  # the gateway's PDOs\n\
[<net>] set rpdo|tpdo <n> <cob-id> <type> <count> [<index> <subindex>] <datatype>...\n\
info version | help [datatype|lss]\n\
Response: \"[\"<sequence>\"]\" OK | <value> | ERROR:<code> | ERROR:0x<SDO-abort-code>\r\n";

const HELP_TYPES: &str = "\nDatatypes: b, i8, i16, i32, i64, u8, u16, u32, u64, x8, x16, x32, x64 (hex),\n\
r32, r64, vs (visible string, in double quotes if it has blanks), os, us, d (base64), hex (bytes)\r\n";

const HELP_LSS: &str = "\nLSS: lss_switch_glob <0|1> | lss_switch_sel <vendor> <product> <revision> <serial> |\n\
lss_set_node <node> | lss_conf_bitrate 0 <index> | lss_activate_bitrate <ms> | lss_store |\n\
lss_inquire_addr [<0..3>] | lss_get_node | lss_ident_nonconf | _lss_fastscan [<ms>] |\n\
lss_allnodes [<ms> [<first node> <store 0|1>]]\r\n";

impl Session {
    /// A session with the default node and SDO timeout of the command line.
    pub fn new(master: Master, node: Option<u8>, sdo_timeout: Duration, retries: u8) -> Session {
        Session {
            master,
            node,
            net: 1,
            sdo_timeout,
            retries,
            block: false,
            rpdo: BTreeMap::new(),
            tpdo: BTreeMap::new(),
        }
    }

    fn target(&self, node: Option<u8>) -> Result<u8, u16> {
        node.or(self.node).ok_or(code::NO_DEFAULT_NODE)
    }

    /// The answer to one line (CR LF terminated; an empty line or a
    /// comment gets an empty answer, as CANopenNode gives).
    pub async fn line(&mut self, line: &str) -> String {
        let p = parse(line);
        let seq = p.seq.unwrap_or(0);
        if let Some(net) = p.net
            && net != 0
            && net != self.net
        {
            return error(seq, code::UNSUPPORTED_NET);
        }
        match p.request {
            Err((c, _why)) => error(seq, c),
            Ok(r) => self.execute(seq, r).await,
        }
    }

    async fn execute(&mut self, seq: u32, r: ServiceRequest) -> String {
        match r {
            ServiceRequest::Empty => "\r\n".to_owned(),
            ServiceRequest::Read { node, index, sub, ty } => self.sdo_read(seq, node, index, sub, ty).await,
            ServiceRequest::Write { node, index, sub, ty, value } => {
                self.sdo_write(seq, node, index, sub, ty, &value).await
            }
            ServiceRequest::Nmt { node, cs } => match self.target(node) {
                Ok(n) => match self.master.send(Frame::new(0x000, &[cs, n])).await {
                    Ok(()) => ok(seq),
                    Err(_) => error(seq, code::INTERNAL_STATE),
                },
                Err(c) => error(seq, c),
            },
            ServiceRequest::SetNetwork(n) => {
                if n == 0 || n == 1 {
                    self.net = 1;
                    ok(seq)
                } else {
                    error(seq, code::UNSUPPORTED_NET)
                }
            }
            ServiceRequest::SetNode(n) => {
                self.node = Some(n);
                ok(seq)
            }
            ServiceRequest::SetSdoTimeout(ms) => {
                self.sdo_timeout = Duration::from_millis(u64::from(ms));
                ok(seq)
            }
            ServiceRequest::SetSdoBlock(b) => {
                self.block = b;
                ok(seq)
            }
            ServiceRequest::InfoVersion => {
                // No CANopen identity of its own: vendor/product/serial 0; gateway
                // class 4 (SDO, NMT, PDO, LSS), CiA 309-3 protocol 3.0.
                let (maj, min) = version();
                value(seq, &format!("0 0 {maj}.{min} 0 4 3.0 {maj}.{min}"))
            }
            ServiceRequest::Help(topic) => match topic.as_deref() {
                None => HELP.to_owned(),
                Some("datatype") => HELP_TYPES.to_owned(),
                Some("lss") => HELP_LSS.to_owned(),
                Some(_) => error(seq, code::SYNTAX),
            },
            ServiceRequest::Lss { cmd, args } => self.lss(seq, &cmd, &args).await,
            ServiceRequest::PdoRead(num) => self.pdo_read(seq, num),
            ServiceRequest::PdoWrite { num, values } => self.pdo_write(seq, num, &values).await,
            ServiceRequest::SetPdo { tx, ext, args } => self.set_pdo(seq, tx, ext, &args),
        }
    }

    /// `[net] [node] r[ead] INDEX SUB TYPE`: an SDO upload shown as TYPE.
    async fn sdo_read(
        &mut self,
        seq: u32,
        node: Option<u8>,
        index: u16,
        sub: u8,
        ty: Option<GwType>,
    ) -> String {
        let node = match self.target(node) {
            Ok(n) if n > 0 => n,
            Ok(_) => return error(seq, code::UNSUPPORTED_NODE),
            Err(c) => return error(seq, c),
        };
        let proto = if self.block { Protocol::Block } else { Protocol::Auto };
        let sdo = self.master.sdo(node).timeout(self.sdo_timeout).retries(self.retries).protocol(proto);
        match sdo.upload(index, sub).await {
            Ok(d) => match show(ty, &d) {
                Some(v) => value(seq, &v),
                // The data do not fit the type asked for (CiA 301 0607 0010h).
                None => sdo_error(seq, &SdoError::Abort { code: crate::SdoAbort::TYPE_MISMATCH, text: None }),
            },
            Err(e) => sdo_error(seq, &e),
        }
    }

    /// `[net] [node] w[rite] INDEX SUB TYPE VALUE`: an SDO download.
    async fn sdo_write(
        &mut self,
        seq: u32,
        node: Option<u8>,
        index: u16,
        sub: u8,
        ty: GwType,
        v: &[String],
    ) -> String {
        let node = match self.target(node) {
            Ok(n) if n > 0 => n,
            Ok(_) => return error(seq, code::UNSUPPORTED_NODE),
            Err(c) => return error(seq, c),
        };
        let Some(data) = encode(ty, v).filter(|d| !d.is_empty()) else {
            return error(seq, code::SYNTAX);
        };
        let proto = if self.block && data.len() > 4 { Protocol::Block } else { Protocol::Auto };
        let sdo = self.master.sdo(node).timeout(self.sdo_timeout).retries(self.retries).protocol(proto);
        match sdo.download(index, sub, &data).await {
            Ok(()) => ok(seq),
            Err(e) => sdo_error(seq, &e),
        }
    }

    /// `read pdo N`: the values of the last RPDO N received, per mapped entry.
    fn pdo_read(&self, seq: u32, num: u16) -> String {
        match self.rpdo.get(&num) {
            None => error(seq, code::INTERNAL_STATE),
            Some(p) => {
                let frame = *p.latest.lock().unwrap_or_else(|e| e.into_inner());
                let data = frame.map(|f| f.data().to_vec()).unwrap_or_default();
                let mut s = format!("{} pdo {}", self.net, p.bits.len());
                for m in layout_of(&p.bits) {
                    let v = m.read(&data).unwrap_or(0);
                    s.push_str(&format!(" 0x{v:x}"));
                }
                value(seq, &s)
            }
        }
    }

    /// `write pdo N VALUES...`: sends TPDO N with VALUES packed by its mapping.
    async fn pdo_write(&self, seq: u32, num: u16, values: &[u64]) -> String {
        match self.tpdo.get(&num) {
            None => error(seq, code::INTERNAL_STATE),
            Some(p) if p.bits.len() != values.len() => error(seq, code::SYNTAX),
            Some(p) => {
                let mut data = [0u8; 8];
                let mut len_bits = 0;
                for (m, &v) in layout_of(&p.bits).zip(values) {
                    m.write(&mut data, v);
                    len_bits = m.end();
                }
                let len = len_bits.div_ceil(8);
                match self.master.send_pdo(p.cob, &data[..len.min(8)]).await {
                    Ok(()) => ok(seq),
                    Err(_) => error(seq, code::INTERNAL_STATE),
                }
            }
        }
    }

    /// `set rpdo|tpdo[x] N COBID TRANS [INHIBIT EVENT | SYNC] COUNT ([INDEX SUB] TYPE)...`.
    fn set_pdo(&mut self, seq: u32, tx: bool, ext: bool, a: &[String]) -> String {
        let mut it = a.iter();
        let mut n = || it.next().and_then(|s| c_number(s));
        let (Some(num), Some(cob), Some(trans)) = (n(), n(), n()) else { return error(seq, code::SYNTAX) };
        if !(1..=512).contains(&num) || trans > 255 {
            return error(seq, code::SYNTAX);
        }
        let mut rest: Vec<&String> = a.iter().skip(3).collect();
        if ext && tx {
            // Inhibit time and event timer, or the SYNC start value.
            let skip = if trans >= 0xFD { 2 } else { 1 };
            if rest.len() < skip {
                return error(seq, code::SYNTAX);
            }
            rest.drain(..skip);
        }
        let Some(count) = rest.first().and_then(|s| c_number(s)) else { return error(seq, code::SYNTAX) };
        let mut bits = Vec::new();
        let mut i = 1;
        for _ in 0..count {
            // An optional INDEX SUB before the type (dummy mapping without it).
            if rest.get(i).is_some_and(|t| GwType::parse(t).is_none()) {
                i += 2;
            }
            let Some(b) = rest.get(i).and_then(|t| GwType::parse(t)).and_then(GwType::bits) else {
                return error(seq, code::SYNTAX);
            };
            bits.push(b);
            i += 1;
        }
        if i != rest.len() || bits.iter().map(|&b| usize::from(b)).sum::<usize>() > 64 {
            return error(seq, code::SYNTAX);
        }
        let cob16 = (cob & 0x7FF) as u16;
        let latest: Arc<Mutex<Option<Frame>>> = Arc::default();
        let callback = (!tx && cob & 0x8000_0000 == 0).then(|| {
            let l = latest.clone();
            self.master.on_pdo(cob16, move |f, _| *l.lock().unwrap_or_else(|e| e.into_inner()) = Some(*f))
        });
        let pdo = LocalPdo { cob: cob16, bits, latest, _callback: callback };
        if tx {
            self.tpdo.insert(num as u16, pdo);
        } else {
            self.rpdo.insert(num as u16, pdo);
        }
        ok(seq)
    }

    async fn lss(&mut self, seq: u32, cmd: &str, a: &[String]) -> String {
        let arg = |i: usize| a.get(i).and_then(|s| c_number(s));
        let lss = self.master.lss().timeout(self.sdo_timeout.min(Duration::from_millis(500)));
        match (cmd, a.len()) {
            ("lss_switch_glob", 1) => {
                let mode = match arg(0) {
                    Some(0) => LssMode::Waiting,
                    Some(1) => LssMode::Configuration,
                    _ => return error(seq, code::SYNTAX),
                };
                match lss.switch_global(mode).await {
                    Ok(()) => ok(seq),
                    Err(e) => lss_error(seq, e, code::INTERNAL_STATE),
                }
            }
            ("lss_switch_sel", 4) => {
                let v: Option<Vec<u32>> =
                    (0..4).map(|i| arg(i).and_then(|v| u32::try_from(v).ok())).collect();
                let Some(v) = v else { return error(seq, code::SYNTAX) };
                match lss.switch_selective(&Identity::new(v[0], v[1], v[2], v[3])).await {
                    Ok(()) => ok(seq),
                    Err(e) => lss_error(seq, e, code::INTERNAL_STATE),
                }
            }
            ("lss_set_node", 1) => match arg(0) {
                Some(n @ (1..=127 | 255)) => match lss.configure_node_id(n as u8).await {
                    Ok(()) => ok(seq),
                    Err(e) => lss_error(seq, e, code::LSS_NODE_ID),
                },
                _ => error(seq, code::SYNTAX),
            },
            ("lss_conf_bitrate", 2) => match (arg(0), arg(1)) {
                (Some(0), Some(i @ 0..=9)) if i != 5 => match lss.configure_bit_timing(i as u8).await {
                    Ok(()) => ok(seq),
                    Err(e) => lss_error(seq, e, code::LSS_BITRATE),
                },
                _ => error(seq, code::SYNTAX),
            },
            ("lss_activate_bitrate", 1) => match arg(0).and_then(|v| u16::try_from(v).ok()) {
                Some(ms) => match lss.activate_bit_timing(ms).await {
                    Ok(()) => ok(seq),
                    Err(e) => lss_error(seq, e, code::INTERNAL_STATE),
                },
                None => error(seq, code::SYNTAX),
            },
            ("lss_store", 0) => match lss.store().await {
                Ok(()) => ok(seq),
                Err(e) => lss_error(seq, e, code::LSS_STORE),
            },
            ("lss_get_node", 0) => match lss.inquire_node_id().await {
                Ok(n) => value(seq, &format!("0x{n:02X}")),
                Err(e) => lss_error(seq, e, code::INTERNAL_STATE),
            },
            ("lss_inquire_addr", 0) => match lss.inquire_identity().await {
                Ok(x) => value(seq, &addr_text(&x)),
                Err(e) => lss_error(seq, e, code::INTERNAL_STATE),
            },
            ("lss_inquire_addr", 1) => {
                let field = match arg(0) {
                    Some(0) => LssField::Vendor,
                    Some(1) => LssField::Product,
                    Some(2) => LssField::Revision,
                    Some(3) => LssField::Serial,
                    _ => return error(seq, code::SYNTAX),
                };
                match lss.inquire_identity().await {
                    Ok(x) => value(seq, &format!("0x{:08X}", field.get(&x))),
                    Err(e) => lss_error(seq, e, code::INTERNAL_STATE),
                }
            }
            ("lss_ident_nonconf", 0) => match lss.identify_non_configured().await {
                Ok(true) => ok(seq),
                Ok(false) => error(seq, code::TIMEOUT),
                Err(e) => lss_error(seq, e, code::INTERNAL_STATE),
            },
            ("_lss_fastscan", 0 | 1) => {
                let ms = arg(0).filter(|&v| v > 0).unwrap_or(100).min(0xFFFF);
                let lss = lss.timeout(Duration::from_millis(ms));
                match lss.fastscan().await {
                    Ok(Some(x)) => value(seq, &addr_text(&x)),
                    Ok(None) => error(seq, code::TIMEOUT),
                    Err(e) => lss_error(seq, e, code::INTERNAL_STATE),
                }
            }
            ("lss_allnodes", n) if n == 0 || n == 1 || n == 3 || n == 11 => {
                Self::lss_allnodes(seq, lss, n, a).await
            }
            _ => error(
                seq,
                if cmd.starts_with("lss_") || cmd == "_lss_fastscan" {
                    code::SYNTAX
                } else {
                    code::NOT_SUPPORTED
                },
            ),
        }
    }
    /// `lss_allnodes [TIMEOUT [NODE STORE [VEND_MASK VEND ... SER_MASK SER]]]`:
    /// fastscan and give node-IDs from NODE up until no slave answers.
    async fn lss_allnodes(seq: u32, lss: crate::lss::LssMaster, n: usize, a: &[String]) -> String {
        let arg = |i: usize| a.get(i).and_then(|s| c_number(s));
        let ms = arg(0).filter(|&v| v > 0).unwrap_or(100).min(0xFFFF);
        let (mut id, store) = if n >= 3 {
            match (arg(1), arg(2)) {
                (Some(s @ 1..=127), Some(st @ 0..=1)) => (s as u8, st == 1),
                _ => return error(seq, code::SYNTAX),
            }
        } else {
            (2, true)
        };
        let known: Vec<(LssField, u32)> = if n == 11 {
            let fields = [LssField::Vendor, LssField::Product, LssField::Revision, LssField::Serial];
            let mut k = Vec::new();
            for (i, f) in fields.into_iter().enumerate() {
                match (arg(3 + 2 * i), arg(4 + 2 * i).and_then(|v| u32::try_from(v).ok())) {
                    (Some(2), Some(v)) => k.push((f, v)),
                    (Some(0 | 1), Some(_)) => {}
                    _ => return error(seq, code::SYNTAX),
                }
            }
            k
        } else {
            Vec::new()
        };
        let lss = lss.timeout(Duration::from_millis(ms));
        let mut out = String::new();
        let mut found = 0;
        loop {
            let scan =
                known.iter().fold(FastScan::new(Duration::from_millis(ms)), |s, (f, v)| s.with_known(*f, *v));
            match lss.assign_node_id_with(scan, id, store).await {
                Ok(Some(x)) => {
                    found += 1;
                    out.push_str(&format!("# Node-ID {id} assigned to: {}\n", addr_text(&x)));
                }
                Ok(None) => break,
                Err(e) => return out + &lss_error(seq, e, code::LSS_NODE_ID),
            }
            if id == 127 {
                out.push_str("# Not all nodes scanned!\n");
                return out + &ok(seq);
            }
            id += 1;
        }
        out + &format!("# Found {found} nodes, search finished.\n") + &ok(seq)
    }
}

/// An LSS address as the gateway prints it: four 32-bit hex numbers.
fn addr_text(x: &Identity) -> String {
    format!("0x{:08X} 0x{:08X} 0x{:08X} 0x{:08X}", x.vendor_id, x.product_code, x.revision, x.serial)
}

fn version() -> (u32, u32) {
    let mut v = env!("CARGO_PKG_VERSION").split('.').map(|p| p.parse::<u32>().unwrap_or(0));
    (v.next().unwrap_or(0), v.next().unwrap_or(0))
}

/// A local PDO's values, placed by their lengths alone (the gateway's
/// `set rpdo`/`set tpdo` give no objects).
fn layout_of(bits: &[u8]) -> impl Iterator<Item = drivebus_pdo::MappedObject> + '_ {
    drivebus_pdo::layout(bits.iter().map(|&b| drivebus_pdo::PdoMapEntry::new(0, 0, b)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips() {
        for data in [&b""[..], b"a", b"ab", b"abc", b"drivebus gateway"] {
            assert_eq!(unbase64(&base64(data)).unwrap(), data);
        }
        assert_eq!(base64(b"Man"), "TWFu");
        assert_eq!(base64(b"Ma"), "TWE=");
        assert!(unbase64("T!").is_none());
    }

    #[test]
    fn values_shown_and_encoded_per_type() {
        let t = |s| GwType::parse(s).unwrap();
        assert_eq!(show(Some(t("u16")), &[0xF4, 0x01]).unwrap(), "500");
        assert_eq!(show(Some(t("i16")), &(-300i16).to_le_bytes()).unwrap(), "-300");
        assert_eq!(show(Some(t("x32")), &0x20192u32.to_le_bytes()).unwrap(), "0x00020192");
        assert_eq!(show(Some(t("vs")), b"say \"hi\"").unwrap(), "\"say \"\"hi\"\"\"");
        assert_eq!(show(None, &[0x92, 0x01, 0x02, 0x00]).unwrap(), "92 01 02 00");
        assert_eq!(show(Some(t("b")), &[1]).unwrap(), "1");
        assert!(show(Some(t("u32")), &[1]).is_none());
        let v = |s: &str| vec![s.to_owned()];
        assert_eq!(encode(t("u16"), &v("0x1F4")).unwrap(), 500u16.to_le_bytes());
        assert_eq!(encode(t("i16"), &v("-300")).unwrap(), (-300i16).to_le_bytes());
        assert!(encode(t("u8"), &v("256")).is_none());
        assert!(encode(t("u8"), &v("x")).is_none());
        assert_eq!(encode(t("vs"), &["\"a b\"".to_owned()]).unwrap(), b"a b");
        assert_eq!(encode(t("vs"), &["a".to_owned(), "b".to_owned()]).unwrap(), b"a b");
        assert_eq!(encode(t("hex"), &["0102".to_owned(), "03".to_owned()]).unwrap(), [1, 2, 3]);
        assert!(encode(t("hex"), &v("123")).is_none());
        assert_eq!(encode(t("d"), &v("TWFu")).unwrap(), b"Man");
    }

    proptest::proptest! {
        /// Any value text for any type, and any bytes shown as any type:
        /// a value or `None` (answered as a 309-3 error), never a panic.
        #[test]
        fn any_value_encodes_or_errs(
            ty in proptest::sample::select(vec![
                "b", "i8", "i16", "i32", "i64", "u8", "u16", "u32", "u64", "x8", "x16", "x32", "x64",
                "r32", "r64", "t", "td", "vs", "os", "us", "d", "hex",
            ]),
            words in proptest::collection::vec("\\PC{0,12}", 0..4),
            data in proptest::collection::vec(proptest::num::u8::ANY, 0..12),
        ) {
            if let Some(t) = GwType::parse(ty) {
                let _ = encode(t, &words);
                let _ = show(Some(t), &data);
            }
            let _ = unbase64(words.first().map_or("", String::as_str));
        }
    }
}
