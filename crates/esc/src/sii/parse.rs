//! Decoding an SII image into [`SiiContent`] (the inverse of
//! [`super::encode`]).

use super::*;

fn word(b: &[u8], w: usize) -> u16 {
    u16::from_le_bytes([b[w * 2], b[w * 2 + 1]])
}

fn dword(b: &[u8], w: usize) -> u32 {
    u32::from(word(b, w)) | (u32::from(word(b, w + 1)) << 16)
}

fn mailbox_at(b: &[u8], w: usize) -> MailboxArea {
    MailboxArea {
        rx_offset: word(b, w),
        rx_size: word(b, w + 1),
        tx_offset: word(b, w + 2),
        tx_size: word(b, w + 3),
    }
}

/// Decodes an image.
pub fn parse(b: &[u8]) -> Result<SiiContent, SiiError> {
    if b.len() < 0x80 {
        return Err(SiiError::TooShort);
    }
    let computed = config_crc(&b[..14]);
    if computed != b[14] {
        return Err(SiiError::Checksum { computed, stored: b[14] });
    }
    let mut c = SiiContent {
        config: ConfigArea {
            pdi_control: word(b, 0),
            pdi_config: word(b, 1),
            sync_impulse_len: word(b, 2),
            pdi_config2: word(b, 3),
            station_alias: word(b, 4),
        },
        identity: Identity {
            vendor_id: dword(b, 8),
            product_code: dword(b, 10),
            revision: dword(b, 12),
            serial: dword(b, 14),
        },
        bootstrap_mailbox: mailbox_at(b, 0x14),
        mailbox: mailbox_at(b, 0x18),
        mailbox_protocols: word(b, 0x1C),
        size_kbit: word(b, 0x3E).wrapping_add(1),
        version: word(b, 0x3F),
        ..SiiContent::default()
    };
    let mut w = 0x40usize;
    loop {
        if (w + 2) * 2 > b.len() {
            return Err(SiiError::CategoryOverrun(0, w));
        }
        let kind = word(b, w);
        if kind == category::END {
            break;
        }
        let len = usize::from(word(b, w + 1));
        let data = b.get((w + 2) * 2..(w + 2 + len) * 2).ok_or(SiiError::CategoryOverrun(kind, w))?;
        parse_category(&mut c, kind, data).map_err(|()| SiiError::BadCategory(kind, w))?;
        w += 2 + len;
    }
    Ok(c)
}

fn parse_category(c: &mut SiiContent, kind: u16, d: &[u8]) -> Result<(), ()> {
    let bad = ();
    match kind {
        category::STRINGS => {
            let n = *d.first().ok_or(bad)?;
            let mut p = 1;
            for _ in 0..n {
                let l = usize::from(*d.get(p).ok_or(bad)?);
                let s = d.get(p + 1..p + 1 + l).ok_or(bad)?;
                c.strings.push(s.iter().map(|&ch| char::from(ch)).collect());
                p += 1 + l;
            }
        }
        category::GENERAL => {
            let g = d.get(..18).ok_or(bad)?;
            c.general = Some(General {
                group_idx: g[0],
                image_idx: g[1],
                order_idx: g[2],
                name_idx: g[3],
                coe_details: g[5],
                foe_details: g[6],
                eoe_details: g[7],
                soe_channels: g[8],
                ds402_channels: g[9],
                sysman_class: g[10],
                flags: g[11],
                ebus_current: i16::from_le_bytes([g[12], g[13]]),
                physical_ports: u16::from_le_bytes([g[14], g[15]]),
                physical_memory_address: u16::from_le_bytes([g[16], g[17]]),
            });
        }
        category::FMMU => {
            let mut f = d.to_vec();
            while f.last() == Some(&0xFF) {
                f.pop();
            }
            c.fmmus = f;
        }
        category::SYNC_MANAGER => {
            for s in d.chunks_exact(8) {
                c.sync_managers.push(SiiSyncManager {
                    start: u16::from_le_bytes([s[0], s[1]]),
                    length: u16::from_le_bytes([s[2], s[3]]),
                    control: s[4],
                    enable: s[6],
                    sm_type: s[7],
                });
            }
        }
        category::FMMU_EX => c.fmmu_ex = d.to_vec(),
        category::TXPDO | category::RXPDO => {
            let mut p = 0;
            let mut pdos = Vec::new();
            while p + 8 <= d.len() {
                let h = &d[p..p + 8];
                let n = usize::from(h[2]);
                let mut pdo = SiiPdo {
                    index: u16::from_le_bytes([h[0], h[1]]),
                    sync_manager: h[3],
                    dc_sync: h[4],
                    name_idx: h[5],
                    flags: u16::from_le_bytes([h[6], h[7]]),
                    entries: Vec::with_capacity(n),
                };
                p += 8;
                for _ in 0..n {
                    let e = d.get(p..p + 8).ok_or(bad)?;
                    pdo.entries.push(SiiPdoEntry {
                        index: u16::from_le_bytes([e[0], e[1]]),
                        sub_index: e[2],
                        name_idx: e[3],
                        data_type: e[4],
                        bit_len: e[5],
                        flags: u16::from_le_bytes([e[6], e[7]]),
                    });
                    p += 8;
                }
                pdos.push(pdo);
            }
            if kind == category::TXPDO {
                c.tx_pdos = pdos;
            } else {
                c.rx_pdos = pdos;
            }
        }
        category::DC => {
            for s in d.chunks_exact(24) {
                c.dc.push(SiiDcSync {
                    cycle_time0: u32::from_le_bytes([s[0], s[1], s[2], s[3]]),
                    shift_time0: u32::from_le_bytes([s[4], s[5], s[6], s[7]]),
                    shift_time1: u32::from_le_bytes([s[8], s[9], s[10], s[11]]),
                    sync1_cycle_factor: i16::from_le_bytes([s[12], s[13]]),
                    assign_activate: u16::from_le_bytes([s[14], s[15]]),
                    sync0_cycle_factor: i16::from_le_bytes([s[16], s[17]]),
                    name_idx: s[18],
                    desc_idx: s[19],
                });
            }
        }
        _ => c.other.push((kind, d.to_vec())),
    }
    Ok(())
}
