//! [`SlaveDescription`]: everything an ESI file says about one device,
//! built from the running dictionary plus the facts a dictionary cannot
//! hold (names, ESC layout, mailbox protocols, DC modes, EEPROM).

use crate::model::EsiObject;
use crate::pdo;
use drivebus_coe::{access_bits, default_object_access};
use drivebus_od::{DataType, ObjectDictionary, SubObject};

/// One EtherCAT device as an ESI file (ETG.2000) describes it. Every field
/// is written to the file and read back, except [`SlaveDescription::serial`].
///
/// The SII EEPROM image (ETG.1000.6 §5.4) can be generated from the same
/// value; see the crate documentation for which field feeds which SII word.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SlaveDescription {
    /// `Vendor/Id` and 1018h:01; SII words 0x08–0x09.
    pub vendor_id: u32,
    /// `Vendor/Name`.
    pub vendor_name: String,
    /// `Device/Type@ProductCode` and 1018h:02; SII words 0x0A–0x0B.
    pub product_code: u32,
    /// `Device/Type@RevisionNo` and 1018h:03; SII words 0x0C–0x0D. For
    /// Technosoft drives the firmware ID in ASCII ([`crate::firmware_revision`]).
    pub revision: u32,
    /// 1018h:04; SII words 0x0E–0x0F. ETG.2000 has no element for it: not
    /// written to the ESI, read back as 0.
    pub serial: u32,
    /// `Device/Type` text: the order number TwinCAT lists, and the SII
    /// "order" string (ethercrab names the device after it).
    pub type_name: String,
    /// `Device/Name` (LcId 1033): the long name; SII "name" string.
    pub name: String,
    /// `Groups/Group/Type` and `Device/GroupType`; SII "group" string.
    pub group_type: String,
    /// `Groups/Group/Name`.
    pub group_name: String,
    /// `Device/URL`, if any.
    pub url: Option<String>,
    /// `Device@Physics`: one letter per port (`Y` MII, `K` E-Bus, `H`
    /// fast hot-connect); SII General "physical ports" nibbles.
    pub physics: String,
    /// `Device/Info/Mailbox/Timeout` (ms), if the device needs other than
    /// the master's defaults.
    pub mailbox_timeouts: Option<MailboxTimeouts>,
    /// `Profile/ProfileNo` (402) and `Profile/AddInfo`.
    pub profile: EsiProfile,
    /// `Profile/Dictionary/Objects`: the object dictionary as ETG.2000 can
    /// describe it, in index order.
    pub objects: Vec<EsiObject>,
    /// `Fmmu` elements in order; SII FMMU category.
    pub fmmus: Vec<FmmuUsage>,
    /// `Sm` elements in order (index = SM number); SII SyncManager category.
    pub sync_managers: Vec<SyncManager>,
    /// `RxPdo` elements: default-assigned first (in 1C12h order), then the
    /// others by index; SII RxPDO category.
    pub rx_pdos: Vec<EsiPdo>,
    /// `TxPdo` elements, ordered like [`SlaveDescription::rx_pdos`].
    pub tx_pdos: Vec<EsiPdo>,
    /// `Mailbox`, if the device has one; SII word 0x1C and General CoE details.
    pub mailbox: Option<Mailbox>,
    /// `Dc/OpMode` elements; SII DC category.
    pub dc: Vec<DcOpMode>,
    /// `Eeprom`: size, configuration area, bootstrap mailbox.
    pub eeprom: Eeprom,
}

/// `Profile`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EsiProfile {
    /// `ProfileNo`: the device profile (402 for CiA 402 drives), 1000h bits 0–15.
    pub number: u16,
    /// `AddInfo`: 1000h bits 16–31 (the CiA 402 drive type).
    pub add_info: u16,
}

/// `Device/Info/Mailbox/Timeout`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MailboxTimeouts {
    /// `RequestTimeout` in ms.
    pub request_ms: u32,
    /// `ResponseTimeout` in ms.
    pub response_ms: u32,
}

