//! An SII EEPROM image (ETG.1000.6 §5.4) read back as a
//! [`SlaveDescription`]: the reverse of [`crate::sii`], for a device given
//! by a dump of its EEPROM (identity, names, sync managers, FMMUs, PDOs,
//! mailbox protocols, DC modes). The image itself stays what the device
//! serves; the description says what it contains.
//!
//! What an image cannot say: the vendor name, a URL, port physics other
//! than the General nibbles, and the object dictionary (see
//! [`crate::dictionary`]).

use crate::description::{
    CoeDetails, DcOpMode, Eeprom, EsiPdo, EsiProfile, FmmuUsage, Mailbox, PdoEntry, SlaveDescription, SmKind,
    SyncManager, SyncSignal,
};
use crate::read::ReadError;
use drivebus_esc::sii::{SiiContent, SiiPdo, fmmu_usage, protocols, sm_type};
use drivebus_od::DataType;

/// The description an SII image gives. Fails, naming the category entry,
/// on a sync manager type other than mailbox or process data.
pub fn describe_sii(c: &SiiContent) -> Result<SlaveDescription, ReadError> {
    let string = |i: u8| sii_string(c, i);
    let g = c.general.unwrap_or_default();
    let sync_managers = sync_managers(c)?;
    let b = c.bootstrap_mailbox;
    Ok(SlaveDescription {
        vendor_id: c.identity.vendor_id,
        vendor_name: String::new(),
        product_code: c.identity.product_code,
        revision: c.identity.revision,
        serial: c.identity.serial,
        type_name: string(g.order_idx),
        name: string(g.name_idx),
        group_type: string(g.group_idx),
        group_name: string(g.group_idx),
        url: None,
        physics: physics(g.physical_ports),
        mailbox_timeouts: None,
        profile: EsiProfile { number: if g.ds402_channels > 0 { 402 } else { 0 }, add_info: 0 },
        objects: Vec::new(),
        fmmus: c
            .fmmus
            .iter()
            .filter_map(|f| match *f {
                fmmu_usage::OUTPUTS => Some(FmmuUsage::Outputs),
                fmmu_usage::INPUTS => Some(FmmuUsage::Inputs),
                fmmu_usage::SM_STATUS => Some(FmmuUsage::MBoxState),
                _ => None,
            })
            .collect(),
        rx_pdos: pdos(c, &c.rx_pdos, sync_managers.len()),
        tx_pdos: pdos(c, &c.tx_pdos, sync_managers.len()),
        sync_managers,
        mailbox: mailbox(c),
        dc: dc_modes(c),
        eeprom: Eeprom {
            byte_size: u32::from(c.size_kbit) * 128,
            config: c.config,
            bootstrap: (b.rx_size > 0).then_some(b),
        },
    })
}

/// String `i` of the Strings category (1-based; 0 and a missing one are empty).
fn sii_string(c: &SiiContent, i: u8) -> String {
    match i {
        0 => String::new(),
        i => c.strings.get(usize::from(i) - 1).cloned().unwrap_or_default(),
    }
}

/// The SyncManager category.
fn sync_managers(c: &SiiContent) -> Result<Vec<SyncManager>, ReadError> {
    c.sync_managers
        .iter()
        .enumerate()
        .map(|(n, s)| {
            let kind = match s.sm_type {
                sm_type::MAILBOX_OUT => SmKind::MBoxOut,
                sm_type::MAILBOX_IN => SmKind::MBoxIn,
                sm_type::OUTPUTS => SmKind::Outputs,
                sm_type::INPUTS => SmKind::Inputs,
                t => {
                    return Err(ReadError {
                        at: format!("SII SyncManager category, SM{n}"),
                        message: format!("type {t} is neither mailbox nor process data"),
                    });
                }
            };
            Ok(SyncManager {
                kind,
                start: s.start,
                default_size: (s.length > 0).then_some(s.length),
                control: s.control,
                enable: s.enable & 0x01 != 0,
            })
        })
        .collect()
}

/// The RxPDO or TxPDO category; a PDO's sync manager only if the image has it.
fn pdos(c: &SiiContent, list: &[SiiPdo], sync_managers: usize) -> Vec<EsiPdo> {
    list.iter()
        .map(|p| EsiPdo {
            index: p.index,
            name: sii_string(c, p.name_idx),
            sm: (usize::from(p.sync_manager) < sync_managers).then_some(p.sync_manager),
            fixed: p.flags & crate::sii::pdo_flags::FIXED != 0,
            mandatory: p.flags & crate::sii::pdo_flags::MANDATORY != 0,
            entries: p
                .entries
                .iter()
                .map(|e| PdoEntry {
                    index: e.index,
                    sub: e.sub_index,
                    bit_len: e.bit_len,
                    name: sii_string(c, e.name_idx),
                    data_type: DataType::from_index(u16::from(e.data_type)),
                })
                .collect(),
        })
        .collect()
}

