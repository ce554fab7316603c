//! The PDO communication and mapping objects (CiA 301 7.5.2.35..7.5.2.38)
//! and their defaults.

use crate::cobid::{COB_ID_BITS, COB_INVALID, COB_NO_RTR};
use crate::config::PdoConfig;
use crate::mapping::{PdoKind, validate_mapping};
use alloc::format;
use drivebus_od::{Access, DataType, Object, ObjectCode, ObjectDictionary, SdoAbort, SubObject, Value};

/// Communication record sub-index: COB-ID (UNSIGNED32).
pub const SUB_COB_ID: u8 = 1;
/// Communication record sub-index: transmission type (UNSIGNED8).
pub const SUB_TRANSMISSION_TYPE: u8 = 2;
/// Communication record sub-index: inhibit time, 100 µs (UNSIGNED16; TPDO only).
pub const SUB_INHIBIT_TIME: u8 = 3;
/// Communication record sub-index: event timer, ms (UNSIGNED16). On an RPDO
/// it is the deadline monitoring time.
pub const SUB_EVENT_TIMER: u8 = 5;
/// TPDO communication sub 4: reserved, a compatibility entry (CiA 301 7.5.2.35).
pub const SUB_RESERVED: u8 = 4;
/// Communication record sub-index: SYNC start value (UNSIGNED8; TPDO only).
pub const SUB_SYNC_START: u8 = 6;

/// Transmission type: event-driven, manufacturer-specific.
pub const TT_EVENT_MANUFACTURER: u8 = 254;
/// Transmission type: event-driven, profile-specific (the CiA 301 default).
pub const TT_EVENT_PROFILE: u8 = 255;
/// Transmission type: synchronous, sent on RTR only.
pub const TT_SYNC_RTR: u8 = 252;
/// Transmission type: event-driven, sent on RTR only.
pub const TT_EVENT_RTR: u8 = 253;

/// Index of the communication record of PDO `n` (0-based).
#[inline]
pub const fn comm_index(kind: PdoKind, n: u16) -> u16 {
    match kind {
        PdoKind::Rpdo => 0x1400 + n,
        PdoKind::Tpdo => 0x1800 + n,
    }
}

/// Index of the mapping record of PDO `n` (0-based).
#[inline]
pub const fn map_index(kind: PdoKind, n: u16) -> u16 {
    match kind {
        PdoKind::Rpdo => 0x1600 + n,
        PdoKind::Tpdo => 0x1A00 + n,
    }
}

/// What a PDO index belongs to: `(kind, n, is_mapping_record)`, for PDOs
/// the configuration has.
pub fn classify(cfg: &PdoConfig, index: u16) -> Option<(PdoKind, u16, bool)> {
    let (kind, n, map) = match index {
        0x1400..=0x15FF => (PdoKind::Rpdo, index - 0x1400, false),
        0x1600..=0x17FF => (PdoKind::Rpdo, index - 0x1600, true),
        0x1800..=0x19FF => (PdoKind::Tpdo, index - 0x1800, false),
        0x1A00..=0x1BFF => (PdoKind::Tpdo, index - 0x1A00, true),
        _ => return None,
    };
    let count = match kind {
        PdoKind::Rpdo => cfg.rpdo_count,
        PdoKind::Tpdo => cfg.tpdo_count,
    };
    (n < count.min(crate::MAX_PDOS)).then_some((kind, n, map))
}

/// The CiA 301 default COB-ID of PDO `n`: the pre-defined connection set
/// for n = 0..=3 (RPDO 200h/300h/400h/500h, TPDO 180h/280h/380h/480h +
/// node-id), invalid otherwise. TPDOs carry bit 30 (no RTR) when the device
/// does not support RTR.
pub fn default_cob_id(cfg: &PdoConfig, kind: PdoKind, n: u16) -> u32 {
    let base = match kind {
        PdoKind::Rpdo => 0x200,
        PdoKind::Tpdo => 0x180,
    };
    let rtr = if kind == PdoKind::Tpdo && !cfg.rtr_supported { COB_NO_RTR } else { 0 };
    if n < 4 && (1..=127).contains(&cfg.node_id) {
        (base + 0x100 * u32::from(n) + u32::from(cfg.node_id)) | rtr
    } else {
        COB_INVALID | rtr
    }
}

