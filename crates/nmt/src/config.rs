//! Device personality switches and the CiA 301 objects NMT owns.

use crate::state::CommandSet;
use drivebus_od::{Access, DataType, Object, ObjectDictionary, Value};

/// 100Ch Guard time (UNSIGNED16, ms).
pub const GUARD_TIME: u16 = 0x100C;
/// 100Dh Life time factor (UNSIGNED8).
pub const LIFE_TIME_FACTOR: u16 = 0x100D;
/// 1016h Consumer heartbeat time (ARRAY of UNSIGNED32).
pub const CONSUMER_HEARTBEAT_TIME: u16 = 0x1016;
/// 1017h Producer heartbeat time (UNSIGNED16, ms).
pub const PRODUCER_HEARTBEAT_TIME: u16 = 0x1017;
/// 1029h Error behaviour (ARRAY of UNSIGNED8).
pub const ERROR_BEHAVIOUR: u16 = 0x1029;

/// NMT command COB-ID (CiA 301 §7.2.8.3.1).
pub const NMT_COB_ID: u16 = 0x000;
/// Base of the NMT error control COB-IDs (boot-up, heartbeat, guarding): 700h + node-ID.
pub const ERROR_CONTROL_BASE: u16 = 0x700;

/// Most consumer entries 1016h can have (one per other node).
pub const MAX_CONSUMER_ENTRIES: u8 = 127;

/// What a device implements of NMT and error control. Real drives differ:
/// the SSD 630 answers node guarding but has no heartbeat and ignores
/// 100Ch/100Dh; KC1 and AKD do not list command 80h.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NmtConfig {
    /// The node-ID, 1..=127. Any other value (e.g. FFh, "not configured" in
    /// CiA 305) keeps the device in Initialisation until LSS sets one.
    pub node_id: u8,
    /// NMT commands the device reacts to; the others are ignored.
    pub supported_commands: CommandSet,
    /// Go to Operational by itself right after the boot-up message
    /// (manufacturer flag such as SSD 630 2018h = 1).
    pub auto_start: bool,
    /// Heartbeat producer (1017h) and consumer (1016h) implemented.
    pub heartbeat_supported: bool,
    /// Node guarding (RTR on 700h + node-ID answered) implemented.
    pub guarding_supported: bool,
    /// Life guarding evaluated from 100Ch × 100Dh. False for devices that
    /// answer guarding but never supervise the master (SSD 630 §8).
    pub life_guarding_honoured: bool,
}

impl NmtConfig {
    /// Every CiA 301 feature on: all commands, heartbeat, guarding with life
    /// guarding, no auto-start.
    pub const fn new(node_id: u8) -> NmtConfig {
        NmtConfig {
            node_id,
            supported_commands: CommandSet::ALL,
            auto_start: false,
            heartbeat_supported: true,
            guarding_supported: true,
            life_guarding_honoured: true,
        }
    }
}

/// Insert the NMT error-control objects the configuration calls for, with
/// their CiA 301 defaults (all 0 = off), hooked so the node routes writes
/// through [`crate::Nmt::check_write`] and [`crate::Nmt::reconfigure`]:
///
/// - 100Ch, 100Dh when `guarding_supported` (even if life guarding is not
///   honoured: such devices still list the objects);
/// - 1017h when `heartbeat_supported`, and 1016h with
///   `n_consumer_entries` (clamped to 127) entries when that is non-zero.
pub fn install(od: &mut ObjectDictionary, config: &NmtConfig, n_consumer_entries: u8) {
    if config.guarding_supported {
        od.insert(hooked(Object::var(
            GUARD_TIME,
            "Guard time",
            DataType::Unsigned16,
            Access::Rw,
            Value::U16(0),
        )));
        od.insert(hooked(Object::var(
            LIFE_TIME_FACTOR,
            "Life time factor",
            DataType::Unsigned8,
            Access::Rw,
            Value::U8(0),
        )));
    }
    if config.heartbeat_supported {
        od.insert(hooked(Object::var(
            PRODUCER_HEARTBEAT_TIME,
            "Producer heartbeat time",
            DataType::Unsigned16,
            Access::Rw,
            Value::U16(0),
        )));
        let n = n_consumer_entries.min(MAX_CONSUMER_ENTRIES);
        if n > 0 {
            od.insert(hooked(Object::array(
                CONSUMER_HEARTBEAT_TIME,
                "Consumer heartbeat time",
                DataType::Unsigned32,
                Access::Rw,
                n,
                Value::U32(0),
            )));
        }
    }
}

/// Insert 1029h Error behaviour with `n_classes` (1..=254) entries, all 0
/// (CiA 301 §7.5.2.32 default: change to pre-operational). Sub 1 is the
/// communication error class; subs 2.. are profile or manufacturer classes.
pub fn install_error_behaviour(od: &mut ObjectDictionary, n_classes: u8) {
    let n = n_classes.clamp(1, 254);
    od.insert(hooked(Object::array(
        ERROR_BEHAVIOUR,
        "Error behaviour",
        DataType::Unsigned8,
        Access::Rw,
        n,
        Value::U8(0),
    )));
    if let Some(o) = od.object_mut(ERROR_BEHAVIOUR)
        && let Some(s) = o.subs_mut().get_mut(1)
    {
        s.name = "Communication error".into();
    }
}

/// Mark every writable sub-object hooked (sub 0 of an ARRAY stays plain).
fn hooked(mut o: Object) -> Object {
    for s in o.subs_mut() {
        if s.access.writable() {
            s.owner = drivebus_od::Owner::HOOKED;
            s.live = true;
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn install_follows_config() {
        let mut od = ObjectDictionary::new();
        install(&mut od, &NmtConfig::new(5), 3);
        install_error_behaviour(&mut od, 2);
        assert_eq!(od.get_u32(0x1016, 0), Some(3));
        assert!(od.get(0x1016, 3).unwrap().is_hooked());
        assert!(!od.get(0x1016, 0).unwrap().is_hooked());
        assert!(od.get(0x1017, 0).unwrap().is_hooked());
        assert!(od.get(0x100C, 0).is_some() && od.get(0x100D, 0).is_some());
        assert_eq!(od.get_u32(0x1029, 0), Some(2));
        assert_eq!(od.get(0x1029, 1).unwrap().name, "Communication error");

        let mut od = ObjectDictionary::new();
        let ssd =
            NmtConfig { heartbeat_supported: false, life_guarding_honoured: false, ..NmtConfig::new(1) };
        install(&mut od, &ssd, 4);
        assert!(od.get(0x1016, 0).is_none() && od.get(0x1017, 0).is_none());
        assert!(od.get(0x100C, 0).is_some());

        let mut od = ObjectDictionary::new();
        install(&mut od, &NmtConfig::new(1), 0);
        assert!(od.get(0x1016, 0).is_none() && od.get(0x1017, 0).is_some());
    }
}
