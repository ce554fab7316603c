//! The SDO content of the Technosoft iPOS CoE manual's examples (seed002,
//! P091.064.UM.0524, `seed002-ipos-examples.md`) replayed against the built
//! `ipos` personality as CANopen expedited SDO frames to node-ID 1.
//!
//! The drive is EtherCAT: its SDOs travel in CoE mailboxes with the CiA 301
//! SDO command layout but no CAN frames and no node-ID, so the frames and
//! confirmations here are derived from the printed (index, sub, value)
//! content. The motion examples (E05, E06, E18–E23, E29/E30, E38–E41) are
//! replayed with their process data as CAN PDOs and their motion in
//! `replay_ipos_motion.rs`. Skipped with the reason in `replay_report.md`:
//! the EtherCAT state machine, FoE/EoE, TwinCAT GUI steps, TML code, and
//! what the personality does not emulate (PT/PVT, gearing, camming).

use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Duration, Frame};
use drivebus_node::MemoryStorage;
use drivebus_personality::ipos::Ipos;
use drivebus_personality::{PersonalityDevice, Profile, build_with};

struct Rig {
    bus: Bus,
    probe: ProbeId,
    dut: NodeId,
    /// SDO transfers replayed (request + confirmation each).
    transfers: usize,
}

impl Rig {
    fn new() -> Rig {
        let node =
            build_with(Profile::Ipos, 1, Box::new(MemoryStorage::new()), Box::new(Ipos::new())).unwrap();
        let mut bus = Bus::new(BusConfig::zero_time());
        let probe = bus.attach_probe();
        let dut = bus.attach(node);
        bus.run_for(Duration::from_millis(1));
        assert_eq!(bus.take_received(probe), vec![Frame::new(0x701, &[0])]);
        Rig { bus, probe, dut, transfers: 0 }
    }

    fn dn(&self) -> &PersonalityDevice {
        self.bus.node::<PersonalityDevice>(self.dut).unwrap()
    }

    fn exchange(&mut self, req: [u8; 8]) -> Vec<Frame> {
        self.bus.take_received(self.probe);
        self.bus.send_from(self.probe, Frame::new(0x601, &req));
        self.bus.run_for(Duration::from_micros(500));
        self.transfers += 1;
        self.bus.take_received(self.probe)
    }

    /// CoE SDO downloads as expedited CANopen downloads: each confirmed
    /// (`581 60 ..`) and stored.
    fn downloads(&mut self, steps: &[(u16, u8, &[u8])]) {
        for (index, sub, data) in steps {
            let cmd = 0x23 | ((4 - data.len() as u8) << 2);
            let mut b = [cmd, *index as u8, (*index >> 8) as u8, *sub, 0, 0, 0, 0];
            b[4..4 + data.len()].copy_from_slice(data);
            let got = self.exchange(b);
            let ok = Frame::new(0x581, &[0x60, *index as u8, (*index >> 8) as u8, *sub, 0, 0, 0, 0]);
            assert_eq!(got, vec![ok], "{index:04X}:{sub} := {data:02X?}");
            let e = self.dn().node.od().get(*index, *sub).expect("object");
            if e.access.readable() {
                assert_eq!(e.bytes(), *data, "{index:04X}:{sub} stored");
            }
        }
    }

    fn upload(&mut self, index: u16, sub: u8) -> Frame {
        let got = self.exchange([0x40, index as u8, (index >> 8) as u8, sub, 0, 0, 0, 0]);
        assert_eq!(got.len(), 1);
        got[0]
    }
}

/// E05 (§1.6.1): profile position — 6060h := 1, 6081h := 0009_0000h.
#[test]
fn e05_profile_position_sdos() {
    let mut r = Rig::new();
    r.downloads(&[(0x6060, 0, &[1]), (0x6081, 0, &0x0009_0000u32.to_le_bytes())]);
}

/// E12 (§3.2.2), E13 (§4.5.3.1), E14 (§4.7.3).
#[test]
fn e12_e14_outputs_and_step_loss() {
    let mut r = Rig::new();
    r.downloads(&[
        (0x2089, 0, &7i16.to_le_bytes()),
        (0x2089, 0, &0i16.to_le_bytes()),
        (0x60FE, 1, &0x0002_0000u32.to_le_bytes()),
        (0x60FE, 2, &0x0003_0000u32.to_le_bytes()),
        // TYPO (examples file): printed "6056h" in the text; 6065h meant.
        (0x6065, 0, &1000u32.to_le_bytes()),
        (0x6066, 0, &20u16.to_le_bytes()),
    ]);
}

