//! CAN frames, identifiers, caller-supplied time and the transmit sink.
//!
//! This crate is the vocabulary every sans-IO layer of drivebus speaks: a
//! protocol machine takes a [`Frame`] and an [`Instant`] and emits frames into
//! a [`TxSink`]. Nothing here reads a clock or touches I/O. [`Device`] is
//! the contract every host (virtual bus, real-time loop, test) drives.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

pub mod cob;
mod device;
pub mod fault;
mod frame;
mod identity;
#[cfg(feature = "pcap")]
pub mod pcap;
mod time;
pub mod timing;

pub use device::{Device, LinkState};
pub use fault::{FaultAction, FaultRule, Recurrence, XorShift64};
pub use frame::{CanId, Frame, FrameError, MAX_DATA_LEN};
pub use identity::Identity;
pub use time::Instant;

pub use core::time::Duration;

/// Where a protocol machine puts the frames it wants sent.
///
/// Protocol machines take it generically (`&mut impl TxSink`) so the hot
/// paths monomorphise and inline; the [`Device`] contract passes
/// `&mut dyn TxSink` (hand it on as `&mut out`).
pub trait TxSink {
    /// Queue one frame for transmission.
    fn send(&mut self, frame: Frame);
}

impl TxSink for alloc::vec::Vec<Frame> {
    #[inline]
    fn send(&mut self, frame: Frame) {
        self.push(frame);
    }
}

impl<F: FnMut(Frame)> TxSink for F {
    #[inline]
    fn send(&mut self, frame: Frame) {
        self(frame)
    }
}

/// Earliest of two optional deadlines (`None` means "no deadline").
#[inline]
pub fn earliest(a: Option<Instant>, b: Option<Instant>) -> Option<Instant> {
    match (a, b) {
        (Some(x), Some(y)) => Some(if x <= y { x } else { y }),
        (x, None) => x,
        (None, y) => y,
    }
}
