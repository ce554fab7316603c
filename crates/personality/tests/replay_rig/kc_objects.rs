//! The bodies of the Kollmorgen manufacturer-object tests (`kc1_objects.rs`,
//! `akd_objects.rs`): the KC1 and the AKD document the same objects (KC1
//! §7.2.2, AKD §6.2.2); each function takes the profile and says in its
//! callers which section it proves.

use super::Rig;
use drivebus_can::Frame;
use drivebus_personality::Profile;

/// Node-ID of the drive under test.
pub const ID: u8 = 3;

/// `profile` as node 3, NMT operational.
pub fn operational(profile: Profile) -> Rig {
    let (mut r, _) = Rig::new(profile, ID);
    r.send("000#0103");
    r.run_ms(5);
    r.take();
    r
}

/// Write `data` to `index:sub`; panic with the abort code if refused.
pub fn put(r: &mut Rig, index: u16, sub: u8, data: &[u8]) {
    if let Err(a) = r.download(ID, index, sub, data) {
        panic!("write {index:04X}h:{sub}: abort {a:08X}");
    }
}

/// The abort code of a write that must be refused.
pub fn refused(r: &mut Rig, index: u16, sub: u8, data: &[u8]) -> u32 {
    match r.download(ID, index, sub, data) {
        Ok(()) => panic!("write {index:04X}h:{sub} := {data:02X?} was taken"),
        Err(a) => a,
    }
}

/// An upload as a signed number of its length.
pub fn get(r: &mut Rig, index: u16, sub: u8) -> i64 {
    let v = r.upload(ID, index, sub).unwrap_or_else(|a| panic!("read {index:04X}h:{sub}: abort {a:08X}"));
    match v.len() {
        1 => i64::from(v[0] as i8),
        2 => i64::from(i16::from_le_bytes([v[0], v[1]])),
        4 => i64::from(i32::from_le_bytes([v[0], v[1], v[2], v[3]])),
        _ => panic!("read {index:04X}h:{sub}: {} bytes", v.len()),
    }
}

/// An unsigned upload.
pub fn getu(r: &mut Rig, index: u16, sub: u8) -> u64 {
    let v = r.upload(ID, index, sub).unwrap_or_else(|a| panic!("read {index:04X}h:{sub}: abort {a:08X}"));
    let mut b = [0u8; 8];
    b[..v.len().min(8)].copy_from_slice(&v[..v.len().min(8)]);
    u64::from_le_bytes(b)
}

/// Mode `mode`, then shutdown, switch on, enable operation.
pub fn enable(r: &mut Rig, mode: i8) {
    put(r, 0x6060, 0, &[mode as u8]);
    for cw in [0x06u16, 0x07, 0x0F] {
        put(r, 0x6040, 0, &cw.to_le_bytes());
        r.run_ms(2);
    }
    assert_eq!(r.statusword() & 0x6F, 0x27, "operation enabled: {:04X}", r.statusword());
}

/// The EMCY frames (80h + node-ID) among `frames`.
pub fn emcys(frames: &[Frame]) -> Vec<Frame> {
    frames.iter().copied().filter(|f| f.std_id() == Some(0x80 + u16::from(ID))).collect()
}

/// An EMCY frame in the Kollmorgen form (KC1 §6.4.4.2, AKD §5.4.4.2):
/// code, error register, category 01h, bytes 4–7 zero.
pub fn emcy(code: u16, register: u8) -> Frame {
    let [lo, hi] = code.to_le_bytes();
    Frame::new(0x80 + u16::from(ID), &[lo, hi, register, 0x01, 0, 0, 0, 0])
}

/// Let `ms` pass; the EMCY frames sent meanwhile.
pub fn emcys_after(r: &mut Rig, ms: u64) -> Vec<Frame> {
    r.take();
    r.run_ms(ms);
    emcys(&r.take())
}

/// Sends one SYNC every `period_us` for `ms` milliseconds.
pub fn syncs(r: &mut Rig, period_us: u64, ms: u64) -> Vec<Frame> {
    let mut out = Vec::new();
    let n = ms * 1000 / period_us;
    for _ in 0..n {
        r.send("080#");
        r.run_for(drivebus_can::Duration::from_micros(period_us - 1));
        out.extend(r.take());
    }
    out
}

/// Sends `cmd` (with CR LF) 4 characters per write to 2026h:1 and reads
/// 2026h:2 until the reply's end (NUL): the reply text (KC1 §7.2.2.6, AKD
/// §6.2.2.9).
pub fn ascii(r: &mut Rig, cmd: &str) -> String {
    let line = format!("{cmd}\r\n");
    for chunk in line.as_bytes().chunks(4) {
        put(r, 0x2026, 1, chunk);
    }
    let mut out = String::new();
    for _ in 0..64 {
        let v = r.upload(ID, 0x2026, 2).expect("2026h:2");
        let end = v.iter().position(|&b| b == 0);
        out.extend(v[..end.unwrap_or(v.len())].iter().map(|&b| char::from(b)));
        if end.is_some() {
            break;
        }
    }
    out
}