/// E15 (§4.8.5/§4.8.6): identity. The manual decodes an iPOS4808 MY-CAT-STO
/// (product 27 214 121, serial "LE1158"); the personality is the iPOS360x
/// VX-CAT of §1.5.4.6 (product 28 002 021), so 1018h:2 is that one's and
/// the serial (per device) is not compared. Vendor 1A3h and device type
/// 0006_0192h as printed; the revision is the firmware ID "A00G" (§1.5.4.6,
/// the twin's FA00G firmware) where the example prints "0100": the SII and
/// ESI revision are the firmware ID, and the twin's 1018h:03 agrees with them.
#[test]
fn e15_identity() {
    let mut r = Rig::new();
    assert_eq!(r.upload(0x1018, 1), Frame::new(0x581, &[0x43, 0x18, 0x10, 0x01, 0xA3, 0x01, 0, 0]));
    let p = 28_002_021u32.to_le_bytes();
    assert_eq!(r.upload(0x1018, 2), Frame::new(0x581, &[0x43, 0x18, 0x10, 0x02, p[0], p[1], p[2], p[3]]));
    assert_eq!(r.upload(0x1018, 3), Frame::new(0x581, &[0x43, 0x18, 0x10, 0x03, 0x47, 0x30, 0x30, 0x41]));
    assert_eq!(r.upload(0x1000, 0), Frame::new(0x581, &[0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x06, 0x00]));
    // §4.8.2: 6502h = 001C03E5h (no tq, ECAM, EGEAR bits although they work).
    assert_eq!(r.dn().node.od().get_u32(0x6502, 0), Some(0x001C_03E5));
}

/// E16 (§5.1.10.1), E18 (§6.4), E19–E22 (§7.3), E23 (§8.3).
#[test]
fn e16_e23_factor_homing_profile_torque() {
    let mut r = Rig::new();
    r.downloads(&[
        (0x6093, 1, &u32::MAX.to_le_bytes()),
        (0x6093, 2, &13_493_038u32.to_le_bytes()),
        // E18 homing method 18
        (0x6099, 2, &0x0005_0000u32.to_le_bytes()),
        (0x6099, 1, &0x0014_0000u32.to_le_bytes()),
        (0x609A, 0, &0x0000_028Fu32.to_le_bytes()),
        (0x607C, 0, &0x0000_07D0i32.to_le_bytes()),
        (0x6098, 0, &[0x12]),
        // E19 / E20
        (0x6081, 0, &0x0010_AAACu32.to_le_bytes()),
        (0x607A, 0, &0x0006_1A80i32.to_le_bytes()),
        (0x6081, 0, &0x0010_AAACu32.to_le_bytes()),
        (0x607A, 0, &0x0000_7D00i32.to_le_bytes()),
        // E21 / E22 S-curve
        (0x6086, 0, &3i16.to_le_bytes()),
        (0x6081, 0, &0x000F_0000u32.to_le_bytes()),
        (0x2023, 0, &0x1F4Bu16.to_le_bytes()),
        (0x6086, 0, &3i16.to_le_bytes()),
        (0x6081, 0, &0x0005_0000u32.to_le_bytes()),
        (0x2023, 0, &0x013Bu16.to_le_bytes()),
        // E23 torque
        (0x6075, 0, &0x03E8u32.to_le_bytes()),
        (0x6087, 0, &0x03E8u32.to_le_bytes()),
        (0x6071, 0, &0x01F4i16.to_le_bytes()),
        (0x6071, 0, &(-1200i16).to_le_bytes()),
    ]);
}

/// E26–E28 (§9.4): PT (60C0h = 0) and PVT (60C0h = −1) set-up; E29/E30
/// (§10.3) target velocity; E37 (§12) 60C2h = 4 × 10⁻³ s.
#[test]
fn e26_e37_ip_submodes_velocity_period() {
    let mut r = Rig::new();
    r.downloads(&[
        (0x60C0, 0, &0i16.to_le_bytes()),
        (0x2073, 0, &0x000Cu16.to_le_bytes()),
        (0x2074, 0, &0xA001u16.to_le_bytes()),
        (0x2079, 0, &0x3E8i32.to_le_bytes()),
        (0x60C0, 0, &(-1i16).to_le_bytes()),
        (0x2073, 0, &0x000Fu16.to_le_bytes()),
        (0x2074, 0, &0xB001u16.to_le_bytes()),
        (0x60C0, 0, &(-1i16).to_le_bytes()),
        (0x2073, 0, &0x000Cu16.to_le_bytes()),
        (0x2074, 0, &0xA001u16.to_le_bytes()),
        // E30's text computes 0200_0000h but prints 0014_0000h: both written.
        (0x60FF, 0, &0x0014_0000i32.to_le_bytes()),
        (0x60FF, 0, &0x0200_0000i32.to_le_bytes()),
        (0x60C2, 1, &[4]),
        (0x60C2, 2, &[0xFD]),
    ]);
}

