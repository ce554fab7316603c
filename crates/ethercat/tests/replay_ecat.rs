//! The iPOS manual's EtherCAT examples replayed against the emulated slave
//! (seed002-ipos-examples.md): E01–E12 and E46–E49, with E05/E06 on the
//! bus they were written for (process data in OP instead of CAN PDOs) and
//! E50's EoE. What each checks, and which TwinCAT GUI steps have no wire
//! content, is in `tests/replay_report.md`. A master cycle here is: the
//! outputs written into SM2, 1 ms, the inputs read from SM3 (free run).

mod drive_rig;

use drive_rig::{FoeResult, Rig, al, mbx};
use drivebus_can::Duration;
use drivebus_esc::frame::{DatagramCommand, station_address};
use drivebus_ethercat::drive::DriveSlaveExt;
use drivebus_personality::Profile;
use drivebus_personality::ipos::foe::{F515X_PASSWORD, FA0XX_PASSWORD, FileKind, IposFiles, SwImage};

fn ipos() -> Rig {
    Rig::new(Profile::Ipos)
}

/// To OP in free run with the current mapping.
fn op(r: &mut Rig) {
    r.safeop();
    assert_eq!(r.request(al::OP), (0x08, 0));
}

/// One master cycle with the default image (RxPDO1 6040h + 607Ah; TxPDO1
/// 6041h + 6064h + 6077h, TxPDO2 60F4h + 60FDh): (statusword, position).
fn cycle(r: &mut Rig, cw: u16, target: i32) -> (u16, i32, Vec<u8>) {
    let mut out = vec![0u8; usize::from(r.pd.0)];
    out[..2].copy_from_slice(&cw.to_le_bytes());
    out[2..6].copy_from_slice(&target.to_le_bytes());
    r.outputs(&out);
    r.tick(Duration::from_millis(1));
    let i = r.inputs();
    (u16::from_le_bytes([i[0], i[1]]), i32::from_le_bytes([i[2], i[3], i[4], i[5]]), i)
}

/// Controlword `cw` until the statusword shows `mask`/`want` (at most `n` cycles).
fn until(r: &mut Rig, cw: u16, target: i32, mask: u16, want: u16, n: u32) -> (u16, i32) {
    for _ in 0..n {
        let (sw, pos, _) = cycle(r, cw, target);
        if sw & mask == want {
            return (sw, pos);
        }
    }
    panic!("statusword never had {want:04X} under {mask:04X}");
}

/// E01 (§1.5.3): the scan finds the drive — a broadcast read counts it,
/// its SII gives the name and identity — and Free Run reaches OP.
#[test]
fn e01_detecting_the_drive() {
    let mut r = ipos();
    let (_, wkc) = r.dg(DatagramCommand::Brd, station_address(0, 0x0000), &[0, 0]);
    assert_eq!(wkc, 1, "one slave");
    let c = r.s.esc().sii_image().parse().unwrap();
    let g = c.general.unwrap();
    assert_eq!(c.strings[usize::from(g.order_idx) - 1], "iPOS360x VX-CAT");
    assert_eq!(c.identity.vendor_id, 0x1A3);
    r.preop();
    op(&mut r);
}

/// E02 (§1.5.4): NC-PTP runs the drive in csp at a 1 ms cycle (the slow
/// loop); a reversing sequence of 720° (2 rotations = 4000 counts at
/// 0.18°/count) at 720°/s, the lag within 90° (500 counts). Homing sensor
/// = IN0 = 60FDh bit 16, which is in TxPDO2 (byte 12 of the inputs).
#[test]
fn e02_nc_ptp_csp_reversing_sequence() {
    let mut r = ipos();
    r.preop();
    r.down(0x6060, 0, &[8]).unwrap();
    op(&mut r);
    let (_, start, _) = cycle(&mut r, 0, 0);
    until(&mut r, 0x06, start, 0x6F, 0x21, 20);
    until(&mut r, 0x07, start, 0x6F, 0x23, 20);
    until(&mut r, 0x0F, start, 0x6F, 0x27, 20);
    // 720°/s = 4000 counts/s = 4 counts per 1 ms cycle; two reversals.
    let mut target = start;
    let mut lag = 0i32;
    let mut far = start;
    for k in 0..3000 {
        let dir = if (k / 1000) % 2 == 0 { 4 } else { -4 };
        target += dir;
        let (sw, pos, i) = cycle(&mut r, 0x0F, target);
        assert_eq!(sw & 0x08, 0, "no fault");
        lag = lag.max((target - pos).abs());
        far = far.max(pos);
        assert_eq!(i.len(), 16);
    }
    assert!(lag <= 500, "lag {lag} counts (90° = 500)");
    assert!(far - start >= 3990, "2 rotations: {}", far - start);
    assert_eq!(drive_probe_offset(&r), Some(12), "60FDh at byte 12 of the inputs");
}