/// 1002h bit 14 "power stage enabled" and 2002h:2 (its second byte) while
/// enabled; in fault bit 15 "error state", 2001h:1 the fault number
/// (F439 following error, F129 heartbeat loss), 1002h mapped in a TPDO
/// carries the same bits (KC1 §7.2.1.3, §7.2.2.2, §7.2.2.3; AKD §6.2.1.3,
/// §6.2.2.2, §6.2.2.3).
pub fn status_register(profile: Profile) {
    let mut r = operational(profile);
    assert_eq!(getu(&mut r, 0x1002, 0) & (1 << 14), 0, "disabled: no power stage");
    enable(&mut r, 3);
    let s = getu(&mut r, 0x1002, 0);
    assert_ne!(s & (1 << 14), 0, "1002h {s:08X}: power stage enabled");
    assert_eq!(s & (1 << 15), 0, "1002h {s:08X}: no error state");
    for (sub, byte) in (1..=4u8).zip(s.to_le_bytes()) {
        assert_eq!(getu(&mut r, 0x2002, sub), u64::from(byte), "2002h:{sub} = byte {sub} of 1002h");
    }
    // TPDO4 event-driven with 1002h: the bits go out as they change.
    put(&mut r, 0x1803, 1, &0x8000_0483u32.to_le_bytes());
    put(&mut r, 0x1A03, 0, &[0]);
    put(&mut r, 0x1A03, 1, &0x1002_0020u32.to_le_bytes());
    put(&mut r, 0x1A03, 0, &[1]);
    put(&mut r, 0x1803, 1, &0x0000_0483u32.to_le_bytes());
    r.take();
    r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Fault(0x8611));
    r.run_ms(50);
    let frames = r.take();
    let s = getu(&mut r, 0x1002, 0);
    assert_ne!(s & (1 << 15), 0, "1002h {s:08X}: error state");
    assert_eq!(getu(&mut r, 0x2001, 1), 439, "2001h:1 = F439");
    let tpdo = frames.iter().rev().find(|f| f.std_id() == Some(0x483)).expect("TPDO4 with 1002h");
    assert_eq!(u64::from(u32::from_le_bytes(tpdo.data()[..4].try_into().unwrap())), s, "TPDO4 = 1002h");
    // Fault reset, then a heartbeat loss while enabled: F129.
    put(&mut r, 0x6040, 0, &0x80u16.to_le_bytes());
    r.run_ms(2);
    assert_eq!(getu(&mut r, 0x2001, 1), 0, "no fault after the reset");
    enable(&mut r, 3);
    put(&mut r, 0x1016, 1, &0x0001_0064u32.to_le_bytes());
    r.send("701#05");
    r.run_ms(300);
    assert_eq!(getu(&mut r, 0x2001, 1), 129, "2001h:1 = F129");
    assert_ne!(getu(&mut r, 0x1002, 0) & (1 << 15), 0, "error state");
}

/// PL.ERRWTHRESH (3483h) exceeded: warning n439 sends EMCY FF12h, sets
/// statusword bit 7, 1002h bit 8 and 2000h:1 = 439, without a state change;
/// gone, the reset EMCY 0000h follows (KC1 §6.4.4, §7.1, §7.2.2.1; AKD
/// §5.4.4, §6.1, §6.2.2.1).
pub fn warning_n439(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x3483, 0, &1i32.to_le_bytes());
    put(&mut r, 0x6083, 0, &3_600_000u32.to_le_bytes());
    put(&mut r, 0x6084, 0, &3_600_000u32.to_le_bytes());
    put(&mut r, 0x6081, 0, &360_000u32.to_le_bytes());
    enable(&mut r, 1);
    r.take();
    put(&mut r, 0x607A, 0, &360_000i32.to_le_bytes());
    put(&mut r, 0x6040, 0, &0x1Fu16.to_le_bytes());
    r.run_ms(20);
    let e = emcys(&r.take());
    assert_eq!(e.first(), Some(&emcy(0xFF12, 0x80)), "n439 EMCY: {e:?}");
    let sw = r.statusword();
    assert_eq!(sw & 0x6F, 0x27, "still operation enabled");
    assert_ne!(sw & 0x80, 0, "statusword bit 7: {sw:04X}");
    assert_eq!(getu(&mut r, 0x2000, 1), 439, "2000h:1");
    assert_ne!(getu(&mut r, 0x1002, 0) & (1 << 8), 0, "1002h bit 8");
    // At standstill the error is gone: the warning clears.
    r.run_ms(2000);
    let e: Vec<Frame> = emcys(&r.take());
    assert_eq!(getu(&mut r, 0x2000, 1), 0, "2000h:1 after the move");
    assert_eq!(r.statusword() & 0x80, 0, "bit 7 after the move");
    assert_eq!(e.last().map(|f| f.data()[..2].to_vec()), Some(vec![0, 0]), "reset EMCY: {e:?}");
}

/// 607Dh written takes effect only after it is saved and the drive
/// restarted (KC1 §7.11.2.2, AKD §6.11.2.2): before, pv runs through the
/// new limit; after 1010h and NMT reset node the limit acts, as
/// `beyond` (EMCY frame the profile sends when pv passes +1 revolution).
pub fn software_limit_after_restart(profile: Profile, beyond: Frame) {
    let mut r = operational(profile);
    put(&mut r, 0x607D, 1, &(-36_000i32).to_le_bytes());
    put(&mut r, 0x607D, 2, &36_000i32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &72_000i32.to_le_bytes());
    let e = emcys_after(&mut r, 1000);
    assert!(r.position() > 40_000, "ran past the new limit: {}", r.position());
    assert!(e.is_empty(), "no limit before the restart: {e:?}");
    put(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    put(&mut r, 0x6040, 0, &0u16.to_le_bytes());
    put(&mut r, 0x1010, 1, b"save");
    r.send("000#8103");
    r.run_ms(10);
    r.send("000#0103");
    r.run_ms(5);
    // A warning shows at once (the axis stands beyond the limit), a fault
    // when the axis moves on outwards.
    let mut e = emcys(&r.take());
    assert_eq!(get(&mut r, 0x607D, 2), 36_000, "saved");
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &72_000i32.to_le_bytes());
    e.extend(emcys_after(&mut r, 1500));
    assert!(e.contains(&beyond), "limit EMCY {beyond:?} after the restart: {e:?}");
}

