//! `drivebus ethercat sdo read`: one entry, a VAR, or a whole ARRAY or
//! RECORD named and typed by the slave's SDO Information and read by
//! complete access where the slave offers them
//! (`drivebus_ethercat::master::LineMaster::read_object`); without SDO
//! Information, by the CiA 301/402 and ETG.1000.6 tables, else by size.

use drivebus_ethercat::master::{self, DescribedBy, Entry, LineMaster, ObjectDescription, ObjectRead};
use drivebus_master::DataType;

use super::EcatSdoRead;
use super::line::{master_err, with_master};
use crate::args::Global;
use crate::dict::Dict;
use crate::error::coded;
use crate::output::outln;
use crate::sdo_cmd::{Row, parse_type, row_json, row_text};

/// The CoE objects of ETG.1000.6 (§5.6.7.4) a slave has besides CiA 301's:
/// sync manager communication types (1C00h) and PDO assignments
/// (1C10h..1C2Fh), as arrays: (object name, entry name, entry type).
fn etg_array(index: u16, sub: u8) -> Option<(String, String, DataType)> {
    let (object, entry, dt) = match index {
        0x1C00 => (
            "Sync manager communication type".to_owned(),
            format!("Communication type SM{}", sub.wrapping_sub(1)),
            DataType::Unsigned8,
        ),
        0x1C10..=0x1C2F => (
            format!("Sync manager {} PDO assignment", index - 0x1C10),
            format!("PDO {sub}"),
            DataType::Unsigned16,
        ),
        _ => return None,
    };
    Some(if sub == 0 {
        (object, "Number of entries".into(), DataType::Unsigned8)
    } else {
        (object, entry, dt)
    })
}

/// What the tables know of `index`, for a slave without SDO Information:
/// the entries of a CiA record or array, whether it is known at all, and
/// each sub-index's bit length (for complete access).
struct Tables {
    entries: Option<Vec<u8>>,
    known: bool,
    etg: bool,
    bits: Vec<Option<u16>>,
}

impl Tables {
    fn new(dict: &Dict, index: u16) -> Tables {
        let bits = (0..=255u8)
            .map(|s| {
                let dt = dict.data_type(index, s).or_else(|| etg_array(index, s).map(|e| e.2))?;
                if dt == DataType::Boolean { Some(1) } else { dt.fixed_size().map(|n| 8 * n as u16) }
            })
            .collect();
        let entries = dict.entries(index);
        let etg = etg_array(index, 0).is_some();
        Tables { known: entries.is_some() || dict.data_type(index, 0).is_some() || etg, entries, etg, bits }
    }

    /// The entries 1.. to read after sub 0 (`zero`), the way the tables
    /// see the object, and whether they are a guess to check by reading
    /// sub 1: an object outside the tables is an array or record when its
    /// sub 0 is one byte with entries behind it (1C13h), a VAR otherwise.
    fn subs(&self, zero: &[u8]) -> (Vec<u8>, bool) {
        match (&self.entries, zero) {
            (Some(all), _) => {
                let highest = zero.first().copied().unwrap_or(0);
                (all.iter().copied().filter(|&s| (1..=highest).contains(&s)).collect(), false)
            }
            (None, [n]) if *n > 0 && (!self.known || self.etg) => ((1..=*n).collect(), true),
            _ => (Vec::new(), false),
        }
    }
}

