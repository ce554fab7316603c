//! Every personality built with `BuildOptions { eds_object: true }` serves
//! its own EDS at 1021h "store EDS" (CiA 301 §7.5.2.21; 1022h = 0, ASCII,
//! §7.5.2.22), and that EDS read back by SDO upload (segmented, CiA 301
//! §7.2.4.3.6–8), parsed (CiA 306) and converted to a dictionary gives the
//! node's own dictionary.
//!
//! Equality, per object: index, object code and name; per sub-index:
//! number, name, data type, access, PDO mapping, low/high limit and
//! default value (node-relative defaults come back through `$NODEID`).
//! Not compared, because an EDS does not carry them: live values (the
//! value of a sub-object may differ from its default), hooks, persistence
//! groups, maximum lengths and which defaults follow the node-ID. One
//! exclusion: the default of 1021h itself, which the generator leaves
//! empty (the EDS would have to contain itself).

mod replay_rig;

use drivebus_can::Frame;
use drivebus_node::MemoryStorage;
use drivebus_od::ObjectDictionary;
use drivebus_personality::Profile;
use drivebus_personality::build::BuildOptions;
use replay_rig::*;

const NODE: u8 = 9;

/// One request, exactly one SDO response.
fn one(r: &mut Rig, f: Frame) -> Frame {
    r.take();
    r.bus.send_from(r.probe, f);
    r.run_for(drivebus_can::Duration::from_micros(1));
    let v: Vec<Frame> =
        r.take().into_iter().filter(|f| f.std_id() == Some(0x580 + u16::from(NODE))).collect();
    assert_eq!(v.len(), 1, "{v:?}");
    v[0]
}

/// Segmented (or expedited) upload of index:sub.
fn upload(r: &mut Rig, index: u16, sub: u8) -> Vec<u8> {
    let rx = 0x600 + u16::from(NODE);
    let [il, ih] = index.to_le_bytes();
    let resp = one(r, Frame::new(rx, &[0x40, il, ih, sub, 0, 0, 0, 0]));
    let d = resp.data().to_vec();
    assert_eq!(d[0] & 0xE0, 0x40, "upload of {index:04X}h:{sub}: {resp:?}");
    if d[0] & 0x02 != 0 {
        let n = if d[0] & 1 != 0 { 4 - usize::from((d[0] >> 2) & 3) } else { 4 };
        return d[4..4 + n].to_vec();
    }
    let size = u32::from_le_bytes([d[4], d[5], d[6], d[7]]) as usize;
    let mut data = Vec::with_capacity(size);
    let mut toggle = 0u8;
    loop {
        let seg = one(r, Frame::new(rx, &[0x60 | toggle << 4, 0, 0, 0, 0, 0, 0, 0]));
        let s = seg.data();
        assert_eq!(s[0] & 0xF0, toggle << 4, "segment toggle: {seg:?}");
        let n = 7 - usize::from((s[0] >> 1) & 7);
        data.extend_from_slice(&s[1..1 + n]);
        if s[0] & 1 != 0 {
            break;
        }
        toggle ^= 1;
    }
    assert_eq!(data.len(), size);
    data
}

/// What an EDS describes of a dictionary, one line per object and sub.
fn described(od: &ObjectDictionary) -> Vec<String> {
    let mut v = Vec::new();
    for o in od.objects() {
        v.push(format!("{:04X} {:?} {:?}", o.index, o.code, o.name));
        for s in o.subs() {
            let default = if o.index == 0x1021 { &[][..] } else { &s.default[..] };
            v.push(format!(
                "{:04X}sub{} {:?} {:?} {:?} map={} def={:02X?} lo={:02X?} hi={:02X?}",
                o.index,
                s.sub,
                s.name,
                s.data_type,
                s.access,
                s.pdo_mappable,
                default,
                s.low_limit,
                s.high_limit
            ));
        }
    }
    v
}

#[test]
fn every_profile_serves_an_eds_that_gives_its_dictionary() {
    for p in Profile::all() {
        let pn = p
            .build_with_options(NODE, Box::new(MemoryStorage::new()), BuildOptions { eds_object: true })
            .unwrap_or_else(|e| panic!("{p}: {e}"));
        assert!(pn.node.config().eds_object, "{p}");
        let (mut r, _boot) = Rig::with(pn);
        let own = described(r.node().od());
        assert!(own.len() > 300, "{p}: {} lines", own.len());
        let text = upload(&mut r, 0x1021, 0);
        // 1022h: 0 = ASCII (CiA 301 §7.5.2.22).
        assert_eq!(upload(&mut r, 0x1022, 0), [0], "{p}");
        let text = String::from_utf8(text).unwrap_or_else(|e| panic!("{p}: not UTF-8: {e}"));
        let parsed = drivebus_eds::parse(&text).unwrap_or_else(|e| panic!("{p}: {e}"));
        let back = drivebus_eds::to_od(&parsed.eds, NODE).unwrap_or_else(|e| panic!("{p}: {e:?}"));
        let back = described(&back);
        let missing: Vec<&String> = own.iter().filter(|l| !back.contains(l)).collect();
        let extra: Vec<&String> = back.iter().filter(|l| !own.contains(l)).collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "{p}: {} lines differ\nnode only: {missing:#?}\nEDS only: {extra:#?}",
            missing.len() + extra.len()
        );
        assert_eq!(back, own, "{p}: order");
    }
}

/// Without the option a faithful personality has no 1021h (the manuals do
/// not list it); `generic` has it either way.
#[test]
fn the_option_is_opt_in() {
    for p in Profile::all() {
        let (mut r, _) = Rig::new(*p, NODE);
        let has = r.node().od().object(0x1021).is_some();
        assert_eq!(has, *p == Profile::Generic, "{p}");
        if !has {
            let f = r.sdo_read(NODE, 0x1021, 0);
            assert_eq!(f.data()[0], 0x80, "{p}: {f:?}");
        }
    }
}
