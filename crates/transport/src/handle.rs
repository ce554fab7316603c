//! The bus handle every transport yields.

use std::io;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use drivebus_can::Frame;
use tokio::sync::{broadcast, mpsc, oneshot};

use crate::hub::{Hub, HubFrame, ParticipantId};
use crate::stats::BusErrors;

/// Frames buffered towards the user before the transport counts an overrun.
/// Deep enough for bursts (an SDO block is 127 frames); a user that stops
/// reading loses frames like a CAN controller with a full receive FIFO rather
/// than stalling the link (which would deadlock a user that only sends).
pub(crate) const RX_QUEUE: usize = 4096;
/// Frames buffered from the user towards the transport.
pub(crate) const TX_QUEUE: usize = 256;

/// A connection to a CAN bus: send and receive classic CAN frames.
///
/// Frames a handle sends are not received back by the same handle (no
/// echo), as on a real controller. Use [`split`](CanBus::split) to send and
/// receive from different tasks.
pub struct CanBus {
    tx: CanTx,
    rx: CanRx,
}

/// The sending half of a [`CanBus`]; cheap to clone.
#[derive(Clone)]
pub struct CanTx(TxInner);

/// The receiving half of a [`CanBus`].
pub struct CanRx(RxInner);

#[derive(Clone)]
enum TxInner {
    Hub { hub: Hub, id: ParticipantId },
    Chan { tx: mpsc::Sender<Out>, status: Arc<LinkStatus>, rtr: bool },
}

enum RxInner {
    Hub { rx: broadcast::Receiver<HubFrame>, id: ParticipantId, overruns: u64, _hub: Hub },
    Chan { rx: mpsc::Receiver<Frame>, status: Arc<LinkStatus> },
}

/// Why [`CanTx::try_send`] did not queue a frame.
#[derive(Debug)]
pub enum TrySendError {
    /// The transport cannot take it without waiting; here it is back.
    Busy(Frame),
    /// The transport failed or cannot carry this frame.
    Failed(io::Error),
}

/// What a user handle asks of its transport task, in order: a frame
/// queued after a flush is written after the flush completed.
pub(crate) enum Out {
    /// Write this frame.
    Frame(Frame),
    /// Answer once every earlier frame has been handed to the OS and the
    /// device/socket has taken it (`tcdrain` on serial ports).
    Flush(oneshot::Sender<()>),
    /// Flush, then end the connection the way the peer expects (TCP: FIN
    /// after the data and wait for the peer's; slcan: `C`), then answer.
    Close(oneshot::Sender<()>),
}

impl CanBus {
    /// Joins the halves again.
    pub fn from_parts(tx: CanTx, rx: CanRx) -> CanBus {
        CanBus { tx, rx }
    }
    /// Splits into a sender (clonable) and a receiver.
    pub fn split(self) -> (CanTx, CanRx) {
        (self.tx, self.rx)
    }
    /// Queues `frame` for transmission; waits while the transport is busy.
    pub async fn send(&self, frame: Frame) -> io::Result<()> {
        self.tx.send(frame).await
    }
    /// The next frame from the bus. An error means the link is gone
    /// (connection closed, device removed) and says why.
    pub async fn recv(&mut self) -> io::Result<Frame> {
        self.rx.recv().await
    }
    /// A new sender for this bus.
    pub fn sender(&self) -> CanTx {
        self.tx.clone()
    }
    /// Waits until every frame sent before this call has been written
    /// (see [`CanTx::flush`]).
    pub async fn flush(&self) -> io::Result<()> {
        self.tx.flush().await
    }
    /// Flushes, then ends the connection so that the peer has received
    /// every frame: on TCP a FIN after the data and a wait (bounded) for
    /// the peer's own close, on slcan the `C` command after the frames.
    /// A process that exits right after this has lost nothing it sent.
    pub async fn close(self) -> io::Result<()> {
        self.tx.close().await
    }
}

impl CanTx {
    /// Queues `frame` for transmission; waits while the transport is busy
    /// (on a paced hub: until the frame's slot on the bus).
    pub async fn send(&self, frame: Frame) -> io::Result<()> {
        match &self.0 {
            TxInner::Hub { hub, id } => {
                hub.publish(*id, frame).await;
                Ok(())
            }
            TxInner::Chan { rtr: false, .. } if frame.is_rtr() => Err(io::Error::new(
                io::ErrorKind::Unsupported,
                "this transport cannot carry RTR frames (socketcand)",
            )),
            TxInner::Chan { tx, status, .. } => tx.send(Out::Frame(frame)).await.map_err(|_| status.error()),
        }
    }

