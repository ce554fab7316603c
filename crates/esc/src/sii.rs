//! The SII EEPROM image (ETG.1000.6 §5.4, ETG.2010): encoder, builder and
//! parser.
//!
//! Layout (word addresses):
//!
//! | words | content |
//! |---|---|
//! | 0x00–0x07 | ESC configuration area: PDI control, PDI configuration, SYNC impulse length, extended PDI configuration, station alias, 2 reserved, CRC-8 in the low byte of word 7 |
//! | 0x08–0x0F | vendor ID, product code, revision, serial number (u32 each) |
//! | 0x14–0x17 | bootstrap mailbox: receive offset/size, send offset/size |
//! | 0x18–0x1B | standard mailbox: receive offset/size, send offset/size |
//! | 0x1C | mailbox protocols (AoE 1, EoE 2, CoE 4, FoE 8, SoE 0x10, VoE 0x20) |
//! | 0x3E | EEPROM size in Kbit − 1 |
//! | 0x3F | version (1) |
//! | 0x40… | categories: `type u16, length in words u16, data`, ended by type 0xFFFF |
//!
//! The CRC is CRC-8 with polynomial 0x07 and initial value 0xFF over bytes
//! 0–13 (ETG.1000.6 Table 16).

use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;

const ESC_CRC: crc::Algorithm<u8> = crc::Algorithm {
    width: 8,
    poly: 0x07,
    init: 0xFF,
    refin: false,
    refout: false,
    xorout: 0x00,
    check: 0xFB,
    residue: 0x00,
};

/// CRC-8 of the configuration area (ETG.1000.6 Table 16).
pub fn config_crc(first_14_bytes: &[u8]) -> u8 {
    crc::Crc::<u8>::new(&ESC_CRC).checksum(first_14_bytes)
}

/// Mailbox protocol bits (SII word 0x1C).
pub mod protocols {
    /// ADS over EtherCAT.
    pub const AOE: u16 = 0x01;
    /// Ethernet over EtherCAT.
    pub const EOE: u16 = 0x02;
    /// CANopen over EtherCAT.
    pub const COE: u16 = 0x04;
    /// File access over EtherCAT.
    pub const FOE: u16 = 0x08;
    /// Servo profile over EtherCAT.
    pub const SOE: u16 = 0x10;
    /// Vendor specific.
    pub const VOE: u16 = 0x20;
}

/// Category types (ETG.1000.6 Table 19).
pub mod category {
    /// Strings.
    pub const STRINGS: u16 = 10;
    /// General.
    pub const GENERAL: u16 = 30;
    /// FMMU usage.
    pub const FMMU: u16 = 40;
    /// Sync managers.
    pub const SYNC_MANAGER: u16 = 41;
    /// FMMU extended.
    pub const FMMU_EX: u16 = 42;
    /// TxPDOs (slave → master).
    pub const TXPDO: u16 = 50;
    /// RxPDOs (master → slave).
    pub const RXPDO: u16 = 51;
    /// Distributed clock operation modes.
    pub const DC: u16 = 60;
    /// End marker.
    pub const END: u16 = 0xFFFF;
}

/// Words 0x00–0x06 of the configuration area (words 0x05–0x06 are
/// reserved and written 0); the ESI's `ConfigData` holds the same words.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ConfigArea {
    /// Word 0: PDI control (low byte → 0x0140) and ESC configuration (high byte → 0x0141).
    pub pdi_control: u16,
    /// Word 1: PDI configuration (→ 0x0150).
    pub pdi_config: u16,
    /// Word 2: SYNC impulse length in 10 ns (→ 0x0982).
    pub sync_impulse_len: u16,
    /// Word 3: extended PDI configuration (→ 0x0152).
    pub pdi_config2: u16,
    /// Word 4: configured station alias (→ 0x0012).
    pub station_alias: u16,
}

