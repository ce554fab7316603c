//! An in-process link between ethercrab 0.7.1 and a [`Host`]: ethercrab's
//! sendable frames go straight through the segment and the replies straight
//! back into its `PduRx`, with no socket, no root and no network.
//!
//! Use it where `ethercrab::std::tx_rx_task` would go:
//!
//! ```no_run
//! # use drivebus_ethercat::{Clock, Host, link};
//! # use ethercrab::PduStorage;
//! static PDU_STORAGE: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();
//! # async fn demo(host: Host) {
//! let (tx, rx, pdu_loop) = PDU_STORAGE.try_split().expect("split once");
//! tokio::spawn(link::run(host, tx, rx));
//! # }
//! ```
//!
//! With a real-time clock the link also wakes itself at the devices' next
//! deadline (SYNC0 pulses, watchdogs) through an `async-io` timer, so it
//! works under tokio, smol or any executor. With a simulated clock, time
//! moves with the frames and with [`Host::advance`].

use crate::host::Host;
use async_io::Timer;
use ethercrab::error::Error;
use ethercrab::{PduRx, PduTx};
use std::future::Future;
use std::pin::Pin;
use std::task::{Context, Poll};

/// Largest Ethernet frame the link passes (jumbo frames included).
const MAX_FRAME: usize = 9216;

/// The link future returned by [`run`].
pub struct InProcessLink<'sto> {
    host: Host,
    tx: Option<PduTx<'sto>>,
    rx: Option<PduRx<'sto>>,
    buf: Vec<u8>,
    timer: Option<Timer>,
    /// Replies ethercrab refused (e.g. after its timeout freed the slot).
    pub refused: u64,
}

impl std::fmt::Debug for InProcessLink<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("InProcessLink").field("host", &self.host).field("refused", &self.refused).finish()
    }
}

/// Serves ethercrab's PDU loop from `host` until the `MainDevice` is
/// released; resolves to the `PduTx`/`PduRx` for reuse.
pub fn run<'sto>(host: Host, tx: PduTx<'sto>, rx: PduRx<'sto>) -> InProcessLink<'sto> {
    InProcessLink { host, tx: Some(tx), rx: Some(rx), buf: vec![0; MAX_FRAME], timer: None, refused: 0 }
}

impl<'sto> Future for InProcessLink<'sto> {
    type Output = Result<(PduTx<'sto>, PduRx<'sto>), Error>;

    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        let this = self.get_mut();
        let (Some(tx), Some(rx)) = (this.tx.as_mut(), this.rx.as_mut()) else {
            return Poll::Pending;
        };
        tx.replace_waker(cx.waker());
        if tx.should_exit() {
            let (tx, rx) = (this.tx.take(), this.rx.take());
            if let (Some(tx), Some(rx)) = (tx, rx) {
                return Poll::Ready(Ok((tx.release(), rx.release())));
            }
            return Poll::Pending;
        }
        while let Some(frame) = tx.next_sendable_frame() {
            let buf = &mut this.buf;
            let mut len = 0;
            frame.send_blocking(|data| {
                let n = data.len().min(buf.len());
                buf[..n].copy_from_slice(&data[..n]);
                len = n;
                Ok(data.len())
            })?;
            if this.host.process_frame(&mut buf[..len]).lost {
                // Never comes back: ethercrab's PDU timeout sees it.
                continue;
            }
            if rx.receive_frame(&buf[..len]).is_err() {
                this.refused += 1;
            }
        }
        if !this.host.clock().is_simulated()
            && let Some(at) = this.host.poll().and_then(|d| this.host.clock().to_std(d))
        {
            let timer = this.timer.get_or_insert_with(|| Timer::at(at));
            timer.set_at(at);
            if Pin::new(timer).poll(cx).is_ready() {
                cx.waker().wake_by_ref();
            }
        }
        Poll::Pending
    }
}
