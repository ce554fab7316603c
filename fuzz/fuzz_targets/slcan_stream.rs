//! Bytes on an slcan serial line, cut anywhere: the line splitter, the frame
//! parser and the adapter emulator must never panic.
#![no_main]

use drivebus_transport::slcan::codec::{LineSplitter, Token, parse_frame};
use drivebus_transport::slcan::device::SlcanDevice;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut lines = LineSplitter::new();
    let mut dev = SlcanDevice::new();
    let mut reply = Vec::new();
    let cut = usize::from(data.first().copied().unwrap_or(1)).max(1);
    for chunk in data.chunks(cut) {
        lines.feed(chunk, |t| {
            if let Token::Line(l) = t {
                let _ = parse_frame(l);
                let _ = dev.handle_line(l, &mut reply);
            }
        });
    }
});