fn drive_probe_offset(r: &Rig) -> Option<usize> {
    let od = r.s.app().device().node.od();
    let tx: Vec<(u16, Vec<u32>)> = drivebus_personality::ecat::rules::assigned(od, 0x1C13)
        .into_iter()
        .map(|p| (p, drivebus_personality::ecat::rules::entries(od, p)))
        .collect();
    drivebus_ethercat::drive_probe::offsets(&tx, 0x60FD, 0).first().copied()
}

/// E03 (§1.5.4.6): 1018h:02 names the product; the revision is the
/// firmware ID in ASCII ("A00G" for the twin's FA00G), in 1018h:03 and the
/// SII alike; "Write E²PROM" through the ESC, then a reset: the new
/// content (here the station alias) is what the ESC loads.
#[test]
fn e03_identity_and_writing_the_eeprom() {
    let mut r = ipos();
    r.preop();
    assert_eq!(r.up_u32(0x1018, 2), 28_002_021);
    let rev = r.up_u32(0x1018, 3);
    assert_eq!(drivebus_esi::revision_firmware(rev).as_deref(), Some("A00G"));
    assert_eq!(r.s.esc().sii_image().parse().unwrap().identity.revision, rev);
    // Write word 4 (alias) and the new CRC (word 7), then reload.
    r.wr(0x0508, &[0x05, 0x00]);
    r.wr(0x0502, &[0x01, 0x02, 4, 0, 0, 0]);
    let crc = drivebus_esc::sii::config_crc(&r.s.esc().sii_image().bytes()[..14]);
    r.wr(0x0508, &[crc, 0x00]);
    r.wr(0x0502, &[0x01, 0x02, 7, 0, 0, 0]);
    r.wr(0x0502, &[0x00, 0x04]);
    assert_eq!(r.rd16(0x0012), 5, "alias loaded from the written EEPROM");
    assert!(r.s.esc().sii_image().checksum_ok());
}

/// E04 (§1.5.5): a 1 ms free-run cycle; "Reload I/O devices" activates
/// the PDO mapping and SYNC0 if enabled: 1C32h:01 = 1 (SM-synchronous)
/// without DC, 2 with SYNC0 at the cycle.
#[test]
fn e04_free_run_cycle_and_sync0() {
    let mut r = ipos();
    r.preop();
    op(&mut r);
    for _ in 0..10 {
        cycle(&mut r, 0, 0);
    }
    assert_eq!(r.up_u32(0x1C32, 1), 1);
    let mut r = ipos();
    r.preop();
    let (o, i) = (6, 16);
    r.pd_sms(o, i, true);
    r.wr(0x09A0, &1_000_000u32.to_le_bytes());
    r.wr(0x0981, &[0x03]);
    assert_eq!(r.request(al::SAFEOP), (0x04, 0));
    assert_eq!((r.up_u32(0x1C32, 1), r.up_u32(0x1C32, 0x0A)), (2, 1_000_000));
}

