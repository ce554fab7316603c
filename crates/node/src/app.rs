//! How application code (a CiA 402 drive, a test) attaches to a node.

use drivebus_can::Instant;
use drivebus_emcy::EmcyReceived;
use drivebus_nmt::{NmtState, RemoteState};
use drivebus_od::{NoHooks, ObjectDictionary, ObjectHooks};
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
}

/// Application behaviour on top of the object-dictionary hooks.
///
/// Every method has an empty default, so a plain device is `NoHooks`.
pub trait Application: ObjectHooks {
    /// A SYNC was received or produced. Synchronous RPDO data has already
    /// been applied and synchronous TPDOs sampled when this is called.
    fn on_sync(&mut self, od: &mut ObjectDictionary, counter: Option<u8>, now: Instant) {
        let _ = (od, counter, now);
    }
    /// Something happened on the communication side.
    fn on_event(&mut self, od: &mut ObjectDictionary, event: NodeEvent, now: Instant) {
        let _ = (od, event, now);
    }
    /// Time passed: do the application's timed work (a drive steps its
    /// model here) and return its next deadline.
    fn poll(&mut self, od: &mut ObjectDictionary, now: Instant) -> Option<Instant> {
        let _ = (od, now);
        None
    }
}

impl Application for NoHooks {}
