//! Test rig and a sans-IO mini master for the mailbox server.
//!
//! `Rig` plays the ESC: a request goes in as the master wrote SM0 (padded
//! to the SM0 length), responses come out as the master reads SM1. The
//! `ethercrab` module packs requests byte for byte as ethercrab 0.7.1's
//! encoders do (`src/mailbox/coe/services.rs`); the `soem` module runs
//! SOEM's client algorithms (`ec_coe.c`, `ec_foe.c`: sizes, segmenting,
//! fragment parsing, BUSY handling), re-expressed here, not copied.
#![allow(dead_code)]

use drivebus_base::{Duration, Instant};
use drivebus_coe::{AlState, FileHandler, MailboxConfig, MailboxServer, ObjectAccess};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectCode, ObjectDictionary, SubObject, Value};

pub type Dev = (ObjectDictionary, NoHooks);

pub struct Rig<A: ObjectAccess, F: FileHandler> {
    pub server: MailboxServer,
    pub dev: A,
    pub files: F,
    pub now: Instant,
    pub state: AlState,
    /// The master's mailbox counter (SOEM's `ec_nextmbxcnt`: 1..=7).
    cnt: u8,
}

impl<A: ObjectAccess, F: FileHandler> Rig<A, F> {
    pub fn new(config: MailboxConfig, dev: A, files: F) -> Self {
        Rig {
            server: MailboxServer::new(config).unwrap(),
            dev,
            files,
            now: Instant::from_millis(1),
            state: AlState::PreOp,
            cnt: 0,
        }
    }
    pub fn rx(&self) -> usize {
        self.server.config().rx_size
    }
    pub fn tx(&self) -> usize {
        self.server.config().tx_size
    }
    pub fn counter(&mut self) -> u8 {
        self.cnt = if self.cnt >= 7 { 1 } else { self.cnt + 1 };
        self.cnt
    }
    pub fn tick(&mut self, d: Duration) {
        self.now += d;
    }
    /// The master writes SM0: its bytes, then zeros to the SM0 length.
    pub fn send(&mut self, req: &[u8]) {
        let mut sm0 = req.to_vec();
        sm0.resize(sm0.len().max(self.rx()), 0);
        self.now += Duration::from_micros(50);
        self.server.handle_request(&sm0, self.now, self.state, &mut self.dev, &mut self.files);
    }
    /// The master reads SM1 (if the slave wrote it).
    pub fn read(&mut self) -> Option<Vec<u8>> {
        self.now += Duration::from_micros(50);
        let r = self.server.next_response(self.now).map(<[u8]>::to_vec);
        if let Some(m) = &r {
            assert!(m.len() <= self.tx(), "response longer than SM1");
            assert_eq!(usize::from(u16::from_le_bytes([m[0], m[1]])) + 6, m.len(), "length field");
        }
        r
    }
    /// Request, then exactly one response.
    pub fn one(&mut self, req: &[u8]) -> Vec<u8> {
        self.send(req);
        self.read().expect("a response")
    }
}

/// The service data of a response (after the 6-byte header).
pub fn body(m: &[u8]) -> &[u8] {
    &m[6..]
}
/// Mailbox type of a response.
pub fn mtype(m: &[u8]) -> u8 {
    m[5] & 0x0F
}
/// Mailbox header bytes with counter `cnt` and type `t`.
pub fn header(len: usize, t: u8, cnt: u8) -> [u8; 6] {
    let l = (len as u16).to_le_bytes();
    [l[0], l[1], 0, 0, 0, t | (cnt << 4)]
}
/// A whole mailbox: header with the body's length, then the body.
pub fn mbx(t: u8, cnt: u8, body: &[u8]) -> Vec<u8> {
    let mut v = header(body.len(), t, cnt).to_vec();
    v.extend_from_slice(body);
    v
}