/// The mailbox when the image gives both its sizes, with the protocols
/// and the General category's CoE details.
fn mailbox(c: &SiiContent) -> Option<Mailbox> {
    let g = c.general.unwrap_or_default();
    let m = c.mailbox;
    let coe = c.mailbox_protocols & protocols::COE != 0;
    let d = g.coe_details;
    (m.rx_size > 0 && m.tx_size > 0).then_some(Mailbox {
        data_link_layer: g.flags & 0x04 != 0,
        coe: coe.then_some(CoeDetails {
            sdo_info: d & 0x02 != 0,
            pdo_assign: d & 0x04 != 0,
            pdo_config: d & 0x08 != 0,
            pdo_upload: d & 0x10 != 0,
            complete_access: d & 0x20 != 0,
        }),
        foe: c.mailbox_protocols & protocols::FOE != 0,
        eoe: c.mailbox_protocols & protocols::EOE != 0,
    })
}

/// The General category's port nibbles as ESI `Physics` letters.
fn physics(ports: u16) -> String {
    (0..4)
        .map(|i| match (ports >> (4 * i)) & 0x0F {
            1 => 'Y',
            3 => 'K',
            4 => 'H',
            _ => ' ',
        })
        .collect::<String>()
        .trim_end()
        .to_string()
}

/// The DC category's operation modes.
fn dc_modes(c: &SiiContent) -> Vec<DcOpMode> {
    c.dc.iter()
        .map(|s| DcOpMode {
            name: sii_string(c, s.name_idx),
            desc: sii_string(c, s.desc_idx),
            assign_activate: s.assign_activate,
            sync0: (s.assign_activate & 0x0200 != 0).then_some(SyncSignal {
                cycle_ns: s.cycle_time0,
                factor: s.sync0_cycle_factor,
                shift_ns: s.shift_time0,
            }),
            sync1: (s.assign_activate & 0x0400 != 0).then_some(SyncSignal {
                cycle_ns: 0,
                factor: s.sync1_cycle_factor,
                shift_ns: s.shift_time1,
            }),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_esc::sii::SiiImage;

    /// The image of a description reads back as the same description, as
    /// far as an image can say it.
    #[test]
    fn ipos_image_reads_back_as_its_description() {
        let eds = drivebus_eds::parse(include_str!("../../personality/eds/ipos.eds")).unwrap().eds;
        let od = drivebus_eds::to_od(&eds, 1).unwrap();
        let facts = crate::ipos::facts(0x1A3, "Technosoft S.A.", 28_002_021, "iPOS360x VX-CAT");
        let d = SlaveDescription::new(&od, &facts);
        let back = describe_sii(&SiiImage::from(&d).parse().unwrap()).unwrap();
        assert_eq!(
            (back.vendor_id, back.product_code, back.revision),
            (d.vendor_id, d.product_code, d.revision)
        );
        assert_eq!((back.type_name.as_str(), back.name.as_str()), (d.type_name.as_str(), d.name.as_str()));
        assert_eq!(back.sync_managers, d.sync_managers);
        assert_eq!(back.fmmus, d.fmmus);
        assert_eq!(back.mailbox, d.mailbox);
        assert_eq!(back.physics, d.physics);
        assert_eq!(back.sii_coe_details(), d.sii_coe_details());
        let idx = |p: &[EsiPdo]| p.iter().map(|p| (p.index, p.bits())).collect::<Vec<_>>();
        assert_eq!(idx(&back.rx_pdos), idx(&d.rx_pdos));
        assert_eq!(idx(&back.tx_pdos), idx(&d.tx_pdos));
        assert_eq!(back.dc.iter().map(|m| m.assign_activate).collect::<Vec<_>>(), [0, 0x0300]);
    }

    #[test]
    fn unknown_sm_type_is_named() {
        let img = SiiImage::builder()
            .sync_manager(drivebus_esc::sii::SiiSyncManager {
                start: 0x1000,
                length: 1,
                control: 0,
                enable: 1,
                sm_type: 3,
            })
            .sync_manager(drivebus_esc::sii::SiiSyncManager {
                start: 0x0998,
                length: 0,
                control: 0,
                enable: 4,
                sm_type: 7,
            })
            .build();
        let e = describe_sii(&img.parse().unwrap()).unwrap_err();
        assert_eq!(e.at, "SII SyncManager category, SM1");
        assert!(e.message.contains("type 7"), "{e}");
    }
}
