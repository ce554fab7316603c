//! LSS frame codec (CiA 305 v3.0.0): one enum per direction, each with
//! `to_frame` / `from_frame`. Figure numbers refer to CiA 305 v3.0.0.
//!
//! Every LSS frame has DLC 8; `from_frame` ignores frames with another
//! COB-ID, an RTR bit or a DLC other than 8, and unknown command specifiers.
//! Reserved bytes are written as 0 and not checked on receipt.

use drivebus_can::{Frame, Identity};

use crate::{LssMode, MASTER_TO_SLAVE, SLAVE_TO_MASTER};

/// Command specifiers (byte 0 of every LSS frame).
pub mod cs {
    /// Switch state global (Fig. 31), master → slave, no response.
    pub const SWITCH_STATE_GLOBAL: u8 = 0x04;
    /// Configure node-ID (Fig. 33), request and response.
    pub const CONFIGURE_NODE_ID: u8 = 0x11;
    /// Configure bit timing parameters (Fig. 34), request and response.
    pub const CONFIGURE_BIT_TIMING: u8 = 0x13;
    /// Activate bit timing parameters (Fig. 35), no response.
    pub const ACTIVATE_BIT_TIMING: u8 = 0x15;
    /// Store configuration (Fig. 36), request and response.
    pub const STORE_CONFIGURATION: u8 = 0x17;
    /// Switch state selective, vendor-ID (Fig. 32).
    pub const SWITCH_SELECTIVE_VENDOR: u8 = 0x40;
    /// Switch state selective, product code.
    pub const SWITCH_SELECTIVE_PRODUCT: u8 = 0x41;
    /// Switch state selective, revision number.
    pub const SWITCH_SELECTIVE_REVISION: u8 = 0x42;
    /// Switch state selective, serial number.
    pub const SWITCH_SELECTIVE_SERIAL: u8 = 0x43;
    /// Switch state selective response, slave → master.
    pub const SWITCH_SELECTIVE_RESPONSE: u8 = 0x44;
    /// Identify remote slave, vendor-ID (Fig. 42).
    pub const IDENTIFY_VENDOR: u8 = 0x46;
    /// Identify remote slave, product code.
    pub const IDENTIFY_PRODUCT: u8 = 0x47;
    /// Identify remote slave, revision number low bound.
    pub const IDENTIFY_REVISION_LOW: u8 = 0x48;
    /// Identify remote slave, revision number high bound.
    pub const IDENTIFY_REVISION_HIGH: u8 = 0x49;
    /// Identify remote slave, serial number low bound.
    pub const IDENTIFY_SERIAL_LOW: u8 = 0x4A;
    /// Identify remote slave, serial number high bound.
    pub const IDENTIFY_SERIAL_HIGH: u8 = 0x4B;
    /// Identify non-configured remote slave (Fig. 44).
    pub const IDENTIFY_NON_CONFIGURED: u8 = 0x4C;
    /// Identify slave (Fig. 43): answer to identify remote slave and fastscan.
    pub const IDENTIFY_SLAVE: u8 = 0x4F;
    /// Identify non-configured slave (Fig. 45).
    pub const IDENTIFY_NON_CONFIGURED_SLAVE: u8 = 0x50;
    /// LSS fastscan (Fig. 46).
    pub const FASTSCAN: u8 = 0x51;
    /// Inquire identity vendor-ID (Fig. 37), request and response.
    pub const INQUIRE_VENDOR: u8 = 0x5A;
    /// Inquire identity product code (Fig. 38).
    pub const INQUIRE_PRODUCT: u8 = 0x5B;
    /// Inquire identity revision number (Fig. 39).
    pub const INQUIRE_REVISION: u8 = 0x5C;
    /// Inquire identity serial number (Fig. 40).
    pub const INQUIRE_SERIAL: u8 = 0x5D;
    /// Inquire node-ID (Fig. 41), request and response.
    pub const INQUIRE_NODE_ID: u8 = 0x5E;
}

