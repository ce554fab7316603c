//! The sync manager objects of a CoE dictionary: 1C00h communication
//! types, 1C12h/1C13h PDO assignment (ETG.1000.6 §5.6.7.4) and 1C32h/1C33h
//! synchronisation parameters (ETG.1020 "Synchronization").

use super::EcatFacts;
use drivebus_od::{Access, DataType, Object, ObjectDictionary, SubObject, Value};

/// 1C32h/1C33h:04 "synchronization types supported": bit 0 free run, bit 1
/// synchronous with the SM event, bits 2–4 = 001b DC SYNC0 (ETG.1020).
pub const SYNC_MODES_SUPPORTED: u16 = 0x0007;

/// 1C32h/1C33h sub-indices (ETG.1020).
pub mod sub {
    /// Synchronization type: 0 free run, 1 SM event, 2 DC SYNC0 (1C33h:
    /// 34 = synchronous with the SM2 event).
    pub const SYNC_TYPE: u8 = 0x01;
    /// Cycle time \[ns\].
    pub const CYCLE_TIME: u8 = 0x02;
    /// Shift time \[ns\].
    pub const SHIFT_TIME: u8 = 0x03;
    /// Synchronization types supported.
    pub const SUPPORTED: u8 = 0x04;
    /// Minimum cycle time \[ns\].
    pub const MIN_CYCLE: u8 = 0x05;
    /// Calc and copy time \[ns\].
    pub const CALC_COPY: u8 = 0x06;
    /// Get cycle time: 0 stop, 1 measure, 2 reset the error counters.
    pub const GET_CYCLE: u8 = 0x08;
    /// Delay time \[ns\].
    pub const DELAY: u8 = 0x09;
    /// SYNC0 cycle time \[ns\].
    pub const SYNC0_CYCLE: u8 = 0x0A;
    /// SM event missed counter.
    pub const SM_EVENT_MISSED: u8 = 0x0B;
    /// Cycle time too small counter.
    pub const CYCLE_TOO_SMALL: u8 = 0x0C;
    /// Sync error (the last cycle had one).
    pub const SYNC_ERROR: u8 = 0x20;
}

fn u8s(sub: u8, name: &'static str, access: Access, v: u8) -> SubObject {
    SubObject::new(sub, name, DataType::Unsigned8, access, Value::U8(v))
}

fn u16s(sub: u8, name: &'static str, access: Access, v: u16) -> SubObject {
    SubObject::new(sub, name, DataType::Unsigned16, access, Value::U16(v))
}

fn u32s(sub: u8, name: &'static str, access: Access, v: u32) -> SubObject {
    SubObject::new(sub, name, DataType::Unsigned32, access, Value::U32(v))
}

fn assignment(index: u16, name: &'static str, slots: u8, assigned: &[u16]) -> Object {
    // Sub 0 is written in every assignment procedure (iPOS §2.4 step 7).
    let mut o = Object::record(index, name).with_sub(u8s(
        0,
        "Number of assigned PDOs",
        Access::Rw,
        assigned.len() as u8,
    ));
    for n in 1..=slots {
        let v = assigned.get(usize::from(n) - 1).copied().unwrap_or(0);
        o = o.with_sub(u16s(n, "PDO mapping object index of assigned PDO", Access::Rw, v));
    }
    o
}

fn sync_parameter(index: u16, name: &'static str, facts: &EcatFacts, sync_type: u16) -> Object {
    use Access::{Ro, Rw};
    use sub::*;
    Object::record(index, name)
        .with_sub(u8s(0, "Number of sub indices", Access::Const, SYNC_ERROR))
        .with_sub(u16s(SYNC_TYPE, "Synchronization type", Rw, sync_type))
        .with_sub(u32s(CYCLE_TIME, "Cycle time", Rw, facts.min_cycle_ns))
        .with_sub(u32s(SHIFT_TIME, "Shift time", Rw, 0))
        .with_sub(u16s(SUPPORTED, "Synchronization types supported", Ro, SYNC_MODES_SUPPORTED))
        .with_sub(u32s(MIN_CYCLE, "Minimum cycle time", Ro, facts.min_cycle_ns))
        .with_sub(u32s(CALC_COPY, "Calc and copy time", Ro, 0))
        .with_sub(u16s(GET_CYCLE, "Get cycle time", Rw, 0))
        .with_sub(u32s(DELAY, "Delay time", Ro, 0))
        .with_sub(u32s(SYNC0_CYCLE, "Sync0 cycle time", Ro, 0))
        .with_sub(u16s(SM_EVENT_MISSED, "SM event missed", Ro, 0))
        .with_sub(u16s(CYCLE_TOO_SMALL, "Cycle time too small", Ro, 0))
        .with_sub(SubObject::new(SYNC_ERROR, "Sync error", DataType::Boolean, Ro, Value::Bool(false)))
}

/// Puts the sync manager objects into an EtherCAT dictionary: 1C00h,
/// 1C12h and 1C13h where the profile's EDS lacks them (one assignment slot
/// per mapping object, the profile's default assignment), 1C32h and 1C33h
/// always (the iPOS manual does not document them, §A.5 of the inventory;
/// masters read them, ethercrab's DC set-up and TwinCAT's among them). The
/// synchronisation parameters are volatile: the slave derives them from
/// the ESC's DC registers at every PRE-OP → SAFE-OP.
pub fn sync_objects(od: &mut ObjectDictionary, facts: &EcatFacts) {
    if od.object(0x1C00).is_none() {
        let mut o = Object::record(0x1C00, "Sync manager communication type").with_sub(u8s(
            0,
            "Number of used sync manager channels",
            Access::Const,
            4,
        ));
        for (n, t) in [1u8, 2, 3, 4].into_iter().enumerate() {
            o = o.with_sub(u8s(n as u8 + 1, "Communication type", Access::Const, t));
        }
        od.insert(o);
    }
    let count = |range: core::ops::RangeInclusive<u16>| {
        od.objects().iter().filter(|o| range.contains(&o.index)).count().clamp(1, 254) as u8
    };
    let (rx, tx) = (count(0x1600..=0x17FF), count(0x1A00..=0x1BFF));
    if od.object(0x1C12).is_none() {
        od.insert(assignment(0x1C12, "Sync manager 2 PDO assignment", rx, facts.rx_assigned));
    }
    if od.object(0x1C13).is_none() {
        od.insert(assignment(0x1C13, "Sync manager 3 PDO assignment", tx, facts.tx_assigned));
    }
    // SM-synchronous until the master activates DC (the slave applies the
    // outputs at the SM2 event and latches the inputs for SM3).
    od.insert(sync_parameter(0x1C32, "SM output parameter", facts, 1));
    od.insert(sync_parameter(0x1C33, "SM input parameter", facts, 0x22));
    for index in [0x1C32u16, 0x1C33] {
        if let Some(o) = od.object(index) {
            let subs: alloc::vec::Vec<u8> = o.subs().iter().map(|s| s.sub).collect();
            for s in subs {
                if let Some(e) = od.get_mut(index, s) {
                    e.persist = drivebus_od::PersistGroup::Volatile;
                }
            }
        }
    }
}

extern crate alloc;
