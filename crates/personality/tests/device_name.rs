//! 1008h "manufacturer device name" (CiA 301 §7.5.2.8): every personality
//! names itself, with what the product reports (KC1 §7.2.1.7 and AKD
//! §6.2.1.7: "Yzzz", the manuals' own example M006; iPOS §4.8.3 "iPOS";
//! SSD 630 §14.7 "631_402"; DDS6 §6.3.5 gives no value: the model of the
//! product code in 1018h:02, §6.3.16), read by SDO upload from the running
//! drive and equal to the EDS's DefaultValue.

mod replay_rig;

use drivebus_personality::Profile;
use replay_rig::Rig;

#[test]
fn every_personality_names_itself() {
    let want = [
        (Profile::Kc1, "M006"),
        (Profile::Akd, "M006"),
        (Profile::Ipos, "iPOS"),
        (Profile::Ssd630, "631_402"),
        (Profile::Dds6, "DDS6244"),
        (Profile::Generic, "drivebus generic servo"),
    ];
    assert_eq!(want.len(), Profile::all().len());
    for (p, name) in want {
        let (mut r, _) = Rig::new(p, 7);
        let got = r.upload(7, 0x1008, 0).unwrap_or_else(|a| panic!("{p}: 1008h aborted {a:08X}h"));
        assert_eq!(String::from_utf8_lossy(&got), name, "{p}: 1008h");
        let eds = p.parse_eds().eds;
        let d = eds.objects[&0x1008].var.as_ref().and_then(|v| v.default.clone());
        assert_eq!(d.as_deref(), Some(name), "{p}: EDS 1008h DefaultValue");
    }
}
