//! What a virtual drive is built from.

use super::mode::op;
use super::units::FactorGroup;
use crate::model::DriveParams;
use crate::state_machine::Options;

/// What happens when a limit switch (60FDh bit 0/1) becomes active in the
/// direction of motion (CiA 402-2 §6.2 leaves the reaction to the device).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LimitSwitchReaction {
    /// Stop on the quick-stop ramp, refuse motion towards the switch, set
    /// statusword bit 11 (internal limit active) and bit 7 (warning).
    #[default]
    StopAndWarn,
    /// Fault 8612h (reference limit), executed per 605Eh.
    Fault,
}

/// When pp and pv report statusword bit 10 "target reached" (CiA 402-2
/// words it on the actual value alone; drives differ in whether the
/// profile generator must have finished too).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TargetReached {
    /// The profile has finished (pp trajectory done, pv ramp at the target)
    /// and the actual value is within 6067h / 606Dh for 6068h / 606Eh. A
    /// buffered pp set-point starts when the running trajectory ends.
    #[default]
    ProfileDone,
    /// The actual value within the window for the window time is enough,
    /// even while the profile still runs; a buffered pp set-point starts as
    /// soon as the running one is reached this way (LAM DDS6 traces).
    ActualInWindow,
}

/// Digital I/O layout (60FDh / 60FEh).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IoConfig {
    /// How limit switches act.
    pub limit_switch: LimitSwitchReaction,
    /// 60FDh bit 3 interlock input is present (when set and active the
    /// drive function is not enabled).
    pub interlock: bool,
    /// 60FEh:2 bit mask default: which physical outputs the master may set.
    pub output_mask: u32,
}

impl Default for IoConfig {
    fn default() -> Self {
        IoConfig {
            limit_switch: LimitSwitchReaction::StopAndWarn,
            interlock: false,
            output_mask: 0xFFFF_0000,
        }
    }
}

/// Power-on values of the profile parameters, in OD units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProfileDefaults {
    /// 607Fh max profile velocity \[velocity units\].
    pub max_profile_velocity: u32,
    /// 6081h profile velocity.
    pub profile_velocity: u32,
    /// 6083h profile acceleration \[acceleration units\].
    pub profile_acceleration: u32,
    /// 6084h profile deceleration.
    pub profile_deceleration: u32,
    /// 6085h quick stop deceleration.
    pub quick_stop_deceleration: u32,
    /// 60C5h / 60C6h max acceleration / deceleration.
    pub max_acceleration: u32,
    /// 6065h following error window \[position units\].
    pub following_error_window: u32,
    /// 6066h following error time out \[ms\].
    pub following_error_timeout: u16,
    /// 6067h position window \[position units\].
    pub position_window: u32,
    /// 6068h position window time \[ms\].
    pub position_window_time: u16,
    /// 606Dh velocity window \[velocity units\].
    pub velocity_window: u16,
    /// 606Eh velocity window time \[ms\].
    pub velocity_window_time: u16,
    /// 606Fh velocity threshold \[velocity units\].
    pub velocity_threshold: u16,
    /// 6070h velocity threshold time \[ms\].
    pub velocity_threshold_time: u16,
    /// 6087h torque slope \[per mille of rated torque per second\].
    pub torque_slope: u32,
}

/// Everything fixed when a drive is built.
#[derive(Debug, Clone, PartialEq)]
pub struct DriveConfig {
    /// Motor, power stage, axis and inner loops.
    pub params: DriveParams,
    /// Control (and simulation) rate \[Hz\], 4000..=16000; overrides
    /// `params.control.control_rate_hz`.
    pub control_rate_hz: f64,
    /// 6502h bits of the modes the drive itself runs (pp, vl, pv, tq; see
    /// [`op::supported_bit`]); registered mode handlers add theirs.
    pub modes: u32,
    /// Factor group power-on values (608Fh:1 is forced to the encoder).
    pub factor: FactorGroup,
    /// 60A8h–60ABh SI unit codes (position, velocity, acceleration, jerk).
    pub si_units: [u32; 4],
    /// Profile defaults.
    pub profile: ProfileDefaults,
    /// Option codes 605Ah–605Eh, 6007h power-on values.
    pub options: Options,
    /// I/O layout.
    pub io: IoConfig,
    /// Statusword bit 9 "remote": the drive follows the controlword
    /// (CiA 402-2 §6.2.2). Personalities without local control keep `true`.
    pub remote: bool,
    /// Fault 8700h when SYNC stops while a cyclic mode (ip, csp, csv, cst) runs.
    pub sync_loss_fault: bool,
    /// How statusword bit 10 "target reached" is judged in pp and pv.
    pub target_reached: TargetReached,
    /// Initial mode of operation (6060h).
    pub initial_mode: i8,
    /// The personality hook: statusword bits 8/9/14/15 and write vetoes by
    /// drive state (see [`DriveExtension`](super::DriveExtension)). None by
    /// default.
    pub extension: super::Extension,
}

impl DriveConfig {
    /// A fully featured servo drive on `params`: pp, vl, pv, tq; position
    /// units of 0.001° of the motor shaft (a non-integer increments ratio,
    /// 2^20 / 360000 for the default encoder), velocity units of position
    /// units/s, defaults sized from the motor.
    pub fn servo(params: DriveParams) -> DriveConfig {
        let cpr = params.encoder.counts_per_rev;
        let factor = FactorGroup { feed: (360_000, 1), ..FactorGroup::increments(cpr) };
        // Motor limit in position units/s (milli-degrees/s).
        let vmax = params.motor.max_speed / (2.0 * core::f64::consts::PI) * 360_000.0;
        let vmax = vmax.clamp(1.0, f64::from(u32::MAX / 2)) as u32;
        let profile = ProfileDefaults {
            max_profile_velocity: vmax,
            profile_velocity: vmax / 2,
            profile_acceleration: vmax.saturating_mul(10),
            profile_deceleration: vmax.saturating_mul(10),
            quick_stop_deceleration: vmax.saturating_mul(40),
            max_acceleration: u32::MAX,
            following_error_window: 36_000,
            following_error_timeout: 50,
            position_window: 100,
            position_window_time: 10,
            velocity_window: 20_000,
            velocity_window_time: 10,
            velocity_threshold: 20_000,
            velocity_threshold_time: 10,
            torque_slope: 10_000,
        };
        DriveConfig {
            params,
            control_rate_hz: params.control.control_rate_hz,
            modes: op::supported_bit(op::PP)
                | op::supported_bit(op::VL)
                | op::supported_bit(op::PV)
                | op::supported_bit(op::TQ),
            factor,
            // SI codes (CiA 402-2 / ETG.1004 style): milli-degree, per second.
            si_units: [0xFD41_0000, 0xFD41_0300, 0xFD41_0357, 0],
            profile,
            options: Options::default(),
            io: IoConfig::default(),
            remote: true,
            sync_loss_fault: true,
            target_reached: TargetReached::ProfileDone,
            initial_mode: op::PP,
            extension: super::Extension::none(),
        }
    }
}

impl Default for DriveConfig {
    /// [`DriveConfig::servo`] on [`DriveParams::servo_small`].
    fn default() -> Self {
        DriveConfig::servo(DriveParams::servo_small())
    }
}
