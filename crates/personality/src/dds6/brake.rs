//! The holding brake (§4.3, §6.4.3 2360h, §6.4.22 3360h, §6.4.8 2810h:0Ah):
//! the brake output (active = released) from the drive's handling, the
//! manual signal and the action that combines them; the status bits of
//! 3360h:02.

use super::io;
use drivebus_cia402::drive::BrakeControl;

/// 2360h:01 Option_HBRKS bits (§6.4.3).
pub mod option {
    /// Bit 0: the drive handles the brake on enable / disable.
    pub const HANDLED: u16 = 1 << 0;
    /// Bit 1: manual, only the manual signal commands the brake.
    pub const MANUAL: u16 = 1 << 1;
}

/// The manual-control action of 2360h:01 bits 8–11. The manual prints the
/// list "None, Release, Engage, Release / Engage, Shared Release, Shared
/// Engage, Shared release / engage" with only "0 = None" numbered; the
/// others are taken as 1–6 in the printed order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ManualBrakeAction {
    /// 0: the signal does nothing.
    None,
    /// 1: active signal, always released.
    Release,
    /// 2: active signal, always engaged.
    Engage,
    /// 3: active released, inactive engaged.
    ReleaseEngage,
    /// 4: a rising edge releases; the drive may engage again.
    SharedRelease,
    /// 5: a rising edge engages; the drive may release again.
    SharedEngage,
    /// 6: rising edge releases, falling edge engages; the drive too.
    SharedReleaseEngage,
}

impl ManualBrakeAction {
    /// Bits 8–11 of 2360h:01; an unknown code acts as None.
    pub fn of(option: u16) -> ManualBrakeAction {
        match (option >> 8) & 0x0F {
            1 => ManualBrakeAction::Release,
            2 => ManualBrakeAction::Engage,
            3 => ManualBrakeAction::ReleaseEngage,
            4 => ManualBrakeAction::SharedRelease,
            5 => ManualBrakeAction::SharedEngage,
            6 => ManualBrakeAction::SharedReleaseEngage,
            _ => ManualBrakeAction::None,
        }
    }
}

/// The brake's settings and state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldingBrakeControl {
    /// 2360h:01.
    pub option: u16,
    /// 2360h:02 Application_Time_HBRKS \[ms\].
    pub application_ms: u16,
    /// 2360h:03 Release_Time_HBRKS \[ms\].
    pub release_ms: u16,
    /// 2810h:0Ah Holding_Brake_DIA.
    pub input: u16,
    /// 3360h:01 Control_HBRKC.
    pub control: u8,
    signal_was: bool,
    drive_was: bool,
    /// A shared action's edge in force until the drive commands again.
    shared: Option<bool>,
    /// The brake output: active = released.
    output: bool,
    /// Time since the output changed \[s\].
    since_s: f64,
}

impl Default for HoldingBrakeControl {
    fn default() -> Self {
        HoldingBrakeControl {
            option: 0,
            application_ms: 200,
            release_ms: 200,
            input: 0,
            control: 0,
            signal_was: false,
            drive_was: false,
            shared: None,
            output: false,
            // Engaged since power-on.
            since_s: f64::MAX,
        }
    }
}

impl HoldingBrakeControl {
    /// The drive handles the brake automatically (bit 0, not manual).
    pub fn automatic(&self) -> bool {
        self.option & (option::HANDLED | option::MANUAL) == option::HANDLED
    }

    /// The brake output (active = released, §4.3).
    pub fn output(&self) -> bool {
        self.output
    }

    /// One control period. `drive_release`: the motor is enabled or being
    /// enabled (the drive wants the brake free); `enabled`: the drive
    /// function runs (its own brake sequence releases); `di` the inputs
    /// (3210h:01). Returns who commands the machine's brake.
    pub fn step(&mut self, drive_release: bool, enabled: bool, di: u16, dt: f64) -> BrakeControl {
        let signal = self.control & 1 != 0 || io::function_active(self.input, di);
        let (rising, falling) = (signal && !self.signal_was, !signal && self.signal_was);
        self.signal_was = signal;
        let auto = self.automatic() && drive_release;
        if auto != self.drive_was {
            // "Also the drive can release or engage the brake when necessary".
            self.shared = None;
        }
        self.drive_was = auto;
        let release = if self.option & option::MANUAL != 0 {
            signal
        } else {
            match ManualBrakeAction::of(self.option) {
                ManualBrakeAction::None => auto,
                ManualBrakeAction::Release => signal || auto,
                ManualBrakeAction::Engage => !signal && auto,
                ManualBrakeAction::ReleaseEngage => signal,
                ManualBrakeAction::SharedRelease
                | ManualBrakeAction::SharedEngage
                | ManualBrakeAction::SharedReleaseEngage => {
                    let a = ManualBrakeAction::of(self.option);
                    if rising && a != ManualBrakeAction::SharedEngage {
                        self.shared = Some(true);
                    } else if (rising && a == ManualBrakeAction::SharedEngage)
                        || (falling && a == ManualBrakeAction::SharedReleaseEngage)
                    {
                        self.shared = Some(false);
                    }
                    self.shared.unwrap_or(auto)
                }
            }
        };
        if release != self.output {
            self.output = release;
            self.since_s = 0.0;
        } else {
            self.since_s += dt;
        }
        // The drive's own sequence where it agrees (it holds the axis while
        // the brake closes after a disable), else the output as commanded.
        if release == enabled {
            BrakeControl::Auto
        } else if release {
            BrakeControl::Released
        } else {
            BrakeControl::Engaged
        }
    }

