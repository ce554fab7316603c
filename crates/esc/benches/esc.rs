//! Frame processing cost of the emulated ESC.
//!
//! * `fprd_one_slave`, `lrw_one_slave`: one datagram through one ESC.
//! * `fprd_64_line`, `lrw_64_line`: one datagram through a line of 64 ESCs
//!   (every ESC processes it; the FPRD addresses the last one, the LRW maps
//!   4 bytes per slave).
//! * `cycle_64_line`: one 1 ms cycle as ethercrab sends it in DC mode —
//!   FRMW 0x0910 + LRW of the whole image + an FPRD of AL status per slave
//!   in one frame — then a poll of the line, on bare ESCs.
//! * `cycle_64_line_firmware`: the same with slave firmware on every ESC
//!   (state machine in OP, outputs applied and inputs produced per cycle).
//! * `fprd_64_line_firmware`, `lrw_64_line_firmware`: one datagram through
//!   the line of ESCs with firmware, the firmware polled after the frame
//!   as a host does (`Segment::process_frame`).
//! * `fprd_x64_64_line`: one frame of 64 FPRDs (one per slave, as a master
//!   checks AL status) through the bare line: divide by 64 for one
//!   datagram in a full frame.
//!
//! Run: `cargo bench -p drivebus-esc --bench esc`.

// criterion_main! generates an undocumented `main`.
#![allow(missing_docs)]

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use drivebus_base::{Duration, Instant};
use drivebus_esc::fmmu::Fmmu;
use drivebus_esc::frame::{DatagramCommand, FrameBuilder, position_address, station_address};
use drivebus_esc::segment::{Segment, SegmentConfig, SegmentDevice};
use drivebus_esc::sii::{SiiImage, SiiSyncManager};
use drivebus_esc::slave::{ProcessDataSizes, Slave, SlaveApp, SlaveConfig};
use drivebus_esc::{Esc, EscConfig};

fn sii() -> SiiImage {
    SiiImage::builder()
        .identity(0xDB0, 1, 1, 1)
        .sync_manager(SiiSyncManager { start: 0x1000, length: 2, control: 0x64, enable: 1, sm_type: 3 })
        .sync_manager(SiiSyncManager { start: 0x1100, length: 2, control: 0x20, enable: 1, sm_type: 4 })
        .build()
}

struct Loopback([u8; 2]);

impl SlaveApp for Loopback {
    fn process_data_sizes(&self) -> ProcessDataSizes {
        ProcessDataSizes { output_bits: 16, input_bits: 16 }
    }
    fn outputs(&mut self, data: &[u8], _now: Instant) {
        self.0.copy_from_slice(data);
    }
    fn inputs(&mut self, data: &mut [u8], _now: Instant) {
        data.copy_from_slice(&self.0);
    }
}

/// Sends one frame with one datagram through `dev`.
fn send<D: SegmentDevice>(seg: &mut Segment<D>, cmd: DatagramCommand, addr: u32, data: &[u8]) {
    let mut buf = [0u8; 256];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(cmd, 0, addr, data).unwrap();
    let n = b.finish();
    seg.process_frame(&mut buf[..n], Instant::ZERO);
}

/// Configures every slave as a master would: address, SM0 outputs / SM1
/// inputs (2 bytes each, 3-buffer), FMMU0/1 at logical 4·i, DC, AL OP.
fn configure<D: SegmentDevice>(seg: &mut Segment<D>) {
    let n = seg.len();
    for i in 0..n as u16 {
        send(seg, DatagramCommand::Apwr, position_address(i, 0x0010), &(0x1000 + i).to_le_bytes());
    }
    for i in 0..n as u16 {
        let a = 0x1000 + i;
        send(seg, DatagramCommand::Fpwr, station_address(a, 0x0800), &[0x00, 0x10, 2, 0, 0x64, 0, 1, 0]);
        send(seg, DatagramCommand::Fpwr, station_address(a, 0x0808), &[0x00, 0x11, 2, 0, 0x20, 0, 1, 0]);
        let fmmu = |logical: u32, phys: u16, read: bool| Fmmu {
            logical_start: logical,
            length: 2,
            logical_start_bit: 0,
            logical_stop_bit: 7,
            physical_start: phys,
            physical_start_bit: 0,
            read,
            write: !read,
            enabled: true,
        };
        let inputs = fmmu(2 * u32::from(i), 0x1100, true);
        let outputs = fmmu(2 * (n as u32 + u32::from(i)), 0x1000, false);
        send(seg, DatagramCommand::Fpwr, station_address(a, 0x0600), &inputs.to_registers());
        send(seg, DatagramCommand::Fpwr, station_address(a, 0x0610), &outputs.to_registers());
    }
    for (state, _) in [(2u8, 0), (4, 0), (8, 0)] {
        send(seg, DatagramCommand::Bwr, station_address(0, 0x0120), &[state, 0]);
        seg.poll(Instant::ZERO);
    }
}

