//! NMT commands, heartbeat and guarding monitor, EMCY events, SYNC and TIME producers.

mod common;

use std::time::Duration;

use common::{bounded, host, master, node};
use drivebus_can::Frame;
use drivebus_master::{MasterEvent, NmtCommand, RemoteState};
use drivebus_transport::Hub;
use tokio::sync::broadcast;

async fn next_event(
    rx: &mut broadcast::Receiver<MasterEvent>,
    pred: impl Fn(&MasterEvent) -> bool,
) -> MasterEvent {
    loop {
        let e = tokio::time::timeout(Duration::from_secs(3), rx.recv()).await.expect("event").expect("open");
        if pred(&e) {
            return e;
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn nmt_heartbeat_and_loss() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let mut ev = m.subscribe_events();
        let boot = m.expect_bootup(6, Duration::from_secs(2));
        let h = host(&hub, node(6));
        boot.await.unwrap();
        assert_eq!(m.node_state(6), Some(RemoteState::BootUp));
        assert_eq!(next_event(&mut ev, |_| true).await, MasterEvent::Bootup { node: 6 });
        m.sdo(6).write::<u16>(0x1017, 0, 20).await.unwrap();
        assert_eq!(
            m.wait_for_heartbeat(6, Duration::from_secs(1)).await.unwrap(),
            RemoteState::PreOperational
        );
        m.nmt(6, NmtCommand::Start).await.unwrap();
        next_event(&mut ev, |e| *e == MasterEvent::Heartbeat { node: 6, state: RemoteState::Operational })
            .await;
        assert_eq!(m.node_state(6), Some(RemoteState::Operational));
        // Broadcast stop (node 0).
        m.nmt(0, NmtCommand::Stop).await.unwrap();
        next_event(&mut ev, |e| *e == MasterEvent::Heartbeat { node: 6, state: RemoteState::Stopped }).await;
        m.nmt(6, NmtCommand::EnterPreOperational).await.unwrap();
        next_event(&mut ev, |e| *e == MasterEvent::Heartbeat { node: 6, state: RemoteState::PreOperational })
            .await;
        // Reset node: boot-up again, heartbeat back to its default (0: off).
        m.reset_node(6, Duration::from_secs(2)).await.unwrap();
        assert_eq!(m.node_status(6).unwrap().bootups, 2);
        m.reset_communication(6, Duration::from_secs(2)).await.unwrap();
        // Heartbeat loss.
        m.sdo(6).write::<u16>(0x1017, 0, 20).await.unwrap();
        m.monitor_heartbeat(6, Some(Duration::from_millis(100)));
        m.wait_for_heartbeat(6, Duration::from_secs(1)).await.unwrap();
        h.stop();
        next_event(&mut ev, |e| *e == MasterEvent::HeartbeatLost { node: 6 }).await;
        assert!(m.node_status(6).unwrap().lost);
        assert_eq!(m.seen_nodes(), vec![6]);
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn heartbeat_recovery_event() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let mut ev = m.subscribe_events();
        let h = host(&hub, node(8));
        m.sdo(8).write::<u16>(0x1017, 0, 20).await.unwrap();
        m.monitor_heartbeat(8, Some(Duration::from_millis(80)));
        m.wait_for_heartbeat(8, Duration::from_secs(1)).await.unwrap();
        // Silence the heartbeat (1017h = 0), then turn it back on.
        m.sdo(8).write::<u16>(0x1017, 0, 0).await.unwrap();
        next_event(&mut ev, |e| *e == MasterEvent::HeartbeatLost { node: 8 }).await;
        m.sdo(8).write::<u16>(0x1017, 0, 20).await.unwrap();
        next_event(&mut ev, |e| *e == MasterEvent::HeartbeatRecovered { node: 8 }).await;
        drop(h);
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn node_guarding_answers_and_loss() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let mut ev = m.subscribe_events();
        let h = host(&hub, node(11));
        m.start_guarding(11, Duration::from_millis(20), 3).await.unwrap();
        // Guarding answers carry the state (7Fh, with the toggle bit masked).
        next_event(&mut ev, |e| {
            *e == MasterEvent::Heartbeat { node: 11, state: RemoteState::PreOperational }
        })
        .await;
        h.stop();
        next_event(&mut ev, |e| *e == MasterEvent::HeartbeatLost { node: 11 }).await;
        m.stop_guarding(11);
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn emcy_events_with_standard_and_registered_texts() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        m.add_emcy_texts(12, [(0xFF01u16, "Encoder cable broken")]);
        let mut ev = m.subscribe_events();
        let boot = m.expect_bootup(12, Duration::from_secs(1));
        let h = host(&hub, node(12));
        boot.await.unwrap();
        h.with(|d, now| d.node.raise_emcy(0x2310, [1, 2, 3, 4, 5], now)).await.unwrap();
        let e = next_event(&mut ev, |e| matches!(e, MasterEvent::Emcy { .. })).await;
        let MasterEvent::Emcy { node, code, register, data, text } = e else { unreachable!() };
        assert_eq!((node, code, data), (12, 0x2310, [1, 2, 3, 4, 5]));
        assert_ne!(register & 0x01, 0, "generic error bit");
        assert_eq!(text.as_deref(), drivebus_emcy::describe(0x2310));
        assert!(text.is_some());
        h.with(|d, now| d.node.raise_emcy(0xFF01, [0; 5], now)).await.unwrap();
        let e = next_event(&mut ev, |e| matches!(e, MasterEvent::Emcy { code: 0xFF01, .. })).await;
        assert!(matches!(e, MasterEvent::Emcy { text: Some(t), .. } if t == "Encoder cable broken"));
        assert_eq!(m.emcy_text(12, 0xFF01).as_deref(), Some("Encoder cable broken"));
        assert_eq!(m.emcy_text(3, 0xFF01), drivebus_emcy::describe(0xFF01).map(str::to_owned));
    })
    .await;
}

