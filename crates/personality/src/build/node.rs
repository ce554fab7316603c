//! [`PersonalityNode`]: the node, the drive and the behaviour composed as
//! one station of the virtual bus (see the parent module).

use super::{Action, Behaviour, Context, EmcyFrame, FilterOutcome, Verdict};
use crate::Profile;
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_bus::{BusNode, LinkState, Outbox};
use drivebus_can::{Frame, Instant, TxSink, earliest};
use drivebus_cia402::drive::{Drive, EmcyRequest, Injection};
use drivebus_node::{Application, Node, NodeEvent};
use drivebus_od::{ObjectDictionary, ObjectHooks, SdoAbort, WriteOutcome};

extern crate alloc;

/// The application the node sees: behaviour first, then the drive.
struct Composite<'a> {
    drive: &'a mut Drive,
    behaviour: &'a mut dyn Behaviour,
    actions: &'a mut Vec<Action>,
    state: &'a mut ModeState,
    node_id: u8,
    now: Instant,
}

/// Framework-level state: the manufacturer mode shown in 6061h and the
/// supported homing methods.
#[derive(Debug, Clone, Default)]
pub(super) struct ModeState {
    /// The manufacturer mode selected (negative), and its stand-in.
    pub(super) manufacturer: Option<(i8, i8)>,
    /// 6098h values accepted.
    pub(super) homing: Vec<i8>,
    /// 6060h values accepted (the profile's list).
    pub(super) modes: Vec<i8>,
}

impl Composite<'_> {
    fn cx(&mut self) -> (Context<'_>, &mut dyn Behaviour) {
        (
            Context { drive: self.drive, actions: self.actions, node_id: self.node_id, now: self.now },
            self.behaviour,
        )
    }
}

impl ObjectHooks for Composite<'_> {
    fn on_read(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) -> Result<(), SdoAbort> {
        let (mut cx, b) = self.cx();
        b.on_read(&mut cx, od, index, sub)?;
        self.drive.on_read(od, index, sub)
    }

    fn on_write(
        &mut self,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let (mut cx, b) = self.cx();
        match b.on_write(&mut cx, od, index, sub, data)? {
            Verdict::Handled => return Ok(WriteOutcome::Handled),
            Verdict::Store => return Ok(WriteOutcome::Store),
            Verdict::Pass => {}
        }
        match (index, sub) {
            // CiA 402-2 6060h: 0 "no mode change" (the drive's power-on
            // value where the manual gives no default mode): the mode in
            // force stays, a manufacturer mode included.
            (0x6060, 0) if data.first().copied().unwrap_or(0) == 0 => {
                return self.drive.on_write(od, index, sub, data);
            }
            (0x6060, 0) => {
                let m = data.first().copied().unwrap_or(0) as i8;
                if !self.state.modes.contains(&m) {
                    // CiA 402-2 §6.3.2: a mode the drive does not list is refused.
                    return Err(SdoAbort::INVALID_VALUE);
                }
                if m < 0 {
                    let Some(stand_in) = self.behaviour.manufacturer_mode(m) else {
                        return Err(SdoAbort::INVALID_VALUE);
                    };
                    self.drive.on_write(od, index, sub, &[stand_in as u8])?;
                    self.state.manufacturer = Some((m, stand_in));
                    return Ok(WriteOutcome::Store);
                }
                self.state.manufacturer = None;
            }
            (0x6098, 0) => {
                let m = data.first().copied().unwrap_or(0) as i8;
                if !self.state.homing.contains(&m) && m != 0 {
                    // CiA 402-2 §6.7: a method not in 60E3h is refused.
                    return Err(SdoAbort::INVALID_VALUE);
                }
            }
            _ => {}
        }
        let r = self.drive.on_write(od, index, sub, data);
        // The drive may have published (statusword after a controlword).
        self.patch(od);
        r
    }

    fn after_write(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) {
        let (mut cx, b) = self.cx();
        b.after_write(&mut cx, od, index, sub);
        self.drive.after_write(od, index, sub);
        self.patch(od);
    }
}

impl Application for Composite<'_> {
    fn on_sync(&mut self, od: &mut ObjectDictionary, counter: Option<u8>, now: Instant) {
        self.drive.on_sync(od, counter, now);
        self.patch(od);
    }

    fn on_event(&mut self, od: &mut ObjectDictionary, event: NodeEvent, now: Instant) {
        self.drive.on_event(od, event, now);
        if matches!(event, NodeEvent::ResetApplication) {
            self.state.manufacturer = None;
        }
        let (mut cx, b) = self.cx();
        b.on_event(&mut cx, od, &event);
        self.patch(od);
    }

    fn poll(&mut self, od: &mut ObjectDictionary, now: Instant) -> Option<Instant> {
        let next = self.drive.poll(od, now);
        self.patch(od);
        next
    }
}