/// What an FMMU is for (`Fmmu` text; SII FMMU codes 1, 2, 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FmmuUsage {
    /// Process data outputs (master → slave).
    Outputs,
    /// Process data inputs (slave → master).
    Inputs,
    /// The SM1 status byte, for mailbox polling.
    MBoxState,
}

impl FmmuUsage {
    /// The `Fmmu` element text.
    pub fn name(self) -> &'static str {
        match self {
            FmmuUsage::Outputs => "Outputs",
            FmmuUsage::Inputs => "Inputs",
            FmmuUsage::MBoxState => "MBoxState",
        }
    }
    /// The SII FMMU category code (ETG.1000.6 Table 23).
    pub fn sii_code(self) -> u8 {
        match self {
            FmmuUsage::Outputs => 1,
            FmmuUsage::Inputs => 2,
            FmmuUsage::MBoxState => 3,
        }
    }
}

/// What a sync manager carries (`Sm` text; SII SM type 1–4 and 1C00h values).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SmKind {
    /// Mailbox master → slave (SM0).
    MBoxOut,
    /// Mailbox slave → master (SM1).
    MBoxIn,
    /// Process data outputs, RxPDOs (SM2).
    Outputs,
    /// Process data inputs, TxPDOs (SM3).
    Inputs,
}

impl SmKind {
    /// The `Sm` element text.
    pub fn name(self) -> &'static str {
        match self {
            SmKind::MBoxOut => "MBoxOut",
            SmKind::MBoxIn => "MBoxIn",
            SmKind::Outputs => "Outputs",
            SmKind::Inputs => "Inputs",
        }
    }
    /// The SII type and 1C00h communication type (ETG.1000.6: 1 mailbox
    /// receive, 2 mailbox send, 3 process data output, 4 process data input).
    pub fn code(self) -> u8 {
        match self {
            SmKind::MBoxOut => 1,
            SmKind::MBoxIn => 2,
            SmKind::Outputs => 3,
            SmKind::Inputs => 4,
        }
    }
}

/// One `Sm` element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncManager {
    /// What it carries.
    pub kind: SmKind,
    /// `StartAddress` in the ESC's process RAM.
    pub start: u16,
    /// `DefaultSize` in bytes: the mailbox size, or the process data size of
    /// the default PDO assignment.
    pub default_size: Option<u16>,
    /// `ControlByte` (register 0x0804): 0x26 mailbox write, 0x22 mailbox
    /// read, 0x64 3-buffer write with watchdog, 0x20 3-buffer read.
    pub control: u8,
    /// `Enable` (SII enable byte bit 0).
    pub enable: bool,
}

/// One `RxPdo`/`TxPdo` element.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EsiPdo {
    /// `Index`: the mapping object (16xxh/1Axxh).
    pub index: u16,
    /// `Name`: the mapping object's name.
    pub name: String,
    /// `@Sm`: the sync manager it is assigned to by default (1C12h/1C13h);
    /// `None` when not assigned by default.
    pub sm: Option<u8>,
    /// `@Fixed`: the mapping cannot be changed (sub 0 not writable).
    pub fixed: bool,
    /// `@Mandatory`: the PDO must stay assigned.
    pub mandatory: bool,
    /// `Entry` elements: the default mapping.
    pub entries: Vec<PdoEntry>,
}

impl EsiPdo {
    /// Bits of the default mapping.
    pub fn bits(&self) -> u32 {
        self.entries.iter().map(|e| u32::from(e.bit_len)).sum()
    }
}

/// One `Entry` of a PDO.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PdoEntry {
    /// Mapped object; 0 for a gap (dummy entries 0001h–0007h are written as gaps).
    pub index: u16,
    /// Mapped sub-index.
    pub sub: u8,
    /// `BitLen`.
    pub bit_len: u8,
    /// `Name` of the mapped entry.
    pub name: String,
    /// `DataType`; `None` for a gap or an entry the dictionary lacks.
    pub data_type: Option<DataType>,
}

