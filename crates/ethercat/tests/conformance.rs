//! A conformance-style suite for the drive slaves, by the categories of the
//! ETG conformance test: the EtherCAT state machine (every transition,
//! every refused one's AL status code, the error acknowledge), the
//! process-data watchdog, the mailbox (counter, repeat, oversize, unknown
//! protocol), CoE (SDO Information, complete access, segmented transfer,
//! emergencies never as an answer). Frames go through the ESC of one
//! slave; time is simulated.

mod drive_rig;

use drive_rig::{Fail, Rig, al, coe, mbx};
use drivebus_can::Duration;
use drivebus_coe::access_bits::*;
use drivebus_personality::Profile;

const PROFILES: [Profile; 2] = [Profile::Ipos, Profile::Generic];

/// AL status codes (ETG.1000.6 Table 11).
mod code {
    pub const INVALID_STATE_CHANGE: u16 = 0x0011;
    pub const UNKNOWN_STATE: u16 = 0x0012;
    pub const BOOTSTRAP_NOT_SUPPORTED: u16 = 0x0013;
    pub const INVALID_MAILBOX: u16 = 0x0016;
    pub const SM_WATCHDOG: u16 = 0x001B;
    pub const INVALID_OUTPUT: u16 = 0x001D;
    pub const INVALID_INPUT: u16 = 0x001E;
    pub const INVALID_DC_SYNC: u16 = 0x0030;
    pub const DC_CYCLE: u16 = 0x0035;
}

/// A rig in `state` (INIT, PRE-OP, SAFE-OP, OP or BOOT).
fn rig_in(p: Profile, state: u8) -> Rig {
    let mut r = Rig::new(p);
    match state {
        al::INIT => {}
        al::BOOT => {
            r.mailbox_sms();
            assert_eq!(r.request(al::BOOT), (0x03, 0));
        }
        _ => {
            r.preop();
            if state != al::PREOP {
                r.safeop();
            }
            if state == al::OP {
                assert_eq!(r.request(al::OP), (0x08, 0));
            }
        }
    }
    r
}

#[test]
fn esm_transition_matrix() {
    use al::*;
    for p in PROFILES {
        let boot = p == Profile::Ipos;
        // (from, to, expected status, expected code)
        let no = |from: u8| (from | 0x10, code::INVALID_STATE_CHANGE);
        // BOOT only from INIT; a device without it says so (0013h).
        let no_boot = if boot { code::INVALID_STATE_CHANGE } else { code::BOOTSTRAP_NOT_SUPPORTED };
        let matrix: Vec<(u8, u8, (u16, u16))> = vec![
            (INIT, INIT, (0x01, 0)),
            (INIT, PREOP, (0x02, 0)),
            (INIT, SAFEOP, (no(INIT).0 as u16, no(INIT).1)),
            (INIT, OP, (0x11, code::INVALID_STATE_CHANGE)),
            (INIT, BOOT, if boot { (0x03, 0) } else { (0x11, code::BOOTSTRAP_NOT_SUPPORTED) }),
            (INIT, 0x05, (0x11, code::UNKNOWN_STATE)),
            (PREOP, INIT, (0x01, 0)),
            (PREOP, SAFEOP, (0x04, 0)),
            (PREOP, OP, (0x12, code::INVALID_STATE_CHANGE)),
            (PREOP, BOOT, (0x12, no_boot)),
            (SAFEOP, INIT, (0x01, 0)),
            (SAFEOP, PREOP, (0x02, 0)),
            (SAFEOP, OP, (0x08, 0)),
            (SAFEOP, BOOT, (0x14, no_boot)),
            (OP, INIT, (0x01, 0)),
            (OP, PREOP, (0x02, 0)),
            (OP, SAFEOP, (0x04, 0)),
            (OP, BOOT, (0x18, no_boot)),
        ];
        for (from, to, want) in matrix {
            let mut r = rig_in(p, from);
            if from == INIT && matches!(to, PREOP | BOOT) {
                r.mailbox_sms();
            }
            if to == SAFEOP && from == PREOP {
                r.pd_sms(sizes(&r).0, sizes(&r).1, true);
            }
            assert_eq!(r.request(to), want, "{p}: {from:#x} → {to:#x}");
        }
        if boot {
            for (to, want) in [(PREOP, (0x13, code::INVALID_STATE_CHANGE)), (INIT, (0x01, 0))] {
                let mut r = rig_in(p, BOOT);
                assert_eq!(r.request(to), want, "{p}: BOOT → {to:#x}");
            }
        }
    }
}

