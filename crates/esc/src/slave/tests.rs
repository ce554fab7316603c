//! The firmware framework driven through frames, as a master would.

use super::*;
use crate::EscConfig;
use crate::frame::{DatagramCommand, FrameBuilder, datagrams, position_address, station_address};
use crate::sii::{SiiImage, SiiSyncManager, fmmu_usage};
use alloc::vec;
use drivebus_base::Duration;

/// Test application: 2 output bytes, 4 input bytes (outputs echoed plus a
/// counter), echoes mailbox requests, can queue emergencies.
#[derive(Debug, Default)]
struct App {
    outputs: Vec<(Vec<u8>, Instant)>,
    syncs: u32,
    counter: u16,
    last_out: [u8; 2],
    support: Option<SyncSupport>,
    emcy: Vec<Vec<u8>>,
    error: Option<(AlStatusCode, AlState)>,
    watchdog: u32,
    states: Vec<(AlState, AlState)>,
    boot: bool,
}

impl SlaveApp for App {
    fn process_data_sizes(&self) -> ProcessDataSizes {
        ProcessDataSizes { output_bits: 16, input_bits: 32 }
    }
    fn sync_support(&self) -> SyncSupport {
        self.support.unwrap_or_default()
    }
    fn bootstrap_supported(&self) -> bool {
        self.boot
    }
    fn state_changed(&mut self, from: AlState, to: AlState, _now: Instant) {
        self.states.push((from, to));
    }
    fn mailbox(&mut self, request: &[u8], _now: Instant, out: &mut MailboxOut<'_>) {
        out.respond(request);
    }
    fn outputs(&mut self, data: &[u8], now: Instant) {
        self.last_out.copy_from_slice(data);
        self.outputs.push((data.to_vec(), now));
    }
    fn inputs(&mut self, data: &mut [u8], _now: Instant) {
        self.counter += 1;
        data[..2].copy_from_slice(&self.last_out);
        data[2..].copy_from_slice(&self.counter.to_le_bytes());
    }
    fn sync0(&mut self, _now: Instant, _system_time: u64) {
        self.syncs += 1;
    }
    fn watchdog_expired(&mut self, _now: Instant) {
        self.watchdog += 1;
    }
    fn poll(&mut self, _now: Instant, out: &mut MailboxOut<'_>) -> Option<Instant> {
        for m in self.emcy.drain(..) {
            out.unsolicited(&m);
        }
        None
    }
    fn take_error(&mut self) -> Option<(AlStatusCode, AlState)> {
        self.error.take()
    }
}

fn image() -> SiiImage {
    SiiImage::builder()
        .identity(0x1A3, 1, 1, 1)
        .mailbox(
            crate::sii::MailboxArea { rx_offset: 0x1000, rx_size: 64, tx_offset: 0x1080, tx_size: 64 },
            4,
        )
        .bootstrap_mailbox(crate::sii::MailboxArea {
            rx_offset: 0x1400,
            rx_size: 128,
            tx_offset: 0x1600,
            tx_size: 128,
        })
        .fmmus(&[fmmu_usage::OUTPUTS, fmmu_usage::INPUTS])
        .sync_manager(SiiSyncManager { start: 0x1000, length: 64, control: 0x26, enable: 1, sm_type: 1 })
        .sync_manager(SiiSyncManager { start: 0x1080, length: 64, control: 0x22, enable: 1, sm_type: 2 })
        .sync_manager(SiiSyncManager { start: 0x1100, length: 0, control: 0x64, enable: 1, sm_type: 3 })
        .sync_manager(SiiSyncManager { start: 0x1200, length: 0, control: 0x20, enable: 1, sm_type: 4 })
        .build()
}

struct Rig {
    s: Slave<App>,
    t: Instant,
}