fn comm_record(cfg: &PdoConfig, kind: PdoKind, n: u16) -> Object {
    let index = comm_index(kind, n);
    let (name, inhibit_name, timer_name) = match kind {
        PdoKind::Rpdo => {
            ("RPDO communication parameter", "Inhibit time (not used)", "Event timer (deadline)")
        }
        PdoKind::Tpdo => ("TPDO communication parameter", "Inhibit time", "Event timer"),
    };
    let cob = default_cob_id(cfg, kind, n);
    let mut cob_sub =
        SubObject::new(SUB_COB_ID, "COB-ID used by PDO", DataType::Unsigned32, Access::Rw, Value::U32(cob))
            .hooked();
    cob_sub.node_id_relative = n < 4;
    // Sub 4 is "reserved" in CiA 301 v4.2 and not implemented, so the
    // dictionary answers 0609 0011 for it.
    let mut o = Object::record(index, format!("{name} {}", n + 1))
        .with_sub(cob_sub)
        .with_sub(
            SubObject::new(
                SUB_TRANSMISSION_TYPE,
                "Transmission type",
                DataType::Unsigned8,
                Access::Rw,
                Value::U8(TT_EVENT_PROFILE),
            )
            .hooked(),
        )
        .with_sub(
            SubObject::new(SUB_INHIBIT_TIME, inhibit_name, DataType::Unsigned16, Access::Rw, Value::U16(0))
                .hooked(),
        )
        .with_sub(
            SubObject::new(SUB_EVENT_TIMER, timer_name, DataType::Unsigned16, Access::Rw, Value::U16(0))
                .hooked(),
        );
    if kind == PdoKind::Tpdo {
        o = o.with_sub(
            SubObject::new(SUB_SYNC_START, "SYNC start value", DataType::Unsigned8, Access::Rw, Value::U8(0))
                .limits(Value::U8(0), Value::U8(240))
                .hooked(),
        );
    }
    o
}

/// "Mapped object 1" … "Mapped object 64": static, so building a node
/// does not format (and allocate) a name for each of up to 64 × 1024 entries.
const MAPPED_NAMES: [&str; crate::MAX_MAPPED_ENTRIES as usize] = [
    "Mapped object 1",
    "Mapped object 2",
    "Mapped object 3",
    "Mapped object 4",
    "Mapped object 5",
    "Mapped object 6",
    "Mapped object 7",
    "Mapped object 8",
    "Mapped object 9",
    "Mapped object 10",
    "Mapped object 11",
    "Mapped object 12",
    "Mapped object 13",
    "Mapped object 14",
    "Mapped object 15",
    "Mapped object 16",
    "Mapped object 17",
    "Mapped object 18",
    "Mapped object 19",
    "Mapped object 20",
    "Mapped object 21",
    "Mapped object 22",
    "Mapped object 23",
    "Mapped object 24",
    "Mapped object 25",
    "Mapped object 26",
    "Mapped object 27",
    "Mapped object 28",
    "Mapped object 29",
    "Mapped object 30",
    "Mapped object 31",
    "Mapped object 32",
    "Mapped object 33",
    "Mapped object 34",
    "Mapped object 35",
    "Mapped object 36",
    "Mapped object 37",
    "Mapped object 38",
    "Mapped object 39",
    "Mapped object 40",
    "Mapped object 41",
    "Mapped object 42",
    "Mapped object 43",
    "Mapped object 44",
    "Mapped object 45",
    "Mapped object 46",
    "Mapped object 47",
    "Mapped object 48",
    "Mapped object 49",
    "Mapped object 50",
    "Mapped object 51",
    "Mapped object 52",
    "Mapped object 53",
    "Mapped object 54",
    "Mapped object 55",
    "Mapped object 56",
    "Mapped object 57",
    "Mapped object 58",
    "Mapped object 59",
    "Mapped object 60",
    "Mapped object 61",
    "Mapped object 62",
    "Mapped object 63",
    "Mapped object 64",
];

