//! No input panics the mailbox server: the `coe_mailbox` fuzz target's
//! decoding (`support/driver.rs`) under proptest, structured and raw, and
//! over the fuzz seed corpus, whose seeds are checked to reach what they
//! are named after.

#[path = "support/driver.rs"]
mod driver;
mod support;

use proptest::prelude::*;

fn corpus(name: &str) -> Vec<u8> {
    let path = format!("{}/../../fuzz/seeds/coe_mailbox/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Mailbox type and the byte that says what each response is: the SDO
/// command or SDO Info opcode (CoE), the opcode (FoE), the detail (error).
fn kinds(responses: &[Vec<u8>]) -> Vec<(u8, u8)> {
    responses
        .iter()
        .map(|m| {
            let t = m[5] & 0x0F;
            (t, m.get(if t == 4 { 6 } else { 8 }).copied().unwrap_or(0))
        })
        .collect()
}

#[test]
fn seed_corpus() {
    let all = [
        "expedited",
        "complete_access",
        "segmented",
        "segmented_small",
        "sdo_info",
        "foe",
        "foe_boot",
        "other_protocols",
        "emergency_timeout",
    ];
    for name in all {
        let r = driver::drive(&corpus(name));
        let k = kinds(&r);
        let aborts = k.iter().filter(|&&(t, c)| t == 3 && c == 0x80).count();
        match name {
            // Clean SDO traffic: no abort, no mailbox error.
            "expedited" | "complete_access" | "segmented" | "segmented_small" => {
                assert_eq!((aborts, k.iter().filter(|x| x.0 == 0).count()), (0, 0), "{name}: {k:02X?}")
            }
            // Two OD list fragments, counts, descriptions, then an Info error.
            "sdo_info" => {
                assert_eq!(k[..3], [(3, 0x82), (3, 0x02), (3, 0x02)], "{k:02X?}");
                assert_eq!(k.last().unwrap().1, 0x07);
            }
            // ACKs with a BUSY among them, then the DATA packets of the read.
            "foe" => {
                assert!(k.contains(&(4, 6)), "{k:02X?}");
                assert!(k.iter().filter(|x| x == &&(4, 3)).count() >= 3, "{k:02X?}");
            }
            "foe_boot" => assert_eq!(k, [(4, 4), (4, 4)]),
            "other_protocols" => assert!(k.iter().all(|x| x.0 == 0), "{k:02X?}"),
            _ => assert!(k.iter().any(|x| x == &(3, 0x10)) || !k.is_empty(), "{k:02X?}"),
        }
        assert!(!r.is_empty(), "{name}");
    }
}

/// Records that look like real traffic: request mailboxes with a correct
/// header around random service data, reads, time steps, emergencies.
fn structured() -> impl Strategy<Value = Vec<u8>> {
    let record = prop_oneof![
        4 => (0u8..5, prop_oneof![Just(3u8), Just(4), 0u8..16], any::<u8>(), prop::collection::vec(any::<u8>(), 0..300))
            .prop_map(|(state, t, cnt, body)| {
                let mut m = (body.len() as u16).to_le_bytes().to_vec();
                m.extend_from_slice(&[0, 0, 0, t | ((cnt % 8) << 4)]);
                m.extend_from_slice(&body);
                let mut r = vec![state << 2];
                r.extend_from_slice(&(m.len() as u16).to_le_bytes());
                r.extend_from_slice(&m);
                r
            }),
        2 => any::<u8>().prop_map(|n| vec![1, 1, 0, n]),
        1 => (any::<u16>(), any::<u8>()).prop_map(|(ms, s)| { let b = ms.to_le_bytes(); vec![2, 3, 0, b[0], b[1], s] }),
        1 => any::<u8>().prop_map(|b| vec![3, 1, 0, b]),
    ];
    (any::<u8>(), prop::collection::vec(record, 0..40)).prop_map(|(cfg, recs)| {
        let mut v = vec![cfg];
        for r in recs {
            v.extend_from_slice(&r);
        }
        v
    })
}

/// A seed with some bytes changed, as a fuzzer mutates it.
fn mutated_seed() -> impl Strategy<Value = Vec<u8>> {
    let names =
        ["expedited", "complete_access", "segmented", "segmented_small", "sdo_info", "foe", "foe_boot"];
    (0..names.len(), prop::collection::vec((any::<u16>(), any::<u8>()), 1..8)).prop_map(move |(i, edits)| {
        let mut v = corpus(names[i]);
        for (at, b) in edits {
            let n = v.len();
            v[usize::from(at) % n] = b;
        }
        v
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn raw_bytes_never_panic(input in prop::collection::vec(any::<u8>(), 0..600)) {
        driver::drive(&input);
    }

    #[test]
    fn structured_traffic_never_panics(input in structured()) {
        driver::drive(&input);
    }

    #[test]
    fn mutated_seeds_never_panic(input in mutated_seed()) {
        driver::drive(&input);
    }
}
