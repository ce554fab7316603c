//! A line of three emulated EtherCAT slaves (two digital I/O slaves and a
//! mailbox echo slave, firmware included) fed any sequence of Ethernet
//! frames and time steps: nothing may panic, and afterwards a broadcast
//! read of the ESC type must still be counted by every slave the frame
//! reaches.
#![no_main]

use drivebus_can::{Duration, Instant};
use drivebus_esc::frame::{DatagramCommand, FrameBuilder, datagrams, station_address};
use drivebus_esc::segment::{SegmentDevice, Segment, SegmentConfig};
use drivebus_esc::sii::{MailboxArea, SiiImage, SiiSyncManager, protocols};
use drivebus_esc::slave::{MailboxOut, ProcessDataSizes, Slave, SlaveApp, SlaveConfig};
use drivebus_esc::{Esc, EscConfig};
use drivebus_ethercat::dio::{self, DioConfig};
use libfuzzer_sys::fuzz_target;

struct Echo;

impl SlaveApp for Echo {
    fn process_data_sizes(&self) -> ProcessDataSizes {
        ProcessDataSizes { output_bits: 16, input_bits: 16 }
    }
    fn mailbox(&mut self, request: &[u8], _now: Instant, out: &mut MailboxOut<'_>) {
        out.respond(request);
        out.unsolicited(request);
    }
    fn inputs(&mut self, data: &mut [u8], _now: Instant) {
        data.fill(0xA5);
    }
}

fn echo() -> Slave<Echo> {
    let sii = SiiImage::builder()
        .identity(1, 2, 3, 4)
        .mailbox(MailboxArea { rx_offset: 0x1000, rx_size: 64, tx_offset: 0x1080, tx_size: 64 }, protocols::COE)
        .sync_manager(SiiSyncManager { start: 0x1000, length: 64, control: 0x26, enable: 1, sm_type: 1 })
        .sync_manager(SiiSyncManager { start: 0x1080, length: 64, control: 0x22, enable: 1, sm_type: 2 })
        .sync_manager(SiiSyncManager { start: 0x1100, length: 0, control: 0x64, enable: 1, sm_type: 3 })
        .sync_manager(SiiSyncManager { start: 0x1200, length: 0, control: 0x20, enable: 1, sm_type: 4 })
        .build();
    Slave::new(Esc::new(EscConfig::with_sii(sii)), Echo, SlaveConfig::default())
}

fuzz_target!(|data: &[u8]| {
    let devices: Vec<Box<dyn SegmentDevice>> = vec![
        Box::new(dio::slave(&DioConfig::default())),
        Box::new(dio::slave(&DioConfig { channels: 16, ..DioConfig::default() })),
        Box::new(echo()),
    ];
    let mut seg = Segment::with_devices(SegmentConfig::default(), devices);
    let mut now = Instant::ZERO;
    let mut buf = [0u8; 2048];
    // Records: length (u16, 11 bits), time step (10 µs units), frame bytes.
    let mut p = 0;
    while p + 3 <= data.len() {
        let len = usize::from(u16::from_le_bytes([data[p], data[p + 1]]) & 0x07FF);
        now += Duration::from_micros(u64::from(data[p + 2]) * 10);
        p += 3;
        let end = (p + len).min(data.len());
        let frame = &mut buf[..end - p];
        frame.copy_from_slice(&data[p..end]);
        seg.process_frame(frame, now);
        seg.poll(now);
        p = end;
    }
    now += Duration::from_millis(200);
    seg.poll(now);
    let mut f = [0u8; 64];
    let mut b = FrameBuilder::new(&mut f, [0x10; 6]);
    b.push(DatagramCommand::Brd, 0, station_address(0, 0), &[0]).expect("fits");
    let n = b.finish();
    let r = seg.process_frame(&mut f[..n], now);
    let d = datagrams(&f[14..n]).next().expect("one datagram");
    assert_eq!(usize::from(d.wkc), r.reached);
    assert_eq!(d.data[0], 0x04);
});
