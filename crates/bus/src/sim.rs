//! The simulation loop: polls, arbitration, transmission, delivery.

use core::cmp::Reverse;
use core::time::Duration;
use drivebus_can::{Frame, Instant, LinkState, earliest};

use crate::bus::{Bus, Endpoint, InFlight, Outcome, Station, TimedKind};
use crate::candump::{self, LogEntry};
use crate::node::Outbox;
use crate::stats::BusStats;
use crate::timing::{INTERMISSION_BITS, bits_duration, frame_bits};
use drivebus_can::fault::{FaultAction, corrupt_data};

/// A transmit error counter above this makes a station error passive
/// (ISO 11898-1 §12.1.4.2).
const ERROR_PASSIVE_LIMIT: u16 = 127;

/// Full arbitration key: identifier bits as they go on the wire, plus RTR
/// (a data frame beats a remote frame with the same identifier). A standard
/// RTR bit sits where an extended frame has SRR; an extended RTR is the last
/// arbitration bit. Lower wins.
#[inline]
pub(crate) fn arbitration_key(f: &Frame) -> u64 {
    let k = f.id().arbitration_key() << 1;
    match (f.id().is_extended(), f.is_rtr()) {
        (false, true) => k | (1 << 20),
        (true, true) => k | 1,
        _ => k,
    }
}

impl Station {
    /// Polls a node (starting it at its first poll) and records its next
    /// deadline.
    fn poll(&mut self, now: Instant, stats: &mut BusStats) {
        if let Endpoint::Node(n, started) = &mut self.endpoint {
            let mut out = Outbox { queue: &mut self.queue };
            if !*started {
                *started = true;
                n.start(now, &mut out);
            }
            let d = n.poll(now, &mut out);
            // A deadline not after `now` would stall time: push it 1 ns on.
            self.deadline = d.map(|d| d.max(now + Duration::from_nanos(1)));
        }
        self.discard_if_offline(stats);
    }

    pub(crate) fn discard_if_offline(&mut self, stats: &mut BusStats) {
        if !self.link.is_on_bus() && !self.queue.is_empty() {
            stats.discarded += self.queue.len() as u64;
            self.queue.clear();
        }
    }
}

impl Bus {
    /// When the next thing happens: a deadline, a frame ending, the bus
    /// becoming free for a waiting frame, a scheduled send, a recovery.
    /// `None` when nothing is pending at all.
    pub fn next_event_time(&self) -> Option<Instant> {
        let mut t = self.timed.peek().map(|Reverse(e)| e.at);
        match &self.inflight {
            Some(f) => t = earliest(t, Some(f.done_at)),
            None => {
                let waiting = self.stations.iter().any(|s| s.link.is_on_bus() && !s.queue.is_empty());
                if waiting {
                    t = earliest(t, Some(self.idle_at));
                }
            }
        }
        for s in &self.stations {
            t = earliest(t, s.deadline);
            if let LinkState::BusOff { recover_at } = s.link {
                t = earliest(t, recover_at);
            }
        }
        t.map(|t| t.max(self.now))
    }

    /// Advances to the next event time and processes what is due then:
    /// a completing frame, scheduled sends/deliveries, recoveries, node
    /// polls, then at most one new transmission (which, without a bitrate,
    /// also completes at once). Several steps may happen at one instant.
    /// Returns the time processed, `None` if nothing is pending.
    pub fn step(&mut self) -> Option<Instant> {
        let t = self.next_event_time()?;
        self.now = self.now.max(t);
        self.process();
        Some(self.now)
    }

    /// Processes every event up to and including `t`, then sets the time to
    /// `t` (if later). A frame still on the wire at `t` completes later.
    ///
    /// Without a bitrate, nodes that answer each other forever at the same
    /// instant keep this from returning; give such nodes a reaction time.
    pub fn run_until(&mut self, t: Instant) {
        while let Some(next) = self.next_event_time() {
            if next > t {
                break;
            }
            self.now = self.now.max(next);
            self.process();
        }
        self.now = self.now.max(t);
    }

    /// [`Bus::run_until`] `now + d`.
    pub fn run_for(&mut self, d: Duration) {
        self.run_until(self.now + d);
    }

