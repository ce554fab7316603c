//! What every bus layer of drivebus shares and no bus owns: caller-supplied
//! time ([`Instant`], [`Duration`], [`earliest`]), the device identity
//! (CiA 301 1018h, which is also the CiA 305 LSS address and the EtherCAT
//! SII/ESI identity) and the counting half of fault injection
//! ([`Recurrence`], [`XorShift64`]).
//!
//! The lowest crate: the CAN vocabulary (`drivebus-can`) and the EtherCAT
//! slave controller (`drivebus-esc`) both build on it, so neither bus
//! depends on the other. Nothing here reads a clock or touches I/O.
#![cfg_attr(not(feature = "std"), no_std)]

mod identity;
mod recurrence;
mod time;

pub use core::time::Duration;
pub use identity::Identity;
pub use recurrence::{Recurrence, XorShift64};
pub use time::Instant;

/// Earliest of two optional deadlines (`None` means "no deadline").
#[inline]
pub fn earliest(a: Option<Instant>, b: Option<Instant>) -> Option<Instant> {
    match (a, b) {
        (Some(x), Some(y)) => Some(if x <= y { x } else { y }),
        (x, None) => x,
        (None, y) => y,
    }
}
