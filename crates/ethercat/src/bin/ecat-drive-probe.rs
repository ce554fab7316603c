//! `drivebus-ecat-drive-probe`: runs the ethercrab drive scenario
//! ([`drivebus_ethercat::drive_probe`]) on a real interface and prints one
//! summary line. Exit status 0 only if the expected drives were found,
//! every cycle had the expected working counter and every drive followed
//! its csp sine within its following error window.
//!
//! ```text
//! drivebus-ecat-drive-probe --interface veth1 --drives 4 --cycles 5000 [--dc-us 1000] [--remap]
//! ```

use drivebus_can::Duration;
use drivebus_ethercat::drive_probe::{self, DriveScenario};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts, std::ethercat_now};
use std::process::ExitCode;

static PDU_STORAGE: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();

fn parse(s: &str) -> Result<u64, String> {
    s.parse().map_err(|e| format!("{s}: {e}"))
}

fn args() -> Result<(String, Option<usize>, DriveScenario), String> {
    let (mut interface, mut drives, mut s) = (String::new(), None, DriveScenario::default());
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or(format!("{k} needs a value"));
        match k.as_str() {
            "--interface" => interface = v()?,
            "--drives" => drives = Some(parse(&v()?)? as usize),
            "--cycles" => s.cycles = parse(&v()?)? as u32,
            "--dc-us" => s.dc = Some(Duration::from_micros(parse(&v()?)?)),
            "--remap" => s.remap = true,
            _ => {
                return Err("usage: drivebus-ecat-drive-probe --interface IF [--drives N] [--cycles N] \
                            [--dc-us US] [--remap]"
                    .into());
            }
        }
    }
    if interface.is_empty() {
        return Err("--interface is required".into());
    }
    // A loaded 2-core VM can stall a process for a while: a generous
    // process-data watchdog (100 ms) so a stall is not a lost connection.
    s.watchdog_units = 1000;
    Ok((interface, drives, s))
}

fn main() -> ExitCode {
    let (interface, drives, s) = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let (tx, rx, pdu_loop) = PDU_STORAGE.try_split().expect("split once");
    let task = match ethercrab::std::tx_rx_task(&interface, tx, rx) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("cannot open {interface}: {e}");
            return ExitCode::from(2);
        }
    };
    std::thread::spawn(move || async_io::block_on(task));
    let md = MainDevice::new(
        pdu_loop,
        Timeouts {
            pdu: std::time::Duration::from_secs(1),
            eeprom: std::time::Duration::from_millis(200),
            mailbox_response: std::time::Duration::from_secs(2),
            ..Timeouts::default()
        },
        MainDeviceConfig { dc_static_sync_iterations: 2_000, ..MainDeviceConfig::default() },
    );
    let r = async_io::block_on(drive_probe::run(&md, ethercat_now, &s, |d| async move {
        async_io::Timer::after(d).await;
    }));
    match r {
        Ok(r) => {
            for f in &r.found {
                let id = f.sii_identity;
                println!(
                    "drive {:#06x} {} vendor {:#010x} product {} revision {:#010x} serial {} coe_identity_matches {} \
                     out {} B in {} B",
                    f.address,
                    f.name,
                    id[0],
                    id[1],
                    id[2],
                    id[3],
                    f.coe_identity == id,
                    f.outputs,
                    f.inputs
                );
            }
            println!("{}", r.summary());
            let ok = drives.is_none_or(|n| n == r.found.len())
                && r.cycles == s.cycles
                && r.all_followed()
                && r.found.iter().all(|f| f.coe_identity == f.sii_identity);
            if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE }
        }
        Err(e) => {
            println!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
