//! The device identity (CiA 301 object 1018h), which is also the CiA 305
//! LSS address and the EtherCAT SII/ESI identity (vendor, product,
//! revision, serial). Kept here, in the crate every bus layer already
//! depends on, so node, LSS, SII and ESI share one type.

/// The four entries of the identity object 1018h.
///
/// The field order is the LSS address order (vendor-ID, product code,
/// revision, serial number): `Ord` compares in that order, which is the
/// order the LSS services and fastscan walk the 128-bit address.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Identity {
    /// 1018h:01 vendor-ID.
    pub vendor_id: u32,
    /// 1018h:02 product code.
    pub product_code: u32,
    /// 1018h:03 revision number.
    pub revision: u32,
    /// 1018h:04 serial number.
    pub serial: u32,
}

impl Identity {
    /// The identity from its four parts.
    pub const fn new(vendor_id: u32, product_code: u32, revision: u32, serial: u32) -> Self {
        Identity { vendor_id, product_code, revision, serial }
    }

    /// The part at 1018h sub-index `sub` (1..=4), `None` for another sub.
    #[inline]
    pub const fn sub(&self, sub: u8) -> Option<u32> {
        match sub {
            1 => Some(self.vendor_id),
            2 => Some(self.product_code),
            3 => Some(self.revision),
            4 => Some(self.serial),
            _ => None,
        }
    }

    /// Set the part at 1018h sub-index `sub` (1..=4); false (nothing
    /// changed) for another sub.
    #[inline]
    pub fn set_sub(&mut self, sub: u8, value: u32) -> bool {
        match sub {
            1 => self.vendor_id = value,
            2 => self.product_code = value,
            3 => self.revision = value,
            4 => self.serial = value,
            _ => return false,
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sub_indices_name_the_four_parts() {
        let mut id = Identity::new(1, 2, 3, 4);
        assert_eq!([1, 2, 3, 4, 5].map(|s| id.sub(s)), [Some(1), Some(2), Some(3), Some(4), None]);
        assert!(id.set_sub(4, 40));
        assert!(!id.set_sub(0, 9));
        assert_eq!(id, Identity::new(1, 2, 3, 40));
    }

    #[test]
    fn orders_like_the_lss_address() {
        // vendor first, serial last: a higher serial never outranks a
        // higher vendor-ID.
        assert!(Identity::new(1, 9, 9, 9) < Identity::new(2, 0, 0, 0));
        assert!(Identity::new(1, 2, 3, 4) < Identity::new(1, 2, 3, 5));
    }
}
