//! The holding brake sequence and the drive's digital I/O towards the
//! machine (60FDh bits 16–31, 60FEh).
//!
//! The brake (when the machine has one, [`crate::model::BrakeParams`])
//! is engaged while the drive function is disabled and released while it
//! is enabled; the drive waits for its delays as the manuals' brake
//! sequences do (Kollmorgen KC1 §7.2.2.15, AKD §6.2.2.19, LAM DDS6 §4.3):
//!
//! * **enable** (Operation enabled, reached at once as on the iPOS, §4.5.6
//!   2102h): the power stage holds the axis where it stands and releases
//!   the brake; the operating mode runs only once the release delay has
//!   passed (no motion into a closed brake);
//! * **disable** (Operation enabled left by a controlword, 605Ah/605Bh/
//!   605Ch with their ramps first): the brake is applied and the power
//!   stage keeps holding the axis through the apply delay, then goes off
//!   (a hanging load does not drop meanwhile);
//! * **fault**: the power stage goes off at once (Fault, after the 605Eh
//!   reaction); the brake closes after its apply delay, a hanging load may
//!   sag meanwhile.
//!
//! A drive configured with its brake's times ([`super::BrakeDelays`])
//! waits for those instead of the brake itself.
//!
//! 60FEh:1 bit 0 "set brake" (CiA 402-2, with [`super::IoConfig::set_brake_bit`]
//! and enabled in 60FEh:2) and a personality's brake object
//! ([`Drive::set_brake_control`]) override the sequence.

use super::Drive;
use crate::model::Demand;
use crate::state_machine::{DriveFunction, State};

/// Who commands the holding brake ([`Drive::set_brake_control`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum BrakeControl {
    /// The drive's brake sequence (and 60FEh "set brake").
    #[default]
    Auto,
    /// Engaged whatever the drive does (a brake-apply command).
    Engaged,
    /// Released whatever the drive does (a brake-release command: a hanging
    /// load falls with the power stage off).
    Released,
}

impl Drive {
    /// Sets who commands the brake (a personality's brake object, e.g. a
    /// manual release); takes effect at the next control period.
    pub fn set_brake_control(&mut self, c: BrakeControl) {
        self.brake_control = c;
    }

    /// Who commands the brake.
    pub fn brake_control(&self) -> BrakeControl {
        self.brake_control
    }

    /// The drive's own brake times (`None`: it waits for the brake, the
    /// machine's delays); from the next command on.
    pub fn set_brake_delays(&mut self, d: Option<super::BrakeDelays>) {
        self.cfg.io.brake_delays = d;
    }

    /// The digital output lines a personality's output objects set (bit
    /// `n − 1`: line `n`); the machine sees them together with 60FEh's
    /// ([`crate::model::DriveModel::outputs`]).
    pub fn set_output_lines(&mut self, lines: u16) {
        self.app_outputs = lines;
        self.sync_outputs();
    }

    /// Sets the drive's analog output \[V\]
    /// ([`crate::model::DriveModel::analog_output`]).
    pub fn set_analog_output(&mut self, volts: f64) {
        self.model.set_analog_output(volts);
    }

    /// The output lines the machine sees: the personality's
    /// ([`Drive::set_output_lines`]) and 60FEh:1 bits 16–31 with
    /// [`super::IoConfig::output_lines`].
    pub fn output_lines(&self) -> u16 {
        self.model.outputs()
    }

    /// Hands the output lines to the machine after 60FEh or the
    /// personality changed them.
    pub(crate) fn sync_outputs(&mut self) {
        let from_60fe = if self.cfg.io.output_lines { (self.extra.outputs >> 16) as u16 } else { 0 };
        self.model.set_outputs(from_60fe | self.app_outputs);
    }

    /// 60FDh bits 16–31: the machine's input lines, where configured.
    pub(crate) fn input_lines(&self) -> u32 {
        if self.cfg.io.input_lines { u32::from(self.model.digital_inputs()) << 16 } else { 0 }
    }

    /// Commands the brake for this period from the drive function.
    pub(crate) fn command_brake(&mut self, f: DriveFunction) {
        let engage = match self.brake_control {
            BrakeControl::Engaged => true,
            BrakeControl::Released => false,
            BrakeControl::Auto => {
                let set_brake = self.cfg.io.set_brake_bit && self.extra.outputs & 1 != 0;
                f == DriveFunction::Disabled || set_brake
            }
        };
        self.model.set_brake(engage);
    }

    /// The power stage's command while the brake is on its way: holding the
    /// axis at the demand while it releases after an enable (the mode
    /// waits) or closes after a disable (not after a fault); `None`: the
    /// drive function's own command.
    pub(crate) fn brake_hold(&mut self, f: DriveFunction) -> Option<Demand> {
        let b = self.model.brake();
        let pending = match self.cfg.io.brake_delays {
            // The drive's own times from its last command.
            Some(d) => {
                let ms = if b.commanded { d.apply_ms } else { d.release_ms };
                self.model.brake_command_age() * 1000.0 + 1e-6 < f64::from(ms)
            }
            None => b.pending,
        };
        if !(b.fitted && pending) {
            return None;
        }
        let hold = match f {
            DriveFunction::Enabled => !b.commanded,
            DriveFunction::Disabled => {
                b.commanded && !matches!(self.sm.state(), State::Fault | State::FaultReactionActive)
            }
            _ => false,
        };
        if !hold {
            return None;
        }
        self.dem.vel = 0.0;
        self.dem.acc = 0.0;
        Some(self.position_command(self.dem.pos, 0.0, 0.0))
    }
}