/// Error codes of the configure / store responses (byte 1). Byte 2 carries
/// an implementation-specific code when byte 1 is [`err::IMPLEMENTATION_SPECIFIC`].
pub mod err {
    /// Protocol successfully completed.
    pub const OK: u8 = 0;
    /// Configure node-ID: node-ID out of range.
    pub const NODE_ID_OUT_OF_RANGE: u8 = 1;
    /// Configure bit timing: bit timing (table or index) not supported.
    pub const BIT_TIMING_NOT_SUPPORTED: u8 = 1;
    /// Store configuration: not supported.
    pub const STORE_NOT_SUPPORTED: u8 = 1;
    /// Store configuration: storage media access error.
    pub const STORE_ACCESS_ERROR: u8 = 2;
    /// Implementation-specific error, detail in byte 2.
    pub const IMPLEMENTATION_SPECIFIC: u8 = 0xFF;
}

/// Value of the fastscan `BitChecked` byte that resets the scan and asks
/// every unconfigured slave to confirm its presence.
pub const FASTSCAN_CONFIRM: u8 = 0x80;

/// One of the four 32-bit parts of the LSS address; the discriminant is the
/// fastscan `LSSSub` value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LssField {
    /// Vendor-ID (1018h:01).
    Vendor = 0,
    /// Product code (1018h:02).
    Product = 1,
    /// Revision number (1018h:03).
    Revision = 2,
    /// Serial number (1018h:04).
    Serial = 3,
}

impl LssField {
    /// The four fields in address (and fastscan) order.
    pub const ALL: [LssField; 4] =
        [LssField::Vendor, LssField::Product, LssField::Revision, LssField::Serial];

    /// The field of a fastscan `LSSSub`/`LSSNext` value.
    #[inline]
    pub const fn from_index(i: u8) -> Option<LssField> {
        match i {
            0 => Some(LssField::Vendor),
            1 => Some(LssField::Product),
            2 => Some(LssField::Revision),
            3 => Some(LssField::Serial),
            _ => None,
        }
    }

    /// The fastscan `LSSSub` value.
    #[inline]
    pub const fn index(self) -> u8 {
        self as u8
    }

    /// This field's part of an LSS address.
    #[inline]
    pub const fn get(self, addr: &Identity) -> u32 {
        match self {
            LssField::Vendor => addr.vendor_id,
            LssField::Product => addr.product_code,
            LssField::Revision => addr.revision,
            LssField::Serial => addr.serial,
        }
    }

    /// Set this field's part of an LSS address.
    #[inline]
    pub fn set(self, addr: &mut Identity, value: u32) {
        match self {
            LssField::Vendor => addr.vendor_id = value,
            LssField::Product => addr.product_code = value,
            LssField::Revision => addr.revision = value,
            LssField::Serial => addr.serial = value,
        }
    }
}

/// One frame of the six-frame "identify remote slave" request, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum IdentifyStep {
    /// Vendor-ID, must match exactly (46h).
    Vendor = 0,
    /// Product code, must match exactly (47h).
    Product = 1,
    /// Lowest revision number (48h).
    RevisionLow = 2,
    /// Highest revision number (49h).
    RevisionHigh = 3,
    /// Lowest serial number (4Ah).
    SerialLow = 4,
    /// Highest serial number (4Bh): the slave answers after this one.
    SerialHigh = 5,
}

impl IdentifyStep {
    const ALL: [IdentifyStep; 6] = [
        IdentifyStep::Vendor,
        IdentifyStep::Product,
        IdentifyStep::RevisionLow,
        IdentifyStep::RevisionHigh,
        IdentifyStep::SerialLow,
        IdentifyStep::SerialHigh,
    ];
}

