//! CAN frames, identifiers, the transmit sink and the device contract, with
//! the base crate's caller-supplied time.
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
#[cfg(feature = "pcap")]
pub mod pcap;
pub mod timing;

pub use device::{Device, LinkState};
pub use fault::{FaultAction, FaultRule, Recurrence, XorShift64};
pub use frame::{CanId, Frame, FrameError, MAX_DATA_LEN};
// Time and identity are the base crate's (the EtherCAT side shares them).
pub use drivebus_base::{Duration, Identity, Instant, earliest};

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
