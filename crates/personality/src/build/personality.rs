//! [`Personality`]: the CiA 402 drive and the personality's behaviour in
//! front of it, as the node's one [`Application`] (see the parent module).

use super::{Behaviour, Context, Verdict};
use crate::Profile;
use alloc::boxed::Box;
use drivebus_can::{Frame, Instant};
use drivebus_cia402::drive::{Drive, Injection};
use drivebus_node::{AppContext, Application, FrameFilter, NodeEvent};
use drivebus_od::{ObjectDictionary, Owner, SdoAbort, Target, WriteOutcome};

extern crate alloc;

/// The owner tag of the objects the behaviour owns itself (manufacturer
/// objects it hooks); the drive's tags are its table positions, far below.
pub(crate) const BEHAVIOUR: Owner = Owner::app(0xBF);

/// A personality: the CiA 402 drive and the behaviour that makes it act
/// like the product. `drivebus_node::NodeDevice<Personality>` is the device
/// [`crate::build()`] returns.
pub struct Personality {
    /// The CiA 402 drive.
    pub drive: Drive,
    /// The personality's quirks.
    pub behaviour: Box<dyn Behaviour>,
    profile: Profile,
    /// The drive-owned entry whose write the behaviour took with
    /// [`Verdict::Store`]: stored as written, not applied by the drive.
    stored_by_behaviour: Option<(u16, u8)>,
    /// The machine's faults, applied as time passes (`machine`).
    faults: Option<crate::machine::FaultSchedule>,
}

impl core::fmt::Debug for Personality {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Personality")
            .field("profile", &self.profile)
            .field("statusword", &self.drive.statusword())
            .finish()
    }
}

impl Personality {
    /// Pairs a drive with a behaviour.
    pub(crate) fn new(drive: Drive, behaviour: Box<dyn Behaviour>, profile: Profile) -> Self {
        Personality { drive, behaviour, profile, stored_by_behaviour: None, faults: None }
    }

    /// The personality.
    pub fn profile(&self) -> Profile {
        self.profile
    }

    /// The manufacturer mode (negative 6060h) in force, if any.
    pub fn manufacturer_mode(&self) -> Option<i8> {
        self.drive.manufacturer_mode()
    }

    /// Applies a fault injection to the drive (takes effect at its next
    /// control period; EMCY frames follow the personality's mapping).
    pub fn inject(&mut self, what: Injection) {
        self.drive.inject(what);
    }

    /// Applies `schedule` from now on, its times counted from the drive's
    /// boot (replaces an earlier schedule; kept when empty: it holds the
    /// machine's polarities and input values for run-time changes).
    pub fn set_fault_schedule(&mut self, schedule: crate::machine::FaultSchedule) {
        self.faults = Some(schedule);
    }

    /// Makes `change` to the machine at `now` for `duration` seconds
    /// (`None`: until changed again or cleared), through the machine's
    /// schedule exactly as a `[[node.faults]]` / `[[node.inputs]]` entry
    /// due now; it shows at the next poll (wake the device). Values out of
    /// range are refused, naming the key.
    pub fn change_machine(
        &mut self,
        now: Instant,
        change: crate::machine::Change,
        duration: Option<f64>,
    ) -> Result<(), crate::machine::MachineError> {
        use crate::machine::{FaultSchedule, Polarity};
        // A drive built without a machine: the default wiring, inputs low.
        let s = self.faults.get_or_insert_with(|| {
            FaultSchedule::new(alloc::vec::Vec::new(), Polarity::default(), Polarity::NormallyOpen)
        });
        s.change(now, change, duration)
    }

    /// The machine's faults and input changes in force at `now` (the
    /// machine file's and those made at run time).
    pub fn machine_in_force(&self, now: Instant) -> Vec<crate::machine::InForce> {
        self.faults.as_ref().map_or_else(Vec::new, |s| s.in_force(now))
    }

    /// The behaviour as its concrete type `T` (e.g.
    /// [`crate::ssd630::Ssd630`] to switch its enable input at
    /// run time); `None` if it is another type or does not expose itself
    /// ([`Behaviour::as_any_mut`]). A change takes effect at the next poll.
    pub fn behaviour_mut<T: core::any::Any>(&mut self) -> Option<&mut T> {
        self.behaviour.as_any_mut()?.downcast_mut::<T>()
    }

    /// The behaviour's patch of the live values after the drive published
    /// them (statusword bits 8/9/14/15, …).
    fn after_step(&mut self, cx: &mut AppContext<'_>) {
        let (now, node_id) = (cx.now, cx.node_id());
        let (od, requests) = cx.parts();
        let mut c = Context { drive: &mut self.drive, requests, node_id, now };
        self.behaviour.after_step(&mut c, od);
    }