/// A small but varied device: every kind of entry the server treats
/// differently.
pub fn test_od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    od.insert(Object::var(0x1000, "Device type", DataType::Unsigned32, Access::Ro, Value::U32(0x0006_0192)));
    od.insert(Object::var(
        0x1008,
        "Manufacturer device name",
        DataType::VisibleString,
        Access::Const,
        Value::Str("drivebus iPOS twin".into()),
    ));
    od.insert(
        Object::record(0x1018, "Identity Object")
            .with_sub(SubObject::new(1, "Vendor ID", DataType::Unsigned32, Access::Ro, Value::U32(0x1A3)))
            .with_sub(SubObject::new(
                2,
                "Product Code",
                DataType::Unsigned32,
                Access::Ro,
                Value::U32(28002021),
            ))
            .with_sub(SubObject::new(3, "Revision", DataType::Unsigned32, Access::Ro, Value::U32(0x30313030)))
            .with_sub(SubObject::new(4, "Serial", DataType::Unsigned32, Access::Ro, Value::U32(0x4C451158))),
    );
    od.insert(pdo_assign(0x1C12, 0x1600, 1, 4));
    od.insert(pdo_assign(0x1C13, 0x1A00, 2, 4));
    od.insert(mapping(0x1600, &[0x6040_0010, 0x607A_0020]));
    od.insert(mapping(0x1A00, &[0x6041_0010, 0x6064_0020]));
    od.insert(mapping(0x1A01, &[0x6061_0008]));
    od.insert(Object::var(0x2000, "Blob", DataType::Domain, Access::Rw, Value::Bytes(pattern(300, 1))));
    od.insert(Object::var(0x2001, "Text", DataType::VisibleString, Access::Rw, Value::Str("hello".into())));
    od.insert(Object::var(0x2002, "Password", DataType::Unsigned8, Access::Wo, Value::U8(0)));
    od.insert(
        Object::var(0x2003, "Limited", DataType::Integer16, Access::Rw, Value::I16(0)).with_sub(
            SubObject::new(0, "Limited", DataType::Integer16, Access::Rw, Value::I16(5))
                .limits(Value::I16(-100), Value::I16(100))
                .mappable(),
        ),
    );
    od.insert(
        Object::record(0x2100, "Flags")
            .with_sub(SubObject::new(1, "a", DataType::Unsigned8, Access::Rw, Value::U8(0x11)))
            .with_sub(SubObject::new(2, "on", DataType::Boolean, Access::Rw, Value::Bool(true)))
            .with_sub(SubObject::new(3, "off", DataType::Boolean, Access::Rw, Value::Bool(false)))
            .with_sub(SubObject::new(4, "c", DataType::Unsigned32, Access::Ro, Value::U32(0xA1B2C3D4))),
    );
    od.insert(Object::array(0x3000, "Table", DataType::Unsigned32, Access::Rw, 64, Value::U32(0)));
    for i in 1..=64u8 {
        let r = od.find(0x3000, i).unwrap();
        od.set_raw(r, &(0x0101_0101u32 * u32::from(i)).to_le_bytes());
    }
    od.insert(Object::var(0x6040, "Controlword", DataType::Unsigned16, Access::Rww, Value::U16(0)).with_sub(
        SubObject::new(0, "Controlword", DataType::Unsigned16, Access::Rww, Value::U16(0)).mappable(),
    ));
    od.insert(
        Object::var(0x6041, "Statusword", DataType::Unsigned16, Access::Ro, Value::U16(0x0250)).with_sub(
            SubObject::new(0, "Statusword", DataType::Unsigned16, Access::Ro, Value::U16(0x0250)).mappable(),
        ),
    );
    od
}

/// A PDO assignment object (1C12h/1C13h): writable sub 0 = `n`, `max` u16 entries.
pub fn pdo_assign(index: u16, first: u16, n: u8, max: u8) -> Object {
    let mut o = Object::with_code(index, ObjectCode::Array, "Sync Manager PDO assignment")
        .with_sub(SubObject::new(0, "Number of entries", DataType::Unsigned8, Access::Rw, Value::U8(n)));
    for i in 1..=max {
        let v = if i <= n { first + u16::from(i) - 1 } else { 0 };
        o = o.with_sub(SubObject::new(i, "PDO", DataType::Unsigned16, Access::Rw, Value::U16(v)));
    }
    o
}

/// A PDO mapping record with a writable sub 0 and 8 u32 entries.
pub fn mapping(index: u16, entries: &[u32]) -> Object {
    let mut o = Object::with_code(index, ObjectCode::Record, "PDO Mapping").with_sub(SubObject::new(
        0,
        "Number of mapped objects",
        DataType::Unsigned8,
        Access::Rw,
        Value::U8(entries.len() as u8),
    ));
    for i in 1..=8u8 {
        let v = entries.get(usize::from(i) - 1).copied().unwrap_or(0);
        o = o.with_sub(SubObject::new(i, "Mapped object", DataType::Unsigned32, Access::Rw, Value::U32(v)));
    }
    o
}