/// `Mailbox`: protocols and their details.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mailbox {
    /// `@DataLinkLayer`: the mailbox counter and SM1 repeat are handled
    /// (ETG.1000.4 §5.6); SII General flag 0x04.
    pub data_link_layer: bool,
    /// `CoE`, if announced (SII protocol bit 0x04).
    pub coe: Option<CoeDetails>,
    /// `FoE` announced (SII protocol bit 0x08).
    pub foe: bool,
    /// `EoE` announced (SII protocol bit 0x02).
    pub eoe: bool,
}

/// `CoE` attributes; SII General "CoE details" bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CoeDetails {
    /// `@SdoInfo` (bit 0x02).
    pub sdo_info: bool,
    /// `@PdoAssign`: 1C12h/1C13h writable (bit 0x04).
    pub pdo_assign: bool,
    /// `@PdoConfig`: mapping objects writable (bit 0x08).
    pub pdo_config: bool,
    /// `@PdoUpload`: the master reads the mapping at startup (bit 0x10).
    pub pdo_upload: bool,
    /// `@CompleteAccess` (bit 0x20); SOEM then reads 1C12h/1C13h by CA.
    pub complete_access: bool,
}

/// One `Dc/OpMode`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DcOpMode {
    /// `Name`: `FreeRun`, `DC`, …
    pub name: String,
    /// `Desc`: what TwinCAT shows.
    pub desc: String,
    /// `AssignActivate`: value for registers 0x0980–0x0981 (0x0300 = cyclic
    /// unit on, SYNC0 on; 0 = no DC).
    pub assign_activate: u16,
    /// `CycleTimeSync0`/`ShiftTimeSync0`, for modes using SYNC0.
    pub sync0: Option<SyncSignal>,
    /// `CycleTimeSync1`/`ShiftTimeSync1`, for modes using SYNC1.
    pub sync1: Option<SyncSignal>,
}

/// Cycle and shift of one SYNC signal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncSignal {
    /// Cycle time in ns; 0 means `factor` × the master's cycle.
    pub cycle_ns: u32,
    /// `@Factor` of the cycle time.
    pub factor: i16,
    /// Shift time in ns.
    pub shift_ns: u32,
}

/// `Eeprom`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Eeprom {
    /// `ByteSize`; SII word 0x3E = ByteSize / 128 − 1 (Kbit − 1).
    pub byte_size: u32,
    /// `ConfigData`: SII words 0x00–0x06.
    pub config: ConfigArea,
    /// `BootStrap`: SII words 0x14–0x17, the mailbox in BOOT.
    pub bootstrap: Option<MailboxArea>,
}

/// SII words 0x00–0x06, the ESI's `ConfigData`: the SII's own type.
pub use drivebus_esc::sii::ConfigArea;

/// Mailbox offsets and sizes (`BootStrap`): the SII's own type.
pub use drivebus_esc::sii::MailboxArea;

/// Restricts the ESM states in which entries may be read or written
/// (ETG.2000 `ReadRestrictions`/`WriteRestrictions`, SDO Information
/// access bits), e.g. 1C12h writable only in PRE-OP (iPOS §2.3.10).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateRule {
    /// Object index.
    pub index: u16,
    /// One sub-index, or every sub-index.
    pub sub: Option<u8>,
    /// States (bit 0 PRE-OP, 1 SAFE-OP, 2 OP) in which reading stays allowed.
    pub read: u16,
    /// States in which writing stays allowed.
    pub write: u16,
}

/// All states: no restriction.
pub const ALL_STATES: u16 = 0b111;
/// PRE-OP only.
pub const PREOP: u16 = 0b001;

