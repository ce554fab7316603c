//! Faults of the line (issue 17 §3) under running masters, in-process on
//! simulated time: ethercrab on a line of I/O slaves, and the tool master
//! (`drivebus_ethercat::master`) driving iPOS twins. Each fault is seen by
//! the master and the line recovers when it is cleared.

use drivebus_can::fault::Recurrence;
use drivebus_can::{Duration, Instant};
use drivebus_ethercat::dio::{self, DioConfig};
use drivebus_ethercat::drive::{DriveLine as Line, with_drive};
use drivebus_ethercat::master::drive::CyclicDrive;
use drivebus_ethercat::master::{AlState, LineMaster, PduFrames};
use drivebus_ethercat::{BoxDevice, Clock, Host, LineFault, link};
use drivebus_personality::Profile;
use drivebus_personality::machine::Change;
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, RetryBehaviour, SubDeviceState, Timeouts};

fn dio_line(n: u32) -> Host {
    let devices: Vec<BoxDevice> = (0..n)
        .map(|i| Box::new(dio::slave(&DioConfig { serial: i, ..DioConfig::default() })) as BoxDevice)
        .collect();
    Host::line(devices, Clock::simulated(Instant::from_millis(1)))
}

fn ethercrab_on(
    storage: &'static PduStorage<16, { PduStorage::element_size(1100) }>,
    host: &Host,
    retries: RetryBehaviour,
) -> MainDevice<'static> {
    let (tx, rx, pdu_loop) = storage.try_split().unwrap();
    tokio::spawn(link::run(host.clone(), tx, rx));
    let timeouts = Timeouts { pdu: std::time::Duration::from_millis(20), ..Timeouts::default() };
    MainDevice::new(
        pdu_loop,
        timeouts,
        MainDeviceConfig { dc_static_sync_iterations: 10, retry_behaviour: retries },
    )
}

fn fault(host: &Host, f: LineFault) {
    host.with_segment(|s| s.add_fault(f));
}

fn clear(host: &Host) {
    host.with_segment(|s| s.clear_faults());
}

#[tokio::test(flavor = "current_thread")]
async fn ethercrab_sees_a_broken_link_and_a_skewed_counter_and_the_line_comes_back() {
    static S: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();
    let host = dio_line(4);
    let md = ethercrab_on(&S, &host, RetryBehaviour::None);
    let clk: &'static Clock = Box::leak(Box::new(host.clock().clone()));
    let group = md.init_single_group::<4, 16>(move || clk.ethercat_ns()).await.unwrap();
    let group = group.into_op(&md).await.unwrap();
    assert_eq!(group.tx_rx(&md).await.unwrap().working_counter, 12);

    fault(&host, LineFault::Break { after: 1 });
    host.advance(Duration::from_millis(1));
    let r = group.tx_rx(&md).await.unwrap();
    assert_eq!(r.working_counter, 6, "slaves 3 and 4 are behind the break");
    assert_eq!(r.subdevice_states[2..], [SubDeviceState::None, SubDeviceState::None]);
    clear(&host);
    host.advance(Duration::from_millis(1));
    let r = group.tx_rx(&md).await.unwrap();
    assert_eq!(r.working_counter, 12);
    assert!(r.subdevice_states.iter().all(|s| *s == SubDeviceState::Op));

    // Slave 2 counts one too many in every datagram it takes part in.
    fault(&host, LineFault::WkcSkew { slave: 1, skew: 1 });
    assert_eq!(group.tx_rx(&md).await.unwrap().working_counter, 13);
    clear(&host);
    assert_eq!(group.tx_rx(&md).await.unwrap().working_counter, 12);
}

