//! A personality-style application wrapping the drive: manufacturer
//! statusword bits 8/14/15 and bit 9 *remote* (CiA 402-2 §6.2.2), and
//! write vetoes by drive state on objects other owners hold (a 1010h store
//! refused while enabled or operational, 0800 0022) — the watcher's veto
//! step of the write path.

mod drive_rig;

use drive_rig::{ID, Rig};
use drivebus_cia402::drive::{Drive, DriveConfig, generic_drive};
use drivebus_cia402::state_machine::State;
use drivebus_node::{AppContext, Application, NodeDevice, NodeEvent, Request};
use drivebus_od::{ObjectDictionary, SdoAbort, Target, WriteOutcome};

/// SSD 630 style: *remote* follows an enable input; no controlword without
/// it; no 1010h store while the drive is enabled or the node operational.
struct Ssd630 {
    drive: Drive,
    enable_input: bool,
}

fn standard(code: u16) -> Request {
    Request::RaiseEmcy { code, register: None, manufacturer: [0; 5] }
}

impl Ssd630 {
    /// Bits 8 and 14 set, bit 15 off, bit 9 follows the input.
    fn patch(&self, od: &mut ObjectDictionary) {
        let sw = self.drive.statusword();
        let mine = (1 << 8) | (1 << 14) | u16::from(self.enable_input) << 9 | (sw & 0x00FF);
        if let Ok(r) = od.find(0x6041, 0) {
            od.set_le(r, &mine.to_le_bytes());
        }
    }
}

impl Application for Ssd630 {
    fn check_write(
        &mut self,
        cx: &mut AppContext<'_>,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        if at.index == 0x6040 && !self.enable_input {
            return Err(SdoAbort::LOCAL_CONTROL);
        }
        let v = self.drive.view();
        if at.index == 0x1010 && (v.state == State::OperationEnabled || v.operational) {
            return Err(SdoAbort::DEVICE_STATE);
        }
        let r = self.drive.check_object(cx.od, at, data);
        self.drive.flush_emcy(cx, standard);
        r
    }
    fn apply_write(&mut self, cx: &mut AppContext<'_>, at: &Target) {
        self.drive.apply_object(cx.od, at);
        self.drive.flush_emcy(cx, standard);
        self.patch(cx.od);
    }
    fn on_read(&mut self, cx: &mut AppContext<'_>, at: &Target) -> Result<(), SdoAbort> {
        self.drive.refresh_object(cx.od, at);
        Ok(())
    }
    fn on_sync(&mut self, cx: &mut AppContext<'_>, _: Option<u8>) {
        self.drive.sync(cx.od);
        self.drive.flush_emcy(cx, standard);
        self.patch(cx.od);
    }
    fn on_event(&mut self, cx: &mut AppContext<'_>, event: NodeEvent) {
        self.drive.event(cx.od, event);
        self.drive.flush_emcy(cx, standard);
        self.patch(cx.od);
    }
    fn poll(&mut self, cx: &mut AppContext<'_>) -> Option<drivebus_can::Instant> {
        let next = self.drive.step_to(cx.od, cx.now);
        self.drive.flush_emcy(cx, standard);
        self.patch(cx.od);
        Some(next)
    }
}

fn rig() -> Rig<Ssd630> {
    let dn = generic_drive(ID);
    let mut node = dn.node;
    // The application watches 1010h, which the node's store service owns.
    for s in 1..=4 {
        node.od_mut().get_mut(0x1010, s).expect("1010h").watched = true;
    }
    Rig::with(NodeDevice::new(node, Ssd630 { drive: dn.app, enable_input: false }))
}

#[test]
fn wrapper_sets_manufacturer_bits_and_remote() {
    let mut rig = rig();
    let sw = rig.statusword();
    // Switch on disabled (bit 6), bits 8 and 14 from the wrapper, remote off.
    assert_eq!(sw & 0xC34F, 0x4140, "sw {sw:04X}");
    rig.dn_mut().app.enable_input = true;
    rig.run_ms(0.5);
    let sw = rig.statusword();
    assert_eq!(sw & 0xC34F, 0x4340, "sw {sw:04X}");
}

#[test]
fn local_control_refuses_the_controlword() {
    let mut rig = rig();
    rig.write_aborts(0x6040, 0, &6u16.to_le_bytes(), 0x0800_0021);
    rig.dn_mut().app.enable_input = true;
    rig.enable();
    rig.run_ms(1.0);
    assert_eq!(rig.statusword() & 0x6F, 0x27, "operation enabled");
}

#[test]
fn store_refused_while_enabled_or_operational() {
    let mut rig = rig();
    rig.dn_mut().app.enable_input = true;
    let save = u32::from_le_bytes(*b"save").to_le_bytes();
    // Pre-operational, switch on disabled: allowed.
    rig.write(0x1010, 1, &save);
    rig.enable();
    rig.run_ms(1.0);
    rig.write_aborts(0x1010, 1, &save, 0x0800_0022);
    rig.controlword(0x06);
    rig.run_ms(1.0);
    rig.write(0x1010, 1, &save);
    rig.start();
    rig.write_aborts(0x1010, 1, &save, 0x0800_0022);
}

#[test]
fn the_drive_alone_keeps_remote_from_config() {
    let mut rig = Rig::with_config(DriveConfig { remote: false, ..DriveConfig::default() });
    assert_eq!(rig.statusword() & 0xC300, 0);
    let mut rig = Rig::generic();
    assert_eq!(rig.statusword() & 0xC300, 0x0200);
}
