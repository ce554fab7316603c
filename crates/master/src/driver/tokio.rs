//! The tokio driver: one task owns the transport's receiver, feeds frames
//! and the tokio clock to the core, sends what the core queued, and sleeps
//! until the core's next deadline or a kick from the API.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Weak};

use drivebus_can::Frame;
use drivebus_transport::clock::TokioClock;
use drivebus_transport::{CanBus, CanRx, CanTx};
use tokio::sync::Notify;

use crate::master::{Driver, Master, MasterConfig, Shared};

/// Starts the driver task for `bus` and returns the master on it.
pub(crate) fn spawn(bus: CanBus, config: MasterConfig) -> Master {
    let (tx, rx) = bus.split();
    let clock = TokioClock::start();
    let kick = Arc::new(Notify::new());
    let driver = Driver::Tokio {
        clock,
        tx: tx.clone(),
        kick: kick.clone(),
        sent: AtomicU64::new(0),
        sent_notify: Notify::new(),
        send_lock: tokio::sync::Mutex::new(()),
    };
    let shared = Arc::new(Shared::new(config, driver, clock.now()));
    // The task holds the master weakly: dropping the last `Master` ends it.
    let h = tokio::spawn(run(Arc::downgrade(&shared), rx, tx, kick, clock));
    shared.add_task(h.abort_handle());
    Master { inner: shared }
}

async fn run(shared: Weak<Shared>, mut rx: CanRx, tx: CanTx, kick: Arc<Notify>, clock: TokioClock) {
    let mut out: Vec<Frame> = Vec::with_capacity(64);
    let sleep = tokio::time::sleep(std::time::Duration::from_secs(3600));
    tokio::pin!(sleep);
    loop {
        let Some(s) = shared.upgrade() else { return };
        let Driver::Tokio { send_lock, .. } = &s.driver else { return };
        // Taken before the queue: frames go out in the core's order even
        // when an API call sends from its own task.
        let sending = send_lock.lock().await;
        let next = {
            let mut c = s.core();
            let next = c.poll(clock.now());
            c.take_tx(&mut out);
            c.armed = next;
            next
        };
        let n = out.len() as u64;
        for f in out.drain(..) {
            if let Err(e) = tx.send(f).await {
                s.core().bus_error(e.to_string());
                return;
            }
        }
        if let Driver::Tokio { sent, sent_notify, .. } = &s.driver
            && n > 0
        {
            sent.fetch_add(n, Ordering::AcqRel);
            sent_notify.notify_waiters();
        }
        drop(sending);
        drop(s);
        // One timer, re-armed only when the deadline moves: a new one per
        // received frame costs a timer-wheel registration each time. With
        // no deadline, a fired timer is pushed far out (a stale one only
        // wakes the loop once, harmlessly).
        match next.map(|t| clock.at(t)) {
            Some(d) if sleep.deadline() != d => sleep.as_mut().reset(d),
            None if sleep.is_elapsed() => {
                sleep.as_mut().reset(tokio::time::Instant::now() + std::time::Duration::from_secs(3600))
            }
            _ => {}
        }
        tokio::select! {
            // A frame already queued is handled before a deadline that
            // passed meanwhile (a late SDO answer still counts, CiA 301).
            biased;
            r = rx.recv() => {
                let Some(s) = shared.upgrade() else { return };
                match r {
                    Ok(f) => s.core().handle_frame(&f, clock.now()),
                    Err(e) => {
                        s.core().bus_error(e.to_string());
                        return;
                    }
                }
            }
            () = kick.notified() => {}
            () = &mut sleep => {}
        }
    }
}