#[tokio::test(flavor = "current_thread")]
async fn ethercrab_counts_lost_and_corrupted_frames_and_retries_them() {
    static S: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();
    let host = dio_line(2);
    let md = ethercrab_on(&S, &host, RetryBehaviour::Count(2));
    let clk: &'static Clock = Box::leak(Box::new(host.clock().clone()));
    let group = md.init_single_group::<4, 16>(move || clk.ethercat_ns()).await.unwrap();
    let group = group.into_op(&md).await.unwrap();

    // Every third frame lost: ethercrab sends it again and every cycle
    // completes.
    fault(&host, LineFault::Lose(Recurrence::always().every(3)));
    let before = host.stats().lost;
    for _ in 0..9 {
        host.advance(Duration::from_millis(1));
        assert_eq!(group.tx_rx(&md).await.unwrap().working_counter, 6);
    }
    assert!(host.stats().lost - before >= 3, "{:?}", host.stats());
    clear(&host);

    // Two corrupted frames in a row in front of slave 2, then a clean
    // line: the retries get through, and slave 2 counted the bad frames.
    fault(&host, LineFault::Corrupt { at: 1, pick: Recurrence::always().times(2) });
    assert_eq!(group.tx_rx(&md).await.unwrap().working_counter, 6);
    let invalid: u8 = group.subdevice(&md, 1).unwrap().register_read(0x0300u16).await.unwrap();
    assert_eq!(invalid, 2);
    clear(&host);

    // A line that loses everything exhausts the retries: the cycle fails,
    // and the next one after the fault is cleared is whole again.
    fault(&host, LineFault::Lose(Recurrence::always()));
    assert!(matches!(group.tx_rx(&md).await, Err(ethercrab::error::Error::Timeout(_))));
    clear(&host);
    assert_eq!(group.tx_rx(&md).await.unwrap().working_counter, 6);
}

#[tokio::test(flavor = "current_thread")]
async fn ethercrab_finds_a_power_cycled_slave_in_init_and_brings_it_back_to_op() {
    static S: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();
    let host = dio_line(3);
    let md = ethercrab_on(&S, &host, RetryBehaviour::None);
    let clk: &'static Clock = Box::leak(Box::new(host.clock().clone()));
    let group = md.init_single_group::<4, 16>(move || clk.ethercat_ns()).await.unwrap();
    let group = group.into_op(&md).await.unwrap();
    assert_eq!(group.tx_rx(&md).await.unwrap().working_counter, 9);

    host.with_segment(|s| s.power_off(1));
    host.advance(Duration::from_millis(1));
    assert_eq!(group.tx_rx(&md).await.unwrap().working_counter, 3, "the line ends before slave 2");
    host.with_segment(|s| s.power_on(1));
    host.advance(Duration::from_millis(1));
    let r = group.tx_rx(&md).await.unwrap();
    assert!(r.working_counter < 9, "slave 2 lost its configuration: {}", r.working_counter);
    // In INIT, at its reset station address, its EEPROM as before.
    let al = host.with_segment(|s| s.device(1).unwrap().esc().al_status());
    assert_eq!(al & 0x0F, 1);
    assert_eq!(host.with_segment(|s| s.device(1).unwrap().esc().station_address()), 0);
    drop(group);

    // The master's recovery: initialise the line again and go to OP.
    let group = md.init_single_group::<4, 16>(move || clk.ethercat_ns()).await.unwrap();
    assert_eq!(group.len(), 3);
    let group = group.into_op(&md).await.unwrap();
    let r = group.tx_rx(&md).await.unwrap();
    assert_eq!(r.working_counter, 9);
    assert!(r.subdevice_states.iter().all(|s| *s == SubDeviceState::Op));
}

/// A broadcast read of 2 bytes at 0x0000: each slave that executes it
/// adds 1 to its working counter (bytes 28..30).
fn brd() -> Vec<u8> {
    let mut f = vec![0xFF; 6];
    f.extend_from_slice(&[0x10; 6]);
    f.extend_from_slice(&[0x88, 0xA4]);
    f.extend_from_slice(&(14u16 | 1 << 12).to_le_bytes());
    f.extend_from_slice(&[0x07, 0x42, 0, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0]);
    f
}

#[test]
fn a_line_whose_first_slave_has_no_power_gives_the_master_no_frame_back() {
    let host = dio_line(2);
    let mut f = brd();
    let r = host.process_frame(&mut f);
    assert_eq!((r.reached, r.lost), (2, false));
    assert_eq!(u16::from_le_bytes([f[28], f[29]]), 2);
    // The master's port has no link partner: nothing comes back (SOEM over
    // veth got the frame back untouched, working counter 0).
    host.with_segment(|s| s.power_off(0));
    let r = host.process_frame(&mut brd());
    assert_eq!((r.reached, r.lost), (0, true));
    host.with_segment(|s| s.power_on(0));
    let mut f = brd();
    assert!(!host.process_frame(&mut f).lost);
    assert_eq!(u16::from_le_bytes([f[28], f[29]]), 2);
}

fn drives() -> Host {
    Line::new()
        .drive(Profile::Ipos)
        .drive(Profile::Ipos)
        .host(Clock::simulated(Instant::from_millis(1)))
        .unwrap()
}

