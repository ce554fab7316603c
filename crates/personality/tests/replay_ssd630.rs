//! The SSD Drives 630 manual's examples (seed003, *CANopen-630* V0904,
//! §6, §8, §9, §11, §14) replayed against the built `ssd630` personality
//! on the virtual bus: the CiA 301 frames exactly, the CiA 402 ones with
//! the statuswords the manual prints and the motion it describes.
//!
//! Example ids follow `seed003-ssd630-examples.md`; node-ID 1 throughout.
//! The manual prints 25 SDO frames with 7 data bytes; its §3 says SDO frames
//! are always 8 bytes, so the examples file's corrected frames are replayed.
//! Every other correction is marked `TYPO` with the printed bytes.

#[path = "replay_rig/trace.rs"]
mod shared_trace;
use drivebus_bus::{Bus, BusConfig, NodeId, ProbeId};
use drivebus_can::{Duration, Frame};
use drivebus_node::MemoryStorage;
use drivebus_personality::ssd630::{COUNTS_PER_REV, Ssd630};
use drivebus_personality::{PersonalityDevice, Profile, build_with};
use shared_trace::fr;

struct Rig {
    bus: Bus,
    probe: ProbeId,
    dut: NodeId,
    /// Frames checked against the manual (printed or corrected).
    checked: usize,
}

impl Rig {
    fn with(b: Ssd630) -> Rig {
        let node = build_with(Profile::Ssd630, 1, Box::new(MemoryStorage::new()), Box::new(b)).unwrap();
        let mut bus = Bus::new(BusConfig::zero_time());
        let probe = bus.attach_probe();
        let dut = bus.attach(node);
        bus.run_for(Duration::from_millis(1));
        let mut r = Rig { bus, probe, dut, checked: 0 };
        // Boot-up (CiA 301; the manual does not mention it) and §9's
        // "no error" EMCY with the firmware version.
        assert_eq!(r.take(), vec![fr("701#00"), fr("081#00 00 00 56 38 31 39 64")]);
        r
    }

    fn new() -> Rig {
        Rig::with(Ssd630::new())
    }

    fn dn(&self) -> &PersonalityDevice {
        self.bus.node::<PersonalityDevice>(self.dut).unwrap()
    }

    fn take(&mut self) -> Vec<Frame> {
        self.bus.take_received(self.probe)
    }

    fn send(&mut self, f: &str) {
        self.bus.send_from(self.probe, fr(f));
        self.bus.run_for(Duration::from_micros(200));
    }

    /// Request in, exactly these frames out.
    fn ex(&mut self, req: &str, resp: &[&str]) {
        self.take();
        self.send(req);
        let want: Vec<Frame> = resp.iter().map(|s| fr(s)).collect();
        assert_eq!(self.take(), want, "after {req}");
        self.checked += 1 + resp.len();
    }

    fn steps(&mut self, s: &[(&str, &[&str])]) {
        for (q, a) in s {
            self.ex(q, a);
        }
    }

    fn run_ms(&mut self, ms: u64) {
        self.bus.run_for(Duration::from_millis(ms));
    }

    fn sw(&self) -> u16 {
        self.dn().node.od().get_u32(0x6041, 0).unwrap() as u16
    }

    fn i32(&self, index: u16) -> i32 {
        self.dn().node.od().get_i64(index, 0).unwrap() as i32
    }

    /// Position rate over the next second \[increments/s\].
    fn rate(&mut self) -> f64 {
        let p0 = self.dn().app.drive.position_increments();
        self.run_ms(1000);
        (self.dn().app.drive.position_increments() - p0) as f64
    }

    /// Runs until the statusword has `bits` set (at most `ms`).
    fn wait_sw(&mut self, bits: u16, ms: u64) {
        for _ in 0..ms {
            if self.sw() & bits == bits {
                return;
            }
            self.run_ms(1);
        }
        panic!("statusword {:04X} never had {bits:04X}", self.sw());
    }

