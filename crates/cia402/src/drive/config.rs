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
    /// 6073h max current 0 = no current limit besides 6072h (Kollmorgen
    /// KC1 §7.7.2.4 / AKD §6.7.2.4: power-on value 0 on a drive that moves
    /// in tq).
    pub max_current: bool,
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

/// The physical input behind a touch probe's "touch probe input"
/// (60B8h bits 3–2 = 00, or 60D0h = 1 / 2). CiA 402-2 leaves the wiring
/// to the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ProbeInput {
    /// The home switch (60FDh bit 2).
    #[default]
    HomeSwitch,
    /// The positive limit switch (60FDh bit 1).
    PositiveLimit,
    /// The negative limit switch (60FDh bit 0).
    NegativeLimit,
    /// A dedicated probe input, driven by the application with
    /// [`Drive::set_probe_input`](super::Drive::set_probe_input); an edge
    /// latches the position at the control period it is seen in.
    Dedicated,
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
    /// What "touch probe 1 input" and "touch probe 2 input" are wired to
    /// (default: the home switch for both, the behaviour before this
    /// option existed).
    pub probe_inputs: [ProbeInput; 2],
    /// 60D0h touch probe source is installed and 60B8h trigger selection
    /// 10b ("source per 60D0h") is honoured: 60D0h:k = 1 / 2 selects touch
    /// probe input 1 / 2, 5 / 6 the hardware / software zero impulse of the
    /// encoder (both the index here); other values (3 / 4 touch probe
    /// inputs 3 / 4, manufacturer codes) are refused (0609 0030). `false`: no 60D0h from the drive, selection
    /// 10b captures nothing (personalities keep this unless they opt in).
    pub probe_source_object: bool,
    /// 607Dh acts as a pair of limit switches in every mode but homing
    /// (Technosoft iPOS §4.3.2): past a limit the motion that way stops on
    /// the quick-stop ramp and is refused, statusword bit 11 shows it, and
    /// [`DriveView::software_limit`](super::DriveView::software_limit)
    /// reports which. `false`: 607Dh only clamps pp targets.
    pub software_limit_switches: bool,
    /// 60FDh bits 16–31 (manufacturer-specific in CiA 402-2) show the
    /// machine's digital input lines 1–16
    /// ([`crate::model::DriveModel::digital_inputs`]).
    pub input_lines: bool,
    /// 60FEh:1 bits 16–31 (manufacturer-specific) drive the machine's
    /// digital output lines 1–16, as far as 60FEh:2 enables them.
    pub output_lines: bool,
    /// 60FEh:1 bit 0 is CiA 402-2's "set brake": while set (and enabled in
    /// 60FEh:2) the holding brake is engaged whatever the drive's brake
    /// sequence wants.
    pub set_brake_bit: bool,
}

