//! Error behaviour, object 1029h (CiA 301 §7.5.2.32).

use crate::config::ERROR_BEHAVIOUR;
use crate::state::NmtState;
use alloc::vec::Vec;
use drivebus_od::{ObjectDictionary, SdoAbort, check_len};

/// An error class: the 1029h sub-index that holds its reaction.
///
/// Sub 1 is the communication error (CiA 301: bus-off, heartbeat consumer
/// timeout, life guarding event; the node may add others such as an RPDO
/// timeout). Subs 2.. are device-profile or manufacturer classes (e.g. CiA
/// 401 output errors); the DDS6 only implements sub 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ErrorClass(pub u8);

impl ErrorClass {
    /// 1029h sub 1: communication error.
    pub const COMMUNICATION: ErrorClass = ErrorClass(1);
}

/// A 1029h value decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorAction {
    /// 0: change to pre-operational, only if currently operational.
    PreOperational,
    /// 1: no state change.
    NoChange,
    /// 2: change to stopped.
    Stopped,
    /// 3..=127: reserved by CiA 301; treated as no state change.
    Reserved(u8),
    /// 128..=255: manufacturer-specific; NMT leaves the state alone and the
    /// node/application implements the reaction.
    Manufacturer(u8),
}

impl ErrorAction {
    /// Decode a 1029h value.
    #[inline]
    pub const fn from_value(v: u8) -> ErrorAction {
        match v {
            0 => ErrorAction::PreOperational,
            1 => ErrorAction::NoChange,
            2 => ErrorAction::Stopped,
            3..=127 => ErrorAction::Reserved(v),
            _ => ErrorAction::Manufacturer(v),
        }
    }

    /// The state to change to from `current`, or `None` for no change.
    /// Nothing happens in Initialisation (no error control runs there).
    #[inline]
    pub const fn target(self, current: NmtState) -> Option<NmtState> {
        match (self, current) {
            (ErrorAction::PreOperational, NmtState::Operational) => Some(NmtState::PreOperational),
            (ErrorAction::Stopped, NmtState::PreOperational | NmtState::Operational) => {
                Some(NmtState::Stopped)
            }
            _ => None,
        }
    }
}

/// The 1029h values, read at configuration time. A class without a value
/// (1029h absent or shorter) uses the CiA 301 default 0.
#[derive(Clone, Debug, Default)]
pub(crate) struct ErrorBehaviour {
    values: Vec<u8>,
}

impl ErrorBehaviour {
    /// Read every 1029h sub-index (allocates; configuration time only).
    /// Values set with [`ErrorBehaviour::set`] stay when 1029h is absent.
    pub(crate) fn configure(&mut self, od: &ObjectDictionary) {
        let Some(n) = od.get_u64(ERROR_BEHAVIOUR, 0) else { return };
        self.values.clear();
        for sub in 1..=n.min(254) as u8 {
            self.values.push(od.get_u64(ERROR_BEHAVIOUR, sub).unwrap_or(0) as u8);
        }
    }

    /// Set the value for `class` (1029h write, or a personality without 1029h).
    pub(crate) fn set(&mut self, class: ErrorClass, value: u8) {
        let Some(i) = (class.0 as usize).checked_sub(1) else { return };
        if i >= self.values.len() {
            self.values.resize(i + 1, 0);
        }
        self.values[i] = value;
    }

    /// The action for `class`.
    pub(crate) fn action(&self, class: ErrorClass) -> ErrorAction {
        if class.0 == 0 {
            // Sub 0 is the entry count, not a class.
            return ErrorAction::NoChange;
        }
        let v = (class.0 as usize).checked_sub(1).and_then(|i| self.values.get(i)).copied().unwrap_or(0);
        ErrorAction::from_value(v)
    }
}

/// The 1029h write check: reserved values 3..=127 are refused with `0609 0030`.
pub(crate) fn check_write(sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
    if sub == 0 {
        return Ok(());
    }
    check_len(drivebus_od::DataType::Unsigned8, data.len())?;
    match ErrorAction::from_value(data[0]) {
        ErrorAction::Reserved(_) => Err(SdoAbort::INVALID_VALUE),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn actions_per_state() {
        use NmtState::*;
        let pre = ErrorAction::from_value(0);
        assert_eq!(pre.target(Operational), Some(PreOperational));
        assert_eq!(pre.target(PreOperational), None);
        assert_eq!(pre.target(Stopped), None);
        assert_eq!(ErrorAction::from_value(1).target(Operational), None);
        let stop = ErrorAction::from_value(2);
        assert_eq!(stop.target(Operational), Some(Stopped));
        assert_eq!(stop.target(PreOperational), Some(Stopped));
        assert_eq!(stop.target(Stopped), None);
        assert_eq!(ErrorAction::from_value(3), ErrorAction::Reserved(3));
        assert_eq!(ErrorAction::from_value(0x80), ErrorAction::Manufacturer(0x80));
        assert_eq!(ErrorAction::from_value(0x80).target(Operational), None);
    }

    #[test]
    fn set_and_default() {
        let mut b = ErrorBehaviour::default();
        assert_eq!(b.action(ErrorClass::COMMUNICATION), ErrorAction::PreOperational);
        b.set(ErrorClass(3), 2);
        assert_eq!(b.action(ErrorClass(3)), ErrorAction::Stopped);
        assert_eq!(b.action(ErrorClass(2)), ErrorAction::PreOperational);
        b.set(ErrorClass(0), 2);
        assert_eq!(b.action(ErrorClass(0)), ErrorAction::NoChange);
        assert_eq!(check_write(1, &[3]), Err(SdoAbort::INVALID_VALUE));
        assert_eq!(check_write(1, &[0x81]), Ok(()));
        assert_eq!(check_write(1, &[1, 0]), Err(SdoAbort::DATA_TOO_LONG));
    }
}
