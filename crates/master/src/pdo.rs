//! PDO configuration over SDO (CiA 301 §7.5.2.35..38) and DCF download
//! (CiA 302-2 style configuration manager).
//!
//! PDO numbers are 1-based as in the manuals: TPDO1 is 1800h/1A00h, RPDO1
//! 1400h/1600h.

use std::collections::BTreeMap;
use std::fmt;

use drivebus_eds::{Eds, EdsVar};
use drivebus_nmt::NmtCommand;
use drivebus_od::{DataType, SdoAbort};

use crate::master::Master;
use crate::sdo::{SdoError, SdoHandle};

/// Direction of a PDO, seen from the node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PdoDir {
    /// Receive PDO (master → node), 1400h/1600h.
    Rx,
    /// Transmit PDO (node → master), 1800h/1A00h.
    Tx,
}

impl PdoDir {
    /// Communication parameter index of PDO `num` (1-based).
    pub fn comm_index(self, num: u16) -> u16 {
        let base = if self == PdoDir::Rx { 0x1400 } else { 0x1800 };
        base + (num.clamp(1, 512) - 1)
    }
    /// Mapping parameter index of PDO `num` (1-based).
    pub fn map_index(self, num: u16) -> u16 {
        self.comm_index(num) + 0x200
    }
}

/// One mapped object; the PDO crate's, where the offsets are added up.
pub use drivebus_pdo::PdoMapEntry;

/// A PDO's communication and mapping records.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PdoRecord {
    /// Sub 1, with bit 31 (invalid) and bit 30 (no RTR).
    pub cob_id: u32,
    /// Sub 2.
    pub transmission_type: u8,
    /// Sub 3 (100 µs units); `None` if absent / not to be written.
    pub inhibit_time: Option<u16>,
    /// Sub 5 (ms); `None` if absent / not to be written.
    pub event_timer: Option<u16>,
    /// Sub 6 (TPDO only); `None` if absent / not to be written.
    pub sync_start: Option<u8>,
    /// The mapping, in order.
    pub mapping: Vec<PdoMapEntry>,
}

impl PdoRecord {
    /// A valid PDO on `can_id` with the given transmission type and mapping.
    pub fn new(can_id: u16, transmission_type: u8, mapping: Vec<PdoMapEntry>) -> Self {
        PdoRecord {
            cob_id: u32::from(can_id),
            transmission_type,
            inhibit_time: None,
            event_timer: None,
            sync_start: None,
            mapping,
        }
    }
    /// Bit 31 clear.
    pub fn valid(&self) -> bool {
        self.cob_id & 0x8000_0000 == 0
    }
    /// The 11-bit CAN identifier.
    pub fn can_id(&self) -> u16 {
        (self.cob_id & 0x7FF) as u16
    }
    /// Total mapped length in bytes (rounded up).
    pub fn len_bytes(&self) -> usize {
        self.mapping.iter().map(|m| usize::from(m.bits)).sum::<usize>().div_ceil(8)
    }
}

/// Why a configuration failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ConfigError {
    /// 1018h of the node differs from the DCF (CiA 302-2 identity check).
    IdentityMismatch {
        /// 1018h sub-index compared.
        sub: u8,
        /// Value in the DCF.
        expected: u32,
        /// Value of the node.
        actual: u32,
    },
    /// An SDO transfer failed.
    Sdo {
        /// Object.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The failure.
        error: SdoError,
    },
    /// A ParameterValue does not evaluate for its type.
    Value {
        /// Object.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Why.
        message: String,
    },
    /// The bus failed.
    Transport(String),
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigError::IdentityMismatch { sub, expected, actual } => write!(
                f,
                "identity mismatch at 1018h:{sub}: DCF has {expected:#010X}, node has {actual:#010X}"
            ),
            ConfigError::Sdo { index, sub, error } => write!(f, "{index:04X}h:{sub}: {error}"),
            ConfigError::Value { index, sub, message } => write!(f, "{index:04X}h:{sub}: {message}"),
            ConfigError::Transport(s) => write!(f, "bus error: {s}"),
        }
    }
}

