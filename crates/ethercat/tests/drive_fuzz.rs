//! The `drive_mailbox` fuzz target's harness on stable: over every seed of
//! `fuzz/seeds/drive_mailbox/` and under proptest (structured records and
//! raw bytes). It panics on a finding: a message beyond the mailbox, an
//! unknown type, or a drive that no longer answers afterwards.

use drivebus_ethercat::drive::fuzzing::drive_mailbox;
use proptest::prelude::*;

#[test]
fn seed_corpus() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fuzz/seeds/drive_mailbox");
    let mut n = 0;
    for e in std::fs::read_dir(dir).expect("the seed corpus") {
        let path = e.unwrap().path();
        drive_mailbox(&std::fs::read(&path).unwrap());
        n += 1;
    }
    assert!(n >= 9, "{n} seeds");
}

fn record() -> impl Strategy<Value = Vec<u8>> {
    (0u8..4, prop::collection::vec(any::<u8>(), 0..80)).prop_map(|(tag, mut p)| {
        if tag == 0 && p.len() >= 6 {
            // A plausible header: its length, CoE or FoE most of the time.
            let n = (p.len() - 6) as u16;
            p[..2].copy_from_slice(&n.to_le_bytes());
            p[5] = (p[5] & 0x70) | [3, 4, 3, 0, 5][usize::from(p[5] % 5)];
        }
        let mut v = vec![tag];
        v.extend_from_slice(&(p.len() as u16).to_le_bytes());
        v.extend_from_slice(&p);
        v
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn structured(profile in any::<u8>(), records in prop::collection::vec(record(), 0..12)) {
        let mut data = vec![profile];
        for r in records {
            data.extend_from_slice(&r);
        }
        drive_mailbox(&data);
    }

    #[test]
    fn raw(data in prop::collection::vec(any::<u8>(), 0..300)) {
        drive_mailbox(&data);
    }
}
