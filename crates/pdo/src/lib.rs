//! PDO service (CiA 301 §7.2.2, §7.5.2.35–7.5.2.38), sans-IO.
//!
//! * [`install`] puts the RPDO/TPDO communication and mapping records into
//!   the object dictionary with their CiA 301 defaults; [`set_defaults`]
//!   lets a device profile or personality give a PDO its factory mapping.
//! * [`Pdo::check_write`] / [`Pdo::reconfigure`] implement the CiA 301
//!   configuration procedure for the node's hooks.
//! * [`Pdo::handle_frame`], [`Pdo::on_sync`] and [`Pdo::poll`] run the
//!   PDOs; conditions the node turns into EMCY frames are returned as
//!   [`PdoEvent`]s ([`PdoEvent::emcy_code`]).
//!
//! Mapped data is packed in mapping order, least significant bit first
//! (CiA 301 7.4.7.1). Byte-aligned mappings of plain objects take a copy
//! fast path; anything else is packed bit by bit.
//!
//! # Choices where CiA 301 leaves room
//!
//! * Communication record sub 4 is "reserved" (v4.2) and not implemented:
//!   access gives `0609 0011` from the dictionary. RPDO sub 3 (inhibit
//!   time) exists, is stored and is not used.
//! * Mapping changes need the PDO destroyed (COB-ID bit 31 set) → else
//!   `0609 0030`; entries need sub 0 = 0 → else `0609 0030`. An absent
//!   mapped object or sub-index → `0602 0000`; present but not mappable,
//!   wrong direction, variable size, a bit length other than the object's
//!   (a BOOLEAN may take 1 or 8 bits with bit granularity, 8 with byte
//!   granularity) or an unsupported dummy → `0604 0041`; too long →
//!   `0604 0042` (on the entry alone, or on sub 0 for the total); sub 0
//!   above the supported number of entries → `0609 0031`.
//! * Making a PDO valid whose stored mapping no longer resolves → `0609 0030`.
//!   A valid PDO with sub 0 = 0 is accepted but does not run.
//! * Without RTR support, a TPDO COB-ID with bit 30 = 0 → `0609 0030`
//!   (CiA 301 7.5.2.37); on RPDOs bit 30 is ignored. Drives that accept
//!   such writes anyway (KC1/AKD: masters enable TPDOs as `0000_0183h`,
//!   seed001 AKD example 6) set `ignore_rtr_bit`.
//! * Dummy entries in a TPDO transmit zeros.
//! * RTR: 253 samples and sends at once; 252 sends at once the data sampled
//!   at the last SYNC (before any SYNC: at the next SYNC); 254/255 send at
//!   once unless the inhibit time is running (then when it ends); 0..240
//!   send at the next SYNC.
//! * Event-driven and acyclic TPDOs send their current data at the first
//!   opportunity after [`Pdo::reset`] or a configuration change.
//! * RPDO deadline monitoring starts with the first reception; only frames
//!   with a sufficient length re-arm it.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod bits;
mod check;
mod cobid;
mod config;
mod events;
mod image;
mod layout;
mod mapping;
mod objects;
mod service;

pub use bits::{pack_bits, unpack_bits};
pub use cobid::{COB_EXTENDED, COB_ID_BITS, COB_INVALID, COB_NO_RTR, can_id, is_valid, restricted_id};
pub use config::{DEFAULT_DUMMY_TYPES, Granularity, MAX_MAPPED_ENTRIES, MAX_PDOS, PdoConfig};
pub use events::{EVENT_QUEUE_LEN, PdoEvent, PdoRx};
pub use image::MappedPdo;
pub use layout::{MappedObject, PdoMapEntry, find_mapped, layout, mapped_bits};
pub use mapping::{PdoKind, map_entry, split_entry, validate_entry, validate_mapping};
pub use objects::{
    PdoDefaults, SUB_COB_ID, SUB_EVENT_TIMER, SUB_INHIBIT_TIME, SUB_SYNC_START, SUB_TRANSMISSION_TYPE,
    TT_EVENT_MANUFACTURER, TT_EVENT_PROFILE, TT_EVENT_RTR, TT_SYNC_RTR, classify, comm_index, default_cob_id,
    install, map_index, set_defaults, update_node_id,
};
pub use service::Pdo;
