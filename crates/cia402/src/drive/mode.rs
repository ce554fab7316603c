//! The plug-in interface for operating modes the drive does not implement
//! itself: homing (hm), interpolated position (ip) and the cyclic
//! synchronous modes (csp, csv, cst).
//!
//! Once per control period, while the drive function is enabled
//! (CiA 402-2 §6.2: state *Operation enabled*, no stop in progress) and
//! 6061h names a mode a registered [`ModeHandler`] claims, the drive builds a
//! [`ModeIo`] snapshot (actual values, the model's step events, controlword,
//! the mode parameters from the object dictionary) and calls
//! [`ModeHandler::step`]. The returned [`ModeOutput`] is the set-point for the
//! motor model plus the mode-specific statusword bits. SYNC reception calls
//! [`ModeHandler::on_sync`] so cyclic modes can latch their set-points
//! (CiA 402-4 "cyclic synchronous" modes take the target at SYNC).
//!
//! All positions are in *position units* (the user units after the factor
//! group 608Fh–6092h and polarity 607Eh), velocities in position units per
//! second, accelerations in position units per second² — except the raw OD
//! values in [`ModeParams`] which keep their CiA 402 units (velocity units,
//! acceleration units); convert those with [`Units`].
//!
//! The trait is object safe; the drive stores `Box<dyn ModeHandler + Send>`.
//!
//! # The handler contract
//!
//! - **Statusword.** Bits 10–13 of the statusword belong to the active
//!   mode (CiA 402-2 §6.2.2: bits 12 and 13 are mode-specific). In a
//!   handler's mode the drive shows exactly [`ModeOutput::status`] there
//!   (bit 11 additionally while a limit switch is active); it never ORs in
//!   bits of its own. Bit 7 (warning) is [`ModeOutput::warning`], ORed with
//!   the drive's warnings (limit switch, SYNC loss).
//! - **EMCY.** [`ModeOutput::emcy`] raises a code once (EMCY + 1003h); the
//!   drive clears it (EMCY error reset) when the handler's `warning` drops
//!   or the mode is left. [`ModeOutput::fault`] is a fault (603Fh,
//!   transition 13).
//! - **Following error.** Exactly one party supervises 6065h/6066h per
//!   mode: the drive, unless [`ModeHandler::owns_following_error`] says the
//!   handler does (csp: [`CspMode`](crate::interp::CspMode) reports bit 13
//!   and 8611h itself).
//! - **Objects.** The drive forwards writes of the mode objects a handler
//!   may own (60C0h, 60C1h:1–3, 60C4h:2–6, 6098h) to
//!   [`ModeHandler::write_object`] of every handler, and refreshes 60C4h
//!   from [`ModeHandler::read_object`] before an SDO upload. 60E3h is built
//!   from [`ModeHandler::homing_methods`].
//! - **Positions.** Event positions from the model are raw encoder counts;
//!   add [`ModeIo::inc_offset`] to get 6063h increments (or use
//!   [`ModeIo::event_position`]), so a handler never tracks the drive's
//!   reference shifts itself.

use super::units::Units;
use crate::model::{StepEvents, Switches};
use alloc::vec::Vec;
use drivebus_od::SdoAbort;

/// Modes of operation codes (6060h / 6061h, CiA 402-2 §6.3.2): the table
/// of [`crate::codes::mode`].
pub use crate::codes::mode as op;