pub fn pattern(n: usize, seed: u8) -> Vec<u8> {
    (0..n).map(|i| (i as u8).wrapping_mul(31).wrapping_add(seed)).collect()
}

/// The iPOS twin's dictionary, from the personality's EDS.
pub fn ipos_od() -> ObjectDictionary {
    let text = include_str!("../../../personality/eds/ipos.eds");
    drivebus_eds::to_od(&drivebus_eds::parse(text).unwrap().eds, 1).unwrap()
}

/// Requests packed as ethercrab 0.7.1 packs them (`services.rs`): the
/// mailbox header has length 10 (8 for SDO Info), address 0, priority 0.
pub mod ethercrab {
    /// `SdoNormal::upload`: 12 bytes; `None` is `SubIndex::Complete`
    /// (complete access at sub-index 1).
    pub fn upload(cnt: u8, index: u16, sub: Option<u8>) -> Vec<u8> {
        let i = index.to_le_bytes();
        let (ca, s) = match sub {
            Some(s) => (0, s),
            None => (0x10, 1),
        };
        vec![0x0a, 0, 0, 0, 0, 0x03 | (cnt << 4), 0x00, 0x20, 0x40 | ca, i[0], i[1], s]
    }
    /// `SdoExpedited::download`: 16 bytes, size indicator and expedited set.
    pub fn download(cnt: u8, index: u16, sub: Option<u8>, value: &[u8]) -> Vec<u8> {
        let i = index.to_le_bytes();
        let (ca, s) = match sub {
            Some(s) => (0, s),
            None => (0x10, 1),
        };
        let n = value.len() as u8;
        let mut v =
            vec![0x0a, 0, 0, 0, 0, 0x03 | (cnt << 4), 0x00, 0x20, 0x23 | ca | ((4 - n) << 2), i[0], i[1], s];
        let mut d = [0u8; 4];
        d[..value.len()].copy_from_slice(value);
        v.extend_from_slice(&d);
        v
    }
    /// `SdoSegmented::upload`: 9 bytes.
    pub fn upload_segment(cnt: u8, toggle: bool) -> Vec<u8> {
        vec![0x0a, 0, 0, 0, 0, 0x03 | (cnt << 4), 0x00, 0x20, 0x60 | if toggle { 0x10 } else { 0 }]
    }
    /// `ObjectDescriptionListRequest`: 14 bytes.
    pub fn od_list(cnt: u8, list: u16) -> Vec<u8> {
        let l = list.to_le_bytes();
        vec![0x08, 0, 0, 0, 0, 0x03 | (cnt << 4), 0x00, 0x80, 0x01, 0, 0, 0, l[0], l[1]]
    }
    /// ethercrab's reading of an OD list answer (`send_sdo_info_service`):
    /// it copies `length - 8` bytes after the 12-byte headers of every
    /// fragment, skipping the list type in the first.
    pub fn parse_od_list(fragments: &[Vec<u8>]) -> Vec<u16> {
        let mut buf = Vec::new();
        for (n, f) in fragments.iter().enumerate() {
            let length = usize::from(u16::from_le_bytes([f[0], f[1]])) - 8;
            let start = if n == 0 { 14 } else { 12 };
            buf.extend_from_slice(&f[start..start + length]);
        }
        buf.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect()
    }
}

/// What a SOEM-style call returns instead of data.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Fail {
    Abort(u32),
    InfoError(u32),
    FoeError(u32),
    MailboxError(u16),
    Unexpected(Vec<u8>),
    NoResponse,
}

/// SOEM's client algorithms over a `Rig`.
pub mod soem {
    use super::*;

    fn coe(rig_cnt: u8, body: &[u8]) -> Vec<u8> {
        mbx(0x03, rig_cnt, body)
    }

    fn classify(m: Vec<u8>) -> Fail {
        if mtype(&m) == 0 {
            return Fail::MailboxError(u16::from_le_bytes([m[8], m[9]]));
        }
        let b = body(&m);
        if mtype(&m) == 3 && b.len() >= 10 && b[2] == 0x80 {
            return Fail::Abort(u32::from_le_bytes([b[6], b[7], b[8], b[9]]));
        }
        if mtype(&m) == 3 && b[1] >> 4 == 8 && b[2] & 0x7F == 7 {
            return Fail::InfoError(u32::from_le_bytes([b[6], b[7], b[8], b[9]]));
        }
        if mtype(&m) == 4 && b[0] == 5 {
            return Fail::FoeError(u32::from_le_bytes([b[2], b[3], b[4], b[5]]));
        }
        Fail::Unexpected(m)
    }

