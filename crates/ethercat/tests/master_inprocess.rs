//! The tool master (`drivebus_ethercat::master`) against a line of an
//! iPOS and a generic servo over the in-process link on simulated time:
//! count, AL status, scan (SII and 1018h), CoE read, abort, a refused AL
//! state with its code, the PDO assignment, and the drive over process
//! data with DC: enable, homing, a profile-position move checked against
//! the position, a csp sine followed within the following error window;
//! whole objects named by SDO Information and read by complete access,
//! and without either service.

use drivebus_can::{Duration, Instant};
use drivebus_esi::CoeDetails;
use drivebus_ethercat::drive::DriveLine as Line;
use drivebus_ethercat::drive::DriveSlaveSpec;
use drivebus_ethercat::master::drive::CyclicDrive;
use drivebus_ethercat::master::{
    self, AlState, DescribedBy, LineMaster, MasterError, PduFrames, coe_details,
};
use drivebus_ethercat::{BoxDevice, Clock, Host};
use drivebus_personality::Profile;

fn line() -> Host {
    Line::new()
        .drive(Profile::Ipos)
        .drive(Profile::Generic)
        .host(Clock::simulated(Instant::from_millis(1)))
        .unwrap()
}

#[test]
fn scan_coe_state_and_pdos() {
    static S: PduFrames = PduFrames::new();
    let m = LineMaster::on_host(&S, line()).unwrap();
    async_io::block_on(async {
        assert_eq!(m.count().await.unwrap(), 2);
        let s = m.al_status(1).await.unwrap();
        assert_eq!((s.state, s.error), (Ok(AlState::Init), false));
        // INIT -> SAFE-OP is not a transition (ETG.1000.6 Table 9): refused with 0x0011.
        match m.request_state(1, AlState::SafeOp).await {
            Err(MasterError::Refused {
                position: 1,
                requested: AlState::SafeOp,
                state: Ok(AlState::Init),
                code,
            }) => {
                assert_eq!(code, 0x0011)
            }
            other => panic!("{other:?}"),
        }
        // The error was acknowledged: the slave accepts PRE-OP afterwards... once ethercrab set it up.
        let found = m.scan().await.unwrap();
        assert_eq!(found.len(), 2);
        assert_eq!(found[0].identity[0], 0x1A3, "Technosoft");
        assert_eq!(found[0].coe_identity, Some(found[0].identity));
        assert_eq!(found[0].found.state, Ok(AlState::Init));
        assert_eq!(found[1].position, 2);
        assert_eq!(found[1].address, 0x1001);
        assert!(master::mailbox_protocols(found[0].mailbox).contains(&"CoE"));
        assert_eq!(m.al_status(2).await.unwrap().state, Ok(AlState::PreOp));
        let g = m.init().await.unwrap();
        let sd = m.slave(&g, 1).unwrap();
        let v = master::sdo_read(&sd, 1, 0x1018, 1).await.unwrap();
        assert_eq!(v, 0x1A3u32.to_le_bytes());
        match master::sdo_read(&sd, 1, 0x5FFF, 0).await {
            Err(MasterError::Abort { code: 0x0602_0000, .. }) => {}
            other => panic!("{other:?}"),
        }
        let e = master::sdo_read(&sd, 1, 0x5FFF, 0).await.unwrap_err().to_string();
        assert_eq!(
            e,
            "slave 1: SDO read 5FFFh:00 aborted by the device with code 0x06020000: Object does not exist in the object dictionary"
        );
        let tx = master::pdo_assignment(&sd, 1, 0x1C13).await.unwrap();
        assert_eq!(tx[0], (0x1A00, vec![0x6041_0010, 0x6064_0020, 0x6077_0010]));
        assert!(matches!(m.slave(&g, 3), Err(MasterError::NoSlave { position: 3, count: 2 })));
    });
}

