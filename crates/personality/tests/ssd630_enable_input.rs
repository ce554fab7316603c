//! The SSD 630's "Controller Active" / "Drive Active" input X10.7 switched
//! at run time (`PersonalityDevice::behaviour_mut::<Ssd630>()`), seed003
//! *CANopen-630* manual:
//!
//! * §10.2 Switch on Disabled: the controller checks "a. Controller Active
//!   Input = 24 V … If the conditions are fulfilled, the remote bit in the
//!   statusword will be set and the Shutdown command is being expected";
//! * §10.2 transitions 13/14: "Fault occured or Drive active input = 0V
//!   (see option Index 2019h)"; Fault: "If the controller has been
//!   deactivated via the Active Input only, it will be switched
//!   automatically in the operating state Switch on Disabled";
//! * §11 2019h: 0 = "Remote → local in Switched on disable state",
//!   1 = "Remote → local in FAULT State";
//! * §9 Table 1: 5441h "contact 1 = enable input", error register 81h;
//! * §14.8: statuswords 0240h, 0231h, 0233h, 0627h of the initialisation
//!   (X10.7 at 24 V).

mod replay_rig;

use drivebus_personality::Profile;
use drivebus_personality::ssd630::Ssd630;
use replay_rig::*;

fn statusword(r: &mut Rig) -> u16 {
    r.read_u32(1, 0x6041, 0) as u16
}

fn controlword(r: &mut Rig, cw: u16) {
    let b = cw.to_le_bytes();
    Rig::assert_written(r.sdo_write(1, 0x6040, 0, &b), 1, 0x6040, 0);
    r.run_ms(5);
}

fn set_input(r: &mut Rig, on: bool) {
    r.pn_mut().app.behaviour_mut::<Ssd630>().expect("the 630's behaviour").set_enable_input(on);
    r.run_ms(5);
}

/// §14.8 steps: Shutdown, Switch on, Enable operation.
fn enable(r: &mut Rig) {
    assert_eq!(statusword(r), 0x0240);
    for (cw, sw) in [(0x06, 0x0231), (0x07, 0x0233), (0x0F, 0x0627)] {
        controlword(r, cw);
        assert_eq!(statusword(r), sw, "after controlword {cw:04X}h");
    }
}

fn rig() -> Rig {
    let (r, _boot) = Rig::new(Profile::Ssd630, 1);
    r
}

#[test]
fn dropping_the_input_goes_to_switch_on_disabled() {
    let mut r = rig();
    enable(&mut r);
    set_input(&mut r, false);
    // 2019h = 0: Switch on disabled, remote bit 9 clear (0040h), no EMCY.
    assert_eq!(statusword(&mut r), 0x0040);
    assert!(r.take().iter().all(|f| f.std_id() != Some(0x81)), "no EMCY");
    // Not remote: Shutdown is not accepted (the state stays).
    controlword(&mut r, 0x06);
    assert_eq!(statusword(&mut r), 0x0040);
    // 24 V again: remote, Shutdown expected and accepted.
    set_input(&mut r, true);
    assert_eq!(statusword(&mut r), 0x0240);
    controlword(&mut r, 0x00);
    enable(&mut r);
    assert!(r.pn_mut().app.behaviour_mut::<Ssd630>().unwrap().enable_input());
}

#[test]
fn with_2019h_1_dropping_the_input_faults() {
    let mut r = rig();
    Rig::assert_written(r.sdo_write(1, 0x2019, 0, &[1, 0]), 1, 0x2019, 0);
    enable(&mut r);
    r.take();
    set_input(&mut r, false);
    r.run_ms(20);
    // FAULT with EMCY 5441h, error register 81h (§9 Table 1).
    let emcy: Vec<_> = r.take().into_iter().filter(|f| f.std_id() == Some(0x81)).collect();
    assert_eq!(emcy.first(), Some(&fr("081#41 54 81 00 00 00 00 00")), "{emcy:?}");
    assert_eq!(statusword(&mut r) & 0x4F, 0x08, "Fault");
    assert_eq!(statusword(&mut r) & 0x0200, 0, "not remote");
    // 24 V again, Fault Reset edge: Switch on disabled, then enabled as usual.
    set_input(&mut r, true);
    controlword(&mut r, 0x00);
    controlword(&mut r, 0x80);
    controlword(&mut r, 0x00);
    enable(&mut r);
}

#[test]
fn other_behaviours_are_not_the_630() {
    let (mut r, _) = Rig::new(Profile::Kc1, 1);
    assert!(r.pn_mut().app.behaviour_mut::<Ssd630>().is_none());
}
