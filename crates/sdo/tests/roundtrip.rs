//! Client ↔ server back to back on simulated time: every data type, every
//! protocol and block size, download then upload returns the same bytes; a
//! lossy link still completes block transfers through partial acks.

use drivebus_can::{Duration, Frame, Instant};
use drivebus_od::{ALL_DATA_TYPES, Access, DataType, NoHooks, Object, ObjectDictionary, Value};
use drivebus_sdo::client::{ClientError, Completed, Protocol, SdoClient, SdoClientConfig};
use drivebus_sdo::server::{SdoServer, ServerConfig};
use proptest::prelude::*;

const NODE: u8 = 9;
/// Object of the i-th data type of `ALL_DATA_TYPES`.
const BASE: u16 = 0x3000;

fn od() -> ObjectDictionary {
    let mut od = ObjectDictionary::new();
    for (i, dt) in ALL_DATA_TYPES.iter().enumerate() {
        let default = match dt.fixed_size() {
            Some(n) => Value::Bytes(vec![0; n]),
            None => Value::Bytes(vec![]),
        };
        let mut obj = Object::var(BASE + i as u16, "t", *dt, Access::Rw, default);
        if let Some(n) = dt.fixed_size() {
            // Value::Bytes does not encode fixed types: set the raw zero default.
            obj = Object::with_code(obj.index, drivebus_od::ObjectCode::Var, "t")
                .with_sub(drivebus_od::SubObject::from_bytes(0, "t", *dt, Access::Rw, vec![0; n]));
        }
        od.insert(obj);
    }
    od
}

/// Which side drops which frame (counting that side's frames from 0).
#[derive(Clone, Copy, Default)]
struct Loss {
    client_frame: Option<usize>,
    server_frame: Option<usize>,
}

struct Link {
    client: SdoClient,
    server: SdoServer,
    od: ObjectDictionary,
    now: Instant,
    loss: Loss,
    client_sent: usize,
    server_sent: usize,
}

impl Link {
    fn new(ccfg: SdoClientConfig, scfg: ServerConfig) -> Link {
        Link {
            client: SdoClient::new(ccfg),
            server: SdoServer::default_channel(NODE, scfg),
            od: od(),
            now: Instant::from_millis(1),
            loss: Loss::default(),
            client_sent: 0,
            server_sent: 0,
        }
    }

    /// Carry frames both ways until the client has a result. Each hop takes
    /// 100 µs; when nothing is in flight, time jumps to the next deadline.
    fn run(&mut self, mut from_client: Vec<Frame>) -> Result<Completed, ClientError> {
        for _ in 0..100_000 {
            // Done once the client has a result and its last frames (e.g.
            // the block upload end response) reached the server.
            if from_client.is_empty()
                && let Some(r) = self.client.take_result()
            {
                // Both ends agree the transfer is over.
                assert!(r.is_err() || self.server.is_idle(), "server still busy after {r:?}");
                return r;
            }
            let mut from_server = Vec::new();
            for f in from_client.drain(..) {
                let k = self.client_sent;
                self.client_sent += 1;
                if self.loss.client_frame == Some(k) {
                    continue;
                }
                self.now += Duration::from_micros(100);
                self.server.handle_frame(&f, self.now, &mut self.od, &mut NoHooks, &mut from_server);
            }
            for f in from_server.drain(..) {
                let k = self.server_sent;
                self.server_sent += 1;
                if self.loss.server_frame == Some(k) {
                    continue;
                }
                self.now += Duration::from_micros(100);
                self.client.handle_frame(&f, self.now, &mut from_client);
            }
            // Due server timeouts first, then, on a quiet bus, jump to the
            // earliest deadline and let it fire.
            let mut srv = Vec::new();
            let server_deadline = self.server.poll(self.now, &mut srv);
            for f in srv.drain(..) {
                self.client.handle_frame(&f, self.now, &mut from_client);
            }
            if from_client.is_empty()
                && let Some(t) = drivebus_can::earliest(self.client.deadline(), server_deadline)
            {
                self.now = self.now.max(t);
                self.server.poll(self.now, &mut srv);
                for f in srv.drain(..) {
                    self.client.handle_frame(&f, self.now, &mut from_client);
                }
                self.client.poll(self.now, &mut from_client);
            }
        }
        panic!("transfer did not finish");
    }

