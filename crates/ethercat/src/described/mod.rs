//! Slaves made from a description of a real device: an SII EEPROM image
//! (raw binary, or Intel hex as tools dump it) or an ESI file (ETG.2000
//! XML; `FILE#PRODUCT` or `FILE#N` picks one of several devices), as
//! `drivebus ethercat serve --device FILE` puts them on a line.
//!
//! One [`SlaveDescription`] says what the device is; the slave answers
//! with exactly that:
//!
//! * **SII**: an EEPROM image is served byte for byte (and keeps what a
//!   master writes into it, through a reload, as a real ESC does); an ESI
//!   file's device gets the image [`drivebus_esi::sii`] makes of it.
//!   Identity, names, sync managers, FMMUs, mailbox and protocols, PDO
//!   categories and DC modes are what a master reads there.
//! * **ESC**: the SII configuration area sets it up as on the real device
//!   (an EL2004's or an EK1100's word 0 selects device emulation: the ESC
//!   sets the AL status itself, see [`drivebus_esc::slave`]).
//! * **Process data**: the default PDO assignment (PDOs with a sync
//!   manager) of the one outputs and one inputs SM; outputs are kept
//!   ([`DescribedApp::outputs`]) and, with CoE, mirrored into the mapped
//!   objects; inputs come from an [`InputSource`] ([`Loopback`] for now).
//! * **CoE** (when announced): SDO, complete access and SDO Information
//!   over the ESI's `Dictionary/Objects`, or, without one, the objects
//!   [`drivebus_esi::objects_from_description`] makes (identity, SM types,
//!   PDO mapping and assignment, mapped objects). Writes and reads obey
//!   the described access per ESM state. FoE, EoE and the rest get the
//!   mailbox error "unsupported protocol".
//! * A device without process data (a coupler) only passes the line on.
//!
//! Not served: devices whose outputs (or inputs) are spread over several
//! sync managers (the EL2889's SM0 and SM1), which the slave framework's
//! one-SM-per-direction process image cannot carry — refused with an
//! error naming the SMs; PDO assignment or mapping changes by the master
//! (the described default stays in force).

mod app;
pub mod ihex;
mod line;

pub use app::{DescribedApp, DescribedStats, InputSource, Loopback};
pub use line::{Member, devices, with_device};

use app::{Coe, Mirror};
use drivebus_coe::{MailboxConfig, MailboxServer};
use drivebus_esc::sii::SiiImage;
use drivebus_esc::slave::{ProcessDataSizes, Slave, SlaveConfig};
use drivebus_esc::{Esc, EscConfig};
use drivebus_esi::{SlaveDescription, SmKind};
use std::fmt;
use std::path::Path;

/// A described slave.
pub type DescribedSlave = Slave<DescribedApp>;

/// Why a device file cannot be served: the file, where in it, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoadError {
    /// The file as given.
    pub file: String,
    /// Where: `line 12`, `byte 0x0080`, an element path, an SII category.
    pub at: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.at.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: {}: {}", self.file, self.at, self.message)
        }
    }
}

impl std::error::Error for LoadError {}

/// What a device file was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// A raw binary EEPROM image.
    Binary,
    /// An EEPROM image in Intel hex.
    IntelHex,
    /// An ESI file.
    Esi,
}

/// A device as a file describes it.
#[derive(Debug, Clone)]
pub struct Described {
    /// What the device is.
    pub description: SlaveDescription,
    /// The SII image its ESC serves.
    pub sii: SiiImage,
    /// What the file was.
    pub format: Format,
}

impl Described {
    /// The name masters show: the SII order string / ESI `Type`.
    pub fn type_name(&self) -> &str {
        &self.description.type_name
    }
}

/// Splits `FILE#SELECT`; a `#` that is part of an existing file's name
/// stays in the name.
pub fn split_spec(spec: &str) -> (&str, Option<&str>) {
    match spec.rsplit_once('#') {
        Some((file, sel)) if !Path::new(spec).exists() => (file, Some(sel)),
        _ => (spec, None),
    }
}

/// Reads `FILE` or `FILE#SELECT` (see [`from_bytes`]).
pub fn load(spec: &str) -> Result<Described, LoadError> {
    let (file, select) = split_spec(spec);
    let bytes = std::fs::read(file).map_err(|e| LoadError {
        file: file.to_owned(),
        at: String::new(),
        message: format!("cannot read: {e}"),
    })?;
    from_bytes(file, &bytes, select)
}

