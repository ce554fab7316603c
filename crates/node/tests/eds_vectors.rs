//! Third-party EDS and DCF files (`tests/vectors/eds/`, origins in its
//! README) served as devices: every readable entry answers an SDO upload
//! with the file's value (a DCF's `ParameterValue`, else its
//! `DefaultValue`), and the file's default PDOs run: each valid TPDO sends
//! its mapped values (event-driven ones on entering OPERATIONAL,
//! synchronous ones at SYNC), each valid RPDO writes its mapped entries.

mod common;
use common::*;
use drivebus_can::{Duration, Frame};
use drivebus_node::{EdsOptions, MemoryStorage, Node};
use drivebus_od::ObjectDictionary;

const NODE: u8 = 5;

fn vectors() -> Vec<(String, String)> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/vectors/eds");
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "eds" || e == "dcf"))
        .map(|p| {
            (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read_to_string(&p).unwrap())
        })
        .collect();
    v.sort();
    assert!(v.len() >= 10, "vectors missing: {v:?}");
    v
}

fn build(text: &str) -> (Node, ObjectDictionary) {
    let eds = drivebus_eds::parse(text).unwrap().eds;
    let (node, left_out) =
        Node::from_eds(&eds, text, NODE, Box::new(MemoryStorage::new()), EdsOptions::default()).unwrap();
    // The file's values, but for what the node left out (and said so).
    let mut servable = eds.clone();
    servable.objects.retain(|i, _| !left_out.iter().any(|d| d.message.contains(&format!("object {i:04X} "))));
    (node, drivebus_eds::to_od(&servable, NODE).unwrap())
}

/// A rig around `node`: booted, its boot-up seen, whatever else it sends
/// at boot (a SYNC producer's first SYNC) dropped.
fn rig(node: Node) -> Rig {
    let mut bus = drivebus_bus::Bus::new(drivebus_bus::BusConfig::zero_time());
    let probe = bus.attach_probe();
    let dut = bus.attach(drivebus_node::NodeDevice::new(node, drivebus_od::NoHooks));
    bus.run_for(Duration::from_micros(1));
    let mut rig = Rig { bus, probe, dut };
    assert_eq!(rig.take().first(), Some(&Frame::new(0x700 + u16::from(NODE), &[0])), "boot-up");
    rig
}

/// An SDO upload over the bus, expedited or segmented; `Err(abort code)`.
fn upload(rig: &mut Rig, index: u16, sub: u8) -> Result<Vec<u8>, u32> {
    let r = rig.sdo_read(NODE, index, sub);
    let d = r.data();
    match d[0] {
        0x80 => return Err(u32::from_le_bytes(d[4..8].try_into().unwrap())),
        c if c & 0xE2 == 0x42 => {
            let n = if c & 1 != 0 { 4 - usize::from((c >> 2) & 3) } else { 4 };
            return Ok(d[4..4 + n].to_vec());
        }
        0x41 | 0x40 => {}
        c => panic!("{index:04X}:{sub}: unexpected response {c:02X}"),
    }
    let mut out = Vec::new();
    let mut toggle = 0u8;
    loop {
        rig.take();
        rig.bus
            .send_from(rig.probe, Frame::new(0x600 + u16::from(NODE), &[0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]));
        rig.run_for(Duration::from_micros(1));
        let f = rig.take();
        let d = f[0].data();
        if d[0] == 0x80 {
            return Err(u32::from_le_bytes(d[4..8].try_into().unwrap()));
        }
        assert_eq!(d[0] & 0x10, toggle, "{index:04X}:{sub}: toggle");
        let n = 7 - usize::from((d[0] >> 1) & 7);
        out.extend_from_slice(&d[1..1 + n]);
        if d[0] & 1 != 0 {
            return Ok(out);
        }
        toggle ^= 0x10;
    }
}

#[test]
fn every_readable_entry_answers_with_the_files_value() {
    for (name, text) in vectors() {
        let (node, file) = build(&text);
        let mut rig = rig(node);
        let mut read = 0;
        for o in file.objects() {
            for s in o.subs() {
                // 1003h holds the errors that occurred (none yet), whatever
                // a file gives as default.
                if !s.access.readable() || o.index < 0x1000 || o.index == 0x1003 {
                    continue;
                }
                let got = upload(&mut rig, o.index, s.sub);
                assert_eq!(got.as_deref(), Ok(s.bytes()), "{name}: {:04X}:{}", o.index, s.sub);
                read += 1;
            }
        }
        assert!(read > 0, "{name}: nothing read");
    }
}

/// `(index, sub, bits)` of a PDO's valid mapping in `od`.
fn mapping(od: &ObjectDictionary, map: u16) -> Vec<(u16, u8, u32)> {
    let n = od.get_u32(map, 0).unwrap_or(0) as u8;
    (1..=n).filter_map(|k| od.get_u32(map, k)).map(|e| ((e >> 16) as u16, (e >> 8) as u8, e & 0xFF)).collect()
}

/// The bytes a PDO of `map` carries (byte-aligned entries).
fn packed(od: &ObjectDictionary, map: &[(u16, u8, u32)]) -> Vec<u8> {
    map.iter()
        .flat_map(|&(i, s, bits)| match od.get(i, s) {
            Some(e) => e.bytes()[..(bits / 8) as usize].to_vec(),
            None => vec![0; (bits / 8) as usize], // a dummy entry
        })
        .collect()
}