impl Rig {
    fn new() -> Rig {
        let esc = Esc::new(EscConfig::with_sii(image()));
        let mut r = Rig { s: Slave::new(esc, App::default(), SlaveConfig::default()), t: Instant::ZERO };
        r.dg(DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10]);
        r
    }

    fn dg(&mut self, cmd: DatagramCommand, addr: u32, data: &[u8]) -> (Vec<u8>, u16) {
        self.t += Duration::from_micros(10);
        let mut buf = [0u8; 256];
        let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
        b.push(cmd, 1, addr, data).unwrap();
        let n = b.finish();
        self.s.esc_mut().process_frame(&mut buf[..n], self.t);
        self.s.poll(self.t);
        let d = datagrams(&buf[14..n]).next().unwrap();
        (d.data.to_vec(), d.wkc)
    }

    fn rd(&mut self, ado: u16, len: usize) -> (Vec<u8>, u16) {
        self.dg(DatagramCommand::Fprd, station_address(0x1000, ado), &vec![0; len])
    }

    fn wr(&mut self, ado: u16, data: &[u8]) -> u16 {
        self.dg(DatagramCommand::Fpwr, station_address(0x1000, ado), data).1
    }

    fn status(&mut self) -> (u8, u16) {
        let (d, _) = self.rd(0x0130, 6);
        (d[0], u16::from_le_bytes([d[4], d[5]]))
    }

    fn request(&mut self, state: u8) -> (u8, u16) {
        self.wr(0x0120, &[state, 0]);
        self.status()
    }

    fn mailbox_sms(&mut self, rx_len: u8) {
        self.wr(0x0800, &[0x00, 0x10, rx_len, 0, 0x26, 0, 1, 0]);
        self.wr(0x0808, &[0x80, 0x10, 64, 0, 0x22, 0, 1, 0]);
    }

    fn pd_sms(&mut self, out_len: u8, out_ctrl: u8, in_len: u8) {
        self.wr(0x0810, &[0x00, 0x11, out_len, 0, out_ctrl, 0, 1, 0]);
        self.wr(0x0818, &[0x00, 0x12, in_len, 0, 0x20, 0, 1, 0]);
    }

    fn enter_preop(&mut self) {
        self.mailbox_sms(64);
        assert_eq!(self.request(2), (0x02, 0));
    }

    fn enter_safeop(&mut self) {
        self.enter_preop();
        self.pd_sms(2, 0x64, 4);
        assert_eq!(self.request(4), (0x04, 0));
    }

    /// Moves time to `t + d`, polling at every deadline on the way (and
    /// checking the deadline contract: a deadline is never in the past
    /// after a poll).
    fn advance(&mut self, d: Duration) {
        let end = self.t + d;
        while let Some(next) = self.s.poll(self.t).filter(|n| *n <= end) {
            assert!(next > self.t, "deadline {next:?} not after now {:?}", self.t);
            self.t = next;
        }
        self.t = end;
        self.s.poll(end);
    }
}

#[test]
fn init_enter_preop_checks_the_mailbox_sync_managers() {
    let mut r = Rig::new();
    r.mailbox_sms(32);
    assert_eq!(r.request(2), (0x11, 0x0016), "SM0 length differs from the SII");
    // Without acknowledge the next request is ignored.
    r.mailbox_sms(64);
    r.wr(0x0806, &[0]);
    r.mailbox_sms(64);
    assert_eq!(r.request(2), (0x11, 0x0016));
    assert_eq!(r.request(0x12), (0x02, 0), "acknowledge + request");
    assert_eq!(r.s.app().states, vec![(AlState::Init, AlState::PreOp)]);
}

#[test]
fn invalid_unknown_and_bootstrap_requests() {
    let mut r = Rig::new();
    assert_eq!(r.request(4), (0x11, 0x0011), "INIT -> SAFE-OP");
    assert_eq!(r.request(0x11), (0x01, 0), "INIT + ack clears");
    assert_eq!(r.request(5), (0x11, 0x0012), "unknown state");
    assert_eq!(r.request(1), (0x01, 0), "INIT request clears without ack");
    assert_eq!(r.request(3), (0x11, 0x0013), "no bootstrap");
    r.request(0x11);
    r.enter_preop();
    assert_eq!(r.request(8), (0x12, 0x0011), "PRE-OP -> OP");
}

