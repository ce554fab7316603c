//! The SII EEPROM image (ETG.1000.6 §5.4) of a [`SlaveDescription`]: the
//! one conversion, so the image a slave's ESC serves and the ESI file it
//! ships with say the same (the table in the crate docs says which field
//! feeds which word or category).

use crate::description::{EsiPdo, SlaveDescription, SmKind};
use drivebus_esc::sii::{
    General, MailboxArea, SiiBuilder, SiiContent, SiiDcSync, SiiImage, SiiPdo, SiiPdoEntry, SiiSyncManager,
};

/// ETG.2000 PDO attributes as SII PDO flags (ETG.1000.6 Table 26).
pub mod pdo_flags {
    /// `@Mandatory`.
    pub const MANDATORY: u16 = 0x0001;
    /// Assigned by default (`@Sm` given).
    pub const DEFAULT: u16 = 0x0002;
    /// `@Fixed`: the mapping cannot be changed.
    pub const FIXED: u16 = 0x0010;
}

fn mailbox(d: &SlaveDescription) -> MailboxArea {
    let area = |k: SmKind| d.sm(k).map_or((0, 0), |(_, s)| (s.start, s.default_size.unwrap_or(0)));
    let (rx_offset, rx_size) = area(SmKind::MBoxOut);
    let (tx_offset, tx_size) = area(SmKind::MBoxIn);
    MailboxArea { rx_offset, rx_size, tx_offset, tx_size }
}

fn pdo(b: &mut SiiBuilder, p: &EsiPdo, direction_sm: u8) -> SiiPdo {
    let name_idx = b.add_string(&p.name);
    let entries = p
        .entries
        .iter()
        .map(|e| SiiPdoEntry {
            index: e.index,
            sub_index: e.sub,
            name_idx: if e.name.is_empty() { 0 } else { b.add_string(&e.name) },
            data_type: e.data_type.map_or(0, |t| t as u16 as u8),
            bit_len: e.bit_len,
            flags: 0,
        })
        .collect();
    let mut flags = 0;
    if p.mandatory {
        flags |= pdo_flags::MANDATORY;
    }
    if p.sm.is_some() {
        flags |= pdo_flags::DEFAULT;
    }
    if p.fixed {
        flags |= pdo_flags::FIXED;
    }
    // An unassigned PDO belongs to its direction's SM; the DEFAULT flag
    // tells it apart from the assigned ones.
    SiiPdo {
        index: p.index,
        sync_manager: p.sm.unwrap_or(direction_sm),
        dc_sync: 0,
        name_idx,
        flags,
        entries,
    }
}

/// The SII builder of `d`, ready to [`SiiBuilder::build`].
impl From<&SlaveDescription> for SiiBuilder {
    fn from(d: &SlaveDescription) -> SiiBuilder {
        let boot = d.eeprom.bootstrap.unwrap_or_default();
        let content = SiiContent {
            config: d.eeprom.config,
            bootstrap_mailbox: boot,
            mailbox: mailbox(d),
            mailbox_protocols: d.sii_mailbox_protocols(),
            size_kbit: u16::try_from(d.eeprom.byte_size / 128).unwrap_or(u16::MAX),
            version: 1,
            ..SiiContent::default()
        };
        let m = d.mailbox;
        let general = General {
            coe_details: d.sii_coe_details(),
            foe_details: u8::from(m.is_some_and(|m| m.foe)),
            eoe_details: u8::from(m.is_some_and(|m| m.eoe)),
            ds402_channels: u8::from(d.profile.number == 402),
            flags: if m.is_some_and(|m| m.data_link_layer) { 0x04 } else { 0 },
            physical_ports: d.sii_physical_ports(),
            ..General::default()
        };
        let mut b = SiiBuilder::from_content(content)
            .identity(d.vendor_id, d.product_code, d.revision, d.serial)
            .general(general)
            .names(&d.group_type, &d.type_name, &d.name)
            .fmmus(&d.fmmus.iter().map(|f| f.sii_code()).collect::<Vec<_>>());
        for s in &d.sync_managers {
            b = b.sync_manager(SiiSyncManager {
                start: s.start,
                length: s.default_size.unwrap_or(0),
                control: s.control,
                enable: u8::from(s.enable),
                sm_type: s.kind.code(),
            });
        }
        let out_sm = d.sm(SmKind::Outputs).map_or(0, |(i, _)| i);
        let in_sm = d.sm(SmKind::Inputs).map_or(0, |(i, _)| i);
        for p in &d.tx_pdos {
            let x = pdo(&mut b, p, in_sm);
            b = b.tx_pdo(x);
        }
        for p in &d.rx_pdos {
            let x = pdo(&mut b, p, out_sm);
            b = b.rx_pdo(x);
        }
        for m in &d.dc {
            let name_idx = b.add_string(&m.name);
            let desc_idx = b.add_string(&m.desc);
            b = b.dc(SiiDcSync {
                cycle_time0: m.sync0.map_or(0, |s| s.cycle_ns),
                shift_time0: m.sync0.map_or(0, |s| s.shift_ns),
                shift_time1: m.sync1.map_or(0, |s| s.shift_ns),
                sync1_cycle_factor: m.sync1.map_or(0, |s| s.factor),
                assign_activate: m.assign_activate,
                sync0_cycle_factor: m.sync0.map_or(0, |s| s.factor),
                name_idx,
                desc_idx,
            });
        }
        b
    }
}