/// 2071h (mA) is the torque controller's input as 6071h in tq; 2077h reads
/// the present current in mA, 6077h × rated current / 1000 (KC1
/// §7.7.2.1–2, AKD §6.7.2.1–2).
pub fn target_current(profile: Profile) {
    let mut r = operational(profile);
    enable(&mut r, 4);
    put(&mut r, 0x2071, 0, &500i32.to_le_bytes());
    r.run_ms(50);
    assert!(r.velocity() > 0, "2071h accelerates the motor");
    // The motor's rated current in mA (6075h is not in the object table).
    let rated = (r.pn().app.drive.config().params.motor.rated_current * 1000.0).round() as i64;
    let t = get(&mut r, 0x6077, 0);
    let i = get(&mut r, 0x2077, 0);
    assert!(t > 0, "6077h {t}");
    assert_eq!(i, t * rated / 1000, "2077h = 6077h × rated current / 1000");
    assert_eq!(get(&mut r, 0x6071, 0), 500 * 1000 / rated, "6071h shows the set-point in ‰");
}

/// 60C2h (KC1 §7.9.2.3, AKD §6.9.2.3): "only multiples of 1 ms"; the
/// second of the two writes that makes 0.5 ms is refused (0609 0030).
pub fn ip_period_whole_ms(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x60C2, 1, &[5]);
    assert_eq!(refused(&mut r, 0x60C2, 2, &[(-4i8) as u8]), 0x0609_0030, "5 × 10⁻⁴ s");
    put(&mut r, 0x60C2, 2, &[(-3i8) as u8]);
    put(&mut r, 0x60C2, 1, &[2]);
    assert_eq!(getu(&mut r, 0x60C2, 1), 2);
    assert_eq!(get(&mut r, 0x60C2, 2), -3);
    put(&mut r, 0x60C2, 1, &[20]);
    put(&mut r, 0x60C2, 2, &[(-4i8) as u8]);
    // The pair in the other order.
    put(&mut r, 0x60C2, 2, &[(-4i8) as u8]);
    assert_eq!(refused(&mut r, 0x60C2, 1, &[5]), 0x0609_0030, "5 × 10⁻⁴ s again");
}

/// FBUS.PARAM02 = 1 (36E6h): the PLL locks onto SYNCs at the 60C2h period
/// (3496h:2 inside 3496h:1 ± 3496h:3); SYNCs at another period leave it
/// unlocked: warning n125, EMCY 8781h (KC1 §5.4, §7.2.2.18; AKD §3.4,
/// §6.2.2.22).
pub fn pll_lock(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x36E6, 0, &1u32.to_le_bytes());
    put(&mut r, 0x60C2, 1, &[1]);
    put(&mut r, 0x60C2, 2, &[(-3i8) as u8]);
    enable(&mut r, 7);
    r.take();
    let frames = syncs(&mut r, 1000, 300);
    assert!(emcys(&frames).is_empty(), "locked at 1 ms: {:?}", emcys(&frames));
    let dist = getu(&mut r, 0x3496, 1) as i64;
    let wnd = getu(&mut r, 0x3496, 3) as i64;
    let act = getu(&mut r, 0x3496, 2) as i64;
    assert!((act - dist).abs() < wnd, "3496h:2 {act} within {dist} ± {wnd}");
    let frames = syncs(&mut r, 1500, 300);
    assert_eq!(emcys(&frames).first(), Some(&emcy(0x8781, 0x80)), "n125");
    assert_ne!(r.statusword() & 0x80, 0, "bit 7");
    assert_eq!(getu(&mut r, 0x2000, 1), 125);
}

/// The guarding/heartbeat loss EMCY 8130h (F129) in the form of the other
/// drive faults: register without the generic bit (10h, communication),
/// category 01h (KC1 §6.4.4.2, §7.1; AKD §5.4.4.2, §6.1).
pub fn heartbeat_emcy_form(profile: Profile) {
    let mut r = operational(profile);
    enable(&mut r, 3);
    put(&mut r, 0x1016, 1, &0x0001_0064u32.to_le_bytes());
    r.send("701#05");
    let e = emcys_after(&mut r, 300);
    assert_eq!(e, vec![emcy(0x8130, 0x10)], "heartbeat loss");
}

/// The Telnet commands of the ASCII channel (KC1 §7.2.2.6, AKD §6.2.2.9):
/// a parameter by its name reads and writes the object the appendix gives
/// it (MOTOR.TBRAKEAPP = 366Eh), DRV.WARNINGS lists the warnings, an
/// unknown name is an error.
pub fn ascii_parameters(profile: Profile) {
    let mut r = operational(profile);
    assert_eq!(ascii(&mut r, "MOTOR.TBRAKEAPP 75"), ">\n\r\n");
    assert_eq!(get(&mut r, 0x366E, 0), 75, "366Eh written through Telnet");
    put(&mut r, 0x366E, 0, &80i32.to_le_bytes());
    assert_eq!(ascii(&mut r, "MOTOR.TBRAKEAPP"), ">80\n\r\n");
    assert_eq!(ascii(&mut r, "DRV.WARNINGS"), ">No warnings active\n\r\n");
    assert_eq!(ascii(&mut r, "NO.SUCH"), ">Error: unknown command\n\r\n");
}

