//! The device contract: what any host (the virtual bus, a real-time loop on
//! a real bus, a test) runs.

use crate::{Frame, Instant, TxSink};
use core::any::Any;

/// Connection state of a station's CAN controller (ISO 11898-1 fault
/// confinement, plus the cable).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkState {
    /// Transmits and receives normally (error active).
    Active,
    /// Still on the bus, but its transmit error counter passed 127: it
    /// only signals errors passively (ISO 11898-1 §12.1.4.2).
    ErrorPassive,
    /// Its controller is bus-off: nothing it queues reaches the bus and it
    /// receives nothing. `recover_at` is when automatic recovery completes.
    BusOff {
        /// Automatic recovery time, `None` when only a manual recovery helps.
        recover_at: Option<Instant>,
    },
    /// Unplugged: nothing in, nothing out, until reconnected.
    Disconnected,
}

impl LinkState {
    /// True while the station takes part in bus traffic (active or error
    /// passive).
    #[inline]
    pub const fn is_on_bus(self) -> bool {
        matches!(self, LinkState::Active | LinkState::ErrorPassive)
    }
}

/// A sans-IO CAN device: the one contract every host drives (the virtual
/// bus `drivebus_bus::Bus`, the real-time host `drivebus_transport::host`,
/// tests, an embedded main loop).
///
/// The host calls [`start`](Device::start) once (power on), then
/// [`handle_frame`](Device::handle_frame) for every received frame and
/// [`poll`](Device::poll) at (or after) the deadline `poll` last returned,
/// and after every other call (a frame or a link change may move the
/// deadline). `now` never decreases. A deadline is a promise: polling
/// earlier does nothing observable. Frames go into `out` in the order they
/// must reach the bus.
///
/// The transmit sink is `&mut dyn TxSink` so hosts can hold
/// `Box<dyn Device>`; the device's protocol machines still run
/// monomorphised behind it (`&mut out` is a sized `TxSink`).
pub trait Device {
    /// Power on at `now` (e.g. a CANopen node's boot-up message).
    fn start(&mut self, now: Instant, out: &mut dyn TxSink);

    /// A frame was received at `now` (the end of its EOF on the wire).
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut dyn TxSink);

    /// Do the work due at `now`; return the next deadline (`None`: none).
    fn poll(&mut self, now: Instant, out: &mut dyn TxSink) -> Option<Instant>;

    /// The controller's link state changed (error passive, bus-off,
    /// recovered, unplugged). Frames emitted while not on the bus are
    /// discarded by the host. Default: ignored.
    fn link_changed(&mut self, state: LinkState, now: Instant, out: &mut dyn TxSink) {
        let _ = (state, now, out);
    }

    /// Another station's transmission was destroyed and an error frame
    /// ended at `now`. Default: ignored.
    fn handle_error_frame(&mut self, now: Instant, out: &mut dyn TxSink) {
        let _ = (now, out);
    }

    /// The device as [`Any`], so a host can hand out its concrete type.
    fn as_any(&self) -> &dyn Any;

    /// The device as [`Any`], mutably.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

/// A boxed device is a device; `as_any` reaches the boxed value, not the box.
impl<D: Device + ?Sized> Device for alloc::boxed::Box<D> {
    #[inline]
    fn start(&mut self, now: Instant, out: &mut dyn TxSink) {
        (**self).start(now, out)
    }
    #[inline]
    fn handle_frame(&mut self, frame: &Frame, now: Instant, out: &mut dyn TxSink) {
        (**self).handle_frame(frame, now, out)
    }
    #[inline]
    fn poll(&mut self, now: Instant, out: &mut dyn TxSink) -> Option<Instant> {
        (**self).poll(now, out)
    }
    #[inline]
    fn link_changed(&mut self, state: LinkState, now: Instant, out: &mut dyn TxSink) {
        (**self).link_changed(state, now, out)
    }
    #[inline]
    fn handle_error_frame(&mut self, now: Instant, out: &mut dyn TxSink) {
        (**self).handle_error_frame(now, out)
    }
    fn as_any(&self) -> &dyn Any {
        (**self).as_any()
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        (**self).as_any_mut()
    }
}

/// `&mut &mut dyn TxSink` is a sized sink: pass `&mut out` where a
/// protocol machine takes `&mut impl TxSink`.
impl TxSink for &mut dyn TxSink {
    #[inline]
    fn send(&mut self, frame: Frame) {
        (**self).send(frame)
    }
}
