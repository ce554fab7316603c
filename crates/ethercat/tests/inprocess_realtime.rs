//! The in-process link on the machine's clock: device deadlines (SYNC0
//! pulses) are served by the link's own timer between frames. Real time on
//! a shared machine, so inputs one cycle late are tolerated; working
//! counters and data must be right.

use drivebus_can::Duration;
use drivebus_ethercat::dio::{self, DioConfig};
use drivebus_ethercat::probe::{self, ScenarioConfig};
use drivebus_ethercat::{BoxDevice, Clock, Host, link};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts};

static S: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();

#[tokio::test(flavor = "current_thread")]
async fn realtime_dc_line_of_two() {
    let cfgs: Vec<DioConfig> =
        (0..2).map(|i| DioConfig { mask: 0x33 << i, ..DioConfig::default() }).collect();
    let devices: Vec<BoxDevice> = cfgs.iter().map(|c| Box::new(dio::slave(c)) as BoxDevice).collect();
    let clock = Clock::real();
    let host = Host::line(devices, clock.clone());
    let (tx, rx, pdu_loop) = S.try_split().unwrap();
    tokio::spawn(link::run(host.clone(), tx, rx));
    let md = MainDevice::new(
        pdu_loop,
        Timeouts { pdu: std::time::Duration::from_secs(1), ..Timeouts::default() },
        MainDeviceConfig { dc_static_sync_iterations: 500, ..MainDeviceConfig::default() },
    );
    let clk: &'static Clock = Box::leak(Box::new(clock));
    let cfg = ScenarioConfig {
        masks: cfgs.iter().map(|c| c.mask).collect(),
        cycles: 1000,
        cycle: Duration::from_millis(1),
        dc: Some(Duration::from_millis(1)),
        watchdog_units: 10_000,
    };
    let r = probe::run(&md, move || clk.ethercat_ns(), &cfg, tokio::time::sleep).await.expect("scenario");
    assert_eq!(r.found.len(), 2);
    assert_eq!((r.cycles, r.bad_wkc, r.bad_data), (1000, 0, 0), "{}", r.summary());
    // SYNC0 pulses were served at their deadlines (by the link's timer or
    // before the next frame), about one per cycle.
    assert!(host.stats().deadline_polls > 500, "{:?}", host.stats());
}
