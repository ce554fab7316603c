//! How application code (a CiA 402 drive, a personality, a test) attaches
//! to a node: the [`Application`] callbacks, the [`AppContext`] they get,
//! and the [`Request`]s they hand back.

use alloc::vec::Vec;
use drivebus_can::{Frame, Instant, LinkState};
use drivebus_emcy::EmcyReceived;
use drivebus_nmt::{NmtCommand, NmtState, RemoteState};
use drivebus_od::{NoHooks, ObjectDictionary, SdoAbort, Target, WriteOutcome};
use drivebus_sync::TimeOfDay;

/// Something the communication layer tells the application.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NodeEvent {
    /// The NMT state changed.
    NmtState {
        /// Previous state.
        from: NmtState,
        /// New state.
        to: NmtState,
    },
    /// NMT reset node: the application's parameters were set to their
    /// power-on values; reset the application now.
    ResetApplication,
    /// NMT reset communication was carried out.
    ResetCommunication,
    /// A monitored node's heartbeat stopped (1016h).
    HeartbeatTimeout {
        /// Node-ID.
        node: u8,
    },
    /// A monitored node's heartbeat came back.
    HeartbeatRecovered {
        /// Node-ID.
        node: u8,
    },
    /// A monitored node booted (heartbeat 00h).
    RemoteBootup {
        /// Node-ID.
        node: u8,
    },
    /// A monitored node reported another state.
    RemoteState {
        /// Node-ID.
        node: u8,
        /// Its state.
        state: RemoteState,
    },
    /// The master stopped guarding this node (100Ch × 100Dh expired).
    LifeGuardingLost,
    /// Guarding resumed.
    LifeGuardingResolved,
    /// No SYNC within the expected time.
    SyncTimeout,
    /// An RPDO's deadline (event timer) expired.
    RpdoTimeout {
        /// RPDO number (0-based).
        rpdo: u16,
    },
    /// An EMCY from a consumed producer (1028h).
    Emcy(EmcyReceived),
    /// A TIME stamp was received.
    Time(TimeOfDay),
    /// LSS configured a new node-ID (active after reset communication).
    LssNodeId(u8),
    /// LSS "activate bit timing": switch the controller to the CiA 305
    /// table index after `delay_ms`, then stay silent for `delay_ms`.
    LssActivateBitTiming {
        /// Bit timing table index (0 = 1 Mbit/s … 8 = 10 kbit/s).
        index: u8,
        /// Switch delay in ms.
        delay_ms: u16,
    },
    /// The CAN controller's link state changed (the host's
    /// [`Device::link_changed`](drivebus_can::Device::link_changed)).
    Link(LinkState),
}

/// What [`Application::filter_frame`] does with a received frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameFilter {
    /// Hand the frame to the node unchanged.
    Pass,
    /// Hand this frame instead (e.g. a drive that corrects an SDO size field).
    Replace(Frame),
    /// The device ignores the frame.
    Drop,
}

/// Something the application asks the node to do. Requests queue in the
/// [`AppContext`] and the node carries them out right after the callback
/// that produced them returned (in order; one that makes more runs them
/// too, a few rounds deep).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Request {
    /// Raise an error: 1001h, 1003h and an EMCY frame (CiA 301 §7.2.7).
    /// `register: None` keeps CiA 301's bookkeeping (generic bit plus the
    /// class bit of `code`). `Some(bits)` is a device-defined error
    /// register: 1001h is exactly the OR of the active such errors' bits,
    /// the 1003h entry carries manufacturer byte 0 as additional
    /// information, and each clear sends a reset EMCY with the bits still
    /// set (KC1/AKD, iPOS, SSD 630 manuals).
    RaiseEmcy {
        /// Error code.
        code: u16,
        /// Device-defined register bits, or `None`.
        register: Option<u8>,
        /// Manufacturer-specific bytes 3–7.
        manufacturer: [u8; 5],
    },
    /// An error went away (the error-reset EMCY goes when the last clears).
    ClearEmcy(u16),
    /// Every active error went away.
    ClearAllEmcy,
    /// Send an EMCY frame outside the error bookkeeping (boot messages,
    /// quirks).
    RawEmcy {
        /// Error code.
        code: u16,
        /// Error register byte.
        register: u8,
        /// Manufacturer-specific bytes 3–7.
        bytes: [u8; 5],
    },
    /// Send an event-driven / acyclic TPDO (0-based number).
    RequestTpdo(u16),
    /// Restrict change-of-state detection of a TPDO (0-based) to the set
    /// bits of `mask` (byte `i` masks PDO byte `i`); `None`: every bit.
    TpdoChangeMask {
        /// TPDO number, 0-based.
        tpdo: u16,
        /// The mask.
        mask: Option<[u8; 8]>,
    },
    /// A local NMT command: the device acts on it as on one received for
    /// its node-ID (see [`crate::Node::nmt_command`]).
    Nmt(NmtCommand),
    /// Save every parameter group as a 1010h:01 "save all parameters"
    /// write does (a manufacturer's own save command, e.g. Kollmorgen
    /// DRV.NVSAVE, Technosoft iPOS 2076h, whether or not the device has
    /// 1010h); the stored values come back at the next power-on or reset.
    /// A store that fails leaves the previous images and is not reported
    /// (the application's object has no abort left to give).
    StoreParameters,
    /// Put this raw value back into a sub-object after the current call,
    /// and re-read the PDO configuration (used to lift a restriction for
    /// one write, e.g. remapping a valid PDO).
    Restore {
        /// Index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The raw little-endian value.
        value: u32,
        /// Only if the sub-object still holds this value; `None`: always.
        only_if: Option<u32>,
    },
}

