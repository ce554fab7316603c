//! Random frame sequences never panic, never break the state machine and
//! keep the poll promise.

mod common;

use common::{Dev, NODE, ms};
use drivebus_can::{CanId, Frame, Instant};
use drivebus_nmt::{CommandSet, InitSubState, NmtCommand, NmtConfig, NmtEvent, NmtState};
use proptest::prelude::*;

#[derive(Clone, Debug)]
enum Step {
    Frame { id: u16, rtr: bool, data: Vec<u8>, ext: bool },
    Command { cs: u8, node: u8 },
    Heartbeat { node: u8, state: u8 },
    Write { index: u16, sub: u8, data: Vec<u8> },
    Error { class: u8 },
    Wait { ms: u64 },
}

fn step() -> impl Strategy<Value = Step> {
    let cs = prop_oneof![Just(1u8), Just(2), Just(0x80), Just(0x81), Just(0x82), any::<u8>()];
    let node = prop_oneof![Just(0u8), Just(NODE), 1u8..=127, any::<u8>()];
    prop_oneof![
        (
            prop_oneof![Just(0u16), 0x700u16..=0x77F, 0u16..=0x7FF],
            any::<bool>(),
            proptest::collection::vec(any::<u8>(), 0..=8),
            any::<bool>()
        )
            .prop_map(|(id, rtr, data, ext)| Step::Frame { id, rtr, data, ext }),
        (cs, node).prop_map(|(cs, node)| Step::Command { cs, node }),
        (1u8..=8, prop_oneof![Just(0u8), Just(4), Just(5), Just(0x7F), any::<u8>()])
            .prop_map(|(node, state)| Step::Heartbeat { node, state }),
        (
            prop_oneof![Just(0x1016u16), Just(0x1017), Just(0x100C), Just(0x100D), Just(0x1029)],
            0u8..=5,
            proptest::collection::vec(any::<u8>(), 0..=5)
        )
            .prop_map(|(index, sub, data)| Step::Write { index, sub, data }),
        (0u8..=4).prop_map(|class| Step::Error { class }),
        (0u64..=700).prop_map(|ms| Step::Wait { ms }),
    ]
}

fn config() -> impl Strategy<Value = NmtConfig> {
    (any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>()).prop_map(
        |(no80, auto, hb, guard, life)| NmtConfig {
            supported_commands: if no80 {
                CommandSet::ALL.without(NmtCommand::EnterPreOperational)
            } else {
                CommandSet::ALL
            },
            auto_start: auto,
            heartbeat_supported: hb,
            guarding_supported: guard,
            life_guarding_honoured: life,
            ..NmtConfig::new(NODE)
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn random_sequences(cfg in config(), steps in proptest::collection::vec(step(), 0..60)) {
        let mut d = Dev::new(cfg, 4, 2);
        let mut t = 0u64;
        d.boot(ms(t));
        let mut deadline: Option<Instant> = None;
        for s in steps {
            let ev = match s {
                Step::Frame { id, rtr, data, ext } => {
                    let cid = if ext { CanId::Extended(u32::from(id)) } else { CanId::Standard(id) };
                    let f = if rtr {
                        Frame::try_remote(cid, data.len() as u8).unwrap()
                    } else {
                        Frame::try_new(cid, &data).unwrap()
                    };
                    d.rx(f, ms(t))
                }
                Step::Command { cs, node } => d.cmd(cs, node, ms(t)),
                Step::Heartbeat { node, state } => d.rx(Frame::new(0x700 + u16::from(node), &[state]), ms(t)),
                Step::Write { index, sub, data } => {
                    let _ = d.write(index, sub, &data, ms(t));
                    None
                }
                Step::Error { class } => d.nmt.on_error(drivebus_nmt::ErrorClass(class)),
                Step::Wait { ms: dt } => {
                    // An early poll does nothing observable.
                    if let Some(dl) = deadline && ms(t + dt) < dl {
                        d.poll(ms(t + dt));
                        prop_assert!(d.out.is_empty());
                    }
                    t += dt;
                    None
                }
            };
            if matches!(ev, Some(NmtEvent::ResetApplication | NmtEvent::ResetCommunication)) {
                prop_assert!(d.nmt.state().is_initialisation());
                d.boot(ms(t));
            }
            deadline = d.poll(ms(t));
            if let Some(dl) = deadline {
                prop_assert!(dl >= ms(t));
            }
            let _ = d.events();
            let state = d.nmt.state();
            prop_assert!(
                matches!(state, NmtState::PreOperational | NmtState::Operational | NmtState::Stopped),
                "{state:?}"
            );
            prop_assert_ne!(state, NmtState::Initialisation(InitSubState::Initialising));
            // Everything the slave sends is one byte on its own 700h + node-ID.
            for f in d.take() {
                prop_assert_eq!(f.std_id(), Some(0x705));
                prop_assert_eq!(f.len(), 1);
                prop_assert!(!f.is_rtr());
            }
        }
    }
}