    /// The drive's EMCY requests, as the personality sends them.
    fn flush(&mut self, cx: &mut AppContext<'_>) {
        let b = &self.behaviour;
        self.drive.flush_emcy(cx, |code| b.emcy(code).raise());
    }

    fn drive_owns(at: &Target) -> bool {
        at.owner.is_app() && at.owner != BEHAVIOUR
    }
}

impl Application for Personality {
    fn check_write(
        &mut self,
        cx: &mut AppContext<'_>,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        self.stored_by_behaviour = None;
        let (now, node_id) = (cx.now, cx.node_id());
        let (od, requests) = cx.parts();
        let mut c = Context { drive: &mut self.drive, requests, node_id, now };
        let verdict = self.behaviour.on_write(&mut c, od, at.index, at.sub, data);
        let r = match verdict {
            Err(e) => Err(e),
            Ok(Verdict::Handled) => Ok(WriteOutcome::Handled),
            Ok(Verdict::Store) => {
                self.stored_by_behaviour = Some((at.index, at.sub));
                Ok(WriteOutcome::Store)
            }
            // The drive's entry checks its own objects; another owner's
            // (a watched communication object) checks after this returns.
            Ok(Verdict::Pass) if Self::drive_owns(at) => self.drive.check_object(od, at, data),
            Ok(Verdict::Pass) => Ok(WriteOutcome::Store),
        };
        self.flush(cx);
        r
    }

    fn apply_write(&mut self, cx: &mut AppContext<'_>, at: &Target) {
        let taken = self.stored_by_behaviour.take() == Some((at.index, at.sub));
        if Self::drive_owns(at) && !taken {
            self.drive.apply_object(cx.od, at);
        }
        let (now, node_id) = (cx.now, cx.node_id());
        let (od, requests) = cx.parts();
        let mut c = Context { drive: &mut self.drive, requests, node_id, now };
        self.behaviour.after_write(&mut c, od, at.index, at.sub);
        self.after_step(cx);
        self.flush(cx);
    }

    fn on_read(&mut self, cx: &mut AppContext<'_>, at: &Target) -> Result<(), SdoAbort> {
        let (now, node_id) = (cx.now, cx.node_id());
        let (od, requests) = cx.parts();
        let mut c = Context { drive: &mut self.drive, requests, node_id, now };
        self.behaviour.on_read(&mut c, od, at.index, at.sub)?;
        if Self::drive_owns(at) {
            self.drive.refresh_object(cx.od, at);
        }
        Ok(())
    }

    fn filter_frame(&mut self, od: &ObjectDictionary, node_id: u8, frame: &Frame) -> FrameFilter {
        self.behaviour.filter_rx(od, node_id, frame)
    }

    fn on_start(&mut self, cx: &mut AppContext<'_>) {
        if let Some(f) = &mut self.faults {
            f.start(cx.now);
        }
        let (now, node_id) = (cx.now, cx.node_id());
        let (od, requests) = cx.parts();
        let mut c = Context { drive: &mut self.drive, requests, node_id, now };
        self.behaviour.on_boot(&mut c, od);
        self.flush(cx);
    }

    fn on_sync(&mut self, cx: &mut AppContext<'_>, counter: Option<u8>) {
        let _ = counter;
        self.drive.sync(cx.od);
        let (now, node_id) = (cx.now, cx.node_id());
        let (od, requests) = cx.parts();
        let mut c = Context { drive: &mut self.drive, requests, node_id, now };
        self.behaviour.on_sync(&mut c, od);
        self.after_step(cx);
        self.flush(cx);
    }

    fn on_event(&mut self, cx: &mut AppContext<'_>, event: NodeEvent) {
        self.drive.event(cx.od, event);
        let (now, node_id) = (cx.now, cx.node_id());
        let (od, requests) = cx.parts();
        let mut c = Context { drive: &mut self.drive, requests, node_id, now };
        self.behaviour.on_event(&mut c, od, &event);
        self.after_step(cx);
        self.flush(cx);
    }

    fn poll(&mut self, cx: &mut AppContext<'_>) -> Option<Instant> {
        // Before the step, so the step sees what became due.
        let fault_due = self.faults.as_mut().and_then(|f| f.run(cx.now, &mut self.drive));
        let next = self.drive.step_to(cx.od, cx.now);
        self.after_step(cx);
        self.flush(cx);
        Some(fault_due.map_or(next, |d| d.min(next)))
    }
}