    fn process(&mut self) {
        let now = self.now;
        self.finish_due();
        for i in 0..self.stations.len() {
            if let LinkState::BusOff { recover_at: Some(r) } = self.stations[i].link
                && r <= now
            {
                self.stations[i].link = LinkState::Active;
                self.stations[i].tec = 0;
                self.notify_link(i);
            }
        }
        while self.timed.peek().is_some_and(|Reverse(e)| e.at <= now) {
            let Some(Reverse(e)) = self.timed.pop() else { break };
            match e.kind {
                TimedKind::Send { station, frame } => {
                    if let Some(st) = self.stations.get_mut(station) {
                        if st.link.is_on_bus() {
                            st.queue.push_back(frame);
                        } else {
                            self.stats.discarded += 1;
                        }
                    }
                }
                TimedKind::Deliver { from, frame } => self.deliver(from, frame),
            }
        }
        for st in &mut self.stations {
            if st.deadline.is_some_and(|d| d <= now) {
                st.poll(now, &mut self.stats);
            }
        }
        if self.inflight.is_none()
            && self.idle_at <= now
            && let Some(i) = self.arbitrate()
        {
            self.start(i);
            // Without a bitrate the frame is done as soon as it starts.
            self.finish_due();
        }
    }

    fn finish_due(&mut self) {
        let now = self.now;
        if let Some(f) = self.inflight.take_if(|f| f.done_at <= now) {
            self.finish(f);
        }
    }

    /// The station whose queue head wins arbitration; ties (the same
    /// identifier from two stations, an error on a real bus) go to the
    /// lowest station id.
    fn arbitrate(&self) -> Option<usize> {
        let mut best: Option<(u64, usize)> = None;
        for (i, st) in self.stations.iter().enumerate() {
            if !st.link.is_on_bus() {
                continue;
            }
            if let Some(f) = st.queue.front() {
                let k = arbitration_key(f);
                if best.is_none_or(|(b, _)| k < b) {
                    best = Some((k, i));
                }
            }
        }
        best.map(|(_, i)| i)
    }

    fn start(&mut self, i: usize) {
        let now = self.now;
        let Some(st) = self.stations.get_mut(i) else { return };
        let Some(frame) = st.queue.pop_front() else { return };
        let retry = core::mem::take(&mut st.head_is_retry);
        let outcome =
            if retry { Outcome::Deliver { frame, altered: false } } else { self.apply_rules(&frame, i) };
        let fb = frame_bits(&frame);
        let (to_done, on_wire) = match outcome {
            Outcome::Error { .. } => {
                let b = fb.with_crc_error();
                (b - INTERMISSION_BITS, b)
            }
            _ => (fb.to_end_of_frame(), fb.total()),
        };
        let (done_at, idle_at) = match self.cfg.rate() {
            Some(r) => (now + bits_duration(to_done, r), now + bits_duration(on_wire, r)),
            None => (now, now),
        };
        self.stats.bits += u64::from(on_wire);
        self.stats.busy += idle_at - now;
        self.window.record(now, idle_at);
        self.idle_at = idle_at;
        self.inflight = Some(InFlight { from: i, frame, done_at, outcome });
    }

    fn apply_rules(&mut self, frame: &Frame, from: usize) -> Outcome {
        let node = u32::try_from(from).unwrap_or(u32::MAX);
        let mut action = None;
        for rule in self.rules.iter_mut().flatten() {
            if rule.try_fire(frame, node, &mut self.rng) {
                action = Some(rule.action());
                break;
            }
        }
        match action {
            None => Outcome::Deliver { frame: *frame, altered: false },
            Some(FaultAction::Drop) => Outcome::Drop,
            Some(FaultAction::Corrupt) => Outcome::Error { bus_off: false },
            Some(FaultAction::BusOff) => Outcome::Error { bus_off: true },
            Some(FaultAction::Delay(d)) => Outcome::Delay(d),
            Some(FaultAction::Duplicate) => Outcome::Duplicate,
            Some(FaultAction::CorruptSilently { xor }) => {
                Outcome::Deliver { frame: corrupt_data(frame, xor, &mut self.rng), altered: true }
            }
        }
    }

