//! SocketCAN: runs only where the kernel has AF_CAN and a `vcan0`.
#![cfg(target_os = "linux")]

use std::io::{self, Write};

use drivebus_transport::{Frame, open};

/// Says the test was skipped on the real stderr: libtest captures
/// `eprintln!` of passing tests, and a skip must never look like a pass.
fn skip(why: &str) {
    let _ = writeln!(io::stderr(), "skipped: {why}");
}

#[tokio::test]
async fn vcan0_or_skip() {
    let a = match open("socketcan://vcan0").await {
        Ok(bus) => bus,
        Err(e) => {
            let io_err = std::error::Error::source(&e).and_then(|s| s.downcast_ref::<io::Error>());
            let raw = io_err.and_then(io::Error::raw_os_error);
            // EAFNOSUPPORT (97): no AF_CAN at all; ENODEV (19): no vcan0
            // interface (what a kernel without SocketCAN/vcan gives first).
            match raw {
                Some(97) => {
                    skip(&format!("this kernel has no SocketCAN ({e})"));
                    return;
                }
                Some(19) => {
                    skip(&format!("no vcan0 interface, this kernel has no SocketCAN/vcan ({e})"));
                    return;
                }
                _ => {}
            }
            panic!("unexpected SocketCAN error: {e}");
        }
    };
    let mut b = open("socketcan://vcan0").await.unwrap();
    a.send(Frame::new(0x123, &[1, 2])).await.unwrap();
    let got = tokio::time::timeout(std::time::Duration::from_secs(2), b.recv()).await.unwrap().unwrap();
    assert_eq!(got, Frame::new(0x123, &[1, 2]));
}
