//! SDO client against hosted nodes: expedited, segmented, block, typed
//! helpers, aborts with text, timeouts, EDS-typed values.

mod common;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use common::{bounded, host, master, node};
use drivebus_master::{DataType, Protocol, SdoAbort, SdoError, Value};
use drivebus_od::{Access, Object, ObjectDictionary};
use drivebus_transport::Hub;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn expedited_and_typed_round_trips() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _h = host(&hub, node(5));
        let sdo = m.sdo(5);
        assert_eq!(sdo.read::<u32>(0x1000, 0).await.unwrap(), 0x0002_0192);
        assert_eq!(sdo.read::<u32>(0x1018, 1).await.unwrap(), 0xABC);
        assert_eq!(sdo.read::<i32>(0x2002, 0).await.unwrap(), -5);
        sdo.write::<i32>(0x2002, 0, -123_456).await.unwrap();
        assert_eq!(sdo.read::<i32>(0x2002, 0).await.unwrap(), -123_456);
        // 1017h heartbeat time, u16.
        sdo.write::<u16>(0x1017, 0, 250).await.unwrap();
        assert_eq!(sdo.read::<u16>(0x1017, 0).await.unwrap(), 250);
        // A u16 is not a u32: decode error, not a panic.
        assert!(matches!(sdo.read::<u64>(0x1017, 0).await, Err(SdoError::Decode(_))));
        // Segmented upload of the device name (1008h).
        assert_eq!(sdo.read::<String>(0x1008, 0).await.unwrap(), "test node 5");
        sdo.write(0x2001, 0, "a longer visible string".to_string()).await.unwrap();
        assert_eq!(sdo.read::<String>(0x2001, 0).await.unwrap(), "a longer visible string");
    })
    .await;
}

/// One progress report: bytes done, total.
type Step = (usize, Option<usize>);

