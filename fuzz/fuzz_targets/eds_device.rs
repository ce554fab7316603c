//! Any file a device may be built from (`serve --device FILE:NODE`):
//! reading it, building the node it describes (and the CiA 401 module
//! when 1000h says so), booting it, starting it and a SYNC must give a
//! device or an error, never a panic.
#![no_main]

use drivebus_can::{Device, Frame, Instant};
use drivebus_node::{EdsOptions, MemoryStorage, Node, NodeDevice};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok(p) = drivebus_eds::parse(&text) else { return };
    let opts = EdsOptions { eds_object: data.len() % 2 == 0 };
    let Ok((mut node, _)) = Node::from_eds(&p.eds, &text, 5, Box::new(MemoryStorage::new()), opts) else {
        return;
    };
    let mut out: Vec<Frame> = Vec::new();
    let now = Instant::from_nanos(1);
    if drivebus_cia401::is_io_module(node.config().device_type) {
        let io = drivebus_cia401::IoModule::install(&mut node);
        let mut dev = NodeDevice::new(node, io);
        dev.app.set_input_line(1, true);
        dev.app.set_analog_input(1, 1000);
        dev.start(Instant::ZERO, &mut out);
        dev.handle_frame(&Frame::new(0, &[1, 5]), now, &mut out);
        dev.handle_frame(&Frame::new(0x80, &[]), now, &mut out);
        dev.poll(now, &mut out);
    } else {
        let mut dev = NodeDevice::new(node, drivebus_od::NoHooks);
        dev.start(Instant::ZERO, &mut out);
        dev.handle_frame(&Frame::new(0, &[1, 5]), now, &mut out);
        dev.handle_frame(&Frame::new(0x80, &[]), now, &mut out);
        dev.handle_frame(&Frame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), now, &mut out);
        dev.poll(now, &mut out);
    }
});