impl ConfigArea {
    /// The 14 bytes of words 0–6, little-endian (the ESI's `ConfigData`).
    pub fn bytes(&self) -> [u8; 14] {
        let mut b = [0u8; 14];
        for (i, w) in
            [self.pdi_control, self.pdi_config, self.sync_impulse_len, self.pdi_config2, self.station_alias]
                .into_iter()
                .enumerate()
        {
            b[2 * i..2 * i + 2].copy_from_slice(&w.to_le_bytes());
        }
        b
    }

    /// From `ConfigData` bytes (missing words are 0).
    pub fn from_bytes(b: &[u8]) -> ConfigArea {
        let w = |i: usize| b.get(2 * i..2 * i + 2).map_or(0, |x| u16::from_le_bytes([x[0], x[1]]));
        ConfigArea {
            pdi_control: w(0),
            pdi_config: w(1),
            sync_impulse_len: w(2),
            pdi_config2: w(3),
            station_alias: w(4),
        }
    }
}

/// Identity words 0x08–0x0F: the 1018h identity, one type with the
/// CANopen node's and the LSS address.
pub use drivebus_base::Identity;

/// Mailbox offsets and sizes: SII words 0x14–0x17 (bootstrap) and
/// 0x18–0x1B (standard), the ESI's `BootStrap` (receive start, size, send
/// start, size).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MailboxArea {
    /// Receive mailbox (master → slave, SM0) start.
    pub rx_offset: u16,
    /// Receive mailbox size.
    pub rx_size: u16,
    /// Send mailbox (slave → master, SM1) start.
    pub tx_offset: u16,
    /// Send mailbox size.
    pub tx_size: u16,
}

impl MailboxArea {
    /// The 8 bytes as the SII and the ESI's `BootStrap` hold them.
    pub fn bytes(&self) -> [u8; 8] {
        let mut b = [0u8; 8];
        for (i, w) in [self.rx_offset, self.rx_size, self.tx_offset, self.tx_size].into_iter().enumerate() {
            b[2 * i..2 * i + 2].copy_from_slice(&w.to_le_bytes());
        }
        b
    }
}

/// The General category (ETG.1000.6 Table 21), 32 bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct General {
    /// Group string index.
    pub group_idx: u8,
    /// Image string index.
    pub image_idx: u8,
    /// Order string index (ethercrab names the device after this one).
    pub order_idx: u8,
    /// Name string index (the long description).
    pub name_idx: u8,
    /// CoE details: 0x01 SDO, 0x02 SDO info, 0x04 PDO assign, 0x08 PDO config,
    /// 0x10 upload at startup, 0x20 complete access. Masters reject other bits.
    pub coe_details: u8,
    /// FoE details.
    pub foe_details: u8,
    /// EoE details.
    pub eoe_details: u8,
    /// SoE channels.
    pub soe_channels: u8,
    /// DS402 channels.
    pub ds402_channels: u8,
    /// SysmanClass.
    pub sysman_class: u8,
    /// Flags: 0x01 enable SAFEOP, 0x02 enable not LRW, 0x04 mailbox DLL,
    /// 0x08 identity AL status, 0x10 identity physical memory.
    pub flags: u8,
    /// E-bus current consumption in mA.
    pub ebus_current: i16,
    /// Physical ports, 4 bits each (1 MII, 3 E-bus).
    pub physical_ports: u16,
    /// Physical memory address of the identification value.
    pub physical_memory_address: u16,
}

/// FMMU usage codes (ETG.1000.6 Table 23).
pub mod fmmu_usage {
    /// Not used.
    pub const UNUSED: u8 = 0;
    /// Outputs.
    pub const OUTPUTS: u8 = 1;
    /// Inputs.
    pub const INPUTS: u8 = 2;
    /// Sync manager status (mailbox polling).
    pub const SM_STATUS: u8 = 3;
}

