//! A CiA 301 device built from any EDS or DCF (CiA 306): the dictionary
//! is the file's — its objects, sub-indices, types, access, limits, PDO
//! mapping flags, defaults and a DCF's `ParameterValue`s — and the
//! services run what the file's objects describe: the PDOs 1400h/1600h
//! and 1800h/1A00h it lists, heartbeat (1016h/1017h), guarding
//! (100Ch/100Dh), SYNC (1005h–1007h, 1019h), TIME (1012h), EMCY (1014h,
//! 1015h, 1003h, 1028h), 1029h, store/restore (1010h/1011h), extra SDO
//! servers (1201h..), LSS when `[DeviceInfo] LSS_Supported=1`, and 1021h
//! serving the file's own text.
//!
//! ```
//! use drivebus_node::{EdsOptions, MemoryStorage, Node};
//! let text = "[DeviceInfo]\nLSS_Supported=0\n[1000]\nParameterName=Device type\nDataType=0x0007\n\
//!             AccessType=ro\nDefaultValue=0x000F0191\n[1017]\nParameterName=Producer heartbeat time\n\
//!             DataType=0x0006\nAccessType=rw\nDefaultValue=100\n";
//! let eds = drivebus_eds::parse(text).unwrap().eds;
//! let (node, _warnings) =
//!     Node::from_eds(&eds, text, 5, Box::new(MemoryStorage::new()), EdsOptions::default()).unwrap();
//! assert_eq!(node.od().get_u32(0x1000, 0), Some(0x000F_0191));
//! assert!(node.od().object(0x1018).is_none()); // only what the file has
//! ```

use crate::config::NodeConfig;
use crate::node::{Node, NodeTemplate};
use crate::storage::Storage;
use alloc::boxed::Box;
use alloc::vec::Vec;
use drivebus_eds::{Diagnostic, Eds, EdsError};
use drivebus_od::{Object, ObjectDictionary};
use drivebus_pdo::Granularity;

/// What a device built from a file has beyond the file.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EdsOptions {
    /// Add 1021h "store EDS" and 1022h "storage format" (CiA 301
    /// §7.5.2.21/22) serving the file when the file does not list them
    /// (`drivebus serve --eds-object`). A file that lists 1021h serves
    /// itself there anyway.
    pub eds_object: bool,
}

/// The highest sub-index of `index` in `od` (CiA 301 sub 0 of an ARRAY or
/// RECORD), 0 when absent.
fn highest_sub(od: &ObjectDictionary, index: u16) -> u8 {
    od.object(index).and_then(|o| o.subs().last()).map_or(0, |s| s.sub)
}

/// How many PDOs of a kind the file has: communication and mapping
/// parameter objects from the first on, without a gap (the PDO service
/// numbers them densely; objects after a gap stay plain values).
fn pdo_count(od: &ObjectDictionary, comm: u16, map: u16) -> u16 {
    (0..512u16).take_while(|n| od.object(comm + n).is_some() && od.object(map + n).is_some()).count() as u16
}

impl NodeConfig {
    /// The configuration of node `node_id` whose dictionary `od` was
    /// converted from `eds` (see the module docs): the services the file's
    /// objects describe, the PDO counts, granularity and mapping size of
    /// its PDO objects, LSS as `[DeviceInfo]` says, its `[DeviceInfo]` and
    /// text for 1021h.
    pub fn from_eds(eds: &Eds, od: &ObjectDictionary, node_id: u8) -> NodeConfig {
        let has = |index: u16| od.object(index).is_some();
        let mut c = NodeConfig::new(node_id);
        c.device_type = od.get_u32(0x1000, 0).unwrap_or(0);
        c.nmt.heartbeat_supported = has(0x1017) || has(0x1016);
        c.nmt.guarding_supported = has(0x100C) && has(0x100D);
        c.nmt.life_guarding_honoured = c.nmt.guarding_supported;
        c.heartbeat_consumers = highest_sub(od, 0x1016);
        c.emcy_history = highest_sub(od, 0x1003);
        c.emcy_consumers = highest_sub(od, 0x1028);
        c.error_classes = highest_sub(od, 0x1029);
        c.emcy_inhibit = has(0x1015);
        c.sync_window = has(0x1007);
        c.sync_counter = has(0x1019);
        c.time = has(0x1012);
        c.store_restore = has(0x1010) || has(0x1011);
        c.eds_object = has(0x1021);
        c.sdo_server_param = has(0x1200);
        c.extra_sdo_servers = (1..128u16).take_while(|n| has(0x1200 + n)).count() as u8;
        c.lss = eds.device_info.lss_supported;
        let p = &mut c.pdo;
        p.rpdo_count = pdo_count(od, 0x1400, 0x1600);
        p.tpdo_count = pdo_count(od, 0x1800, 0x1A00);
        p.granularity = if eds.device_info.granularity == 8 { Granularity::Byte } else { Granularity::Bit };
        let maps = (0..p.rpdo_count)
            .map(|n| 0x1600 + n)
            .chain((0..p.tpdo_count).map(|n| 0x1A00 + n))
            .map(|i| highest_sub(od, i));
        p.max_entries = maps.max().unwrap_or(0).min(drivebus_pdo::MAX_MAPPED_ENTRIES);
        p.dummy_types = (1..=7u16).filter(|&t| eds.dummy_supported(t)).fold(0, |m, t| m | 1 << t);
        c.eds_device_info = Some(eds.device_info.clone());
        c
    }
}