#[test]
fn the_tool_master_counts_broken_and_lost_cycles_and_keeps_driving() {
    static S: PduFrames = PduFrames::new();
    let host = drives();
    let m = LineMaster::on_host(&S, host.clone()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 1, Duration::from_millis(1), true, None).await.unwrap();
        d.enable(Duration::from_secs(2)).await.unwrap();
        assert_eq!(d.bad_wkc, 0);

        fault(&host, LineFault::Break { after: 0 });
        for _ in 0..5 {
            d.cycle().await.unwrap();
        }
        assert_eq!(d.bad_wkc, 5, "drive 2 does not answer behind the break");
        clear(&host);
        for _ in 0..5 {
            d.cycle().await.unwrap();
        }
        assert_eq!(d.bad_wkc, 5);

        // Two process-data frames lost: two bad cycles, the next ones whole,
        // the drive still enabled and then moving.
        fault(&host, LineFault::Lose(Recurrence::always().every(50).times(2)));
        for _ in 0..120 {
            d.cycle().await.unwrap();
        }
        assert_eq!(d.lost, 2);
        assert_eq!(d.bad_wkc, 7);
        assert_eq!(d.fb.state(), Some(drivebus_cia402::codes::State::OperationEnabled));
        clear(&host);
        let pos = d.move_to(2000, false, Some(100_000), Duration::from_secs(10), |_| {}).await.unwrap();
        assert!((pos - 2000).abs() <= 10, "{pos}");

        fault(&host, LineFault::WkcSkew { slave: 1, skew: -1 });
        d.cycle().await.unwrap();
        assert_eq!(d.bad_wkc, 8);
        clear(&host);
        d.cycle().await.unwrap();
        assert_eq!(d.bad_wkc, 8);
    });
}

#[test]
fn a_machine_fault_of_an_ethercat_ipos_shows_in_its_statusword_and_resets() {
    static S: PduFrames = PduFrames::new();
    let host = drives();
    let m = LineMaster::on_host(&S, host.clone()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 2, Duration::from_millis(1), true, None).await.unwrap();
        d.enable(Duration::from_secs(2)).await.unwrap();
        let now = host.clock().now();
        with_drive(&host, 1, |s| {
            s.app_mut().change_machine(now, Change::fault("encoder", None).unwrap(), None)
        })
        .unwrap()
        .unwrap();
        let mut seen = false;
        for _ in 0..200 {
            if d.cycle().await.unwrap().state() == Some(drivebus_cia402::codes::State::Fault) {
                seen = true;
                break;
            }
        }
        assert!(seen, "statusword {:04X}h", d.fb.statusword);
        let now = host.clock().now();
        with_drive(&host, 1, |s| s.app_mut().change_machine(now, Change::ClearFaults, None))
            .unwrap()
            .unwrap();
        d.enable(Duration::from_secs(2)).await.unwrap();
        assert_eq!(d.fb.state(), Some(drivebus_cia402::codes::State::OperationEnabled));
    });
}

#[test]
fn the_tool_master_finds_a_power_cycled_drive_in_init_and_brings_the_line_back_to_op() {
    static S: PduFrames = PduFrames::new();
    let host = drives();
    let m = LineMaster::on_host(&S, host.clone()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 1, Duration::from_millis(1), true, None).await.unwrap();
        d.enable(Duration::from_secs(2)).await.unwrap();
        host.with_segment(|s| s.power_off(1));
        d.cycle().await.unwrap();
        assert_eq!(d.bad_wkc, 1);
        assert_eq!(m.count().await.unwrap(), 1);
        host.with_segment(|s| s.power_on(1));
        assert_eq!(m.count().await.unwrap(), 2);
        assert_eq!(m.al_status(2).await.unwrap().state, Ok(AlState::Init));
        drop(d);
        // Recovery: the line set up again, drive 2 under control in OP.
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 2, Duration::from_millis(1), true, None).await.unwrap();
        d.enable(Duration::from_secs(2)).await.unwrap();
        assert_eq!(m.al_status(2).await.unwrap().state, Ok(AlState::Op));
        assert_eq!(d.bad_wkc, 0);
    });
}