/// 1026h OS prompt (KC1 §7.2.1.18, AKD §6.2.1.19): one character per
/// write to sub 1, the reply one character per read of sub 2.
pub fn os_prompt(profile: Profile) {
    let mut r = operational(profile);
    for b in "DRV.FAULTS\r\n".bytes() {
        put(&mut r, 0x1026, 1, &[b]);
    }
    let mut out = String::new();
    for _ in 0..40 {
        let c = getu(&mut r, 0x1026, 2) as u8;
        if c == 0 {
            break;
        }
        out.push(char::from(c));
    }
    assert_eq!(out, ">No faults active\n\r\n");
}

/// A motion task set and started through Telnet (MT.NUM, MT.P, MT.V,
/// MT.SET, MT.MOVE; KC1 §5.1.2, AKD §4.1) runs in pp to its position.
pub fn motion_task(profile: Profile) {
    let mut r = operational(profile);
    enable(&mut r, 1);
    for c in ["MT.NUM 1", "MT.P 18000", "MT.V 36000", "MT.CNTL 0", "MT.SET"] {
        assert_eq!(ascii(&mut r, c), ">\n\r\n", "{c}");
    }
    assert_eq!(ascii(&mut r, "MT.MOVE 1"), ">\n\r\n");
    r.run_ms(2000);
    assert!((r.position() - 18_000).abs() < 100, "at the task's position: {}", r.position());
    assert_ne!(r.statusword() & 0x400, 0, "target reached");
}

/// The measurement mirrors of the object table (KC1 §8.1.3, AKD §7.1.4)
/// read the model: VL.FB 3618h = 606Ch, PL.ERR 35C5h = 60F4h, IL.FB 3558h
/// = 2077h, VBUS.VALUE 361Ah the DC bus, MOTOR.TEMP 3612h the winding,
/// FB1.MECHPOS 35D2h the position within one turn.
pub fn measurement_mirrors(profile: Profile) {
    let mut r = operational(profile);
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &36_000i32.to_le_bytes());
    r.run_ms(800);
    let (v, vl) = (get(&mut r, 0x606C, 0), get(&mut r, 0x3618, 0));
    assert!(v > 30_000 && (v - vl).abs() <= 50, "VL.FB {vl} vs 606Ch {v}");
    let (fe, pl) = (get(&mut r, 0x60F4, 0), get(&mut r, 0x35C5, 0));
    assert!((fe - pl).abs() <= 50, "PL.ERR {pl} vs 60F4h {fe}");
    let (i, il) = (get(&mut r, 0x2077, 0), get(&mut r, 0x3558, 0));
    assert!((i - il).abs() <= 50, "IL.FB {il} vs 2077h {i}");
    let m = r.pn().app.drive.model();
    let (bus, temp) = (m.bus_voltage().round() as i64, m.temperature().round() as i64);
    assert!(bus > 0);
    assert_eq!(get(&mut r, 0x361A, 0), bus, "VBUS.VALUE");
    assert_eq!(get(&mut r, 0x3612, 0), temp, "MOTOR.TEMP");
    let per_rev = u64::from(r.pn().app.drive.config().params.encoder.counts_per_rev);
    let inc = r.pn().app.drive.position_increments().rem_euclid(per_rev as i64) as u64;
    let mech = getu(&mut r, 0x35D2, 0);
    assert!(mech < per_rev, "FB1.MECHPOS {mech} within a turn");
    assert!(mech.abs_diff(inc) < per_rev / 10, "FB1.MECHPOS {mech} near {inc}");
}

/// VL.THRESH (3627h): above it the drive faults F302 (EMCY 8480h).
pub fn overspeed(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x3627, 0, &18_000i32.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &36_000i32.to_le_bytes());
    let e = emcys_after(&mut r, 1000);
    assert_eq!(e.first(), Some(&emcy(0x8480, 0x80)), "F302: {e:?}");
    assert_eq!(getu(&mut r, 0x2001, 1), 302);
}

/// MOTOR.TEMPWARN (3453h) below the winding temperature: warning n301
/// (EMCY 7186h); MOTOR.TEMPFAULT (3586h): fault F301 (EMCY 7180h).
pub fn motor_temperature(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x3453, 0, &1u32.to_le_bytes());
    let e = emcys_after(&mut r, 5);
    assert_eq!(e, vec![emcy(0x7186, 0x80)], "n301");
    assert_eq!(getu(&mut r, 0x2000, 1), 301);
    put(&mut r, 0x3586, 0, &1u32.to_le_bytes());
    let e = emcys_after(&mut r, 5);
    assert_eq!(e, vec![emcy(0x7180, 0x80)], "F301");
    assert_eq!(getu(&mut r, 0x2001, 1), 301);
}

