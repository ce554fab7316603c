//! ethercrab 0.7.1 against digital I/O slaves over the in-process link, on
//! simulated time (deterministic: the clock moves only with frames and the
//! scenario's cycle waits).

use drivebus_can::{Duration, Instant};
use drivebus_esc::ClockConfig;
use drivebus_ethercat::dio::{self, DioConfig, VENDOR_ID};
use drivebus_ethercat::probe::{self, ScenarioConfig, ScenarioReport};
use drivebus_ethercat::{BoxDevice, Clock, Host, link};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts};
use std::sync::Arc;

type Storage = PduStorage<16, { PduStorage::element_size(1100) }>;

fn configs(n: usize) -> Vec<DioConfig> {
    (0..n)
        .map(|i| DioConfig {
            channels: if i % 2 == 0 { 8 } else { 16 },
            mask: 0x5A5A_5A5A ^ (i as u32 * 0x0101_0101),
            serial: 100 + i as u32,
            alias: 0,
            // Every ESC powers up at a different time and drifts differently.
            clock: ClockConfig {
                offset_ns: 7_000_000 * (i as u64 + 1),
                drift_ppb: 40_000 - 25_000 * i as i32,
            },
        })
        .collect()
}

async fn scenario(storage: &'static Storage, n: usize, dc: bool) -> (ScenarioReport, Host) {
    let clock = Clock::simulated(Instant::from_millis(1));
    let cfgs = configs(n);
    let devices: Vec<BoxDevice> = cfgs.iter().map(|c| Box::new(dio::slave(c)) as BoxDevice).collect();
    let host = Host::line(devices, clock.clone());
    let (tx, rx, pdu_loop) = storage.try_split().expect("split once");
    tokio::spawn(link::run(host.clone(), tx, rx));
    let md = Arc::new(MainDevice::new(
        pdu_loop,
        // The slaves run on simulated time, ethercrab's timers on real time:
        // on a loaded host the link task may wait long for a core, which
        // says nothing about the slaves.
        Timeouts {
            pdu: Duration::from_secs(2),
            eeprom: Duration::from_secs(2),
            state_transition: Duration::from_secs(30),
            mailbox_response: Duration::from_secs(10),
            ..Timeouts::default()
        },
        MainDeviceConfig { dc_static_sync_iterations: 2_000, ..MainDeviceConfig::default() },
    ));
    let clk: &'static Clock = Box::leak(Box::new(clock.clone()));
    let cfg = ScenarioConfig {
        masks: cfgs.iter().map(|c| c.mask).collect(),
        cycles: 5_000,
        cycle: Duration::from_millis(1),
        dc: dc.then_some(Duration::from_millis(1)),
        watchdog_units: 1000,
    };
    let h = host.clone();
    let report = probe::run(
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
    (report, host)
}

fn check(report: &ScenarioReport, n: usize) {
    assert_eq!(report.found.len(), n, "discovery count");
    for (i, f) in report.found.iter().enumerate() {
        let bytes = if i % 2 == 0 { 1 } else { 2 };
        assert_eq!(f.name, if bytes == 1 { "DB-DIO8" } else { "DB-DIO16" }, "name from the SII order string");
        assert_eq!(f.vendor_id, VENDOR_ID);
        assert_eq!(f.serial, 100 + i as u32);
        assert_eq!((f.inputs, f.outputs), (bytes, bytes), "PDO sizes from the SII categories");
        assert_eq!(f.address, 0x1000 + i as u16);
    }
    assert_eq!(report.cycles, 5_000);
    assert_eq!(report.expected_wkc, 3 * n as u16);
    assert_eq!(report.bad_wkc, 0, "{}", report.summary());
    assert_eq!(report.bad_data, 0, "{}", report.summary());
    assert_eq!(report.late_data, 0, "simulated time: always exactly one cycle: {}", report.summary());
}

#[tokio::test(flavor = "current_thread")]
async fn one_slave_free_run() {
    static S: Storage = PduStorage::new();
    let (r, host) = scenario(&S, 1, false).await;
    check(&r, 1);
    assert_eq!(host.stats().bad_frames, 0);
}

#[tokio::test(flavor = "current_thread")]
async fn line_of_four_free_run() {
    static S: Storage = PduStorage::new();
    let (r, _) = scenario(&S, 4, false).await;
    check(&r, 4);
    // Propagation delays: ethercrab halves port time differences; each hop
    // is link (300 ns) + ESC (200 ns).
    let d: Vec<u32> = r.found.iter().map(|f| f.propagation_delay).collect();
    assert_eq!(d, vec![0, 500, 1000, 1500]);
}

#[tokio::test(flavor = "current_thread")]
async fn one_slave_dc_sync0_1ms() {
    static S: Storage = PduStorage::new();
    let (r, host) = scenario(&S, 1, true).await;
    check(&r, 1);
    // The frame reaches the reference a constant few µs after the master
    // wakes (5 µs simulated turnaround + transit): the master stays locked
    // to SYNC0 to within that.
    assert!(r.max_dc_offset_error < 20_000, "{}", r.summary());
    host.with_segment(|s| {
        let e = s.device(0).unwrap().esc();
        assert_eq!(e.peek_u16(0x0130), 0x04, "back in SAFE-OP at the end");
    });
}

#[tokio::test(flavor = "current_thread")]
async fn line_of_four_dc_sync0_1ms() {
    static S: Storage = PduStorage::new();
    let (r, host) = scenario(&S, 4, true).await;
    check(&r, 4);
    assert!(r.max_dc_offset_error < 20_000, "{}", r.summary());
    // The follower clocks learned their drift relative to the reference
    // (slave 0: +40 ppm): slave i drifts 25 ppm·i slower.
    host.with_segment(|s| {
        for i in 1..4 {
            let ppb = s.device(i).unwrap().esc().clock_correction_ppb();
            assert!((ppb - 25_000 * i as i64).abs() < 3_000, "slave {i}: {ppb} ppb");
        }
    });
}
