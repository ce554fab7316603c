//! Layer Setting Services (CiA 305 v3.0.0), sans-IO.
//!
//! * [`LssSlave`]: the slave side of every CiA 305 service a CANopen device
//!   offers: switch state global/selective, configure node-ID and bit timing,
//!   activate bit timing, store configuration, inquire identity and node-ID,
//!   identify (non-configured) remote slave and fastscan.
//! * [`codec`]: [`LssRequest`] / [`LssResponse`], the frame codec both sides
//!   share, and [`master`]: request builders and the response parser an LSS
//!   master (the `drivebus lss …` CLI, tests) uses.
//! * [`FastScan`]: the master's fastscan state machine, which finds the
//!   128-bit LSS address of one unconfigured slave bit by bit.
//!
//! All LSS frames are 8 bytes: master → slave on COB-ID [`MASTER_TO_SLAVE`]
//! (7E5h), slave → master on [`SLAVE_TO_MASTER`] (7E4h). Byte 0 is the
//! command specifier; unused bytes are sent as 0 and ignored on receipt.
//!
//! # Contract for a device booting without a node-ID
//!
//! A device whose stored node-ID is invalid ([`UNCONFIGURED`], FFh) is an
//! *unconfigured* LSS slave (CiA 305 §"non-configured LSS slave"). The node
//! (`drivebus-node`, or whoever integrates [`LssSlave`]) must then run in
//! **LSS-only operation**:
//!
//! 1. Construct the slave with `node_id = 0xFF`. [`LssSlave::is_lss_only`]
//!    returns true.
//! 2. While it is true, the node sends **nothing** but what the LSS slave
//!    emits: no boot-up message, no heartbeat, EMCY, PDO or SDO; it ignores
//!    NMT commands and routes only 7E5h frames to
//!    [`LssSlave::handle_frame`]. The NMT state machine stays in
//!    *Initialisation* (it has no node-ID to build its COB-IDs from).
//! 3. An LSS master finds the device (fastscan or switch state selective),
//!    configures a node-ID ([`LssEvent::NodeIdConfigured`]), optionally
//!    stores it ([`LssEvent::StoreRequested`], answered through
//!    [`LssSlave::complete_store`]) and switches the slaves back to waiting.
//! 4. On that switch, because the active node-ID is invalid and the pending
//!    one is valid, the slave returns [`LssEvent::ResetCommunication`]: the
//!    node performs NMT *reset communication* on its own, calls
//!    [`LssSlave::reset_communication`] (the pending node-ID becomes active),
//!    initialises its other services with that node-ID and sends its boot-up.
//!
//! A device that already has a valid node-ID runs normally with the LSS slave
//! alongside. A node-ID configured over LSS is only *pending*: it takes effect
//! when the node next performs NMT reset communication (NMT command, reset
//! node, power cycle), at which point it calls
//! [`LssSlave::reset_communication`]. The node persists the pending node-ID
//! and bit timing only on [`LssEvent::StoreRequested`].
//!
//! ```
//! use drivebus_can::Instant;
//! use drivebus_lss::{Identity, LssEvent, LssMode, LssSlave, StoreStatus, master};
//!
//! let addr = Identity::new(0x30C, 0x0060_4100, 0x0001_0002, 42);
//! let mut slave = LssSlave::new(addr, 0xFF, 4); // stored node-ID: none, 125 kbit/s
//! assert!(slave.is_lss_only()); // no boot-up, no other service yet
//! let (now, mut out) = (Instant::ZERO, Vec::new());
//! let mut event = None;
//! for f in master::switch_state_selective(&addr) {
//!     event = slave.handle_frame(&f, now, &mut out);
//! }
//! assert_eq!(event, Some(LssEvent::EnteredConfiguration));
//! let ev = slave.handle_frame(&master::configure_node_id(7), now, &mut out);
//! assert_eq!(ev, Some(LssEvent::NodeIdConfigured(7)));
//! let ev = slave.handle_frame(&master::store_configuration(), now, &mut out);
//! assert_eq!(ev, Some(LssEvent::StoreRequested { node_id: 7, bit_timing: 4 }));
//! // ... the node writes node-ID 7 and bit timing 4 to its storage ...
//! slave.complete_store(StoreStatus::Stored, &mut out);
//! let ev = slave.handle_frame(&master::switch_state_global(LssMode::Waiting), now, &mut out);
//! assert_eq!(ev, Some(LssEvent::ResetCommunication { node_id: 7 }));
//! // The node's NMT reset communication:
//! assert_eq!(slave.reset_communication(), 7);
//! assert!(!slave.is_lss_only()); // now it sends its boot-up 707h
//! assert_eq!(out.len(), 3); // answers 44h, 11h, 17h
//! ```
//!
//! None of the five reference drives (KC1, AKD, iPOS, SSD 630, DDS6) documents
//! LSS: they take node-ID and bit rate from rotary switches, DIP switches or
//! their setup tools (`seed000-kc1.md` §4.2.2, `seed001-akd.md` B.13,
//! `seed003-ssd630.md` B.1, `seed004-dds6.md` B.11; the iPOS in
//! `seed002-ipos.md` is an EtherCAT drive). The tests use their identity
//! objects (1018h) as realistic LSS addresses.
#![cfg_attr(not(feature = "std"), no_std)]

