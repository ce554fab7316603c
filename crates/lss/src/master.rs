//! LSS master side: request frame builders and the response parser.
//!
//! Thin, allocation-free helpers over [`LssRequest`] / [`LssResponse`] for
//! the async master (`drivebus lss scan|set-node-id`) and for tests. Which
//! requests are answered (CiA 305 v3.0.0): configure node-ID, configure bit
//! timing, store configuration, the inquire services, the last frame of
//! switch state selective and of identify remote slave, identify
//! non-configured remote slave and fastscan. Switch state global and activate
//! bit timing are never answered; see [`expects_response`].

use drivebus_can::Frame;

use crate::codec::{FASTSCAN_CONFIRM, IdentifyStep, LssField, LssRequest, LssResponse, cs};
use crate::{Identity, LssAddressRange, LssMode, STANDARD_TABLE};

/// Switch state global (04h): every slave enters `mode`. No response.
pub fn switch_state_global(mode: LssMode) -> Frame {
    LssRequest::SwitchStateGlobal(mode).to_frame()
}

/// Switch state selective (40h..43h): the four frames, to be sent in order.
/// The one slave with this address answers the last with 44h.
pub fn switch_state_selective(addr: &Identity) -> [Frame; 4] {
    LssField::ALL.map(|field| LssRequest::SwitchStateSelective { field, value: field.get(addr) }.to_frame())
}

/// Configure node-ID (11h). Answered with [`LssResponse::ConfigureNodeId`].
pub fn configure_node_id(node_id: u8) -> Frame {
    LssRequest::ConfigureNodeId(node_id).to_frame()
}

/// Configure bit timing (13h) with an index of the standard CiA table.
pub fn configure_bit_timing(index: u8) -> Frame {
    LssRequest::ConfigureBitTiming { table: STANDARD_TABLE, index }.to_frame()
}

/// Activate bit timing (15h): slaves in configuration switch after
/// `delay_ms`, then stay silent for another `delay_ms`. No response.
pub fn activate_bit_timing(delay_ms: u16) -> Frame {
    LssRequest::ActivateBitTiming { delay_ms }.to_frame()
}

/// Store configuration (17h). Answered with [`LssResponse::StoreConfiguration`].
pub fn store_configuration() -> Frame {
    LssRequest::StoreConfiguration.to_frame()
}

/// Inquire one part of the LSS address (5Ah..5Dh).
pub fn inquire_identity(field: LssField) -> Frame {
    LssRequest::InquireIdentity(field).to_frame()
}

/// Inquire node-ID (5Eh).
pub fn inquire_node_id() -> Frame {
    LssRequest::InquireNodeId.to_frame()
}

/// Identify remote slave (46h..4Bh): the six frames, to be sent in order.
/// Every slave in the range answers the last with 4Fh.
pub fn identify_remote_slave(range: &LssAddressRange) -> [Frame; 6] {
    let values = [
        (IdentifyStep::Vendor, range.vendor_id),
        (IdentifyStep::Product, range.product_code),
        (IdentifyStep::RevisionLow, range.revision_low),
        (IdentifyStep::RevisionHigh, range.revision_high),
        (IdentifyStep::SerialLow, range.serial_low),
        (IdentifyStep::SerialHigh, range.serial_high),
    ];
    values.map(|(step, value)| LssRequest::IdentifyRemoteSlave { step, value }.to_frame())
}

/// Identify non-configured remote slave (4Ch). Unconfigured slaves answer 50h.
pub fn identify_non_configured() -> Frame {
    LssRequest::IdentifyNonConfigured.to_frame()
}

/// One fastscan frame (51h).
pub fn fastscan(id_number: u32, bit_checked: u8, sub: u8, next: u8) -> Frame {
    LssRequest::FastScan { id_number, bit_checked, sub, next }.to_frame()
}

/// The fastscan reset frame: every unconfigured slave in waiting restarts
/// its scan and answers 4Fh.
pub fn fastscan_reset() -> Frame {
    fastscan(0, FASTSCAN_CONFIRM, 0, 0)
}

/// Decode a frame from a slave (7E4h).
#[inline]
pub fn parse_response(frame: &Frame) -> Option<LssResponse> {
    LssResponse::from_frame(frame)
}