    fn finish(&mut self, f: InFlight) {
        let InFlight { from, frame, outcome, .. } = f;
        if let Outcome::Error { bus_off } = outcome {
            self.stats.error_frames += 1;
            self.signal_error_frame(from);
            let Some(st) = self.stations.get_mut(from) else { return };
            st.tec = st.tec.saturating_add(8);
            if bus_off || st.tec > 255 {
                // The destroyed frame is lost with the rest of the queue.
                self.stats.discarded += 1;
                self.go_bus_off(from);
            } else if st.link.is_on_bus() {
                // Automatic retransmission: back to the head of its queue.
                st.queue.push_front(frame);
                if st.tec > ERROR_PASSIVE_LIMIT && st.link == LinkState::Active {
                    st.link = LinkState::ErrorPassive;
                    self.notify_link(from);
                }
            }
            return;
        }
        self.stats.frames += 1;
        *self.stats.per_id.entry(frame.id()).or_insert(0) += 1;
        if let Some(st) = self.stations.get_mut(from) {
            st.tec = st.tec.saturating_sub(1);
            if st.tec <= ERROR_PASSIVE_LIMIT && st.link == LinkState::ErrorPassive {
                st.link = LinkState::Active;
                self.notify_link(from);
            }
        }
        match outcome {
            Outcome::Deliver { frame: seen, altered } => {
                if altered {
                    self.stats.corrupted += 1;
                }
                self.deliver(from, seen);
            }
            Outcome::Drop => self.stats.dropped += 1,
            Outcome::Delay(d) => {
                self.stats.delayed += 1;
                let at = self.now + d;
                self.push_timed(at, TimedKind::Deliver { from, frame });
            }
            Outcome::Duplicate => {
                self.stats.duplicated += 1;
                self.deliver(from, frame);
                if let Some(st) = self.stations.get_mut(from)
                    && st.link.is_on_bus()
                {
                    st.queue.push_front(frame);
                    st.head_is_retry = true;
                }
            }
            Outcome::Error { .. } => {}
        }
    }

    /// Tells every other active node that an error frame just ended.
    fn signal_error_frame(&mut self, from: usize) {
        let now = self.now;
        for (i, st) in self.stations.iter_mut().enumerate() {
            if i == from || !st.link.is_on_bus() {
                continue;
            }
            if let Endpoint::Node(n, true) = &mut st.endpoint {
                let mut out = Outbox { queue: &mut st.queue };
                n.handle_error_frame(now, &mut out);
                st.poll(now, &mut self.stats);
            }
        }
    }

    /// Tells station `i` its link state changed and polls it.
    pub(crate) fn notify_link(&mut self, i: usize) {
        let now = self.now;
        let Some(st) = self.stations.get_mut(i) else { return };
        if let Endpoint::Node(n, true) = &mut st.endpoint {
            let mut out = Outbox { queue: &mut st.queue };
            n.link_changed(st.link, now, &mut out);
            st.poll(now, &mut self.stats);
        }
        st.discard_if_offline(&mut self.stats);
    }

    /// Hands `frame` to every station on the bus except its transmitter
    /// (unless echo is on), logs it, and polls each receiving node.
    fn deliver(&mut self, from: usize, frame: Frame) {
        let now = self.now;
        if self.cfg.log {
            self.log.push(LogEntry { time: now, frame });
        }
        if let Some(sink) = &mut self.sink {
            self.line.clear();
            // Writing into a String cannot fail.
            let _ =
                candump::write_line(&mut self.line, self.cfg.log_epoch_us, &self.cfg.interface, now, &frame);
            sink(&self.line);
        }
        let echo = self.cfg.echo;
        for (i, st) in self.stations.iter_mut().enumerate() {
            if (i == from && !echo) || !st.link.is_on_bus() {
                continue;
            }
            match &mut st.endpoint {
                Endpoint::Node(n, started) => {
                    if *started {
                        let mut out = Outbox { queue: &mut st.queue };
                        n.handle_frame(&frame, now, &mut out);
                    }
                    st.poll(now, &mut self.stats);
                }
                Endpoint::Probe { received, capture } => {
                    if *capture {
                        received.push((now, frame));
                    }
                }
                Endpoint::Off => {}
            }
        }
    }
}
