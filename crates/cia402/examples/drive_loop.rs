//! Instruction-count instrument for `valgrind --tool=callgrind`: the pp
//! cycle of `benches/drive.rs` (RPDO, SYNC, eight control periods) N times
//! (`drive_loop N`), or its csp cycle (`drive_loop N csp`), so two trees
//! compare instruction-exact.
use drivebus_can::{Duration, Frame, Instant};
use drivebus_cia402::drive::{Drive, DriveConfig, generic_drive, generic_drive_with};
use drivebus_cia402::interp::CspMode;
use drivebus_node::NodeDevice;
const ID: u8 = 1;
fn frame(dn: &mut NodeDevice<Drive>, f: &Frame, t: Instant, out: &mut Vec<Frame>) {
    dn.node.handle_frame(f, t, &mut dn.app, out);
}
fn main() {
    let n: u64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let csp = std::env::args().nth(2).as_deref() == Some("csp");
    let mut dn = if csp {
        generic_drive_with(ID, DriveConfig::default(), vec![Box::new(CspMode::new())])
    } else {
        generic_drive(ID)
    };
    let mut out = Vec::with_capacity(64);
    let mut t = Instant::ZERO;
    dn.node.boot(t, &mut dn.app, &mut out);
    dn.node.poll(t, &mut dn.app, &mut out);
    frame(&mut dn, &Frame::new(0x000, &[0x01, ID]), t, &mut out);
    let mode = if csp { 8 } else { 1 };
    frame(&mut dn, &Frame::new(0x600 + u16::from(ID), &[0x2F, 0x60, 0x60, 0, mode, 0, 0, 0]), t, &mut out);
    for cw in [0x06u16, 0x0F] {
        frame(&mut dn, &Frame::new(0x200 + u16::from(ID), &cw.to_le_bytes()), t, &mut out);
    }
    t += Duration::from_millis(1);
    dn.node.poll(t, &mut dn.app, &mut out);
    out.clear();
    let sync = Frame::new(0x080, &[]);
    for k in 1..=n {
        let target = (90_000.0 * (k as f64 * 1e-3 * std::f64::consts::PI).sin()) as i32;
        // pp: a new set-point each cycle ("change immediately"); csp: the
        // target is taken at SYNC.
        let cw: u16 = if csp {
            0x0F
        } else if k.is_multiple_of(2) {
            0x3F
        } else {
            0x2F
        };
        let mut d = [0u8; 6];
        d[..2].copy_from_slice(&cw.to_le_bytes());
        d[2..].copy_from_slice(&target.to_le_bytes());
        frame(&mut dn, &Frame::new(0x301, &d), t, &mut out);
        frame(&mut dn, &sync, t, &mut out);
        t += Duration::from_millis(1);
        dn.node.poll(t, &mut dn.app, &mut out);
        std::hint::black_box(out.len());
        out.clear();
    }
    assert_eq!(dn.app.statusword() & 0x6F, 0x27);
    println!("{} steps", dn.app.steps());
}