/// E05 (§1.6.1): a profile position move with 6060h and 6081h by SDO and
/// the controlword and target in the default RxPDO1: 80000 counts at
/// 9.0 IU, then back to 40000.
#[test]
fn e05_position_profile_with_coe_commands() {
    let mut r = ipos();
    r.preop();
    op(&mut r);
    r.down(0x6060, 0, &[1]).unwrap();
    until(&mut r, 0x06, 0, 0x6F, 0x21, 20);
    until(&mut r, 0x07, 80_000, 0x6F, 0x23, 20);
    r.down(0x6081, 0, &0x0009_0000u32.to_le_bytes()).unwrap();
    until(&mut r, 0x0F, 80_000, 0x6F, 0x27, 20);
    let (_, _) = until(&mut r, 0x1F, 80_000, 0x1000, 0x1000, 50);
    let (_, pos) = until(&mut r, 0x1F, 80_000, 0x0400, 0x0400, 12_000);
    assert!((pos - 80_000).abs() <= 5, "{pos}");
    cycle(&mut r, 0x0F, 40_000);
    until(&mut r, 0x1F, 40_000, 0x1000, 0x1000, 50);
    let (_, pos) = until(&mut r, 0x1F, 40_000, 0x0400, 0x0400, 8_000);
    assert!((pos - 40_000).abs() <= 5, "{pos}");
}

/// E06 (§1.6.2): csp by hand: small target steps (20–200 counts) in
/// RxPDO1, each reached within the 1 ms cycle.
#[test]
fn e06_csp_manual_commands() {
    let mut r = ipos();
    r.preop();
    r.down(0x6060, 0, &[8]).unwrap();
    op(&mut r);
    let (_, start, _) = cycle(&mut r, 0, 0);
    until(&mut r, 0x06, start, 0x6F, 0x21, 20);
    until(&mut r, 0x07, start, 0x6F, 0x23, 20);
    until(&mut r, 0x0F, start, 0x6F, 0x27, 20);
    let mut target = start;
    for step in [20, 50, 100, 200, -200, -100, -50, -20] {
        target += step;
        // The demand (6062h) covers the step within the cycle: free run
        // is not synchronised with the drive's loop (§3.2: that is what
        // SYNC0 is for), so to within the part of the step one control
        // period takes.
        cycle(&mut r, 0x0F, target);
        cycle(&mut r, 0x0F, target);
        let demand = r.up_u32(0x6062, 0) as i32;
        assert!((demand - target).abs() <= step.abs() / 4, "6062h {demand} vs {target}");
        // The motor settles there (its position loop), the demand exactly.
        let mut pos = 0;
        for _ in 0..100 {
            pos = cycle(&mut r, 0x0F, target).1;
        }
        assert_eq!(r.up_u32(0x6062, 0) as i32, target);
        assert!((pos - target).abs() <= 5, "{pos} vs {target}");
    }
}

/// E07 (§1.6.3.1): RxPDO2 := 60B8h + 2092h:01, assigned in 1C12h; the
/// process image grows to 12 bytes and UserVar1 comes through it. The
/// remark: a mapping over 64 bits is confirmed, EMCY 8220h, ignored.
#[test]
fn e07_mapping_rxpdo2() {
    let mut r = ipos();
    r.preop();
    for (i, s, v) in [
        (0x1C12u16, 0u8, &[0u8][..]),
        (0x1601, 0, &[0]),
        (0x1601, 1, &0x60B8_0010u32.to_le_bytes()),
        (0x1601, 2, &0x2092_0120u32.to_le_bytes()),
        (0x1601, 0, &[2]),
        (0x1C12, 2, &0x1601u16.to_le_bytes()),
        (0x1C12, 0, &[2]),
    ] {
        r.down(i, s, v).unwrap_or_else(|e| panic!("{i:04X}:{s}: {e:?}"));
    }
    let (o, _) = r.safeop();
    assert_eq!(o, 12, "6040h + 607Ah + 60B8h + 2092h:01");
    assert_eq!(r.request(al::OP), (0x08, 0));
    let mut out = vec![0u8; 12];
    out[8..12].copy_from_slice(&0x1234_5678u32.to_le_bytes());
    r.outputs(&out);
    r.tick(Duration::from_millis(2));
    assert_eq!(r.up_u32(0x2092, 1), 0x1234_5678);
    // Over 64 bits (E07 remark): confirmed, EMCY 8220h, mapping ignored.
    let mut r = ipos();
    r.preop();
    r.down(0x1601, 0, &[0]).unwrap();
    for (s, e) in [(1u8, 0x2092_0120u32), (2, 0x2092_0220), (3, 0x60B8_0010)] {
        r.down(0x1601, s, &e.to_le_bytes()).unwrap();
    }
    r.down(0x1601, 0, &[3]).unwrap();
    r.collect_emergencies(Duration::from_millis(50));
    assert!(r.emergencies.iter().any(|e| e.0 == 0x8220), "{:X?}", r.emergencies);
    assert_eq!(r.up(0x1601, 0).unwrap(), [0]);
}