    fn download(&mut self, index: u16, data: &[u8], p: Protocol) -> Result<Completed, ClientError> {
        let mut out = Vec::new();
        self.client.start_download(index, 0, data, p, self.now, &mut out).expect("start");
        self.run(out)
    }

    fn upload(&mut self, index: u16, p: Protocol) -> Result<Completed, ClientError> {
        let mut out = Vec::new();
        self.client.start_upload(index, 0, p, self.now, &mut out).expect("start");
        self.run(out)
    }
}

/// A random valid encoding of `dt`.
fn value_of(dt: DataType) -> BoxedStrategy<Vec<u8>> {
    match dt.fixed_size() {
        Some(_) if dt == DataType::Boolean => (0u8..=1).prop_map(|b| vec![b]).boxed(),
        Some(n) => proptest::collection::vec(any::<u8>(), n).boxed(),
        None if dt == DataType::UnicodeString => proptest::collection::vec(any::<u16>(), 0..200)
            .prop_map(|u| u.iter().flat_map(|c| c.to_le_bytes()).collect())
            .boxed(),
        None => prop_oneof![
            3 => proptest::collection::vec(any::<u8>(), 0..64),
            2 => proptest::collection::vec(any::<u8>(), 64..1200),
        ]
        .boxed(),
    }
}

#[derive(Clone, Copy, Debug)]
enum Proto {
    Auto,
    Expedited,
    Segmented,
    Block { crc: bool },
}

fn case() -> impl Strategy<Value = (usize, Vec<u8>, Proto, Proto, u8, u8, u8, bool)> {
    (0..ALL_DATA_TYPES.len()).prop_flat_map(|i| {
        (
            Just(i),
            value_of(ALL_DATA_TYPES[i]),
            prop_oneof![
                Just(Proto::Auto),
                Just(Proto::Expedited),
                Just(Proto::Segmented),
                any::<bool>().prop_map(|crc| Proto::Block { crc }),
            ],
            prop_oneof![
                Just(Proto::Auto),
                Just(Proto::Segmented),
                any::<bool>().prop_map(|crc| Proto::Block { crc }),
            ],
            1u8..=127,
            1u8..=127,
            prop_oneof![Just(0u8), 1u8..=255],
            any::<bool>(),
        )
    })
}

fn config(p: Proto, blksize: u8, pst: u8) -> (SdoClientConfig, Protocol) {
    let mut c = SdoClientConfig::for_node(NODE);
    c.block_size = blksize;
    c.pst = pst;
    let p = match p {
        Proto::Auto => Protocol::Auto,
        Proto::Expedited => Protocol::Expedited,
        Proto::Segmented => Protocol::Segmented,
        Proto::Block { crc } => {
            c.crc = crc;
            Protocol::Block
        }
    };
    (c, p)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn download_then_upload_returns_the_same_bytes(
        (i, data, down, up, client_blk, server_blk, pst, server_crc) in case()
    ) {
        let index = BASE + i as u16;
        let (dcfg, dproto) = config(down, client_blk, pst);
        // Expedited needs 1..=4 bytes; fall back to Auto otherwise.
        let dproto = if dproto == Protocol::Expedited && !(1..=4).contains(&data.len()) { Protocol::Auto } else { dproto };
        let scfg = ServerConfig { block_size: server_blk, crc: server_crc, ..ServerConfig::default() };
        let mut link = Link::new(dcfg, scfg);
        prop_assert_eq!(link.download(index, &data, dproto), Ok(Completed::Download));
        prop_assert_eq!(link.od.get(index, 0).unwrap().bytes(), &data[..]);

        let (ucfg, uproto) = config(up, client_blk, pst);
        link.client = SdoClient::new(ucfg);
        prop_assert_eq!(link.upload(index, uproto), Ok(Completed::Upload(data.clone())));
    }
}