/// Sync manager types in the SII (ETG.1000.6 Table 24).
pub mod sm_type {
    /// Unused.
    pub const UNUSED: u8 = 0;
    /// Mailbox out (master → slave).
    pub const MAILBOX_OUT: u8 = 1;
    /// Mailbox in (slave → master).
    pub const MAILBOX_IN: u8 = 2;
    /// Process data outputs.
    pub const OUTPUTS: u8 = 3;
    /// Process data inputs.
    pub const INPUTS: u8 = 4;
}

/// One entry of the SyncManager category (8 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SiiSyncManager {
    /// Physical start address.
    pub start: u16,
    /// Default length (0 for process data SMs sized from the mapping).
    pub length: u16,
    /// Control register value (0x0804): mode bits 1:0, direction bits 3:2, …
    pub control: u8,
    /// Enable flags: 0x01 enable, 0x02 fixed content, 0x04 virtual, 0x08 OP only.
    pub enable: u8,
    /// Type, see [`sm_type`].
    pub sm_type: u8,
}

/// One PDO entry (8 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SiiPdoEntry {
    /// Object index (0 for padding).
    pub index: u16,
    /// Sub-index.
    pub sub_index: u8,
    /// Name string index.
    pub name_idx: u8,
    /// Data type (ETG.1000.6 Table 64, e.g. 1 BOOLEAN, 7 UNSIGNED32).
    pub data_type: u8,
    /// Length in bits.
    pub bit_len: u8,
    /// Flags.
    pub flags: u16,
}

/// A PDO of the TxPDO/RxPDO categories.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SiiPdo {
    /// PDO index (0x16xx RxPDO, 0x1Axx TxPDO).
    pub index: u16,
    /// Sync manager the PDO belongs to.
    pub sync_manager: u8,
    /// DC sync.
    pub dc_sync: u8,
    /// Name string index.
    pub name_idx: u8,
    /// PDO flags.
    pub flags: u16,
    /// Entries.
    pub entries: Vec<SiiPdoEntry>,
}

impl SiiPdo {
    /// Total bits of all entries.
    pub fn bit_len(&self) -> u32 {
        self.entries.iter().map(|e| u32::from(e.bit_len)).sum()
    }
}

/// One entry of the DC category (24 bytes, ETG.2010).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SiiDcSync {
    /// SYNC0 cycle time in ns (0: the master's cycle).
    pub cycle_time0: u32,
    /// SYNC0 shift time in ns.
    pub shift_time0: u32,
    /// SYNC1 shift time in ns.
    pub shift_time1: u32,
    /// SYNC1 cycle factor.
    pub sync1_cycle_factor: i16,
    /// Value for 0x0980/0x0981 ("AssignActivate").
    pub assign_activate: u16,
    /// SYNC0 cycle factor.
    pub sync0_cycle_factor: i16,
    /// Name string index.
    pub name_idx: u8,
    /// Description string index.
    pub desc_idx: u8,
}

/// Everything an SII image holds, decoded.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SiiContent {
    /// Configuration area.
    pub config: ConfigArea,
    /// Identity.
    pub identity: Identity,
    /// Bootstrap mailbox (words 0x14–0x17).
    pub bootstrap_mailbox: MailboxArea,
    /// Standard mailbox (words 0x18–0x1B).
    pub mailbox: MailboxArea,
    /// Mailbox protocols (word 0x1C), see [`protocols`].
    pub mailbox_protocols: u16,
    /// EEPROM size in Kbit (word 0x3E + 1).
    pub size_kbit: u16,
    /// Version (word 0x3F).
    pub version: u16,
    /// Strings; index 1 is the first.
    pub strings: Vec<String>,
    /// General category.
    pub general: Option<General>,
    /// FMMU usage, one code per FMMU, see [`fmmu_usage`].
    pub fmmus: Vec<u8>,
    /// Sync managers.
    pub sync_managers: Vec<SiiSyncManager>,
    /// FMMU_EX category, raw (3 bytes per FMMU).
    pub fmmu_ex: Vec<u8>,
    /// TxPDOs (inputs).
    pub tx_pdos: Vec<SiiPdo>,
    /// RxPDOs (outputs).
    pub rx_pdos: Vec<SiiPdo>,
    /// DC operation modes.
    pub dc: Vec<SiiDcSync>,
    /// Other categories, raw: `(type, data)`; data length is even.
    pub other: Vec<(u16, Vec<u8>)>,
}