/// A request, master → slave (7E5h).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LssRequest {
    /// Switch every slave to `mode` (04h).
    SwitchStateGlobal(LssMode),
    /// One of the four switch state selective frames (40h..43h).
    SwitchStateSelective {
        /// Which part of the address this frame carries.
        field: LssField,
        /// Its value.
        value: u32,
    },
    /// Configure the pending node-ID (11h).
    ConfigureNodeId(u8),
    /// Configure the pending bit timing (13h).
    ConfigureBitTiming {
        /// Table selector, 0 = standard CiA table.
        table: u8,
        /// Index in the table.
        index: u8,
    },
    /// Activate the pending bit timing after `delay_ms` (15h).
    ActivateBitTiming {
        /// Switch delay in ms, applied before and after the switch.
        delay_ms: u16,
    },
    /// Store the pending node-ID and bit timing (17h).
    StoreConfiguration,
    /// Inquire one part of the LSS address (5Ah..5Dh).
    InquireIdentity(LssField),
    /// Inquire the node-ID (5Eh).
    InquireNodeId,
    /// One of the six identify remote slave frames (46h..4Bh).
    IdentifyRemoteSlave {
        /// Which bound this frame carries.
        step: IdentifyStep,
        /// Its value.
        value: u32,
    },
    /// Identify non-configured remote slave (4Ch).
    IdentifyNonConfigured,
    /// Fastscan (51h); the fields are raw so a slave can ignore invalid ones.
    FastScan {
        /// The IDNumber being determined.
        id_number: u32,
        /// Lowest bit checked (0..=31) or [`FASTSCAN_CONFIRM`].
        bit_checked: u8,
        /// Part of the address being checked (0..=3).
        sub: u8,
        /// Part the slave checks next when this one completes (0..=3).
        next: u8,
    },
}

/// A response, slave → master (7E4h).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LssResponse {
    /// A slave matched the selective address and is in configuration (44h).
    SwitchStateSelective,
    /// Answer to configure node-ID (11h); `error` is one of [`err`].
    ConfigureNodeId {
        /// Error code, 0 = success.
        error: u8,
        /// Implementation-specific error when `error` is FFh.
        spec_error: u8,
    },
    /// Answer to configure bit timing (13h).
    ConfigureBitTiming {
        /// Error code, 0 = success.
        error: u8,
        /// Implementation-specific error when `error` is FFh.
        spec_error: u8,
    },
    /// Answer to store configuration (17h).
    StoreConfiguration {
        /// Error code, 0 = success.
        error: u8,
        /// Implementation-specific error when `error` is FFh.
        spec_error: u8,
    },
    /// Answer to an inquire identity (5Ah..5Dh).
    Identity {
        /// Which part was inquired.
        field: LssField,
        /// Its value.
        value: u32,
    },
    /// Answer to inquire node-ID (5Eh).
    NodeId(u8),
    /// Identify slave (4Fh): a slave is in the identify range or matched a fastscan step.
    IdentifySlave,
    /// Identify non-configured slave (50h).
    IdentifyNonConfiguredSlave,
}

#[inline]
fn u32_at(d: &[u8; 8]) -> u32 {
    u32::from_le_bytes([d[1], d[2], d[3], d[4]])
}

#[inline]
fn with_u32(cs: u8, v: u32) -> [u8; 8] {
    let b = v.to_le_bytes();
    [cs, b[0], b[1], b[2], b[3], 0, 0, 0]
}

/// The 8 data bytes of an LSS frame on `cob_id`, or `None` if it is not one.
#[inline]
fn lss_bytes(frame: &Frame, cob_id: u16) -> Option<&[u8; 8]> {
    if frame.std_id() != Some(cob_id) || frame.is_rtr() || frame.len() != 8 {
        return None;
    }
    Some(frame.raw_data())
}

impl LssRequest {
    /// The 8 data bytes of the request.
    pub fn to_bytes(&self) -> [u8; 8] {
        match *self {
            LssRequest::SwitchStateGlobal(mode) => [cs::SWITCH_STATE_GLOBAL, mode as u8, 0, 0, 0, 0, 0, 0],
            LssRequest::SwitchStateSelective { field, value } => {
                with_u32(cs::SWITCH_SELECTIVE_VENDOR + field.index(), value)
            }
            LssRequest::ConfigureNodeId(id) => [cs::CONFIGURE_NODE_ID, id, 0, 0, 0, 0, 0, 0],
            LssRequest::ConfigureBitTiming { table, index } => {
                [cs::CONFIGURE_BIT_TIMING, table, index, 0, 0, 0, 0, 0]
            }
            LssRequest::ActivateBitTiming { delay_ms } => {
                let d = delay_ms.to_le_bytes();
                [cs::ACTIVATE_BIT_TIMING, d[0], d[1], 0, 0, 0, 0, 0]
            }
            LssRequest::StoreConfiguration => [cs::STORE_CONFIGURATION, 0, 0, 0, 0, 0, 0, 0],
            LssRequest::InquireIdentity(field) => [cs::INQUIRE_VENDOR + field.index(), 0, 0, 0, 0, 0, 0, 0],
            LssRequest::InquireNodeId => [cs::INQUIRE_NODE_ID, 0, 0, 0, 0, 0, 0, 0],
            LssRequest::IdentifyRemoteSlave { step, value } => {
                with_u32(cs::IDENTIFY_VENDOR + step as u8, value)
            }
            LssRequest::IdentifyNonConfigured => [cs::IDENTIFY_NON_CONFIGURED, 0, 0, 0, 0, 0, 0, 0],
            LssRequest::FastScan { id_number, bit_checked, sub, next } => {
                let b = id_number.to_le_bytes();
                [cs::FASTSCAN, b[0], b[1], b[2], b[3], bit_checked, sub, next]
            }
        }
    }

