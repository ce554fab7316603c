//! The EtherCAT state machine states, as the ESC layer passes them in.

/// An ESM state (AL status bits 0-3; ETG.1000.6, EtherCAT state machine).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EsmState {
    /// INIT (1): no mailbox.
    Init,
    /// PRE-OPERATIONAL (2): mailbox only.
    PreOp,
    /// BOOTSTRAP (3): mailbox with FoE only, for firmware download.
    Boot,
    /// SAFE-OPERATIONAL (4): mailbox, inputs.
    SafeOp,
    /// OPERATIONAL (8): mailbox, inputs and outputs.
    Op,
}

impl EsmState {
    /// From the AL status (or AL control) state code in bits 0-3.
    pub const fn from_code(code: u8) -> Option<EsmState> {
        match code & 0x0F {
            1 => Some(EsmState::Init),
            2 => Some(EsmState::PreOp),
            3 => Some(EsmState::Boot),
            4 => Some(EsmState::SafeOp),
            8 => Some(EsmState::Op),
            _ => None,
        }
    }

    /// The AL state code.
    pub const fn code(self) -> u8 {
        match self {
            EsmState::Init => 1,
            EsmState::PreOp => 2,
            EsmState::Boot => 3,
            EsmState::SafeOp => 4,
            EsmState::Op => 8,
        }
    }

    /// Whether the mailbox runs in this state (every state but INIT).
    pub const fn has_mailbox(self) -> bool {
        !matches!(self, EsmState::Init)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip() {
        for s in [EsmState::Init, EsmState::PreOp, EsmState::Boot, EsmState::SafeOp, EsmState::Op] {
            assert_eq!(EsmState::from_code(s.code()), Some(s));
        }
        // The error-indication bit 4 is ignored.
        assert_eq!(EsmState::from_code(0x12), Some(EsmState::PreOp));
        assert_eq!(EsmState::from_code(0x05), None);
    }
}