/// The device `bytes` describe: an ESI file if it starts with `<`, Intel
/// hex if it starts with `:`, else a binary EEPROM image. `select` picks a
/// device of an ESI file: its 1-based position, its `Type` (order
/// number) or its product code (`#x…`, `0x…`); needed when the file
/// describes several. `file` names the source in errors.
pub fn from_bytes(file: &str, bytes: &[u8], select: Option<&str>) -> Result<Described, LoadError> {
    let err = |at: String, message: String| LoadError { file: file.to_owned(), at, message };
    let start = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if start.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'<') {
        let text = std::str::from_utf8(start)
            .map_err(|e| err(format!("byte {}", e.valid_up_to()), "not UTF-8".into()))?;
        let all = drivebus_esi::read_all(text).map_err(|e| err(e.at, e.message))?;
        let description = pick(all, select).map_err(|m| err(String::new(), m))?;
        let sii = SiiImage::from(&description);
        return Ok(Described { description, sii, format: Format::Esi });
    }
    if select.is_some() {
        return Err(err(
            String::new(),
            "#SELECT picks a device of an ESI file; this is an EEPROM image".into(),
        ));
    }
    let (image, format) = if ihex::is_hex(bytes) {
        let b = ihex::parse(bytes).map_err(|e| err(format!("line {}", e.line), e.message))?;
        (b, Format::IntelHex)
    } else {
        (bytes.to_vec(), Format::Binary)
    };
    if image.len() > ihex::MAX_LEN {
        return Err(err(String::new(), format!("{} bytes: larger than an SII EEPROM (64 KiB)", image.len())));
    }
    let sii = SiiImage::from_bytes(image);
    let content = sii.parse().map_err(|e| err("SII".into(), e.to_string()))?;
    let description = drivebus_esi::describe_sii(&content).map_err(|e| err(e.at, e.message))?;
    Ok(Described { description, sii, format })
}