/// What the dictionary cannot tell about a device: identity as the ESI
/// states it, names, ESC layout and protocols.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceFacts {
    /// Vendor ID.
    pub vendor_id: u32,
    /// Vendor name.
    pub vendor_name: String,
    /// Product code.
    pub product_code: u32,
    /// Revision number.
    pub revision: u32,
    /// Serial number (SII only).
    pub serial: u32,
    /// Order number (`Device/Type` text).
    pub type_name: String,
    /// Long name.
    pub name: String,
    /// Group type identifier.
    pub group_type: String,
    /// Group display name.
    pub group_name: String,
    /// URL.
    pub url: Option<String>,
    /// Port physics.
    pub physics: String,
    /// Mailbox timeouts.
    pub mailbox_timeouts: Option<MailboxTimeouts>,
    /// Device profile number (`ProfileNo`); `None`: 1000h bits 0–15.
    pub profile_no: Option<u16>,
    /// SM0/SM1 (receive/send) mailbox; `None` for a device without mailbox.
    pub mailbox_area: Option<MailboxArea>,
    /// SM2 start address and control byte.
    pub outputs_sm: (u16, u8),
    /// SM3 start address and control byte.
    pub inputs_sm: (u16, u8),
    /// FMMUs.
    pub fmmus: Vec<FmmuUsage>,
    /// Mailbox protocols.
    pub mailbox: Option<Mailbox>,
    /// DC operation modes.
    pub dc: Vec<DcOpMode>,
    /// EEPROM.
    pub eeprom: Eeprom,
    /// State-dependent access restrictions.
    pub state_rules: Vec<StateRule>,
}

impl DeviceFacts {
    /// Facts with drivebus's default ESC layout: 512-byte mailboxes at
    /// 0x1000/0x1200, SM2 at 0x1400 (0x64), SM3 at 0x1800 (0x20), FMMUs for
    /// outputs, inputs and the mailbox state, two MII ports, CoE with every
    /// detail the `drivebus-coe` server implements, no FoE, free run only,
    /// a 2 KiB EEPROM.
    pub fn new(vendor_id: u32, vendor_name: &str, product_code: u32, revision: u32, product: &str) -> Self {
        let mbx = MailboxArea { rx_offset: 0x1000, rx_size: 512, tx_offset: 0x1200, tx_size: 512 };
        DeviceFacts {
            vendor_id,
            vendor_name: vendor_name.into(),
            product_code,
            revision,
            serial: 0,
            type_name: product.into(),
            name: product.into(),
            group_type: "Drives".into(),
            group_name: "Drives".into(),
            url: None,
            physics: "YY".into(),
            mailbox_timeouts: None,
            profile_no: None,
            mailbox_area: Some(mbx),
            outputs_sm: (0x1400, 0x64),
            inputs_sm: (0x1800, 0x20),
            fmmus: vec![FmmuUsage::Outputs, FmmuUsage::Inputs, FmmuUsage::MBoxState],
            mailbox: Some(Mailbox {
                data_link_layer: true,
                coe: Some(CoeDetails {
                    sdo_info: true,
                    pdo_assign: true,
                    pdo_config: true,
                    pdo_upload: false,
                    complete_access: true,
                }),
                foe: false,
                eoe: false,
            }),
            dc: vec![free_run()],
            eeprom: Eeprom { byte_size: 2048, config: default_config_area(), bootstrap: None },
            state_rules: Vec::new(),
        }
    }

    /// The access word of a dictionary entry: what SDO Information reports
    /// for it ([`default_object_access`]) narrowed by the state rules.
    pub fn object_access(&self, index: u16, s: &SubObject) -> u16 {
        apply_rules(&self.state_rules, index, s.sub, default_object_access(s))
    }
}

/// Narrow an access word by the rules that name `(index, sub)`.
pub fn apply_rules(rules: &[StateRule], index: u16, sub: u8, word: u16) -> u16 {
    rules.iter().filter(|r| r.index == index && r.sub.is_none_or(|s| s == sub)).fold(word, |w, r| {
        let keep = r.read | (r.write << 3) | !(access_bits::READ | access_bits::WRITE);
        w & keep
    })
}

/// The `FreeRun` mode every device has: no DC (AssignActivate 0).
pub fn free_run() -> DcOpMode {
    DcOpMode { name: "FreeRun".into(), desc: "FreeRun".into(), assign_activate: 0, sync0: None, sync1: None }
}