/// Collects frames with `id` for `dur` from a separate participant.
async fn collect(rx: &mut drivebus_transport::CanBus, id: u16, dur: Duration) -> Vec<Frame> {
    let mut v = Vec::new();
    let end = tokio::time::Instant::now() + dur;
    while let Ok(Ok(f)) = tokio::time::timeout_at(end, rx.recv()).await {
        if f.std_id() == Some(id) {
            v.push(f);
        }
    }
    v
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sync_producer_counter_and_stop() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let mut spy = hub.attach();
        let mut ticks = m.subscribe_sync();
        m.start_sync(Duration::from_millis(5), 4);
        assert!(m.sync_running());
        let frames = collect(&mut spy, 0x080, Duration::from_millis(200)).await;
        // Counting frames, not timing them: at least a few, counter cycling 1..=4.
        assert!(frames.len() >= 8, "{} SYNCs", frames.len());
        assert!(frames.len() <= 45, "{} SYNCs in 200 ms at 5 ms", frames.len());
        let counters: Vec<u8> = frames.iter().map(|f| f.data()[0]).collect();
        assert_eq!(counters[0], 1);
        for w in counters.windows(2) {
            assert_eq!(w[1], if w[0] == 4 { 1 } else { w[0] + 1 }, "{counters:?}");
        }
        let t = ticks.recv().await.unwrap();
        assert_eq!((t.seq, t.counter), (1, Some(1)));
        m.stop_sync();
        assert!(!m.sync_running());
        tokio::time::sleep(Duration::from_millis(20)).await;
        let after = collect(&mut spy, 0x080, Duration::from_millis(50)).await;
        assert!(after.is_empty());
        // Without counter: empty frames.
        m.start_sync(Duration::from_millis(5), 0);
        let frames = collect(&mut spy, 0x080, Duration::from_millis(50)).await;
        assert!(!frames.is_empty() && frames.iter().all(|f| f.is_empty()));
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn time_stamp_frame() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let mut spy = hub.attach();
        let ms = 1_700_000_000_123u64;
        m.send_time(ms).await.unwrap();
        let f = tokio::time::timeout(Duration::from_secs(1), spy.recv()).await.unwrap().unwrap();
        assert_eq!(f.std_id(), Some(0x100));
        assert_eq!(drivebus_sync::TimeOfDay::from_bytes(f.data()).unwrap().to_unix_ms(), ms);
        assert!(m.send_time(0).await.is_err(), "1970 cannot be encoded");
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn own_heartbeat_producer() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let mut spy = hub.attach();
        m.start_heartbeat(0x7E, RemoteState::Operational, 10);
        let frames = collect(&mut spy, 0x77E, Duration::from_millis(200)).await;
        assert!((5..=25).contains(&frames.len()), "{} heartbeats in 200 ms at 10 ms", frames.len());
        assert!(frames.iter().all(|f| f.data() == [0x05]), "{frames:?}");
        m.stop_heartbeat();
        // One heartbeat may already be on its way when the producer stops
        // (a loaded machine delivers it late); a running producer would send
        // about ten in 100 ms.
        let after = collect(&mut spy, 0x77E, Duration::from_millis(100)).await;
        assert!(after.len() <= 1, "{} heartbeats after the producer stopped", after.len());
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn time_producer_follows_the_master_clock() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let mut spy = hub.attach();
        let ms = 1_700_000_000_000u64;
        m.start_time(Duration::from_millis(20), ms);
        let frames = collect(&mut spy, 0x100, Duration::from_millis(200)).await;
        assert!((4..=12).contains(&frames.len()), "{} TIME stamps in 200 ms at 20 ms", frames.len());
        let stamps: Vec<u64> = frames
            .iter()
            .map(|f| drivebus_sync::TimeOfDay::from_bytes(f.data()).unwrap().to_unix_ms())
            .collect();
        assert!(stamps[0] >= ms && stamps[0] < ms + 50, "{stamps:?}");
        // Each stamp is the time it was sent: rising, 20 ms apart on average
        // (a late poll sends late, the next one is on schedule again).
        assert!(stamps.windows(2).all(|w| w[1] > w[0]), "{stamps:?}");
        let mean = (stamps[stamps.len() - 1] - stamps[0]) / (stamps.len() as u64 - 1);
        assert!((18..=30).contains(&mean), "{mean} ms apart: {stamps:?}");
        m.stop_time();
        tokio::time::sleep(Duration::from_millis(30)).await;
        assert!(collect(&mut spy, 0x100, Duration::from_millis(60)).await.is_empty());
    })
    .await;
}
