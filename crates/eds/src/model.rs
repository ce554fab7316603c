//! The in-memory form of an EDS or DCF file.
//!
//! Values are kept as the file wrote them (`$NODEID+0x180`, `0x10`, `017`),
//! so writing a file back reproduces it; conversion to an object dictionary
//! evaluates them.

use drivebus_od::{Access, ObjectCode};
use std::collections::BTreeMap;

/// A whole EDS (or DCF, when `commissioning` is present).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Eds {
    /// `[FileInfo]` keys in file order, verbatim.
    pub file_info: Vec<(String, String)>,
    /// `[DeviceInfo]`.
    pub device_info: DeviceInfo,
    /// `[DummyUsage]` (CiA 306 §4.5): the `DummyXXXX` entries the file has,
    /// by data type index (standard files list 0001h–0007h; tools such as
    /// Lely's write 0010h–001Bh too), `true` where the dummy is supported.
    pub dummy_usage: BTreeMap<u16, bool>,
    /// `[Comments]` lines.
    pub comments: Vec<String>,
    /// Objects by index.
    pub objects: BTreeMap<u16, EdsObject>,
    /// `[MandatoryObjects]` as listed.
    pub mandatory: Vec<u16>,
    /// `[OptionalObjects]` as listed.
    pub optional: Vec<u16>,
    /// `[ManufacturerObjects]` as listed.
    pub manufacturer: Vec<u16>,
    /// `[DeviceComissioning]` (DCF only).
    pub commissioning: Option<Commissioning>,
    /// Sections this reader does not interpret (tool sections), verbatim.
    pub other_sections: Vec<(String, Vec<(String, String)>)>,
}

impl Eds {
    /// Whether the file declares dummy mapping of data type `index`
    /// (`DummyXXXX=1`).
    pub fn dummy_supported(&self, index: u16) -> bool {
        self.dummy_usage.get(&index).copied().unwrap_or(false)
    }

    /// Forget the line numbers (for comparing files read from different texts).
    pub fn strip_lines(&mut self) {
        for o in self.objects.values_mut() {
            o.line = 0;
            if let Some(v) = &mut o.var {
                v.line = 0;
            }
            for v in o.subs.values_mut() {
                v.line = 0;
            }
        }
    }
}

/// `[DeviceInfo]` (CiA 306 §4.4).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeviceInfo {
    /// VendorName.
    pub vendor_name: String,
    /// VendorNumber (1018h:1).
    pub vendor_number: Option<u32>,
    /// ProductName.
    pub product_name: String,
    /// ProductNumber (1018h:2).
    pub product_number: Option<u32>,
    /// RevisionNumber (1018h:3).
    pub revision_number: Option<u32>,
    /// OrderCode.
    pub order_code: String,
    /// Supported bit rates in kbit/s (`BaudRate_10` .. `BaudRate_1000`).
    pub baud_rates: Vec<u32>,
    /// SimpleBootUpMaster.
    pub simple_boot_up_master: bool,
    /// SimpleBootUpSlave.
    pub simple_boot_up_slave: bool,
    /// Granularity: 0 = no mapping, 1..=64 = bits per mapping unit (8 = byte).
    pub granularity: u8,
    /// DynamicChannelsSupported.
    pub dynamic_channels_supported: u8,
    /// GroupMessaging.
    pub group_messaging: bool,
    /// NrOfRXPDO.
    pub nr_of_rx_pdo: u16,
    /// NrOfTXPDO.
    pub nr_of_tx_pdo: u16,
    /// LSS_Supported.
    pub lss_supported: bool,
    /// Keys this reader does not interpret, verbatim.
    pub other: Vec<(String, String)>,
}

/// `[DeviceComissioning]` of a DCF (CiA 306 spells it with one "m").
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Commissioning {
    /// NodeID.
    pub node_id: u8,
    /// NodeName.
    pub node_name: String,
    /// Baudrate in kbit/s.
    pub baudrate: u32,
    /// NetNumber.
    pub net_number: u32,
    /// NetworkName.
    pub network_name: String,
    /// CANopenManager.
    pub canopen_manager: bool,
    /// LSS_SerialNumber.
    pub lss_serial_number: Option<u32>,
    /// Keys this reader does not interpret (`NodeRefd`, `NetRefd`), verbatim.
    pub other: Vec<(String, String)>,
}

/// One object section and its sub-objects.
#[derive(Clone, Debug, PartialEq)]
pub struct EdsObject {
    /// Index.
    pub index: u16,
    /// ParameterName.
    pub name: String,
    /// ObjectType.
    pub object_type: ObjectCode,
    /// SubNumber as written.
    pub sub_number: Option<u8>,
    /// CompactSubObj: subs 1..=n are implied from the object's own keys.
    pub compact_sub_obj: Option<u8>,
    /// ObjFlags.
    pub obj_flags: u32,
    /// For VAR and DOMAIN: the value description of the object itself.
    pub var: Option<EdsVar>,
    /// Sub-objects (explicit `[xxxxsubN]` sections, or expanded compact ones).
    pub subs: BTreeMap<u8, EdsVar>,
    /// `[xxxxName]` entries of a compact object.
    pub compact_names: BTreeMap<u8, String>,
    /// `[xxxxValue]` entries of a compact object.
    pub compact_values: BTreeMap<u8, String>,
    /// 1-based line of the section header (0 when built in code).
    pub line: usize,
}

/// A value description: a VAR object, or one sub-object.
#[derive(Clone, Debug, PartialEq)]
pub struct EdsVar {
    /// ParameterName.
    pub name: String,
    /// DataType as its CiA 301 index (0x0007 = UNSIGNED32).
    pub data_type: u16,
    /// AccessType.
    pub access: Access,
    /// DefaultValue as written.
    pub default: Option<String>,
    /// ParameterValue as written (DCF).
    pub parameter_value: Option<String>,
    /// LowLimit as written.
    pub low_limit: Option<String>,
    /// HighLimit as written.
    pub high_limit: Option<String>,
    /// PDOMapping.
    pub pdo_mapping: bool,
    /// ObjFlags.
    pub obj_flags: u32,
    /// UploadFile (DOMAIN).
    pub upload_file: Option<String>,
    /// DownloadFile (DOMAIN).
    pub download_file: Option<String>,
    /// Denotation (DCF).
    pub denotation: Option<String>,
    /// 1-based line of the section (0 when built in code).
    pub line: usize,
}

impl EdsVar {
    /// A value description with no default, limits or flags.
    pub fn new(name: impl Into<String>, data_type: u16, access: Access) -> EdsVar {
        EdsVar {
            name: name.into(),
            data_type,
            access,
            default: None,
            parameter_value: None,
            low_limit: None,
            high_limit: None,
            pdo_mapping: false,
            obj_flags: 0,
            upload_file: None,
            download_file: None,
            denotation: None,
            line: 0,
        }
    }
}

/// A problem found while reading, with the line it is on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// 1-based line (0 if not tied to a line).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(f, "line {}: {}", self.line, self.message)
        } else {
            f.write_str(&self.message)
        }
    }
}

/// Reading failed: every real error found, each with its line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EdsError {
    /// The errors, in file order; those without a line (found after reading) last.
    pub errors: Vec<Diagnostic>,
}

impl std::fmt::Display for EdsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, e) in self.errors.iter().enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for EdsError {}
