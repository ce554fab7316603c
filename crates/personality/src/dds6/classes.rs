//! Error classes (§5, §6.4.7 2480h, §6.4.12 3080h:02): every EMCY code of
//! the §5 table has a class, and the class is the drive's reaction.
//!
//! | class | §5 "Drive's reaction" | here |
//! |---|---|---|
//! | 0 | none (warning) | EMCY, statusword bit 7 |
//! | 2 | deceleration with Quick Stop, no FAULT | EMCY, quick stop (held in Quick stop active: "stop of the motor", no disabling) |
//! | 4 | Quick Stop, then motor disabling and FAULT | fault, quick-stop ramp first |
//! | 6 | motor disabling and FAULT | fault, drive disabled at once |
//! | 8 | as 6, reset only by a power cycle | as 6; fault reset refused until power-on |
//!
//! The class of 8611h is 2480h:01 (object default 6, §6.4.7; the §5
//! table prints 2 as "the default value": the object's own default is what
//! a master reads back, so it is the one in force), that of 82B2h is
//! 3080h:02 (default 2).

use super::error_class;
use drivebus_cia402::drive::{Drive, ErrorReaction};
use drivebus_cia402::state_machine::Reaction;

/// EMCY 8611h "Following error" (class 2480h:01).
pub const EMCY_FOLLOWING_ERROR: u16 = 0x8611;
/// EMCY 8612h "Limit switch activation" (class 2).
pub const EMCY_LIMIT_SWITCH: u16 = 0x8612;
/// EMCY 8613h "Homing error" (class 2).
pub const EMCY_HOMING: u16 = 0x8613;
/// EMCY 82B2h "SYNC period breach" (class 3080h:02).
pub const EMCY_SYNC_BREACH: u16 = 0x82B2;

/// The drive's reaction to an error of `class`; `None` for a value that is
/// no class.
pub fn reaction(class: u8) -> Option<ErrorReaction> {
    Some(match class {
        0 => ErrorReaction::Warning,
        2 => ErrorReaction::QuickStop,
        4 => ErrorReaction::React(Reaction::QuickStopRamp),
        6 | 8 => ErrorReaction::React(Reaction::DisableDrive),
        _ => return None,
    })
}

/// The classes 2480h:01 accepts (§6.4.7 table: 2, 4, 6, 8).
pub fn following_error_class_valid(class: u8) -> bool {
    matches!(class, 2 | 4 | 6 | 8)
}

/// The classes 3080h:02 accepts (§6.4.12 table: 0, 2, 4, 6).
pub fn sync_class_valid(class: u8) -> bool {
    matches!(class, 0 | 2 | 4 | 6)
}

/// The class of `code` in force: the §5 table, 8611h and 82B2h as their
/// objects say.
pub fn class_of(code: u16, following_error: u8, sync: u8) -> Option<u8> {
    match code {
        EMCY_FOLLOWING_ERROR => Some(following_error),
        EMCY_SYNC_BREACH => Some(sync),
        _ => error_class(code),
    }
}

/// Tells the drive the reaction of every code of the §5 table.
pub fn install(drive: &mut Drive, following_error: u8, sync: u8) {
    for e in crate::Profile::Dds6.info().emcy {
        if let Some(class) = class_of(e.code, following_error, sync) {
            drive.set_fault_action(e.code, reaction(class));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_react_as_section_5_says() {
        assert_eq!(reaction(0), Some(ErrorReaction::Warning));
        assert_eq!(reaction(2), Some(ErrorReaction::QuickStop));
        assert_eq!(reaction(4), Some(ErrorReaction::React(Reaction::QuickStopRamp)));
        assert_eq!(reaction(6), Some(ErrorReaction::React(Reaction::DisableDrive)));
        assert_eq!(reaction(8), Some(ErrorReaction::React(Reaction::DisableDrive)));
        assert_eq!(reaction(3), None);
        assert_eq!(class_of(0x8611, 6, 2), Some(6));
        assert_eq!(class_of(0x82B2, 6, 0), Some(0));
        assert_eq!(class_of(0x8130, 6, 2), Some(2));
        assert!(following_error_class_valid(8) && !following_error_class_valid(0));
        assert!(sync_class_valid(0) && !sync_class_valid(8));
    }
}