    /// Queues `frame` without waiting. [`TrySendError::Busy`] hands it
    /// back when the transport cannot take it at once (its queue is full,
    /// or a paced hub must wait for the frame's slot): call
    /// [`send`](Self::send) then.
    pub fn try_send(&self, frame: Frame) -> Result<(), TrySendError> {
        match &self.0 {
            TxInner::Hub { hub, .. } if hub.is_paced() => Err(TrySendError::Busy(frame)),
            TxInner::Hub { hub, id } => {
                hub.publish_now(*id, frame);
                Ok(())
            }
            TxInner::Chan { rtr: false, .. } if frame.is_rtr() => Err(TrySendError::Failed(io::Error::new(
                io::ErrorKind::Unsupported,
                "this transport cannot carry RTR frames (socketcand)",
            ))),
            TxInner::Chan { tx, status, .. } => match tx.try_send(Out::Frame(frame)) {
                Ok(()) => Ok(()),
                Err(mpsc::error::TrySendError::Full(_)) => Err(TrySendError::Busy(frame)),
                Err(mpsc::error::TrySendError::Closed(_)) => Err(TrySendError::Failed(status.error())),
            },
        }
    }

    /// False for transports that cannot carry remote (RTR) frames
    /// (socketcand): sending one fails.
    pub fn carries_rtr(&self) -> bool {
        match &self.0 {
            TxInner::Hub { .. } => true,
            TxInner::Chan { rtr, .. } => *rtr,
        }
    }

    /// The error frames and error counters the transport reports (SocketCAN
    /// error frames); `None` for transports that report none.
    pub fn bus_errors(&self) -> Option<BusErrors> {
        match &self.0 {
            TxInner::Hub { .. } => None,
            TxInner::Chan { status, .. } => status.errors.lock().ok().and_then(|e| e.clone()),
        }
    }

    /// Waits until every frame this transport was given before the call
    /// has been written to the socket or device, so that a program may
    /// report success and exit without losing it. On the in-process hub
    /// frames are relayed at once, so this returns at once.
    pub async fn flush(&self) -> io::Result<()> {
        self.request(Out::Flush).await
    }

    /// [`flush`](Self::flush), then closes the connection for every
    /// handle (see [`CanBus::close`]).
    pub async fn close(&self) -> io::Result<()> {
        self.request(Out::Close).await
    }

    async fn request(&self, make: fn(oneshot::Sender<()>) -> Out) -> io::Result<()> {
        match &self.0 {
            TxInner::Hub { .. } => Ok(()),
            TxInner::Chan { tx, status, .. } => {
                let (done, wait) = oneshot::channel();
                tx.send(make(done)).await.map_err(|_| status.error())?;
                wait.await.map_err(|_| status.error())
            }
        }
    }
}

impl CanRx {
    /// The next frame from the bus (see [`CanBus::recv`]).
    pub async fn recv(&mut self) -> io::Result<Frame> {
        match &mut self.0 {
            RxInner::Hub { rx, id, overruns, .. } => loop {
                match rx.recv().await {
                    Ok(m) if m.from == *id => continue,
                    Ok(m) => return Ok(m.frame),
                    // A receiver that fell behind loses the oldest frames,
                    // as a controller whose FIFO overflowed.
                    Err(broadcast::error::RecvError::Lagged(n)) => {
                        *overruns += n;
                        tracing::warn!(lost = n, "virtual bus receiver overrun");
                    }
                    Err(broadcast::error::RecvError::Closed) => {
                        return Err(io::Error::new(io::ErrorKind::BrokenPipe, "hub closed"));
                    }
                }
            },
            RxInner::Chan { rx, status } => rx.recv().await.ok_or_else(|| status.error()),
        }
    }
    /// Frames lost because this receiver was not read fast enough.
    pub fn overruns(&self) -> u64 {
        match &self.0 {
            RxInner::Hub { overruns, .. } => *overruns,
            RxInner::Chan { status, .. } => status.overruns.load(Ordering::Relaxed),
        }
    }
}

impl std::fmt::Debug for CanBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self.tx.0 {
            TxInner::Hub { .. } => "CanBus(hub)",
            TxInner::Chan { .. } => "CanBus(link)",
        })
    }
}

/// Builds a handle on a hub port.
pub(crate) fn hub_handle(hub: Hub, id: ParticipantId, rx: broadcast::Receiver<HubFrame>) -> CanBus {
    CanBus {
        tx: CanTx(TxInner::Hub { hub: hub.clone(), id }),
        rx: CanRx(RxInner::Hub { rx, id, overruns: 0, _hub: hub }),
    }
}

