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

/// Objects whose value 0 switches their supervision or limit off, as some
/// manuals define (CiA 402-2 itself uses FFFFFFFFh for 6065h "off"). The
/// dictionary keeps the 0 the master wrote; the drive works with
/// `u32::MAX` (no window, no limit) while the object is 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ZeroMeansOff {
    /// 6065h following error window 0 = following error monitoring off
    /// (Kollmorgen KC1 §7.8.2.3, AKD §6.8.2.3).
    pub following_error_window: bool,
    /// 6080h max motor speed 0 = no speed limit (Technosoft iPOS §15.2.3:
    /// "the speed limitation is activated when setting a value different
    /// from zero").
    pub max_motor_speed: bool,
}

impl ZeroMeansOff {
    /// The value the drive works with for a written `v`.
    pub(crate) fn effective(on: bool, v: u32) -> u32 {
        if on && v == 0 { u32::MAX } else { v }
    }
}

/// What a profile acceleration, deceleration or homing acceleration
/// (6083h, 6084h, 609Ah) of 0 means. A zero ramp the drive works with
/// refuses motion: pp does not acknowledge the set-point, pv holds velocity
/// 0 (reached on the quick-stop ramp), hm reports a homing error (bit 13);
/// a halt with 6084h = 0 uses 6085h. Likewise a torque slope 6087h of 0
/// holds the tq torque demand at 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ZeroRamp {
    /// Writes of 0 are refused (0609 0032): a ramp must be positive.
    #[default]
    Refused,
    /// Writes of 0 are taken (a manual's value range from 0); the drive
    /// then refuses motion as above.
    RefusesMotion,
    /// Writes of 0 are taken and select the drive's own ramp, in the
    /// objects' units (Kollmorgen: 6083h/6084h are DRV.ACC/DRV.DEC in pv
    /// and MT.ACC/MT.DEC otherwise, 609Ah HOME.ACC; the manuals' examples
    /// jog and home at the default 0).
    DriveRamp {
        /// Used for 6083h = 0.
        acceleration: u32,
        /// Used for 6084h = 0.
        deceleration: u32,
        /// Used for 609Ah = 0.
        homing: u32,
    },
}

impl ZeroRamp {
    /// The value the drive works with for a written ramp `v` of `index`.
    pub(crate) fn effective(self, index: u16, v: u32) -> u32 {
        match self {
            ZeroRamp::DriveRamp { acceleration, deceleration, homing } if v == 0 => match index {
                0x6083 => acceleration,
                0x6084 => deceleration,
                0x609A => homing,
                _ => v,
            },
            _ => v,
        }
    }
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
    /// 60FEh:1 keeps the command as written and the mask (sub 2) only
    /// selects which bits reach the outputs, re-applied when the mask is
    /// written (Technosoft iPOS §4.5.3: "outputs change when this
    /// sub-index is written"). `false`: sub 1 stores the masked value.
    pub keep_unmasked_command: bool,
}

impl Default for IoConfig {
    fn default() -> Self {
        IoConfig {
            limit_switch: LimitSwitchReaction::StopAndWarn,
            interlock: false,
            output_mask: 0xFFFF_0000,
            keep_unmasked_command: false,
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
    /// The units stay at `factor` whatever 6091h/6092h/6096h/6097h hold:
    /// those objects are stored set-up parameters (Technosoft iPOS §5.2.2:
    /// the conversion is the position factor 6093h, which the set-up tool
    /// computes from them; their defaults 1/1 describe internal units).
    pub fixed_factor_group: bool,
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
    /// Objects whose 0 means "off" on this drive (none by default).
    pub zero_means_off: ZeroMeansOff,
    /// What 6083h / 6084h / 609Ah = 0 means.
    pub zero_ramp: ZeroRamp,
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
            fixed_factor_group: false,
            // SI codes (CiA 402-2 / ETG.1004 style): milli-degree, per second.
            si_units: [0xFD41_0000, 0xFD41_0300, 0xFD41_0357, 0],
            profile,
            options: Options::default(),
            io: IoConfig::default(),
            remote: true,
            sync_loss_fault: true,
            target_reached: TargetReached::ProfileDone,
            initial_mode: op::PP,
            zero_means_off: ZeroMeansOff::default(),
            zero_ramp: ZeroRamp::Refused,
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
