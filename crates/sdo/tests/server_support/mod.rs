//! A tiny scripted SDO client and a test dictionary for the server's
//! integration tests. It deliberately does not use `client.rs`: the server
//! is checked against the protocol as written here, frame by frame.
#![allow(dead_code)]

use drivebus_can::{Duration, Frame, Instant};
use drivebus_od::{Access, DataType, NoHooks, Object, ObjectDictionary, SubObject, Value};
use drivebus_sdo::crc::crc16;
use drivebus_sdo::server::{SdoServer, ServerConfig};

pub const NODE: u8 = 5;
pub const RX: u16 = 0x600 + NODE as u16;
pub const TX: u16 = 0x580 + NODE as u16;

/// 1000h u32 ro, 1007h u32 rw, 2000h DOMAIN rw of `domain_len` bytes.
pub fn test_od(domain_len: usize) -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    od.insert(Object::var(0x1000, "Device type", DataType::Unsigned32, Access::Ro, Value::U32(0x0002_0192)));
    od.insert(Object::var(0x1007, "Window", DataType::Unsigned32, Access::Rw, Value::U32(0)));
    od.insert(Object::var(
        0x2000,
        "Blob",
        DataType::Domain,
        Access::Rw,
        Value::Bytes(pattern(domain_len, 1)),
    ));
    od.insert(Object::var(0x2001, "Text", DataType::VisibleString, Access::Rw, Value::Str("hello".into())));
    od.insert(
        Object::record(0x2010, "Rec")
            .with_sub(SubObject::new(1, "a", DataType::Unsigned8, Access::Rw, Value::U8(7)))
            .with_sub(SubObject::new(2, "b", DataType::Integer64, Access::Rw, Value::I64(-2))),
    );
    od
}

/// Deterministic non-trivial bytes.
pub fn pattern(len: usize, seed: u32) -> Vec<u8> {
    let mut x = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
    (0..len)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as u8
        })
        .collect()
}

/// The server on its bus: one request in, its responses out.
pub struct Wire {
    pub server: SdoServer,
    pub od: ObjectDictionary,
    pub now: Instant,
    out: Vec<Frame>,
}

impl Wire {
    pub fn new(od: ObjectDictionary, config: ServerConfig) -> Wire {
        Wire { server: SdoServer::default_channel(NODE, config), od, now: Instant::ZERO, out: Vec::new() }
    }

    /// Send one request; every response must be an 8-byte frame on TX.
    pub fn send(&mut self, data: [u8; 8]) -> Vec<[u8; 8]> {
        self.now += Duration::from_micros(100);
        self.out.clear();
        self.server.handle_frame(&Frame::new8(RX, data), self.now, &mut self.od, &mut NoHooks, &mut self.out);
        self.out
            .iter()
            .map(|f| {
                assert_eq!((f.std_id(), f.len()), (Some(TX), 8), "{f}");
                *f.raw_data()
            })
            .collect()
    }

    /// Send one request and return the last response without building a
    /// vector (for the allocation test); `[0; 8]` if there was none.
    pub fn send_no_alloc(&mut self, data: [u8; 8]) -> [u8; 8] {
        self.send_count(data).1
    }

    /// Send one request; return how many responses came and the last one.
    pub fn send_count(&mut self, data: [u8; 8]) -> (usize, [u8; 8]) {
        self.now += Duration::from_micros(100);
        let mut n = 0;
        let mut last = [0; 8];
        let mut sink = |f: Frame| {
            n += 1;
            last = *f.raw_data();
        };
        self.server.handle_frame(&Frame::new8(RX, data), self.now, &mut self.od, &mut NoHooks, &mut sink);
        (n, last)
    }

    fn one(&mut self, data: [u8; 8]) -> Result<[u8; 8], [u8; 8]> {
        let r = self.send(data);
        assert_eq!(r.len(), 1, "request {data:02X?} got {r:02X?}");
        if r[0][0] == 0x80 { Err(r[0]) } else { Ok(r[0]) }
    }