/// `drivebus ethercat sdo read`: a VAR, one entry, or (no sub-index) a
/// whole array or record: every entry up to sub 0's count.
pub async fn sdo_read(g: &Global, a: &EcatSdoRead) -> anyhow::Result<()> {
    let dict = Dict::default();
    let (index, sub) = dict.resolve(&a.object, a.sub.as_deref()).map_err(|e| coded("usage", e))?;
    let forced = a.ty.as_deref().map(parse_type).transpose()?;
    let tables = Tables::new(&dict, index);
    // One upload: an entry asked for, or a VAR the tool knows.
    let single = sub.or((tables.entries.is_none() && dict.data_type(index, 0).is_some()).then_some(0));
    let pos = a.slave;
    let read = with_master(g, &a.line, async move |m: &LineMaster| {
        m.check_position(pos).await.map_err(master_err)?;
        let group = m.init().await.map_err(master_err)?;
        let sd = m.slave(&group, pos).map_err(master_err)?;
        if let Some(s) = single {
            let data = master::sdo_read(&sd, pos, index, s).await.map_err(master_err)?;
            return Ok((None, vec![Entry { sub: s, info: None, data }]));
        }
        let mut read = m.read_object(&sd, pos, index).await.map_err(master_err)?;
        if let DescribedBy::NoSdoInfo(_) = read.described {
            let zero = master::sdo_read(&sd, pos, index, 0).await.map_err(master_err)?;
            let (mut subs, guess) = tables.subs(&zero);
            if guess && master::sdo_read(&sd, pos, index, 1).await.is_err() {
                subs.clear();
            }
            let layout: Vec<_> = subs.iter().map(|&s| (s, tables.bits[usize::from(s)])).collect();
            let (values, by_ca) = master::read_entries(&sd, pos, index, &layout, read.complete_access)
                .await
                .map_err(master_err)?;
            read.read_complete = by_ca;
            read.entries.push(Entry { sub: 0, info: None, data: zero });
            read.entries.extend(values.into_iter().map(|(sub, data)| Entry { sub, info: None, data }));
        }
        let entries = std::mem::take(&mut read.entries);
        Ok((Some(read), entries))
    })
    .await?;
    print(g, &dict, forced, pos, index, read)
}

fn by_size(d: &[u8]) -> Option<DataType> {
    match d.len() {
        1 => Some(DataType::Unsigned8),
        2 => Some(DataType::Unsigned16),
        4 => Some(DataType::Unsigned32),
        8 => Some(DataType::Unsigned64),
        _ => None,
    }
}

/// An entry as a row: named and typed by `--type`, then the slave's SDO
/// Information (`object`, the entry's description), then the CiA 301/402
/// dictionary and ETG.1000.6, else by size.
fn row(
    dict: &Dict,
    forced: Option<DataType>,
    index: u16,
    object: Option<&ObjectDescription<Vec<u8>>>,
    e: &Entry,
) -> Row {
    let info = e.info.as_ref();
    let name = match (object, info) {
        (Some(o), Some(i)) if o.compound() => Some(format!("{} / {}", o.name_text(), i.name_text())),
        (Some(o), _) if !o.compound() => Some(o.name_text()),
        _ => None,
    };
    let etg = etg_array(index, e.sub);
    let name = name
        .or_else(|| dict.name(index, e.sub))
        .or_else(|| etg.as_ref().map(|(o, n, _)| format!("{o} / {n}")));
    let dt = forced
        .or_else(|| info.and_then(|i| DataType::from_index(i.data_type)))
        .or_else(|| dict.data_type(index, e.sub))
        .or_else(|| etg.map(|(_, _, t)| t))
        .or_else(|| by_size(&e.data));
    (e.sub, name, dt, e.data.clone())
}

/// What to tell the user when the names and types are not the slave's.
fn note(pos: usize, read: &ObjectRead) -> Option<String> {
    match &read.described {
        DescribedBy::NoSdoInfo(why) => Some(format!(
            "slave {pos} has no SDO Information ({why}): names and types from CiA 301/402 and ETG.1000.6 where known, else by size"
        )),
        DescribedBy::SdoInfo(_) => None,
    }
}

fn print(
    g: &Global,
    dict: &Dict,
    forced: Option<DataType>,
    pos: usize,
    index: u16,
    (read, entries): (Option<ObjectRead>, Vec<Entry>),
) -> anyhow::Result<()> {
    let object = match read.as_ref().map(|r| &r.described) {
        Some(DescribedBy::SdoInfo(o)) => Some(o),
        _ => None,
    };
    let row = |e: &Entry| row(dict, forced, index, object, e);
    let note = read.as_ref().and_then(|r| note(pos, r));
    if g.json {
        let items: Vec<serde_json::Value> = entries
            .iter()
            .map(|e| {
                let mut j = slave_json(pos, row_json(0, index, &row(e)));
                if let Some(i) = &e.info {
                    j["access"] = i.access_text().into();
                    j["bits"] = i.bit_length.into();
                }
                j
            })
            .collect();
        match (&read, items.as_slice()) {
            (Some(r), _) if object.is_none_or(|o| o.compound()) => {
                let mut j = serde_json::json!({"slave": pos, "index": index, "entries": items,
                    "names_from": if object.is_some() { "sdo_info" } else { "tables" },
                    "complete_access": r.read_complete});
                if let Some(o) = object {
                    j["name"] = o.name_text().into();
                    j["object_code"] = o.code_name().into();
                }
                if let Some(n) = note {
                    j["note"] = n.into();
                }
                outln!("{j}");
            }
            (_, [one]) => outln!("{one}"),
            _ => outln!("{}", serde_json::json!({"slave": pos, "index": index, "entries": items})),
        }
    } else {
        if let Some(n) = note {
            eprintln!("note: {n}");
        }
        for e in &entries {
            outln!("{}", row_text(index, &row(e)));
        }
    }
    Ok(())
}