fn sizes(r: &Rig) -> (u16, u16) {
    let s = drivebus_esc::slave::SlaveApp::process_data_sizes(r.s.app());
    (s.output_bytes() as u16, s.input_bytes() as u16)
}

#[test]
fn refused_transitions_say_why_and_wait_for_the_acknowledge() {
    for p in PROFILES {
        // INIT → PRE-OP without the mailbox sync managers (ETG.1000.6: 0016h).
        let mut r = Rig::new(p);
        assert_eq!(r.request(al::PREOP), (0x11, code::INVALID_MAILBOX), "{p}");
        // The error is indicated until acknowledged: a request without
        // the acknowledge bit is ignored (INIT excepted).
        r.mailbox_sms();
        assert_eq!(r.request(al::PREOP), (0x11, code::INVALID_MAILBOX), "{p}: not acknowledged");
        assert_eq!(r.request(al::PREOP | al::ACK), (0x02, 0), "{p}: acknowledged");
        // PRE-OP → SAFE-OP with SM2/SM3 lengths that do not match the mapping.
        let (o, i) = sizes(&r);
        r.pd_sms(o + 1, i, true);
        assert_eq!(r.request(al::SAFEOP), (0x12, code::INVALID_OUTPUT), "{p}");
        r.pd_sms(o, i - 2, true);
        assert_eq!(r.request(al::SAFEOP | al::ACK), (0x12, code::INVALID_INPUT), "{p}");
        // DC: cyclic unit without SYNC0 (0x0981 = 01h) is invalid.
        r.pd_sms(o, i, true);
        r.wr(0x0981, &[0x01]);
        assert_eq!(r.request(al::SAFEOP | al::ACK), (0x12, code::INVALID_DC_SYNC), "{p}");
        // INIT is always taken and clears the error.
        assert_eq!(r.request(al::INIT), (0x01, 0), "{p}");
    }
    // iPOS §3.2: SYNC0 a multiple of the 1 ms slow loop.
    let mut r = rig_in(Profile::Ipos, al::PREOP);
    let (o, i) = sizes(&r);
    r.pd_sms(o, i, true);
    r.wr(0x09A0, &1_500_000u32.to_le_bytes());
    r.wr(0x0981, &[0x03]);
    assert_eq!(r.request(al::SAFEOP), (0x12, code::DC_CYCLE));
    // 1C32h:01 = 2 (DC SYNC0) asked for, DC not activated: 0030h.
    r.wr(0x0981, &[0x00]);
    r.request(al::PREOP | al::ACK);
    r.down(0x1C32, 1, &2u16.to_le_bytes()).unwrap();
    assert_eq!(r.request(al::SAFEOP), (0x12, code::INVALID_DC_SYNC));
}

#[test]
fn ipos_reports_refused_transitions_with_emcy_a0xx() {
    let mut r = rig_in(Profile::Ipos, al::PREOP);
    let (o, i) = sizes(&r);
    r.pd_sms(o, i + 1, true);
    assert_eq!(r.request(al::SAFEOP), (0x12, code::INVALID_INPUT));
    r.collect_emergencies(Duration::from_millis(50));
    // Table 3.1.3 A0xxh "ESM transition error": A0 + the AL code's low byte.
    assert!(r.emergencies.iter().any(|e| e.0 == 0xA01E), "{:X?}", r.emergencies);
}

/// Fresh inputs: free run latches them when the master has read the
/// last ones, so the first read gives what was latched before.
fn fresh_inputs(r: &mut Rig) -> Vec<u8> {
    r.inputs();
    r.tick(Duration::from_millis(1));
    r.inputs()
}

/// Enables the drive through the process data: controlword 6, 7, Fh with
/// the target at the actual position (csp, 6060h = 8 by SDO).
fn enable(r: &mut Rig) {
    for cw in [0x06u16, 0x07, 0x0F] {
        let inp = fresh_inputs(r);
        let mut out = vec![0u8; usize::from(r.pd.0)];
        out[..2].copy_from_slice(&cw.to_le_bytes());
        out[2..6].copy_from_slice(&inp[2..6]);
        r.outputs(&out);
        r.tick(Duration::from_millis(5));
    }
    let sw = u16::from_le_bytes(fresh_inputs(r)[..2].try_into().unwrap());
    assert_eq!(sw & 0x6F, 0x27, "operation enabled: {sw:04X}");
}