/// Why a link task stopped, and its overrun count.
#[derive(Default)]
pub(crate) struct LinkStatus {
    reason: Mutex<Option<String>>,
    overruns: AtomicU64,
    /// Set by transports that report bus errors (SocketCAN).
    errors: Mutex<Option<BusErrors>>,
}

impl LinkStatus {
    fn error(&self) -> io::Error {
        let why = self.reason.lock().map(|r| r.clone()).unwrap_or(None);
        io::Error::new(io::ErrorKind::BrokenPipe, why.unwrap_or_else(|| "transport closed".into()))
    }
}

/// The transport's side of a handle built by [`link`].
pub(crate) struct LinkEnd {
    pub from_user: mpsc::Receiver<Out>,
    pub up: Uplink,
}

/// Delivers received frames and the link's fate to the user; clonable so a
/// reader thread can own one while a writer owns `from_user`.
#[derive(Clone)]
pub(crate) struct Uplink {
    pub to_user: mpsc::Sender<Frame>,
    status: Arc<LinkStatus>,
}

impl Uplink {
    /// Hands a received frame to the user without ever blocking the link.
    pub fn deliver(&self, frame: Frame) {
        if let Err(mpsc::error::TrySendError::Full(_)) = self.to_user.try_send(frame) {
            let n = self.status.overruns.fetch_add(1, Ordering::Relaxed);
            if n.is_power_of_two() {
                tracing::warn!(lost = n + 1, "receiver not read fast enough: frames dropped");
            }
        }
    }
    /// This transport reports bus errors: [`CanTx::bus_errors`] is `Some`
    /// from now on.
    pub fn reports_errors(&self) {
        if let Ok(mut e) = self.status.errors.lock() {
            e.get_or_insert_with(BusErrors::default);
        }
    }
    /// Counts one SocketCAN error frame (`class`: its `CAN_ERR_*` bits).
    #[cfg_attr(not(target_os = "linux"), allow(dead_code))] // only SocketCAN reports them
    pub fn error_frame(&self, class: u32, data: &[u8]) {
        if let Ok(mut e) = self.status.errors.lock() {
            e.get_or_insert_with(BusErrors::default).record_socketcan(class, data);
        }
    }
    /// Records why the link stopped; the user's next call reports it.
    pub fn fail(&self, why: impl Into<String>) {
        let why = why.into();
        tracing::debug!(%why, "link closed");
        if let Ok(mut r) = self.status.reason.lock() {
            r.get_or_insert(why);
        }
    }
}

impl LinkEnd {
    /// See [`Uplink::deliver`].
    pub fn deliver(&self, frame: Frame) {
        self.up.deliver(frame)
    }
    /// See [`Uplink::fail`].
    pub fn fail(&self, why: impl Into<String>) {
        self.up.fail(why)
    }
    /// True once the user dropped every handle half.
    pub fn user_gone(&self) -> bool {
        self.up.to_user.is_closed() && self.from_user.is_closed()
    }
}

/// A user handle plus the transport end feeding it; `rtr`: whether the
/// transport can carry remote frames.
pub(crate) fn link(rtr: bool) -> (CanBus, LinkEnd) {
    let (to_user, rx) = mpsc::channel(RX_QUEUE);
    let (tx, from_user) = mpsc::channel(TX_QUEUE);
    let status = Arc::new(LinkStatus::default());
    let bus = CanBus {
        tx: CanTx(TxInner::Chan { tx, status: status.clone(), rtr }),
        rx: CanRx(RxInner::Chan { rx, status: status.clone() }),
    };
    (bus, LinkEnd { from_user, up: Uplink { to_user, status } })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A transport that reports bus errors (SocketCAN) makes them visible
    /// on every sender; the others report none.
    #[tokio::test]
    async fn bus_errors_reach_the_senders() {
        let (bus, end) = link(true);
        let tx = bus.sender();
        assert_eq!(tx.bus_errors(), None);
        end.up.reports_errors();
        assert_eq!(tx.bus_errors(), Some(BusErrors::default()));
        end.up.error_frame(0x0040, &[0; 8]);
        end.up.error_frame(0x0204, &[0, 0x08, 0, 0, 0, 0, 128, 0]);
        let e = bus.sender().bus_errors().unwrap();
        assert_eq!((e.error_frames, e.bus_off, e.tx_errors, e.rx_errors), (2, 1, Some(128), Some(0)));
        let hub = Hub::default();
        assert_eq!(hub.attach().sender().bus_errors(), None);
    }
}
