//! The personality hook (`DriveExtension`): manufacturer statusword bits
//! 8/14/15 and bit 9 *remote* (CiA 402-2 §6.2.2), and write vetoes by drive
//! state (a 1010h store refused while enabled or operational, 0800 0022).

mod drive_rig;

use core::sync::atomic::{AtomicBool, Ordering};
use drive_rig::Rig;
use drivebus_cia402::drive::{DriveConfig, DriveExtension, DriveView, Extension};
use drivebus_cia402::state_machine::State;
use drivebus_od::SdoAbort;
use std::sync::Arc;

#[derive(Default)]
struct Ssd630 {
    enable_input: AtomicBool,
}

impl DriveExtension for Ssd630 {
    fn status_bits(&self, view: &DriveView) -> u16 {
        let remote = self.enable_input.load(Ordering::Relaxed);
        // Bit 8 and 14 set, bit 15 off; bit 9 follows the input.
        (1 << 8) | (1 << 14) | u16::from(remote) << 9 | (view.statusword & 0x00FF)
    }
    fn check_write(&self, view: &DriveView, index: u16, _sub: u8, _data: &[u8]) -> Result<(), SdoAbort> {
        if index == 0x6040 && !self.enable_input.load(Ordering::Relaxed) {
            return Err(SdoAbort::LOCAL_CONTROL);
        }
        if index == 0x1010 && (view.state == State::OperationEnabled || view.operational) {
            return Err(SdoAbort::DEVICE_STATE);
        }
        Ok(())
    }
}

fn rig() -> (Rig, Arc<Ssd630>) {
    let ext = Arc::new(Ssd630::default());
    let cfg = DriveConfig { extension: Extension::new(ext.clone()), ..DriveConfig::default() };
    (Rig::with_config(cfg), ext)
}

#[test]
fn extension_sets_manufacturer_bits_and_remote() {
    let (mut rig, ext) = rig();
    let sw = rig.statusword();
    // Switch on disabled (bit 6), bits 8 and 14 from the hook, remote off.
    assert_eq!(sw & 0xC34F, 0x4140, "sw {sw:04X}");
    ext.enable_input.store(true, Ordering::Relaxed);
    rig.run_ms(0.5);
    let sw = rig.statusword();
    assert_eq!(sw & 0xC34F, 0x4340, "sw {sw:04X}");
}

#[test]
fn local_control_refuses_the_controlword() {
    let (mut rig, ext) = rig();
    rig.write_aborts(0x6040, 0, &6u16.to_le_bytes(), 0x0800_0021);
    ext.enable_input.store(true, Ordering::Relaxed);
    rig.enable();
    rig.run_ms(1.0);
    assert_eq!(rig.statusword() & 0x6F, 0x27, "operation enabled");
}

#[test]
fn store_refused_while_enabled_or_operational() {
    let (mut rig, ext) = rig();
    ext.enable_input.store(true, Ordering::Relaxed);
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
fn no_extension_keeps_remote_from_config() {
    let mut rig = Rig::with_config(DriveConfig { remote: false, ..DriveConfig::default() });
    assert_eq!(rig.statusword() & 0xC300, 0);
    let mut rig = Rig::generic();
    assert_eq!(rig.statusword() & 0xC300, 0x0200);
}
