//! The DCF of a running drive (CiA 306 §5, `drivebus_eds::dcf_from_od`):
//! its EDS with every readable value the drive holds as `ParameterValue`
//! and `[DeviceComissioning]`. For every profile, after the master has
//! configured something, the DCF reads back (CiA 306), passes the checker
//! without errors, and converted for the node gives the drive's values.

mod replay_rig;

use drivebus_eds::{Commissioning, Severity, check, dcf_from_od, parse, to_od, write};
use drivebus_od::DataType;
use drivebus_personality::Profile;
use replay_rig::Rig;

const NODE: u8 = 12;

#[test]
fn dcf_of_every_running_drive() {
    for &p in Profile::all() {
        let (mut r, _) = Rig::new(p, NODE);
        // A configured value: TPDO1 event timer 100 ms where it is writable.
        let _ = r.download(NODE, 0x1800, 5, &100u16.to_le_bytes());
        let eds = p.parse_eds().eds;
        let c = Commissioning {
            node_id: NODE,
            node_name: format!("{p} axis"),
            baudrate: 500,
            net_number: 1,
            lss_serial_number: r.node().od().get_u32(0x1018, 4),
            ..Commissioning::default()
        };
        let od = r.node().od().clone();
        let text = write(&dcf_from_od(&eds, &od, c));
        let back = parse(&text).unwrap_or_else(|e| panic!("{p}: {e}")).eds;
        let errors: Vec<_> = check(&back).into_iter().filter(|f| f.severity == Severity::Error).collect();
        assert!(errors.is_empty(), "{p}: {errors:#?}");
        assert_eq!(back.commissioning.as_ref().map(|c| c.node_id), Some(NODE), "{p}");
        let got = to_od(&back, NODE).unwrap_or_else(|e| panic!("{p}: {e}"));
        let mut compared = 0;
        for o in od.objects() {
            for s in o.subs().iter().filter(|s| s.access.readable() && s.data_type != DataType::Domain) {
                let Some(g) = got.get(o.index, s.sub) else { continue };
                assert_eq!(g.bytes(), s.bytes(), "{p} {:04X}:{}", o.index, s.sub);
                compared += 1;
            }
        }
        assert!(compared > 200, "{p}: {compared} values");
    }
}