/// `od` brought back to the objects and sub-indices of `file`, except the
/// objects of `keep`: what the services added and the file lacks goes
/// (the service runs on its power-on setting, as on a device whose
/// manual does not list the object). Every kept entry stays as merged
/// (the file's description and value, the service's owner).
fn prune(od: &mut ObjectDictionary, file: &ObjectDictionary, keep: &[u16]) {
    let indices: Vec<u16> = od.objects().iter().map(|o| o.index).filter(|i| !keep.contains(i)).collect();
    for index in indices {
        let Some(f) = file.object(index) else {
            od.remove(index);
            continue;
        };
        let Some(o) = od.object(index) else { continue };
        if o.subs().iter().all(|s| f.get(s.sub).is_some()) {
            continue;
        }
        let kept: Vec<_> = o.subs().iter().filter(|s| f.get(s.sub).is_some()).cloned().collect();
        let mut n =
            kept.iter().cloned().fold(Object::with_code(index, o.code, o.name.clone()), Object::with_sub);
        n.flags = o.flags;
        // `with_sub` may re-group persistence: each entry exactly as merged.
        for (dst, src) in n.subs_mut().iter_mut().zip(&kept) {
            *dst = src.clone();
        }
        od.insert(n);
        // Sub 0, which the merge raised to the services' highest
        // sub-index, back as the file has it.
        if let (Some(fs), Ok(r)) = (f.get(0), od.find(index, 0)) {
            od.set_raw(r, fs.bytes());
            if let Some(s0) = od.get_mut(index, 0) {
                s0.default.clone_from(&fs.default);
            }
        }
    }
}

/// `eds` without its objects whose values are of no basic data type (a
/// node cannot encode them), and a warning for each; `None`: all servable.
fn servable(eds: &Eds) -> (Option<Eds>, Vec<Diagnostic>) {
    fn bad(o: &drivebus_eds::EdsObject) -> Option<&drivebus_eds::EdsVar> {
        o.var.iter().chain(o.subs.values()).find(|v| drivebus_od::DataType::from_index(v.data_type).is_none())
    }
    let skipped: Vec<Diagnostic> = eds
        .objects
        .values()
        .filter(|o| o.object_type != drivebus_od::ObjectCode::Null)
        .filter_map(|o| {
            bad(o).map(|v| Diagnostic {
                line: v.line,
                message: alloc::format!(
                    "object {:04X} left out: DataType {:#06x} is not a basic type",
                    o.index,
                    v.data_type
                ),
            })
        })
        .collect();
    if skipped.is_empty() {
        return (None, skipped);
    }
    let mut e = eds.clone();
    e.objects.retain(|_, o| o.object_type == drivebus_od::ObjectCode::Null || bad(o).is_none());
    (Some(e), skipped)
}