#[test]
fn preop_enter_safeop_checks_process_data_sync_managers() {
    let mut r = Rig::new();
    r.enter_preop();
    r.pd_sms(3, 0x64, 4);
    assert_eq!(r.request(4), (0x12, 0x001D), "outputs length");
    r.wr(0x0816, &[0]);
    r.wr(0x081E, &[0]);
    r.pd_sms(2, 0x64, 2);
    assert_eq!(r.request(0x14), (0x12, 0x001E), "inputs length");
    r.wr(0x0816, &[0]);
    r.wr(0x081E, &[0]);
    r.pd_sms(2, 0x66, 4);
    assert_eq!(r.request(0x14), (0x12, 0x0029), "mailbox mode outputs in free run");
    r.wr(0x0816, &[0]);
    r.wr(0x081E, &[0]);
    r.pd_sms(2, 0x60, 4);
    assert_eq!(r.request(0x14), (0x12, 0x001D), "wrong direction");
    r.wr(0x0816, &[0]);
    r.wr(0x081E, &[0]);
    r.pd_sms(2, 0x64, 4);
    assert_eq!(r.request(0x14), (0x04, 0));
    assert_eq!(r.rd(0x1200, 4).0, [0, 0, 1, 0], "first inputs latched on entering SAFE-OP");
    assert_eq!(r.s.sync_config().watchdog, Some(Duration::from_millis(100)));
}

#[test]
fn free_run_outputs_and_inputs_in_op() {
    let mut r = Rig::new();
    r.enter_safeop();
    assert_eq!(r.wr(0x1100, &[0xAB, 0xCD]), 1);
    assert!(r.s.app().outputs.is_empty(), "SAFE-OP: outputs not applied");
    assert_eq!(r.request(8), (0x08, 0));
    r.wr(0x1100, &[0x12, 0x34]);
    assert_eq!(r.s.app().outputs.last().unwrap().0, [0x12, 0x34]);
    // The master reads what was latched before its frame (here: on entering
    // SAFE-OP, before any outputs were applied); each read latches anew.
    let (d, wkc) = r.rd(0x1200, 4);
    assert_eq!((d, wkc), (vec![0, 0, 1, 0], 1));
    let (d, _) = r.rd(0x1200, 4);
    assert_eq!(d, [0x12, 0x34, 2, 0]);
}

#[test]
fn watchdog_expiry_in_op_falls_back_enter_safeop() {
    let mut r = Rig::new();
    r.enter_safeop();
    r.wr(0x0420, &[10, 0]); // 1 ms
    r.wr(0x1100, &[1, 2]);
    r.request(8);
    r.wr(0x1100, &[1, 2]);
    r.advance(Duration::from_micros(900));
    assert_eq!(r.status(), (0x08, 0));
    r.advance(Duration::from_millis(2));
    assert_eq!(r.status(), (0x14, 0x001B));
    assert_eq!(r.s.app().watchdog, 1);
    assert_eq!(r.request(0x18), (0x08, 0), "acknowledge and back to OP");
}

#[test]
fn application_error_takes_the_slave_down() {
    let mut r = Rig::new();
    r.enter_safeop();
    r.request(8);
    r.s.app_mut().error = Some((AlStatusCode::SYNC_ERROR, AlState::SafeOp));
    r.advance(Duration::from_micros(1));
    assert_eq!(r.status(), (0x14, 0x001A));
}

fn dc(r: &mut Rig, act: u8, cycle: u32) -> u64 {
    r.wr(0x0981, &[0]);
    let now_sys = {
        let (d, _) = r.rd(0x0910, 8);
        u64::from_le_bytes(d.try_into().unwrap())
    };
    r.wr(0x0990, &(now_sys + 1_000_000).to_le_bytes());
    r.wr(0x09A0, &u64::from(cycle).to_le_bytes());
    r.wr(0x0981, &[act]);
    now_sys + 1_000_000
}

