//! NMT slave states, commands and the state/service table (CiA 301 §7.3.2).

/// Sub-state of NMT Initialisation (CiA 301 §7.3.2.2.1, Figure "Structure of
/// the Initialisation NMT state").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum InitSubState {
    /// Reset application: manufacturer (2000h–5FFFh) and profile
    /// (6000h–9FFFh) parameters go back to their power-on values, then
    /// reset communication follows.
    ResetApplication,
    /// Reset communication: communication parameters (1000h–1FFFh) go back
    /// to their power-on values.
    ResetCommunication,
    /// Initialising: the device is about to send its boot-up message.
    Initialising,
}

/// The NMT slave state (CiA 301 §7.3.2.2, Figure "NMT state diagram").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NmtState {
    /// Initialisation, with its sub-state. Only LSS runs here.
    Initialisation(InitSubState),
    /// Pre-operational: SDO, SYNC, TIME, EMCY, NMT and error control.
    PreOperational,
    /// Operational: every service, PDO included.
    Operational,
    /// Stopped: only NMT, error control (heartbeat, guarding) and LSS.
    Stopped,
}

impl NmtState {
    /// The 7-bit state code carried by heartbeat and node-guarding frames
    /// (CiA 301 §7.2.8.3.2, Table "State of the NMT slave"): 0 for the
    /// boot-up (Initialisation), 4 stopped, 5 operational, 127 pre-operational.
    #[inline]
    pub const fn code(self) -> u8 {
        match self {
            NmtState::Initialisation(_) => 0x00,
            NmtState::Stopped => 0x04,
            NmtState::Operational => 0x05,
            NmtState::PreOperational => 0x7F,
        }
    }

    /// The state's name as CiA 301 writes it, lower case ("pre-operational").
    pub const fn name(self) -> &'static str {
        match self {
            NmtState::Initialisation(_) => "initialisation",
            NmtState::PreOperational => "pre-operational",
            NmtState::Operational => "operational",
            NmtState::Stopped => "stopped",
        }
    }

    /// True in Initialisation (any sub-state).
    #[inline]
    pub const fn is_initialisation(self) -> bool {
        matches!(self, NmtState::Initialisation(_))
    }

    /// Whether `service` may run in this state.
    ///
    /// CiA 301 §7.3.2.4, Table "States and communication objects":
    ///
    /// | service             | Init | Pre-op | Operational | Stopped |
    /// |---------------------|------|--------|-------------|---------|
    /// | PDO                 |      |        | x           |         |
    /// | SDO                 |      | x      | x           |         |
    /// | SYNC, TIME, EMCY    |      | x      | x           |         |
    /// | NMT, error control  |      | x      | x           | x       |
    /// | boot-up             | x    |        |             |         |
    /// | LSS (CiA 305)       | x    | x      | x           | x       |
    ///
    /// LSS is not in the CiA 301 table: CiA 305 runs the LSS slave state
    /// machine beside NMT, and a device without a valid node-ID waits in
    /// Initialisation (reset communication) for LSS to give it one. So LSS is
    /// allowed in every state; the LSS crate decides what it accepts.
    #[inline]
    pub const fn allows(self, service: Service) -> bool {
        use NmtState as S;
        match service {
            Service::Pdo => matches!(self, S::Operational),
            Service::Sdo | Service::Sync | Service::Time | Service::Emcy => {
                matches!(self, S::PreOperational | S::Operational)
            }
            Service::Nmt | Service::ErrorControl => {
                matches!(self, S::PreOperational | S::Operational | S::Stopped)
            }
            Service::BootUp => matches!(self, S::Initialisation(_)),
            Service::Lss => true,
        }
    }

    /// Every service that runs in this state.
    pub fn services(self) -> impl Iterator<Item = Service> {
        Service::ALL.into_iter().filter(move |s| self.allows(*s))
    }
}

/// A communication service, for [`NmtState::allows`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Service {
    /// Process data objects (RPDO reception, TPDO transmission).
    Pdo,
    /// Service data objects (server and client).
    Sdo,
    /// SYNC producer and consumer.
    Sync,
    /// TIME producer and consumer.
    Time,
    /// Emergency producer and consumer.
    Emcy,
    /// Reception of NMT commands.
    Nmt,
    /// Heartbeat producer/consumer and node/life guarding.
    ErrorControl,
    /// The boot-up message (sent on leaving Initialisation).
    BootUp,
    /// Layer setting services (CiA 305).
    Lss,
}

impl Service {
    /// Every service, in declaration order.
    pub const ALL: [Service; 9] = [
        Service::Pdo,
        Service::Sdo,
        Service::Sync,
        Service::Time,
        Service::Emcy,
        Service::Nmt,
        Service::ErrorControl,
        Service::BootUp,
        Service::Lss,
    ];
}

/// An NMT node-control command specifier (CiA 301 §7.2.8.3.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum NmtCommand {
    /// 01h Start remote node.
    Start = 0x01,
    /// 02h Stop remote node.
    Stop = 0x02,
    /// 80h Enter pre-operational.
    EnterPreOperational = 0x80,
    /// 81h Reset node.
    ResetNode = 0x81,
    /// 82h Reset communication.
    ResetCommunication = 0x82,
}

impl NmtCommand {
    /// Every command.
    pub const ALL: [NmtCommand; 5] = [
        NmtCommand::Start,
        NmtCommand::Stop,
        NmtCommand::EnterPreOperational,
        NmtCommand::ResetNode,
        NmtCommand::ResetCommunication,
    ];

