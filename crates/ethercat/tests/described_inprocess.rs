//! ethercrab 0.7.1 (through the tool master) against a line made from real
//! devices' descriptions, over the in-process link on simulated time: an
//! EK1100 coupler, an EL2004 (its EEPROM image in Intel hex) and an EL2828
//! (binary image) as ethercrab's repository dumped them from the real
//! terminals, the KickCAT Freedom-K64F board from its ESI file, and an
//! iPOS twin. The line is discovered with the real names and identities,
//! goes to OP, the outputs the master writes appear on the devices and the
//! board's inputs (its outputs looped back) come back.

use drivebus_can::Instant;
use drivebus_ethercat::described::{self, Member};
use drivebus_ethercat::master::{LineMaster, PduFrames};
use drivebus_ethercat::{Clock, Host};
use drivebus_personality::Profile;
use std::time::Duration;

fn vector(name: &str) -> String {
    format!("{}/../../tests/vectors/ethercat/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn line() -> Host {
    let dev =
        |f: &str| Member::Device(Box::new(described::load(&vector(f)).unwrap_or_else(|e| panic!("{e}"))));
    let members = [
        dev("ek1100.bin"),
        dev("el2004.hex"),
        dev("el2828.bin"),
        dev("kickcat-freedom-k64f.xml"),
        Member::Drive(Profile::Ipos),
    ];
    Host::line(described::devices(&members, None).unwrap(), Clock::simulated(Instant::from_millis(1)))
}

#[test]
fn real_devices_discovered_to_op_with_outputs_and_inputs() {
    static S: PduFrames = PduFrames::new();
    let host = line();
    let m = LineMaster::on_host(&S, host.clone()).unwrap();
    async_io::block_on(async {
        let (found, group) = m.scan_group().await.unwrap();
        let seen: Vec<(&str, [u32; 4])> = found.iter().map(|f| (f.name.as_str(), f.identity)).collect();
        assert_eq!(seen[0], ("EK1100", [2, 0x044C_2C52, 0x0012_0000, 0]));
        assert_eq!(seen[1], ("EL2004", [2, 0x07D4_3052, 0x0010_0000, 0]));
        assert_eq!(seen[2], ("EL2828", [2, 0x0B0C_3052, 0x0011_0000, 0]));
        assert_eq!(seen[3], ("Board", [0x6A5, 0x00DE_FEDE, 0x5A01, 4]), "serial: its position");
        assert_eq!(found[3].coe_identity, Some(found[3].identity), "1018h over CoE agrees");
        assert_eq!(found[4].identity[0], 0x1A3, "the iPOS twin");
        let md = m.main_device();
        let g = group.into_safe_op(md).await.unwrap();
        let g = g.into_op(md).await.unwrap();
        let mut wkc = 0;
        for k in 0..50u8 {
            {
                let sd = g.subdevice(md, 1).unwrap();
                sd.outputs_raw_mut()[0] = 0x05;
            }
            g.subdevice(md, 2).unwrap().outputs_raw_mut()[0] = 0xA5 ^ k;
            g.subdevice(md, 3).unwrap().outputs_raw_mut().copy_from_slice(&[1, 2, 3]);
            wkc = g.tx_rx(md).await.unwrap().working_counter;
            m.pace().sleep(Duration::from_millis(1)).await;
        }
        let board = g.subdevice(md, 3).unwrap();
        assert_eq!(board.inputs_raw().to_vec(), [1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3], "outputs looped back");
        assert!(wkc > 0);
        for i in 0..5 {
            assert_eq!(
                m.al_status(i + 1).await.unwrap().state,
                Ok(drivebus_ethercat::master::AlState::Op),
                "slave {i}"
            );
        }
    });
    let outputs = |i| described::with_device(&host, i, |s| s.app().outputs().to_vec()).unwrap();
    assert_eq!(outputs(1), [0x05], "EL2004 channels 1 and 3 on");
    assert_eq!(outputs(2), [0xA5 ^ 49], "EL2828: the last value written");
    assert_eq!(outputs(3), [1, 2, 3], "the board's LEDs");
    let led = described::with_device(&host, 3, |s| s.app().dictionary().unwrap().get_u64(0x7001, 0)).unwrap();
    assert_eq!(led, Some(2), "LED_G (7001h) over CoE is the output value");
}

/// A CoE device from its EEPROM image alone (a Kollmorgen AKD): the
/// dictionary a master reads is made from the image's PDOs, so ethercrab
/// reads 1018h and the 1C12h/1C13h assignment (1701h, 1B01h) over CoE,
/// goes to OP, and the controlword it writes lands in 6040h.
#[test]
fn coe_image_without_esi_serves_its_pdos() {
    static S: PduFrames = PduFrames::new();
    let akd = Member::Device(Box::new(described::load(&vector("akd.bin")).unwrap()));
    let host =
        Host::line(described::devices(&[akd], None).unwrap(), Clock::simulated(Instant::from_millis(1)));
    let m = LineMaster::on_host(&S, host.clone()).unwrap();
    async_io::block_on(async {
        let (found, group) = m.scan_group().await.unwrap();
        assert_eq!(found[0].name, "AKD");
        assert_eq!(found[0].identity, [0x6A, 0x0041_4B44, 2, 0x9983_0093]);
        assert_eq!(found[0].coe_identity, Some(found[0].identity));
        let md = m.main_device();
        {
            let sd = m.slave(&group, 1).unwrap();
            let rx = drivebus_ethercat::master::pdo_assignment(&sd, 1, 0x1C12).await.unwrap();
            assert_eq!(rx, [(0x1701, vec![0x60C1_0120, 0x6040_0010])]);
        }
        let g = group.into_safe_op(md).await.unwrap().into_op(md).await.unwrap();
        for _ in 0..20 {
            g.subdevice(md, 0).unwrap().outputs_raw_mut().copy_from_slice(&[0x10, 0x27, 0, 0, 0x0F, 0x00]);
            g.tx_rx(md).await.unwrap();
            m.pace().sleep(Duration::from_millis(1)).await;
        }
        assert_eq!(g.subdevice(md, 0).unwrap().inputs_raw().to_vec(), [0x10, 0x27, 0, 0, 0x0F, 0x00]);
    });
    let cw = described::with_device(&host, 0, |s| s.app().dictionary().unwrap().get_u64(0x6040, 0)).unwrap();
    assert_eq!(cw, Some(0x000F));
    let ip = described::with_device(&host, 0, |s| s.app().dictionary().unwrap().get_u64(0x60C1, 1)).unwrap();
    assert_eq!(ip, Some(10_000));
}