/// Object-dictionary parameters a mode handler may need, in their raw
/// CiA 402 units, refreshed by the drive whenever one of them is written.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ModeParams {
    /// 607Ah target position \[position units\] (csp target, ip fallback).
    pub target_position: i32,
    /// 60FFh target velocity \[velocity units\] (csv target).
    pub target_velocity: i32,
    /// 6071h target torque \[per mille of rated torque\] (cst target).
    pub target_torque: i16,
    /// 60B0h position offset \[position units\] (csp).
    pub position_offset: i32,
    /// 60B1h velocity offset \[velocity units\] (csp/csv feed-forward).
    pub velocity_offset: i32,
    /// 60B2h torque offset \[per mille\] (csp/csv/cst feed-forward).
    pub torque_offset: i16,
    /// 6098h homing method.
    pub homing_method: i8,
    /// 6099h:1 speed during search for switch \[velocity units\].
    pub homing_speed_switch: u32,
    /// 6099h:2 speed during search for zero \[velocity units\].
    pub homing_speed_zero: u32,
    /// 609Ah homing acceleration \[acceleration units\].
    pub homing_acceleration: u32,
    /// 607Ch home offset \[position units\].
    pub home_offset: i32,
    /// 60C0h interpolation sub mode select.
    pub interpolation_sub_mode: i16,
    /// 60C1h:1 interpolation data record, first value (ip position set-point).
    pub interpolation_data: i32,
    /// 60C2h:1 interpolation time period value.
    pub interpolation_period_value: u8,
    /// 60C2h:2 interpolation time index (period = value · 10^index s).
    pub interpolation_period_index: i8,
    /// 6065h following error window \[position units\]; `u32::MAX` = off.
    pub following_error_window: u32,
    /// 6066h following error time out \[ms\].
    pub following_error_timeout: u16,
    /// 6067h position window \[position units\]; `u32::MAX` = off.
    pub position_window: u32,
    /// 6068h position window time \[ms\].
    pub position_window_time: u16,
    /// 607Fh max profile velocity \[velocity units\].
    pub max_profile_velocity: u32,
    /// 6080h max motor speed \[velocity units\].
    pub max_motor_speed: u32,
    /// 6083h profile acceleration \[acceleration units\].
    pub profile_acceleration: u32,
    /// 6084h profile deceleration \[acceleration units\].
    pub profile_deceleration: u32,
    /// 6085h quick stop deceleration \[acceleration units\].
    pub quick_stop_deceleration: u32,
    /// 60C5h max acceleration \[acceleration units\].
    pub max_acceleration: u32,
    /// 60C6h max deceleration \[acceleration units\].
    pub max_deceleration: u32,
    /// 607Dh:1/2 software position limits \[position units\] (min, max);
    /// both 0 = off (CiA 402-2 §6.6.x).
    pub software_limits: (i32, i32),
    /// 607Bh:1/2 position range limits \[position units\] (min, max);
    /// positions wrap between them on modulo axes; both 0 = off.
    pub position_range: (i32, i32),
    /// 6072h max torque \[per mille\].
    pub max_torque: u16,
    /// Homing returns to the home position after the reference is taken
    /// ([`DriveConfig::homing_return_to_home`](super::DriveConfig::homing_return_to_home)).
    pub homing_return_to_home: bool,
    /// Homing takes its reference without resetting the position (set by
    /// [`Drive::set_homing_keeps_position`](super::Drive::set_homing_keeps_position)).
    pub homing_keeps_position: bool,
}

impl ModeParams {
    /// 60C2h as seconds (`value · 10^index`); `None` for a zero or absurd period.
    pub fn interpolation_period_s(&self) -> Option<f64> {
        // Asked every control period (the KC1 family's PLL): a table, not `pow`.
        const TEN_TO_MINUS: [f64; 7] = [1.0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6];
        let v = f64::from(self.interpolation_period_value);
        let i = self.interpolation_period_index;
        if v == 0.0 || !(-6..=0).contains(&i) {
            return None;
        }
        Some(v * TEN_TO_MINUS[usize::from(i.unsigned_abs())])
    }
}

/// What the drive tells a mode handler each control period.
#[derive(Debug, Clone, Copy)]
pub struct ModeIo<'a> {
    /// Controlword 6040h as last received. Mode-specific bits: 4 (new
    /// set-point / homing start / ip enable), 5, 6, 8 (halt), 9.
    pub controlword: u16,
    /// Position actual value 6064h \[position units\], exact.
    pub position: i64,
    /// Position actual internal value 6063h \[increments\].
    pub position_inc: i64,
    /// 6063h minus the raw encoder counts \[increments\]: the shift of the
    /// position reference caused by every `position_reset` so far (homing).
    /// Model event `counts` + this = 6063h at the event.
    pub inc_offset: i64,
    /// Velocity actual \[position units/s\] (from the measured motor speed).
    pub velocity: f64,
    /// Torque actual \[per mille of rated torque\] (6077h).
    pub torque: f64,
    /// The position demand the drive last commanded \[position units\]
    /// (6062h); where a newly entered mode starts from without a jump.
    pub demand_position: f64,
    /// The velocity demand the drive last commanded \[position units/s\].
    pub demand_velocity: f64,
    /// The model's events of the last control period (index pulse, switch
    /// edges with exact positions in rad and encoder counts; convert with
    /// [`Units::inc_to_pos`] on `counts`).
    pub events: &'a StepEvents,
    /// Limit and home switch levels after the last period.
    pub switches: Switches,
    /// The machine's master encoder (pulse/direction) input \[counts\]
    /// that gearing and camming follow
    /// ([`crate::model::DriveModel::master_position`]).
    pub master_position: i64,
    /// Its speed \[counts/s\].
    pub master_velocity: f64,
    /// The mode parameters.
    pub params: &'a ModeParams,
    /// Factor group conversions.
    pub units: &'a Units,
    /// The control period \[s\].
    pub dt: f64,
    /// Time since the drive started \[s\] (simulated).
    pub time: f64,
}

