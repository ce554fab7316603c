//! How a motion ended: [`MotionReport`], what [`RemoteDrive::move_to`] and
//! [`RemoteDrive::home`] return (as `Ok` at the target, inside
//! [`DriveError::Stopped`] anywhere else), and [`DriveFlags`], the
//! statusword bits and switch inputs that explain a stop.
//!
//! CiA 402-2 §6.2.2 (statusword): bit 7 warning, bit 10 target reached,
//! bit 11 internal limit active, bits 12/13 mode-specific (pp: set-point
//! acknowledge / following error; hm: homing attained / homing error).
//! CiA 402-2 §6.7 (60FDh digital inputs): bit 0 negative limit switch,
//! bit 1 positive limit switch, bit 2 home switch, bit 3 interlock.

use std::fmt;
use std::time::Duration;

use super::{DriveError, DriveState, RemoteDrive, cw};
use drivebus_cia402::codes::sw;

/// 60FDh bit 0: negative limit switch.
pub const DI_NEGATIVE_LIMIT: u32 = 1 << 0;
/// 60FDh bit 1: positive limit switch.
pub const DI_POSITIVE_LIMIT: u32 = 1 << 1;
/// 60FDh bit 2: home switch.
pub const DI_HOME_SWITCH: u32 = 1 << 2;
/// 60FDh bit 3: interlock.
pub const DI_INTERLOCK: u32 = 1 << 3;

/// Where a motion ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionEnd {
    /// Profile position: the drive reports the target reached (bit 10)
    /// with no limit, error or halt.
    TargetReached,
    /// Homing completed (bits 12 and 10).
    HomingAttained,
    /// A limit switch stopped the axis (60FDh bit 0 or 1).
    LimitSwitch {
        /// The positive switch (bit 1); else the negative one (bit 0).
        positive: bool,
    },
    /// The axis stands at a software position limit (607Dh) with bit 11 set.
    SoftwareLimit,
    /// Internal limit active (bit 11) with no switch input and not at 607Dh.
    InternalLimit,
    /// Following error (profile position, bit 13).
    FollowingError,
    /// Homing error (homing mode, bit 13).
    HomingError,
    /// The drive went to Fault (or fault reaction active).
    Fault,
    /// Quick stop active.
    QuickStop,
    /// Halt (controlword bit 8) stopped the axis.
    Halted,
    /// The drive left operation enabled (disabled, switched off).
    Disabled,
}

impl MotionEnd {
    /// True when the motion did what it was asked.
    pub fn succeeded(self) -> bool {
        matches!(self, MotionEnd::TargetReached | MotionEnd::HomingAttained)
    }

    /// A short code for machines (`--json`): `target_reached`, `limit_switch`, ...
    pub fn code(self) -> &'static str {
        match self {
            MotionEnd::TargetReached => "target_reached",
            MotionEnd::HomingAttained => "homing_attained",
            MotionEnd::LimitSwitch { .. } => "limit_switch",
            MotionEnd::SoftwareLimit => "software_limit",
            MotionEnd::InternalLimit => "internal_limit",
            MotionEnd::FollowingError => "following_error",
            MotionEnd::HomingError => "homing_error",
            MotionEnd::Fault => "fault",
            MotionEnd::QuickStop => "quick_stop",
            MotionEnd::Halted => "halted",
            MotionEnd::Disabled => "disabled",
        }
    }
}

/// What a motion did: where it ended, why, how long it took.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MotionReport {
    /// Where it ended.
    pub end: MotionEnd,
    /// Position actual value 6064h at the end, when readable.
    pub position: Option<i32>,
    /// The absolute target of a move (`None` for homing or an unknown base).
    pub target: Option<i32>,
    /// The statusword at the end.
    pub statusword: u16,
    /// Digital inputs 60FDh at the end, when the drive has them.
    pub inputs: Option<u32>,
    /// Error code 603Fh, read when the drive faulted.
    pub error_code: Option<u16>,
    /// Homing: the method (6098h) that ran.
    pub homing_method: Option<i8>,
    /// Homing error: the methods the drive offers (60E3h), when readable.
    pub homing_methods: Vec<i8>,
    /// From the start of the command to the end of the motion (master time).
    pub duration: Duration,
}