pub mod codec;
mod fastscan;
pub mod master;
mod slave;

pub use codec::{IdentifyStep, LssField, LssRequest, LssResponse};
pub use fastscan::{FastScan, FastScanOutcome};
pub use slave::{LssEvent, LssSlave, StoreStatus};

use drivebus_od::ObjectDictionary;

/// COB-ID of LSS requests, master → slave (CiA 305).
pub const MASTER_TO_SLAVE: u16 = 0x7E5;
/// COB-ID of LSS responses, slave → master (CiA 305).
pub const SLAVE_TO_MASTER: u16 = 0x7E4;
/// The invalid node-ID: a slave holding it is unconfigured.
pub const UNCONFIGURED: u8 = 0xFF;
/// Table selector of the standard CiA bit timing table.
pub const STANDARD_TABLE: u8 = 0;

/// True for a node-ID a CANopen device may use (1..=127).
#[inline]
pub const fn is_valid_node_id(id: u8) -> bool {
    matches!(id, 1..=127)
}

/// True for a value "configure node-ID" accepts: 1..=127, or FFh to make
/// the device unconfigured again (CiA 305 v3.0.0, configure node-ID).
#[inline]
pub const fn is_configurable_node_id(id: u8) -> bool {
    is_valid_node_id(id) || id == UNCONFIGURED
}

/// Bit rate in kbit/s of an index of the standard CiA bit timing table
/// (table selector 0): 0 = 1000, 1 = 800, 2 = 500, 3 = 250, 4 = 125,
/// 5 = reserved, 6 = 50, 7 = 20, 8 = 10. Index 9 (automatic bit rate
/// detection), the reserved index 5 and anything above give `None`.
///
/// Index 5 was 100 kbit/s in early tables (some masters still document it
/// so); CiA 305 v3.0.0 marks it reserved, so a slave refuses it unless its
/// integrator opts in with [`LssSlave::with_bit_timings`].
pub const fn bit_rate_kbit(index: u8) -> Option<u16> {
    match index {
        0 => Some(1000),
        1 => Some(800),
        2 => Some(500),
        3 => Some(250),
        4 => Some(125),
        6 => Some(50),
        7 => Some(20),
        8 => Some(10),
        _ => None,
    }
}

/// Index in the standard bit timing table of a bit rate in kbit/s.
pub const fn bit_timing_index(kbit: u16) -> Option<u8> {
    match kbit {
        1000 => Some(0),
        800 => Some(1),
        500 => Some(2),
        250 => Some(3),
        125 => Some(4),
        50 => Some(6),
        20 => Some(7),
        10 => Some(8),
        _ => None,
    }
}