impl Composite<'_> {
    /// Live values the framework and the behaviour own after a drive step.
    fn patch(&mut self, od: &mut ObjectDictionary) {
        if let Some((m, stand_in)) = self.state.manufacturer {
            if self.drive.mode() == stand_in {
                if let Ok(r) = od.find(0x6061, 0) {
                    od.set_le(r, &[m as u8]);
                }
            } else {
                self.state.manufacturer = None;
            }
        }
        let (mut cx, b) = self.cx();
        b.after_step(&mut cx, od);
    }
}

/// A personality on the virtual bus: the CiA 301 node, the CiA 402 drive
/// and the behaviour in front of it. Boots at the first poll.
pub struct PersonalityNode {
    /// The CiA 301 device.
    pub node: Node,
    /// The CiA 402 drive application.
    pub drive: Drive,
    /// The personality's quirks.
    pub behaviour: Box<dyn Behaviour>,
    profile: Profile,
    state: ModeState,
    actions: Vec<Action>,
    /// Errors raised with an explicit register (code, register bits).
    own_errors: Vec<(u16, u8)>,
    booted: bool,
}

impl core::fmt::Debug for PersonalityNode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("PersonalityNode")
            .field("profile", &self.profile)
            .field("node_id", &self.node.node_id())
            .field("nmt", &self.node.nmt_state())
            .field("statusword", &self.drive.statusword())
            .finish()
    }
}

impl PersonalityNode {
    /// The personality.
    pub fn profile(&self) -> Profile {
        self.profile
    }

    /// The manufacturer mode (negative 6060h) in force, if any.
    pub fn manufacturer_mode(&self) -> Option<i8> {
        self.state.manufacturer.map(|(m, _)| m)
    }

    /// Applies a fault injection to the drive (takes effect at its next
    /// control period; EMCY frames follow the personality's mapping).
    pub fn inject(&mut self, what: Injection) {
        self.drive.inject(what);
    }

    /// The behaviour as its concrete type `T` (e.g.
    /// [`crate::behaviour::ssd630::Ssd630`] to switch its enable input at
    /// run time); `None` if it is another type or does not expose itself
    /// ([`Behaviour::as_any_mut`]). A change takes effect at the next poll.
    pub fn behaviour_mut<T: core::any::Any>(&mut self) -> Option<&mut T> {
        self.behaviour.as_any_mut()?.downcast_mut::<T>()
    }

    fn split(&mut self, now: Instant) -> (&mut Node, Composite<'_>) {
        let node_id = self.node.node_id();
        (
            &mut self.node,
            Composite {
                drive: &mut self.drive,
                behaviour: &mut *self.behaviour,
                actions: &mut self.actions,
                state: &mut self.state,
                node_id,
                now,
            },
        )
    }

    /// Raises an error with an explicit register: EMCY frame, 1001h, 1003h.
    fn raise_own(&mut self, e: EmcyFrame, bits: u8, now: Instant) {
        if self.own_errors.iter().any(|(c, _)| *c == e.code) {
            return;
        }
        self.own_errors.push((e.code, bits));
        let reg = self.own_errors.iter().fold(0, |a, (_, r)| a | r);
        self.node.send_raw_emcy(e.code, reg, e.bytes, now);
        let od = self.node.od_mut();
        if let Ok(r) = od.find(0x1001, 0) {
            od.set_raw(r, &[reg]);
        }
        // 1003h through the node's EMCY producer, so its reads agree (CiA
        // 301 §7.5.2.5; KC1 §7.2.1.4: the code, with the manufacturer's
        // first byte as additional information).
        self.node.record_emcy_history(u32::from(e.code) | (u32::from(e.bytes[0]) << 16));
    }

    /// Clears an error raised by [`Self::raise_own`]; the error-reset EMCY
    /// carries the register of the errors still active.
    fn clear_own(&mut self, code: u16, now: Instant) -> bool {
        let before = self.own_errors.len();
        self.own_errors.retain(|(c, _)| *c != code);
        if self.own_errors.len() == before {
            return false;
        }
        let reg = self.own_errors.iter().fold(0, |a, (_, r)| a | r);
        self.node.send_raw_emcy(0, reg, [0; 5], now);
        let od = self.node.od_mut();
        if let Ok(r) = od.find(0x1001, 0) {
            od.set_raw(r, &[reg]);
        }
        true
    }

    fn raise_frame(&mut self, e: EmcyFrame, now: Instant) {
        match e.register {
            Some(bits) => self.raise_own(e, bits, now),
            None => {
                self.node.raise_emcy(e.code, e.bytes, now);
            }
        }
    }

    fn clear_code(&mut self, code: u16, now: Instant) {
        if !self.clear_own(code, now) {
            self.node.clear_emcy(code, now);
        }
    }