impl MotionReport {
    /// Why the motion ended where it did, in words with the objects and
    /// bits that say so (empty reason for a success).
    pub fn reason(&self) -> String {
        let sw = self.statusword;
        match self.end {
            MotionEnd::TargetReached => "target reached (statusword bit 10)".into(),
            MotionEnd::HomingAttained => "homing attained (statusword bits 12 and 10)".into(),
            MotionEnd::LimitSwitch { positive } => format!(
                "the {} limit switch is active (60FDh bit {}; statusword bit 11 internal limit active)",
                if positive { "positive" } else { "negative" },
                u8::from(positive)
            ),
            MotionEnd::SoftwareLimit => {
                "the axis is at a software position limit 607Dh (statusword bit 11 internal limit active)"
                    .into()
            }
            MotionEnd::InternalLimit => "internal limit active (statusword bit 11)".into(),
            MotionEnd::FollowingError => {
                "following error (statusword bit 13: the position lagged beyond 6065h)".into()
            }
            MotionEnd::HomingError => {
                let mut s = "homing error (statusword bit 13)".to_owned();
                if self.homing_method == Some(0) {
                    s.push_str(": 6098h homing method is 0 (no method)");
                } else if let Some(m) = self.homing_method
                    && !self.homing_methods.is_empty()
                    && !self.homing_methods.contains(&m)
                {
                    s.push_str(&format!(": the drive does not offer method {m}"));
                }
                if !self.homing_methods.is_empty() {
                    let list: Vec<String> = self.homing_methods.iter().map(i8::to_string).collect();
                    s.push_str(&format!("; 60E3h offers methods {}", list.join(", ")));
                }
                if let Some(i) = self.inputs {
                    let active = DriveFlags::inputs_text(i);
                    if !active.is_empty() {
                        s.push_str(&format!("; active inputs: {active}"));
                    }
                }
                s
            }
            MotionEnd::Fault => match self.error_code {
                Some(c) if c != 0 => format!(
                    "the drive faulted: error {c:04X}h {}",
                    drivebus_emcy::describe(c).unwrap_or("(manufacturer-specific)")
                ),
                _ => "the drive faulted".into(),
            },
            MotionEnd::QuickStop => "quick stop active".into(),
            MotionEnd::Halted => "halted (controlword bit 8)".into(),
            MotionEnd::Disabled => {
                format!("the drive left operation enabled ({})", DriveState::from_statusword(sw))
            }
        }
    }

    /// The distance left to the target, when both are known.
    pub fn short_of_target(&self) -> Option<i64> {
        Some(i64::from(self.target?) - i64::from(self.position?))
    }
}

impl fmt::Display for MotionReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let at = self.position.map_or_else(|| "an unknown position".to_owned(), |p| p.to_string());
        if self.end.succeeded() {
            return write!(f, "{} at {at} after {:.3} s", self.reason(), self.duration.as_secs_f64());
        }
        write!(f, "stopped at {at}")?;
        if let (Some(t), Some(left)) = (self.target, self.short_of_target()) {
            write!(f, ", {} short of the target {t}", left.abs())?;
        }
        write!(f, " after {:.3} s: {}", self.duration.as_secs_f64(), self.reason())
    }
}

/// The statusword bits and 60FDh inputs that explain why an axis stands,
/// for `drive status`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DriveFlags {
    /// The statusword.
    pub statusword: u16,
    /// 60FDh, when readable.
    pub inputs: Option<u32>,
    /// Modes of operation display 6061h (bit 13 means following error in
    /// pp/csp, homing error in hm).
    pub mode: Option<i8>,
}