#[test]
fn process_data_watchdog_takes_the_slave_to_safe_op_and_the_drive_reacts() {
    for p in PROFILES {
        let mut r = rig_in(p, al::PREOP);
        r.down(0x6060, 0, &[8]).unwrap();
        // 6007h = 1: the drive faults (iPOS default; CiA 402-2 option 1).
        r.down(0x6007, 0, &1i16.to_le_bytes()).unwrap();
        // Process-data watchdog 10 ms (0x0420 in units of 0x0400, 100 µs).
        r.wr(0x0420, &100u16.to_le_bytes());
        r.safeop();
        assert_eq!(r.request(al::OP), (0x08, 0), "{p}");
        enable(&mut r);
        // The master stops: no outputs for 20 ms.
        r.tick(Duration::from_millis(20));
        let b = r.rd(0x0130, 6);
        assert_eq!(
            (b[0], u16::from_le_bytes([b[4], b[5]])),
            (0x14, code::SM_WATCHDOG),
            "{p}: SAFE-OP + 001Bh"
        );
        r.collect_emergencies(Duration::from_millis(50));
        assert!(r.emergencies.iter().any(|e| e.0 == 0x8100 && e.1 & 0x10 != 0), "{p}: {:X?}", r.emergencies);
        // 6007h = 1: fault with 603Fh = 8100h.
        assert_eq!(r.up_u32(0x6041, 0) & 0x08, 0x08, "{p}: fault");
        assert_eq!(r.up_u32(0x603F, 0), 0x8100, "{p}");
        if p == Profile::Ipos {
            assert_eq!(r.up_u32(0x2000, 0) & 1, 1, "2000h bit 0: EtherCAT communication error");
        }
        // The ESM error acknowledge clears 2000h bit 0; the drive's fault
        // stays until its fault reset.
        assert_eq!(r.request(al::SAFEOP | al::ACK), (0x04, 0), "{p}");
        if p == Profile::Ipos {
            assert_eq!(r.up_u32(0x2000, 0) & 1, 0);
        }
        assert_eq!(r.up_u32(0x6041, 0) & 0x08, 0x08, "{p}: still faulted");
        r.emergencies.clear();
        r.down(0x6040, 0, &0u16.to_le_bytes()).unwrap();
        r.down(0x6040, 0, &0x80u16.to_le_bytes()).unwrap();
        r.tick(Duration::from_millis(5));
        assert_eq!(r.up_u32(0x6041, 0) & 0x08, 0, "{p}: fault reset");
        r.collect_emergencies(Duration::from_millis(50));
        assert!(r.emergencies.iter().any(|e| e.0 == 0x0000), "{p}: error reset EMCY {:X?}", r.emergencies);
    }
}

#[test]
fn leaving_op_runs_the_abort_connection_option() {
    for (opt, want) in [(0i16, 0x27u16), (2, 0x40), (3, 0x07)] {
        let mut r = rig_in(Profile::Ipos, al::PREOP);
        r.down(0x6060, 0, &[8]).unwrap();
        r.down(0x6007, 0, &opt.to_le_bytes()).unwrap();
        r.safeop();
        assert_eq!(r.request(al::OP), (0x08, 0));
        enable(&mut r);
        assert_eq!(r.request(al::SAFEOP), (0x04, 0));
        r.tick(Duration::from_millis(50));
        // 0: no action; 2: disable voltage; 3: quick stop (then, option
        // 605Ah, switch on disabled or quick stop active).
        let sw = r.up_u32(0x6041, 0) as u16;
        let state = if want == 0x40 { sw & 0x4F } else { sw & 0x6F };
        if opt == 3 {
            assert!(matches!(sw & 0x6F, 0x07) || sw & 0x4F == 0x40, "6007h = 3: {sw:04X}");
        } else {
            assert_eq!(state, want, "6007h = {opt}: {sw:04X}");
        }
    }
}