    /// §14.8 (EX14.8): the state machine to Operation enabled by SDO.
    fn enable(&mut self) {
        self.steps(&[
            // Printed "0250h" in the text; the bytes 40 02 are 0240h, replayed.
            ("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 40 02 00 00"]),
            ("601#2B 40 60 00 06 00 00 00", &["581#60 40 60 00 00 00 00 00"]),
            // "repeat step 1 → 0231h" (ready to switch on).
            ("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 31 02 00 00"]),
            ("601#2B 40 60 00 07 00 00 00", &["581#60 40 60 00 00 00 00 00"]),
            // → 0233h (switched on).
            ("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 33 02 00 00"]),
            ("601#2B 40 60 00 0F 00 00 00", &["581#60 40 60 00 00 00 00 00"]),
        ]);
        self.run_ms(5);
        // → 0627h (operation enabled, target reached, remote).
        self.ex("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 27 06 00 00"]);
    }
}

/// §9 transition 0 / Table 1: after initialisation the 630 sends EMCY 0000h,
/// register 00h, "Vxxxx" (checked in `Rig::with`); §8: no heartbeat.
#[test]
fn boot_emcy_and_no_heartbeat() {
    let mut r = Rig::new();
    r.run_ms(2000);
    assert!(r.take().is_empty(), "§8: node guarding only, nothing sent unasked");
}

/// EX14.1: unknown index 1234h → `0601 0000h` (not CiA 301's 0602 0000h).
/// Both rows printed with 7 bytes (one 00 lost).
#[test]
fn ex14_1_unknown_index_0601() {
    let mut r = Rig::new();
    r.ex("601#40 34 12 00 00 00 00 00", &["581#80 34 12 00 00 00 01 06"]);
}

/// EX14.2: 6060h := 9 → `0609 0030h` (mode 9 is not a 630 mode, §12).
#[test]
fn ex14_2_mode_9_refused() {
    let mut r = Rig::new();
    // Printed with 7 bytes: `2F 60 60 00 09 00 00`.
    r.ex("601#2F 60 60 00 09 00 00 00", &["581#80 60 60 00 30 00 09 06"]);
}

/// EX14.3–EX14.7: identity and communication objects.
#[test]
fn ex14_3_to_7_identity() {
    let mut r = Rig::new();
    r.steps(&[
        // EX14.3: device type 0002 0192h.
        ("601#40 00 10 00 00 00 00 00", &["581#43 00 10 00 92 01 02 00"]),
        // EX14.4 TYPO: the bytes address 1018h; the title and the 1-byte
        // reply 00h are the error register 1001h's.
        ("601#40 01 10 00 00 00 00 00", &["581#4F 01 10 00 00 00 00 00"]),
        // EX14.5: manufacturer status register 0 (active, error free).
        ("601#40 02 10 00 00 00 00 00", &["581#43 02 10 00 00 00 00 00"]),
        // EX14.6 INCONSISTENT: node 1's COB-IDs, value printed 4; node 1 reads 1.
        ("601#40 0B 10 00 00 00 00 00", &["581#43 0B 10 00 01 00 00 00"]),
        // EX14.7: segmented upload of "631_402"; the segment request carries
        // the index in its reserved bytes (ignored).
        ("601#40 08 10 00 00 00 00 00", &["581#41 08 10 00 07 00 00 00"]),
        ("601#60 08 10 00 00 00 00 00", &["581#01 36 33 31 5F 34 30 32"]),
    ]);
    assert_eq!(r.checked, 12);
}

/// EX14.8: state machine by SDO — 0240h, 0231h, 0233h, 0627h (§14.8).
#[test]
fn ex14_8_state_machine() {
    let mut r = Rig::new();
    r.enable();
    assert_eq!(r.dn().node.od().get_i64(0x6061, 0), Some(1), "§10: pp after power-on");
}

/// §10.2: without the enable input (X10.7) the remote bit is clear and the
/// Shutdown command is not accepted.
#[test]
fn remote_bit_needs_enable_input() {
    let mut r = Rig::with(Ssd630::with_enable_input(false));
    r.ex("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 40 00 00 00"]);
    r.ex("601#2B 40 60 00 06 00 00 00", &["581#60 40 60 00 00 00 00 00"]);
    r.run_ms(5);
    r.ex("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 40 00 00 00"]);
}

