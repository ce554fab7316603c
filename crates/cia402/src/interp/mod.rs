//! Interpolated position (ip) and cyclic synchronous (csp, csv, cst)
//! set-point handling.
//!
//! - [`ip`]: the ip mode engine with its data buffer (60C0h–60C4h).
//! - [`cyclic`]: the csp/csv/cst engine: SYNC-latched targets, linear
//!   interpolation at the control rate, offsets 60B0h–60B2h, following error
//!   supervision (6065h, 6066h, 60F4h, fault 8611h).
//!
//! Both work in position units and are driven by the drive through the
//! `ModeHandler` adapters ([`IpMode`], [`CspMode`], [`CsvMode`], [`CstMode`])
//! or directly on a [`crate::model::DriveModel`] (see the tests).

mod adapter;
pub mod cyclic;
pub mod ip;

pub use adapter::{CspMode, CstMode, CsvMode, IpMode, IpMonitor};
pub use cyclic::{
    Cyclic, CyclicConfig, CyclicKind, CyclicOutput, FollowingWatch, Interpolator, SetPointSample,
};
pub use ip::{Ip, IpBuffer, IpBufferError, IpConfig, IpOutput, IpRecord, Organisation, SubMode};
