//! ethercrab 0.7.1 against a line of drivebus digital I/O slaves in one
//! process, in real time (no root, no network): discovery, OP, 2000 cycles
//! at 1 ms, then the same with DC SYNC0, and a pcapng capture for
//! Wireshark.
//!
//! ```text
//! cargo run --release -p drivebus-ethercat --example inprocess -- [SLAVES] [trace.pcapng]
//! ```

use drivebus_can::Duration;
use drivebus_ethercat::dio::{self, DioConfig};
use drivebus_ethercat::probe::{self, ScenarioConfig};
use drivebus_ethercat::{BoxDevice, Clock, Host, link};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts};

static PDU_STORAGE: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();

#[tokio::main(flavor = "current_thread")]
async fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(4);
    let pcap = args.next();
    let cfgs: Vec<DioConfig> = (0..n)
        .map(|i| DioConfig { channels: 8, mask: 0x5A ^ i as u32, serial: i as u32, ..DioConfig::default() })
        .collect();
    let devices: Vec<BoxDevice> = cfgs.iter().map(|c| Box::new(dio::slave(c)) as BoxDevice).collect();
    let clock = Clock::real();
    let host = Host::line(devices, clock.clone());
    if let Some(p) = &pcap {
        let f = std::fs::File::create(p).expect("create capture");
        host.set_capture(Box::new(std::io::BufWriter::new(f)), "inprocess").expect("capture");
    }
    let (tx, rx, pdu_loop) = PDU_STORAGE.try_split().expect("split once");
    tokio::spawn(link::run(host.clone(), tx, rx));
    let md = MainDevice::new(pdu_loop, Timeouts::default(), MainDeviceConfig::default());
    let clk: &'static Clock = Box::leak(Box::new(clock));
    for dc in [None, Some(Duration::from_millis(1))] {
        let cfg = ScenarioConfig {
            masks: cfgs.iter().map(|c| c.mask).collect(),
            cycles: 2000,
            cycle: Duration::from_millis(1),
            dc,
            watchdog_units: 10_000,
        };
        let r = probe::run(&md, move || clk.ethercat_ns(), &cfg, tokio::time::sleep).await.expect("scenario");
        for f in &r.found {
            println!("{:#06x} {} serial {} delay {} ns", f.address, f.name, f.serial, f.propagation_delay);
        }
        println!("{}: {}", if dc.is_some() { "DC" } else { "free run" }, r.summary());
    }
    host.stop_capture().expect("flush capture");
    println!("{:?}", host.stats());
}
