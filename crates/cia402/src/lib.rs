//! CiA 402 drive building blocks for virtual drives: the device control
//! state machine ([`state_machine`], CiA 402-2 §6.2 / IEC 61800-7-201), a
//! physical motor and axis model ([`model`]) stepped at the drive's control
//! rate, the drive itself ([`drive`]: object dictionary binding, device
//! control, pp/pv/vl/tq, factor group, I/O, touch probe, faults) and the
//! plug-in modes: homing ([`homing`]) and ip/csp/csv/cst ([`interp`]). All
//! of it is pure, deterministic logic (no clocks, no I/O, no allocation per
//! step).
//!
//! [`codes`] holds the CiA 402 tables a drive and a master share (states
//! and their statusword coding, controlword commands, modes and their
//! names). Without the default `drive` feature the crate is only those
//! tables and the state machine: what a master depends on.
//!
//! # A generic drive on the bus
//!
//! (With the `drive` feature.) [`drive::generic_drive`] is a complete CiA 402 servo (CiA 301 node,
//! pre-defined PDO set, pp/vl/pv/tq); [`drive::generic_drive_with`] adds a
//! configuration and mode handlers:
//!
//! ```
//! use drivebus_bus::{Bus, BusConfig};
//! use drivebus_can::Duration;
//! use drivebus_cia402::drive::{Drive, DriveConfig, ModeHandler, generic_drive_with};
//! use drivebus_cia402::homing::HomingMode;
//! use drivebus_cia402::interp::{CspMode, CstMode, CsvMode, IpMode};
//!
//! let handlers: Vec<Box<dyn ModeHandler + Send>> = vec![
//!     Box::new(HomingMode::default()), // hm, every standard method (60E3h)
//!     Box::new(IpMode::new(16)),       // ip, 16-record buffer (60C4h:1)
//!     Box::new(CspMode::new()),
//!     Box::new(CsvMode::new()),
//!     Box::new(CstMode::new()),
//! ];
//! let mut bus = Bus::new(BusConfig::zero_time());
//! let id = bus.attach(generic_drive_with(3, DriveConfig::default(), handlers));
//! bus.run_for(Duration::from_millis(1)); // boot-up, pre-operational
//! let dn = bus.node::<drivebus_node::NodeDevice<Drive>>(id).unwrap();
//! assert_eq!(dn.app.supported_modes(), 0x3EF); // 6502h: pp vl pv tq hm ip csp csv cst
//! assert_eq!(dn.app.statusword() & 0x4F, 0x40); // switch on disabled
//! ```
//!
//! A master then drives it over the bus as any CiA 402 device: NMT start,
//! controlword 6040h 06h/07h/0Fh, 6060h the mode, targets by SDO or RPDO,
//! SYNC for the cyclic modes. On any other host (a real bus, an embedded
//! main loop) the same `drivebus_node::NodeDevice<Drive>` is the device: it
//! implements `drivebus_can::Device`; or install a [`drive::Drive`] on your
//! own `drivebus_node::Node` ([`drive::Drive::install_with`]) and pass it as
//! the node's application.
//!
//! Personalities wrap the drive in their own `drivebus_node::Application`
//! (manufacturer statusword bits, write vetoes by drive state, e.g. no
//! 1010h store while enabled) and call the drive's parts
//! ([`drive::Drive::check_object`], [`drive::Drive::sync`], …).
//!
//! # The mode handler contract
//!
//! pp, pv, vl and tq run inside the drive; hm, ip, csp, csv and cst are
//! [`drive::ModeHandler`]s (see [`drive::mode`] for the full contract):
//!
//! - once per control period while *Operation enabled* in its mode the
//!   handler gets a [`drive::ModeIo`] snapshot and returns a
//!   [`drive::ModeOutput`]: the set-point, statusword bits 10–13 (the mode's
//!   alone: the drive adds none of its own, CiA 402-2 §6.2.2), bit 7
//!   `warning`, an `emcy` code to raise, a `fault`, a `position_reset`
//!   (homing) and a `torque_offset` feed-forward;
//! - `on_sync` latches cyclic set-points at SYNC; `enter`/`exit` bracket
//!   the mode;
//! - `owns_following_error` decides who supervises 6065h/6066h in the mode
//!   (one owner: the drive by default, [`interp::CspMode`] in csp);
//! - `write_object` / `read_object` own mode objects (60C0h, 60C1h, 60C4h,
//!   6098h) with their SDO aborts; `homing_methods` fills 60E3h;
//! - event positions: raw encoder counts + [`drive::ModeIo::inc_offset`] =
//!   6063h, so handlers never track the reference shifts.
//!
//! # How the drive uses the state machine and the model
//!
//! Once per control period (4–16 kHz):
//!
//! 1. Feed new controlwords (6040h) to [`state_machine::StateMachine::controlword`];
//!    on `Outcome::fault_reset` call [`model::DriveModel::clear_faults`].
//! 2. Read [`state_machine::StateMachine::drive_function`]:
//!    `Disabled` → [`model::Demand::Off`]; `Enabled` → the operating mode's
//!    set-point (CSP: `Demand::Position` with velocity/acceleration
//!    feed-forward; CSV/PV: `Demand::Velocity`; CST/TQ: `Demand::Torque`);
//!    `Stopping(reaction)` → execute the ramp (slow-down 6084h, quick stop
//!    6085h: a velocity or position ramp; current limit: velocity 0 and let
//!    the loop saturate; voltage limit: [`model::Demand::ShortCircuit`]);
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
//! use drivebus_cia402::model::{Demand, DriveModel, DriveParams};
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
//!         DriveFunction::Enabled => Demand::Position {
//!             position: 0.001 * k as f64,
//!             velocity: 0.001 / dt,
//!             acceleration: 0.0,
//!         },
//!         _ => Demand::Off,
//!     };
//!     motor.set_demand(cmd);
//!     motor.step(dt);
//!     if let Some(code) = motor.faults().error_code() {
//!         sm.fault(code);
//!     }
//! }
//! assert_eq!(sm.statusword() & 0x6F, 0x27); // operation enabled
//! assert!((motor.position() - 0.8).abs() < 0.01);
//! ```
#![cfg_attr(not(feature = "std"), no_std)]

#[cfg(feature = "drive")]
extern crate alloc;

pub mod codes;
#[cfg(feature = "drive")]
pub mod drive;
#[cfg(feature = "drive")]
pub mod homing;
#[cfg(feature = "drive")]
pub mod interp;
#[cfg(feature = "drive")]
pub mod model;
pub mod state_machine;