    /// Read the next mailbox that is not an emergency (SOEM's
    /// `ecx_mbxreceive` reports emergencies and keeps waiting).
    pub fn receive<A: ObjectAccess, F: FileHandler>(rig: &mut Rig<A, F>) -> Option<Vec<u8>> {
        loop {
            let m = rig.read()?;
            let b = body(&m);
            if mtype(&m) == 3 && b[1] >> 4 == 1 {
                continue;
            }
            return Some(m);
        }
    }

    /// `ecx_SDOread`.
    pub fn sdo_read<A: ObjectAccess, F: FileHandler>(
        rig: &mut Rig<A, F>,
        index: u16,
        sub: u8,
        ca: bool,
    ) -> Result<Vec<u8>, Fail> {
        let i = index.to_le_bytes();
        let c = rig.counter();
        let sub = if ca && sub > 1 { 1 } else { sub };
        rig.send(&coe(c, &[0x00, 0x20, if ca { 0x50 } else { 0x40 }, i[0], i[1], sub, 0, 0, 0, 0]));
        let m = receive(rig).ok_or(Fail::NoResponse)?;
        let b = body(&m);
        if !(mtype(&m) == 3 && b[1] >> 4 == 3 && b[3..5] == i) {
            return Err(classify(m));
        }
        if b[2] & 0x02 != 0 {
            let n = 4 - usize::from((b[2] >> 2) & 3);
            return Ok(b[6..6 + n].to_vec());
        }
        let total = u32::from_le_bytes([b[6], b[7], b[8], b[9]]) as usize;
        let here = u16::from_le_bytes([m[0], m[1]]) as usize - 10;
        if here >= total {
            return Ok(b[10..10 + total].to_vec());
        }
        let mut data = b[10..10 + here].to_vec();
        let mut toggle = 0u8;
        loop {
            let c = rig.counter();
            rig.send(&coe(c, &[0x00, 0x20, 0x60 | toggle, i[0], i[1], sub, 0, 0, 0, 0]));
            let m = receive(rig).ok_or(Fail::NoResponse)?;
            let b = body(&m);
            if !(mtype(&m) == 3 && b[1] >> 4 == 3 && b[2] & 0xE0 == 0) {
                return Err(classify(m));
            }
            let mut k = u16::from_le_bytes([m[0], m[1]]) as usize - 3;
            if b[2] & 0x01 != 0 {
                if k == 7 {
                    k -= usize::from((b[2] & 0x0E) >> 1);
                }
                data.extend_from_slice(&b[3..3 + k]);
                return Ok(data);
            }
            data.extend_from_slice(&b[3..3 + k]);
            toggle ^= 0x10;
        }
    }

