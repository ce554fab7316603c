//! The CoE server's way into the drive: [`ObjectAccess`] over the node's
//! read and write path (`Node::read_object` / `Node::write_object`, the
//! path the CAN SDO server takes), and the access word SDO Information
//! reports with the EtherCAT state rules.

use drivebus_can::{Frame, Instant};
use drivebus_coe::{ObjectAccess, access_bits, default_object_access};
use drivebus_od::{ObjectDictionary, SdoAbort};
use drivebus_personality::PersonalityDevice;
use drivebus_personality::ecat::rules;

/// The drive for one mailbox request.
pub struct DriveAccess<'a> {
    /// The drive.
    pub dev: &'a mut PersonalityDevice,
    /// When the request came.
    pub now: Instant,
    /// CAN frames the node produced (EMCY), for the EtherCAT layer to turn
    /// into CoE emergencies.
    pub frames: &'a mut Vec<Frame>,
}

impl ObjectAccess for DriveAccess<'_> {
    fn dictionary(&self) -> &ObjectDictionary {
        self.dev.node.od()
    }

    fn read(&mut self, index: u16, sub: u8) -> Result<&[u8], SdoAbort> {
        self.dev.read_object(index, sub, self.now)
    }

    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.dev.write_object(index, sub, data, self.now, self.frames)
    }

    fn object_access(&self, index: u16, sub: u8) -> u16 {
        object_access(self.dev.node.od(), index, sub)
    }
}

/// The ETG.1000.6 access word of an entry: the dictionary's, narrowed to
/// PRE-OP for what the EtherCAT rules allow only there.
pub fn object_access(od: &ObjectDictionary, index: u16, sub: u8) -> u16 {
    let bits = od.get(index, sub).map_or(0, default_object_access);
    if rules::preop_only(index, sub) && bits & access_bits::WRITE != 0 {
        (bits & !access_bits::WRITE) | access_bits::WRITE_PREOP
    } else {
        bits
    }
}