/// The SII image of `d`.
impl From<&SlaveDescription> for SiiImage {
    fn from(d: &SlaveDescription) -> SiiImage {
        SiiBuilder::from(d).build()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DeviceFacts, SmKind};
    use drivebus_esc::sii::{protocols, sm_type};

    #[test]
    fn ipos_image_says_what_the_description_says() {
        let eds = drivebus_eds::parse(include_str!("../../personality/eds/ipos.eds")).unwrap().eds;
        let od = drivebus_eds::to_od(&eds, 1).unwrap();
        let facts = crate::ipos::facts(0x1A3, "Technosoft S.A.", 28_002_021, "iPOS360x VX-CAT");
        let d = SlaveDescription::new(&od, &facts);
        let img = SiiImage::from(&d);
        assert!(img.checksum_ok());
        assert!(img.bytes().len() <= d.eeprom.byte_size as usize, "{} bytes", img.bytes().len());
        let c = img.parse().unwrap();
        assert_eq!(c.identity.vendor_id, 0x1A3);
        assert_eq!(c.identity.revision, crate::ipos::REVISION);
        assert_eq!((c.mailbox.rx_offset, c.mailbox.rx_size, c.mailbox.tx_size), (0x1000, 512, 512));
        assert_eq!(c.bootstrap_mailbox.rx_size, 512, "BOOT uses the same mailbox");
        assert_eq!(c.mailbox_protocols, protocols::COE | protocols::FOE);
        let g = c.general.unwrap();
        assert_eq!(c.strings[usize::from(g.order_idx) - 1], "iPOS360x VX-CAT");
        assert_eq!(g.coe_details, d.sii_coe_details());
        let types: Vec<u8> = c.sync_managers.iter().map(|s| s.sm_type).collect();
        assert_eq!(types, [sm_type::MAILBOX_OUT, sm_type::MAILBOX_IN, sm_type::OUTPUTS, sm_type::INPUTS]);
        // 1600h assigned (48 bits = 6 bytes); 1A00h + 1A01h (128 bits).
        assert_eq!(c.sync_managers[2].length, 6);
        assert_eq!(c.sync_managers[3].length, 16);
        let assigned: Vec<u16> =
            c.rx_pdos.iter().filter(|p| p.flags & pdo_flags::DEFAULT != 0).map(|p| p.index).collect();
        assert_eq!(assigned, [0x1600]);
        assert_eq!(c.tx_pdos.iter().find(|p| p.index == 0x1A00).unwrap().bit_len(), 64);
        assert_eq!(c.dc.iter().map(|m| m.assign_activate).collect::<Vec<_>>(), [0, 0x0300]);
        assert_eq!(d.sm(SmKind::Inputs).unwrap().0, 3);
        let _ = DeviceFacts::new(1, "", 2, 3, "");
    }
}