#[test]
fn dc_configuration_is_checked_against_the_application() {
    let mut r = Rig::new();
    r.enter_preop();
    r.pd_sms(2, 0x64, 4);
    dc(&mut r, 0x01, 1_000_000);
    assert_eq!(r.request(4), (0x12, 0x0030), "cyclic unit on, SYNC0 off");
    dc(&mut r, 0x03, 10_000);
    assert_eq!(r.request(0x14), (0x12, 0x0036), "cycle below 50 us");
    r.s.app_mut().support =
        Some(SyncSupport { cycle_step: Duration::from_micros(250), ..SyncSupport::default() });
    dc(&mut r, 0x03, 1_100_000);
    assert_eq!(r.request(0x14), (0x12, 0x0035), "not a multiple of the loop period");
    r.s.app_mut().support = Some(SyncSupport { dc_sync01: false, ..SyncSupport::default() });
    dc(&mut r, 0x07, 1_000_000);
    assert_eq!(r.request(0x14), (0x12, 0x0028), "SYNC1 not supported");
    r.s.app_mut().support = Some(SyncSupport { free_run: false, ..SyncSupport::default() });
    r.wr(0x0981, &[0]);
    assert_eq!(r.request(0x14), (0x12, 0x0027), "free run not supported");
    dc(&mut r, 0x03, 1_000_000);
    assert_eq!(r.request(0x14), (0x04, 0));
    assert_eq!(r.s.sync_config().mode, SyncMode::DcSync0);
}

#[test]
fn dc_op_waits_for_sync0_then_applies_outputs_at_each_pulse() {
    let mut r = Rig::new();
    r.enter_preop();
    r.pd_sms(2, 0x64, 4);
    let start = dc(&mut r, 0x03, 1_000_000);
    r.request(4);
    r.wr(0x1100, &[7, 7]);
    assert_eq!(r.request(8), (0x04, 0), "pending: no SYNC0 yet");
    r.advance(Duration::from_millis(2));
    assert_eq!(r.status(), (0x08, 0));
    let n = r.s.app().syncs;
    assert!(n >= 1);
    r.wr(0x1100, &[9, 9]);
    assert!(r.s.app().outputs.iter().all(|(o, _)| o == &[7, 7]), "DC: not applied at the SM event");
    r.advance(Duration::from_millis(1));
    assert_eq!(r.s.app().outputs.last().unwrap().0, [9, 9]);
    // Outputs are applied at the exact SYNC0 instant.
    let (_, at) = r.s.app().outputs.last().unwrap().clone();
    let sys = r.s.esc().system_time(at);
    assert_eq!((sys - start) % 1_000_000, 0, "on the SYNC0 grid");
    // SYNC0 stopping is a fatal sync error.
    r.wr(0x0981, &[0]);
    r.advance(Duration::from_millis(10));
    assert_eq!(r.status(), (0x14, 0x002C));
}

/// SOEM's order: `ec_config_map` requests SAFE-OP (taken in free run),
/// then `ec_configdc` / `ec_dcsync0` activate SYNC0. The SAFE-OP → OP
/// request takes the DC set-up: OP waits for SYNC0 and the outputs go to
/// the application at the pulses, not at the SM event. A cycle the
/// application cannot run is refused there as it would be at PRE-OP →
/// SAFE-OP.
#[test]
fn dc_set_up_in_safe_op_is_taken_at_op() {
    let mut r = Rig::new();
    r.enter_preop();
    r.pd_sms(2, 0x64, 4);
    r.wr(0x0981, &[0]);
    assert_eq!(r.request(4), (0x04, 0));
    assert_eq!(r.s.sync_config().mode, SyncMode::FreeRun);
    r.s.app_mut().support =
        Some(SyncSupport { cycle_step: Duration::from_micros(250), ..SyncSupport::default() });
    dc(&mut r, 0x03, 1_100_000);
    assert_eq!(r.request(8), (0x14, 0x0035), "not a multiple of the loop period");
    assert_eq!(r.request(0x14), (0x04, 0), "acknowledged");
    let start = dc(&mut r, 0x03, 1_000_000);
    r.wr(0x1100, &[7, 7]);
    assert_eq!(r.request(8), (0x04, 0), "pending: no SYNC0 yet");
    assert_eq!(r.s.sync_config().mode, SyncMode::DcSync0);
    assert_eq!(r.s.sync_config().sync0_cycle, 1_000_000);
    r.advance(Duration::from_millis(2));
    assert_eq!(r.status(), (0x08, 0));
    r.wr(0x1100, &[9, 9]);
    assert!(r.s.app().outputs.iter().all(|(o, _)| o == &[7, 7]), "DC: not applied at the SM event");
    r.advance(Duration::from_millis(1));
    let (o, at) = r.s.app().outputs.last().unwrap().clone();
    assert_eq!(o, [9, 9]);
    assert_eq!((r.s.esc().system_time(at) - start) % 1_000_000, 0, "on the SYNC0 grid");
}