/// E08 (§1.6.3.2): TxPDO3 := 60B9h + 60BAh, assigned in 1C13h: 22 input bytes.
#[test]
fn e08_mapping_txpdo3() {
    let mut r = ipos();
    r.preop();
    for (i, s, v) in [
        (0x1C13u16, 0u8, &[0u8][..]),
        (0x1A02, 0, &[0]),
        (0x1A02, 1, &0x60B9_0010u32.to_le_bytes()),
        (0x1A02, 2, &0x60BA_0020u32.to_le_bytes()),
        (0x1A02, 0, &[2]),
        (0x1C13, 3, &0x1A02u16.to_le_bytes()),
        (0x1C13, 0, &[3]),
    ] {
        r.down(i, s, v).unwrap_or_else(|e| panic!("{i:04X}:{s}: {e:?}"));
    }
    let (_, i) = r.safeop();
    assert_eq!(i, 22);
}

/// E09–E11 (§2.4–§2.6): the general procedure with E10's RxPDO3 and
/// E11's TxPDO4, every SDO download as printed (1C12h:02 and 1C13h:03
/// assigned first, see the analyst notes), then SAFE-OP and OP.
#[test]
fn e09_e10_e11_mapping_procedures() {
    let mut r = ipos();
    r.preop();
    r.down(0x1C12, 0, &[0]).unwrap();
    r.down(0x1C12, 2, &0x1601u16.to_le_bytes()).unwrap();
    r.down(0x1C13, 0, &[0]).unwrap();
    r.down(0x1C13, 3, &0x1A02u16.to_le_bytes()).unwrap();
    let e10: [(u16, u8, &[u8]); 6] = [
        (0x1602, 0, &[0]),
        (0x1602, 1, &0x6040_0010u32.to_le_bytes()),
        (0x1602, 2, &0x6060_0008u32.to_le_bytes()),
        (0x1602, 0, &[2]),
        (0x1C12, 3, &0x1602u16.to_le_bytes()),
        (0x1C12, 0, &[3]),
    ];
    let e11: [(u16, u8, &[u8]); 6] = [
        (0x1A03, 0, &[0]),
        (0x1A03, 1, &0x6064_0020u32.to_le_bytes()),
        (0x1A03, 2, &0x60FD_0020u32.to_le_bytes()),
        (0x1A03, 0, &[2]),
        (0x1C13, 4, &0x1A03u16.to_le_bytes()),
        (0x1C13, 0, &[4]),
    ];
    for (i, s, v) in e10.iter().chain(&e11) {
        r.down(*i, *s, v).unwrap_or_else(|e| panic!("{i:04X}:{s}: {e:?}"));
    }
    let (o, i) = r.safeop();
    assert_eq!((o, i), (6 + 8 + 3, 16 + 4 + 8), "RxPDO1..3, TxPDO1..4");
    assert_eq!(r.request(al::OP), (0x08, 0));
    // RxPDO3's modes of operation reaches 6060h every cycle.
    let mut out = vec![0u8; usize::from(o)];
    out[16] = 8;
    r.outputs(&out);
    r.tick(Duration::from_millis(2));
    assert_eq!(r.up(0x6060, 0).unwrap(), [8]);
    // Out of PRE-OP the assignment is fixed (§2.3.10).
    assert_eq!(r.down(0x1C12, 0, &[0]), Err(drive_rig::Fail::Abort(0x0800_0022)));
}

