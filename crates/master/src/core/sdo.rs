//! SDO transfers inside the core: one `drivebus_sdo::client::SdoClient`
//! per running transfer, one transfer per server at a time (an SDO server
//! runs one), transfers to different servers in parallel. Later requests
//! to a busy server queue in order.
//!
//! Another client on the same server (CiA 301's default SDO is meant for
//! one, but a monitor often runs next to a command) shows as requests on
//! the server's request COB-ID that this master did not send, and as
//! answers naming other objects (the client ignores those). A transfer
//! that fails while that is going on is started again where repeating it
//! is safe (reads; writes of up to 4 bytes the server refused for its
//! protocol state, so did not store), up to [`OTHER_CLIENT_RETRIES`]
//! times; if it still fails, its outcome says another client was there.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

use drivebus_can::{CanId, Frame, Instant};
use drivebus_od::SdoAbort;
use drivebus_sdo::client::{ClientError, Completed, Protocol, SdoClient, SdoClientConfig};
use tokio::sync::oneshot;

/// A progress callback: bytes done, total when known.
pub type Progress = Arc<dyn Fn(usize, Option<usize>) + Send + Sync>;

/// How often a transfer disturbed by another client is started again.
pub(crate) const OTHER_CLIENT_RETRIES: u8 = 3;

/// Another client's traffic seen during a transfer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct OtherClient {
    /// Its requests on the server's request COB-ID.
    pub requests: u32,
    /// Answers to it (naming other objects) the client ignored.
    pub answers: u32,
    /// The object the last of those answers named.
    pub last: Option<(u16, u8)>,
    /// Times the transfer was started again.
    pub retries: u8,
}

impl OtherClient {
    fn seen(&self) -> bool {
        self.requests > 0 || self.answers > 0
    }
}

/// The outcome a transfer's future receives: the result and, when it
/// failed, another client's traffic seen meanwhile.
pub(crate) struct Outcome {
    pub result: Result<Completed, ClientError>,
    pub other: Option<OtherClient>,
}

/// What it takes to start a transfer again.
#[derive(Clone)]
struct Again {
    cfg: SdoClientConfig,
    index: u16,
    sub: u8,
    /// A download's data, kept for downloads of up to 4 bytes only.
    data: Option<Vec<u8>>,
    download: bool,
    protocol: Protocol,
}

/// One transfer asked for.
pub(crate) struct Request {
    pub cfg: SdoClientConfig,
    pub index: u16,
    pub sub: u8,
    /// `Some` for a download.
    pub data: Option<Vec<u8>>,
    pub protocol: Protocol,
    pub progress: Option<Progress>,
    pub done: oneshot::Sender<Outcome>,
}

struct Active {
    id: u64,
    client: SdoClient,
    progress: Option<Progress>,
    last_progress: Option<(usize, Option<usize>)>,
    download_len: usize,
    done: Option<oneshot::Sender<Outcome>>,
    again: Again,
    other: OtherClient,
}

impl Active {
    /// Starts the transfer again after another client disturbed it, when
    /// repeating it is safe; true if it did.
    fn retry(&mut self, e: &ClientError, now: Instant, out: &mut Vec<Frame>) -> bool {
        let other = OtherClient {
            answers: self.other.answers + self.client.foreign_answers(),
            last: self.client.last_foreign().or(self.other.last),
            ..self.other
        };
        self.other = other;
        if !other.seen() || other.retries >= OTHER_CLIENT_RETRIES {
            return false;
        }
        // The server refused the transfer for its protocol state (another
        // client's request came in between): nothing was stored.
        let refused = match e {
            ClientError::ProtocolViolation(_) => true,
            ClientError::ServerAbort(code) => code.0 >> 16 == 0x0504 || code.0 == 0x0503_0000,
            _ => false,
        };
        let safe = if self.again.download {
            refused && self.again.data.is_some()
        } else {
            refused || *e == ClientError::Timeout
        };
        if !safe {
            return false;
        }
        let a = self.again.clone();
        let mut client = SdoClient::new(a.cfg);
        let started = match a.data {
            Some(d) if a.download => client.start_download_owned(a.index, a.sub, d, a.protocol, now, out),
            _ => client.start_upload(a.index, a.sub, a.protocol, now, out),
        };
        if started.is_err() {
            return false;
        }
        self.client = client;
        self.other.retries += 1;
        true
    }
}

#[derive(Default)]
struct Server {
    active: Option<Active>,
    queue: VecDeque<(u64, Request)>,
}