impl ModeIo<'_> {
    /// Controlword bit `n`.
    pub fn cw_bit(&self, n: u8) -> bool {
        n < 16 && self.controlword & (1 << n) != 0
    }

    /// Where a model event happened in the actual-position frame
    /// \[position units\] (its exact encoder position shifted by
    /// [`ModeIo::inc_offset`]).
    pub fn event_position(&self, e: &crate::model::Event) -> f64 {
        let u = self.units;
        u.inc_to_pos_f(u.rad_to_inc(e.position) + self.inc_offset as f64)
    }
}

/// The set-point a mode produces, in position units (see module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ModeCommand {
    /// Follow `position` \[position units\] with velocity \[units/s\] and
    /// acceleration \[units/s²\] feed-forward (pp, hm, ip, csp).
    Position {
        /// Position demand.
        position: f64,
        /// Velocity feed-forward.
        velocity: f64,
        /// Acceleration feed-forward.
        acceleration: f64,
    },
    /// Velocity demand \[units/s\] with acceleration feed-forward (csv, hm).
    Velocity {
        /// Velocity demand.
        velocity: f64,
        /// Acceleration feed-forward.
        acceleration: f64,
    },
    /// Torque demand \[per mille of rated torque 6076h\] (cst).
    Torque(f64),
    /// Hold the present position demand (nothing to do, or halted).
    Hold,
}

impl Default for ModeCommand {
    /// [`ModeCommand::Hold`].
    fn default() -> Self {
        ModeCommand::Hold
    }
}

/// What a mode handler returns each control period. Build it with
/// [`ModeOutput::new`] or `ModeOutput { command, status, ..Default::default() }`
/// so fields added later keep their neutral defaults.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ModeOutput {
    /// The set-point for the motor.
    pub command: ModeCommand,
    /// Statusword bits 10 (target reached), 11 (internal limit active),
    /// 12 and 13 (mode-specific); other bits are ignored (mask
    /// [`ModeOutput::STATUS_MASK`]).
    pub status: u16,
    /// Set the actual position to this value \[position units\] (homing:
    /// the home position becomes the home offset, CiA 402-2 §6.7). The drive
    /// shifts its position reference; the motor does not move.
    pub position_reset: Option<i64>,
    /// Report a fault (603Fh / EMCY code, e.g. 8611h following error).
    pub fault: Option<u16>,
    /// Statusword bit 7 (warning) while set, e.g. ip buffer under/overflow.
    pub warning: bool,
    /// Raise this EMCY error code (once; repeated values are ignored while
    /// raised). The drive clears it when `warning` goes false or the mode
    /// is left (e.g. FF01h / FF02h ip buffer underflow / overflow).
    pub emcy: Option<u16>,
    /// Torque feed-forward \[per mille of rated torque 6076h\] added to a
    /// position or velocity command (csp/csv 60B2h); ignored otherwise.
    pub torque_offset: f64,
}

impl ModeOutput {
    /// Statusword bits a mode may set.
    pub const STATUS_MASK: u16 = 0x3C00;

    /// Hold position, no status bits.
    pub const fn hold() -> Self {
        ModeOutput::new(ModeCommand::Hold, 0)
    }

    /// A command with status bits.
    pub const fn new(command: ModeCommand, status: u16) -> Self {
        ModeOutput {
            command,
            status,
            position_reset: None,
            fault: None,
            warning: false,
            emcy: None,
            torque_offset: 0.0,
        }
    }
}