/// EX14.9: positioning by SDO, +100 000 increments at 1000 min⁻¹, then
/// −100 000 at 100 min⁻¹ (relative moves, §14.9).
#[test]
fn ex14_9_positioning_by_sdo() {
    let mut r = Rig::new();
    r.enable();
    r.steps(&[
        ("601#23 81 60 00 E8 03 00 00", &["581#60 81 60 00 00 00 00 00"]),
        // TYPO: printed `2B 7A 60 00 A0 68 01 00` (2-byte command, 92 320);
        // 100 000 = A0 86 01 00 with 23h (as in EX14.11).
        ("601#23 7A 60 00 A0 86 01 00", &["581#60 7A 60 00 00 00 00 00"]),
        // "repeat step 1 → 0627h (axis stopped)".
        ("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 27 06 00 00"]),
        ("601#2B 40 60 00 5F 00 00 00", &["581#60 40 60 00 00 00 00 00"]),
    ]);
    r.run_ms(2);
    // "→ 9227h (set_point_acknowledge = 1, target reached = 0 → axis moves)".
    r.ex("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 27 92 00 00"]);
    r.ex("601#2B 40 60 00 0F 00 00 00", &["581#60 40 60 00 00 00 00 00"]);
    r.wait_sw(0x0400, 10_000);
    r.run_ms(50);
    assert_eq!(r.sw(), 0x0627);
    let p = r.i32(0x6064);
    assert!((p - 100_000).abs() <= 10, "§14.9: +100 000 increments, at {p}");
    r.steps(&[
        ("601#23 81 60 00 64 00 00 00", &["581#60 81 60 00 00 00 00 00"]),
        // TYPO: printed with command 2Bh for the 4-byte value.
        ("601#23 7A 60 00 60 79 FE FF", &["581#60 7A 60 00 00 00 00 00"]),
        // TYPO: "→ 062Fh (axis stopped)" has the fault bit; 0627h meant.
        ("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 27 06 00 00"]),
        ("601#2B 40 60 00 5F 00 00 00", &["581#60 40 60 00 00 00 00 00"]),
    ]);
    r.run_ms(2);
    r.ex("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 27 92 00 00"]);
    r.ex("601#2B 40 60 00 0F 00 00 00", &["581#60 40 60 00 00 00 00 00"]);
    // 100 000 increments at 100 min⁻¹ (4096 increments per revolution):
    // 24.4 revolutions in ≈ 14.6 s.
    r.run_ms(5_000);
    // 100 min⁻¹ = 4096 · 100 / 60 = 6827 increments/s (the measured 606Ch
    // is quantised at this speed: the position rate is compared).
    let v = r.rate();
    assert!((v + 6827.0).abs() < 70.0, "§14.9: −100 min⁻¹, at {v} inc/s");
    assert_eq!(r.sw() & 0x0400, 0, "still moving at 100 min⁻¹");
    r.wait_sw(0x0400, 10_000);
    r.run_ms(50);
    let p = r.i32(0x6064);
    assert!(p.abs() <= 10, "back at the start, at {p}");
}

/// EX14.10: homing by SDO, method −24 (own mode 0: next zero pulse in
/// positive direction) at 50 min⁻¹ (§14.10).
#[test]
fn ex14_10_homing() {
    let mut r = Rig::new();
    r.enable();
    // Row 1 has a stray 03 in byte 5 of a 1-byte download: outside the
    // payload, replayed as printed.
    r.steps(&[
        ("601#2F 60 60 00 06 03 00 00", &["581#60 60 60 00 00 00 00 00"]),
        ("601#40 61 60 00 00 00 00 00", &["581#4F 61 60 00 06 00 00 00"]),
        ("601#23 99 60 01 32 00 00 00", &["581#60 99 60 01 00 00 00 00"]),
        ("601#2F 98 60 00 E8 00 00 00", &["581#60 98 60 00 00 00 00 00"]),
        ("601#2B 40 60 00 1F 00 00 00", &["581#60 40 60 00 00 00 00 00"]),
    ]);
    // At 50 min⁻¹ a revolution takes 1.2 s: the zero pulse is within one.
    r.wait_sw(0x1400, 3000);
    r.run_ms(20);
    // "wait till Bit 12 Homing attained feeds to 1": 9627h.
    r.ex("601#40 41 60 00 00 00 00 00", &["581#4B 41 60 00 27 96 00 00"]);
    let p = r.i32(0x6064);
    assert!(p.abs() < i32::try_from(COUNTS_PER_REV).unwrap() / 50, "homed near 0: {p}");
    r.steps(&[
        ("601#2B 40 60 00 0F 00 00 00", &["581#60 40 60 00 00 00 00 00"]),
        // TYPO: printed `2F 40 60 00 01 ..` / `60 40 60 ..` (6040h); the
        // step is 6060h := 1 (profile position).
        ("601#2F 60 60 00 01 00 00 00", &["581#60 60 60 00 00 00 00 00"]),
        ("601#40 61 60 00 00 00 00 00", &["581#4F 61 60 00 01 00 00 00"]),
    ]);
}