impl std::error::Error for ConfigError {}

/// A PDO write the device refused ([`Master::try_write_pdo`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PdoWriteError {
    /// The refusal.
    pub cause: ConfigError,
    /// The configuration read before writing (`None`: it could not be read,
    /// nothing was written).
    pub previous: Option<PdoRecord>,
    /// Writing `previous` back: `Ok` when it is in force again.
    pub restored: Result<(), ConfigError>,
}

impl fmt::Display for PdoWriteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.cause)?;
        match (&self.previous, &self.restored) {
            (None, _) => Ok(()),
            (Some(_), Ok(())) => f.write_str("; the previous configuration was restored"),
            (Some(_), Err(e)) => write!(f, "; restoring the previous configuration failed too: {e}"),
        }
    }
}

impl std::error::Error for PdoWriteError {}

fn at(index: u16, sub: u8) -> impl FnOnce(SdoError) -> ConfigError {
    move |error| ConfigError::Sdo { index, sub, error }
}

/// Optional sub-objects read as absent.
fn optional<T>(r: Result<T, SdoError>) -> Result<Option<T>, SdoError> {
    match r {
        Ok(v) => Ok(Some(v)),
        Err(SdoError::Abort { code, .. })
            if code == SdoAbort::NO_SUB_INDEX || code == SdoAbort::NO_OBJECT =>
        {
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

impl Master {
    /// Reads PDO `num` (1-based) of `node`.
    pub async fn read_pdo(&self, node: u8, dir: PdoDir, num: u16) -> Result<PdoRecord, SdoError> {
        let sdo = self.sdo(node);
        let (ci, mi) = (dir.comm_index(num), dir.map_index(num));
        let cob_id: u32 = sdo.read(ci, 1).await?;
        let transmission_type: u8 = sdo.read(ci, 2).await?;
        let inhibit_time = optional(sdo.read::<u16>(ci, 3).await)?;
        let event_timer = optional(sdo.read::<u16>(ci, 5).await)?;
        let sync_start = if dir == PdoDir::Tx { optional(sdo.read::<u8>(ci, 6).await)? } else { None };
        let n: u8 = sdo.read(mi, 0).await?;
        let mut mapping = Vec::with_capacity(usize::from(n));
        for s in 1..=n.min(64) {
            mapping.push(PdoMapEntry::from_raw(sdo.read::<u32>(mi, s).await?));
        }
        Ok(PdoRecord { cob_id, transmission_type, inhibit_time, event_timer, sync_start, mapping })
    }

    /// Writes PDO `num` of `node` with the CiA 301 procedure (see
    /// [`write_pdo_raw`](Self::write_pdo_raw)), reading the PDO first: if
    /// the device refuses any step, the previous configuration is written
    /// back (best effort), so a refused mapping does not leave the PDO
    /// invalid and empty. The error is the refusal; use
    /// [`try_write_pdo`](Self::try_write_pdo) to learn whether the
    /// restore worked.
    pub async fn write_pdo(
        &self,
        node: u8,
        dir: PdoDir,
        num: u16,
        rec: &PdoRecord,
    ) -> Result<(), ConfigError> {
        self.try_write_pdo(node, dir, num, rec).await.map_err(|e| e.cause)
    }

    /// [`write_pdo`](Self::write_pdo) with the details of a refusal: the
    /// configuration in force before, and whether it was restored.
    pub async fn try_write_pdo(
        &self,
        node: u8,
        dir: PdoDir,
        num: u16,
        rec: &PdoRecord,
    ) -> Result<(), PdoWriteError> {
        let previous = self.read_pdo(node, dir, num).await.map_err(|e| PdoWriteError {
            cause: ConfigError::Sdo { index: dir.comm_index(num), sub: 1, error: e },
            previous: None,
            restored: Ok(()),
        })?;
        match self.write_pdo_raw(node, dir, num, rec).await {
            Ok(()) => Ok(()),
            Err(cause) => {
                let restored = self.write_pdo_raw(node, dir, num, &previous).await;
                Err(PdoWriteError { cause, previous: Some(previous), restored })
            }
        }
    }

    /// Writes PDO `num` of `node` with the CiA 301 procedure: invalidate
    /// (bit 31), parameters, clear mapping (sub 0 = 0), entries, count,
    /// then the COB-ID (first with bit 31 so an ID change is accepted,
    /// then as given). `inhibit_time`/`event_timer`/`sync_start` of `None`
    /// are left alone. A refusal leaves the PDO as far as it got.
    pub async fn write_pdo_raw(
        &self,
        node: u8,
        dir: PdoDir,
        num: u16,
        rec: &PdoRecord,
    ) -> Result<(), ConfigError> {
        let sdo = self.sdo(node);
        let (ci, mi) = (dir.comm_index(num), dir.map_index(num));
        let old: u32 = sdo.read(ci, 1).await.map_err(at(ci, 1))?;
        if old & 0x8000_0000 == 0 {
            sdo.write(ci, 1, old | 0x8000_0000).await.map_err(at(ci, 1))?;
        }
        sdo.write(ci, 2, rec.transmission_type).await.map_err(at(ci, 2))?;
        if let Some(v) = rec.inhibit_time {
            sdo.write(ci, 3, v).await.map_err(at(ci, 3))?;
        }
        if let Some(v) = rec.event_timer {
            sdo.write(ci, 5, v).await.map_err(at(ci, 5))?;
        }
        if let Some(v) = rec.sync_start {
            sdo.write(ci, 6, v).await.map_err(at(ci, 6))?;
        }
        sdo.write(mi, 0, 0u8).await.map_err(at(mi, 0))?;
        for (i, m) in rec.mapping.iter().enumerate() {
            let s = (i + 1) as u8;
            sdo.write(mi, s, m.raw()).await.map_err(at(mi, s))?;
        }
        let n = rec.mapping.len() as u8;
        sdo.write(mi, 0, n).await.map_err(at(mi, 0))?;
        set_cob_id(&sdo, ci, rec.cob_id).await
    }

    /// Applies a DCF (CiA 302-2 configuration manager, simplified): checks
    /// 1018h:1..3 against the DCF's vendor/product/revision when given,
    /// writes every writable entry that has a `ParameterValue` (PDOs with
    /// the invalidate/map/validate procedure, other objects in index order),
    /// then sends NMT start when `start`. `node` evaluates `$NODEID`.
    pub async fn apply_dcf(&self, node: u8, dcf: &Eds, start: bool) -> Result<usize, ConfigError> {
        let sdo = self.sdo(node);
        let info = &dcf.device_info;
        for (sub, expected) in
            [(1u8, info.vendor_number), (2, info.product_number), (3, info.revision_number)]
        {
            let Some(expected) = expected else { continue };
            let actual: u32 = sdo.read(0x1018, sub).await.map_err(at(0x1018, sub))?;
            if actual != expected {
                return Err(ConfigError::IdentityMismatch { sub, expected, actual });
            }
        }
        // (index, sub) → encoded value, for every writable ParameterValue.
        let mut values: BTreeMap<u16, BTreeMap<u8, Vec<u8>>> = BTreeMap::new();
        for (index, obj) in &dcf.objects {
            let vars: Vec<(u8, &EdsVar)> = match &obj.var {
                Some(v) => vec![(0, v)],
                None => obj.subs.iter().map(|(s, v)| (*s, v)).collect(),
            };
            for (sub, v) in vars {
                let (Some(text), true) = (&v.parameter_value, v.access.writable()) else { continue };
                let dt = DataType::from_index(v.data_type).ok_or_else(|| ConfigError::Value {
                    index: *index,
                    sub,
                    message: format!("data type {:#06x} is not a basic type", v.data_type),
                })?;
                let bytes = drivebus_eds::eval(text, dt, node).map_err(|message| ConfigError::Value {
                    index: *index,
                    sub,
                    message,
                })?;
                values.entry(*index).or_default().insert(sub, bytes);
            }
        }
        let is_comm = |i: u16| (0x1400..=0x15FF).contains(&i) || (0x1800..=0x19FF).contains(&i);
        let is_map = |i: u16| (0x1600..=0x17FF).contains(&i) || (0x1A00..=0x1BFF).contains(&i);
        let comm_of = |i: u16| if is_map(i) { i - 0x200 } else { i };
        let mut written = 0usize;
        // 1. Invalidate every PDO being configured, remembering its COB-ID.
        let mut pdo_comm: BTreeMap<u16, u32> = BTreeMap::new();
        for &i in values.keys().filter(|&&i| is_comm(i) || is_map(i)) {
            let ci = comm_of(i);
            if pdo_comm.contains_key(&ci) {
                continue;
            }
            let old: u32 = sdo.read(ci, 1).await.map_err(at(ci, 1))?;
            if old & 0x8000_0000 == 0 {
                sdo.write(ci, 1, old | 0x8000_0000).await.map_err(at(ci, 1))?;
            }
            pdo_comm.insert(ci, old);
        }
        // 2. Everything that is not a PDO.
        for (&index, subs) in values.iter().filter(|(i, _)| !is_comm(**i) && !is_map(**i)) {
            for (&sub, data) in subs {
                sdo.download(index, sub, data).await.map_err(at(index, sub))?;
                written += 1;
            }
        }
        // 3. Mappings: count 0, entries, count.
        for (&index, subs) in values.iter().filter(|(i, _)| is_map(**i)) {
            sdo.write(index, 0, 0u8).await.map_err(at(index, 0))?;
            for (&sub, data) in subs.iter().filter(|(s, _)| **s != 0) {
                sdo.download(index, sub, data).await.map_err(at(index, sub))?;
                written += 1;
            }
            let count = match subs.get(&0) {
                Some(d) => d.first().copied().unwrap_or(0),
                None => subs.keys().filter(|s| **s != 0).count() as u8,
            };
            sdo.write(index, 0, count).await.map_err(at(index, 0))?;
            written += 1;
        }
        // 4. Communication parameters, the COB-ID last.
        for (&ci, &old) in &pdo_comm {
            let subs = values.get(&ci);
            if let Some(subs) = subs {
                for (&sub, data) in subs.iter().filter(|(s, _)| **s != 1 && **s != 0) {
                    sdo.download(ci, sub, data).await.map_err(at(ci, sub))?;
                    written += 1;
                }
            }
            let cob = subs
                .and_then(|s| s.get(&1))
                .and_then(|d| <u32 as crate::SdoValue>::from_sdo(d))
                .unwrap_or(old);
            set_cob_id(&sdo, ci, cob).await?;
            written += 1;
        }
        if start {
            self.nmt(node, NmtCommand::Start).await.map_err(|e| ConfigError::Transport(e.to_string()))?;
        }
        Ok(written)
    }
}

/// Writes a COB-ID to a PDO that is currently invalid: with bit 31 first
/// (changing the CAN-ID of a valid PDO is refused, CiA 301), then as given.
async fn set_cob_id(sdo: &SdoHandle, ci: u16, cob: u32) -> Result<(), ConfigError> {
    sdo.write(ci, 1, cob | 0x8000_0000).await.map_err(at(ci, 1))?;
    if cob & 0x8000_0000 == 0 {
        sdo.write(ci, 1, cob).await.map_err(at(ci, 1))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_and_entries() {
        assert_eq!(PdoDir::Tx.comm_index(1), 0x1800);
        assert_eq!(PdoDir::Tx.map_index(4), 0x1A03);
        assert_eq!(PdoDir::Rx.comm_index(2), 0x1401);
        assert_eq!(PdoDir::Rx.map_index(1), 0x1600);
        let e = PdoMapEntry::new(0x6041, 0, 16);
        assert_eq!(e.raw(), 0x6041_0010);
        assert_eq!(PdoMapEntry::from_raw(0x607A_0020), PdoMapEntry::new(0x607A, 0, 32));
        let r = PdoRecord::new(0x181, 255, vec![e, PdoMapEntry::new(0x2000, 0, 1)]);
        assert!(r.valid());
        assert_eq!(r.len_bytes(), 3);
    }
}
