//! SDO transfers inside the core: one `drivebus_sdo::client::SdoClient`
//! per running transfer, one transfer per server at a time (an SDO server
//! runs one), transfers to different servers in parallel. Later requests
//! to a busy server queue in order.

use std::collections::{HashMap, VecDeque};
use std::sync::Arc;

use drivebus_can::{CanId, Frame, Instant};
use drivebus_od::SdoAbort;
use drivebus_sdo::client::{ClientError, Completed, Protocol, SdoClient, SdoClientConfig};
use tokio::sync::oneshot;

/// A progress callback: bytes done, total when known.
pub type Progress = Arc<dyn Fn(usize, Option<usize>) + Send + Sync>;

/// The outcome a transfer's future receives.
pub(crate) type Outcome = Result<Completed, ClientError>;

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
}

#[derive(Default)]
struct Server {
    active: Option<Active>,
    queue: VecDeque<(u64, Request)>,
}

/// Every server the master talks to, keyed by its response COB-ID.
#[derive(Default)]
pub(crate) struct SdoPool {
    servers: HashMap<CanId, Server>,
    /// Transfers started (for reports).
    pub started: u64,
}

impl SdoPool {
    /// Queues `req` (starts it at once when its server is idle).
    pub(crate) fn start(&mut self, id: u64, req: Request, now: Instant, out: &mut Vec<Frame>) {
        let key = req.cfg.rx_id;
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
                    })
                }
                Err(e) => {
                    let _ = req.done.send(Err(e));
                }
            }
        }
    }

    /// Reports progress, delivers a finished result and starts the next
    /// transfer of the server.
    fn settle(server: &mut Server, now: Instant, out: &mut Vec<Frame>, started: &mut u64) {
        let Some(a) = &mut server.active else { return };
        if let Some(r) = a.client.take_result() {
            // A final report at 100 %: the last segment completes the
            // transfer without another progress step.
            if let (Some(cb), Ok(done)) = (&a.progress, &r) {
                let total = match done {
                    Completed::Upload(d) => d.len(),
                    Completed::Download => a.download_len,
                };
                cb(total, Some(total));
            }
            if let Some(done) = a.done.take() {
                let _ = done.send(r);
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
    }
}
