//! Bytes from a socketcand peer, cut anywhere: the splitter and message
//! parser must never panic, whatever a client or host sends.
#![no_main]

use drivebus_transport::socketcand::proto::{Splitter, parse};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut s = Splitter::new();
    // The first byte decides where the stream is cut, like TCP reads.
    let cut = usize::from(data.first().copied().unwrap_or(1)).max(1);
    for chunk in data.chunks(cut) {
        s.feed(chunk, |msg| {
            let _ = parse(msg);
        });
    }
});