/// An operating mode implemented outside the drive (hm, ip, csp, csv, cst).
pub trait ModeHandler {
    /// The 6502h bits of the modes this handler implements (see
    /// [`op::supported_bit`]); the drive adds them to 6502h and accepts
    /// these codes in 6060h.
    fn supported_modes(&self) -> u32;

    /// The mode became active with the drive function enabled: on a 6060h
    /// change while enabled (CiA 402-2 §6.3: takes effect at once) or on
    /// entering *Operation enabled* with this mode selected. Start bumplessly
    /// from `io.demand_position` / `io.position`.
    fn enter(&mut self, mode: i8, io: &ModeIo<'_>);

    /// One control period of `dt` seconds in `mode`.
    fn step(&mut self, mode: i8, io: &ModeIo<'_>, dt: f64) -> ModeOutput;

    /// A SYNC was received (or produced) while `mode` is active and the
    /// synchronous RPDOs are applied: latch cyclic set-points from
    /// `io.params`.
    fn on_sync(&mut self, mode: i8, io: &ModeIo<'_>) {
        let _ = (mode, io);
    }

    /// The mode was left or the drive function disabled (stop, fault).
    fn exit(&mut self, mode: i8) {
        let _ = mode;
    }

    /// Whether this handler supervises the following error (6065h/6066h,
    /// bit 13, fault 8611h) in `mode` itself; then the drive does not (one
    /// owner per mode). Default: the drive supervises.
    fn owns_following_error(&self, mode: i8) -> bool {
        let _ = mode;
        false
    }

    /// A write of a mode object the drive forwards (60C0h, 60C1h:1–3,
    /// 60C4h:2–6, 6098h; see the module docs), already checked against the
    /// object's type and limits. `Ok(true)`: the handler owns the object and
    /// accepted the value (the dictionary stores it); `Ok(false)`: not its
    /// object; `Err`: the SDO abort (an RPDO write is dropped). Called
    /// whether or not the mode is active.
    fn write_object(&mut self, index: u16, sub: u8, data: &[u8], units: &Units) -> Result<bool, SdoAbort> {
        let _ = (index, sub, data, units);
        Ok(false)
    }

    /// The present value of an object the handler owns (60C4h subs), shown
    /// by an SDO upload; `None` keeps the dictionary's value.
    fn read_object(&self, index: u16, sub: u8) -> Option<i64> {
        let _ = (index, sub);
        None
    }

    /// 60E3h supported homing methods (in 60E3h sub order), for a handler
    /// implementing hm; `None` (the default) for other handlers.
    fn homing_methods(&self) -> Option<Vec<i8>> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::ModeParams;

    #[test]
    fn interpolation_period_is_value_times_ten_to_the_index() {
        let p = |value, index| ModeParams {
            interpolation_period_value: value,
            interpolation_period_index: index,
            ..ModeParams::default()
        };
        assert_eq!(p(1, 0).interpolation_period_s(), Some(1.0));
        assert_eq!(p(4, -3).interpolation_period_s(), Some(0.004));
        assert_eq!(p(250, -6).interpolation_period_s(), Some(0.000_25));
        assert_eq!(p(2, -1).interpolation_period_s(), Some(0.2));
        // What `pow` gave, to the last bit or two (the table's 1e-5 is the
        // nearer one), and the same whole nanoseconds.
        for index in -6..=0i8 {
            for value in 1..=255u8 {
                let want = f64::from(value) * libm::pow(10.0, f64::from(index));
                let got = p(value, index).interpolation_period_s().unwrap();
                assert!((got - want).abs() <= want * 4.0 * f64::EPSILON, "{value}·10^{index}: {got} {want}");
                assert_eq!((got * 1e9).round(), (want * 1e9).round(), "{value}·10^{index}");
            }
        }
        // Zero, and indices outside -6..=0: no period.
        assert_eq!(p(0, -3).interpolation_period_s(), None);
        assert_eq!(p(1, -7).interpolation_period_s(), None);
        assert_eq!(p(1, 1).interpolation_period_s(), None);
        assert_eq!(p(1, i8::MIN).interpolation_period_s(), None);
    }
}
