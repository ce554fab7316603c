//! The simulated-time driver: the master as one station of the
//! deterministic virtual bus (`drivebus_bus::Bus`). [`SimBus::block_on`]
//! runs a future of master calls to completion while advancing simulated
//! time: after every step it sends what the core queued, runs the bus to
//! the next deadline (or one step), hands the received frames to the core
//! with their times and polls it. The same master code as on a real bus,
//! exact and repeatable.

use std::future::Future;
use std::pin::pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, atomic::AtomicU64};
use std::task::{Context, Poll, Wake, Waker};
use std::time::Duration;

use drivebus_bus::{Bus, NodeId, ProbeId};
use drivebus_can::{Frame, Instant};

use crate::master::{Driver, Master, MasterConfig, Shared};

/// The future did not finish within the simulated time allowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stalled {
    /// Simulated time when the driver gave up.
    pub at: Instant,
}

impl std::fmt::Display for Stalled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "nothing finished after {:.3} s of simulated time", self.at.as_nanos() as f64 / 1e9)
    }
}

impl std::error::Error for Stalled {}

/// A master on a simulated bus with the devices attached to it.
pub struct SimBus {
    bus: Bus,
    probe: ProbeId,
    master: Master,
    step: Duration,
    limit: Duration,
    realtime: Option<(std::time::Instant, Instant)>,
    out: Vec<Frame>,
    stuck: u32,
}

struct Flag(AtomicBool);

impl Wake for Flag {
    fn wake(self: Arc<Self>) {
        self.0.store(true, Ordering::Release);
    }
    fn wake_by_ref(self: &Arc<Self>) {
        self.0.store(true, Ordering::Release);
    }
}

impl SimBus {
    /// The master joins `bus` as a probe station, with the default configuration.
    pub fn new(bus: Bus) -> SimBus {
        SimBus::with_config(bus, MasterConfig::default())
    }

    /// The master joins `bus` with `config`.
    pub fn with_config(mut bus: Bus, config: MasterConfig) -> SimBus {
        let probe = bus.attach_probe();
        let now = bus.now();
        let driver = Driver::Sim { now: AtomicU64::new(now.as_nanos()) };
        let master = Master { inner: Arc::new(Shared::new(config, driver, now)) };
        SimBus {
            bus,
            probe,
            master,
            step: Duration::from_micros(100),
            limit: Duration::from_secs(3600),
            realtime: None,
            out: Vec::new(),
            stuck: 0,
        }
    }

    /// The master (clone it freely; its futures run inside [`block_on`](Self::block_on)).
    pub fn master(&self) -> &Master {
        &self.master
    }

    /// The bus, to inspect statistics or the log.
    pub fn bus(&self) -> &Bus {
        &self.bus
    }

    /// The bus, to attach devices or inject faults.
    pub fn bus_mut(&mut self) -> &mut Bus {
        &mut self.bus
    }

    /// Attaches a device (before or between runs).
    pub fn attach<N: drivebus_can::Device + 'static>(&mut self, node: N) -> NodeId {
        self.bus.attach(node)
    }

    /// Simulated now.
    pub fn now(&self) -> Instant {
        self.bus.now()
    }

    /// Longest simulated wait between two master steps when nothing is
    /// due (how soon the master reacts to a frame; default 100 µs).
    pub fn set_step(&mut self, step: Duration) {
        self.step = step.max(Duration::from_micros(1));
    }

    /// Longest simulated time one `block_on` may take (default 1 h).
    pub fn set_limit(&mut self, limit: Duration) {
        self.limit = limit;
    }

    /// Paces simulated time to the wall clock (for watching a demo).
    pub fn set_realtime(&mut self, on: bool) {
        self.realtime = on.then(|| (std::time::Instant::now(), self.bus.now()));
    }

    fn set_clock(&self) {
        if let Driver::Sim { now } = &self.master.inner.driver {
            now.store(self.bus.now().as_nanos(), Ordering::Release);
        }
    }

    /// Sends what the core queued, at the current simulated time.
    fn pump(&mut self) {
        self.master.inner.core().take_tx(&mut self.out);
        for f in self.out.drain(..) {
            self.bus.send_from(self.probe, f);
        }
    }

    /// One step of simulated time: to the core's next deadline or by the
    /// step, whichever is first; received frames go to the core.
    fn advance(&mut self, cap: Instant) {
        let now = self.bus.now();
        let mut target = now + self.step;
        if let Some(t) = self.master.inner.core().next_deadline() {
            target = target.min(t.max(now));
        }
        let mut target = target.min(cap).max(now);
        // Work due now is done by the poll below; a deadline that stays in
        // the past (it should not) must not freeze simulated time.
        if target == now {
            self.stuck += 1;
            if self.stuck > 1000 {
                target = now + self.step;
                self.stuck = 0;
            }
        } else {
            self.stuck = 0;
        }
        self.bus.run_until(target);
        self.set_clock();
        let got = self.bus.take_received_timed(self.probe);
        let mut c = self.master.inner.core();
        for (t, f) in got {
            c.handle_frame(&f, t);
        }
        c.poll(self.bus.now());
        drop(c);
        if let Some((wall0, sim0)) = self.realtime {
            let due = wall0 + Duration::from_nanos(self.bus.now().as_nanos().saturating_sub(sim0.as_nanos()));
            if let Some(ahead) = due.checked_duration_since(std::time::Instant::now()) {
                std::thread::sleep(ahead);
            }
        }
    }

    /// Runs `fut` (master calls) to completion in simulated time.
    pub fn block_on<F: Future>(&mut self, fut: F) -> Result<F::Output, Stalled> {
        let flag = Arc::new(Flag(AtomicBool::new(true)));
        let waker = Waker::from(flag.clone());
        let mut cx = Context::from_waker(&waker);
        let mut fut = pin!(fut);
        let give_up = self.bus.now() + self.limit;
        self.set_clock();
        loop {
            while flag.0.swap(false, Ordering::AcqRel) {
                if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
                    self.pump();
                    return Ok(v);
                }
            }
            self.pump();
            if self.bus.now() >= give_up {
                return Err(Stalled { at: self.bus.now() });
            }
            self.advance(give_up);
        }
    }

    /// Advances simulated time by `d` with the master running (heartbeats
    /// and EMCYs recorded, SYNC produced).
    pub fn run_for(&mut self, d: Duration) {
        let end = self.bus.now() + d;
        self.set_clock();
        while self.bus.now() < end {
            self.pump();
            self.advance(end);
        }
        self.pump();
    }
}
