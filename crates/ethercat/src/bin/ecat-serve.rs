//! `drivebus-ecat-serve`: puts a line of digital I/O test slaves on a
//! network interface (AF_PACKET, root) for any EtherCAT master.
//!
//! ```text
//! drivebus-ecat-serve --interface veth0 --dio 4 [--pcap trace.pcapng] [--seconds 60]
//! ```
//!
//! Slave i (from 0) has 8 channels when i is even and 16 when odd, and
//! input mask `0x5a5a5a5a ^ (i · 0x01010101)`, as the probe expects.

use drivebus_ethercat::dio::{self, DioConfig};
use drivebus_ethercat::{BoxDevice, Clock, Host, server};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

fn main() -> ExitCode {
    let mut interface = String::new();
    let mut n = 1usize;
    let mut pcap = None;
    let mut seconds = None;
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let v = it.next();
        match (k.as_str(), v) {
            ("--interface", Some(v)) => interface = v,
            ("--dio", Some(v)) => n = v.parse().unwrap_or(1),
            ("--pcap", Some(v)) => pcap = Some(v),
            ("--seconds", Some(v)) => seconds = v.parse::<u64>().ok(),
            _ => {
                eprintln!("usage: drivebus-ecat-serve --interface IF [--dio N] [--pcap FILE] [--seconds S]");
                return ExitCode::from(2);
            }
        }
    }
    let devices: Vec<BoxDevice> = (0..n)
        .map(|i| {
            let cfg = DioConfig {
                channels: if i % 2 == 0 { 8 } else { 16 },
                mask: 0x5A5A_5A5A ^ (i as u32 * 0x0101_0101),
                serial: 100 + i as u32,
                ..DioConfig::default()
            };
            Box::new(dio::slave(&cfg)) as BoxDevice
        })
        .collect();
    let host = Host::line(devices, Clock::real());
    if let Some(p) = pcap {
        match std::fs::File::create(&p) {
            Ok(f) => {
                if let Err(e) = host.set_capture(Box::new(std::io::BufWriter::new(f)), &interface) {
                    eprintln!("{p}: {e}");
                    return ExitCode::from(2);
                }
            }
            Err(e) => {
                eprintln!("{p}: {e}");
                return ExitCode::from(2);
            }
        }
    }
    let stop = Arc::new(AtomicBool::new(false));
    if let Some(s) = seconds {
        let stop = stop.clone();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_secs(s));
            stop.store(true, Ordering::Release);
        });
    }
    println!("serving {n} digital I/O slave(s) on {interface}");
    let r = server::serve(&interface, &host, &stop);
    let _ = host.stop_capture();
    match r {
        Ok(s) => {
            println!("frames={} ignored={}", s.frames, s.ignored);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{interface}: {e}");
            ExitCode::FAILURE
        }
    }
}
