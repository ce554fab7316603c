//! ethercrab's frames of one cycle of an iPOS line, recorded once and
//! replayed: shared by the `drive_line` bench and the `drive_line_loop`
//! example (instruction counts under callgrind).

use crate::ipos_line;
use drivebus_can::{Duration, Instant};
use drivebus_esc::frame::{DatagramCommand, FrameBuilder, station_address};
use drivebus_ethercat::drive::DriveLine;
use drivebus_ethercat::{Clock, Host};
use drivebus_personality::Profile;
use ethercrab::{MainDevice, MainDeviceConfig, PduRx, PduStorage, PduTx, Timeouts};
use std::future::Future;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll};

/// ethercrab's PDU storage for one line.
pub type Storage = PduStorage<16, { PduStorage::element_size(1500) }>;

/// ethercrab's frames straight through the host (as `link::run` does on
/// simulated time), copied as sent while `recording` is set.
struct RecordingLink<'sto> {
    host: Host,
    tx: PduTx<'sto>,
    rx: PduRx<'sto>,
    recording: Arc<AtomicBool>,
    frames: Arc<Mutex<Vec<Vec<u8>>>>,
}

impl Future for RecordingLink<'_> {
    type Output = ();

    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        let this = self.get_mut();
        this.tx.replace_waker(cx.waker());
        if this.tx.should_exit() {
            return Poll::Ready(());
        }
        let mut buf = [0u8; 1600];
        while let Some(frame) = this.tx.next_sendable_frame() {
            let mut len = 0;
            frame
                .send_blocking(|data| {
                    buf[..data.len()].copy_from_slice(data);
                    len = data.len();
                    Ok(len)
                })
                .expect("send");
            if this.recording.load(Ordering::Acquire) {
                this.frames.lock().unwrap().push(buf[..len].to_vec());
            }
            this.host.process_frame(&mut buf[..len]);
            this.rx.receive_frame(&buf[..len]).expect("ethercrab takes the reply");
        }
        Poll::Pending
    }
}

/// The frames ethercrab sent while recording.
pub type Recorded = Arc<Mutex<Vec<Vec<u8>>>>;

/// ethercrab's main device on `host`'s line, its frames going straight
/// through the host on a thread of their own, and what it sends copied into
/// the returned list while the returned flag is set.
pub fn recording_main_device(
    host: &Host,
    storage: &'static Storage,
) -> (MainDevice<'static>, Arc<AtomicBool>, Recorded) {
    let (tx, rx, pdu_loop) = storage.try_split().expect("split once");
    let recording = Arc::new(AtomicBool::new(false));
    let frames = Arc::new(Mutex::new(Vec::new()));
    let link =
        RecordingLink { host: host.clone(), tx, rx, recording: recording.clone(), frames: frames.clone() };
    std::thread::spawn(move || async_io::block_on(link));
    let md = MainDevice::new(
        pdu_loop,
        // Real-time timeouts on a loaded 2-core host: generous, since the
        // slaves answer at once and only scheduling can delay a reply.
        Timeouts {
            state_transition: std::time::Duration::from_secs(20),
            pdu: std::time::Duration::from_secs(2),
            eeprom: std::time::Duration::from_secs(2),
            mailbox_echo: std::time::Duration::from_secs(2),
            mailbox_response: std::time::Duration::from_secs(5),
            ..Timeouts::default()
        },
        MainDeviceConfig { dc_static_sync_iterations: 1_000, ..MainDeviceConfig::default() },
    );
    (md, recording, frames)
}

/// A line of `n` iPOS in OP, every drive enabled, and ethercrab's frames
/// of one cycle.
pub fn line_in_op(n: usize, storage: &'static Storage) -> (Host, Vec<Vec<u8>>) {
    let clock = Clock::simulated(Instant::from_millis(1));
    let line = (0..n).fold(DriveLine::new(), |l, _| l.drive(Profile::Ipos));
    let host = line.host(clock.clone()).expect("line");
    let (md, recording, frames) = recording_main_device(&host, storage);
    // ethercrab wants a `Copy` clock function.
    let c: &'static Clock = Box::leak(Box::new(clock.clone()));
    let h = host.clone();
    const CYCLES: u32 = 300;
    let r = async_io::block_on(ipos_line::run(
        &md,
        move || c.ethercat_ns(),
        CYCLES,
        move |d| {
            h.advance(Duration::from_nanos(d.as_nanos() as u64));
            std::future::ready(())
        },
        |k| recording.store(k == CYCLES - 1, Ordering::Release),
    ))
    .expect("ethercrab brings the line to OP");
    assert_eq!((r.slaves, r.enabled, r.bad_wkc), (n, n, 0), "{r:?}");
    let frames = frames.lock().unwrap().clone();
    assert!(!frames.is_empty());
    (host, frames)
}

/// A frame's datagrams as (command, data length) (the `io_line` example prints them).
#[allow(dead_code)] // not every includer prints frames
pub fn datagrams(frame: &[u8]) -> Vec<(u8, usize)> {
    let (mut off, mut out) = (16, Vec::new());
    while off + 12 <= frame.len() {
        let word = u16::from_le_bytes([frame[off + 6], frame[off + 7]]);
        let len = usize::from(word & 0x7FF);
        out.push((frame[off], len));
        if word & 0x8000 == 0 {
            break;
        }
        off += 12 + len;
    }
    out
}

/// The working counters of a frame's LRW datagrams.
pub fn lrw_wkc(frame: &[u8]) -> u16 {
    // Ethernet header 14, EtherCAT header 2; each datagram: 10-byte header
    // (command, index, address, length with the "more" bit 15), data, WKC.
    let (mut off, mut sum) = (16, 0);
    loop {
        let word = u16::from_le_bytes([frame[off + 6], frame[off + 7]]);
        let len = usize::from(word & 0x7FF);
        if frame[off] == DatagramCommand::Lrw as u8 {
            sum += u16::from_le_bytes([frame[off + 10 + len], frame[off + 11 + len]]);
        }
        if word & 0x8000 == 0 {
            return sum;
        }
        off += 12 + len;
    }
}

/// One cycle: `frames` through the line, then the clock to the next 1 ms.
pub fn cycle(host: &Host, frames: &[Vec<u8>], buf: &mut [u8]) -> u16 {
    let start = host.clock().now();
    let mut wkc = 0;
    for f in frames {
        let b = &mut buf[..f.len()];
        b.copy_from_slice(f);
        host.process_frame(b);
        wkc += lrw_wkc(b);
    }
    let next = start + Duration::from_millis(1);
    host.advance(next.saturating_duration_since(host.clock().now()));
    wkc
}

/// One frame polling every slave's mailbox.
pub fn mailbox_polls(n: usize) -> Vec<u8> {
    let mut buf = vec![0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    for i in 0..n as u16 {
        // SM1 status byte (0x080D): "mailbox full" tells the master to read.
        b.push(DatagramCommand::Fprd, i as u8, station_address(0x1000 + i, 0x080D), &[0]).unwrap();
    }
    let len = b.finish();
    buf.truncate(len);
    buf
}
