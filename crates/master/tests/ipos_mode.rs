//! The drive handle against the iPOS personality on the virtual bus in
//! simulated time. Its 6061h takes the value of 6060h only once the drive
//! is in Operation enabled (iPOS manual §4.2.4): a mode set before
//! enabling is checked when enabling reached Operation enabled, and no
//! motion starts before 6061h shows the mode.

use std::time::Duration;

use drivebus_bus::{Bus, BusConfig, ProbeId};
use drivebus_master::drive::mode;
use drivebus_master::{DriveError, DriveState, Master, MasterConfig, ModeNotShown, SimBus};
use drivebus_personality::Profile as Personality;

const NODE: u8 = 3;

fn ipos() -> (SimBus, ProbeId) {
    let mut bus = Bus::new(BusConfig::with_bitrate(1_000_000));
    bus.attach(Personality::Ipos.build_on_default_machine(NODE).unwrap());
    let probe = bus.attach_probe();
    let cfg = MasterConfig { sdo_timeout: Duration::from_millis(300), ..Default::default() };
    let mut sim = SimBus::with_config(bus, cfg);
    sim.set_limit(Duration::from_secs(120));
    (sim, probe)
}

async fn display(m: &Master) -> i8 {
    m.sdo(NODE).read::<i8>(0x6061, 0).await.unwrap()
}

/// Where in the frames the master received or sent the first SDO frame
/// (from the server when `response`) starting with `head`.
fn sdo_at(bus: &Bus, probe: ProbeId, response: bool, head: &[u8]) -> Option<usize> {
    let id = if response { 0x580 } else { 0x600 } + u16::from(NODE);
    bus.received(probe).iter().position(|(_, f)| f.std_id() == Some(id) && f.data().starts_with(head))
}

#[test]
fn a_mode_set_before_enabling_is_checked_once_enabled() {
    let (mut sim, probe) = ipos();
    let m = sim.master().clone();
    sim.block_on(async {
        let d = m.drive(NODE).await.unwrap().with_timeout(Duration::from_millis(500));
        assert_eq!(d.state().await.unwrap(), DriveState::SwitchOnDisabled);
        let before = display(&m).await;
        assert_ne!(before, mode::PP);
        // Not enabled: 6061h keeps the mode it had, set_mode does not wait.
        d.set_mode(mode::PP).await.unwrap();
        assert_eq!(display(&m).await, before, "iPOS §4.2.4");
        d.enable().await.unwrap();
        assert_eq!(display(&m).await, mode::PP);
        let from = d.position().await.unwrap();
        // The iPOS has no 6084h: one acceleration (6083h) for both ramps.
        m.sdo(NODE).write::<u32>(0x6081, 0, 100_000).await.unwrap();
        m.sdo(NODE).write::<u32>(0x6083, 0, 1_000_000).await.unwrap();
        d.move_to(2000, true, None, Duration::from_secs(10)).await.unwrap();
        let moved = d.position().await.unwrap() - from;
        assert!((moved - 2000).abs() <= 10, "moved {moved}");

        // Homing from ready to switch on: home() sets the mode, enables
        // with controlword 0Fh and starts only once 6061h shows homing.
        d.disable().await.unwrap();
        d.home(35, Duration::from_secs(10)).await.unwrap();
        assert_eq!(display(&m).await, mode::HM);
        assert_eq!(d.position().await, Some(0), "method 35: here is 0");

        // A mode set and never enabled: the move is refused before any
        // set-point, naming the mode, 6061h and the statusword.
        d.disable().await.unwrap();
        d.set_mode(mode::PP).await.unwrap();
        let e = d.move_to(1000, false, None, Duration::from_secs(5)).await.unwrap_err();
        let sw = d.statusword().await.unwrap();
        assert_eq!(e, DriveError::Mode(ModeNotShown { mode: mode::PP, display: mode::HM, statusword: sw }));
        assert_eq!(
            e.to_string(),
            format!(
                "6061h shows mode 6 (homing), not mode 1 (profile position) written to 6060h \
                 (statusword {sw:04X}h, ready to switch on): a drive may take a new mode only in operation enabled"
            )
        );
        assert_eq!(d.position().await, Some(0), "nothing moved");
        d.enable().await.unwrap();
        assert_eq!(display(&m).await, mode::PP);
    })
    .unwrap();
    // The homing start (controlword 1Fh by SDO) went out only after 6061h
    // was read as homing.
    let shown = sdo_at(sim.bus(), probe, true, &[0x4F, 0x61, 0x60, 0x00, mode::HM as u8]);
    let start = sdo_at(sim.bus(), probe, false, &[0x2B, 0x40, 0x60, 0x00, 0x1F, 0x00]);
    assert!(
        matches!((shown, start), (Some(a), Some(b)) if a < b),
        "6061h = 6 at {shown:?}, start at {start:?}"
    );
}