/// Mailbox message: CoE-typed, counter `cnt`, payload `p`.
fn msg(cnt: u8, p: &[u8]) -> Vec<u8> {
    let mut m = vec![0u8; 6];
    m[0..2].copy_from_slice(&(p.len() as u16).to_le_bytes());
    m[5] = 0x03 | (cnt << 4);
    m.extend_from_slice(p);
    m.resize(64, 0);
    m
}

#[test]
fn mailbox_request_response_counter_and_duplicates() {
    let mut r = Rig::new();
    r.enter_preop();
    assert_eq!(r.wr(0x1000, &msg(1, b"hello")), 1);
    let (d, wkc) = r.rd(0x1080, 64);
    assert_eq!(wkc, 1, "response waiting in SM1");
    assert_eq!(&d[6..11], b"hello");
    assert_eq!(d[5] >> 4, 1, "the slave's own counter");
    // Same counter again: a repeated frame, dropped.
    r.wr(0x1000, &msg(1, b"again"));
    assert_eq!(r.rd(0x1080, 64).1, 0);
    r.wr(0x1000, &msg(2, b"next"));
    let (d, _) = r.rd(0x1080, 64);
    assert_eq!((&d[6..10], d[5] >> 4), (&b"next"[..], 2));
    // Length beyond the mailbox: a mailbox error reply (type 0, code 8).
    let mut bad = msg(3, b"x");
    bad[0] = 200;
    r.wr(0x1000, &bad);
    let (d, _) = r.rd(0x1080, 64);
    assert_eq!((d[5] & 0x0F, u16::from_le_bytes([d[8], d[9]])), (0, mailbox_error::INVALID_SIZE));
}

#[test]
fn repeat_request_resends_the_last_message() {
    let mut r = Rig::new();
    r.enter_preop();
    r.wr(0x1000, &msg(1, b"one"));
    let (first, _) = r.rd(0x1080, 64);
    // The master "lost" it: toggle repeat request in SM1's activate register.
    r.wr(0x080E, &[0x03]);
    let (pdi_ctl, _) = r.rd(0x080F, 1);
    assert_eq!(pdi_ctl[0] & 0x02, 0x02, "repeat acknowledged");
    let (again, wkc) = r.rd(0x1080, 64);
    assert_eq!((again, wkc), (first, 1));
    // A response waiting unread is not lost by a repeat.
    r.wr(0x1000, &msg(2, b"two"));
    r.wr(0x080E, &[0x01]);
    let (d, _) = r.rd(0x1080, 64);
    assert_eq!(&d[6..9], b"one", "repeat of the last read message");
    let (d, _) = r.rd(0x1080, 64);
    assert_eq!(&d[6..9], b"two", "then the pending one");
}

#[test]
fn unsolicited_messages_wait_for_a_quiet_mailbox_and_never_overtake() {
    let mut r = Rig::new();
    r.enter_preop();
    r.wr(0x1000, &msg(1, b"req"));
    r.s.app_mut().emcy.push(msg(0, b"emcy")[..10].to_vec());
    // The response goes first.
    let (d, _) = r.rd(0x1080, 64);
    assert_eq!(&d[6..9], b"req");
    // The emergency waits until the mailbox has been quiet for 10 ms.
    assert_eq!(r.rd(0x1080, 64).1, 0);
    r.advance(Duration::from_millis(11));
    let (d, wkc) = r.rd(0x1080, 64);
    assert_eq!((&d[6..10], wkc), (&b"emcy"[..], 1));
}