fn one_frame(cmd: DatagramCommand, addr: u32, data: &[u8]) -> ([u8; 1600], usize) {
    let mut buf = [0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(cmd, 0, addr, data).unwrap();
    let n = b.finish();
    (buf, n)
}

fn cycle_frame(n: usize) -> ([u8; 1600], usize) {
    let mut buf = [0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    b.push(DatagramCommand::Frmw, 0, station_address(0x1000, 0x0910), &[0; 8]).unwrap();
    b.push(DatagramCommand::Lrw, 1, 0, &vec![0u8; 4 * n]).unwrap();
    for i in 0..n as u16 {
        b.push(DatagramCommand::Fprd, 2, station_address(0x1000 + i, 0x0130), &[0; 2]).unwrap();
    }
    let len = b.finish();
    (buf, len)
}

fn fprd_per_slave(n: usize) -> ([u8; 1600], usize) {
    let mut buf = [0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]);
    for i in 0..n as u16 {
        b.push(DatagramCommand::Fprd, 2, station_address(0x1000 + i, 0x0130), &[0; 2]).unwrap();
    }
    let len = b.finish();
    (buf, len)
}

fn line(n: usize) -> Segment<Esc> {
    let escs = (0..n).map(|_| Esc::new(EscConfig::with_sii(sii()))).collect();
    let mut s = Segment::with_devices(SegmentConfig::default(), escs);
    configure(&mut s);
    s
}

fn benches(c: &mut Criterion) {
    let mut one = line(1);
    let (mut f, n) = one_frame(DatagramCommand::Fprd, station_address(0x1000, 0x0130), &[0; 2]);
    c.bench_function("fprd_one_slave", |b| {
        b.iter(|| black_box(one.device_mut(0).unwrap().process_frame(black_box(&mut f[..n]), Instant::ZERO)))
    });
    let (mut f, n) = one_frame(DatagramCommand::Lrw, 0, &[0; 4]);
    c.bench_function("lrw_one_slave", |b| {
        b.iter(|| black_box(one.device_mut(0).unwrap().process_frame(black_box(&mut f[..n]), Instant::ZERO)))
    });

    let mut l64 = line(64);
    let (mut f, n) = one_frame(DatagramCommand::Fprd, station_address(0x1000 + 63, 0x0130), &[0; 2]);
    c.bench_function("fprd_64_line", |b| {
        b.iter(|| black_box(l64.process_frame(black_box(&mut f[..n]), Instant::ZERO)))
    });
    let (mut f, n) = one_frame(DatagramCommand::Lrw, 0, &[0; 4 * 64]);
    c.bench_function("lrw_64_line", |b| {
        b.iter(|| black_box(l64.process_frame(black_box(&mut f[..n]), Instant::ZERO)))
    });

    let (mut f, n) = cycle_frame(64);
    let mut t = Instant::ZERO;
    c.bench_function("cycle_64_line", |b| {
        b.iter(|| {
            t += Duration::from_millis(1);
            black_box(l64.process_frame(black_box(&mut f[..n]), t));
            black_box(l64.poll(t))
        })
    });

    let slaves: Vec<Slave<Loopback>> = (0..64)
        .map(|_| Slave::new(Esc::new(EscConfig::with_sii(sii())), Loopback([0; 2]), SlaveConfig::default()))
        .collect();
    let mut fw = Segment::with_devices(SegmentConfig::default(), slaves);
    configure(&mut fw);
    assert!(fw.devices().iter().all(|s| s.esc().al_status() == 0x08), "all in OP");
    let (mut f, n) = fprd_per_slave(64);
    c.bench_function("fprd_x64_64_line", |b| {
        b.iter(|| black_box(l64.process_frame(black_box(&mut f[..n]), Instant::ZERO)))
    });
    let (mut f, n) = one_frame(DatagramCommand::Fprd, station_address(0x1000 + 63, 0x0130), &[0; 2]);
    c.bench_function("fprd_64_line_firmware", |b| {
        b.iter(|| black_box(fw.process_frame(black_box(&mut f[..n]), t)))
    });
    let (mut f, n) = one_frame(DatagramCommand::Lrw, 0, &[0; 4 * 64]);
    c.bench_function("lrw_64_line_firmware", |b| {
        b.iter(|| black_box(fw.process_frame(black_box(&mut f[..n]), t)))
    });
    let (mut f, n) = cycle_frame(64);
    c.bench_function("cycle_64_line_firmware", |b| {
        b.iter(|| {
            t += Duration::from_millis(1);
            black_box(fw.process_frame(black_box(&mut f[..n]), t));
            black_box(fw.poll(t))
        })
    });
}

criterion_group!(esc, benches);
criterion_main!(esc);