/// Why an image could not be parsed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SiiError {
    /// Shorter than the 128-byte fixed area.
    TooShort,
    /// The configuration area CRC (word 7) does not match.
    Checksum {
        /// CRC computed over bytes 0–13.
        computed: u8,
        /// CRC stored in byte 14.
        stored: u8,
    },
    /// A category runs past the end of the image or has no end marker:
    /// its type and the word address of its header.
    CategoryOverrun(u16, usize),
    /// A category's content is malformed: its type and the word address
    /// of its header.
    BadCategory(u16, usize),
}

impl fmt::Display for SiiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SiiError::TooShort => f.write_str("SII image shorter than 128 bytes"),
            SiiError::Checksum { computed, stored } => {
                write!(f, "SII configuration CRC {stored:#04x} stored, {computed:#04x} computed")
            }
            SiiError::CategoryOverrun(t, w) => {
                write!(f, "SII category {t} at word {w:#06x} (byte {:#06x}) runs past the image", w * 2)
            }
            SiiError::BadCategory(t, w) => {
                write!(f, "SII category {t} at word {w:#06x} (byte {:#06x}) is malformed", w * 2)
            }
        }
    }
}

/// A raw SII EEPROM image (bytes, little-endian words).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SiiImage {
    bytes: Vec<u8>,
}

impl SiiImage {
    /// Starts a typed builder.
    pub fn builder() -> SiiBuilder {
        SiiBuilder::default()
    }

    /// Wraps raw bytes (e.g. a dump); an odd length gets one 0xFF byte.
    pub fn from_bytes(mut bytes: Vec<u8>) -> SiiImage {
        if bytes.len() % 2 == 1 {
            bytes.push(0xFF);
        }
        SiiImage { bytes }
    }

    /// The raw bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Mutable raw bytes (the ESC writes words through the SII interface).
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.bytes
    }

    /// Word `addr`, or 0xFFFF past the end (an erased EEPROM cell).
    pub fn word(&self, addr: usize) -> u16 {
        match self.bytes.get(addr * 2..addr * 2 + 2) {
            Some(w) => u16::from_le_bytes([w[0], w[1]]),
            None => 0xFFFF,
        }
    }

    /// Number of words.
    pub fn words(&self) -> usize {
        self.bytes.len() / 2
    }

    /// True if the configuration-area CRC matches.
    pub fn checksum_ok(&self) -> bool {
        self.bytes.len() >= 16 && config_crc(&self.bytes[..14]) == self.bytes[14]
    }

    /// Decodes the image.
    pub fn parse(&self) -> Result<SiiContent, SiiError> {
        parse(&self.bytes)
    }
}

/// Typed builder for [`SiiImage`].
#[derive(Debug, Clone, Default)]
pub struct SiiBuilder {
    content: SiiContent,
}

impl SiiBuilder {
    /// Starts from decoded content (round trips).
    pub fn from_content(content: SiiContent) -> SiiBuilder {
        SiiBuilder { content }
    }

    /// Configuration area.
    pub fn config(mut self, config: ConfigArea) -> Self {
        self.content.config = config;
        self
    }

    /// Station alias (word 4).
    pub fn station_alias(mut self, alias: u16) -> Self {
        self.content.config.station_alias = alias;
        self
    }

    /// Identity.
    pub fn identity(mut self, vendor_id: u32, product_code: u32, revision: u32, serial: u32) -> Self {
        self.content.identity = Identity { vendor_id, product_code, revision, serial };
        self
    }

    /// Standard mailbox and its protocols.
    pub fn mailbox(mut self, mailbox: MailboxArea, protocols: u16) -> Self {
        self.content.mailbox = mailbox;
        self.content.mailbox_protocols = protocols;
        self
    }

