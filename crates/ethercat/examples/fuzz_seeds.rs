//! Writes the seed corpus of `fuzz/fuzz_targets/esc_segment.rs` from real
//! ethercrab traffic: ethercrab 0.7.1 runs the digital I/O scenario (free
//! run, then DC) over the in-process link against a line of three slaves,
//! the host captures every frame, and the master's frames are cut into
//! windows of consecutive frames in the target's record format
//! (`len u16, time step u8, frame`).
//!
//! ```text
//! cargo run -p drivebus-ethercat --example fuzz_seeds -- fuzz/seeds/esc_segment
//! ```

use drivebus_can::{Duration, Instant};
use drivebus_ethercat::dio::{self, DioConfig};
use drivebus_ethercat::probe::{self, ScenarioConfig};
use drivebus_ethercat::{BoxDevice, Clock, Host, link};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts};
use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption;
use pcap_file::pcapng::{Block, PcapNgReader};
use std::io::Write;
use std::sync::{Arc, Mutex};

type Storage = PduStorage<16, { PduStorage::element_size(1100) }>;
static FREE: Storage = PduStorage::new();
static DC: Storage = PduStorage::new();

#[derive(Clone, Default)]
struct Shared(Arc<Mutex<Vec<u8>>>);

impl Write for Shared {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().map_err(|_| std::io::Error::other("poisoned"))?.extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

async fn session(storage: &'static Storage, dc: bool) -> Vec<Vec<u8>> {
    let clock = Clock::simulated(Instant::from_millis(1));
    let cfgs: Vec<DioConfig> = [8u8, 16, 8]
        .iter()
        .enumerate()
        .map(|(i, &channels)| DioConfig {
            channels,
            mask: 0x5A ^ i as u32,
            serial: i as u32,
            ..DioConfig::default()
        })
        .collect();
    let devices: Vec<BoxDevice> = cfgs.iter().map(|c| Box::new(dio::slave(c)) as BoxDevice).collect();
    let host = Host::line(devices, clock.clone());
    let cap = Shared::default();
    host.set_capture(Box::new(cap.clone()), "inprocess").expect("capture");
    let (tx, rx, pdu_loop) = storage.try_split().expect("split once");
    tokio::spawn(link::run(host.clone(), tx, rx));
    let md = MainDevice::new(
        pdu_loop,
        Timeouts::default(),
        MainDeviceConfig { dc_static_sync_iterations: 8, ..MainDeviceConfig::default() },
    );
    let clk: &'static Clock = Box::leak(Box::new(clock));
    let cfg = ScenarioConfig {
        masks: cfgs.iter().map(|c| c.mask).collect(),
        cycles: 12,
        cycle: Duration::from_millis(1),
        dc: dc.then_some(Duration::from_millis(1)),
        watchdog_units: 1000,
    };
    let h = host.clone();
    let r = probe::run(
        &md,
        move || clk.ethercat_ns(),
        &cfg,
        move |d| {
            h.advance(d);
            std::future::ready(())
        },
    )
    .await
    .expect("scenario");
    assert_eq!(r.bad_wkc + r.bad_data, 0, "{}", r.summary());
    host.stop_capture().expect("flush");
    let bytes = cap.0.lock().expect("capture").clone();
    let mut reader = PcapNgReader::new(&bytes[..]).expect("pcapng");
    let mut frames = Vec::new();
    while let Some(b) = reader.next_block() {
        if let Ok(Block::EnhancedPacket(p)) = b
            && p.options.contains(&EnhancedPacketOption::Flags(1))
        {
            frames.push(p.data.to_vec());
        }
    }
    frames
}

fn record(out: &mut Vec<u8>, frame: &[u8]) {
    out.extend_from_slice(&(frame.len() as u16).to_le_bytes());
    out.push(1); // 10 µs between frames
    out.extend_from_slice(frame);
}

#[tokio::main(flavor = "current_thread")]
async fn main() {
    let dir = std::env::args().nth(1).expect("usage: fuzz_seeds OUTPUT_DIR");
    std::fs::create_dir_all(&dir).expect("create output dir");
    let mut written = 0;
    for (name, frames) in [("free-run", session(&FREE, false).await), ("dc", session(&DC, true).await)] {
        // Windows of consecutive frames, spread over the session so the
        // seeds cover discovery, SII, DC setup, state changes and cycles.
        let window = 48;
        let starts: Vec<usize> = (0..12).map(|k| k * frames.len().saturating_sub(window) / 11).collect();
        for (k, s) in starts.into_iter().enumerate() {
            let mut seed = Vec::new();
            for f in frames.iter().skip(s).take(window) {
                record(&mut seed, f);
            }
            std::fs::write(format!("{dir}/ethercrab-{name}-{k:02}"), seed).expect("write seed");
            written += 1;
        }
        println!("{name}: {} master frames", frames.len());
    }
    println!("{written} seeds in {dir}");
}
