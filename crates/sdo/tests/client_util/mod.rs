//! Helpers shared by the client tests: scripted server frames and
//! byte-exact assertions on what the client sends.
#![allow(dead_code)]

use drivebus_can::{Duration, Frame, Instant};
use drivebus_sdo::client::{Protocol, SdoClient, SdoClientConfig};

/// Node used by the synthetic tests (600h+5 / 580h+5).
pub const NODE: u8 = 5;
pub const TX: u16 = 0x600 + NODE as u16;
pub const RX: u16 = 0x580 + NODE as u16;

/// Parse "4B 41 60 00 40 02 00 00" into bytes.
pub fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace().map(|b| u8::from_str_radix(b, 16).expect("hex byte")).collect()
}

/// A frame on `id` from a hex string.
pub fn fr(id: u16, s: &str) -> Frame {
    Frame::new(id, &hex(s))
}

/// A client for [`NODE`] with the default configuration.
pub fn client() -> SdoClient {
    SdoClient::new(SdoClientConfig::for_node(NODE))
}

pub fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

/// A client driver that records what the client sends, step by step.
pub struct Script {
    pub c: SdoClient,
    pub now: Instant,
    pub out: Vec<Frame>,
    pub tx: u16,
    pub rx: u16,
}

impl Script {
    pub fn new(c: SdoClient) -> Self {
        let tx = c.config().tx_id.raw() as u16;
        let rx = c.config().rx_id.raw() as u16;
        Script { c, now: Instant::ZERO, out: Vec::new(), tx, rx }
    }

    pub fn node() -> Self {
        Script::new(client())
    }

    pub fn upload(&mut self, index: u16, sub: u8, p: Protocol) {
        self.c.start_upload(index, sub, p, self.now, &mut self.out).expect("start upload");
    }

    pub fn download(&mut self, index: u16, sub: u8, data: &[u8], p: Protocol) {
        self.c.start_download(index, sub, data, p, self.now, &mut self.out).expect("start download");
    }

    /// Assert the client sent exactly these frames (hex strings) since the
    /// last check, on its tx COB-ID.
    #[track_caller]
    pub fn sent(&mut self, frames: &[&str]) {
        let want: Vec<Frame> = frames.iter().map(|s| fr(self.tx, s)).collect();
        let got: Vec<Frame> = self.out.drain(..).collect();
        assert_eq!(got, want, "frames sent by the client");
    }

    /// Assert nothing was sent since the last check.
    #[track_caller]
    pub fn silent(&mut self) {
        self.sent(&[]);
    }

    /// The server sends `s` on the client's rx COB-ID, 1 ms later.
    pub fn recv(&mut self, s: &str) {
        self.now += Duration::from_millis(1);
        let f = fr(self.rx, s);
        self.c.handle_frame(&f, self.now, &mut self.out);
    }
}