    /// 3360h:02 Status_HBRKC: bit 0 output active, bit 1 released
    /// (Release_Time passed), bit 2 engaged (Application_Time passed).
    pub fn status(&self) -> u8 {
        let ms = self.since_s * 1000.0 + 1e-9;
        let released = self.output && ms >= f64::from(self.release_ms);
        let engaged = !self.output && ms >= f64::from(self.application_ms);
        u8::from(self.output) | u8::from(released) << 1 | u8::from(engaged) << 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 0.001;

    fn run(b: &mut HoldingBrakeControl, release: bool, enabled: bool, di: u16, ms: u32) -> BrakeControl {
        let mut c = BrakeControl::Auto;
        for _ in 0..ms {
            c = b.step(release, enabled, di, DT);
        }
        c
    }

    #[test]
    fn handled_brake_releases_then_reports() {
        let mut b = HoldingBrakeControl { option: option::HANDLED, ..HoldingBrakeControl::default() };
        assert_eq!(b.status(), 0b100, "engaged at power-on");
        // Being enabled: released at once, "released" after 200 ms.
        assert_eq!(run(&mut b, true, false, 0, 100), BrakeControl::Released);
        assert_eq!(b.status(), 0b001);
        assert_eq!(run(&mut b, true, true, 0, 150), BrakeControl::Auto);
        assert_eq!(b.status(), 0b011);
        // Disabled: output off, "engaged" after 200 ms.
        run(&mut b, false, false, 0, 100);
        assert_eq!(b.status(), 0b000);
        run(&mut b, false, false, 0, 150);
        assert_eq!(b.status(), 0b100);
    }

    #[test]
    fn not_handled_keeps_the_brake_engaged() {
        let mut b = HoldingBrakeControl::default();
        assert_eq!(run(&mut b, true, true, 0, 10), BrakeControl::Engaged);
        assert!(!b.output());
    }

    #[test]
    fn manual_signal_and_actions() {
        // Manual: 3360h:01 bit 0 releases.
        let mut b = HoldingBrakeControl {
            option: option::HANDLED | option::MANUAL,
            control: 1,
            ..HoldingBrakeControl::default()
        };
        assert_eq!(run(&mut b, false, false, 0, 5), BrakeControl::Released);
        // ManualBrakeAction 2 "Engage": an active input (DI4 per 2810h:0Ah = 0204h)
        // engages an enabled motor's brake.
        let mut b = HoldingBrakeControl {
            option: option::HANDLED | 2 << 8,
            input: 0x0204,
            ..HoldingBrakeControl::default()
        };
        assert_eq!(run(&mut b, true, true, 0, 5), BrakeControl::Auto);
        assert_eq!(run(&mut b, true, true, 1 << 4, 5), BrakeControl::Engaged);
        // ManualBrakeAction 4 "Shared release": an edge releases a disabled motor's
        // brake until the drive commands again.
        let mut b =
            HoldingBrakeControl { option: option::HANDLED | 4 << 8, ..HoldingBrakeControl::default() };
        b.control = 1;
        assert_eq!(run(&mut b, false, false, 0, 5), BrakeControl::Released);
        b.control = 0;
        assert_eq!(run(&mut b, false, false, 0, 5), BrakeControl::Released, "latched");
        run(&mut b, true, true, 0, 5);
        assert_eq!(run(&mut b, false, false, 0, 5), BrakeControl::Auto, "the drive engaged it");
        assert_eq!(ManualBrakeAction::of(0x0F00), ManualBrakeAction::None);
    }
}