impl DriveFlags {
    /// The active inputs of a 60FDh value, in words (empty when none).
    pub fn inputs_text(inputs: u32) -> String {
        let mut v = Vec::new();
        for (bit, name) in [
            (DI_NEGATIVE_LIMIT, "negative limit switch (60FDh bit 0)"),
            (DI_POSITIVE_LIMIT, "positive limit switch (60FDh bit 1)"),
            (DI_HOME_SWITCH, "home switch (60FDh bit 2)"),
            (DI_INTERLOCK, "interlock (60FDh bit 3)"),
        ] {
            if inputs & bit != 0 {
                v.push(name);
            }
        }
        v.join(", ")
    }

    /// The statusword bits that say something is limited or wrong, in
    /// words: bit 7 warning, bit 11 internal limit active, bit 13 (its
    /// meaning in the mode shown).
    pub fn statusword_text(&self) -> Vec<String> {
        let s = self.statusword;
        let mut v = Vec::new();
        if s & sw::WARNING != 0 {
            v.push("warning (bit 7)".to_owned());
        }
        if s & sw::INTERNAL_LIMIT != 0 {
            v.push("internal limit active (bit 11)".to_owned());
        }
        if s & sw::MODE_13 != 0 {
            v.push(match self.mode {
                Some(super::mode::HM) => "homing error (bit 13)".to_owned(),
                Some(super::mode::PP | super::mode::CSP | super::mode::IP) => {
                    "following error (bit 13)".to_owned()
                }
                _ => "bit 13 (mode-specific: following or homing error)".to_owned(),
            });
        }
        v
    }
}

impl RemoteDrive {
    /// 60FDh digital inputs.
    pub async fn digital_inputs(&self) -> Option<u32> {
        let v = self.read_raw(0x60FD, 0).await.ok()?;
        (v.len() >= 4).then(|| u32::from_le_bytes([v[0], v[1], v[2], v[3]]))
    }

    /// The homing methods the drive offers (60E3h), empty when unreadable.
    pub async fn homing_methods(&self) -> Vec<i8> {
        let Ok(n) = self.sdo.read::<u8>(0x60E3, 0).await else { return Vec::new() };
        let mut v = Vec::new();
        for sub in 1..=n {
            match self.sdo.read::<i8>(0x60E3, sub).await {
                Ok(m) => v.push(m),
                Err(_) => break,
            }
        }
        v
    }

    /// True for a statusword that ends a motion whatever bit 10 says: the
    /// drive left operation enabled, or bit 13 in profile position
    /// (following error).
    pub(super) fn ended_abnormally(sw: u16, homing: bool) -> bool {
        DriveState::from_statusword(sw) != DriveState::OperationEnabled || (!homing && sw & sw::MODE_13 != 0)
    }