/// SII configuration words for drivebus's software ESC: an SPI PDI
/// (0x05), DC SYNC output unit on (0x0141 bit 2), SYNC0 driven as an
/// active-low push-pull output and mapped to the AL event (0x0151 = 0x0C),
/// a 10 µs SYNC impulse (1000 × 10 ns, the ESC's reset value of 0x0982).
pub fn default_config_area() -> ConfigArea {
    ConfigArea {
        pdi_control: 0x0405,
        pdi_config: 0x0C00,
        sync_impulse_len: 1000,
        pdi_config2: 0,
        station_alias: 0,
    }
}

impl SlaveDescription {
    /// Describe `od` with `facts`: the dictionary's objects (defaults, not
    /// current values), its PDO mapping objects with their default mapping,
    /// the default assignment from 1C12h/1C13h (or, on a CAN dictionary,
    /// the PDOs whose COB-ID is valid) and the process data SM sizes that
    /// assignment gives. Never fails: what does not fit is left for
    /// [`crate::check_dictionary`] and [`crate::check_ethercat`] to report.
    pub fn new(od: &ObjectDictionary, facts: &DeviceFacts) -> SlaveDescription {
        let objects: Vec<EsiObject> = od
            .objects()
            .iter()
            .map(|o| EsiObject::from_od(o, |index, s| facts.object_access(index, s)))
            .collect();
        let device_type = od.get(0x1000, 0).map_or(0, |s| drivebus_od::le_u64(&s.default) as u32);
        let mut sync_managers = Vec::new();
        if let Some(m) = facts.mailbox_area {
            sync_managers.push(SyncManager {
                kind: SmKind::MBoxOut,
                start: m.rx_offset,
                default_size: Some(m.rx_size),
                control: 0x26,
                enable: true,
            });
            sync_managers.push(SyncManager {
                kind: SmKind::MBoxIn,
                start: m.tx_offset,
                default_size: Some(m.tx_size),
                control: 0x22,
                enable: true,
            });
        }
        let out_sm = sync_managers.len() as u8;
        let in_sm = out_sm + 1;
        let (rx_pdos, tx_pdos) = pdo::describe(od, &objects, out_sm, in_sm);
        let size = |pdos: &[EsiPdo]| {
            let bits: u32 = pdos.iter().filter(|p| p.sm.is_some()).map(EsiPdo::bits).sum();
            Some(u16::try_from(bits.div_ceil(8)).unwrap_or(u16::MAX))
        };
        for (kind, (start, control), pdos) in
            [(SmKind::Outputs, facts.outputs_sm, &rx_pdos), (SmKind::Inputs, facts.inputs_sm, &tx_pdos)]
        {
            sync_managers.push(SyncManager { kind, start, default_size: size(pdos), control, enable: true });
        }
        SlaveDescription {
            vendor_id: facts.vendor_id,
            vendor_name: facts.vendor_name.clone(),
            product_code: facts.product_code,
            revision: facts.revision,
            serial: facts.serial,
            type_name: facts.type_name.clone(),
            name: facts.name.clone(),
            group_type: facts.group_type.clone(),
            group_name: facts.group_name.clone(),
            url: facts.url.clone(),
            physics: facts.physics.clone(),
            mailbox_timeouts: facts.mailbox_timeouts,
            profile: EsiProfile {
                number: facts.profile_no.unwrap_or(device_type as u16),
                add_info: (device_type >> 16) as u16,
            },
            objects,
            fmmus: facts.fmmus.clone(),
            sync_managers,
            rx_pdos,
            tx_pdos,
            mailbox: facts.mailbox,
            dc: facts.dc.clone(),
            eeprom: facts.eeprom,
        }
    }

    /// One object.
    pub fn object(&self, index: u16) -> Option<&EsiObject> {
        self.objects.binary_search_by_key(&index, |o| o.index).ok().map(|i| &self.objects[i])
    }

    /// The first sync manager of a kind and its number.
    pub fn sm(&self, kind: SmKind) -> Option<(u8, &SyncManager)> {
        self.sync_managers.iter().enumerate().find(|(_, s)| s.kind == kind).map(|(i, s)| (i as u8, s))
    }