/// E12 (§3.2.2): 2089h := 7 is taken (the oscilloscope outputs are not
/// emulated); conditions a)/b): SYNC0 2 ms (a multiple of the 1 ms loop)
/// is accepted and 60C2h follows it, SYNC0 1.5 ms is refused (AL 0035h).
#[test]
fn e12_synchronization_conditions() {
    let mut r = ipos();
    r.preop();
    r.down(0x2089, 0, &7i16.to_le_bytes()).unwrap();
    assert_eq!(r.up(0x2089, 0).unwrap(), 7i16.to_le_bytes());
    r.pd_sms(6, 16, true);
    r.wr(0x09A0, &2_000_000u32.to_le_bytes());
    r.wr(0x0981, &[0x03]);
    assert_eq!(r.request(al::SAFEOP), (0x04, 0));
    assert_eq!((r.up_u32(0x60C2, 1), r.up(0x60C2, 2).unwrap()), (2, vec![(-3i8) as u8]));
    assert_eq!(r.request(al::PREOP), (0x02, 0));
    r.wr(0x0981, &[0x00]);
    r.wr(0x09A0, &1_500_000u32.to_le_bytes());
    r.wr(0x0981, &[0x03]);
    assert_eq!(r.request(al::SAFEOP), (0x12, 0x0035));
}

fn setup_file() -> Vec<u8> {
    // A .sw image (§17.3): a block at 5638h, as Figure 17.4.1 shows.
    b"5638\nC400\n0\n92\n\n5700\n1\n2\n".to_vec()
}