    /// `ecx_SDOwrite`: expedited up to 4 bytes (not with CA), else normal
    /// with `SM0 − 16` data bytes, then segments of up to `SM0 − 9`.
    pub fn sdo_write<A: ObjectAccess, F: FileHandler>(
        rig: &mut Rig<A, F>,
        index: u16,
        sub: u8,
        ca: bool,
        data: &[u8],
    ) -> Result<(), Fail> {
        let i = index.to_le_bytes();
        let maxdata = rig.rx() - 0x10;
        let c = rig.counter();
        if data.len() <= 4 && !ca {
            let mut b = vec![0x00, 0x20, 0x23 | (((4 - data.len()) << 2) as u8 & 0x0C), i[0], i[1], sub];
            let mut d = [0u8; 4];
            d[..data.len()].copy_from_slice(data);
            b.extend_from_slice(&d);
            rig.send(&coe(c, &b));
            let m = receive(rig).ok_or(Fail::NoResponse)?;
            let b = body(&m);
            return if mtype(&m) == 3 && b[1] >> 4 == 3 && b[3..5] == i && b[5] == sub {
                Ok(())
            } else {
                Err(classify(m))
            };
        }
        let sub = if ca && sub > 1 { 1 } else { sub };
        let first = data.len().min(maxdata);
        let mut b = vec![0x00, 0x20, if ca { 0x31 } else { 0x21 }, i[0], i[1], sub];
        b.extend_from_slice(&(data.len() as u32).to_le_bytes());
        b.extend_from_slice(&data[..first]);
        rig.send(&coe(c, &b));
        let m = receive(rig).ok_or(Fail::NoResponse)?;
        let rb = body(&m);
        if !(mtype(&m) == 3 && rb[1] >> 4 == 3 && rb[3..5] == i && rb[5] == sub) {
            return Err(classify(m));
        }
        let seg_max = maxdata + 7;
        let mut rest = &data[first..];
        let mut toggle = 0u8;
        let mut more = data.len() > maxdata;
        while more {
            let k = rest.len().min(seg_max);
            more = rest.len() > seg_max;
            let mut cmd = if more { 0x00 } else { 0x01 };
            let mut sb = vec![0x00, 0x20];
            if !more && k < 7 {
                cmd |= ((7 - k) << 1) as u8;
                sb.push(cmd | toggle);
                sb.extend_from_slice(&rest[..k]);
                sb.resize(10, 0);
            } else {
                sb.push(cmd | toggle);
                sb.extend_from_slice(&rest[..k]);
            }
            rest = &rest[k..];
            let c = rig.counter();
            rig.send(&coe(c, &sb));
            let m = receive(rig).ok_or(Fail::NoResponse)?;
            let rb = body(&m);
            if !(mtype(&m) == 3 && rb[1] >> 4 == 3 && rb[2] & 0xE0 == 0x20) {
                return Err(classify(m));
            }
            toggle ^= 0x10;
        }
        Ok(())
    }

    /// `ecx_readODlist` (list type 1), generalised to any list type.
    pub fn od_list<A: ObjectAccess, F: FileHandler>(
        rig: &mut Rig<A, F>,
        list: u16,
    ) -> Result<Vec<u16>, Fail> {
        let c = rig.counter();
        let l = list.to_le_bytes();
        rig.send(&coe(c, &[0x00, 0x80, 0x01, 0, 0, 0, l[0], l[1]]));
        let mut out = Vec::new();
        let mut first = true;
        loop {
            let m = receive(rig).ok_or(Fail::NoResponse)?;
            let b = body(&m);
            if !(mtype(&m) == 3 && b[2] & 0x7F == 0x02) {
                return Err(classify(m));
            }
            let len = u16::from_le_bytes([m[0], m[1]]) as usize;
            let (n, off) = if first { ((len - 8) / 2, 8) } else { ((len - 6) / 2, 6) };
            out.extend((0..n).map(|k| u16::from_le_bytes([b[off + 2 * k], b[off + 2 * k + 1]])));
            first = false;
            if u16::from_le_bytes([b[4], b[5]]) == 0 {
                return Ok(out);
            }
        }
    }

    /// `ecx_readODdescription`: (data type, object code, max sub, name).
    pub fn od_desc<A: ObjectAccess, F: FileHandler>(
        rig: &mut Rig<A, F>,
        index: u16,
    ) -> Result<(u16, u8, u8, String), Fail> {
        let c = rig.counter();
        let i = index.to_le_bytes();
        rig.send(&coe(c, &[0x00, 0x80, 0x03, 0, 0, 0, i[0], i[1]]));
        let m = receive(rig).ok_or(Fail::NoResponse)?;
        let b = body(&m);
        if !(mtype(&m) == 3 && b[2] & 0x7F == 0x04) {
            return Err(classify(m));
        }
        let n = u16::from_le_bytes([m[0], m[1]]) as usize - 12;
        let name = String::from_utf8_lossy(&b[12..12 + n]).into_owned();
        Ok((u16::from_le_bytes([b[8], b[9]]), b[11], b[10], name))
    }

    /// Get Entry Description with `value_info`; returns the whole body.
    pub fn oe_raw<A: ObjectAccess, F: FileHandler>(
        rig: &mut Rig<A, F>,
        index: u16,
        sub: u8,
        value_info: u8,
    ) -> Result<Vec<u8>, Fail> {
        let c = rig.counter();
        let i = index.to_le_bytes();
        rig.send(&coe(c, &[0x00, 0x80, 0x05, 0, 0, 0, i[0], i[1], sub, value_info]));
        let m = receive(rig).ok_or(Fail::NoResponse)?;
        if !(mtype(&m) == 3 && body(&m)[2] & 0x7F == 0x06) {
            return Err(classify(m));
        }
        Ok(body(&m).to_vec())
    }