    /// The request as a frame on 7E5h.
    #[inline]
    pub fn to_frame(&self) -> Frame {
        Frame::new8(MASTER_TO_SLAVE, self.to_bytes())
    }

    /// Decode a frame received on 7E5h; `None` for anything that is not a
    /// well-formed LSS request (including an undefined switch mode).
    pub fn from_frame(frame: &Frame) -> Option<LssRequest> {
        let d = lss_bytes(frame, MASTER_TO_SLAVE)?;
        let req = match d[0] {
            cs::SWITCH_STATE_GLOBAL => LssRequest::SwitchStateGlobal(LssMode::from_byte(d[1])?),
            c @ cs::SWITCH_SELECTIVE_VENDOR..=cs::SWITCH_SELECTIVE_SERIAL => {
                LssRequest::SwitchStateSelective {
                    field: LssField::from_index(c - cs::SWITCH_SELECTIVE_VENDOR)?,
                    value: u32_at(d),
                }
            }
            cs::CONFIGURE_NODE_ID => LssRequest::ConfigureNodeId(d[1]),
            cs::CONFIGURE_BIT_TIMING => LssRequest::ConfigureBitTiming { table: d[1], index: d[2] },
            cs::ACTIVATE_BIT_TIMING => {
                LssRequest::ActivateBitTiming { delay_ms: u16::from_le_bytes([d[1], d[2]]) }
            }
            cs::STORE_CONFIGURATION => LssRequest::StoreConfiguration,
            c @ cs::INQUIRE_VENDOR..=cs::INQUIRE_SERIAL => {
                LssRequest::InquireIdentity(LssField::from_index(c - cs::INQUIRE_VENDOR)?)
            }
            cs::INQUIRE_NODE_ID => LssRequest::InquireNodeId,
            c @ cs::IDENTIFY_VENDOR..=cs::IDENTIFY_SERIAL_HIGH => LssRequest::IdentifyRemoteSlave {
                step: *IdentifyStep::ALL.get(usize::from(c - cs::IDENTIFY_VENDOR))?,
                value: u32_at(d),
            },
            cs::IDENTIFY_NON_CONFIGURED => LssRequest::IdentifyNonConfigured,
            cs::FASTSCAN => {
                LssRequest::FastScan { id_number: u32_at(d), bit_checked: d[5], sub: d[6], next: d[7] }
            }
            _ => return None,
        };
        Some(req)
    }
}

impl LssResponse {
    /// The 8 data bytes of the response.
    pub fn to_bytes(&self) -> [u8; 8] {
        match *self {
            LssResponse::SwitchStateSelective => [cs::SWITCH_SELECTIVE_RESPONSE, 0, 0, 0, 0, 0, 0, 0],
            LssResponse::ConfigureNodeId { error, spec_error } => {
                [cs::CONFIGURE_NODE_ID, error, spec_error, 0, 0, 0, 0, 0]
            }
            LssResponse::ConfigureBitTiming { error, spec_error } => {
                [cs::CONFIGURE_BIT_TIMING, error, spec_error, 0, 0, 0, 0, 0]
            }
            LssResponse::StoreConfiguration { error, spec_error } => {
                [cs::STORE_CONFIGURATION, error, spec_error, 0, 0, 0, 0, 0]
            }
            LssResponse::Identity { field, value } => with_u32(cs::INQUIRE_VENDOR + field.index(), value),
            LssResponse::NodeId(id) => [cs::INQUIRE_NODE_ID, id, 0, 0, 0, 0, 0, 0],
            LssResponse::IdentifySlave => [cs::IDENTIFY_SLAVE, 0, 0, 0, 0, 0, 0, 0],
            LssResponse::IdentifyNonConfiguredSlave => {
                [cs::IDENTIFY_NON_CONFIGURED_SLAVE, 0, 0, 0, 0, 0, 0, 0]
            }
        }
    }