/// PL.ERRFTHRESH (35C7h) is the following error window 6065h.
pub fn following_error_threshold(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x35C7, 0, &1i32.to_le_bytes());
    assert_eq!(getu(&mut r, 0x6065, 0), 1);
    put(&mut r, 0x6065, 0, &2u32.to_le_bytes());
    assert_eq!(get(&mut r, 0x35C7, 0), 2, "reads 6065h");
    put(&mut r, 0x6083, 0, &3_600_000u32.to_le_bytes());
    put(&mut r, 0x6081, 0, &360_000u32.to_le_bytes());
    enable(&mut r, 1);
    put(&mut r, 0x607A, 0, &360_000i32.to_le_bytes());
    put(&mut r, 0x6040, 0, &0x1Fu16.to_le_bytes());
    r.run_ms(200);
    assert_eq!(getu(&mut r, 0x2001, 1), 439, "F439");
}

/// FBUS.PLLTHRESH (50B1h): the PLL locks only after that many cycles in
/// the window; one that never locked reports no loss.
pub fn pll_threshold(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x36E6, 0, &1u32.to_le_bytes());
    put(&mut r, 0x50B1, 0, &100_000u32.to_le_bytes());
    put(&mut r, 0x60C2, 1, &[1]);
    put(&mut r, 0x60C2, 2, &[(-3i8) as u8]);
    enable(&mut r, 7);
    syncs(&mut r, 1000, 300);
    let frames = syncs(&mut r, 1500, 300);
    assert!(emcys(&frames).is_empty(), "never locked: {:?}", emcys(&frames));
}

/// FBUS.PARAM05 bit 0 (KC1 §5.4, AKD §3.4): faults reset by the
/// controlword only; clear, DRV.CLRFAULTS resets them too.
pub fn clear_faults_by_telnet(profile: Profile) {
    let mut r = operational(profile);
    r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Fault(0x4310));
    r.run_ms(5);
    put(&mut r, 0x36E9, 0, &1u32.to_le_bytes());
    assert!(ascii(&mut r, "DRV.CLRFAULTS").starts_with(">Error"), "bit 0 set");
    assert_eq!(r.statusword() & 0x4F, 0x08, "still fault");
    put(&mut r, 0x36E9, 0, &0u32.to_le_bytes());
    assert_eq!(ascii(&mut r, "DRV.CLRFAULTS"), ">\n\r\n");
    r.run_ms(2);
    assert_eq!(r.statusword() & 0x4F, 0x40, "switch on disabled: {:04X}", r.statusword());
}

/// MT.SET as an object (3431h): the pp set-point stored as task n; the
/// task runs with MT.MOVE. 2071h beyond MOTOR.IPEAK (358Fh) is refused.
pub fn motion_task_object_and_peak_current(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x607A, 0, &9_000i32.to_le_bytes());
    put(&mut r, 0x6081, 0, &36_000u32.to_le_bytes());
    put(&mut r, 0x3431, 0, &2u16.to_le_bytes());
    put(&mut r, 0x607A, 0, &0i32.to_le_bytes());
    enable(&mut r, 1);
    assert_eq!(ascii(&mut r, "MT.MOVE 2"), ">\n\r\n");
    r.run_ms(1500);
    assert!((r.position() - 9_000).abs() < 100, "task 2: {}", r.position());
    put(&mut r, 0x358F, 0, &1000u32.to_le_bytes());
    assert_eq!(refused(&mut r, 0x2071, 0, &1500i32.to_le_bytes()), 0x0609_0031);
    put(&mut r, 0x2071, 0, &(-900i32).to_le_bytes());
}

/// The model's velocity \[rad/s\] (motor side), for effects the user units hide.
fn motor_velocity(r: &Rig) -> f64 {
    r.pn().app.drive.model().velocity()
}

/// DRV.DIR 352Ah inverts the direction (the motor turns the other way,
/// 606Ch keeps the sign of the set-point); MOTOR.VMAX 35A3h (rpm) limits
/// the speed; MT.TPOSWND 35C6h is the drive's position window, MT.TVELWND
/// 3856h the velocity window 606Dh.
pub fn drive_parameters(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x352A, 0, &1u32.to_le_bytes());
    put(&mut r, 0x35A3, 0, &30u32.to_le_bytes());
    put(&mut r, 0x35C6, 0, &1234i32.to_le_bytes());
    put(&mut r, 0x3856, 0, &321i32.to_le_bytes());
    assert_eq!(getu(&mut r, 0x606D, 0), 321, "MT.TVELWND = 606Dh");
    assert_eq!(r.pn().app.drive.mode_params().position_window, 1234, "MT.TPOSWND = 6067h");
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &36_000i32.to_le_bytes());
    r.run_ms(1000);
    let v = get(&mut r, 0x606C, 0);
    assert!((v - 18_000).abs() < 500, "30 rpm = 18000 units/s: {v}");
    assert!(motor_velocity(&r) < -1.0, "DRV.DIR: the motor turns negative: {}", motor_velocity(&r));
}

/// 204Ch (KC1 §7.5.2.1, AKD §6.5.2.1) with FBUS.PARAM05 bit 4: the velocity
/// set-point is scaled by numerator/denominator (2/1: twice the speed), a
/// negative factor reverses it; 0 is refused.
pub fn pv_scaling(profile: Profile) {
    let mut r = operational(profile);
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &18_000i32.to_le_bytes());
    r.run_ms(800);
    let plain = motor_velocity(&r);
    assert_eq!(refused(&mut r, 0x204C, 1, &0i32.to_le_bytes()), 0x0609_0030);
    put(&mut r, 0x204C, 1, &2i32.to_le_bytes());
    r.run_ms(800);
    assert!((motor_velocity(&r) - plain).abs() < plain * 0.05, "bit 4 clear: 204Ch inactive");
    put(&mut r, 0x36E9, 0, &0x10u32.to_le_bytes());
    r.run_ms(800);
    let scaled = motor_velocity(&r);
    // The set-point × numerator / denominator drives the motor.
    assert!((scaled / plain - 2.0).abs() < 0.05, "scaled {scaled} vs {plain}");
    put(&mut r, 0x204C, 1, &(-1i32).to_le_bytes());
    r.run_ms(1500);
    assert!(motor_velocity(&r) < -plain * 0.9, "negative factor reverses: {}", motor_velocity(&r));
}