#[test]
fn leaving_to_init_resets_the_mailbox() {
    let mut r = Rig::new();
    r.enter_preop();
    r.wr(0x1000, &msg(1, b"x"));
    assert_eq!(r.request(1), (0x01, 0));
    assert_eq!(r.s.app().states.last(), Some(&(AlState::PreOp, AlState::Init)));
    r.request(2);
    // Counter memory is gone: counter 1 is a new request again.
    r.rd(0x1080, 64);
    r.wr(0x1000, &msg(1, b"y"));
    assert_eq!(&r.rd(0x1080, 64).0[6..7], b"y");
}

#[test]
fn bootstrap_uses_its_own_mailbox_and_leaves_only_to_init() {
    let mut r = Rig::new();
    r.s.app_mut().boot = true;
    r.mailbox_sms(64);
    assert_eq!(r.request(3), (0x11, 0x0015), "standard mailbox SMs are not the bootstrap ones");
    r.wr(0x0806, &[0]);
    r.wr(0x080E, &[0]);
    r.wr(0x0800, &[0x00, 0x14, 128, 0, 0x26, 0, 1, 0]);
    r.wr(0x0808, &[0x00, 0x16, 128, 0, 0x22, 0, 1, 0]);
    assert_eq!(r.request(0x13), (0x03, 0));
    // The bootstrap mailbox works (the application sees FoE-style traffic).
    let mut m = msg(1, b"boot");
    m.resize(128, 0);
    r.wr(0x1400, &m);
    assert_eq!(&r.rd(0x1600, 128).0[6..10], b"boot");
    assert_eq!(r.request(2), (0x13, 0x0011), "BOOT -> PRE-OP is not allowed");
    assert_eq!(r.request(0x11), (0x01, 0));
}

/// An ESC in device emulation (SII word 0 high byte bit 0, like an EL2004):
/// the AL status follows the AL control without checks, and the firmware
/// follows it with the process data of the SMs as the master set them up.
#[test]
fn device_emulation_state_is_followed_with_process_data() {
    let img = SiiImage::builder()
        .config(crate::sii::ConfigArea { pdi_control: 0x0104, ..Default::default() })
        .identity(2, 0x07D4_3052, 0x0010_0000, 0)
        .fmmus(&[fmmu_usage::OUTPUTS])
        .sync_manager(SiiSyncManager { start: 0x0F00, length: 1, control: 0x44, enable: 9, sm_type: 3 })
        .build();
    let esc = Esc::new(EscConfig::with_sii(img));
    assert!(esc.device_emulation());
    let mut r = Rig { s: Slave::new(esc, App::default(), SlaveConfig::default()), t: Instant::ZERO };
    r.dg(DatagramCommand::Apwr, position_address(0, 0x0010), &[0x00, 0x10]);
    // The test app wants 2 output bytes: SM0 set up for them, no mailbox.
    r.wr(0x0800, &[0x00, 0x0F, 2, 0, 0x44, 0, 1, 0]);
    assert_eq!(r.request(2), (0x02, 0));
    assert_eq!(r.request(4), (0x04, 0), "no checks: the ESC sets the state");
    assert_eq!(r.request(8), (0x08, 0));
    r.wr(0x0F00, &[0x5A, 0xA5]);
    assert_eq!(r.s.app().outputs.last().map(|o| o.0.clone()), Some(vec![0x5A, 0xA5]));
    assert_eq!(r.s.state(), AlState::Op);
    assert_eq!(
        r.s.app().states,
        vec![
            (AlState::Init, AlState::PreOp),
            (AlState::PreOp, AlState::SafeOp),
            (AlState::SafeOp, AlState::Op)
        ]
    );
    r.request(1);
    assert_eq!(r.s.state(), AlState::Init);
}
