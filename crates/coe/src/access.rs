//! How the mailbox servers reach the device's objects.
//!
//! The CoE server never touches values itself: it reads and writes through
//! [`ObjectAccess`], so the device's own rules (hooks, ESM-dependent write
//! permissions, PDO assignment procedures) decide, and their [`SdoAbort`]
//! goes to the master unchanged — the same code the CAN SDO server sends.

use drivebus_od::{Access, ObjectDictionary, ObjectHooks, PersistGroup, SdoAbort, SubObject};

/// The device behind the CoE server.
pub trait ObjectAccess {
    /// The dictionary, for metadata: object codes, types, access, names,
    /// limits, defaults and PDO mappability (SDO Information, complete
    /// access layout, pre-checks before a segmented download).
    fn dictionary(&self) -> &ObjectDictionary;

    /// A checked read through the device's read path (access, read hook).
    fn read(&mut self, index: u16, sub: u8) -> Result<&[u8], SdoAbort>;

    /// A checked write through the device's write path (access, type,
    /// limits, write hook, the device's rules).
    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort>;

    /// The ETG.1000.6 "object access" word of an entry, as SDO Information
    /// reports it and as the OD lists filter on (see [`access_bits`]).
    /// The default derives it from the dictionary; a device whose rights
    /// depend on the ESM state (e.g. PDO assignment writable only in
    /// PRE-OP) overrides it.
    fn object_access(&self, index: u16, sub: u8) -> u16 {
        self.dictionary().get(index, sub).map_or(0, default_object_access)
    }
}

/// Bits of the ETG.1000.6 SDO Information "object access" word.
pub mod access_bits {
    /// Readable in PRE-OP.
    pub const READ_PREOP: u16 = 0x0001;
    /// Readable in SAFE-OP.
    pub const READ_SAFEOP: u16 = 0x0002;
    /// Readable in OP.
    pub const READ_OP: u16 = 0x0004;
    /// Readable in every state with a mailbox.
    pub const READ: u16 = READ_PREOP | READ_SAFEOP | READ_OP;
    /// Writable in PRE-OP.
    pub const WRITE_PREOP: u16 = 0x0008;
    /// Writable in SAFE-OP.
    pub const WRITE_SAFEOP: u16 = 0x0010;
    /// Writable in OP.
    pub const WRITE_OP: u16 = 0x0020;
    /// Writable in every state with a mailbox.
    pub const WRITE: u16 = WRITE_PREOP | WRITE_SAFEOP | WRITE_OP;
    /// Mappable into an RxPDO.
    pub const RXPDO: u16 = 0x0040;
    /// Mappable into a TxPDO.
    pub const TXPDO: u16 = 0x0080;
    /// Stored for device replacement (OD list type 4).
    pub const BACKUP: u16 = 0x0100;
    /// Usable as a startup parameter (OD list type 5).
    pub const SETTINGS: u16 = 0x0200;
}

/// The object access word a plain dictionary entry implies: read/write in
/// every mailbox state by its access type; RxPDO-mappable if mappable and
/// writable (TxPDO: and readable), `rww`/`rwr` naming the one direction;
/// backup when 1010h stores it; settings when it is also writable.
pub fn default_object_access(s: &SubObject) -> u16 {
    use access_bits::*;
    let mut bits = 0;
    if s.access.readable() {
        bits |= READ;
    }
    if s.access.writable() {
        bits |= WRITE;
    }
    if s.pdo_mappable {
        bits |= match s.access {
            Access::Rww | Access::Wo => RXPDO,
            Access::Rwr | Access::Ro | Access::Const => TXPDO,
            Access::Rw => RXPDO | TXPDO,
        };
    }
    if s.persist != PersistGroup::Volatile {
        bits |= BACKUP;
        if s.access.writable() {
            bits |= SETTINGS;
        }
    }
    bits
}

/// A borrowed dictionary and its hooks, as a node holds them.
pub struct OdAccess<'a, H: ?Sized> {
    /// The dictionary.
    pub od: &'a mut ObjectDictionary,
    /// The hooks its hooked entries go through.
    pub hooks: &'a mut H,
}

impl<'a, H: ObjectHooks + ?Sized> OdAccess<'a, H> {
    /// Pair a dictionary with its hooks.
    pub fn new(od: &'a mut ObjectDictionary, hooks: &'a mut H) -> Self {
        OdAccess { od, hooks }
    }
}

impl<H: ObjectHooks + ?Sized> ObjectAccess for OdAccess<'_, H> {
    fn dictionary(&self) -> &ObjectDictionary {
        self.od
    }
    fn read(&mut self, index: u16, sub: u8) -> Result<&[u8], SdoAbort> {
        self.od.read(self.hooks, index, sub)
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.od.write(self.hooks, index, sub, data)
    }
}

/// An owned dictionary with its hooks (tests, simple devices).
impl<H: ObjectHooks> ObjectAccess for (ObjectDictionary, H) {
    fn dictionary(&self) -> &ObjectDictionary {
        &self.0
    }
    fn read(&mut self, index: u16, sub: u8) -> Result<&[u8], SdoAbort> {
        self.0.read(&mut self.1, index, sub)
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.0.write(&mut self.1, index, sub, data)
    }
}

#[cfg(test)]
mod tests {
    use super::access_bits::*;
    use super::*;
    use drivebus_od::{DataType, NoHooks, Object, Value};

    #[test]
    fn access_word_follows_the_dictionary() {
        let ro = SubObject::new(0, "x", DataType::Unsigned32, Access::Ro, Value::U32(0));
        assert_eq!(default_object_access(&ro), READ);
        let mut rw = SubObject::new(0, "x", DataType::Unsigned16, Access::Rw, Value::U16(0)).mappable();
        rw.persist = PersistGroup::Application;
        assert_eq!(default_object_access(&rw), READ | WRITE | RXPDO | TXPDO | BACKUP | SETTINGS);
        let rww = SubObject::new(0, "x", DataType::Unsigned16, Access::Rww, Value::U16(0)).mappable();
        assert_eq!(default_object_access(&rww), READ | WRITE | RXPDO);
        let rwr = SubObject::new(0, "x", DataType::Unsigned16, Access::Rwr, Value::U16(0)).mappable();
        assert_eq!(default_object_access(&rwr), READ | WRITE | TXPDO);
    }

    #[test]
    fn adapters_go_through_the_checked_paths() {
        let mut od = ObjectDictionary::new();
        od.insert(Object::var(0x1000, "Device type", DataType::Unsigned32, Access::Ro, Value::U32(0x60192)));
        od.insert(Object::var(0x2000, "x", DataType::Unsigned16, Access::Rw, Value::U16(1)));
        let mut pair = (od.clone(), NoHooks);
        assert_eq!(pair.read(0x1000, 0), Ok(&[0x92, 0x01, 0x06, 0x00][..]));
        assert_eq!(pair.write(0x1000, 0, &[0; 4]), Err(SdoAbort::WRITE_READ_ONLY));
        assert_eq!(pair.write(0x2000, 0, &[1]), Err(SdoAbort::DATA_TOO_SHORT));
        let mut hooks = NoHooks;
        let mut a = OdAccess::new(&mut od, &mut hooks);
        a.write(0x2000, 0, &[7, 0]).unwrap();
        assert_eq!(a.read(0x2000, 0), Ok(&[7, 0][..]));
        assert_eq!(a.object_access(0x2000, 0), READ | WRITE | BACKUP | SETTINGS);
        assert_eq!(a.object_access(0x3000, 0), 0);
    }
}
