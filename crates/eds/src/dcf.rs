//! The DCF of a configured device (CiA 306 §5): its EDS with the values it
//! holds as `ParameterValue` and a `[DeviceComissioning]` section.

use crate::model::{Commissioning, Eds, EdsVar};
use crate::value::format;
use drivebus_od::{DataType, ObjectDictionary};

/// Whether `text` survives a `key=value` line (CiA 306 files have no escape).
fn one_line(text: &str) -> bool {
    !text.chars().any(|c| c.is_control())
}

/// The DCF of a device: `eds`, its description, with each entry's present
/// value as `ParameterValue` and `commissioning` as `[DeviceComissioning]`
/// (node-ID, node name, bit rate, net number, LSS serial number …).
///
/// `value(index, sub, var)` gives the bytes the device holds (little-endian,
/// as an SDO upload returns them), `None` where the value is unknown (not
/// read, write-only, refused): such an entry keeps no `ParameterValue`.
/// DOMAIN entries never get one (CiA 306 puts domain data in files), nor a
/// value that does not fit on one line. `[FileInfo]` gets `LastEDS`, the
/// EDS's `FileName`.
///
/// ```
/// use drivebus_eds::{Commissioning, dcf, parse, write};
/// let eds = parse("[1017]\nParameterName=HB\nDataType=0x0006\nAccessType=rw\nDefaultValue=0\n").unwrap().eds;
/// let c = Commissioning { node_id: 5, baudrate: 500, ..Commissioning::default() };
/// let d = dcf(&eds, c, |_, _, _| Some(vec![0xFA, 0x00]));
/// let text = write(&d);
/// assert!(text.contains("ParameterValue=0x00FA") && text.contains("[DeviceComissioning]\nNodeID=0x05"));
/// ```
pub fn dcf(
    eds: &Eds,
    commissioning: Commissioning,
    mut value: impl FnMut(u16, u8, &EdsVar) -> Option<Vec<u8>>,
) -> Eds {
    let mut d = eds.clone();
    for (index, o) in d.objects.iter_mut() {
        if o.compact_sub_obj.take().is_some() {
            // Each sub-index gets its own value: written out in full.
            o.var = None;
            o.compact_names.clear();
            o.compact_values.clear();
            o.sub_number = Some(o.subs.len() as u8);
        }
        let vars: Vec<(u8, &mut EdsVar)> = match &mut o.var {
            Some(v) => vec![(0, v)],
            None => o.subs.iter_mut().map(|(k, v)| (*k, v)).collect(),
        };
        for (sub, v) in vars {
            v.parameter_value = DataType::from_index(v.data_type)
                .filter(|dt| *dt != DataType::Domain)
                .and_then(|dt| value(*index, sub, v).map(|b| format(dt, &b)))
                .filter(|t| one_line(t));
        }
    }
    if let Some(name) =
        eds.file_info.iter().find(|(k, _)| k.eq_ignore_ascii_case("FileName")).map(|e| e.1.clone())
    {
        d.file_info.retain(|(k, _)| !k.eq_ignore_ascii_case("LastEDS"));
        d.file_info.push(("LastEDS".into(), name));
    }
    d.commissioning = Some(commissioning);
    d
}

/// [`dcf`] with the values of `od`, a dictionary of the device (e.g. a
/// running node's): every readable entry `od` has.
pub fn dcf_from_od(eds: &Eds, od: &ObjectDictionary, commissioning: Commissioning) -> Eds {
    dcf(eds, commissioning, |index, sub, _| {
        od.get(index, sub).filter(|s| s.access.readable()).map(|s| s.bytes().to_vec())
    })
}