/// MOTOR.ICONT 358Eh (mA) is the rated current 6071h/6077h count in: twice
/// the rating, twice the torque for the same per mille; 2077h follows.
pub fn rated_current(profile: Profile) {
    let accel = |icont: Option<u32>| {
        let mut r = operational(profile);
        if let Some(i) = icont {
            put(&mut r, 0x358E, 0, &i.to_le_bytes());
        }
        enable(&mut r, 4);
        put(&mut r, 0x6071, 0, &100i16.to_le_bytes());
        r.run_ms(20);
        let (t, i) = (get(&mut r, 0x6077, 0), get(&mut r, 0x2077, 0));
        (r.pn().app.drive.model().torque(), t, i)
    };
    let rated =
        (operational(profile).pn().app.drive.config().params.motor.rated_current * 1000.0).round() as u32;
    let (v1, _, _) = accel(None);
    let (v2, t2, i2) = accel(Some(2 * rated));
    assert!((v2 / v1 - 2.0).abs() < 0.05, "twice the torque (N·m): {v2} vs {v1}");
    assert_eq!(i2, t2 * i64::from(2 * rated) / 1000, "2077h in MOTOR.ICONT");
}

/// VBUS.UVFTHRESH 361Dh (mV): a DC bus below it with the power stage on
/// is F502 (EMCY 3220h).
pub fn under_voltage(profile: Profile) {
    let mut r = operational(profile);
    let bus = get(&mut r, 0x361A, 0);
    put(&mut r, 0x361D, 0, &(((bus + 10) * 1000) as u32).to_le_bytes());
    assert!(emcys_after(&mut r, 5).is_empty(), "disabled: no fault");
    enable_quietly(&mut r, 3);
    let e = emcys_after(&mut r, 5);
    assert_eq!(e.first(), Some(&emcy(0x3220, 0x04)), "F502: {e:?}");
    assert_eq!(getu(&mut r, 0x2001, 1), 502);
}

/// [`enable`] without asserting the state (a fault may follow at once).
fn enable_quietly(r: &mut Rig, mode: i8) {
    put(r, 0x6060, 0, &[mode as u8]);
    for cw in [0x06u16, 0x07, 0x0F] {
        put(r, 0x6040, 0, &cw.to_le_bytes());
    }
}

/// The latch objects (KC1 §7.2.2.7–13, AKD §6.2.2.10–17) on a machine with
/// a home switch: 20A4h = 3 latches both edges of the input, 20A5h shows
/// them valid, 20A0h/20A1h the positions (as 60BAh/60BBh), 20A6h the last
/// edge; acknowledging latch 1 (20A5h := 0100h) re-arms it.
pub fn latches(profile: Profile) {
    let pn = drivebus_personality::build::build_on_machine(
        profile,
        ID,
        Box::new(drivebus_node::MemoryStorage::new()),
        |c| c.params.axis.home_switch = Some((0.25, 0.5)),
    )
    .unwrap();
    let (mut r, _) = Rig::with(pn);
    r.send("000#0103");
    r.run_ms(5);
    put(&mut r, 0x20A4, 0, &0x0003u16.to_le_bytes());
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &18_000i32.to_le_bytes());
    r.run_ms(3000);
    let st = getu(&mut r, 0x20A5, 0);
    assert_eq!(st & 0x1F, 0x03, "latch 1 rising and falling valid: {st:04X}");
    let (rise, fall) = (get(&mut r, 0x20A0, 0), get(&mut r, 0x20A1, 0));
    assert!(0 < rise && rise < fall, "edges at {rise}, {fall}");
    assert_eq!((rise, fall), (get(&mut r, 0x60BA, 0), get(&mut r, 0x60BB, 0)), "the touch probe's");
    assert_eq!(get(&mut r, 0x20A6, 0), fall, "20A6h: the last edge");
    put(&mut r, 0x20A5, 0, &0x0100u16.to_le_bytes());
    assert_eq!(getu(&mut r, 0x20A5, 0) & 0x03, 0, "re-armed");
}

/// DRV.ACC 3501h / DRV.DEC 3522h are the ramps pv runs with while
/// 6083h/6084h are 0 (KC1 §7.11.2.4/5, AKD §6.11.2.4/5: "DRV.ACC in the
/// profile velocity mode"); they read the drive's own ramps at power-on.
/// HOME.ACC 3502h is the homing acceleration while 609Ah is 0.
pub fn drive_ramps(profile: Profile) {
    let mut r = operational(profile);
    assert!(get(&mut r, 0x3501, 0) > 0, "DRV.ACC shows the drive's ramp");
    put(&mut r, 0x3501, 0, &3_600i32.to_le_bytes());
    put(&mut r, 0x3522, 0, &7_200i32.to_le_bytes());
    assert_eq!(refused(&mut r, 0x3501, 0, &0i32.to_le_bytes()), 0x0609_0032);
    enable(&mut r, 3);
    put(&mut r, 0x60FF, 0, &36_000i32.to_le_bytes());
    r.run_ms(1000);
    let v = get(&mut r, 0x606C, 0);
    assert!((v - 3_600).abs() < 400, "1 s at DRV.ACC 3600: {v}");
    put(&mut r, 0x60FF, 0, &0i32.to_le_bytes());
    r.run_ms(250);
    let v = get(&mut r, 0x606C, 0);
    assert!((v - 1_800).abs() < 400, "250 ms at DRV.DEC 7200: {v}");
    // HOME.ACC 3502h: the homing acceleration while 609Ah is 0.
    put(&mut r, 0x3502, 0, &5_000i32.to_le_bytes());
    assert_eq!(r.pn().app.drive.mode_params().homing_acceleration, 5_000);
}