/// The CAN row JSON with `slave` instead of `node`.
fn slave_json(slave: usize, mut j: serde_json::Value) -> serde_json::Value {
    if let Some(o) = j.as_object_mut() {
        o.remove("node");
        o.insert("slave".into(), slave.into());
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_ethercat::master::EntryDescription;

    fn entry(sub: u8, info: Option<(&str, u16, u16)>, data: &[u8]) -> Entry {
        let info = info.map(|(name, data_type, bit_length)| EntryDescription {
            index: 0,
            sub,
            value_info: 0,
            data_type,
            bit_length,
            access: 0x3F,
            values: Vec::new(),
            name: name.into(),
        });
        Entry { sub, info, data: data.to_vec() }
    }

    #[test]
    fn names_and_types_come_from_the_slave_first() {
        let dict = Dict::default();
        let o = ObjectDescription {
            index: 0x1C13,
            object_code: 8,
            data_type: 6,
            max_sub: 4,
            name: b"TxPDO assign".to_vec(),
        };
        let e = entry(1, Some(("PDO 1st", 7, 32)), &[0x00, 0x1A, 0, 0]);
        let r = row(&dict, None, 0x1C13, Some(&o), &e);
        assert_eq!(r.1.as_deref(), Some("TxPDO assign / PDO 1st"));
        assert_eq!(r.2, Some(DataType::Unsigned32), "the slave's type, not the table's");
        // --type wins; an entry the slave did not describe takes the table's name.
        let r = row(&dict, Some(DataType::Integer32), 0x1C13, Some(&o), &entry(2, None, &[1, 0x1A]));
        assert_eq!(
            (r.1.as_deref(), r.2),
            (Some("Sync manager 3 PDO assignment / PDO 2"), Some(DataType::Integer32))
        );
        // A VAR is named after its object.
        let v = ObjectDescription {
            index: 0x2000,
            object_code: 7,
            data_type: 9,
            max_sub: 0,
            name: b"Name".to_vec(),
        };
        let r = row(&dict, None, 0x2000, Some(&v), &entry(0, Some(("x", 9, 32)), b"iPOS"));
        assert_eq!((r.1.as_deref(), r.2), (Some("Name"), Some(DataType::VisibleString)));
    }

    #[test]
    fn without_sdo_information_the_tables_name_and_it_is_said() {
        let dict = Dict::default();
        let read = ObjectRead {
            index: 0x1C13,
            described: DescribedBy::NoSdoInfo("its SII announces no SDO Information (CoE details)".into()),
            complete_access: false,
            read_complete: false,
            entries: Vec::new(),
        };
        let r = row(&dict, None, 0x1C13, None, &entry(1, None, &[0x00, 0x1A]));
        assert_eq!(
            (r.1.as_deref(), r.2),
            (Some("Sync manager 3 PDO assignment / PDO 1"), Some(DataType::Unsigned16))
        );
        let r = row(&dict, None, 0x2345, None, &entry(3, None, &[1, 2, 3, 4]));
        assert_eq!((r.1, r.2), (None, Some(DataType::Unsigned32)), "by size");
        assert_eq!(
            note(2, &read).unwrap(),
            "slave 2 has no SDO Information (its SII announces no SDO Information (CoE details)): names and types from CiA 301/402 and ETG.1000.6 where known, else by size"
        );
        let t = Tables::new(&dict, 0x1C13);
        assert_eq!(t.subs(&[2]), (vec![1, 2], true));
        assert_eq!((t.bits[0], t.bits[1]), (Some(8), Some(16)));
        assert_eq!(Tables::new(&dict, 0x1018).subs(&[4]), (vec![1, 2, 3, 4], false));
        assert_eq!(Tables::new(&dict, 0x2345).subs(&[1, 2, 3, 4]), (vec![], false), "a VAR");
    }
}