/// What an [`Application`] callback gets: the dictionary, the time, the
/// node-ID, and the queue for its [`Request`]s.
pub struct AppContext<'a> {
    /// The node's dictionary: read parameters, push live values with
    /// `set_le`/`set_raw` (through handles resolved once).
    pub od: &'a mut ObjectDictionary,
    /// The time of the call.
    pub now: Instant,
    node_id: u8,
    requests: &'a mut Vec<Request>,
}

impl<'a> AppContext<'a> {
    /// A context over `od` whose requests go to `requests` (the node builds
    /// one per callback; tests and benches driving an application without
    /// a node build their own).
    pub fn new(
        od: &'a mut ObjectDictionary,
        now: Instant,
        node_id: u8,
        requests: &'a mut Vec<Request>,
    ) -> Self {
        AppContext { od, now, node_id, requests }
    }

    /// The node-ID (FFh while unconfigured).
    #[inline]
    pub fn node_id(&self) -> u8 {
        self.node_id
    }
    /// Queue a request for the node.
    #[inline]
    pub fn request(&mut self, r: Request) {
        self.requests.push(r);
    }
    /// Raise an error with CiA 301's bookkeeping.
    pub fn raise_emcy(&mut self, code: u16) {
        self.request(Request::RaiseEmcy { code, register: None, manufacturer: [0; 5] });
    }
    /// An error went away.
    pub fn clear_emcy(&mut self, code: u16) {
        self.request(Request::ClearEmcy(code));
    }
    /// Send an event-driven TPDO (0-based).
    pub fn request_tpdo(&mut self, n: u16) {
        self.request(Request::RequestTpdo(n));
    }
    /// A local NMT command.
    pub fn nmt_command(&mut self, cmd: NmtCommand) {
        self.request(Request::Nmt(cmd));
    }
    /// The dictionary and the request queue apart (an application handing
    /// both to its parts).
    pub fn parts(&mut self) -> (&mut ObjectDictionary, &mut Vec<Request>) {
        (self.od, self.requests)
    }
    /// A context over the same dictionary and queue (to hand on to an
    /// application this one wraps).
    pub fn reborrow(&mut self) -> AppContext<'_> {
        AppContext { od: self.od, now: self.now, node_id: self.node_id, requests: self.requests }
    }
}

/// Application behaviour on a node: the owner of its own objects on the
/// write path, the watcher of communication objects it marked, and the
/// receiver of the node's events.
///
/// The node calls an [`Application`] through one dispatch per write: for a
/// sub-object whose owner tag is an application tag
/// ([`Owner::is_app`](drivebus_od::Owner::is_app)) it calls
/// [`check_write`](Application::check_write) before and
/// [`apply_write`](Application::apply_write) after the store, once each;
/// for a sub-object marked `watched` (another owner, e.g. 1010h) it calls
/// `check_write` first (a veto), then the owner checks, stores and applies,
/// then `apply_write` tells the application. `DEVELOPERS.md` has the whole
/// order.
///
/// Every method has an empty default, so a plain device is [`NoHooks`].
pub trait Application {
    /// A write to an entry this application owns or watches, after type,
    /// length and limit checks, before anything is stored. An abort refuses
    /// it; [`WriteOutcome::Handled`] means the application applied it
    /// itself (nothing is stored, `apply_write` is not called). For a
    /// watched entry, `Store` lets the owner's check go on.
    fn check_write(
        &mut self,
        cx: &mut AppContext<'_>,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let _ = (cx, at, data);
        Ok(WriteOutcome::Store)
    }

    /// The write `check_write` accepted is stored (and, for a watched
    /// entry, applied by its owner): take the new value.
    fn apply_write(&mut self, cx: &mut AppContext<'_>, at: &Target) {
        let _ = (cx, at);
    }

    /// Before a live entry this application owns or watches is read: may
    /// refresh the value (`cx.od.set_raw(at.r, ..)`) or refuse.
    fn on_read(&mut self, cx: &mut AppContext<'_>, at: &Target) -> Result<(), SdoAbort> {
        let _ = (cx, at);
        Ok(())
    }

    /// A received frame before the node handles it: pass, replace or drop
    /// (a drive whose firmware reads frames its own way).
    fn filter_frame(&mut self, od: &ObjectDictionary, node_id: u8, frame: &Frame) -> FrameFilter {
        let _ = (od, node_id, frame);
        FrameFilter::Pass
    }

    /// The node booted (boot-up message sent, stored values loaded).
    fn on_start(&mut self, cx: &mut AppContext<'_>) {
        let _ = cx;
    }

    /// A SYNC was received or produced. Synchronous TPDOs have been
    /// sampled and the synchronous RPDO data applied when this is called.
    fn on_sync(&mut self, cx: &mut AppContext<'_>, counter: Option<u8>) {
        let _ = (cx, counter);
    }

    /// Something happened on the communication side.
    fn on_event(&mut self, cx: &mut AppContext<'_>, event: NodeEvent) {
        let _ = (cx, event);
    }

    /// Time passed: do the application's timed work (a drive steps its
    /// model here) and return its next deadline. Called when that deadline
    /// is due and after any other callback.
    fn poll(&mut self, cx: &mut AppContext<'_>) -> Option<Instant> {
        let _ = cx;
        None
    }
}

impl Application for NoHooks {}
