//! The machine file is outside input: whatever the text, parsing and
//! laying it over every profile answer with a machine or an error placed
//! inside the text — never a panic — and every machine that passes the
//! checks builds a drive (DEVELOPERS.md: nothing panics on input).

use drivebus_personality::Profile;
use drivebus_personality::machine::MachineFile;
use proptest::prelude::*;

const EXAMPLE: &str = include_str!("../../../docs/examples/machine.toml");

fn exercise(text: &str) {
    let lines = text.split('\n').count();
    match MachineFile::parse(text) {
        Err(e) => {
            assert!(e.line <= lines && (e.line == 0) == (e.column == 0), "{e} in {text:?}");
        }
        Ok(f) => {
            let nodes: Vec<u8> = f.nodes().collect();
            assert!(nodes.iter().all(|n| (1..=127).contains(n)));
            for &p in Profile::all() {
                for &n in &nodes {
                    match f.machine_for(p, n) {
                        Ok(m) => {
                            assert!(m.check().is_ok());
                            // Only a valid machine comes out; it must build
                            // (the model may still refuse extreme values).
                            let _ = p.build_on(n, &m);
                        }
                        Err(e) => assert!(e.line >= 1 && e.line <= lines, "{e}"),
                    }
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// The documented example with a slice cut out and other text put in.
    #[test]
    fn a_mangled_example_never_panics(at in 0usize..EXAMPLE.len(), cut in 0usize..40, put in "[ -~\n]{0,12}") {
        let at = (0..=at).rev().find(|&i| EXAMPLE.is_char_boundary(i)).unwrap_or(0);
        let end = (at + cut..=EXAMPLE.len()).find(|&i| EXAMPLE.is_char_boundary(i)).unwrap_or(EXAMPLE.len());
        let text = format!("{}{}{}", &EXAMPLE[..at], put, &EXAMPLE[end..]);
        exercise(&text);
    }

    /// Node tables with arbitrary numbers in every numeric key.
    #[test]
    fn any_numbers_never_panic(
        v in proptest::collection::vec(prop_oneof![
            Just("nan".to_owned()), Just("inf".to_owned()), Just("-inf".to_owned()),
            any::<f64>().prop_map(|x| format!("{x:e}")),
            (-1000i64..1000).prop_map(|x| x.to_string()),
        ], 12),
        id in 0u16..300,
    ) {
        let text = format!(
            "[[node]]\nid = {id}\nfeed = {}\ngear_ratio = {}\nstart = {}\n\
             limits = {{ negative = {}, positive = {}, hysteresis = {} }}\n\
             home_switch = {{ from = {}, to = {} }}\nhard_stops = {{ negative = {}, positive = {} }}\n\
             index = {{ offset = {} }}\nload = {{ inertia = {} }}\n",
            v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11]
        );
        exercise(&text);
    }

    /// The signals' keys and an input change with arbitrary numbers.
    #[test]
    fn any_signal_numbers_never_panic(
        v in proptest::collection::vec(prop_oneof![
            Just("nan".to_owned()), Just("inf".to_owned()), Just("-inf".to_owned()),
            any::<f64>().prop_map(|x| format!("{x:e}")),
            (-1000i64..1000).prop_map(|x| x.to_string()),
        ], 10),
        line in 0u16..300,
        input in prop_oneof![
            Just("digital"), Just("analog"), Just("master_velocity"), Just("master_position"),
            Just("motor_temperature"), Just("brake"),
        ],
    ) {
        let text = format!(
            "[[node]]\nid = 5\nio = {{ digital_inputs = [{line}], analog_inputs = [{}], wiring = {{ {line} = {line} }} }}\n\
             master_encoder = {{ position = {}, velocity = {} }}\n\
             brake = {{ release_delay = {}, apply_delay = {}, holding_torque = {} }}\n\
             temperature = {{ ambient = {}, motor = {} }}\n\
             [[node.inputs]]\nat = {}\ninput = \"{input}\"\nline = {line}\nvalue = {}\n",
            v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9]
        );
        exercise(&text);
    }
}

#[test]
fn the_example_itself_is_a_machine() {
    let f = MachineFile::parse(EXAMPLE).unwrap();
    assert_eq!(f.nodes().collect::<Vec<_>>(), [2, 5]);
    exercise(EXAMPLE);
}
