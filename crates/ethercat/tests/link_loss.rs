//! Topology changes under a running ethercrab master (in-process, simulated
//! time), and the pcapng capture of the whole exchange.

use drivebus_can::{Duration, Instant};
use drivebus_ethercat::dio::{self, DioConfig};
use drivebus_ethercat::{BoxDevice, Clock, Host, link};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, SubDeviceState, Timeouts};
use pcap_file::pcapng::{Block, PcapNgReader};
use std::io::Write;
use std::sync::{Arc, Mutex};

#[derive(Clone, Default)]
struct Shared(Arc<Mutex<Vec<u8>>>);

impl Write for Shared {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[tokio::test(flavor = "current_thread")]
async fn cable_break_drops_the_working_counter_and_the_capture_has_every_frame() {
    static S: PduStorage<16, { PduStorage::element_size(1100) }> = PduStorage::new();
    let clock = Clock::simulated(Instant::from_millis(1));
    let devices: Vec<BoxDevice> = (0..4)
        .map(|i| Box::new(dio::slave(&DioConfig { serial: i, ..DioConfig::default() })) as BoxDevice)
        .collect();
    let host = Host::line(devices, clock.clone());
    let cap = Shared::default();
    host.set_capture(Box::new(cap.clone()), "inprocess0").unwrap();
    let (tx, rx, pdu_loop) = S.try_split().unwrap();
    tokio::spawn(link::run(host.clone(), tx, rx));
    let md = MainDevice::new(
        pdu_loop,
        Timeouts::default(),
        MainDeviceConfig { dc_static_sync_iterations: 10, ..MainDeviceConfig::default() },
    );
    let clk: &'static Clock = Box::leak(Box::new(clock));
    let group = md.init_single_group::<4, 16>(move || clk.ethercat_ns()).await.unwrap();
    let group = group.into_op(&md).await.unwrap();
    let r = group.tx_rx(&md).await.unwrap();
    assert_eq!(r.working_counter, 12);

    // Pull the cable between slave 1 and slave 2.
    host.with_segment(|s| s.set_cable(1, false));
    host.advance(Duration::from_millis(1));
    let r = group.tx_rx(&md).await.unwrap();
    assert_eq!(r.working_counter, 6, "only the first two slaves answer");
    // The status reads of the lost slaves come back untouched (zeros).
    assert_eq!(
        &r.subdevice_states[..],
        &[SubDeviceState::Op, SubDeviceState::Op, SubDeviceState::None, SubDeviceState::None]
    );
    // Slave 1 saw its port 1 link go down (lost link counter 0x0311).
    let lost: u8 = group.subdevice(&md, 1).unwrap().register_read(0x0311u16).await.unwrap();
    assert_eq!(lost, 1);

    // Reconnect: the slaves behind the break kept their configuration and
    // are still in OP (their watchdog had no time to expire).
    host.with_segment(|s| s.set_cable(1, true));
    host.advance(Duration::from_millis(1));
    let r = group.tx_rx(&md).await.unwrap();
    assert_eq!(r.working_counter, 12);
    assert!(r.subdevice_states.iter().all(|s| *s == SubDeviceState::Op));

    host.stop_capture().unwrap();
    let frames = host.stats().frames;
    let bytes = cap.0.lock().unwrap().clone();
    let mut reader = PcapNgReader::new(&bytes[..]).unwrap();
    let mut packets = 0u64;
    let mut last_ts = 0u128;
    while let Some(b) = reader.next_block() {
        if let Block::EnhancedPacket(p) = b.unwrap() {
            packets += 1;
            assert!(p.timestamp.as_nanos() >= last_ts, "timestamps never go back");
            last_ts = p.timestamp.as_nanos();
            assert_eq!(&p.data[12..14], &[0x88, 0xA4]);
        }
    }
    assert_eq!(packets, 2 * frames, "every frame in and out");
}