fn payload(n: usize) -> Vec<u8> {
    (0..n).map(|i| (i * 7 + i / 256) as u8).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn segmented_and_block_10k_with_progress() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _h = host(&hub, node(7));
        let data = payload(10 * 1024);
        for proto in [Protocol::Segmented, Protocol::Block] {
            let seen: Arc<Mutex<Vec<Step>>> = Arc::default();
            let s2 = seen.clone();
            let sdo = m.sdo(7).protocol(proto).on_progress(move |d, t| s2.lock().unwrap().push((d, t)));
            sdo.download(0x2000, 0, &data).await.unwrap();
            let p = seen.lock().unwrap().clone();
            assert!(p.len() > 10, "{proto:?}: progress reported {} times", p.len());
            assert_eq!(*p.last().unwrap(), (data.len(), Some(data.len())));
            assert!(p.windows(2).all(|w| w[0].0 <= w[1].0), "progress is monotonic");
            seen.lock().unwrap().clear();
            let back = sdo.upload(0x2000, 0).await.unwrap();
            assert_eq!(back, data, "{proto:?} upload");
            let p = seen.lock().unwrap().clone();
            assert!(p.len() > 10);
            assert_eq!(*p.last().unwrap(), (data.len(), Some(data.len())));
        }
        // Auto with a block threshold picks block for big downloads.
        let small = payload(3000);
        m.sdo(7).block_threshold(Some(1000)).download(0x2000, 0, &small).await.unwrap();
        assert_eq!(m.sdo(7).protocol(Protocol::Block).block_size(16).upload(0x2000, 0).await.unwrap(), small);
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn aborts_carry_code_and_text() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _h = host(&hub, node(9));
        let e = m.sdo(9).upload(0x5555, 0).await.unwrap_err();
        assert_eq!(e.abort_code(), Some(SdoAbort::NO_OBJECT));
        assert!(e.to_string().contains("06020000h"), "{e}");
        assert!(e.to_string().contains("does not exist"), "{e}");
        let e = m.sdo(9).write::<u32>(0x1000, 0, 1).await.unwrap_err();
        assert_eq!(e.abort_code(), Some(SdoAbort::WRITE_READ_ONLY));
        let e = m.sdo(9).upload(0x1018, 9).await.unwrap_err();
        assert_eq!(
            e,
            SdoError::Abort { code: SdoAbort::NO_SUB_INDEX, text: SdoAbort::NO_SUB_INDEX.description() }
        );
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn missing_node_times_out_and_retries() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let mut frames = m.subscribe_frames();
        let spy = hub.attach();
        let mut spy_rx = spy;
        let t0 = tokio::time::Instant::now();
        let e = m.sdo(42).timeout(Duration::from_millis(50)).retries(2).upload(0x1000, 0).await.unwrap_err();
        assert_eq!(e, SdoError::Timeout);
        assert!(t0.elapsed() >= Duration::from_millis(150));
        // 3 requests and 3 abort frames (0504 0000) went out.
        let mut reqs = 0;
        while let Ok(Ok(f)) = tokio::time::timeout(Duration::from_millis(20), spy_rx.recv()).await {
            if f.std_id() == Some(0x600 + 42) {
                reqs += 1;
            }
        }
        assert_eq!(reqs, 6);
        assert!(frames.try_recv().is_err(), "the master does not hear itself");
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn parallel_transfers_to_one_node_are_serialised() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _h = host(&hub, node(3));
        let mut tasks = Vec::new();
        for i in 0..8i32 {
            let m = m.clone();
            tasks.push(tokio::spawn(async move {
                m.sdo(3).write::<i32>(0x2002, 0, i).await.unwrap();
                m.sdo(3).read::<String>(0x1008, 0).await.unwrap()
            }));
        }
        for t in tasks {
            assert_eq!(t.await.unwrap(), "test node 3");
        }
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn values_typed_by_eds_dictionary() {
    bounded(async {
        let hub = Hub::default();
        let mut od = ObjectDictionary::new();
        od.insert(Object::var(0x2002, "Signed", DataType::Integer32, Access::Rw, Value::I32(0)));
        od.insert(Object::var(
            0x2001,
            "Name",
            DataType::VisibleString,
            Access::Rw,
            Value::Str(String::new()),
        ));
        let m = master(&hub).with_eds(4, od);
        let _h = host(&hub, node(4));
        let sdo = m.sdo(4);
        assert_eq!(sdo.read_value(0x2002, 0, None).await.unwrap(), Value::I32(-5));
        assert_eq!(sdo.read_value(0x2001, 0, None).await.unwrap(), Value::Str("drivebus".into()));
        sdo.write_value(0x2002, 0, &Value::I32(77), None).await.unwrap();
        assert_eq!(sdo.read_value(0x2002, 0, Some(DataType::Integer32)).await.unwrap(), Value::I32(77));
        // Standard objects are typed without an EDS (drivebus-objects).
        assert_eq!(sdo.read_value(0x1000, 0, None).await.unwrap(), Value::U32(0x0002_0192));
        // Without a type, no EDS entry and not standard: a clear error.
        assert!(matches!(sdo.read_value(0x2003, 0, None).await, Err(SdoError::InvalidRequest(_))));
        // Out of range for the type: refused locally.
        assert!(matches!(
            sdo.write_value(0x1017, 0, &Value::U32(70_000), Some(DataType::Unsigned16)).await,
            Err(SdoError::InvalidRequest(_))
        ));
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn protocol_violation_is_reported_as_such() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        // A broken server: answers every request with a download response.
        let mut fake = hub.attach();
        tokio::spawn(async move {
            while let Ok(f) = fake.recv().await {
                if f.std_id() == Some(0x615) && f.data().first() != Some(&0x80) {
                    let _ = fake.send(drivebus_can::Frame::new(0x595, &[0x60, 0, 0x10, 0, 0, 0, 0, 0])).await;
                }
            }
        });
        let e = m.sdo(0x15).upload(0x1000, 0).await.unwrap_err();
        assert_eq!(e, SdoError::Protocol(SdoAbort(0x0504_0001)));
        assert!(e.to_string().contains("protocol"), "{e}");
    })
    .await;
}