/// Every server the master talks to, keyed by its response COB-ID.
/// Ordered maps: transfers due at the same instant (a scan's timed-out
/// probes) send their frames in COB-ID order, so a simulated run repeats
/// frame for frame.
#[derive(Default)]
pub(crate) struct SdoPool {
    servers: BTreeMap<CanId, Server>,
    /// Request COB-ID → response COB-ID of the servers in `servers`:
    /// another client's requests show there.
    requests: BTreeMap<CanId, CanId>,
    /// Transfers started (for reports).
    pub started: u64,
}

impl SdoPool {
    /// Queues `req` (starts it at once when its server is idle).
    pub(crate) fn start(&mut self, id: u64, req: Request, now: Instant, out: &mut Vec<Frame>) {
        let key = req.cfg.rx_id;
        self.requests.insert(req.cfg.tx_id, key);
        let server = self.servers.entry(key).or_default();
        server.queue.push_back((id, req));
        if server.active.is_none() {
            Self::next(server, now, out, &mut self.started);
        }
    }

    /// Starts the next queued transfer of `server`, if any.
    fn next(server: &mut Server, now: Instant, out: &mut Vec<Frame>, started: &mut u64) {
        while server.active.is_none() {
            let Some((id, req)) = server.queue.pop_front() else { return };
            let mut client = SdoClient::new(req.cfg);
            let download_len = req.data.as_ref().map_or(0, Vec::len);
            let again = Again {
                cfg: req.cfg,
                index: req.index,
                sub: req.sub,
                data: req.data.as_ref().filter(|d| d.len() <= 4).cloned(),
                download: req.data.is_some(),
                protocol: req.protocol,
            };
            let r = match req.data {
                Some(d) => client.start_download_owned(req.index, req.sub, d, req.protocol, now, out),
                None => client.start_upload(req.index, req.sub, req.protocol, now, out),
            };
            *started += 1;
            match r {
                Ok(()) => {
                    server.active = Some(Active {
                        id,
                        client,
                        progress: req.progress,
                        last_progress: None,
                        download_len,
                        done: Some(req.done),
                        again,
                        other: OtherClient::default(),
                    })
                }
                Err(e) => {
                    let _ = req.done.send(Outcome { result: Err(e), other: None });
                }
            }
        }
    }

    /// Reports progress, delivers a finished result and starts the next
    /// transfer of the server.
    fn settle(server: &mut Server, now: Instant, out: &mut Vec<Frame>, started: &mut u64) {
        let Some(a) = &mut server.active else { return };
        if let Some(r) = a.client.take_result() {
            if let Err(e) = &r
                && a.retry(e, now, out)
            {
                return;
            }
            // A final report at 100 %: the last segment completes the
            // transfer without another progress step.
            if let (Some(cb), Ok(done)) = (&a.progress, &r) {
                let total = match done {
                    Completed::Upload(d) => d.len(),
                    Completed::Download => a.download_len,
                };
                cb(total, Some(total));
            }
            let other = (r.is_err() && a.other.seen()).then_some(a.other);
            if let Some(done) = a.done.take() {
                let _ = done.send(Outcome { result: r, other });
            }
            server.active = None;
            Self::next(server, now, out, started);
        } else if let (Some(cb), Some(p)) = (&a.progress, a.client.progress())
            && a.last_progress != Some(p)
        {
            a.last_progress = Some(p);
            cb(p.0, p.1);
        }
    }

    pub(crate) fn handle_frame(&mut self, f: &Frame, now: Instant, out: &mut Vec<Frame>) {
        // A request to a server we talk to, not sent by us: another client.
        if let Some(key) = self.requests.get(&f.id()) {
            if let Some(a) = self.servers.get_mut(key).and_then(|s| s.active.as_mut()) {
                a.other.requests = a.other.requests.saturating_add(1);
            }
            return;
        }
        let Some(server) = self.servers.get_mut(&f.id()) else { return };
        let Some(a) = &mut server.active else { return };
        a.client.handle_frame(f, now, out);
        Self::settle(server, now, out, &mut self.started);
    }

    pub(crate) fn poll(&mut self, now: Instant, out: &mut Vec<Frame>) -> Option<Instant> {
        let mut next = None;
        for server in self.servers.values_mut() {
            if let Some(a) = &mut server.active {
                a.client.poll(now, out);
                Self::settle(server, now, out, &mut self.started);
            }
            if let Some(a) = &server.active {
                next = drivebus_can::earliest(next, a.client.deadline());
            }
        }
        self.servers.retain(|_, s| s.active.is_some() || !s.queue.is_empty());
        if self.requests.len() > self.servers.len() {
            let servers = &self.servers;
            self.requests.retain(|_, rx| servers.contains_key(rx));
        }
        next
    }