    /// The response as a frame on 7E4h.
    #[inline]
    pub fn to_frame(&self) -> Frame {
        Frame::new8(SLAVE_TO_MASTER, self.to_bytes())
    }

    /// Decode a frame received on 7E4h; `None` if it is not an LSS response.
    pub fn from_frame(frame: &Frame) -> Option<LssResponse> {
        let d = lss_bytes(frame, SLAVE_TO_MASTER)?;
        let rsp = match d[0] {
            cs::SWITCH_SELECTIVE_RESPONSE => LssResponse::SwitchStateSelective,
            cs::CONFIGURE_NODE_ID => LssResponse::ConfigureNodeId { error: d[1], spec_error: d[2] },
            cs::CONFIGURE_BIT_TIMING => LssResponse::ConfigureBitTiming { error: d[1], spec_error: d[2] },
            cs::STORE_CONFIGURATION => LssResponse::StoreConfiguration { error: d[1], spec_error: d[2] },
            c @ cs::INQUIRE_VENDOR..=cs::INQUIRE_SERIAL => LssResponse::Identity {
                field: LssField::from_index(c - cs::INQUIRE_VENDOR)?,
                value: u32_at(d),
            },
            cs::INQUIRE_NODE_ID => LssResponse::NodeId(d[1]),
            cs::IDENTIFY_SLAVE => LssResponse::IdentifySlave,
            cs::IDENTIFY_NON_CONFIGURED_SLAVE => LssResponse::IdentifyNonConfiguredSlave,
            _ => return None,
        };
        Some(rsp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_can::CanId;

    #[test]
    fn command_specifiers_match_cia_305() {
        // Spot checks against the published CiA 305 command specifier list.
        let f = LssRequest::SwitchStateSelective { field: LssField::Serial, value: 0x0102_0304 }.to_frame();
        assert_eq!(format!("{f}"), "7E5#4304030201000000");
        let f = LssRequest::InquireIdentity(LssField::Revision).to_frame();
        assert_eq!(f.data()[0], 0x5C);
        let f = LssRequest::IdentifyRemoteSlave { step: IdentifyStep::SerialHigh, value: 7 }.to_frame();
        assert_eq!(f.data()[0], 0x4B);
        let f =
            LssRequest::FastScan { id_number: 0xAABB_CCDD, bit_checked: 0x80, sub: 2, next: 3 }.to_frame();
        assert_eq!(format!("{f}"), "7E5#51DDCCBBAA800203");
        assert_eq!(format!("{}", LssResponse::IdentifyNonConfiguredSlave.to_frame()), "7E4#5000000000000000");
    }

    #[test]
    fn rejects_non_lss_frames() {
        let ok = LssRequest::InquireNodeId.to_frame();
        assert!(LssRequest::from_frame(&ok).is_some());
        // Wrong direction, short DLC, RTR, extended id, unknown cs, bad mode.
        assert_eq!(LssResponse::from_frame(&ok), None);
        assert_eq!(LssRequest::from_frame(&Frame::new(0x7E5, &[0x5E, 0, 0, 0, 0, 0, 0])), None);
        assert_eq!(LssRequest::from_frame(&Frame::remote(0x7E5, 8)), None);
        let ext = Frame::try_new(CanId::Extended(0x7E5), &[0x5E, 0, 0, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(LssRequest::from_frame(&ext), None);
        assert_eq!(LssRequest::from_frame(&Frame::new8(0x7E5, [0x45, 0, 0, 0, 0, 0, 0, 0])), None);
        assert_eq!(LssRequest::from_frame(&Frame::new8(0x7E5, [0x04, 2, 0, 0, 0, 0, 0, 0])), None);
        assert_eq!(LssResponse::from_frame(&Frame::new8(0x7E4, [0x51, 0, 0, 0, 0, 0, 0, 0])), None);
    }
}
