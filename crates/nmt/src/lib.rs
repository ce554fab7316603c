//! NMT slave, heartbeat producer/consumer, node and life guarding, error
//! behaviour (CiA 301 §7.2.8, §7.3.2), sans-IO.
//!
//! [`Nmt`] is the whole service for one device. The node feeds it frames
//! ([`Nmt::handle_frame`]) and time ([`Nmt::poll`]), answers its events
//! ([`NmtEvent`]) and routes writes to 1016h, 1017h, 100Ch, 100Dh and 1029h
//! through [`Nmt::check_write`] and [`Nmt::reconfigure`].
//!
//! # CiA 301 decisions
//!
//! - **Command frames** (§7.2.8.3.1): `000h`, exactly 2 bytes `[cs,
//!   node-ID]`; node-ID 0 is a broadcast. Any other DLC, an RTR, an
//!   unknown cs or a cs the personality does not implement
//!   ([`NmtConfig::supported_commands`]) is ignored silently: NMT is
//!   unconfirmed, there is nothing to answer with. Commands are ignored in
//!   Initialisation. A command to the current state changes nothing and
//!   reports nothing.
//! - **Resets** (§7.3.2.2.1): reset node and reset communication return
//!   [`NmtEvent::ResetApplication`] / [`NmtEvent::ResetCommunication`]; the
//!   node restores the dictionary and calls [`Nmt::boot`], which sends the
//!   boot-up message (`700h + node-ID, [00]`) and enters Pre-operational
//!   (Operational with [`NmtConfig::auto_start`]). The guarding toggle
//!   restarts at 0. A node-ID outside 1..=127 keeps the device in
//!   Initialisation (CiA 305 unconfigured device).
//! - **Services per state** (§7.3.2.4): see [`NmtState::allows`]; LSS is
//!   allowed in every state (CiA 305 runs beside NMT).
//! - **Heartbeat producer** (§7.2.8.3.2.2, 1017h): the first heartbeat is
//!   one period after the boot-up message or after a 1017h write; a write
//!   (even of the same value) restarts the timer; no extra heartbeat on a
//!   state change.
//! - **Heartbeat consumer** (1016h, §7.5.2.26): monitoring of a node starts
//!   with its first heartbeat; a boot-up message from it restarts that wait.
//!   Time 0, node-ID 0 or > 127 = unused. Two used entries with the same
//!   node-ID → `0604 0043`; reserved bits 24..31 set → `0609 0030`.
//!   Heartbeats must have DLC 1; bit 7 is ignored.
//! - **Node guarding** (§7.2.8.3.2.1): a remote frame of any DLC on `700h +
//!   node-ID` is answered. CiA 301 has a device use heartbeat *or*
//!   guarding: while 1017h ≠ 0 (and heartbeat is implemented) requests are
//!   not answered and life guarding is off. Life guarding starts with the
//!   first request and needs 100Ch × 100Dh ≠ 0.
//! - **Error behaviour** (1029h, §7.5.2.32): 0 pre-operational (only from
//!   Operational), 1 no change, 2 stopped; 3..=127 reserved (refused with
//!   `0609 0030`), 128..=255 manufacturer-specific (no NMT change, the node
//!   reacts). Without 1029h the default 0 applies unless the personality
//!   sets another value ([`Nmt::set_error_behaviour`]).
//!
//! Modules: `state` (states, commands, the state/service table), `producer`
//! (heartbeat producer), `consumer` (heartbeat consumer), `guarding` (node
//! and life guarding), `error_behaviour` (1029h), `config` (personality
//! switches and object installation), `nmt` (the state machine tying them).
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod config;
mod consumer;
mod error_behaviour;
mod events;
mod guarding;
mod nmt;
mod producer;
mod state;

pub use config::{
    CONSUMER_HEARTBEAT_TIME, ERROR_BEHAVIOUR, ERROR_CONTROL_BASE, GUARD_TIME, LIFE_TIME_FACTOR,
    MAX_CONSUMER_ENTRIES, NMT_COB_ID, NmtConfig, PRODUCER_HEARTBEAT_TIME, install, install_error_behaviour,
};
pub use consumer::ConsumerEntry;
pub use error_behaviour::{ErrorAction, ErrorClass};
pub use events::{EVENT_QUEUE_LEN, NmtEvent};
pub use nmt::Nmt;
pub use producer::HeartbeatProducer;
pub use state::{CommandSet, InitSubState, NmtCommand, NmtState, RemoteState, Service};