/// EX14.11: PDO activation and positioning by PDO: RPDO1 controlword,
/// TPDO1 statusword (§14.11).
#[test]
fn ex14_11_positioning_by_pdo() {
    let mut r = Rig::new();
    r.enable();
    r.steps(&[
        // Writing the COB-ID the valid PDO already has.
        ("601#23 00 14 01 01 02 00 00", &["581#60 00 14 01 00 00 00 00"]),
        ("601#23 00 18 01 81 01 00 00", &["581#60 00 18 01 00 00 00 00"]),
        ("601#23 81 60 00 E8 03 00 00", &["581#60 81 60 00 00 00 00 00"]),
        ("601#23 7A 60 00 A0 86 01 00", &["581#60 7A 60 00 00 00 00 00"]),
    ]);
    // Step 5, NMT start: the manual prints no drive frame; entering
    // operational sends the valid event-driven TPDOs once (CiA 301), not
    // asserted here.
    r.send("000#01 01");
    r.take();
    r.send("201#5F 00");
    // Steps 7–9: 9627h "setpoint acknowledge", 9227h "target not
    // reached", 9627h "target reached".
    r.run_ms(5);
    r.wait_sw(0x1400, 10_000);
    r.run_ms(20);
    let got: Vec<Frame> = r.take().into_iter().filter(|f| f.std_id() == Some(0x181)).collect();
    assert_eq!(got, vec![fr("181#27 96"), fr("181#27 92"), fr("181#27 96")], "TPDO1 sequence");
    r.checked += 4;
    // TYPO: step 10 printed on COB-ID 180h; RPDO1 of node 1 is 201h. The
    // trace lists TPDO1 only; TPDO2 (valid by default, §7) follows it.
    r.ex("201#4F 00", &["181#27 06", "281#27 06 01"]);
    // TYPO: step 12 printed as an upload of 6061h (`40 61 60 00 60 79 FE FF`
    // → `4F 61 60 00 00 ..`); the step is 607Ah := −100 000.
    r.ex("601#23 7A 60 00 60 79 FE FF", &["581#60 7A 60 00 00 00 00 00"]);
    let p = r.i32(0x6064);
    assert!((p - 100_000).abs() <= 10, "+100 000 increments by PDO, at {p}");
}

/// EX14.12 + EX14.13: SYNC PDO set-up in pre-operational — the valid RPDO1
/// and TPDO1 are remapped without invalidating them (§7: writing sub 0
/// checks and activates), both synchronous; 1006h = 5000 µs (§14.13).
#[test]
fn ex14_12_13_sync_pdo_setup() {
    let mut r = Rig::new();
    r.steps(&[
        ("601#2F 00 16 00 00 00 00 00", &["581#60 00 16 00 00 00 00 00"]),
        // TYPO: reply printed `4F 00 16 01 06 ..` (an upload reply).
        ("601#23 00 16 01 10 00 40 60", &["581#60 00 16 01 00 00 00 00"]),
        ("601#23 00 16 02 20 01 C1 60", &["581#60 00 16 02 00 00 00 00"]),
        ("601#2F 00 16 00 02 00 00 00", &["581#60 00 16 00 00 00 00 00"]),
        ("601#2F 00 14 02 01 00 00 00", &["581#60 00 14 02 00 00 00 00"]),
        ("601#23 00 14 01 01 02 00 00", &["581#60 00 14 01 00 00 00 00"]),
        ("601#2F 00 1A 00 00 00 00 00", &["581#60 00 1A 00 00 00 00 00"]),
        // TYPO: reply printed `4F 00 1A 01 06 ..`.
        ("601#23 00 1A 01 10 00 41 60", &["581#60 00 1A 01 00 00 00 00"]),
        ("601#23 00 1A 02 20 00 63 60", &["581#60 00 1A 02 00 00 00 00"]),
        ("601#2F 00 1A 00 02 00 00 00", &["581#60 00 1A 00 00 00 00 00"]),
        ("601#2F 00 18 02 01 00 00 00", &["581#60 00 18 02 00 00 00 00"]),
        // TYPO: printed value 0x00001801; TPDO1 of node 1 is 181h.
        ("601#23 00 18 01 81 01 00 00", &["581#60 00 18 01 00 00 00 00"]),
        ("601#23 06 10 00 88 13 00 00", &["581#60 06 10 00 00 00 00 00"]),
    ]);
    let od = r.dn().node.od();
    assert_eq!(od.get_u32(0x1600, 1), Some(0x6040_0010));
    assert_eq!(od.get_u32(0x1600, 2), Some(0x60C1_0120));
    assert_eq!(od.get_u32(0x1A00, 2), Some(0x6063_0020));
    assert_eq!(od.get_u32(0x1400, 1), Some(0x201), "RPDO1 stayed valid");
    assert_eq!(od.get_u32(0x1800, 1), Some(0x181), "TPDO1 stayed valid");
    assert_eq!(od.get_u32(0x1006, 0), Some(5000));
    // §14.14 (frames lost): operational, SYNC → TPDO1 = statusword + 6063h.
    r.send("000#01 01");
    r.take();
    r.ex("080#", &["181#40 02 00 00 00 00"]);
}

