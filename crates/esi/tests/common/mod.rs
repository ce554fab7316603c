//! Descriptions of the personalities, as the integrator will build them:
//! the EDS read into a dictionary, the facts from `ProfileInfo`.
#![allow(dead_code)]

use drivebus_eds::Eds;
use drivebus_esi::{DeviceFacts, SlaveDescription, ipos};
use drivebus_od::ObjectDictionary;
use drivebus_personality::{Profile, Transport};

/// Node-ID the EDS `$NODEID` values are evaluated with.
pub const NODE_ID: u8 = 1;

/// The facts of a personality: the iPOS twin's own, or drivebus's
/// default layout with the profile's identity.
pub fn facts(p: Profile) -> DeviceFacts {
    let i = p.info();
    let (vendor, product) = (i.vendor_id.unwrap_or(0), i.product_code.unwrap_or(0));
    match i.transport {
        Transport::EtherCatCoe => ipos::facts(vendor, i.vendor_name, product, i.product_name),
        Transport::Can => {
            DeviceFacts::new(vendor, i.vendor_name, product, i.revision.unwrap_or(0), i.product_name)
        }
    }
}

/// The EDS, its dictionary and the description built from them.
pub fn build(p: Profile) -> (SlaveDescription, ObjectDictionary, Eds) {
    let eds = p.parse_eds().eds;
    let od = drivebus_eds::to_od(&eds, NODE_ID).expect("the shipped EDS converts");
    (SlaveDescription::new(&od, &facts(p)), od, eds)
}

/// Written and read back; the serial number is not in an ESI.
pub fn round_trip(d: &SlaveDescription) -> SlaveDescription {
    let xml = drivebus_esi::write(d);
    let mut back = drivebus_esi::read(&xml).unwrap_or_else(|e| panic!("{e}"));
    back.serial = d.serial;
    back
}