fn pick(mut all: Vec<SlaveDescription>, select: Option<&str>) -> Result<SlaveDescription, String> {
    let list = |all: &[SlaveDescription]| {
        all.iter()
            .enumerate()
            .map(|(i, d)| {
                format!(
                    "#{} {} (product {:#010x}, revision {:#010x})",
                    i + 1,
                    d.type_name,
                    d.product_code,
                    d.revision
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let Some(sel) = select else {
        return match all.len() {
            1 => Ok(all.remove(0)),
            0 => Err("describes no device".into()),
            _ => Err(format!(
                "describes {} devices, pick one with FILE#N or FILE#PRODUCT: {}",
                all.len(),
                list(&all)
            )),
        };
    };
    let code = sel
        .strip_prefix("#x")
        .or_else(|| sel.strip_prefix("0x"))
        .and_then(|h| u32::from_str_radix(h, 16).ok());
    let hits: Vec<usize> = match sel.parse::<usize>() {
        Ok(n) if (1..=all.len()).contains(&n) => vec![n - 1],
        Ok(n) => return Err(format!("#{n}: the file describes {} devices: {}", all.len(), list(&all))),
        Err(_) => (0..all.len())
            .filter(|&i| all[i].type_name.eq_ignore_ascii_case(sel) || Some(all[i].product_code) == code)
            .collect(),
    };
    match hits.as_slice() {
        [i] => Ok(all.swap_remove(*i)),
        [] => Err(format!("no device {sel:?} in the file: {}", list(&all))),
        _ => Err(format!("{sel:?} matches several devices, pick one with #N: {}", list(&all))),
    }
}

/// The outputs and inputs SM numbers of `d` and their default PDO
/// assignment's bits; an error when a direction spreads over several SMs.
fn process_data(d: &SlaveDescription) -> Result<(ProcessDataSizes, Option<u8>, Option<u8>), String> {
    let mut sizes = ProcessDataSizes::default();
    let mut sms = (None, None);
    for (n, s) in d.sync_managers.iter().enumerate() {
        let (pdos, bits, sm) = match s.kind {
            SmKind::Outputs => (&d.rx_pdos, &mut sizes.output_bits, &mut sms.0),
            SmKind::Inputs => (&d.tx_pdos, &mut sizes.input_bits, &mut sms.1),
            _ => continue,
        };
        let b: u32 = pdos.iter().filter(|p| p.sm == Some(n as u8)).map(|p| p.bits()).sum();
        if b == 0 {
            continue;
        }
        if let Some(first) = *sm {
            return Err(format!(
                "{} over SM{first} and SM{n}: one sync manager per direction is served",
                if s.kind == SmKind::Outputs { "outputs" } else { "inputs" }
            ));
        }
        *bits = b;
        *sm = Some(n as u8);
    }
    Ok((sizes, sms.0, sms.1))
}

/// Entries of the PDOs assigned to `sm`, at their bit offsets, that the
/// dictionary holds with a value of 1 to 64 bits.
fn mirrors(od: &drivebus_od::ObjectDictionary, pdos: &[drivebus_esi::EsiPdo], sm: Option<u8>) -> Vec<Mirror> {
    let assigned = pdos.iter().filter(|p| sm.is_some() && p.sm == sm);
    let entries =
        assigned.flat_map(|p| &p.entries).map(|e| drivebus_pdo::PdoMapEntry::new(e.index, e.sub, e.bit_len));
    let mut out = Vec::new();
    for place in drivebus_pdo::layout(entries) {
        let e = place.entry;
        let bits = usize::from(e.bits);
        if e.index != 0
            && let Ok(entry) = od.find(e.index, e.sub)
            && od.entry(entry).data_type.fixed_size().is_some()
            && bits <= 64
        {
            out.push(Mirror { entry, bit_off: place.bit_offset, bits });
        }
    }
    out
}

/// The slave of `d`, with serial number `serial` in an ESI device's SII
/// (an image keeps its own) and `inputs` as its input source.
pub fn slave(d: &Described, serial: u32, inputs: Box<dyn InputSource>) -> Result<DescribedSlave, LoadError> {
    let err = |message: String| LoadError { file: d.type_name().to_owned(), at: String::new(), message };
    let desc = &d.description;
    let (sizes, out_sm, in_sm) = process_data(desc).map_err(err)?;
    let sii = match d.format {
        Format::Esi => SiiImage::from(&SlaveDescription { serial, ..desc.clone() }),
        _ => d.sii.clone(),
    };
    let d = &Described { sii: sii.clone(), ..d.clone() };
    let coe = match desc.mailbox.and_then(|m| m.coe) {
        Some(details) => {
            let objects = drivebus_esi::device_objects(&SlaveDescription { serial, ..desc.clone() });
            let mut od = drivebus_esi::dictionary(&objects);
            // The identity is the device's (`Device/Type`, SII words 8–15):
            // an ESI's 1018h defaults are often placeholders.
            let id = d.sii.parse().map(|c| c.identity).unwrap_or_default();
            for (sub, v) in [(1, id.vendor_id), (2, id.product_code), (3, id.revision), (4, id.serial)] {
                if let Some(e) =
                    od.get_mut(0x1018, sub).filter(|e| e.data_type == drivebus_od::DataType::Unsigned32)
                {
                    e.default = v.to_le_bytes().to_vec();
                }
                let _ = od.set_value(0x1018, sub, &drivebus_od::Value::U32(v));
            }
            let access = objects
                .iter()
                .flat_map(|o| o.subs.iter().map(move |s| ((o.index, s.sub), s.access)))
                .collect();
            let size = |k| desc.sm(k).and_then(|(_, s)| s.default_size).map_or(0, usize::from);
            let cfg = MailboxConfig {
                complete_access: details.complete_access,
                sdo_info: details.sdo_info,
                ..MailboxConfig::with_sizes(size(SmKind::MBoxOut), size(SmKind::MBoxIn))
            };
            let mbx = MailboxServer::new(cfg).map_err(|e| err(format!("mailbox: {e}")))?;
            let outputs = mirrors(&od, &desc.rx_pdos, out_sm);
            let inputs = mirrors(&od, &desc.tx_pdos, in_sm);
            Some(Coe { od, access, mbx, outputs, inputs })
        }
        None => None,
    };
    let app = DescribedApp {
        name: d.type_name().to_owned(),
        sizes,
        outputs: vec![0; sizes.output_bytes()],
        applied: vec![0; sizes.output_bytes()],
        inputs: vec![0; sizes.input_bytes()],
        source: inputs,
        coe,
        esm: drivebus_coe::AlState::Init,
        stats: DescribedStats::default(),
    };
    Ok(Slave::new(Esc::new(EscConfig::with_sii(sii)), app, SlaveConfig::default()))
}

#[cfg(test)]
mod tests;