#[test]
fn every_block_size_both_directions() {
    let data: Vec<u8> = (0..=255u8).cycle().take(7 * 127 + 3).collect();
    let index = BASE + 13; // DOMAIN
    for blk in 1..=127u8 {
        for crc in [false, true] {
            let mut c = SdoClientConfig::for_node(NODE);
            c.block_size = blk;
            c.crc = crc;
            let s = ServerConfig { block_size: blk, ..ServerConfig::default() };
            let mut link = Link::new(c, s);
            assert_eq!(link.download(index, &data, Protocol::Block), Ok(Completed::Download), "blk {blk}");
            assert_eq!(link.upload(index, Protocol::Block), Ok(Completed::Upload(data.clone())), "blk {blk}");
        }
    }
}

#[test]
fn lossy_block_download_completes_via_partial_ack() {
    let data: Vec<u8> = (0..100).collect(); // 15 segments
    let index = BASE + 13;
    for dropped in 1..=14 {
        let mut link = Link::new(SdoClientConfig::for_node(NODE), ServerConfig::default());
        // Client frame 0 is the initiate; frames 1..=15 the segments; drop
        // one that is not the last of the sub-block.
        link.loss.client_frame = Some(dropped);
        assert_eq!(link.download(index, &data, Protocol::Block), Ok(Completed::Download), "drop {dropped}");
        assert_eq!(link.od.get(index, 0).unwrap().bytes(), &data[..]);
        // Retransmission happened: more frames than initiate + 15 + end.
        assert!(link.client_sent > 17, "drop {dropped}: {} frames", link.client_sent);
    }
}

#[test]
fn lossy_block_upload_completes_via_partial_ack() {
    let data: Vec<u8> = (0..100).rev().collect();
    let index = BASE + 13;
    for dropped in 1..=14 {
        let mut link = Link::new(SdoClientConfig::for_node(NODE), ServerConfig::default());
        link.od.get_mut(index, 0).unwrap();
        link.od.set_value(index, 0, &Value::Bytes(data.clone())).unwrap();
        // Server frame 0 is the initiate response; 1..=15 the segments.
        link.loss.server_frame = Some(dropped);
        assert_eq!(
            link.upload(index, Protocol::Block),
            Ok(Completed::Upload(data.clone())),
            "drop {dropped}"
        );
        assert!(link.server_sent > 17, "drop {dropped}: {} frames", link.server_sent);
    }
}

#[test]
fn lost_response_is_recovered_by_retry() {
    let mut c = SdoClientConfig::for_node(NODE);
    c.timeout = Duration::from_millis(300);
    let mut link = Link::new(c, ServerConfig::default());
    link.od.set_value(BASE + 6, 0, &Value::U32(0xDEAD_BEEF)).unwrap();
    // The expedited response is lost: the client times out, aborts, retries.
    link.loss.server_frame = Some(0);
    assert_eq!(
        link.upload(BASE + 6, Protocol::Auto),
        Ok(Completed::Upload(0xDEAD_BEEFu32.to_le_bytes().to_vec()))
    );
    assert_eq!(link.client_sent, 3);
}

#[test]
fn block_upload_protocol_switch_below_pst() {
    let index = BASE + 13;
    for (len, pst) in [(3usize, 4u8), (4, 4), (20, 20), (21, 20)] {
        let mut c = SdoClientConfig::for_node(NODE);
        c.pst = pst;
        let mut link = Link::new(c, ServerConfig::default());
        let data: Vec<u8> = (0..len as u8).collect();
        link.od.set_value(index, 0, &Value::Bytes(data.clone())).unwrap();
        assert_eq!(link.upload(index, Protocol::Block), Ok(Completed::Upload(data)), "len {len} pst {pst}");
        // Expedited: request + nothing else; segmented: request + segment
        // requests; block: request, start, ack, end response.
        let want = match len {
            0..=4 => 1,
            _ if len <= usize::from(pst) => 1 + len.div_ceil(7),
            _ => 4,
        };
        assert_eq!(link.client_sent, want, "len {len} pst {pst}");
    }
}
