//! PDO configuration (read, write with the CiA 301 procedure), PDO
//! listeners and senders, DCF application.

mod common;

use std::time::Duration;

use common::{bounded, host, master, node};
use drivebus_master::{ConfigError, NmtCommand, PdoDir, PdoMapEntry, PdoRecord, RemoteState};
use drivebus_transport::Hub;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn read_write_tpdo_and_receive_it() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _h = host(&hub, node(5));
        let before = m.read_pdo(5, PdoDir::Tx, 1).await.unwrap();
        assert_eq!(before.can_id(), 0x185);
        let rec = PdoRecord {
            event_timer: Some(10),
            inhibit_time: Some(0),
            ..PdoRecord::new(
                0x1A5,
                255,
                vec![PdoMapEntry::new(0x2004, 0, 32), PdoMapEntry::new(0x2003, 0, 16)],
            )
        };
        m.write_pdo(5, PdoDir::Tx, 1, &rec).await.unwrap();
        let back = m.read_pdo(5, PdoDir::Tx, 1).await.unwrap();
        assert_eq!(back.cob_id & 0x7FF, 0x1A5);
        assert!(back.valid());
        assert_eq!(back.transmission_type, 255);
        assert_eq!(back.event_timer, Some(10));
        assert_eq!(back.mapping, rec.mapping);
        assert_eq!(back.len_bytes(), 6);
        let mut rx = m.subscribe_pdo(0x1A5);
        m.nmt(5, NmtCommand::Start).await.unwrap();
        let f = tokio::time::timeout(Duration::from_secs(2), rx.recv()).await.unwrap().unwrap();
        assert_eq!(f.data(), &[0xFB, 0xFF, 0xFF, 0xFF, 0xEF, 0xBE]);
        // Mapping a valid PDO without the procedure would be refused; the
        // procedure also works while Operational.
        let rec2 = PdoRecord::new(0x1A5, 255, vec![PdoMapEntry::new(0x2003, 0, 16)]);
        m.write_pdo(5, PdoDir::Tx, 1, &rec2).await.unwrap();
        // A bad mapping surfaces the abort with its location.
        let bad = PdoRecord::new(0x1A5, 255, vec![PdoMapEntry::new(0x1000, 0, 32)]);
        let e = m.write_pdo(5, PdoDir::Tx, 1, &bad).await.unwrap_err();
        assert!(matches!(e, ConfigError::Sdo { index: 0x1A00, sub: 1, .. }), "{e}");
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rpdo_written_by_send_pdo() {
    bounded(async {
        let hub = Hub::default();
        let m = master(&hub);
        let _h = host(&hub, node(6));
        let rec = PdoRecord::new(0x226, 255, vec![PdoMapEntry::new(0x2004, 0, 32)]);
        m.write_pdo(6, PdoDir::Rx, 1, &rec).await.unwrap();
        m.nmt(6, NmtCommand::Start).await.unwrap();
        // Wait until the node is operational (RPDOs are ignored before).
        m.sdo(6).write::<u16>(0x1017, 0, 10).await.unwrap();
        while m.wait_for_heartbeat(6, Duration::from_secs(1)).await.unwrap() != RemoteState::Operational {}
        m.send_pdo(0x226, &1234i32.to_le_bytes()).await.unwrap();
        let mut v = 0;
        for _ in 0..100 {
            v = m.sdo(6).read::<i32>(0x2004, 0).await.unwrap();
            if v == 1234 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
        assert_eq!(v, 1234);
        assert!(m.send_pdo(0x226, &[0; 9]).await.is_err());
    })
    .await;
}

const DCF: &str = r#"
[FileInfo]
FileName=test.dcf

[DeviceInfo]
VendorName=drivebus
VendorNumber=0xABC
ProductNumber=0x107
RevisionNumber=0x00010002

[DeviceComissioning]
NodeID=7

[1017]
ParameterName=Producer heartbeat time
ObjectType=0x7
DataType=0x0006
AccessType=rw
DefaultValue=0
ParameterValue=25

[2002]
ParameterName=Signed
ObjectType=0x7
DataType=0x0004
AccessType=rw
DefaultValue=0
ParameterValue=-42

[1800]
ParameterName=TPDO1 communication
ObjectType=0x9
SubNumber=3

[1800sub0]
ParameterName=Highest sub-index
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=6

[1800sub1]
ParameterName=COB-ID
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=$NODEID+0x180
ParameterValue=$NODEID+0x1C0

[1800sub2]
ParameterName=Transmission type
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=255
ParameterValue=254

[1800sub5]
ParameterName=Event timer
ObjectType=0x7
DataType=0x0006
AccessType=rw
DefaultValue=0
ParameterValue=15

[1A00]
ParameterName=TPDO1 mapping
ObjectType=0x9
SubNumber=2

[1A00sub0]
ParameterName=Number of entries
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=0
ParameterValue=1

[1A00sub1]
ParameterName=Entry 1
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0
ParameterValue=0x20030010
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dcf_applied_and_started() {
    bounded(async {
        let dcf = drivebus_eds::parse(DCF).expect("DCF parses").eds;
        let hub = Hub::default();
        let m = master(&hub);
        let _h = host(&hub, node(7));
        let mut rx = m.subscribe_pdo(0x1C7);
        let n = m.apply_dcf(7, &dcf, true).await.unwrap();
        assert!(n >= 6, "{n} entries written");
        assert_eq!(m.sdo(7).read::<i32>(0x2002, 0).await.unwrap(), -42);
        assert_eq!(m.sdo(7).read::<u16>(0x1017, 0).await.unwrap(), 25);
        let t = m.read_pdo(7, PdoDir::Tx, 1).await.unwrap();
        assert_eq!((t.cob_id, t.transmission_type, t.event_timer), (0x1C7, 254, Some(15)));
        assert_eq!(t.mapping, vec![PdoMapEntry::new(0x2003, 0, 16)]);
        let f = tokio::time::timeout(Duration::from_secs(2), rx.recv()).await.unwrap().unwrap();
        assert_eq!(f.data(), &[0xEF, 0xBE]);
        assert_eq!(m.wait_for_heartbeat(7, Duration::from_secs(1)).await.unwrap(), RemoteState::Operational);

        // The identity check refuses another device.
        let _other = host(&hub, node(8));
        let e = m.apply_dcf(8, &dcf, false).await.unwrap_err();
        assert_eq!(e, ConfigError::IdentityMismatch { sub: 2, expected: 0x107, actual: 0x108 });
    })
    .await;
}