/// E31–E36 (§11, §12): gearing / camming objects as plain parameters, and
/// the modes −1 (FFh) / −2 (FEh) accepted in 6060h (§4.2.3).
#[test]
fn e31_e36_gearing_and_camming() {
    let mut r = Rig::new();
    r.downloads(&[
        (0x201D, 0, &3u16.to_le_bytes()),
        (0x2012, 0, &0x07D0u32.to_le_bytes()),
        (0x2013, 1, &1i16.to_le_bytes()),
        (0x2013, 2, &1u16.to_le_bytes()),
        (0x201D, 0, &1u16.to_le_bytes()),
        (0x6060, 0, &[0xFF]),
        (0x2064, 0, &0x5638_0008u32.to_le_bytes()),
        (0x2065, 0, &0x0000_C400u32.to_le_bytes()),
        (0x201D, 0, &3u16.to_le_bytes()),
        (0x2019, 0, &0x5638u16.to_le_bytes()),
        (0x201A, 0, &0x97F6u16.to_le_bytes()),
        (0x2012, 0, &0x07D0u32.to_le_bytes()),
        (0x201B, 0, &0x1770u32.to_le_bytes()),
        (0x206B, 0, &1u32.to_le_bytes()),
        (0x206C, 0, &1u32.to_le_bytes()),
        (0x6060, 0, &[0xFE]),
    ]);
    // §4.2.3: a mode outside the table is refused.
    let got = r.exchange([0x2F, 0x60, 0x60, 0x00, 0xFD, 0, 0, 0]);
    assert_eq!(got, vec![Frame::new(0x581, &[0x80, 0x60, 0x60, 0x00, 0x30, 0x00, 0x09, 0x06])]);
}

/// E41 (§13) touch probe set-up; E42–E44 (§14) memory access; E50 (§16)
/// EoE IP values in 210Eh.
#[test]
fn e41_e50_probe_memory_eoe_values() {
    let mut r = Rig::new();
    r.downloads(&[
        (0x6081, 0, &0x0002_0000u32.to_le_bytes()),
        (0x60B8, 0, &0x0011u16.to_le_bytes()),
        (0x2067, 0, &0x036A_1234u32.to_le_bytes()),
        (0x2064, 0, &0x5638_0008u32.to_le_bytes()),
        (0x2065, 0, &0x0000_C400u32.to_le_bytes()),
        (0x2065, 0, &0u32.to_le_bytes()),
        (0x2069, 0, &0x5EFF_5E06u32.to_le_bytes()),
        (0x2064, 0, &0x5E06_0009u32.to_le_bytes()),
        (0x2065, 0, &0x5678_1234u32.to_le_bytes()),
        (0x2065, 0, &0xCDEF_09ABu32.to_le_bytes()),
        (0x210E, 1, &0x0C18_A8C0u32.to_le_bytes()),
        (0x210E, 2, &0x00FF_FFFFu32.to_le_bytes()),
        (0x210E, 3, &0x0B18_A8C0u32.to_le_bytes()),
    ]);
}

/// §1.6.3.1: a mapping over 64 bits is confirmed, then ignored with EMCY
/// 8220h "PDO length exceeded" (register: bits 0 and 4, §3.1.3).
#[test]
fn mapping_over_64_bits_ignored_with_8220() {
    let mut r = Rig::new();
    let cob = r.dn().node.od().get_u32(0x1401, 1).unwrap();
    r.downloads(&[
        // The CAN counterpart of §2.4 step 2 (1C12h:00 := 0, PDO unassigned):
        // the PDO invalid while its mapping changes (CiA 301 §7.5.2.36).
        (0x1401, 1, &(cob | 0x8000_0000).to_le_bytes()),
        (0x1601, 0, &[0]),
        (0x1601, 1, &0x60B8_0010u32.to_le_bytes()),
        (0x1601, 2, &0x607A_0020u32.to_le_bytes()),
        (0x1601, 3, &0x60FF_0020u32.to_le_bytes()),
    ]);
    let got = r.exchange([0x2F, 0x01, 0x16, 0x00, 0x03, 0, 0, 0]);
    assert_eq!(
        got,
        vec![
            Frame::new(0x581, &[0x60, 0x01, 0x16, 0x00, 0, 0, 0, 0]),
            Frame::new(0x81, &[0x20, 0x82, 0x11, 0, 0, 0, 0, 0]),
        ]
    );
    assert_eq!(r.dn().node.od().get_u32(0x1601, 0), Some(0), "mapping ignored");
    // 64 bits exactly is taken.
    r.downloads(&[(0x1601, 0, &[2])]);
}