    /// From the command specifier byte; `None` for an unknown one.
    #[inline]
    pub const fn from_cs(cs: u8) -> Option<NmtCommand> {
        Some(match cs {
            0x01 => NmtCommand::Start,
            0x02 => NmtCommand::Stop,
            0x80 => NmtCommand::EnterPreOperational,
            0x81 => NmtCommand::ResetNode,
            0x82 => NmtCommand::ResetCommunication,
            _ => return None,
        })
    }

    /// The command specifier byte.
    #[inline]
    pub const fn cs(self) -> u8 {
        self as u8
    }

    const fn bit(self) -> u8 {
        match self {
            NmtCommand::Start => 1 << 0,
            NmtCommand::Stop => 1 << 1,
            NmtCommand::EnterPreOperational => 1 << 2,
            NmtCommand::ResetNode => 1 << 3,
            NmtCommand::ResetCommunication => 1 << 4,
        }
    }
}

/// The set of NMT commands a device personality implements. A command not
/// in the set is ignored like an unknown command specifier (e.g. the KC1 and
/// AKD manuals do not list 80h "enter pre-operational").
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CommandSet(u8);

impl CommandSet {
    /// All five CiA 301 commands.
    pub const ALL: CommandSet = CommandSet(0x1F);
    /// No command at all.
    pub const NONE: CommandSet = CommandSet(0);

    /// The set without `cmd`.
    #[inline]
    pub const fn without(self, cmd: NmtCommand) -> CommandSet {
        CommandSet(self.0 & !cmd.bit())
    }
    /// The set with `cmd`.
    #[inline]
    pub const fn with(self, cmd: NmtCommand) -> CommandSet {
        CommandSet(self.0 | cmd.bit())
    }
    /// Whether `cmd` is implemented.
    #[inline]
    pub const fn contains(self, cmd: NmtCommand) -> bool {
        self.0 & cmd.bit() != 0
    }
    /// The implemented commands.
    pub fn iter(self) -> impl Iterator<Item = NmtCommand> {
        NmtCommand::ALL.into_iter().filter(move |c| self.contains(*c))
    }
}

impl Default for CommandSet {
    fn default() -> Self {
        CommandSet::ALL
    }
}

impl core::fmt::Debug for CommandSet {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_set().entries(self.iter()).finish()
    }
}

/// The NMT state another node reports in its heartbeat (bit 7 masked off).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RemoteState {
    /// 00h: boot-up message.
    BootUp,
    /// 04h.
    Stopped,
    /// 05h.
    Operational,
    /// 7Fh.
    PreOperational,
    /// A code CiA 301 does not define (kept as received, bit 7 masked).
    Other(u8),
}

impl RemoteState {
    /// Decode a heartbeat/guarding state byte; bit 7 (the guarding toggle,
    /// reserved in heartbeats) is ignored.
    #[inline]
    pub const fn from_code(byte: u8) -> RemoteState {
        match byte & 0x7F {
            0x00 => RemoteState::BootUp,
            0x04 => RemoteState::Stopped,
            0x05 => RemoteState::Operational,
            0x7F => RemoteState::PreOperational,
            other => RemoteState::Other(other),
        }
    }
    /// The 7-bit code.
    #[inline]
    pub const fn code(self) -> u8 {
        match self {
            RemoteState::BootUp => 0x00,
            RemoteState::Stopped => 0x04,
            RemoteState::Operational => 0x05,
            RemoteState::PreOperational => 0x7F,
            RemoteState::Other(c) => c,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        assert_eq!(NmtState::PreOperational.name(), "pre-operational");
        assert_eq!(NmtState::Operational.name(), "operational");
        assert_eq!(NmtState::Stopped.name(), "stopped");
    }

    #[test]
    fn codes() {
        assert_eq!(NmtState::Stopped.code(), 4);
        assert_eq!(NmtState::Operational.code(), 5);
        assert_eq!(NmtState::PreOperational.code(), 0x7F);
        assert_eq!(NmtState::Initialisation(InitSubState::Initialising).code(), 0);
        for c in 0..=255u8 {
            assert_eq!(RemoteState::from_code(c).code(), c & 0x7F);
            match NmtCommand::from_cs(c) {
                Some(cmd) => assert_eq!(cmd.cs(), c),
                None => assert!(![1, 2, 0x80, 0x81, 0x82].contains(&c)),
            }
        }
    }

    #[test]
    fn service_table() {
        use Service::*;
        let init = NmtState::Initialisation(InitSubState::ResetCommunication);
        assert_eq!(init.services().collect::<Vec<_>>(), [BootUp, Lss]);
        assert_eq!(
            NmtState::PreOperational.services().collect::<Vec<_>>(),
            [Sdo, Sync, Time, Emcy, Nmt, ErrorControl, Lss]
        );
        assert_eq!(
            NmtState::Operational.services().collect::<Vec<_>>(),
            [Pdo, Sdo, Sync, Time, Emcy, Nmt, ErrorControl, Lss]
        );
        assert_eq!(NmtState::Stopped.services().collect::<Vec<_>>(), [Nmt, ErrorControl, Lss]);
    }

    #[test]
    fn command_set() {
        let kc1 = CommandSet::ALL.without(NmtCommand::EnterPreOperational);
        assert!(!kc1.contains(NmtCommand::EnterPreOperational));
        assert!(kc1.contains(NmtCommand::Start));
        assert_eq!(kc1.iter().count(), 4);
        assert!(CommandSet::NONE.with(NmtCommand::Stop).contains(NmtCommand::Stop));
        assert_eq!(format!("{kc1:?}"), "{Start, Stop, ResetNode, ResetCommunication}");
    }
}