/// §7: PDO definitions may change in pre-operational only; in operational
/// §5's `0800 0022h` ("due to the actual device state").
#[test]
fn pdo_definitions_only_in_preoperational() {
    let mut r = Rig::new();
    r.send("000#01 01");
    r.take();
    r.ex("601#2F 00 16 00 00 00 00 00", &["581#80 00 16 00 22 00 00 08"]);
    r.ex("601#23 00 14 01 01 02 00 80", &["581#80 00 14 01 22 00 00 08"]);
}

/// EX14.15: profile velocity, 1000 min⁻¹ (§14.15).
#[test]
fn ex14_15_profile_velocity() {
    let mut r = Rig::new();
    r.enable();
    r.steps(&[
        ("601#23 FF 60 00 00 00 00 00", &["581#60 FF 60 00 00 00 00 00"]),
        // TYPO: printed index 6006h (`2F 06 60 ..` / `60 06 60 ..`); 6060h := 3.
        ("601#2F 60 60 00 03 00 00 00", &["581#60 60 60 00 00 00 00 00"]),
        ("601#23 FF 60 00 E8 03 00 00", &["581#60 FF 60 00 00 00 00 00"]),
    ]);
    r.run_ms(1500);
    // 1000 min⁻¹ = 68 267 increments/s.
    let v = r.rate();
    assert!((v - 68_267.0).abs() < 700.0, "§14.15: 1000 min⁻¹, at {v} inc/s");
    assert_eq!(r.dn().node.od().get_i64(0x6061, 0), Some(3));
}

/// EX-STORE (§11): save / load signatures on 1010h:1 / 1011h:1 (frames
/// derived from the printed payloads). TYPO: "load" printed as
/// 73 61 61 64; 6C 6F 61 64 is the signature.
#[test]
fn ex_store_signatures() {
    let mut r = Rig::new();
    r.steps(&[
        ("601#40 10 10 01 00 00 00 00", &["581#43 10 10 01 01 00 00 00"]),
        ("601#23 10 10 01 73 61 76 65", &["581#60 10 10 01 00 00 00 00"]),
        ("601#23 11 10 01 6C 6F 61 64", &["581#60 11 10 01 00 00 00 00"]),
    ]);
}

/// EX-NMT (§6) and EX-GUARD (§8): NMT commands seen through node guarding
/// (toggle starts at 0); 100Ch/100Dh accepted but not evaluated, always 0.
#[test]
fn ex_nmt_guarding_and_life_guarding_ignored() {
    let mut r = Rig::new();
    r.steps(&[
        ("601#2B 0C 10 00 64 00 00 00", &["581#60 0C 10 00 00 00 00 00"]),
        ("601#2F 0D 10 00 03 00 00 00", &["581#60 0D 10 00 00 00 00 00"]),
        ("601#40 0C 10 00 00 00 00 00", &["581#4B 0C 10 00 00 00 00 00"]),
        ("601#40 0D 10 00 00 00 00 00", &["581#4F 0D 10 00 00 00 00 00"]),
    ]);
    for (cmd, guard) in [
        (None, "701#7F"),
        (Some("000#01 01"), "701#85"),
        (Some("000#02 01"), "701#04"),
        (Some("000#80 01"), "701#FF"),
        (Some("000#01 00"), "701#05"),
    ] {
        if let Some(c) = cmd {
            r.send(c);
        }
        r.take();
        r.ex("701#R1", &[guard]);
    }
    // No life guarding: a second of silence from the master changes nothing.
    r.run_ms(1000);
    assert!(r.take().iter().all(|f| f.std_id() != Some(0x81)), "no guarding EMCY");
}

