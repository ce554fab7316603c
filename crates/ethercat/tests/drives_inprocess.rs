//! ethercrab 0.7.1 against CoE drives over the in-process link, on
//! simulated time: one iPOS, and a line of four (two iPOS, two generic).
//! Discovery, identity (SII and 1018h over CoE), the PDO mapping read
//! over CoE, the manual's remapping in PRE-OP (E10/E11), INIT → PRE-OP →
//! SAFE-OP → OP, then 5000 cycles at 1 ms with the expected working
//! counter on every cycle while every enabled drive follows a csp sine —
//! in free run and with DC SYNC0 at 1 ms.

use drivebus_can::{Duration, Instant};
use drivebus_ethercat::drive::{DriveLine, with_drive};
use drivebus_ethercat::drive_probe::{self, DriveReport, DriveScenario, TECHNOSOFT};
use drivebus_ethercat::{Clock, Host, link};
use drivebus_personality::Profile;
use drivebus_personality::ecat::sync_sub;
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, Timeouts};

type Storage = PduStorage<16, { PduStorage::element_size(1100) }>;

async fn scenario(storage: &'static Storage, line: DriveLine, s: DriveScenario) -> (DriveReport, Host) {
    let clock = Clock::simulated(Instant::from_millis(1));
    let host = line.host(clock.clone()).expect("line");
    let (tx, rx, pdu_loop) = storage.try_split().expect("split once");
    tokio::spawn(link::run(host.clone(), tx, rx));
    let md = MainDevice::new(
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
    );
    let clk: &'static Clock = Box::leak(Box::new(clock));
    let h = host.clone();
    let report = drive_probe::run(
        &md,
        move || clk.ethercat_ns(),
        &s,
        move |d| {
            h.advance(d);
            std::future::ready(())
        },
    )
    .await
    .expect("scenario");
    (report, host)
}

fn check(r: &DriveReport, profiles: &[Profile]) {
    println!("{}", r.summary());
    assert_eq!(r.found.len(), profiles.len(), "discovery count");
    for (i, (f, p)) in r.found.iter().zip(profiles).enumerate() {
        let info = p.info();
        assert_eq!(f.name, info.product_name, "name from the SII order string");
        assert_eq!(f.sii_identity, f.coe_identity, "SII identity = 1018h");
        assert_eq!(f.sii_identity[0], info.vendor_id.unwrap_or(0));
        assert_eq!(f.sii_identity[3], i as u32 + 1, "serial = position");
        assert_eq!(f.address, 0x1000 + i as u16);
        if *p == Profile::Ipos {
            assert_eq!(f.sii_identity[0], TECHNOSOFT);
            assert_eq!(f.sii_identity[2], 0x4130_3047, "revision = firmware ID A00G (§1.5.4.6)");
        }
    }
    assert_eq!(r.cycles, 5_000);
    assert_eq!(r.expected_wkc, 3 * profiles.len() as u16);
    assert_eq!(r.bad_wkc, 0, "{}", r.summary());
    assert!(r.all_followed(), "{} {:?}", r.summary(), r.axes);
}

#[tokio::test(flavor = "current_thread")]
async fn one_ipos_free_run() {
    static S: Storage = PduStorage::new();
    let (r, host) = scenario(&S, DriveLine::new().drive(Profile::Ipos), DriveScenario::default()).await;
    check(&r, &[Profile::Ipos]);
    let f = &r.found[0];
    // §2.3 default mapping, read over CoE: 6 output and 16 input bytes.
    assert_eq!(f.rx, [(0x1600, vec![0x6040_0010, 0x607A_0020])]);
    assert_eq!(
        f.tx,
        [(0x1A00, vec![0x6041_0010, 0x6064_0020, 0x6077_0010]), (0x1A01, vec![0x60F4_0020, 0x60FD_0020])]
    );
    assert_eq!((f.outputs, f.inputs), (6, 16));
    let (state, outputs) =
        with_drive(&host, 0, |d| (d.app().esm(), d.app().stats().outputs_applied)).unwrap();
    assert_eq!(state, drivebus_coe::AlState::SafeOp, "back in SAFE-OP at the end");
    assert!(outputs >= 5_000);
}