    /// Expedited or segmented upload, as a CiA 301 client does it.
    pub fn upload(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, [u8; 8]> {
        let i = index.to_le_bytes();
        let r = self.one([0x40, i[0], i[1], sub, 0, 0, 0, 0])?;
        self.finish_upload(r)
    }

    /// Continue an upload from its initiate response (also used after a
    /// block upload request switched protocol).
    pub fn finish_upload(&mut self, r: [u8; 8]) -> Result<Vec<u8>, [u8; 8]> {
        if r[0] & 0x02 != 0 {
            let n = 4 - usize::from((r[0] >> 2) & 3);
            return Ok(r[4..4 + n].to_vec());
        }
        assert_eq!(r[0], 0x41);
        let size = u32::from_le_bytes([r[4], r[5], r[6], r[7]]) as usize;
        let mut data = Vec::with_capacity(size);
        let mut toggle = 0u8;
        loop {
            let s = self.one([0x60 | toggle, 0, 0, 0, 0, 0, 0, 0])?;
            assert_eq!(s[0] & 0xF0, toggle);
            let k = 7 - usize::from((s[0] >> 1) & 7);
            data.extend_from_slice(&s[1..1 + k]);
            if s[0] & 1 != 0 {
                break;
            }
            toggle ^= 0x10;
        }
        assert_eq!(data.len(), size);
        Ok(data)
    }

    /// Segmented download (size indicated), or expedited for ≤ 4 bytes.
    pub fn download(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), [u8; 8]> {
        let i = index.to_le_bytes();
        if !data.is_empty() && data.len() <= 4 {
            let mut f = [0x23 | (((4 - data.len()) as u8) << 2), i[0], i[1], sub, 0, 0, 0, 0];
            f[4..4 + data.len()].copy_from_slice(data);
            self.one(f)?;
            return Ok(());
        }
        let s = (data.len() as u32).to_le_bytes();
        assert_eq!(self.one([0x21, i[0], i[1], sub, s[0], s[1], s[2], s[3]])?[0], 0x60);
        let mut toggle = 0u8;
        let mut chunks = data.chunks(7).peekable();
        if data.is_empty() {
            self.one([0x0F, 0, 0, 0, 0, 0, 0, 0])?;
            return Ok(());
        }
        while let Some(c) = chunks.next() {
            let last = chunks.peek().is_none();
            let mut f = [toggle | (((7 - c.len()) as u8) << 1) | u8::from(last), 0, 0, 0, 0, 0, 0, 0];
            f[1..1 + c.len()].copy_from_slice(c);
            assert_eq!(self.one(f)?, [0x20 | toggle, 0, 0, 0, 0, 0, 0, 0]);
            toggle ^= 0x10;
        }
        Ok(())
    }

    /// Block upload. `lose` names 0-based segment numbers (counted over the
    /// whole transfer, retransmissions included) that the client "misses".
    pub fn block_upload(
        &mut self,
        index: u16,
        sub: u8,
        blksize: u8,
        crc: bool,
        lose: &[usize],
    ) -> Result<Vec<u8>, [u8; 8]> {
        let i = index.to_le_bytes();
        let r = self.one([0xA0 | (u8::from(crc) << 2), i[0], i[1], sub, blksize, 0, 0, 0])?;
        assert_eq!(r[0] & 0xFB, 0xC2, "size indicated, ss=0");
        let server_crc = r[0] & 0x04 != 0;
        let size = u32::from_le_bytes([r[4], r[5], r[6], r[7]]) as usize;
        let mut data = Vec::with_capacity(size + 7);
        let mut seen = 0usize;
        let mut segs = self.send([0xA3, 0, 0, 0, 0, 0, 0, 0]);
        loop {
            let mut ackseq = 0u8;
            let mut done = false;
            for s in &segs {
                let lost = lose.contains(&seen);
                seen += 1;
                if lost || s[0] & 0x7F != ackseq + 1 {
                    continue;
                }
                ackseq += 1;
                data.extend_from_slice(&s[1..8]);
                done = s[0] & 0x80 != 0;
            }
            segs = self.send([0xA2, ackseq, blksize, 0, 0, 0, 0, 0]);
            if done {
                break;
            }
        }
        assert_eq!(segs.len(), 1);
        let end = segs[0];
        if end[0] == 0x80 {
            return Err(end);
        }
        assert_eq!(end[0] & 0xE3, 0xC1);
        let n = usize::from((end[0] >> 2) & 7);
        data.truncate(data.len() - n);
        assert_eq!(data.len(), size);
        if crc && server_crc {
            assert_eq!(u16::from_le_bytes([end[1], end[2]]), crc16(&data), "block upload CRC");
        }
        assert!(self.send([0xA1, 0, 0, 0, 0, 0, 0, 0]).is_empty());
        Ok(data)
    }

    /// Block download with size. `lose` as for [`Wire::block_upload`]:
    /// those segments are "sent" but never reach the server.
    pub fn block_download(
        &mut self,
        index: u16,
        sub: u8,
        data: &[u8],
        crc: bool,
        lose: &[usize],
    ) -> Result<(), [u8; 8]> {
        let i = index.to_le_bytes();
        let s = (data.len() as u32).to_le_bytes();
        let r = self.one([0xC2 | (u8::from(crc) << 2), i[0], i[1], sub, s[0], s[1], s[2], s[3]])?;
        assert_eq!(r[0] & 0xFB, 0xA0);
        let mut blksize = r[4];
        let total = data.len().div_ceil(7).max(1);
        let mut next = 0usize; // next segment (0-based over the data)
        let mut sent = 0usize;
        loop {
            let first = next;
            let mut acks = Vec::new();
            for seq in 1..=blksize {
                let k = first + usize::from(seq) - 1;
                if k >= total {
                    break;
                }
                let last = k + 1 == total;
                let mut f = [seq | (u8::from(last) << 7), 0, 0, 0, 0, 0, 0, 0];
                let chunk = data.get(k * 7..((k + 1) * 7).min(data.len())).unwrap_or(&[]);
                f[1..1 + chunk.len()].copy_from_slice(chunk);
                let lost = lose.contains(&sent);
                sent += 1;
                if !lost {
                    acks.extend(self.send(f));
                }
            }
            assert_eq!(acks.len(), 1, "one ack per sub-block: {acks:02X?}");
            let a = acks[0];
            if a[0] == 0x80 {
                return Err(a);
            }
            assert_eq!(a[0], 0xA2);
            next = first + usize::from(a[1]);
            blksize = a[2];
            if next >= total {
                break;
            }
        }
        let n = (total * 7 - data.len()) as u8;
        let c = if crc { crc16(data) } else { 0 }.to_le_bytes();
        let r = self.one([0xC1 | (n << 2), c[0], c[1], 0, 0, 0, 0, 0])?;
        assert_eq!(r, [0xA1, 0, 0, 0, 0, 0, 0, 0]);
        Ok(())
    }
}
