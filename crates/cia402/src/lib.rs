//! CiA 402 drive building blocks for virtual drives: the device control
//! state machine ([`state_machine`], CiA 402-2 §6.2 / IEC 61800-7-201) and a
//! physical motor and axis model ([`model`]) stepped at the drive's control
//! rate. Both are pure, deterministic logic (no clocks, no I/O, no
//! allocation per step); the operating modes and the object dictionary
//! binding sit on top.
//!
//! # How the mode layer drives them
//!
//! Once per control period (4–16 kHz):
//!
//! 1. Feed new controlwords (6040h) to [`state_machine::StateMachine::controlword`];
//!    on `Outcome::fault_reset` call [`model::DriveModel::clear_faults`].
//! 2. Read [`state_machine::StateMachine::drive_function`]:
//!    `Disabled` → [`model::Command::Off`]; `Enabled` → the operating mode's
//!    set-point (CSP: `Command::Position` with velocity/acceleration
//!    feed-forward; CSV/PV: `Command::Velocity`; CST/TQ: `Command::Torque`);
//!    `Stopping(reaction)` → execute the ramp (slow-down 6084h, quick stop
//!    6085h: a velocity or position ramp; current limit: velocity 0 and let
//!    the loop saturate; voltage limit: [`model::Command::ShortCircuit`]);
//!    `Holding` → hold position / velocity 0.
//! 3. [`model::DriveModel::step`] and use its events (index pulse, switch
//!    edges with interpolated positions for homing and touch probe, end
//!    stops, stall).
//! 4. Report [`model::Faults::error_code`] with
//!    [`state_machine::StateMachine::fault`], and when a stopping ramp has
//!    brought the axis to rest call
//!    [`state_machine::StateMachine::motion_stopped`].
//! 5. Statusword 6041h = `sm.statusword()` (bits 0–6) | the mode's bits.
//!
//! ```
//! use drivebus_cia402::model::{Command, DriveModel, DriveParams};
//! use drivebus_cia402::state_machine::{DriveFunction, Options, StateMachine};
//!
//! let mut sm = StateMachine::new(Options::default());
//! let mut motor = DriveModel::new(DriveParams::servo_small()).unwrap();
//! let dt = motor.params().control_period();
//! sm.self_test_passed();
//! sm.controlword(0x06);
//! sm.controlword(0x0F);
//! for k in 0..800 {
//!     let cmd = match sm.drive_function() {
//!         DriveFunction::Enabled => Command::Position {
//!             position: 0.001 * k as f64,
//!             velocity: 0.001 / dt,
//!             acceleration: 0.0,
//!         },
//!         _ => Command::Off,
//!     };
//!     motor.set_command(cmd);
//!     motor.step(dt);
//!     if let Some(code) = motor.faults().error_code() {
//!         sm.fault(code);
//!     }
//! }
//! assert_eq!(sm.statusword() & 0x6F, 0x27); // operation enabled
//! assert!((motor.position() - 0.8).abs() < 0.01);
//! ```
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

pub mod drive;
pub mod homing;
pub mod interp;
pub mod model;
pub mod state_machine;