fn map_record(cfg: &PdoConfig, kind: PdoKind, n: u16) -> Object {
    let name = match kind {
        PdoKind::Rpdo => "RPDO mapping parameter",
        PdoKind::Tpdo => "TPDO mapping parameter",
    };
    let mut o = Object::with_code(map_index(kind, n), ObjectCode::Record, format!("{name} {}", n + 1))
        .with_sub(
            SubObject::new(0, "Number of mapped objects", DataType::Unsigned8, Access::Rw, Value::U8(0))
                .limits(Value::U8(0), Value::U8(cfg.max_entries))
                .hooked(),
        );
    for i in 1..=cfg.max_entries {
        o = o.with_sub(
            SubObject::new(
                i,
                MAPPED_NAMES[usize::from(i - 1)],
                DataType::Unsigned32,
                Access::Rw,
                Value::U32(0),
            )
            .hooked(),
        );
    }
    o
}

/// Insert the PDO objects with their CiA 301 defaults: 1400h+n/1600h+n for
/// every RPDO, 1800h+n/1A00h+n for every TPDO, and the data type entries of
/// the supported dummy types (DEFTYPE, read-only, value = size in bits).
/// All writable sub-objects are hooked: the node routes writes through
/// [`crate::Pdo::check_write`] and [`crate::Pdo::reconfigure`].
pub fn install(od: &mut ObjectDictionary, cfg: &PdoConfig) {
    let cfg = cfg.normalized();
    for t in 1u16..0x20 {
        if cfg.dummy_supported(t)
            && od.object(t).is_none()
            && let Some(dt) = DataType::from_index(t)
            && let Some(size) = dt.fixed_size()
        {
            let bits = if dt == DataType::Boolean { 1 } else { 8 * size as u32 };
            let mut o = Object::var(t, dt.name(), DataType::Unsigned32, Access::Const, Value::U32(bits));
            o.code = ObjectCode::DefType;
            od.insert(o);
        }
    }
    for n in 0..cfg.rpdo_count {
        od.insert(comm_record(&cfg, PdoKind::Rpdo, n));
        od.insert(map_record(&cfg, PdoKind::Rpdo, n));
    }
    for n in 0..cfg.tpdo_count {
        od.insert(comm_record(&cfg, PdoKind::Tpdo, n));
        od.insert(map_record(&cfg, PdoKind::Tpdo, n));
    }
}

/// A PDO's factory configuration, as a device profile or personality
/// defines it (e.g. CiA 402 RPDO1 = controlword).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PdoDefaults<'a> {
    /// Mapping entries (`index << 16 | sub << 8 | bits`), see [`crate::map_entry`].
    pub entries: &'a [u32],
    /// Transmission type (sub 2).
    pub transmission_type: u8,
    /// Inhibit time in 100 µs (sub 3, TPDO).
    pub inhibit_time: u16,
    /// Event timer in ms (sub 5).
    pub event_timer: u16,
    /// COB-ID (sub 1); `None` keeps the CiA 301 default.
    pub cob_id: Option<u32>,
}

impl<'a> PdoDefaults<'a> {
    /// Event-driven (255) with these entries, other parameters at CiA 301 defaults.
    pub const fn new(entries: &'a [u32]) -> Self {
        PdoDefaults {
            entries,
            transmission_type: TT_EVENT_PROFILE,
            inhibit_time: 0,
            event_timer: 0,
            cob_id: None,
        }
    }
}

fn set_both(od: &mut ObjectDictionary, index: u16, sub: u8, v: Value) -> Result<(), SdoAbort> {
    let r = od.find(index, sub)?;
    let dt = od.entry(r).data_type;
    let bytes = v.encode(dt)?;
    // Factory defaults mostly re-set the 0 an unused mapping entry holds
    // (up to 64 per PDO at every build): then there is nothing to store.
    let e = od.entry(r);
    if e.default == bytes && e.bytes() == bytes.as_slice() {
        return Ok(());
    }
    if let Some(s) = od.get_mut(index, sub) {
        s.default.clone_from(&bytes);
    }
    od.set_raw(r, &bytes);
    Ok(())
}