#[test]
fn drive_enable_home_move_and_csp_with_dc() {
    static S: PduFrames = PduFrames::new();
    let m = LineMaster::on_host(&S, line()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 1, Duration::from_millis(1), true, None).await.unwrap();
        assert!(d.dc());
        assert_eq!(d.expected_wkc(), 6);
        d.enable(Duration::from_secs(2)).await.unwrap();
        assert_eq!(d.fb.state(), Some(drivebus_cia402::codes::State::OperationEnabled));
        let at = d.home(35, Duration::from_secs(10), |_| {}).await.unwrap();
        assert_eq!(at, 0, "method 35: the current position is 0");
        let pos = d.move_to(5000, false, Some(200_000), Duration::from_secs(20), |_| {}).await.unwrap();
        assert!((pos - 5000).abs() <= 10, "{pos}");
        let read = d.read(0x6064, 0).await.unwrap();
        assert!((read - 5000).abs() <= 10, "6064h over CoE: {read}");
        let base = d.fb.position;
        let mut worst = 0i64;
        let n = d
            .csp(
                (0..2000).map(|k| base + (2000.0 * (k as f64 / 1000.0 * std::f64::consts::TAU).sin()) as i32),
                |t, fb| {
                    worst = worst.max((i64::from(t) - i64::from(fb.position)).abs());
                },
            )
            .await
            .unwrap();
        assert_eq!(n, 2000);
        assert!(worst < 2000, "followed: {worst}");
        assert_eq!(d.bad_wkc, 0);
        d.stop().await.unwrap();
    });
}

#[test]
fn drive_in_free_run_on_the_generic_servo() {
    static S: PduFrames = PduFrames::new();
    let m = LineMaster::on_host(&S, line()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 2, Duration::from_millis(1), false, None).await.unwrap();
        assert!(!d.dc());
        let pos = d.move_to(-3000, false, Some(100_000), Duration::from_secs(20), |_| {}).await.unwrap();
        assert!((pos + 3000).abs() <= 10, "{pos}");
        let pos = d.move_to(500, true, None, Duration::from_secs(20), |_| {}).await.unwrap();
        let window = d.read(0x6067, 0).await.unwrap();
        assert!((i64::from(pos) + 2500).abs() <= window, "relative: {pos}, window {window}");
        assert_eq!(d.bad_wkc, 0);
        d.stop().await.unwrap();
    });
}

/// A line of one iPOS offering the CoE services `coe` (`None`: its own).
fn ipos_offering(coe: Option<CoeDetails>) -> Host {
    let spec = DriveSlaveSpec { coe, ..DriveSlaveSpec::new(Profile::Ipos, 1) };
    let d: BoxDevice = Box::new(drivebus_ethercat::drive::slave(&spec).unwrap());
    Host::line(vec![d], Clock::simulated(Instant::from_millis(1)))
}

fn coe(sdo_info: bool, complete_access: bool) -> Option<CoeDetails> {
    Some(CoeDetails { sdo_info, pdo_assign: true, pdo_config: true, pdo_upload: false, complete_access })
}

#[test]
fn whole_objects_by_sdo_information_and_complete_access() {
    static S: PduFrames = PduFrames::new();
    let m = LineMaster::on_host(&S, line()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let sd = m.slave(&g, 1).unwrap();
        let details = m.coe_details(&sd, 1).await.unwrap();
        assert_eq!(details & (coe_details::SDO_INFO | coe_details::COMPLETE_ACCESS), 0x22, "{details:#04x}");
        // The TxPDO assignment: an ARRAY, every entry named and typed by the
        // slave, entries 1.. in one complete-access upload (§2.3 default).
        let r = m.read_object(&sd, 1, 0x1C13).await.unwrap();
        let DescribedBy::SdoInfo(o) = &r.described else { panic!("{r:?}") };
        assert_eq!(
            (o.name_text().as_str(), o.object_code, o.data_type),
            ("Sync Manager Channel 3 (Process Data Input)", 8, 6)
        );
        assert!(r.complete_access && r.read_complete, "{r:?}");
        let subs: Vec<_> = r.entries.iter().map(|e| (e.sub, e.data.clone())).collect();
        assert_eq!(subs, [(0, vec![2]), (1, vec![0x00, 0x1A]), (2, vec![0x01, 0x1A])]);
        let i = r.entries[1].info.as_ref().unwrap();
        assert_eq!((i.data_type, i.bit_length, i.access_text()), (6, 16, "rw"));
        assert_eq!(i.name_text(), "Sync Manager Channel 3: PDO Mapping object index of assigned TxPDO (1st)");
        assert_eq!(r.entries[0].info.as_ref().unwrap().name_text(), "Number of entries");
        // A RECORD: the identity, read only.
        let r = m.read_object(&sd, 1, 0x1018).await.unwrap();
        let DescribedBy::SdoInfo(o) = &r.described else { panic!("{r:?}") };
        assert_eq!((o.name_text().as_str(), o.object_code), ("Identity Object", 9));
        assert!(r.read_complete);
        let names: Vec<_> = r.entries.iter().map(|e| e.info.as_ref().unwrap().name_text()).collect();
        assert_eq!(
            names,
            ["Number of entries", "Vendor ID", "Product Code", "Revision number", "Serial number"]
        );
        assert_eq!(r.entries[1].data, 0x1A3u32.to_le_bytes());
        assert_eq!(r.entries[4].info.as_ref().unwrap().access_text(), "ro");
        // A VAR: sub 0 with its type.
        let r = m.read_object(&sd, 1, 0x1008).await.unwrap();
        assert_eq!(r.entries.len(), 1);
        assert_eq!(r.entries[0].data, b"iPOS");
        assert_eq!(r.entries[0].info.as_ref().unwrap().data_type, 9, "VISIBLE_STRING");
        // No such object: the slave's SDO Info error, as an abort.
        match m.read_object(&sd, 1, 0x5FFF).await {
            Err(MasterError::Abort { index: 0x5FFF, sub: 0, code: 0x0602_0000, .. }) => {}
            other => panic!("{other:?}"),
        }
    });
}

