//! One PDO of another protocol's process image (EtherCAT: the PDOs that
//! 1C12h/1C13h assign to SM2/SM3), moved with the same resolved copy plan
//! and packer the CAN PDO service uses: validated like a mapping write,
//! resolved to entry handles once, sampled and applied without search or
//! allocation.

use crate::config::PdoConfig;
use crate::events::{EventQueue, PdoEvent};
use crate::mapping::{PdoKind, Plan, apply, resolve, sample};
use drivebus_can::MAX_DATA_LEN;
use drivebus_od::{ObjectDictionary, ObjectHooks, SdoAbort};

/// A resolved PDO mapping of at most 64 bits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MappedPdo {
    plan: Plan,
    kind: PdoKind,
    bits: u32,
}

impl MappedPdo {
    /// Validates `entries` (CiA 301 7.5.2.36: objects present, mappable in
    /// this direction, lengths; at most `cfg.max_bits()` in all) and
    /// resolves them. The abort is the one an SDO write of the mapping's
    /// sub 0 would give.
    pub fn resolve(
        od: &ObjectDictionary,
        cfg: &PdoConfig,
        kind: PdoKind,
        entries: &[u32],
    ) -> Result<MappedPdo, SdoAbort> {
        let plan = resolve(od, &cfg.normalized(), kind, entries)?;
        let bits = entries.iter().map(|e| e & 0xFF).sum();
        Ok(MappedPdo { plan, kind, bits })
    }

    /// Mapped length in bits.
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// Direction.
    pub fn kind(&self) -> PdoKind {
        self.kind
    }

    /// The mapped values, least significant bit first (a TxPDO's data):
    /// live entries are refreshed through `hooks` first. Returns the
    /// number of entries whose refresh was refused (their stored value is
    /// sent, as the CAN service does).
    pub fn sample<H: ObjectHooks + ?Sized>(&self, od: &mut ObjectDictionary, hooks: &mut H) -> (u64, u32) {
        let mut events = EventQueue::new();
        let mut buf = [0u8; MAX_DATA_LEN];
        sample(&self.plan, od, hooks, 0, &mut events, &mut buf);
        (u64::from_le_bytes(buf), count(&mut events))
    }

    /// Writes the mapped values of `data` (an RxPDO's bits, least
    /// significant first) through `hooks` as a received PDO does: plain
    /// entries in place, the others by `write_local`. Returns the number
    /// of entries the write path refused.
    pub fn apply<H: ObjectHooks + ?Sized>(&self, od: &mut ObjectDictionary, hooks: &mut H, data: u64) -> u32 {
        let mut events = EventQueue::new();
        apply(&self.plan, od, hooks, 0, &mut events, &data.to_le_bytes());
        count(&mut events)
    }
}

fn count(events: &mut EventQueue) -> u32 {
    let mut n = events.lost;
    while let Some(e) = events.pop() {
        if matches!(e, PdoEvent::RpdoWriteFailed { .. } | PdoEvent::TpdoReadFailed { .. }) {
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_entry;
    use drivebus_od::{Access, DataType, NoHooks, Object, Value};

    fn od() -> ObjectDictionary {
        let mut od = ObjectDictionary::new();
        for (i, t, v) in [
            (0x6040u16, DataType::Unsigned16, Value::U16(0)),
            (0x607A, DataType::Integer32, Value::I32(0)),
            (0x6060, DataType::Integer8, Value::I8(0)),
        ] {
            let mut o = Object::var(i, "x", t, Access::Rw, v);
            o.subs_mut()[0].pdo_mappable = true;
            od.insert(o);
        }
        od
    }

    #[test]
    fn applies_and_samples_like_the_can_service() {
        let mut od = od();
        let cfg = PdoConfig { granularity: crate::Granularity::Bit, ..PdoConfig::default() };
        let e = [map_entry(0x6040, 0, 16), map_entry(0x607A, 0, 32), map_entry(0x6060, 0, 8)];
        let rx = MappedPdo::resolve(&od, &cfg, PdoKind::Rpdo, &e).unwrap();
        assert_eq!(rx.bits(), 56);
        assert_eq!(rx.apply(&mut od, &mut NoHooks, 0x08_FFFF_FFFE_000F), 0);
        assert_eq!(od.get_u32(0x6040, 0), Some(0x000F));
        assert_eq!(od.get_i64(0x607A, 0), Some(-2));
        assert_eq!(od.get_i64(0x6060, 0), Some(8));
        let tx = MappedPdo::resolve(&od, &cfg, PdoKind::Tpdo, &e).unwrap();
        assert_eq!(tx.sample(&mut od, &mut NoHooks), (0x08_FFFF_FFFE_000F, 0));
    }

    #[test]
    fn refuses_what_a_mapping_write_refuses() {
        let od = od();
        let cfg = PdoConfig::default();
        let too_long = [map_entry(0x607A, 0, 32), map_entry(0x607A, 0, 32), map_entry(0x6040, 0, 16)];
        assert_eq!(MappedPdo::resolve(&od, &cfg, PdoKind::Rpdo, &too_long), Err(SdoAbort::PDO_TOO_LONG));
        assert_eq!(
            MappedPdo::resolve(&od, &cfg, PdoKind::Rpdo, &[map_entry(0x6041, 0, 16)]),
            Err(SdoAbort::NO_OBJECT)
        );
        assert_eq!(
            MappedPdo::resolve(&od, &cfg, PdoKind::Rpdo, &[map_entry(0x6040, 0, 8)]),
            Err(SdoAbort::NOT_MAPPABLE)
        );
    }
}