/// E46 (§17.4.3–§17.4.4): a setup file by FoE in OP, PRE-OP and SAFE-OP
/// with password 0 and the naming rules; stored, its .sw blocks kept.
#[test]
fn e46_foe_setup_file() {
    let mut r = ipos();
    r.preop();
    assert_eq!(r.foe_write("FOESW_AXIS1.bin", 0, &setup_file()), FoeResult::Done { busy: 0 });
    r.safeop();
    assert_eq!(r.foe_write("FOESW_AXIS1.efw", 0, &setup_file()), FoeResult::Done { busy: 0 });
    assert_eq!(r.request(al::OP), (0x08, 0));
    let big: Vec<u8> = (0..3000u32).map(|i| i as u8).collect();
    assert_eq!(r.foe_write("FOESW_BIG.bin", 0, &big), FoeResult::Done { busy: 0 });
    // Refused: too long a name, another extension, a password, no prefix.
    for (name, pw, code) in [
        ("FOESW_123456789.bin", 0, 0x8001),
        ("FOESW_AXIS1.sw", 0, 0x8001),
        ("SETUP.bin", 0, 0x8001),
        ("FOESW_AXIS1.bin", 1, 0x8002),
    ] {
        assert_eq!(r.foe_write(name, pw, b"x"), FoeResult::Error(code), "{name}");
    }
    let files = r.s.app_mut().files_mut::<IposFiles>().unwrap();
    assert_eq!(files.taken.len(), 3);
    assert!(files.taken.iter().all(|f| f.kind == FileKind::Setup));
    let img = files.taken[0].image.clone().unwrap();
    assert_eq!(img, SwImage::parse(&setup_file()).unwrap());
    assert_eq!(files.taken[2].data, big);
    // With a state directory the setup file is kept there (it survives a
    // restart of `drivebus ethercat serve --state-dir`).
    let dir = std::env::temp_dir().join(format!("drivebus-e46-{}", std::process::id()));
    let spec = drivebus_ethercat::drive::DriveSlaveSpec {
        state_dir: Some(dir.clone()),
        ..drivebus_ethercat::drive::DriveSlaveSpec::new(Profile::Ipos, 1)
    };
    let mut r = Rig::with_spec(&spec);
    r.preop();
    assert_eq!(r.foe_write("FOESW_AXIS1.bin", 0, &setup_file()), FoeResult::Done { busy: 0 });
    assert_eq!(std::fs::read(dir.join("foe").join("FOESW_AXIS1.bin")).unwrap(), setup_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// E47 (§17.4.5): FB_EcFoeLoad switches to BOOT; a setup file is taken
/// there only with 210Ch = 1. The ESI asks for the 20 s mailbox timeout.
#[test]
fn e47_setup_file_in_boot() {
    let mut r = ipos();
    r.preop();
    r.down(0x210C, 0, &1i16.to_le_bytes()).unwrap();
    assert_eq!(r.request(al::INIT), (0x01, 0));
    assert_eq!(r.request(al::BOOT), (0x03, 0));
    assert_eq!(r.foe_write("FOESW_AXIS1.bin", 0, &setup_file()), FoeResult::Done { busy: 0 });
    let mut r = ipos();
    r.preop();
    assert_eq!(r.request(al::INIT), (0x01, 0));
    assert_eq!(r.request(al::BOOT), (0x03, 0));
    assert_eq!(r.foe_write("FOESW_AXIS1.bin", 0, &setup_file()), FoeResult::Error(0x8009), "210Ch = 0");
    // BOOT carries FoE only (§3.1): CoE is refused.
    let c = r.counter();
    let m = r.one(&mbx(0x03, c, &[0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]));
    assert_eq!((m[5] & 0x0F, u16::from_le_bytes([m[8], m[9]])), (0, 0x0002));
    assert!(r.s.esi().contains("<ResponseTimeout>20000</ResponseTimeout>"), "§17.4.5: 20000 ms");
}

/// E48/E49 (§17.4.6–§17.4.7): firmware only in BOOT, with the FA0xx
/// password (the twin is FA00G; F515x's is refused); erase and programming
/// answer BUSY; back to INIT and OP, the drive runs on.
#[test]
fn e48_e49_firmware_update() {
    let mut r = ipos();
    r.preop();
    let fw: Vec<u8> = (0..5000u32).map(|i| (i * 13) as u8).collect();
    assert_eq!(r.foe_write("FOEFW_FA00H", FA0XX_PASSWORD, &fw), FoeResult::Error(0x8008), "not in PRE-OP");
    assert_eq!(r.request(al::INIT), (0x01, 0));
    assert_eq!(r.request(al::BOOT), (0x03, 0));
    assert_eq!(r.foe_write("FOEFW_FA00H", F515X_PASSWORD, &fw), FoeResult::Error(0x8002), "F515x password");
    // The manual's example name "FOEPW_F515G.foe" does not follow its own rule.
    assert_eq!(r.foe_write("FOEPW_F515G.foe", FA0XX_PASSWORD, &fw), FoeResult::Error(0x8001));
    let FoeResult::Done { busy } = r.foe_write("FOEFW_FA00H", FA0XX_PASSWORD, &fw) else { panic!("refused") };
    assert!(busy >= 3, "BUSY while the flash is erased and programmed ({busy})");
    let files = r.s.app_mut().files_mut::<IposFiles>().unwrap();
    assert_eq!(files.taken.last().map(|f| (f.kind, f.data.len())), Some((FileKind::Firmware, fw.len())));
    assert_eq!(r.request(al::PREOP), (0x13, 0x0011), "BOOT leaves only to INIT");
    assert_eq!(r.request(al::INIT | al::ACK), (0x01, 0));
    r.preop();
    op(&mut r);
    assert_eq!(r.up_u32(0x1018, 3), 0x4130_3047, "still the FA00G twin");
}

/// E50 (§17.5.2.2): 210Eh holds the EoE IP settings (little-endian); the
/// EoE service itself is not offered (mailbox error 0002h).
#[test]
fn e50_eoe_settings_without_eoe() {
    let mut r = ipos();
    r.preop();
    r.down(0x210E, 1, &0x0C18_A8C0u32.to_le_bytes()).unwrap();
    assert_eq!(r.up_u32(0x210E, 1), 0x0C18_A8C0, "192.168.24.12");
    let c = r.counter();
    let m = r.one(&mbx(0x02, c, &[0; 8]));
    assert_eq!((m[5] & 0x0F, u16::from_le_bytes([m[8], m[9]])), (0, 0x0002));
}