    /// SII word 0x1C: mailbox protocols (EoE 0x02, CoE 0x04, FoE 0x08).
    pub fn sii_mailbox_protocols(&self) -> u16 {
        self.mailbox.map_or(0, |m| {
            [(m.eoe, 0x02), (m.coe.is_some(), 0x04), (m.foe, 0x08)]
                .into_iter()
                .filter(|(on, _)| *on)
                .fold(0, |acc, (_, bit)| acc | bit)
        })
    }

    /// SII General "CoE details": 0x01 SDO, 0x02 SDO Info, 0x04 PDO assign,
    /// 0x08 PDO config, 0x10 upload at startup, 0x20 complete access.
    pub fn sii_coe_details(&self) -> u8 {
        self.mailbox.and_then(|m| m.coe).map_or(0, |c| {
            [(true, 0x01), (c.sdo_info, 0x02), (c.pdo_assign, 0x04), (c.pdo_config, 0x08)]
                .into_iter()
                .chain([(c.pdo_upload, 0x10), (c.complete_access, 0x20)])
                .filter(|(on, _)| *on)
                .fold(0, |acc, (_, bit)| acc | bit)
        })
    }

    /// SII General "physical ports": a nibble per port from `physics`
    /// (`Y` 1 MII, `K` 3 E-Bus, `H` 4 fast hot-connect, else 0), port 0 lowest.
    pub fn sii_physical_ports(&self) -> u16 {
        self.physics.chars().take(4).enumerate().fold(0, |acc, (i, c)| {
            let code = match c {
                'Y' => 1,
                'K' => 3,
                'H' => 4,
                _ => 0,
            };
            acc | (code << (4 * i))
        })
    }

    /// The number of objects in the dictionary.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// The smallest SM1 (mailbox send) size ethercrab 0.7.1 can use with
    /// this dictionary (`drivebus-coe` crate docs): 16 bytes more than the
    /// largest value, and 14 + 2 × objects for the OD list.
    pub fn ethercrab_min_mailbox_in(&self) -> usize {
        let largest = self.objects.iter().flat_map(|o| &o.subs).map(|s| s.len).max().unwrap_or(0);
        (16 + largest).max(14 + 2 * self.objects.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use access_bits::*;
    use drivebus_od::{Access, Value};

    #[test]
    fn state_rules_narrow_the_access_word() {
        let rules = [StateRule { index: 0x1C12, sub: None, read: ALL_STATES, write: PREOP }];
        let w = READ | WRITE | BACKUP | SETTINGS;
        assert_eq!(apply_rules(&rules, 0x1C12, 3, w), READ | WRITE_PREOP | BACKUP | SETTINGS);
        assert_eq!(apply_rules(&rules, 0x1C13, 3, w), w);
        assert_eq!(apply_rules(&rules, 0x1C12, 0, READ), READ, "a read-only entry stays read-only");
        let s = SubObject::new(1, "x", DataType::Unsigned16, Access::Rw, Value::U16(0));
        let mut f = DeviceFacts::new(1, "v", 2, 3, "p");
        f.state_rules = rules.to_vec();
        assert_eq!(f.object_access(0x1C12, &s) & WRITE, WRITE_PREOP);
    }

    #[test]
    fn sii_words() {
        let od = ObjectDictionary::new();
        let mut d = SlaveDescription::new(&od, &DeviceFacts::new(1, "v", 2, 3, "p"));
        assert_eq!(d.sii_mailbox_protocols(), 0x04);
        assert_eq!(d.sii_coe_details(), 0x2F);
        assert_eq!(d.sii_physical_ports(), 0x11);
        d.physics = "YYK".into();
        assert_eq!(d.sii_physical_ports(), 0x311);
        let c = default_config_area();
        assert_eq!(ConfigArea::from_bytes(&c.bytes()), c);
        assert_eq!(c.bytes()[..6], [0x05, 0x04, 0x00, 0x0C, 0xE8, 0x03]);
        assert_eq!(d.sm(SmKind::Inputs).map(|(i, s)| (i, s.start)), Some((3, 0x1800)));
        assert_eq!(d.ethercrab_min_mailbox_in(), 16);
    }
}
