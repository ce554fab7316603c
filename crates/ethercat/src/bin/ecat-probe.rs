//! `drivebus-ecat-probe`: runs the ethercrab digital I/O scenario
//! ([`drivebus_ethercat::probe`]) on a real interface and prints one
//! summary line. Exit status 0 only if the expected slaves were found and
//! every cycle had the expected working counter and correct data.
//!
//! ```text
//! drivebus-ecat-probe --interface veth1 --slaves 4 --masks 0x5a,0x5b,0x58,0x59 --cycles 5000 [--dc-us 1000]
//! ```

use drivebus_can::Duration;
use drivebus_ethercat::probe::{self, ScenarioConfig};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts, std::ethercat_now};
use std::process::ExitCode;

static PDU_STORAGE: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();

struct Args {
    interface: String,
    slaves: Option<usize>,
    cfg: ScenarioConfig,
    dc_static: u32,
}

fn parse_u64(s: &str) -> Result<u64, String> {
    let r = match s.strip_prefix("0x") {
        Some(h) => u64::from_str_radix(h, 16),
        None => s.parse(),
    };
    r.map_err(|e| format!("{s}: {e}"))
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        interface: String::new(),
        slaves: None,
        cfg: ScenarioConfig {
            masks: Vec::new(),
            cycles: 1000,
            cycle: Duration::from_millis(1),
            dc: None,
            watchdog_units: 10_000,
        },
        dc_static: 2_000,
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or(format!("{k} needs a value"));
        match k.as_str() {
            "--interface" => a.interface = v()?,
            "--slaves" => a.slaves = Some(parse_u64(&v()?)? as usize),
            "--masks" => {
                a.cfg.masks =
                    v()?.split(',').map(|m| parse_u64(m).map(|x| x as u32)).collect::<Result<_, _>>()?
            }
            "--cycles" => a.cfg.cycles = parse_u64(&v()?)? as u32,
            "--cycle-us" => a.cfg.cycle = Duration::from_micros(parse_u64(&v()?)?),
            "--dc-us" => a.cfg.dc = Some(Duration::from_micros(parse_u64(&v()?)?)),
            "--dc-static" => a.dc_static = parse_u64(&v()?)? as u32,
            "--help" | "-h" => {
                return Err(
                    "usage: drivebus-ecat-probe --interface IF [--slaves N] [--masks M,M…] [--cycles N] \
                            [--cycle-us US] [--dc-us US] [--dc-static N]"
                        .into(),
                );
            }
            other => return Err(format!("unknown argument {other}")),
        }
    }
    if a.interface.is_empty() {
        return Err("--interface is required".into());
    }
    Ok(a)
}

fn main() -> ExitCode {
    let a = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let (tx, rx, pdu_loop) = PDU_STORAGE.try_split().expect("split once");
    let task = match ethercrab::std::tx_rx_task(&a.interface, tx, rx) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("cannot open {}: {e}", a.interface);
            return ExitCode::from(2);
        }
    };
    std::thread::spawn(move || async_io::block_on(task));
    let md = MainDevice::new(
        pdu_loop,
        // Generous: a loaded 2-core VM can stall a process for tens of ms;
        // a lost frame still fails the run, a late one does not.
        Timeouts {
            pdu: std::time::Duration::from_secs(1),
            eeprom: std::time::Duration::from_millis(200),
            mailbox_response: std::time::Duration::from_secs(1),
            ..Timeouts::default()
        },
        MainDeviceConfig { dc_static_sync_iterations: a.dc_static, ..MainDeviceConfig::default() },
    );
    let result = async_io::block_on(probe::run(&md, ethercat_now, &a.cfg, |d| async move {
        async_io::Timer::after(d).await;
    }));
    match result {
        Ok(r) => {
            for f in &r.found {
                println!(
                    "slave {:#06x} {} vendor {:#010x} product {:#010x} serial {} delay {} ns in {} B out {} B",
                    f.address,
                    f.name,
                    f.vendor_id,
                    f.product_id,
                    f.serial,
                    f.propagation_delay,
                    f.inputs,
                    f.outputs
                );
            }
            println!("{}", r.summary());
            let count_ok = a.slaves.is_none_or(|n| n == r.found.len());
            if count_ok
                && r.bad_wkc == 0
                && r.bad_data == 0
                && r.cycles == a.cfg.cycles
                && probe::all_drivebus(&r)
            {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            println!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