/// The two states of the LSS slave FSA (CiA 305 v3.0.0); the byte values
/// are those of "switch state global".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LssMode {
    /// LSS waiting: only selection and identification services apply.
    Waiting = 0,
    /// LSS configuration: node-ID, bit timing, store and inquire apply.
    Configuration = 1,
}

impl LssMode {
    /// The mode for a "switch state global" byte, `None` if undefined.
    #[inline]
    pub const fn from_byte(b: u8) -> Option<LssMode> {
        match b {
            0 => Some(LssMode::Waiting),
            1 => Some(LssMode::Configuration),
            _ => None,
        }
    }
}

/// The 128-bit LSS address is the identity object 1018h: one type,
/// [`Identity`], shared with the node, SII and ESI. Its field order (and
/// `Ord`) is the LSS address order.
pub use drivebus_can::Identity;

/// The LSS address stored in the identity object 1018h sub 1..4 of `od`,
/// `None` if 1018h has no serial number (sub 4): CiA 305 requires all four
/// parts for a unique LSS address.
pub fn address_from_od(od: &ObjectDictionary) -> Option<Identity> {
    Some(Identity {
        vendor_id: od.get_u32(0x1018, 1)?,
        product_code: od.get_u32(0x1018, 2)?,
        revision: od.get_u32(0x1018, 3)?,
        serial: od.get_u32(0x1018, 4)?,
    })
}

/// The address range "identify remote slave" asks about: vendor-ID and
/// product code must match exactly, revision and serial number must lie in
/// the inclusive ranges (CiA 305 v3.0.0, LSS identify remote slave).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LssAddressRange {
    /// Exact vendor-ID.
    pub vendor_id: u32,
    /// Exact product code.
    pub product_code: u32,
    /// Lowest revision number.
    pub revision_low: u32,
    /// Highest revision number.
    pub revision_high: u32,
    /// Lowest serial number.
    pub serial_low: u32,
    /// Highest serial number.
    pub serial_high: u32,
}

impl LssAddressRange {
    /// True when `addr` lies in the range.
    pub const fn contains(&self, addr: &Identity) -> bool {
        addr.vendor_id == self.vendor_id
            && addr.product_code == self.product_code
            && self.revision_low <= addr.revision
            && addr.revision <= self.revision_high
            && self.serial_low <= addr.serial
            && addr.serial <= self.serial_high
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bit_timing_table_is_cia_305() {
        let table: [(u8, Option<u16>); 10] = [
            (0, Some(1000)),
            (1, Some(800)),
            (2, Some(500)),
            (3, Some(250)),
            (4, Some(125)),
            (5, None),
            (6, Some(50)),
            (7, Some(20)),
            (8, Some(10)),
            (9, None),
        ];
        for (i, k) in table {
            assert_eq!(bit_rate_kbit(i), k, "index {i}");
            if let Some(k) = k {
                assert_eq!(bit_timing_index(k), Some(i));
            }
        }
        assert_eq!(bit_timing_index(100), None);
    }

    #[test]
    fn node_id_ranges() {
        assert!(!is_configurable_node_id(0));
        assert!(is_configurable_node_id(1) && is_configurable_node_id(127));
        assert!(!is_configurable_node_id(128) && !is_configurable_node_id(0xFE));
        assert!(is_configurable_node_id(0xFF) && !is_valid_node_id(0xFF));
    }

    #[test]
    fn address_from_identity_object() {
        use drivebus_od::{Access, DataType, Object, SubObject, Value};
        let mut od = ObjectDictionary::new();
        let mut obj = Object::record(0x1018, "Identity");
        for (sub, v) in [(1u8, 0x30Cu32), (2, 0x0060_4100), (3, 0x0001_0000), (4, 1234)] {
            obj = obj.with_sub(SubObject::new(sub, "x", DataType::Unsigned32, Access::Ro, Value::U32(v)));
        }
        od.insert(obj);
        assert_eq!(address_from_od(&od), Some(Identity::new(0x30C, 0x0060_4100, 0x0001_0000, 1234)));
        assert_eq!(address_from_od(&ObjectDictionary::new()), None);
    }
}