    pub(crate) fn deadline(&self) -> Option<Instant> {
        self.servers.values().filter_map(|s| s.active.as_ref().and_then(|a| a.client.deadline())).min()
    }

    /// The future of transfer `id` went away: abort it on the bus (the
    /// server frees itself at once instead of timing out) or unqueue it.
    pub(crate) fn cancel(&mut self, id: u64, now: Instant, out: &mut Vec<Frame>) {
        for server in self.servers.values_mut() {
            server.queue.retain(|(i, _)| *i != id);
            if let Some(a) = &mut server.active
                && a.id == id
            {
                a.client.abort(SdoAbort::GENERAL_ERROR, out);
                server.active = None;
                Self::next(server, now, out, &mut self.started);
            }
        }
    }

    /// The bus is gone: every transfer ends now.
    pub(crate) fn fail_all(&mut self) {
        // Dropping the senders makes every waiting future see the bus error.
        self.servers.clear();
        self.requests.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(data: Option<Vec<u8>>) -> (Request, oneshot::Receiver<Outcome>) {
        let (done, rx) = oneshot::channel();
        let req = Request {
            cfg: SdoClientConfig::for_node(5),
            index: 0x1018,
            sub: 1,
            data,
            protocol: Protocol::Auto,
            progress: None,
            done,
        };
        (req, rx)
    }

    fn frame(id: u16, bytes: [u8; 8]) -> Frame {
        Frame::new(id, &bytes)
    }

    /// Issue 15: a read the server refused while another client's request
    /// was on the bus is started again, and then succeeds.
    #[test]
    fn a_disturbed_read_is_started_again() {
        let mut pool = SdoPool::default();
        let mut out = Vec::new();
        let now = Instant::ZERO;
        let (req, mut rx) = request(None);
        pool.start(1, req, now, &mut out);
        assert_eq!(out.len(), 1);
        out.clear();
        // Another client's request to node 5, then the server's abort of ours.
        pool.handle_frame(&frame(0x605, [0x40, 0x41, 0x60, 0, 0, 0, 0, 0]), now, &mut out);
        pool.handle_frame(&frame(0x585, [0x80, 0x18, 0x10, 1, 0x01, 0, 0x04, 0x05]), now, &mut out);
        assert_eq!(out, [frame(0x605, [0x40, 0x18, 0x10, 1, 0, 0, 0, 0])], "started again");
        assert!(rx.try_recv().is_err(), "not finished yet");
        pool.handle_frame(&frame(0x585, [0x43, 0x18, 0x10, 1, 0xBC, 0x0A, 0, 0]), now, &mut out);
        let o = rx.try_recv().unwrap();
        assert_eq!(o.result, Ok(Completed::Upload(vec![0xBC, 0x0A, 0, 0])));
    }

    /// A write longer than 4 bytes is not repeated; its failure says
    /// another client was there. A genuine abort is not retried either.
    #[test]
    fn unsafe_repeats_are_reported_not_retried() {
        let mut pool = SdoPool::default();
        let mut out = Vec::new();
        let now = Instant::ZERO;
        let (req, mut rx) = request(Some(vec![1, 2, 3, 4, 5, 6]));
        pool.start(1, req, now, &mut out);
        out.clear();
        pool.handle_frame(&frame(0x605, [0x40, 0x41, 0x60, 0, 0, 0, 0, 0]), now, &mut out);
        pool.handle_frame(&frame(0x585, [0x80, 0x18, 0x10, 1, 0x01, 0, 0x04, 0x05]), now, &mut out);
        assert!(out.is_empty(), "{out:?}");
        let o = rx.try_recv().unwrap();
        assert!(o.result.is_err());
        assert_eq!(o.other.map(|c| (c.requests, c.retries)), Some((1, 0)));

        let (req, mut rx) = request(None);
        pool.start(2, req, now, &mut out);
        out.clear();
        pool.handle_frame(&frame(0x605, [0x40, 0x41, 0x60, 0, 0, 0, 0, 0]), now, &mut out);
        pool.handle_frame(&frame(0x585, [0x80, 0x18, 0x10, 1, 0, 0, 0x02, 0x06]), now, &mut out);
        assert!(out.is_empty(), "0602 0000 is the object's own answer");
        assert_eq!(rx.try_recv().unwrap().result, Err(ClientError::ServerAbort(SdoAbort::NO_OBJECT)));
    }
}