/// §9 Table 1: a following error goes out as 8611h with register 21h and
/// five 00h bytes.
#[test]
fn emcy_register_from_table_1() {
    let mut r = Rig::new();
    r.enable();
    r.take();
    r.bus
        .node_mut::<PersonalityDevice>(r.dut)
        .unwrap()
        .app
        .inject(drivebus_cia402::drive::Injection::Fault(0x8611));
    r.run_ms(5);
    let emcy: Vec<Frame> = r.take().into_iter().filter(|f| f.std_id() == Some(0x81)).collect();
    assert_eq!(emcy.first(), Some(&fr("081#11 86 21 00 00 00 00 00")));
}

/// EX14.14 (frames lost, text kept): after EX14.12/13, "Running-up of the
/// State Machine see Chapter 6.1 step 1 – 4 … Interpolated Position Mode +
/// Operational", then SYNC and RPDO1 (controlword + 60C1h:1) every 5 ms
/// (1006h = 5000 µs), TPDO1 (statusword + 6063h) on each SYNC. Derived
/// frames: a ramp of 100 set-points to one revolution.
#[test]
fn ex14_14_interpolated_position_derived() {
    let mut r = Rig::new();
    r.steps(&[
        ("601#2F 00 16 00 00 00 00 00", &["581#60 00 16 00 00 00 00 00"]),
        ("601#23 00 16 01 10 00 40 60", &["581#60 00 16 01 00 00 00 00"]),
        ("601#23 00 16 02 20 01 C1 60", &["581#60 00 16 02 00 00 00 00"]),
        ("601#2F 00 16 00 02 00 00 00", &["581#60 00 16 00 00 00 00 00"]),
        ("601#2F 00 14 02 01 00 00 00", &["581#60 00 14 02 00 00 00 00"]),
        ("601#2F 00 1A 00 00 00 00 00", &["581#60 00 1A 00 00 00 00 00"]),
        ("601#23 00 1A 01 10 00 41 60", &["581#60 00 1A 01 00 00 00 00"]),
        ("601#23 00 1A 02 20 00 63 60", &["581#60 00 1A 02 00 00 00 00"]),
        ("601#2F 00 1A 00 02 00 00 00", &["581#60 00 1A 00 00 00 00 00"]),
        ("601#2F 00 18 02 01 00 00 00", &["581#60 00 18 02 00 00 00 00"]),
        ("601#23 06 10 00 88 13 00 00", &["581#60 06 10 00 00 00 00 00"]),
    ]);
    assert_eq!(r.dn().node.od().get_u32(0x60C2, 1), Some(5), "1006h → 60C2h 5 × 10⁻³ s");
    r.enable();
    r.ex("601#2F 60 60 00 07 00 00 00", &["581#60 60 60 00 00 00 00 00"]);
    r.send("000#01 01");
    r.take();
    let cpr = i64::from(COUNTS_PER_REV);
    for k in 0..=140i64 {
        let sp = (cpr * k.min(100) / 100) as i32;
        let b = sp.to_le_bytes();
        r.bus.send_from(r.probe, fr("080#"));
        r.bus.send_from(r.probe, Frame::new(0x201, &[0x1F, 0x00, b[0], b[1], b[2], b[3]]));
        r.run_ms(5);
    }
    let tpdo: Vec<Frame> = r.take().into_iter().filter(|f| f.std_id() == Some(0x181)).collect();
    assert!(tpdo.len() >= 140, "TPDO1 on every SYNC: {}", tpdo.len());
    let last = tpdo.last().unwrap().data();
    assert_eq!(u16::from_le_bytes([last[0], last[1]]) & 0x106F, 0x1027, "ip active, enabled");
    let p = i32::from_le_bytes([last[2], last[3], last[4], last[5]]);
    assert!((i64::from(p) - cpr).abs() <= 20, "one revolution by ip, at {p}");
}