impl Node {
    /// The device `eds` (read from `text`, which 1021h serves) describes,
    /// as node `node_id` (`$NODEID` evaluated for it), parameters in
    /// `storage` (see the module docs). A value the file gets wrong (a
    /// default that does not fit its type) is an error with its line; an
    /// object of a data type that is no basic type (a structure the file
    /// does not define for it) is left out, named in the warnings returned
    /// beside the node.
    pub fn from_eds(
        eds: &Eds,
        text: &str,
        node_id: u8,
        storage: Box<dyn Storage + Send>,
        options: EdsOptions,
    ) -> Result<(Node, Vec<Diagnostic>), EdsError> {
        let (served, skipped) = servable(eds);
        let file = drivebus_eds::to_od(served.as_ref().unwrap_or(eds), node_id)?;
        let mut cfg = NodeConfig::from_eds(eds, &file, node_id);
        cfg.eds_object |= options.eds_object;
        if cfg.eds_object {
            cfg.eds_text = Some(text.into());
        }
        let keep: &[u16] = if options.eds_object { &[0x1021, 0x1022] } else { &[] };
        let t = NodeTemplate::with_dictionary(cfg, file.clone());
        let (cfg, mut od) = t.into_parts();
        prune(&mut od, &file, keep);
        Ok((Node::assemble(cfg, od, storage), skipped))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MemoryStorage;

    fn node(text: &str, id: u8) -> Node {
        let eds = drivebus_eds::parse(text).unwrap().eds;
        Node::from_eds(&eds, text, id, Box::new(MemoryStorage::new()), EdsOptions::default()).unwrap().0
    }

    const PDO: &str = "[DeviceInfo]\nGranularity=8\nLSS_Supported=1\n\
        [1000]\nParameterName=Device type\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x191\n\
        [1400]\nParameterName=RPDO1\nObjectType=0x9\nSubNumber=3\n\
        [1400sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=2\n\
        [1400sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x200\n\
        [1400sub2]\nParameterName=type\nDataType=0x0005\nAccessType=rw\nDefaultValue=255\n\
        [1600]\nParameterName=RPDO1 map\nObjectType=0x9\nSubNumber=3\n\
        [1600sub0]\nParameterName=n\nDataType=0x0005\nAccessType=rw\nDefaultValue=1\n\
        [1600sub1]\nParameterName=1\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x62000108\n\
        [1600sub2]\nParameterName=2\nDataType=0x0007\nAccessType=rw\nDefaultValue=0\n\
        [1800]\nParameterName=TPDO3\nObjectType=0x9\nSubNumber=1\n\
        [1800sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=0\n";

    #[test]
    fn configuration_follows_the_file() {
        let eds = drivebus_eds::parse(PDO).unwrap().eds;
        let od = drivebus_eds::to_od(&eds, 3).unwrap();
        let c = NodeConfig::from_eds(&eds, &od, 3);
        assert_eq!(c.device_type, 0x191);
        assert_eq!((c.pdo.rpdo_count, c.pdo.tpdo_count, c.pdo.max_entries), (1, 0, 2));
        assert_eq!(c.pdo.granularity, Granularity::Byte);
        assert!(c.lss && !c.nmt.heartbeat_supported && !c.time && !c.store_restore && !c.eds_object);
        assert_eq!((c.heartbeat_consumers, c.emcy_history, c.error_classes), (0, 0, 0));
    }

    #[test]
    fn dictionary_is_the_files_own() {
        let n = node(PDO, 3);
        let indices: Vec<u16> = n.od().objects().iter().map(|o| o.index).collect();
        // 1800h without 1A00h is no TPDO: it stays as the file has it.
        assert_eq!(indices, [0x1000, 0x1400, 0x1600, 0x1800]);
        assert_eq!(n.od().get_u32(0x1400, 1), Some(0x203));
        assert_eq!(n.od().object(0x1400).unwrap().subs().len(), 3);
        assert_eq!(n.od().get_u32(0x1600, 1), Some(0x6200_0108));
    }

    #[test]
    fn an_object_of_no_basic_type_is_left_out_with_a_warning() {
        let text = "[2020]\nParameterName=Complex\nDataType=0x40\nAccessType=rw\n\
                    [2021]\nParameterName=x\nDataType=0x0005\nAccessType=rw\nDefaultValue=7\n";
        let eds = drivebus_eds::parse(text).unwrap().eds;
        let (n, w) =
            Node::from_eds(&eds, text, 1, Box::new(MemoryStorage::new()), EdsOptions::default()).unwrap();
        assert!(n.od().object(0x2020).is_none());
        assert_eq!(n.od().get_u32(0x2021, 0), Some(7));
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].line, 1);
        assert!(w[0].message.contains("2020"), "{}", w[0].message);
    }

    #[test]
    fn eds_object_serves_the_file_text() {
        let eds = drivebus_eds::parse(PDO).unwrap().eds;
        let opts = EdsOptions { eds_object: true };
        let (mut n, _) = Node::from_eds(&eds, PDO, 3, Box::new(MemoryStorage::new()), opts).unwrap();
        assert!(n.od().object(0x1022).is_some());
        let got = n.read_object(0x1021, 0, drivebus_can::Instant::ZERO, &mut drivebus_od::NoHooks).unwrap();
        assert_eq!(got, PDO.as_bytes());
    }

    #[test]
    fn a_default_that_does_not_fit_the_node_id_is_an_error_with_its_line() {
        // Read fine; only node 127 takes the UNSIGNED8 beyond FFh.
        let text = "[2000]\nParameterName=x\nDataType=0x0005\nAccessType=ro\nDefaultValue=$NODEID+0xF0\n";
        let eds = drivebus_eds::parse(text).unwrap().eds;
        assert!(
            Node::from_eds(&eds, text, 15, Box::new(MemoryStorage::new()), EdsOptions::default()).is_ok()
        );
        let e = Node::from_eds(&eds, text, 127, Box::new(MemoryStorage::new()), EdsOptions::default())
            .err()
            .unwrap();
        assert_eq!(e.errors[0].line, 1, "{e}");
    }
}
