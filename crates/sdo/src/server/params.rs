//! SDO server parameter records 1200h..127Fh (CiA 301 §7.5.2) and the glue
//! that builds one [`SdoServer`] per record.
//!
//! 1200h is the default channel: its COB-IDs follow the node-ID and are
//! read-only. 1201h.. are additional channels, invalid (bit 31 set) by
//! default, configured by writing sub 1 and sub 2; sub 3 names the client.

use super::{SdoServer, ServerConfig};
use alloc::vec::Vec;
use drivebus_can::CanId;
use drivebus_od::{
    Access, DataType, Object, ObjectDictionary, ObjectHooks, SdoAbort, SubObject, Target, Value, WriteOutcome,
};

/// First server SDO parameter record.
pub const FIRST_PARAM_INDEX: u16 = 0x1200;
/// Last server SDO parameter record (128 channels).
pub const LAST_PARAM_INDEX: u16 = 0x127F;

/// COB-ID bit 31: the channel is not valid (disabled).
const COB_INVALID: u32 = 1 << 31;
/// COB-ID bit 29: 29-bit (extended) CAN identifier.
const COB_EXTENDED: u32 = 1 << 29;

/// Insert 1200h (default channel of `node_id`) and 1201h..1200h+count-1
/// (additional channels, invalid by default). `count` counts 1200h itself
/// and is clamped to 128; 0 inserts nothing.
pub fn install_server_params(od: &mut ObjectDictionary, node_id: u8, count: u8) {
    if count == 0 {
        return;
    }
    let id = u32::from(node_id & 0x7F);
    let cob = |sub: u8, name: &'static str, v: u32| {
        let mut s = SubObject::new(sub, name, DataType::Unsigned32, Access::Ro, Value::U32(v));
        // CiA 306 $NODEID+600h / +580h, kept for EDS export.
        s.node_id_relative = true;
        s
    };
    od.insert(
        Object::record(FIRST_PARAM_INDEX, "SDO server parameter")
            .with_sub(cob(1, "COB-ID client to server (rx)", 0x600 + id))
            .with_sub(cob(2, "COB-ID server to client (tx)", 0x580 + id)),
    );
    for i in 1..u16::from(count.min(128)) {
        let cob = |sub: u8, name: &'static str| {
            SubObject::new(sub, name, DataType::Unsigned32, Access::Rw, Value::U32(COB_INVALID)).hooked()
        };
        od.insert(
            Object::record(FIRST_PARAM_INDEX + i, "SDO server parameter")
                .with_sub(cob(1, "COB-ID client to server (rx)"))
                .with_sub(cob(2, "COB-ID server to client (tx)"))
                .with_sub(
                    SubObject::new(
                        3,
                        "Node-ID of the SDO client",
                        DataType::Unsigned8,
                        Access::Rw,
                        Value::U8(1),
                    )
                    .limits(Value::U8(1), Value::U8(127))
                    .hooked(),
                ),
        );
    }
}

/// Decode a COB-ID entry: `None` when bit 31 (not valid) is set or when an
/// 11-bit COB-ID has bits above 10 set. Bit 30 (dynamic) is ignored.
pub fn parse_cob_id(v: u32) -> Option<CanId> {
    if v & COB_INVALID != 0 {
        None
    } else if v & COB_EXTENDED != 0 {
        Some(CanId::Extended(v & 0x1FFF_FFFF))
    } else {
        CanId::standard(u16::try_from(v & 0x1FFF_FFFF).ok()?)
    }
}

/// The (client→server, server→client) identifiers of record `index`, or
/// `None` if the record is absent or either COB-ID is not valid.
pub fn cob_ids_from_od(od: &ObjectDictionary, index: u16) -> Option<(CanId, CanId)> {
    let rx = parse_cob_id(od.get_u32(index, 1)?)?;
    let tx = parse_cob_id(od.get_u32(index, 2)?)?;
    Some((rx, tx))
}

/// 11-bit CAN-IDs CiA 301 §7.3.5 reserves (NMT, SYNC/EMCY, TIME, the default
/// SDO channels, LSS, NMT error control): no additional channel may use them.
pub const fn is_restricted_can_id(id: u32) -> bool {
    id <= 0x7FF && drivebus_can::cob::is_restricted(id as u16)
}