#[test]
fn default_pdos_run() {
    let mut tpdos = 0;
    let mut rpdos = 0;
    for (name, text) in vectors() {
        let (node, file) = build(&text);
        let cfg = node.config().pdo;
        let mut rig = rig(node);
        rig.send("000#0105");
        rig.run_for(Duration::from_millis(1));
        let first = rig.take();
        rig.send("080#");
        let at_sync = rig.take();
        for n in 0..cfg.tpdo_count {
            let cob = file.get_u32(0x1800 + n, 1).unwrap_or(0x8000_0000);
            let ttype = file.get_u32(0x1800 + n, 2).unwrap_or(0xFF);
            let map = mapping(&file, 0x1A00 + n);
            // A mapping of an object the file lacks is no valid PDO.
            // Sub 0 FEh/FFh is an MPDO (CiA 301 §7.2.2.6, Lely's fiber
            // slave): not emulated.
            let mpdo = file.get_u32(0x1A00 + n, 0).is_some_and(|k| k > 0x40);
            let valid =
                !mpdo && map.iter().all(|&(i, s, b)| b % 8 == 0 && (i < 0x1000 || file.get(i, s).is_some()));
            if cob & 0x8000_0000 != 0 || cob & 0x2000_0000 != 0 || !valid {
                continue;
            }
            let want = Frame::new((cob & 0x7FF) as u16, &packed(&file, &map));
            let frames = match ttype {
                0xFE | 0xFF => &first,
                1..=0xF0 if ttype == 1 => &at_sync,
                _ => continue,
            };
            assert!(frames.contains(&want), "{name}: TPDO{} {want:?} not in {frames:?}", n + 1);
            tpdos += 1;
        }
        for n in 0..cfg.rpdo_count {
            let cob = file.get_u32(0x1400 + n, 1).unwrap_or(0x8000_0000);
            let map = mapping(&file, 0x1600 + n);
            let writable =
                map.iter().all(|&(i, s, b)| b % 8 == 0 && (i < 0x1000 || file.get(i, s).is_some()));
            if cob & 0x8000_0000 != 0 || map.is_empty() || !writable {
                continue;
            }
            let len: u32 = map.iter().map(|m| m.2 / 8).sum();
            let data: Vec<u8> = (0..len as u8).map(|k| 0x11 + k).collect();
            let ttype = file.get_u32(0x1400 + n, 2).unwrap_or(0xFF);
            rig.bus.send_from(rig.probe, Frame::new((cob & 0x7FF) as u16, &data));
            rig.run_for(Duration::from_micros(1));
            if ttype <= 0xF0 {
                rig.send("080#");
            }
            let mut at = 0usize;
            for &(i, s, bits) in &map {
                let k = (bits / 8) as usize;
                if i >= 0x1000 {
                    let od = rig.node().od();
                    assert_eq!(
                        od.get(i, s).unwrap().bytes(),
                        &data[at..at + k],
                        "{name}: RPDO{} {i:04X}:{s}",
                        n + 1
                    );
                }
                at += k;
            }
            rpdos += 1;
        }
    }
    // Lely's PDO tests have default PDOs (CANopenNode's profile maps
    // nothing by default, canopen-python's sample maps objects it lacks);
    // a run that checks none checks nothing.
    assert!(tpdos >= 1 && rpdos >= 1, "TPDOs {tpdos}, RPDOs {rpdos} checked");
}

/// `LSS_Supported=1` (CiA 306 §4.4) makes an LSS slave (CiA 305): in
/// configuration state it answers "inquire node-ID" with its node-ID; a
/// file without it ignores LSS.
#[test]
fn lss_as_the_file_says() {
    let mut with = 0;
    for (name, text) in vectors() {
        let lss = drivebus_eds::parse(&text).unwrap().eds.device_info.lss_supported;
        let (node, _) = build(&text);
        let mut rig = rig(node);
        rig.send("7E5#0401000000000000");
        rig.send("7E5#5E00000000000000");
        let want = if lss { vec![Frame::new(0x7E4, &[0x5E, NODE, 0, 0, 0, 0, 0, 0])] } else { vec![] };
        assert_eq!(rig.take(), want, "{name}: LSS_Supported={lss}");
        with += usize::from(lss);
    }
    assert!(with >= 2, "{with} files with LSS");
}

/// Files broken in many ways (a window of lines left out, counts and
/// COB-IDs changed) give a device or an error, never a panic: built,
/// booted, started, SYNCed and read (the fuzz target `eds_device` does the
/// same with any bytes).
#[test]
fn broken_files_never_panic() {
    let mut built = 0;
    for (name, text) in vectors() {
        let lines: Vec<&str> = text.lines().collect();
        let step = (lines.len() / 40).max(1);
        let mut variants: Vec<String> = (0..lines.len())
            .step_by(step)
            .map(|at| {
                let mut l = lines.clone();
                l.drain(at..(at + 4).min(lines.len()));
                l.join("\n")
            })
            .collect();
        variants.push(text.replace("DefaultValue=0x0", "DefaultValue=0xFF"));
        variants.push(text.replace("$NODEID+0x", "0x8000"));
        for v in variants {
            let Ok(p) = drivebus_eds::parse(&v) else { continue };
            let Ok((node, _)) = Node::from_eds(
                &p.eds,
                &v,
                NODE,
                Box::new(MemoryStorage::new()),
                EdsOptions { eds_object: true },
            ) else {
                continue;
            };
            let mut bus = drivebus_bus::Bus::new(drivebus_bus::BusConfig::zero_time());
            let probe = bus.attach_probe();
            bus.attach(drivebus_node::NodeDevice::new(node, drivebus_od::NoHooks));
            for f in
                ["000#0105", "080#", "605#4000100000000000", "605#4021100000000000", "7E5#0401000000000000"]
            {
                bus.send_from(probe, fr(f));
                bus.run_for(Duration::from_millis(2));
            }
            built += 1;
        }
        assert!(built > 0, "{name}: no variant built");
    }
}