    /// `ecx_readOEsingle` (value info 0x07): (value info, data type, bit
    /// length, object access, name).
    pub fn oe_desc<A: ObjectAccess, F: FileHandler>(
        rig: &mut Rig<A, F>,
        index: u16,
        sub: u8,
    ) -> Result<(u8, u16, u16, u16, String), Fail> {
        let b = oe_raw(rig, index, sub, 0x07)?;
        let w = |k: usize| u16::from_le_bytes([b[k], b[k + 1]]);
        let n = b.len() - 16;
        Ok((b[9], w(10), w(12), w(14), String::from_utf8_lossy(&b[16..16 + n]).into_owned()))
    }

    /// `ecx_FOEwrite`: WRQ, then DATA packets of `SM0 − 12` bytes, an empty
    /// last packet after a full one, the previous packet again on BUSY.
    pub fn foe_write<A: ObjectAccess, F: FileHandler>(
        rig: &mut Rig<A, F>,
        name: &str,
        password: u32,
        data: &[u8],
        busy_ticks: &mut usize,
    ) -> Result<(), Fail> {
        let maxdata = rig.rx() - 12;
        let c = rig.counter();
        let mut b = vec![2u8, 0];
        b.extend_from_slice(&password.to_le_bytes());
        b.extend_from_slice(name.as_bytes());
        rig.send(&mbx(0x04, c, &b));
        let mut sent = 0u32;
        let mut pos = 0usize;
        let mut seg = 0usize;
        let mut final_zero = true;
        loop {
            let m = receive(rig).ok_or(Fail::NoResponse)?;
            let b = body(&m);
            if mtype(&m) != 4 {
                return Err(classify(m));
            }
            let word = u32::from_le_bytes([b[2], b[3], b[4], b[5]]);
            match b[0] {
                4 if word == sent => {
                    let k = (data.len() - pos).min(maxdata);
                    if k == 0 && !final_zero {
                        return Ok(());
                    }
                    final_zero = pos + k == data.len() && k == maxdata;
                    seg = k;
                }
                4 => return Err(Fail::Unexpected(m)),
                6 if sent > 0 => {
                    *busy_ticks += 1;
                    rig.tick(Duration::from_millis(10));
                    pos -= seg;
                    sent -= 1;
                    let k = (data.len() - pos).min(maxdata);
                    final_zero = pos + k == data.len() && k == maxdata;
                    seg = k;
                }
                6 => continue,
                _ => return Err(classify(m)),
            }
            sent += 1;
            let c = rig.counter();
            let mut d = vec![3u8, 0];
            d.extend_from_slice(&sent.to_le_bytes());
            d.extend_from_slice(&data[pos..pos + seg]);
            pos += seg;
            rig.send(&mbx(0x04, c, &d));
        }
    }

    /// `ecx_FOEread`.
    pub fn foe_read<A: ObjectAccess, F: FileHandler>(
        rig: &mut Rig<A, F>,
        name: &str,
        password: u32,
    ) -> Result<Vec<u8>, Fail> {
        let maxdata = rig.tx() - 12;
        let c = rig.counter();
        let mut b = vec![1u8, 0];
        b.extend_from_slice(&password.to_le_bytes());
        b.extend_from_slice(name.as_bytes());
        rig.send(&mbx(0x04, c, &b));
        let mut out = Vec::new();
        let mut prev = 0u32;
        loop {
            let m = receive(rig).ok_or(Fail::NoResponse)?;
            let b = body(&m);
            if !(mtype(&m) == 4 && b[0] == 3) {
                return Err(classify(m));
            }
            let n = u32::from_le_bytes([b[2], b[3], b[4], b[5]]);
            prev += 1;
            assert_eq!(n, prev, "packet number");
            let k = u16::from_le_bytes([m[0], m[1]]) as usize - 6;
            out.extend_from_slice(&b[6..6 + k]);
            let c = rig.counter();
            let mut a = vec![4u8, 0];
            a.extend_from_slice(&n.to_le_bytes());
            rig.send(&mbx(0x04, c, &a));
            if k < maxdata {
                return Ok(out);
            }
        }
    }
}