/// The abort for an SDO write to a server parameter record, or `Ok` to let
/// it be stored. Indices outside 1200h..127Fh are not ours and pass.
///
/// - 1200h is read-only (`0601 0002`);
/// - a COB-ID may only change while invalid: changing a valid one to
///   another valid one gives `0609 0030` (CiA 301: invalidate first);
/// - a valid 11-bit COB-ID must fit 11 bits and avoid the restricted
///   CAN-IDs (`0609 0030`);
/// - sub 3 (client node-ID) is 1..=127 (`0609 0032` / `0609 0031`).
pub fn check_write(od: &ObjectDictionary, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
    if !(FIRST_PARAM_INDEX..=LAST_PARAM_INDEX).contains(&index) {
        return Ok(());
    }
    if od.object(index).is_none() {
        return Err(SdoAbort::NO_OBJECT);
    }
    if index == FIRST_PARAM_INDEX {
        return Err(SdoAbort::WRITE_READ_ONLY);
    }
    match sub {
        0 => Err(SdoAbort::WRITE_READ_ONLY),
        1 | 2 => {
            drivebus_od::check_len(DataType::Unsigned32, data.len())?;
            let new = u32::from_le_bytes([data[0], data[1], data[2], data[3]]);
            let cur = od.get_u32(index, sub).ok_or(SdoAbort::NO_SUB_INDEX)?;
            if new == cur || new & COB_INVALID != 0 {
                return Ok(());
            }
            if cur & COB_INVALID == 0 {
                return Err(SdoAbort::INVALID_VALUE);
            }
            match parse_cob_id(new) {
                Some(CanId::Standard(id)) if !is_restricted_can_id(id as u32) => Ok(()),
                Some(CanId::Extended(_)) => Ok(()),
                _ => Err(SdoAbort::INVALID_VALUE),
            }
        }
        3 => {
            drivebus_od::check_len(DataType::Unsigned8, data.len())?;
            match data[0] {
                0 => Err(SdoAbort::VALUE_TOO_LOW),
                1..=127 => Ok(()),
                _ => Err(SdoAbort::VALUE_TOO_HIGH),
            }
        }
        _ => Err(SdoAbort::NO_SUB_INDEX),
    }
}

/// Hooks applying [`check_write`] to 1200h..127Fh and storing what passes;
/// for integrators (and tests) without a node to route writes to owners.
#[derive(Clone, Copy, Debug, Default)]
pub struct ParamHooks;

impl ObjectHooks for ParamHooks {
    fn check_write(
        &mut self,
        od: &mut ObjectDictionary,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        check_write(od, at.index, at.sub, data)?;
        Ok(WriteOutcome::Store)
    }
}

impl SdoServer {
    /// A server for record `index` (1200h..127Fh), enabled if both COB-IDs
    /// are valid, disabled (ignoring every frame) otherwise; `None` if the
    /// record does not exist.
    pub fn from_od(od: &ObjectDictionary, index: u16, config: ServerConfig) -> Option<SdoServer> {
        od.object(index)?;
        let placeholder = CanId::Standard(0);
        let mut s = SdoServer::new(placeholder, placeholder, config);
        s.param_index = Some(index);
        s.apply_params(od);
        Some(s)
    }

    /// One server per 1200h..127Fh record present in `od`, in index order.
    pub fn servers_from_od(od: &ObjectDictionary, config: ServerConfig) -> Vec<SdoServer> {
        od.objects()
            .iter()
            .map(|o| o.index)
            .filter(|i| (FIRST_PARAM_INDEX..=LAST_PARAM_INDEX).contains(i))
            .filter_map(|i| SdoServer::from_od(od, i, config))
            .collect()
    }

    /// Re-read the COB-IDs after a write to `index` was stored; does
    /// nothing if `index` is not this channel's record.
    pub fn reconfigure(&mut self, od: &ObjectDictionary, index: u16) {
        if self.param_index == Some(index) {
            self.apply_params(od);
        }
    }

    fn apply_params(&mut self, od: &ObjectDictionary) {
        let Some(index) = self.param_index else { return };
        match cob_ids_from_od(od, index) {
            Some((rx, tx)) => self.set_cob_ids(rx, tx),
            None => self.disable(),
        }
    }
}