impl Default for IoConfig {
    fn default() -> Self {
        IoConfig {
            limit_switch: LimitSwitchReaction::StopAndWarn,
            interlock: false,
            output_mask: 0xFFFF_0000,
            keep_unmasked_command: false,
            probe_inputs: [ProbeInput::HomeSwitch; 2],
            probe_source_object: true,
            software_limit_switches: false,
            input_lines: false,
            output_lines: false,
            set_brake_bit: false,
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

/// 6086h motion profile types as bits of [`DriveConfig::motion_profile_types`]
/// (bit n set: 6086h = n is accepted; CiA 402-2 codes).
pub mod profile_type {
    /// 0: linear ramp (trapezoidal profile).
    pub const LINEAR: u32 = 1 << 0;
    /// 1: sin² ramp.
    pub const SIN_SQUARED: u32 = 1 << 1;
    /// 3: jerk-limited ramp (S-curve, jerk from 60A4h or
    /// [`Drive::set_profile_jerk`](crate::drive::Drive::set_profile_jerk)).
    pub const JERK_LIMITED: u32 = 1 << 3;
    /// Every type the drive implements (2, jerk-free ramp, is not).
    pub const IMPLEMENTED: u32 = LINEAR | SIN_SQUARED | JERK_LIMITED;
}

/// The jerk of the jerk-limited ramp (6086h = 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ProfileJerk {
    /// Jerk rates in acceleration units per second (the acceleration
    /// factor 6097h applies; CiA 402-2 60A4h "profile jerk", sub 1 while
    /// the speed rises, sub 2 while it falls). Rates of 0 run the linear
    /// ramp.
    Rate {
        /// 60A4h:1, speed rising.
        acceleration: u32,
        /// 60A4h:2, speed falling.
        deceleration: u32,
    },
    /// The time \[s\] to build up the profile acceleration (and
    /// deceleration): jerk = 6083h / t (6084h / t), so the S-curve follows
    /// later changes of the ramps (Technosoft iPOS 2023h "jerk time",
    /// seed002 §7.1.2). 0 or not finite runs the linear ramp.
    Time(f64),
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
    /// With [`FactorGroup::scaling`] the units follow scaling objects and
    /// 6091h/6092h/6096h/6097h are stored set-up parameters (Technosoft
    /// iPOS §5.2).
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
    /// Objects whose 0 means "off" on this drive (none by default).
    pub zero_means_off: ZeroMeansOff,
    /// What 6083h / 6084h / 609Ah = 0 means.
    pub zero_ramp: ZeroRamp,
    /// Manufacturer modes (negative 6060h) the drive takes, each with the
    /// standard mode it runs on meanwhile (6061h shows the manufacturer
    /// code). Empty by default: CiA 402 modes only.
    pub manufacturer_modes: alloc::vec::Vec<(i8, i8)>,
    /// 6086h values accepted, as [`profile_type`] bits (others: 0609 0030).
    /// [`DriveConfig::servo`]: linear, sin², jerk-limited.
    pub motion_profile_types: u32,
    /// 60A4h profile jerk (sub 0 = 2) is installed and hooked.
    pub profile_jerk_object: bool,
    /// Power-on jerk of the jerk-limited ramp (60A4h power-on value for a
    /// [`ProfileJerk::Rate`]); changed at run time by 60A4h writes or
    /// [`Drive::set_profile_jerk`](super::Drive::set_profile_jerk).
    pub profile_jerk: ProfileJerk,
    /// pp with 6086h = 3: a new set-point with controlword bit 5 (change
    /// set immediately) is ignored (not acknowledged, no motion), this EMCY
    /// code is raised and statusword bit 7 (warning) set until the next
    /// fault reset (controlword bit 7 rising edge). Technosoft iPOS
    /// (seed002 §7.1.2 / example E21): "with an S-curve, bit5 must be 0,
    /// otherwise a command error is raised" — EMCY 9000h, 2000h bit 14.
    /// `None` (CiA 402-2): the S-curve is re-planned from the present
    /// position, velocity and acceleration, see
    /// [`SCurve::plan`](super::profile::SCurve::plan).
    pub scurve_forbids_change_immediately: Option<u16>,
    /// Homing mode: after the reference is taken and the axis has braked,
    /// move back to the home position (607Ch in the new coordinates) before
    /// reporting homing completed (see
    /// [`HomingMode::with_return_to_home`](crate::homing::HomingMode::with_return_to_home),
    /// which sets the same per handler).
    pub homing_return_to_home: bool,
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
            zero_means_off: ZeroMeansOff::default(),
            zero_ramp: ZeroRamp::Refused,
            manufacturer_modes: alloc::vec::Vec::new(),
            motion_profile_types: profile_type::IMPLEMENTED,
            profile_jerk_object: true,
            // The profile acceleration built up in 10 ms.
            profile_jerk: ProfileJerk::Rate {
                acceleration: profile.profile_acceleration.saturating_mul(100),
                deceleration: profile.profile_deceleration.saturating_mul(100),
            },
            scurve_forbids_change_immediately: None,
            homing_return_to_home: false,
        }
    }
}

impl DriveConfig {
    /// 6072h/6073h power-on value: the motor's peak over rated current in
    /// per mille.
    pub(crate) fn max_torque_per_mille(&self) -> u16 {
        let m = &self.params.motor;
        (m.max_current / m.rated_current * 1000.0).clamp(0.0, 65535.0) as u16
    }
    /// 6075h power-on value \[mA\].
    pub(crate) fn rated_current_ma(&self) -> u32 {
        (self.params.motor.rated_current * 1000.0).clamp(1.0, 4e9) as u32
    }
    /// 6076h power-on value \[mN·m\].
    pub(crate) fn rated_torque_mnm(&self) -> u32 {
        let m = &self.params.motor;
        (m.kt * m.rated_current * 1000.0).clamp(1.0, 4e9) as u32
    }
    /// vl speeds \[rpm of the motor shaft\]: the motor's top speed.
    pub(crate) fn vl_rpm(&self) -> u32 {
        (self.params.motor.max_speed * 60.0 / (2.0 * core::f64::consts::PI)).clamp(1.0, 32767.0) as u32
    }

    /// The 60A4h:1/2 power-on values of [`DriveConfig::profile_jerk`] (a
    /// jerk time is converted with the power-on ramps).
    pub(crate) fn profile_jerk_rates(&self) -> (u32, u32) {
        match self.profile_jerk {
            ProfileJerk::Rate { acceleration, deceleration } => (acceleration, deceleration),
            ProfileJerk::Time(t) if t.is_finite() && t > 0.0 => {
                let r = |x: u32| (f64::from(x) / t).clamp(1.0, f64::from(u32::MAX)) as u32;
                (r(self.profile.profile_acceleration), r(self.profile.profile_deceleration))
            }
            ProfileJerk::Time(_) => (u32::MAX, u32::MAX),
        }
    }
}

impl Default for DriveConfig {
    /// [`DriveConfig::servo`] on [`DriveParams::servo_small`].
    fn default() -> Self {
        DriveConfig::servo(DriveParams::servo_small())
    }
}