    /// Bootstrap mailbox.
    pub fn bootstrap_mailbox(mut self, mailbox: MailboxArea) -> Self {
        self.content.bootstrap_mailbox = mailbox;
        self
    }

    /// Adds a string (deduplicated) and returns its 1-based index.
    pub fn add_string(&mut self, s: &str) -> u8 {
        if let Some(i) = self.content.strings.iter().position(|x| x == s) {
            return (i + 1) as u8;
        }
        self.content.strings.push(String::from(s));
        self.content.strings.len() as u8
    }

    /// General category; set the names with [`SiiBuilder::names`].
    pub fn general(mut self, general: General) -> Self {
        self.content.general = Some(general);
        self
    }

    /// Sets the order (device name), group and long name strings. The order
    /// string becomes string 1, as on ETG devices: ethercrab names a device
    /// after the General "order" index, SOEM after string 1.
    pub fn names(mut self, group: &str, order: &str, name: &str) -> Self {
        let o = self.add_string(order);
        let g = self.add_string(group);
        let n = self.add_string(name);
        let general = self.content.general.get_or_insert_with(General::default);
        general.group_idx = g;
        general.order_idx = o;
        general.name_idx = n;
        self
    }

    /// FMMU usage list, see [`fmmu_usage`].
    pub fn fmmus(mut self, usage: &[u8]) -> Self {
        self.content.fmmus = usage.to_vec();
        self
    }

    /// Adds a sync manager entry.
    pub fn sync_manager(mut self, sm: SiiSyncManager) -> Self {
        self.content.sync_managers.push(sm);
        self
    }

    /// Adds a TxPDO (inputs).
    pub fn tx_pdo(mut self, pdo: SiiPdo) -> Self {
        self.content.tx_pdos.push(pdo);
        self
    }

    /// Adds an RxPDO (outputs).
    pub fn rx_pdo(mut self, pdo: SiiPdo) -> Self {
        self.content.rx_pdos.push(pdo);
        self
    }

    /// Adds a DC operation mode.
    pub fn dc(mut self, dc: SiiDcSync) -> Self {
        self.content.dc.push(dc);
        self
    }

    /// Encodes the image.
    pub fn build(self) -> SiiImage {
        SiiImage { bytes: encode(&self.content) }
    }
}

fn put16(b: &mut Vec<u8>, v: u16) {
    b.extend_from_slice(&v.to_le_bytes());
}

fn put32(b: &mut Vec<u8>, v: u32) {
    b.extend_from_slice(&v.to_le_bytes());
}

fn push_category(out: &mut Vec<u8>, kind: u16, mut data: Vec<u8>) {
    if data.len() % 2 == 1 {
        data.push(0);
    }
    put16(out, kind);
    put16(out, (data.len() / 2) as u16);
    out.extend_from_slice(&data);
}