/// Set the factory configuration of PDO `n` after [`install`] and after the
/// mapped objects exist: value *and* default, so 1011h restore brings it
/// back. The mapping is checked like an SDO download of sub 0 would be;
/// on error nothing is changed. Call [`crate::Pdo::reload`] afterwards.
pub fn set_defaults(
    od: &mut ObjectDictionary,
    cfg: &PdoConfig,
    kind: PdoKind,
    n: u16,
    d: &PdoDefaults<'_>,
) -> Result<(), SdoAbort> {
    let cfg = cfg.normalized();
    if classify(&cfg, comm_index(kind, n)).is_none() {
        return Err(SdoAbort::NO_OBJECT);
    }
    if d.entries.len() > usize::from(cfg.max_entries) {
        return Err(SdoAbort::VALUE_TOO_HIGH);
    }
    validate_mapping(od, &cfg, kind, d.entries.iter().copied())?;
    crate::check::check_transmission_type(&cfg, kind, d.transmission_type)?;
    let ci = comm_index(kind, n);
    let mi = map_index(kind, n);
    for (i, &e) in d.entries.iter().enumerate() {
        set_both(od, mi, i as u8 + 1, Value::U32(e))?;
    }
    // The unused entries: most already hold 0 as value and default, which
    // `set_both` would find, encode and compare one lookup at a time.
    let zero =
        |s: &SubObject| s.data_type == DataType::Unsigned32 && s.default == [0; 4] && s.bytes() == [0; 4];
    let unused = d.entries.len() + 1..=usize::from(cfg.max_entries);
    // One look-up of the object for all of them; only those not at zero
    // go through `set_both`.
    let pending: alloc::vec::Vec<u8> = match od.object(mi) {
        Some(o) => unused.filter(|&i| !o.get(i as u8).is_some_and(zero)).map(|i| i as u8).collect(),
        None => unused.map(|i| i as u8).collect(),
    };
    for i in pending {
        set_both(od, mi, i, Value::U32(0))?;
    }
    set_both(od, mi, 0, Value::U8(d.entries.len() as u8))?;
    set_both(od, ci, SUB_TRANSMISSION_TYPE, Value::U8(d.transmission_type))?;
    set_both(od, ci, SUB_INHIBIT_TIME, Value::U16(d.inhibit_time))?;
    set_both(od, ci, SUB_EVENT_TIMER, Value::U16(d.event_timer))?;
    if let Some(cob) = d.cob_id {
        set_both(od, ci, SUB_COB_ID, Value::U32(cob))?;
        if let Some(s) = od.get_mut(ci, SUB_COB_ID) {
            s.node_id_relative = false;
        }
    }
    Ok(())
}

/// After a node-ID change (LSS, CiA 305; takes effect at reset
/// communication): move the pre-defined connection set COB-IDs (PDO 1..4)
/// still derived from `old_node_id` to `cfg.node_id` and update their
/// defaults (always). An untouched COB-ID becomes the new default; one whose
/// validity/RTR bits were changed keeps them; any other id is left alone.
/// Call [`crate::Pdo::reload`] afterwards.
pub fn update_node_id(od: &mut ObjectDictionary, cfg: &PdoConfig, old_node_id: u8) {
    let cfg = cfg.normalized();
    let old_cfg = PdoConfig { node_id: old_node_id, ..cfg };
    for (kind, count) in [(PdoKind::Rpdo, cfg.rpdo_count), (PdoKind::Tpdo, cfg.tpdo_count)] {
        for n in 0..count.min(4) {
            let ci = comm_index(kind, n);
            let Some(cur) = od.get_u32(ci, SUB_COB_ID) else { continue };
            let old_def = default_cob_id(&old_cfg, kind, n);
            let new_def = default_cob_id(&cfg, kind, n);
            if let Some(s) = od.get_mut(ci, SUB_COB_ID) {
                s.default = new_def.to_le_bytes().to_vec();
            }
            let new = if cur == old_def {
                new_def
            } else if old_def & COB_ID_BITS != 0 && cur & COB_ID_BITS == old_def & COB_ID_BITS {
                let v = (cur & !COB_ID_BITS) | (new_def & COB_ID_BITS);
                if new_def & COB_ID_BITS == 0 { v | COB_INVALID } else { v }
            } else {
                continue;
            };
            if let Ok(r) = od.find(ci, SUB_COB_ID) {
                od.set_raw(r, &new.to_le_bytes());
            }
        }
    }
}
