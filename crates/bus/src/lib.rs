//! Deterministic virtual CAN bus on simulated time: arbitration, bit timing, fault injection, candump log
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;