/// Encodes content into an image. The image is padded with 0xFF to a
/// power-of-two size of at least 2 Kbit; if `size_kbit` is 0 it is derived
/// from that size, and `version` 0 becomes 1.
pub fn encode(c: &SiiContent) -> Vec<u8> {
    let mut b = Vec::with_capacity(512);
    let cfg = &c.config;
    for w in [cfg.pdi_control, cfg.pdi_config, cfg.sync_impulse_len, cfg.pdi_config2, cfg.station_alias, 0, 0]
    {
        put16(&mut b, w);
    }
    let crc = config_crc(&b[..14]);
    put16(&mut b, u16::from(crc));
    let id = &c.identity;
    for v in [id.vendor_id, id.product_code, id.revision, id.serial] {
        put32(&mut b, v);
    }
    b.resize(0x14 * 2, 0);
    for m in [&c.bootstrap_mailbox, &c.mailbox] {
        for w in [m.rx_offset, m.rx_size, m.tx_offset, m.tx_size] {
            put16(&mut b, w);
        }
    }
    put16(&mut b, c.mailbox_protocols);
    b.resize(0x3E * 2, 0);
    let size_at = b.len();
    put16(&mut b, 0);
    put16(&mut b, if c.version == 0 { 1 } else { c.version });

    if !c.strings.is_empty() {
        let mut d = Vec::new();
        d.push(c.strings.len() as u8);
        for s in &c.strings {
            let s = &s.as_bytes()[..s.len().min(255)];
            d.push(s.len() as u8);
            d.extend_from_slice(s);
        }
        push_category(&mut b, category::STRINGS, d);
    }
    if let Some(g) = &c.general {
        let mut d = alloc::vec![
            g.group_idx,
            g.image_idx,
            g.order_idx,
            g.name_idx,
            0,
            g.coe_details,
            g.foe_details,
            g.eoe_details,
            g.soe_channels,
            g.ds402_channels,
            g.sysman_class,
            g.flags,
        ];
        d.extend_from_slice(&g.ebus_current.to_le_bytes());
        d.extend_from_slice(&g.physical_ports.to_le_bytes());
        d.extend_from_slice(&g.physical_memory_address.to_le_bytes());
        d.resize(32, 0);
        push_category(&mut b, category::GENERAL, d);
    }
    if !c.fmmus.is_empty() {
        let mut d = c.fmmus.clone();
        if d.len() % 2 == 1 {
            d.push(0xFF);
        }
        push_category(&mut b, category::FMMU, d);
    }
    if !c.sync_managers.is_empty() {
        let mut d = Vec::new();
        for s in &c.sync_managers {
            put16(&mut d, s.start);
            put16(&mut d, s.length);
            d.extend_from_slice(&[s.control, 0, s.enable, s.sm_type]);
        }
        push_category(&mut b, category::SYNC_MANAGER, d);
    }
    if !c.fmmu_ex.is_empty() {
        push_category(&mut b, category::FMMU_EX, c.fmmu_ex.clone());
    }
    for (kind, pdos) in [(category::TXPDO, &c.tx_pdos), (category::RXPDO, &c.rx_pdos)] {
        if pdos.is_empty() {
            continue;
        }
        let mut d = Vec::new();
        for p in pdos.iter() {
            put16(&mut d, p.index);
            d.extend_from_slice(&[p.entries.len() as u8, p.sync_manager, p.dc_sync, p.name_idx]);
            put16(&mut d, p.flags);
            for e in &p.entries {
                put16(&mut d, e.index);
                d.extend_from_slice(&[e.sub_index, e.name_idx, e.data_type, e.bit_len]);
                put16(&mut d, e.flags);
            }
        }
        push_category(&mut b, kind, d);
    }
    if !c.dc.is_empty() {
        let mut d = Vec::new();
        for s in &c.dc {
            put32(&mut d, s.cycle_time0);
            put32(&mut d, s.shift_time0);
            put32(&mut d, s.shift_time1);
            d.extend_from_slice(&s.sync1_cycle_factor.to_le_bytes());
            put16(&mut d, s.assign_activate);
            d.extend_from_slice(&s.sync0_cycle_factor.to_le_bytes());
            d.extend_from_slice(&[s.name_idx, s.desc_idx, 0, 0, 0, 0]);
        }
        push_category(&mut b, category::DC, d);
    }
    for (kind, data) in &c.other {
        push_category(&mut b, *kind, data.clone());
    }
    put16(&mut b, category::END);
    put16(&mut b, 0);

    let mut size = 256usize;
    while size < b.len() {
        size *= 2;
    }
    let kbit = if c.size_kbit != 0 { c.size_kbit } else { (size * 8 / 1024) as u16 };
    b[size_at..size_at + 2].copy_from_slice(&kbit.saturating_sub(1).to_le_bytes());
    b.resize(size.max(usize::from(kbit) * 128), 0xFF);
    b
}

mod parse;
pub use parse::parse;

#[cfg(test)]
mod tests;