#[test]
fn whole_objects_without_sdo_information_or_complete_access() {
    static S: PduFrames = PduFrames::new();
    let m = LineMaster::on_host(&S, ipos_offering(coe(false, false))).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let sd = m.slave(&g, 1).unwrap();
        let r = m.read_object(&sd, 1, 0x1C13).await.unwrap();
        assert_eq!(
            r.described,
            DescribedBy::NoSdoInfo("its SII announces no SDO Information (CoE details)".into())
        );
        assert!(!r.complete_access && r.entries.is_empty(), "{r:?}");
        // The caller's layout, one upload per entry.
        let (e, by_ca) =
            master::read_entries(&sd, 1, 0x1C13, &[(1, Some(16)), (2, Some(16))], false).await.unwrap();
        assert!(!by_ca);
        assert_eq!(e, [(1, vec![0x00, 0x1A]), (2, vec![0x01, 0x1A])]);
        // The slave really refuses both services (the SII tells the truth).
        assert_eq!(m.object_description(&sd, 1, 0x1C13).await.unwrap(), None);
    });
    static T: PduFrames = PduFrames::new();
    let m = LineMaster::on_host(&T, ipos_offering(coe(false, true))).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let sd = m.slave(&g, 1).unwrap();
        let r = m.read_object(&sd, 1, 0x1018).await.unwrap();
        assert!(matches!(r.described, DescribedBy::NoSdoInfo(_)) && r.complete_access, "{r:?}");
        // Complete access with the caller's layout; a layout that does not
        // fit the image falls back to one upload per entry.
        let layout = [(1, Some(32)), (2, Some(32)), (3, Some(32)), (4, Some(32))];
        let (e, by_ca) = master::read_entries(&sd, 1, 0x1018, &layout, true).await.unwrap();
        assert!(by_ca);
        assert_eq!(e[3], (4, 1u32.to_le_bytes().to_vec()));
        let (e, by_ca) = master::read_entries(&sd, 1, 0x1018, &layout[..3], true).await.unwrap();
        assert!(!by_ca);
        assert_eq!(e.len(), 3);
    });
}

/// The iPOS shows a new mode in 6061h only once in Operation enabled (its
/// manual §4.2.4): homing and a move from a drive not enabled set the mode,
/// enable, and start once 6061h shows the mode.
#[test]
fn ipos_modes_set_before_enabling() {
    static S: PduFrames = PduFrames::new();
    let m = LineMaster::on_host(&S, line()).unwrap();
    async_io::block_on(async {
        let g = m.init().await.unwrap();
        let mut d = CyclicDrive::start(&m, g, 1, Duration::from_millis(1), true, None).await.unwrap();
        assert_eq!(d.fb.state(), Some(drivebus_cia402::codes::State::SwitchOnDisabled));
        let at = d.home(35, Duration::from_secs(10), |_| {}).await.unwrap();
        assert_eq!(at, 0, "method 35: the current position is 0");
        assert_eq!(d.read(0x6061, 0).await.unwrap(), 6);
        d.disable(Duration::from_secs(2)).await.unwrap();
        let pos = d.move_to(3000, false, Some(200_000), Duration::from_secs(20), |_| {}).await.unwrap();
        assert!((pos - 3000).abs() <= 10, "{pos}");
        assert_eq!(d.read(0x6061, 0).await.unwrap(), 1);
        assert_eq!(d.bad_wkc, 0);
        d.stop().await.unwrap();
    });
}