/// DRV.NVSAVE 35EBh saves the parameters as 1010h:1 does: a value saved
/// survives NMT reset node, one written after it does not.
pub fn nvsave(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x366E, 0, &80i32.to_le_bytes());
    put(&mut r, 0x35EB, 0, &1i32.to_le_bytes());
    put(&mut r, 0x366E, 0, &90i32.to_le_bytes());
    r.send("000#8103");
    r.run_ms(10);
    assert_eq!(get(&mut r, 0x366E, 0), 80, "the saved value");
}

/// `profile` as node 3 on its default machine with a holding brake
/// (50 ms release, 40 ms apply), NMT operational.
pub fn with_brake(profile: Profile) -> Rig {
    let text = "[[node]]\nid = 3\n[node.brake]\nrelease_delay = 0.05\napply_delay = 0.04\n";
    let file = drivebus_personality::machine::MachineFile::parse(text).unwrap();
    let m = file.machine_for(profile, ID).unwrap();
    let (mut r, _) = Rig::with(profile.build_on(ID, &m).unwrap());
    r.send("000#0103");
    r.run_ms(5);
    r
}

/// 345Ah (KC1 §7.2.2.15, AKD §6.2.2.19): 0 → 1 → 3 takes the brake over
/// and releases it (345Ah:2 = 3 once the release delay passed); 1 applies
/// it; bit 0 cleared gives it back to the drive (disabled: applied); a
/// fault and a lost fieldbus (NMT stop) end the fieldbus control.
pub fn brake_control(profile: Profile) {
    let mut r = with_brake(profile);
    let released = |r: &Rig| !r.pn().app.drive.model().brake().engaged;
    assert!(!released(&r), "disabled: the drive applies the brake");
    for v in [0u16, 1, 3] {
        put(&mut r, 0x345A, 1, &v.to_le_bytes());
    }
    r.run_ms(20);
    assert_eq!(getu(&mut r, 0x345A, 2), 1, "fieldbus control, release delay running");
    r.run_ms(60);
    assert_eq!(getu(&mut r, 0x345A, 2), 3, "fieldbus control, released");
    assert!(released(&r));
    put(&mut r, 0x345A, 1, &1u16.to_le_bytes());
    r.run_ms(60);
    assert_eq!(getu(&mut r, 0x345A, 2), 1, "applied by the fieldbus");
    put(&mut r, 0x345A, 1, &0u16.to_le_bytes());
    put(&mut r, 0x345A, 1, &3u16.to_le_bytes());
    r.run_ms(60);
    assert_eq!(getu(&mut r, 0x345A, 2), 3);
    put(&mut r, 0x345A, 1, &2u16.to_le_bytes());
    r.run_ms(60);
    assert_eq!(getu(&mut r, 0x345A, 2), 0, "bit 0 clear: the drive applies it");
    // A fault ends the fieldbus control; it needs a new rising edge.
    put(&mut r, 0x345A, 1, &3u16.to_le_bytes());
    r.run_ms(60);
    r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Fault(0x4310));
    r.run_ms(60);
    assert_eq!(getu(&mut r, 0x345A, 2), 0, "after a fault: the drive's");
    put(&mut r, 0x6040, 0, &0x80u16.to_le_bytes());
    put(&mut r, 0x345A, 1, &3u16.to_le_bytes());
    r.run_ms(60);
    assert_eq!(getu(&mut r, 0x345A, 2), 0, "bit 0 still set: no rising edge, the drive applies it");
    put(&mut r, 0x345A, 1, &0u16.to_le_bytes());
    put(&mut r, 0x345A, 1, &3u16.to_le_bytes());
    r.run_ms(60);
    assert_eq!(getu(&mut r, 0x345A, 2), 3);
    // The fieldbus lost: NMT stop gives the brake back.
    r.send("000#0203");
    r.run_ms(60);
    assert!(!released(&r), "NMT stopped: the drive applies the brake");
}

/// MOTOR.BRAKERLS 3450h: 1 releases, 2 applies, 0 gives the brake back to
/// the drive; others are refused.
pub fn brake_release_command(profile: Profile) {
    let mut r = with_brake(profile);
    let released = |r: &Rig| !r.pn().app.drive.model().brake().engaged;
    put(&mut r, 0x3450, 0, &[1]);
    r.run_ms(60);
    assert!(released(&r), "MOTOR.BRAKERLS 1");
    put(&mut r, 0x3450, 0, &[0]);
    r.run_ms(60);
    assert!(!released(&r), "0: the drive's (disabled: applied)");
    assert_eq!(refused(&mut r, 0x3450, 0, &[3]), 0x0609_0030);
}