/// The command specifier of the response a request is answered with, `None`
/// for requests no slave answers. For switch state selective and identify
/// remote slave only the last frame (43h, 4Bh) is answered.
pub fn expects_response(req: &LssRequest) -> Option<u8> {
    match req {
        LssRequest::SwitchStateGlobal(_) | LssRequest::ActivateBitTiming { .. } => None,
        LssRequest::SwitchStateSelective { field: LssField::Serial, .. } => {
            Some(cs::SWITCH_SELECTIVE_RESPONSE)
        }
        LssRequest::SwitchStateSelective { .. } => None,
        LssRequest::ConfigureNodeId(_) => Some(cs::CONFIGURE_NODE_ID),
        LssRequest::ConfigureBitTiming { .. } => Some(cs::CONFIGURE_BIT_TIMING),
        LssRequest::StoreConfiguration => Some(cs::STORE_CONFIGURATION),
        LssRequest::InquireIdentity(f) => Some(cs::INQUIRE_VENDOR + f.index()),
        LssRequest::InquireNodeId => Some(cs::INQUIRE_NODE_ID),
        LssRequest::IdentifyRemoteSlave { step: IdentifyStep::SerialHigh, .. } => Some(cs::IDENTIFY_SLAVE),
        LssRequest::IdentifyRemoteSlave { .. } => None,
        LssRequest::IdentifyNonConfigured => Some(cs::IDENTIFY_NON_CONFIGURED_SLAVE),
        LssRequest::FastScan { .. } => Some(cs::IDENTIFY_SLAVE),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builders_are_frame_exact() {
        assert_eq!(format!("{}", switch_state_global(LssMode::Configuration)), "7E5#0401000000000000");
        assert_eq!(format!("{}", switch_state_global(LssMode::Waiting)), "7E5#0400000000000000");
        let sel = switch_state_selective(&Identity::new(0x30C, 0x0060_4100, 0x0001_0002, 0xA0B0_C0D0));
        assert_eq!(
            sel.map(|f| format!("{f}")),
            ["7E5#400C030000000000", "7E5#4100416000000000", "7E5#4202000100000000", "7E5#43D0C0B0A0000000"]
        );
        assert_eq!(format!("{}", configure_node_id(5)), "7E5#1105000000000000");
        assert_eq!(format!("{}", configure_bit_timing(3)), "7E5#1300030000000000");
        assert_eq!(format!("{}", activate_bit_timing(0x1234)), "7E5#1534120000000000");
        assert_eq!(format!("{}", store_configuration()), "7E5#1700000000000000");
        assert_eq!(format!("{}", inquire_identity(LssField::Vendor)), "7E5#5A00000000000000");
        assert_eq!(format!("{}", inquire_node_id()), "7E5#5E00000000000000");
        assert_eq!(format!("{}", identify_non_configured()), "7E5#4C00000000000000");
        assert_eq!(format!("{}", fastscan_reset()), "7E5#5100000000800000");
        let range = LssAddressRange {
            vendor_id: 1,
            product_code: 2,
            revision_low: 3,
            revision_high: 4,
            serial_low: 5,
            serial_high: 6,
        };
        let ids = identify_remote_slave(&range).map(|f| (f.data()[0], f.data()[1]));
        assert_eq!(ids, [(0x46, 1), (0x47, 2), (0x48, 3), (0x49, 4), (0x4A, 5), (0x4B, 6)]);
    }

    #[test]
    fn responses_parse() {
        let f = Frame::new8(0x7E4, [0x11, 1, 0, 0, 0, 0, 0, 0]);
        assert_eq!(parse_response(&f), Some(LssResponse::ConfigureNodeId { error: 1, spec_error: 0 }));
        let f = Frame::new8(0x7E4, [0x5D, 0x78, 0x56, 0x34, 0x12, 0, 0, 0]);
        assert_eq!(
            parse_response(&f),
            Some(LssResponse::Identity { field: LssField::Serial, value: 0x1234_5678 })
        );
        assert_eq!(expects_response(&LssRequest::SwitchStateGlobal(LssMode::Waiting)), None);
        assert_eq!(
            expects_response(&LssRequest::FastScan { id_number: 0, bit_checked: 0, sub: 0, next: 0 }),
            Some(0x4F)
        );
    }
}
