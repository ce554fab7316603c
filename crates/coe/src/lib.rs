//! EtherCAT slave mailbox protocols, sans-IO: the mailbox layer
//! (ETG.1000.4 §5.6), CoE (ETG.1000.6 §5.6: SDO server with expedited,
//! normal and segmented transfers, complete access, SDO Information,
//! emergencies) and FoE, serving the same [`drivebus_od::ObjectDictionary`]
//! the CAN side serves.
//!
//! # Driving it from an ESC layer
//!
//! ```text
//! SM0 full (master wrote the last byte) ──► handle_request(sm0_bytes, now, esm_state, &mut device, &mut files)
//!                                           then release SM0
//! SM1 empty (master read the last byte) ──► next_response(now) → Some(mailbox) → write it into SM1
//! SM1 repeat request toggled            ──► last_response() → write it again, toggle repeat ack
//! timer at the deadline poll() returned ──► poll(now, &mut files)
//! device error                          ──► queue_emergency(code, register, data)
//! INIT ⇄ PRE-OP/BOOT (mailbox stop/start) ► reset(&mut files); set_mailbox_sizes(..) for the BOOT mailbox
//! ```
//!
//! `device` is anything implementing [`ObjectAccess`] (the device's checked
//! read/write path; [`OdAccess`] adapts a dictionary and its hooks) and
//! `files` a [`FileHandler`] ([`NoFiles`] for a device without FoE). The
//! ESM state is passed with every request: INIT requests are ignored, BOOT
//! accepts FoE only, and the FoE policy sees it.
//!
//! # Order of outgoing mailboxes
//!
//! [`MailboxServer::next_response`] gives, in this order: queued responses
//! (one per request, in request order), the next fragment of an SDO
//! Information answer, then emergencies. Emergencies are **held while an
//! SDO conversation of several mailboxes is under way** (segmented
//! transfer, fragmented OD list) and released when it ends or times out;
//! they are also held while the last request came in BOOT (FoE only).
//! Why: a master reads SM1 right after writing a request and takes what
//! it finds as the answer. ethercrab 0.7.1 asserts that this is not an
//! emergency (`mailbox/coe/mod.rs`), and inside a segmented transfer an
//! emergency in SM1 would be read in place of the next segment. The ESC
//! layer completes this by calling `handle_request` for a full SM0 before
//! asking for the next response, so a response already due always goes
//! ahead of an emergency.
//!
//! # Counters
//!
//! A request whose counter (1..=7) equals the previous request's is a
//! repetition and is dropped (ETG.1000.4 §5.6); counter 0 is never taken
//! as a repetition. Responses carry the server's own counter, 1..=7
//! wrapping to 1, set when the mailbox is handed out.
//!
//! # Allocation
//!
//! Response buffers, the last-response buffer and the emergency ring are
//! allocated by [`MailboxServer::new`]. A transfer allocates at most once,
//! at its initiate (the upload snapshot, the download accumulator, the
//! complete-access image, the OD list), reusing the capacity of earlier
//! transfers; segments, fragments and FoE packets do not allocate.
//!
//! # What the SII should announce, and mailbox sizes
//!
//! Mailbox protocols CoE and FoE (not EoE). CoE details: SDO, SDO
//! Information, PDO assignment, PDO configuration and, when
//! [`MailboxConfig::complete_access`] is on, complete access (SOEM then
//! reads 1C12h/1C13h and the mapping objects by complete access). The
//! bootstrap mailbox (BOOT) may have other SM sizes:
//! [`MailboxServer::set_mailbox_sizes`].
//!
//! ethercrab 0.7.1 cannot decode an upload segment response (its
//! `CoeCommand` has no command specifier 0) and keeps `length − 8` bytes of
//! every OD-list fragment, one index short after the first fragment. Both
//! are avoided by an SM1 of at least 16 bytes more than the largest value
//! and 14 + 2 × (number of objects) bytes: 394 for the iPOS twin's 190
//! objects. SOEM and TwinCAT take every size.
//!
//! # EoE
//!
//! EoE (and AoE, SoE, VoE) is answered with the mailbox error
//! "unsupported protocol". The iPOS keeps its EoE settings in 210Dh/210Eh,
//! reachable by SDO; a Set IP Parameter service alone would let a master
//! believe it can tunnel Ethernet frames, which this slave cannot, so the
//! SII should not announce EoE.

#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod access;
pub mod coe;
pub mod foe;
pub mod mailbox;
mod server;

pub use access::{ObjectAccess, OdAccess, access_bits, default_object_access};
pub use coe::emergency::{Emergency, EmergencyQueueFull};
/// The EtherCAT state the ESC layer passes in: the slave controller's one
/// state type.
pub use drivebus_esc::slave::AlState;
pub use foe::{FileHandler, FoeEnd, FoeError, FoeProgress, NoFiles};
pub use mailbox::{MailboxErrorCode, MailboxHeader, MailboxType};
pub use server::{MailboxConfig, MailboxServer, MailboxSizeError, MailboxStats};
