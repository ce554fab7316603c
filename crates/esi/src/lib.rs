//! EtherCAT Slave Information (ETG.2000 ESI XML) for drivebus devices,
//! generated from the same object dictionary the device serves over CoE
//! and describes in its EDS, plus the checks that the three agree.
//!
//! ```
//! use drivebus_esi::{DeviceFacts, SlaveDescription};
//! let eds = drivebus_eds::parse(include_str!("../../personality/eds/ipos.eds")).unwrap().eds;
//! let od = drivebus_eds::to_od(&eds, 1).unwrap();
//! let facts = drivebus_esi::ipos::facts(0x1A3, "Technosoft S.A.", 28_002_021, "iPOS360x VX-CAT");
//! let desc = SlaveDescription::new(&od, &facts);
//! let xml = drivebus_esi::write(&desc);
//! assert!(drivebus_esi::validate(&xml).iter().all(|p| !p.is_error()));
//! let mut back = drivebus_esi::read(&xml).unwrap();
//! back.serial = desc.serial; // ETG.2000 has no serial number
//! assert_eq!(back, desc);
//! ```
//!
//! * [`SlaveDescription`] is one device as an ESI file describes it;
//!   [`SlaveDescription::new`] builds it from an [`ObjectDictionary`] and
//!   [`DeviceFacts`] (identity, names, ESC layout, protocols, DC, EEPROM);
//!   [`ipos::facts`] gives the Technosoft iPOS twin's facts.
//! * [`write()`] gives the XML (deterministic, schema element order,
//!   escaped by `quick-xml`); [`read`] reads it back; [`validate`] checks
//!   a file has what ETG.2000 and the masters (TwinCAT, SOEM, ethercrab)
//!   need.
//! * [`check_dictionary`], [`check_eds`] and [`check_ethercat`] report,
//!   item by item, where an ESI disagrees with a dictionary or an EDS and
//!   what an EtherCAT dictionary lacks.
//! * [`firmware_revision`] implements Technosoft's revision naming
//!   (iPOS manual §1.5.4.6).
//!
//! # Why `quick-xml`
//!
//! It is maintained, MIT-licensed, has no mandatory dependencies, and
//! offers both a streaming writer (whose escaping makes every name safe)
//! and a pull reader, so one dependency writes and reads. Writing event by
//! event keeps full control of element order, `#x` formatting and
//! attribute order, which a serde mapping would not; no DOM is needed.
//!
//! # What the SII image needs from [`SlaveDescription`]
//!
//! | SII (ETG.1000.6 §5.4) | from |
//! |---|---|
//! | words 0x00–0x06 configuration area, CRC in word 7 | `eeprom.config` ([`ConfigArea`]) |
//! | words 0x08–0x0F identity | `vendor_id`, `product_code`, `revision`, `serial` |
//! | words 0x14–0x17 bootstrap mailbox | `eeprom.bootstrap` |
//! | words 0x18–0x1B standard mailbox | the `MBoxOut`/`MBoxIn` entries of `sync_managers` (start, `default_size`) |
//! | word 0x1C mailbox protocols | [`SlaveDescription::sii_mailbox_protocols`] |
//! | word 0x3E size | `eeprom.byte_size` / 128 − 1 |
//! | Strings / General group, order, name | `group_type`, `type_name`, `name` |
//! | General CoE details, FoE/EoE details | [`SlaveDescription::sii_coe_details`], `mailbox` |
//! | General flags (0x04 mailbox DLL) | `mailbox.data_link_layer` |
//! | General physical ports | [`SlaveDescription::sii_physical_ports`] |
//! | FMMU category | `fmmus` ([`FmmuUsage::sii_code`]) |
//! | SyncManager category | `sync_managers`: start, `default_size`, `control`, `enable` (bit 0), [`SmKind::code`] |
//! | TxPDO / RxPDO categories | `tx_pdos` / `rx_pdos`: index, `sm` (SM number; unassigned PDOs need one picked by the builder), name, entries (index, sub, bit length, name, data type code `DataType as u16`) |
//! | DC category | `dc`: `assign_activate`, `sync0` cycle/factor/shift, `sync1` factor/shift, name, desc |
//!
//! E-bus current is 0 (MII ports). ethercrab reads only the General, FMMU
//! and SM categories of a CoE device and takes its PDOs over CoE.
//!
//! # What is simplified, and why
//!
//! * One device per file, English names only (`LcId` 1033); no modules,
//!   slots, images, `Category`, PDO `Exclude` or vendor-specific parts:
//!   a drivebus device has none of them.
//! * What ETG.2000 cannot say is written the nearest way and compared that
//!   way: node-ID-relative defaults are written evaluated; `const` is `ro`;
//!   a VAR's value has the object's name; an ARRAY whose elements differ in
//!   type or access (or has gaps) is written as a record; dummy mapping
//!   entries (0001h–0007h) become gaps (`Index` 0); the serial number is
//!   not in the file.
//! * Type names follow the Beckhoff slave code tool: `DTxxxx` for arrays
//!   and records, `DTxxxxARR` for array elements, `STRING(n)`,
//!   `ARRAY [0..n-1] OF BYTE` for octet strings; the reader also takes
//!   IEC-style array names.
//! * The dictionary knows no ESM states: read/write restrictions come from
//!   [`DeviceFacts::state_rules`] (the iPOS: 1C12h/1C13h in PRE-OP only).
//! * DC op modes carry `AssignActivate` and SYNC0/SYNC1 cycle and shift,
//!   not op-mode-specific SM or PDO assignments.
//! * The reader reads what the writer writes and the usual variants of
//!   other vendors' files; [`validate`] checks what the masters need, it is
//!   not a full XML-schema validator.
//!
//! [`ObjectDictionary`]: drivebus_od::ObjectDictionary

mod check;
mod check_ecat;
mod description;
mod dictionary;
mod from_sii;
pub mod ipos;
mod model;
mod pdo;
mod read;
mod revision;
pub mod sii;
pub mod types;
mod validate;
mod write;
mod write_dict;
mod xml;

pub use check::{CheckOptions, Disagreement, Source, check_dictionary, check_eds};
pub use check_ecat::check_ethercat;
pub use description::{
    ALL_STATES, CoeDetails, ConfigArea, DcOpMode, DeviceFacts, Eeprom, EsiPdo, EsiProfile, FmmuUsage,
    Mailbox, MailboxArea, MailboxTimeouts, PREOP, PdoEntry, SlaveDescription, SmKind, StateRule, SyncManager,
    SyncSignal, apply_rules, default_config_area, free_run,
};
pub use dictionary::{device_objects, dictionary, objects_from_description};
pub use from_sii::describe_sii;
pub use model::{EsiObject, EsiSub, ObjectKind, access_flags};
pub use pdo::{default_assignment, mapping_values};
pub use read::{ReadError, read, read_all};
pub use revision::{RevisionError, firmware_revision, revision_firmware};
pub use validate::{Problem, validate};
pub use write::{SCHEMA_VERSION, write};
pub use xml::{Element, XmlError, parse as parse_xml};