    /// Classifies the end of a motion from its last statusword.
    pub(super) async fn classify(
        &self,
        sw: u16,
        target: Option<i32>,
        homing: Option<i8>,
        started: drivebus_can::Instant,
    ) -> MotionReport {
        let position = self.position().await;
        let inputs = self.digital_inputs().await;
        let state = DriveState::from_statusword(sw);
        let mut error_code = None;
        let end = match state {
            DriveState::Fault | DriveState::FaultReactionActive => {
                error_code = self
                    .read_raw(0x603F, 0)
                    .await
                    .ok()
                    .and_then(|v| (v.len() >= 2).then(|| u16::from_le_bytes([v[0], v[1]])));
                MotionEnd::Fault
            }
            DriveState::QuickStopActive => MotionEnd::QuickStop,
            DriveState::OperationEnabled => {
                if homing.is_some() {
                    // Homing ends on attained (bits 12 and 10) or error (bit
                    // 13); attained on an active switch is still attained.
                    if sw & sw::MODE_13 != 0 { MotionEnd::HomingError } else { MotionEnd::HomingAttained }
                } else if sw & sw::MODE_13 != 0 {
                    MotionEnd::FollowingError
                } else if sw & sw::INTERNAL_LIMIT != 0 {
                    let i = inputs.unwrap_or(0);
                    if i & DI_POSITIVE_LIMIT != 0 && i & DI_NEGATIVE_LIMIT == 0 {
                        MotionEnd::LimitSwitch { positive: true }
                    } else if i & DI_NEGATIVE_LIMIT != 0 {
                        MotionEnd::LimitSwitch { positive: false }
                    } else {
                        let lim = self.read_i32(0x607D, 1).await.zip(self.read_i32(0x607D, 2).await);
                        match (lim, position) {
                            (Some((lo, hi)), Some(p)) if lo < hi && (p <= lo || p >= hi) => {
                                MotionEnd::SoftwareLimit
                            }
                            _ => MotionEnd::InternalLimit,
                        }
                    }
                } else if self
                    .read_raw(super::CONTROLWORD, 0)
                    .await
                    .ok()
                    .is_some_and(|v| v.len() >= 2 && u16::from_le_bytes([v[0], v[1]]) & cw::HALT != 0)
                {
                    MotionEnd::Halted
                } else {
                    MotionEnd::TargetReached
                }
            }
            _ => MotionEnd::Disabled,
        };
        let homing_methods =
            if end == MotionEnd::HomingError { self.homing_methods().await } else { Vec::new() };
        MotionReport {
            end,
            position,
            target,
            statusword: sw,
            inputs,
            error_code,
            homing_method: homing,
            homing_methods,
            duration: self.master.now().saturating_duration_since(started),
        }
    }

    /// `Ok(report)` for a motion that did what it was asked, else
    /// [`DriveError::Stopped`].
    pub(super) fn settle(report: MotionReport) -> Result<MotionReport, DriveError> {
        if report.end.succeeded() { Ok(report) } else { Err(DriveError::Stopped(Box::new(report))) }
    }
}

/// Bit 12 clear and bit 10 set: a profile move at rest after its set-point.
pub(super) fn pp_at_rest(sw: u16) -> bool {
    sw & sw::MODE_12 == 0 && sw & sw::TARGET_REACHED != 0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(end: MotionEnd) -> MotionReport {
        MotionReport {
            end,
            position: Some(2_519_228),
            target: Some(50_000_000),
            statusword: 0x0EB7,
            inputs: Some(DI_POSITIVE_LIMIT),
            error_code: None,
            homing_method: None,
            homing_methods: Vec::new(),
            duration: Duration::from_millis(873),
        }
    }

    #[test]
    fn a_limit_switch_stop_says_where_and_why() {
        let r = report(MotionEnd::LimitSwitch { positive: true });
        assert_eq!(
            r.to_string(),
            "stopped at 2519228, 47480772 short of the target 50000000 after 0.873 s: the positive limit switch is active (60FDh bit 1; statusword bit 11 internal limit active)"
        );
        assert!(!r.end.succeeded());
        assert_eq!(r.end.code(), "limit_switch");
    }

    #[test]
    fn a_homing_error_names_the_method_and_what_the_drive_offers() {
        let mut r = report(MotionEnd::HomingError);
        r.homing_method = Some(0);
        r.homing_methods = vec![1, 2, 35, 37];
        r.inputs = Some(0);
        let why = r.reason();
        assert!(why.contains("6098h homing method is 0"), "{why}");
        assert!(why.contains("60E3h offers methods 1, 2, 35, 37"), "{why}");
    }

    #[test]
    fn flags_decode_bits_7_11_13_and_the_switches() {
        let f = DriveFlags { statusword: 0x2EB7, inputs: Some(3), mode: Some(1) };
        assert_eq!(
            f.statusword_text(),
            ["warning (bit 7)", "internal limit active (bit 11)", "following error (bit 13)"]
        );
        assert_eq!(
            DriveFlags::inputs_text(3),
            "negative limit switch (60FDh bit 0), positive limit switch (60FDh bit 1)"
        );
    }
}