#[test]
fn a_drifting_clock_shows_in_its_system_time_difference_and_settles_when_cleared() {
    static S: PduFrames = PduFrames::new();
    let host = drives();
    let m = LineMaster::on_host(&S, host.clone()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 1, Duration::from_millis(1), true, None).await.unwrap();
        d.enable(Duration::from_secs(2)).await.unwrap();
        // 0x092C: sign and magnitude of the system time difference (ns).
        let diff = || async {
            let v: u32 = ethercrab::Command::aprd(1, 0x092C).receive(m.main_device()).await.unwrap();
            v & 0x7FFF_FFFF
        };
        for _ in 0..200 {
            d.cycle().await.unwrap();
        }
        let settled = diff().await;
        // 2000 ppm: four times what the ESC's control loop can correct.
        fault(&host, LineFault::Drift { slave: 1, ppb: 2_000_000 });
        for _ in 0..100 {
            d.cycle().await.unwrap();
        }
        let drifted = diff().await;
        assert!(drifted > 10_000 && drifted > 10 * settled, "{settled} ns, then {drifted} ns");
        clear(&host);
        for _ in 0..1000 {
            d.cycle().await.unwrap();
        }
        let after = diff().await;
        assert!(after < drifted / 4, "{drifted} ns, then {after} ns");
    });
}

#[test]
fn a_jittering_clock_shows_in_its_system_time_difference_and_ends_when_cleared() {
    static S: PduFrames = PduFrames::new();
    let host = drives();
    let m = LineMaster::on_host(&S, host.clone()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 1, Duration::from_millis(1), true, None).await.unwrap();
        d.enable(Duration::from_secs(2)).await.unwrap();
        // 0x092C: sign and magnitude of the system time difference (ns).
        let diff = || async {
            let v: u32 = ethercrab::Command::aprd(1, 0x092C).receive(m.main_device()).await.unwrap();
            v & 0x7FFF_FFFF
        };
        for _ in 0..200 {
            d.cycle().await.unwrap();
        }
        let mut settled = 0;
        for _ in 0..100 {
            d.cycle().await.unwrap();
            settled = settled.max(diff().await);
        }
        fault(&host, LineFault::Jitter { slave: 1, amplitude_ns: 20_000, seed: 7 });
        let mut jittered = 0;
        for _ in 0..100 {
            d.cycle().await.unwrap();
            jittered = jittered.max(diff().await);
        }
        assert!(jittered > 2_000 && jittered > 10 * settled.max(1), "{settled} ns, then {jittered} ns");
        assert_eq!(d.bad_wkc, 0, "the process data keeps moving");
        clear(&host);
        for _ in 0..1000 {
            d.cycle().await.unwrap();
        }
        let mut after = 0;
        for _ in 0..100 {
            d.cycle().await.unwrap();
            after = after.max(diff().await);
        }
        assert!(after < jittered / 4, "{jittered} ns, then {after} ns");
    });
}

#[test]
fn a_power_cycled_drive_comes_back_as_at_power_on_and_the_master_brings_it_to_op() {
    static S: PduFrames = PduFrames::new();
    let host = drives();
    let m = LineMaster::on_host(&S, host.clone()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 2, Duration::from_millis(1), true, None).await.unwrap();
        let at_power_on = (d.read(0x6041, 0).await.unwrap(), d.read(0x6064, 0).await.unwrap());
        d.enable(Duration::from_secs(2)).await.unwrap();
        let pos = d.move_to(5000, false, Some(100_000), Duration::from_secs(10), |_| {}).await.unwrap();
        assert!((pos - 5000).abs() <= 10, "{pos}");
        assert_eq!(d.read(0x6041, 0).await.unwrap() & 0x6F, 0x27, "operation enabled");
        drop(d);

        host.with_segment(|s| s.power_off(1));
        host.advance(Duration::from_millis(10));
        host.with_segment(|s| s.power_on(1));
        assert_eq!(m.al_status(2).await.unwrap().state, Ok(AlState::Init));

        // The twin starts again: switch on disabled, the power-on position.
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 2, Duration::from_millis(1), true, None).await.unwrap();
        let now = (d.read(0x6041, 0).await.unwrap(), d.read(0x6064, 0).await.unwrap());
        assert_eq!(now.0 & 0x4F, 0x40, "switch on disabled: {:04X}h", now.0);
        assert_eq!(now, at_power_on, "6041h and 6064h as at power-on (moved to {pos} before)");
        d.enable(Duration::from_secs(2)).await.unwrap();
        assert_eq!(m.al_status(2).await.unwrap().state, Ok(AlState::Op));
        let pos = d.move_to(1000, false, Some(100_000), Duration::from_secs(10), |_| {}).await.unwrap();
        assert!((pos - 1000).abs() <= 10, "{pos}");
    });
}