/// AIN.VALUE 3509h and 3470h:4 (mV, float scale 1000:1) read the machine's
/// analog input 1.
pub fn analog_input_value(profile: Profile) {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Plant;
    let m = drivebus_personality::machine::Machine::default_for(profile);
    let (mut r, _) = Rig::with(profile.build_on(ID, &m).unwrap());
    r.pn_mut().app.inject(Injection::Model(Plant::AnalogInput { channel: 1, volts: -1.25 }));
    r.run_ms(2);
    assert_eq!(get(&mut r, 0x3509, 0), -1250);
    assert_eq!(get(&mut r, 0x3470, 4), -1250);
}

/// 60FDh bits 16–22 mirror DIN1–7, bits 24–30 flag their changes until
/// 20B8h resets them (KC1 §7.2.3.8, §7.2.2.14; AKD §6.2.3.8, §6.2.2.18);
/// 1002h bits 25–28 show DIN1–4. 60FEh:1 bits 16/17 set DOUT1/2 as far as
/// 60FEh:2 enables them (KC1 §7.2.3.9, AKD §6.2.3.9).
pub fn digital_io(profile: Profile) {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Plant;
    let m = drivebus_personality::machine::Machine::default_for(profile);
    let (mut r, _) = Rig::with(profile.build_on(ID, &m).unwrap());
    r.run_ms(2);
    assert_eq!(getu(&mut r, 0x60FD, 0) >> 16, 0, "no input, no change");
    r.pn_mut().app.inject(Injection::Model(Plant::DigitalInput { line: 2, level: true }));
    r.run_ms(2);
    let di = getu(&mut r, 0x60FD, 0);
    assert_eq!(di >> 16, 0x0202, "DIN2 high and changed: {di:08X}");
    assert_ne!(getu(&mut r, 0x1002, 0) & (1 << 26), 0, "1002h bit 26: DIN2");
    put(&mut r, 0x20B8, 0, &0x0002u16.to_le_bytes());
    r.run_ms(1);
    assert_eq!(getu(&mut r, 0x60FD, 0) >> 16, 0x0002, "change flag reset");
    r.pn_mut().app.inject(Injection::Model(Plant::DigitalInput { line: 2, level: false }));
    r.run_ms(2);
    assert_eq!(getu(&mut r, 0x60FD, 0) >> 16, 0x0200, "DIN2 low, changed again");
    put(&mut r, 0x60FE, 2, &0x0003_0000u32.to_le_bytes());
    put(&mut r, 0x60FE, 1, &0x0002_0000u32.to_le_bytes());
    assert_eq!(r.pn().app.drive.output_lines(), 0b10, "DOUT2");
}

/// 60FEh:1 bit 0 "set brake" (enabled in 60FEh:2) applies the holding
/// brake while the drive is enabled (KC1 §7.2.3.9, AKD §6.2.3.9).
pub fn set_brake_bit(profile: Profile) {
    let mut r = with_brake(profile);
    enable(&mut r, 3);
    r.run_ms(100);
    assert!(!r.pn().app.drive.model().brake().engaged, "enabled: released");
    put(&mut r, 0x60FE, 2, &1u32.to_le_bytes());
    put(&mut r, 0x60FE, 1, &1u32.to_le_bytes());
    r.run_ms(100);
    assert!(r.pn().app.drive.model().brake().engaged, "set brake");
}

/// DRV.HANDWHEEL 2050h reads the secondary feedback, the machine's master
/// encoder (counts); DRV.TEMPERATURES 3610h the ambient.
pub fn secondary_feedback(profile: Profile) -> Rig {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Plant;
    let text = "[[node]]\nid = 3\n[node.temperature]\nambient = 31.0\n";
    let m =
        drivebus_personality::machine::MachineFile::parse(text).unwrap().machine_for(profile, ID).unwrap();
    let (mut r, _) = Rig::with(profile.build_on(ID, &m).unwrap());
    r.pn_mut().app.inject(Injection::Model(Plant::MasterPosition(f64::from(1u32 << 20))));
    r.run_ms(2);
    assert_eq!(get(&mut r, 0x2050, 0), 1 << 20, "DRV.HANDWHEEL");
    assert_eq!(get(&mut r, 0x3610, 0), 31, "ambient");
    r
}

/// A pp target beyond an active software limit is clamped to it (the
/// axis stops at the limit) and reported as warning n167 (EMCY 86A9h,
/// KC1 §7.1 / AKD §6.1).
pub fn target_clamped_to_limit(profile: Profile) {
    let mut r = operational(profile);
    put(&mut r, 0x607D, 1, &(-36_000i32).to_le_bytes());
    put(&mut r, 0x607D, 2, &36_000i32.to_le_bytes());
    put(&mut r, 0x1010, 1, b"save");
    r.send("000#8103");
    r.run_ms(10);
    r.send("000#0103");
    r.run_ms(5);
    enable(&mut r, 1);
    put(&mut r, 0x6081, 0, &36_000u32.to_le_bytes());
    put(&mut r, 0x607A, 0, &100_000i32.to_le_bytes());
    put(&mut r, 0x6040, 0, &0x1Fu16.to_le_bytes());
    let e = emcys_after(&mut r, 2500);
    assert_eq!(e.first(), Some(&emcy(0x86A9, 0x80)), "n167: {e:?}");
    assert!((r.position() - 36_000).abs() < 100, "stopped at the limit: {}", r.position());
    assert_eq!(getu(&mut r, 0x2000, 1), 167);
}