/// iPOS §4.9.8: 2080h resets the drive, "not the ECAT interface": the
/// slave stays in OP, the drive restarts in Switch on disabled, and the
/// process data keep driving it (the node follows the ESM again).
#[test]
fn ipos_reset_drive_keeps_the_esm() {
    let mut r = rig_in(Profile::Ipos, al::PREOP);
    r.down(0x6060, 0, &[8]).unwrap();
    r.safeop();
    assert_eq!(r.request(al::OP), (0x08, 0));
    enable(&mut r);
    r.down(0x2080, 0, &1u16.to_le_bytes()).unwrap();
    r.tick(Duration::from_millis(20));
    assert_eq!(r.rd16(0x0130) & 0x1F, 0x08, "still OP, no error");
    let sw = u16::from_le_bytes(fresh_inputs(&mut r)[..2].try_into().unwrap());
    assert_eq!(sw & 0x4F, 0x40, "switch on disabled after the reset: {sw:04X}");
    let nmt = r.s.app().device().node.nmt_state();
    assert_eq!(nmt, drivebus_node::NmtState::Operational, "the node follows OP");
    // 6060h came back from the EEPROM (its power-on value); csp again.
    r.down(0x6060, 0, &[8]).unwrap();
    enable(&mut r);
    // Leaving OP still runs 6007h (default 1: fault): the node is operational.
    assert_eq!(r.request(al::SAFEOP), (0x04, 0));
    r.tick(Duration::from_millis(20));
    assert_eq!(r.up_u32(0x603F, 0) as u16, 0x8100, "6007h fault on leaving OP");
}

#[test]
fn mailbox_counter_repeat_oversize_and_unknown_protocol() {
    for p in PROFILES {
        let mut r = rig_in(p, al::PREOP);
        let up = |c: u8| coe(c, &[0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]);
        // A request repeated with the same counter is not executed again.
        r.send(&up(3));
        assert!(r.read().is_some());
        r.send(&up(3));
        assert_eq!(r.read(), None, "{p}: repeated counter dropped");
        r.send(&up(4));
        let first = r.read().unwrap();
        // SM1 repeat request (0x080E bit 1 toggled): the last message again.
        let act = r.rd(0x080E, 2);
        r.wr(0x080E, &[act[0] ^ 0x02]);
        r.tick(Duration::from_millis(1));
        assert_eq!(r.rd(0x080F, 1)[0] & 0x02, (act[0] ^ 0x02) & 0x02, "{p}: repeat acknowledged");
        assert_eq!(r.read(), Some(first.clone()), "{p}: same message again");
        // A length beyond the mailbox: mailbox error 0008h "invalid size".
        let mut big = up(5);
        big[..2].copy_from_slice(&600u16.to_le_bytes());
        let m = r.one(&big);
        assert_eq!((m[5] & 0x0F, u16::from_le_bytes([m[8], m[9]])), (0, 0x0008), "{p}");
        // EoE, SoE, VoE: 0002h "protocol not supported".
        for t in [0x02u8, 0x05, 0x0F] {
            let c = r.counter();
            let m = r.one(&mbx(t, c, &[0; 8]));
            assert_eq!((m[5] & 0x0F, u16::from_le_bytes([m[8], m[9]])), (0, 0x0002), "{p}: type {t}");
        }
        // The generic servo has no FoE either.
        let c = r.counter();
        let m = r.one(&mbx(0x04, c, &[2, 0, 0, 0, 0, 0, b'x']));
        if p == Profile::Generic {
            assert_eq!((m[5] & 0x0F, u16::from_le_bytes([m[8], m[9]])), (0, 0x0002));
        } else {
            assert_eq!(m[5] & 0x0F, 4, "iPOS answers FoE");
        }
    }
}

/// SDO Information Get OD List (all objects), fragments joined.
fn od_list(r: &mut Rig) -> Vec<u16> {
    let c = r.counter();
    r.send(&coe(c, &[0x00, 0x80, 0x01, 0, 0, 0, 0x01, 0x00]));
    let mut out = Vec::new();
    let mut first = true;
    loop {
        let m = r.read().unwrap();
        let b = &m[6..];
        assert_eq!(b[2] & 0x7F, 0x02, "OD list response");
        let len = usize::from(u16::from_le_bytes([m[0], m[1]]));
        let (n, off) = if first { ((len - 8) / 2, 8) } else { ((len - 6) / 2, 6) };
        out.extend((0..n).map(|k| u16::from_le_bytes([b[off + 2 * k], b[off + 2 * k + 1]])));
        first = false;
        if u16::from_le_bytes([b[4], b[5]]) == 0 {
            return out;
        }
    }
}

