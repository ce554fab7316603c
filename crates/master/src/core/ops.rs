//! Frame-driven operations inside the core: a request/answer exchange
//! (LSS services) and the LSS fastscan. Each sends its frames when
//! started, looks at every received frame, and finishes by answering its
//! future through a oneshot channel.

use drivebus_can::{Duration, Frame, Instant};
use drivebus_lss::{FastScan, FastScanOutcome};
use tokio::sync::oneshot;

/// An operation the core drives; the sans-IO contract of the services.
pub(crate) trait Op: Send {
    /// Sends the first frames.
    fn start(&mut self, now: Instant, out: &mut Vec<Frame>);
    /// A frame was received.
    fn handle_frame(&mut self, f: &Frame, now: Instant, out: &mut Vec<Frame>);
    /// Work due at `now`; the next deadline.
    fn poll(&mut self, now: Instant, out: &mut Vec<Frame>) -> Option<Instant>;
    /// The current deadline, without work.
    fn deadline(&self) -> Option<Instant>;
    /// Finished (its future has been answered).
    fn done(&self) -> bool;
}

/// Which received frames an [`Exchange`] wants.
pub(crate) type Matcher = Box<dyn Fn(&Frame) -> bool + Send>;

/// Sends frames, then collects the matching answers until the first one
/// (`first_only`) or until the timeout; answers with what it collected
/// (empty on a timeout).
pub(crate) struct Exchange {
    frames: Vec<Frame>,
    matcher: Matcher,
    first_only: bool,
    timeout: Duration,
    deadline: Option<Instant>,
    got: Vec<Frame>,
    done: Option<oneshot::Sender<Vec<Frame>>>,
}

impl Exchange {
    pub(crate) fn new(
        frames: Vec<Frame>,
        matcher: Matcher,
        first_only: bool,
        timeout: Duration,
    ) -> (Exchange, oneshot::Receiver<Vec<Frame>>) {
        let (tx, rx) = oneshot::channel();
        (
            Exchange {
                frames,
                matcher,
                first_only,
                timeout,
                deadline: None,
                got: Vec::new(),
                done: Some(tx),
            },
            rx,
        )
    }

    fn finish(&mut self) {
        if let Some(d) = self.done.take() {
            let _ = d.send(std::mem::take(&mut self.got));
        }
    }
}

impl Op for Exchange {
    fn start(&mut self, now: Instant, out: &mut Vec<Frame>) {
        out.append(&mut self.frames);
        self.deadline = Some(now + self.timeout);
    }
    fn handle_frame(&mut self, f: &Frame, _now: Instant, _out: &mut Vec<Frame>) {
        if self.done.is_some() && (self.matcher)(f) {
            self.got.push(*f);
            if self.first_only {
                self.finish();
            }
        }
    }
    fn poll(&mut self, now: Instant, _out: &mut Vec<Frame>) -> Option<Instant> {
        if self.deadline.is_some_and(|d| now >= d) {
            self.finish();
        }
        self.deadline()
    }
    fn deadline(&self) -> Option<Instant> {
        if self.done.is_some() { self.deadline } else { None }
    }
    fn done(&self) -> bool {
        self.done.is_none()
    }
}

/// The LSS fastscan state machine (`drivebus_lss::FastScan`) as an op.
pub(crate) struct FastScanOp {
    scan: FastScan,
    /// The scanner's deadline, as its last `poll` returned it.
    next: Option<Instant>,
    done: Option<oneshot::Sender<FastScanOutcome>>,
}

impl FastScanOp {
    pub(crate) fn new(scan: FastScan) -> (FastScanOp, oneshot::Receiver<FastScanOutcome>) {
        let (tx, rx) = oneshot::channel();
        (FastScanOp { scan, next: None, done: Some(tx) }, rx)
    }

    fn settle(&mut self) {
        if let Some(o) = self.scan.outcome()
            && let Some(d) = self.done.take()
        {
            let _ = d.send(o);
        }
    }
}

impl Op for FastScanOp {
    fn start(&mut self, now: Instant, out: &mut Vec<Frame>) {
        self.scan.start(now, out);
        // An early poll does nothing but report the deadline.
        self.next = self.scan.poll(now, out);
        self.settle();
    }
    fn handle_frame(&mut self, f: &Frame, now: Instant, out: &mut Vec<Frame>) {
        if self.done.is_some() {
            self.scan.handle_frame(f, now, out);
            self.next = self.scan.poll(now, out);
            self.settle();
        }
    }
    fn poll(&mut self, now: Instant, out: &mut Vec<Frame>) -> Option<Instant> {
        self.done.as_ref()?;
        self.next = self.scan.poll(now, out);
        self.settle();
        self.deadline()
    }
    fn deadline(&self) -> Option<Instant> {
        if self.done.is_some() { self.next } else { None }
    }
    fn done(&self) -> bool {
        self.done.is_none()
    }
}