    /// Carries out queued actions and the drive's EMCY requests; returns
    /// whether anything was queued for sending.
    fn drain(&mut self, now: Instant, out: &mut impl TxSink) -> bool {
        let mut any = false;
        let reqs: Vec<EmcyRequest> = self.drive.take_emcy().collect();
        for r in reqs {
            any = true;
            match r {
                EmcyRequest::Raise(c) => {
                    let e = self.behaviour.emcy(c);
                    self.raise_frame(e, now);
                }
                EmcyRequest::Clear(c) => {
                    let code = self.behaviour.emcy(c).code;
                    self.clear_code(code, now);
                }
            }
        }
        let actions: Vec<Action> = self.actions.drain(..).collect();
        for a in actions {
            any = true;
            match a {
                Action::RawEmcy(e) => {
                    let reg = e.register.unwrap_or(0);
                    self.node.send_raw_emcy(e.code, reg, e.bytes, now);
                }
                Action::Raise(e) => self.raise_frame(e, now),
                Action::Clear(c) => self.clear_code(c, now),
                Action::RequestTpdo(n) => {
                    self.node.request_tpdo(n);
                }
                Action::Restore { index, sub, value, only_if } => {
                    let od = self.node.od_mut();
                    if let Ok(r) = od.find(index, sub)
                        && only_if.is_none_or(|v| od.get_u32(index, sub) == Some(v))
                    {
                        let len = od.entry(r).data_type.fixed_size().unwrap_or(4).min(4);
                        od.set_raw(r, &value.to_le_bytes()[..len]);
                    }
                    if let Some(o) = self.node.od().object(index).cloned() {
                        // insert_object re-resolves the PDO service.
                        self.node.insert_object(o);
                    }
                }
                Action::Inject(i) => self.drive.inject(i),
                Action::TpdoChangeMask { tpdo, mask } => {
                    self.node.set_tpdo_change_mask(tpdo, mask);
                }
                Action::Nmt(cmd) => {
                    let (node, mut app) = self.split(now);
                    // What is already queued goes first (the SSD 630's boot
                    // EMCY before the PDOs of operational).
                    node.poll(now, &mut app, out);
                    node.nmt_command(cmd, now, &mut app, out);
                }
            }
        }
        any
    }

    fn after(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        let mut any = false;
        // An action may queue more (an NMT change the behaviour reacts to):
        // a few rounds, bounded so a behaviour cannot loop the node.
        for _ in 0..4 {
            if !self.drain(now, out) {
                break;
            }
            any = true;
        }
        if any {
            let (node, mut app) = self.split(now);
            return node.poll(now, &mut app, out);
        }
        None
    }

    /// Handles a received frame, emitting into any [`TxSink`].
    pub fn handle_frame_into(&mut self, frame: &Frame, now: Instant, out: &mut impl TxSink) {
        if !self.booted {
            return;
        }
        let node_id = self.node.node_id();
        let f = match self.behaviour.filter_rx(self.node.od(), node_id, frame) {
            FilterOutcome::Pass => *frame,
            FilterOutcome::Replace(f) => f,
            FilterOutcome::Drop => return,
        };
        let (node, mut app) = self.split(now);
        node.handle_frame(&f, now, &mut app, out);
        self.after(now, out);
    }

    /// Boots at the first call, then does the node's timed work and steps
    /// the drive up to `now`; returns the next deadline.
    pub fn poll_into(&mut self, now: Instant, out: &mut impl TxSink) -> Option<Instant> {
        if !self.booted {
            self.booted = true;
            let (node, mut app) = self.split(now);
            node.boot(now, &mut app, out);
            let node_id = self.node.node_id();
            let mut cx = Context { drive: &mut self.drive, actions: &mut self.actions, node_id, now };
            self.behaviour.on_boot(&mut cx, self.node.od_mut());
        }
        let (node, mut app) = self.split(now);
        let next = node.poll(now, &mut app, out);
        let d = app.poll(node.od_mut(), now);
        let again = self.after(now, out);
        earliest(earliest(next, d), again)
    }
}

impl BusNode for PersonalityNode {
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut Outbox<'_>) {
        self.handle_frame_into(frame, now, out);
    }

    fn poll(&mut self, now: Instant, out: &mut Outbox<'_>) -> Option<Instant> {
        self.poll_into(now, out)
    }

    fn link_changed(&mut self, state: LinkState, now: Instant, out: &mut Outbox<'_>) {
        // CiA 402-2 6007h: bus-off aborts the connection.
        if state != LinkState::Active {
            self.drive.inject(Injection::ConnectionLost);
            self.after(now, out);
        }
    }
}

impl PersonalityNode {
    /// Assembles a node (used by [`super::build_custom`]).
    pub(super) fn assemble(
        node: Node,
        drive: Drive,
        behaviour: Box<dyn Behaviour>,
        profile: Profile,
        state: ModeState,
    ) -> Self {
        PersonalityNode {
            node,
            drive,
            behaviour,
            profile,
            state,
            actions: Vec::with_capacity(8),
            own_errors: Vec::new(),
            booted: false,
        }
    }
}