#[test]
fn sdo_information_describes_the_running_dictionary() {
    for p in PROFILES {
        let mut r = rig_in(p, al::PREOP);
        let all: Vec<u16> = r.s.app().device().node.od().objects().iter().map(|o| o.index).collect();
        assert_eq!(od_list(&mut r), all, "{p}");
        // Object description of 1C12h: RECORD, its highest sub, its name.
        let c = r.counter();
        let m = r.one(&coe(c, &[0x00, 0x80, 0x03, 0, 0, 0, 0x12, 0x1C]));
        let b = &m[6..];
        assert_eq!(b[2] & 0x7F, 0x04, "{p}");
        let o = r.s.app().device().node.od().object(0x1C12).unwrap();
        assert_eq!((b[11], b[10]), (o.code as u8, o.subs().last().unwrap().sub), "{p}: object code, max sub");
        // Entry description: 1C12h:01 written in PRE-OP only; 6040h RxPDO-mappable.
        for (index, sub, want, not) in [
            (0x1C12u16, 1u8, READ | WRITE_PREOP, WRITE_SAFEOP | WRITE_OP),
            (0x6040, 0, RXPDO | WRITE, 0),
            (0x6041, 0, TXPDO | READ, WRITE),
        ] {
            let c = r.counter();
            let i = index.to_le_bytes();
            let m = r.one(&coe(c, &[0x00, 0x80, 0x05, 0, 0, 0, i[0], i[1], sub, 0x07]));
            let b = &m[6..];
            assert_eq!(b[2] & 0x7F, 0x06, "{p}: {index:04X}");
            let access = u16::from_le_bytes([b[14], b[15]]);
            assert_eq!(access & want, want, "{p}: {index:04X}:{sub} access {access:04X}");
            assert_eq!(access & not, 0, "{p}: {index:04X}:{sub} access {access:04X}");
        }
    }
}

#[test]
fn complete_access_and_segmented_transfers() {
    let mut r = rig_in(Profile::Ipos, al::PREOP);
    // SOEM reads 1C12h/1C13h and the mapping objects by complete access.
    assert_eq!(r.upload(0x1C13, 0, true).unwrap(), [2, 0, 0x00, 0x1A, 0x01, 0x1A]);
    let m = r.upload(0x1A00, 0, true).unwrap();
    assert_eq!(m[0], 3);
    assert_eq!(&m[2..6], &0x6041_0010u32.to_le_bytes());
    // A complete-access write in the order the rules need (sub 0 last).
    let c = r.counter();
    let mut b = vec![0x00, 0x20, 0x21 | 0x10, 0x13, 0x1C, 0x00];
    let data = [1u8, 0, 0x00, 0x1A];
    b.extend_from_slice(&(data.len() as u32).to_le_bytes());
    b.extend_from_slice(&data);
    let m = r.one(&coe(c, &b));
    assert_eq!(m[8] & !0x10, 0x60, "CA download accepted: {m:02X?}");
    assert_eq!(r.up(0x1C13, 0).unwrap(), [1]);
    // Outside PRE-OP the same write is refused with the device's code.
    r.safeop();
    assert_eq!(r.down(0x1C13, 0, &[0]), Err(Fail::Abort(0x0800_0022)));
    // The generic servo serves its EDS at 1021h: larger than the mailbox,
    // so a segmented upload.
    let mut g = rig_in(Profile::Generic, al::PREOP);
    let eds = g.up(0x1021, 0).unwrap();
    assert!(eds.len() > 2 * drive_rig::MBX_LEN, "{} bytes", eds.len());
    assert!(String::from_utf8_lossy(&eds).contains("[1C12]"), "the EtherCAT dictionary's EDS");
    // Normal downloads: a constant refuses with the CAN side's code; a
    // DOMAIN larger than the mailbox (1F50h:01 program data) goes in
    // segments and reads back the same.
    assert_eq!(g.down(0x1008, 0, b"renamed drive"), Err(Fail::Abort(0x0601_0002)));
    let program: Vec<u8> = (0..1500u32).map(|i| (i * 7) as u8).collect();
    g.down(0x1F50, 1, &program).unwrap();
    assert_eq!(g.up(0x1F50, 1).unwrap(), program);
}

#[test]
fn emergencies_never_answer_a_request() {
    let mut r = rig_in(Profile::Ipos, al::PREOP);
    // An emergency waits while requests keep the mailbox busy.
    r.s.app_mut().device_mut().app.inject(drivebus_cia402::drive::Injection::Fault(0x4310));
    for _ in 0..20 {
        let c = r.counter();
        let m = r.one(&coe(c, &[0x00, 0x20, 0x40, 0x41, 0x60, 0x00, 0, 0, 0, 0]));
        assert_eq!(m[7] >> 4, 3, "an SDO response, not an emergency: {m:02X?}");
    }
    r.collect_emergencies(Duration::from_millis(50));
    assert!(r.emergencies.iter().any(|e| e.0 == 0x4310), "{:X?}", r.emergencies);
}