fn four() -> (DriveLine, [Profile; 4]) {
    let p = [Profile::Ipos, Profile::Generic, Profile::Ipos, Profile::Generic];
    (p.iter().fold(DriveLine::new(), |l, p| l.drive(*p)), p)
}

/// The remapped images: E10/E11 on the iPOS (RxPDO1 + RxPDO2 + RxPDO3,
/// TxPDO1..4), the same procedure on the generic servo's free PDOs
/// (1602h + 1603h, 1A02h + 1A03h).
fn check_remapped(r: &DriveReport, profiles: &[Profile]) {
    for (f, p) in r.found.iter().zip(profiles) {
        let rx: Vec<u16> = f.rx.iter().map(|m| m.0).collect();
        let tx: Vec<u16> = f.tx.iter().map(|m| m.0).collect();
        let (want_rx, want_tx): (&[u16], &[u16]) = match p {
            Profile::Ipos => (&[0x1600, 0x1601, 0x1602], &[0x1A00, 0x1A01, 0x1A02, 0x1A03]),
            _ => (&[0x1602, 0x1603], &[0x1A02, 0x1A03]),
        };
        assert_eq!((rx.as_slice(), tx.as_slice()), (want_rx, want_tx), "{p}");
        assert_eq!(f.rx.last().unwrap().1, [0x6040_0010, 0x6060_0008], "{p}: E10");
        assert_eq!(f.tx.last().unwrap().1, [0x6064_0020, 0x60FD_0020], "{p}: E11");
        let bits = |m: &[(u16, Vec<u32>)]| m.iter().flat_map(|p| &p.1).map(|e| e & 0xFF).sum::<u32>();
        assert_eq!((f.outputs, f.inputs), ((bits(&f.rx) / 8) as usize, (bits(&f.tx) / 8) as usize), "{p}");
    }
}

#[tokio::test(flavor = "current_thread")]
async fn line_of_four_remapped_free_run() {
    static S: Storage = PduStorage::new();
    let (line, p) = four();
    let (r, host) = scenario(&S, line, DriveScenario { remap: true, ..DriveScenario::default() }).await;
    check(&r, &p);
    check_remapped(&r, &p);
    // The generic servo's default image: 1602h (controlword + target
    // position) and 1A02h (statusword + position) before the remap.
    let d: Vec<u32> = r.found.iter().map(|f| f.window).collect();
    assert!(d.iter().all(|w| *w > 0));
    for i in 0..4 {
        let t = with_drive(&host, i, |d| d.app().device().node.od().get_u32(0x1C32, sync_sub::SYNC_TYPE))
            .unwrap();
        assert_eq!(t, Some(1), "SM-synchronous without DC (1C32h:01)");
    }
}

#[tokio::test(flavor = "current_thread")]
async fn one_ipos_dc_sync0_1ms() {
    static S: Storage = PduStorage::new();
    let s = DriveScenario { dc: Some(Duration::from_millis(1)), ..DriveScenario::default() };
    let (r, host) = scenario(&S, DriveLine::new().drive(Profile::Ipos), s).await;
    check(&r, &[Profile::Ipos]);
    assert!(r.max_dc_offset_error < 20_000, "{}", r.summary());
    let (ty, cycle, missed, pulses) = with_drive(&host, 0, |d| {
        let od = d.app().device().node.od();
        (
            od.get_u32(0x1C32, sync_sub::SYNC_TYPE),
            od.get_u32(0x1C32, sync_sub::SYNC0_CYCLE),
            od.get_u32(0x1C32, sync_sub::SM_EVENT_MISSED),
            d.app().stats().sync0_pulses,
        )
    })
    .unwrap();
    assert_eq!((ty, cycle), (Some(2), Some(1_000_000)), "DC SYNC0 at 1 ms (1C32h:01, :0A)");
    assert_eq!(missed, Some(0), "one frame per SYNC0 cycle");
    assert!(pulses >= 5_000);
}

#[tokio::test(flavor = "current_thread")]
async fn line_of_four_remapped_dc_sync0_1ms() {
    static S: Storage = PduStorage::new();
    let (line, p) = four();
    let s = DriveScenario { dc: Some(Duration::from_millis(1)), remap: true, ..DriveScenario::default() };
    let (r, _) = scenario(&S, line, s).await;
    check(&r, &p);
    check_remapped(&r, &p);
    assert!(r.max_dc_offset_error < 20_000, "{}", r.summary());
}
