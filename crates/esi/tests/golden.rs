//! The iPOS twin's ESI, compared byte for byte with the committed file.
//! Regenerate it only on purpose: `DRIVEBUS_ESI_BLESS=1 cargo test -p
//! drivebus-esi --test golden`, then review the diff.

mod common;

use drivebus_personality::Profile;
use std::path::Path;

#[test]
fn ipos_esi_matches_the_golden_file() {
    let (desc, _, _) = common::build(Profile::Ipos);
    let xml = drivebus_esi::write(&desc);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/ipos.xml");
    if std::env::var_os("DRIVEBUS_ESI_BLESS").is_some() {
        std::fs::write(&path, &xml).expect("write the golden file");
        return;
    }
    let golden =
        std::fs::read_to_string(&path).expect("tests/golden/ipos.xml (bless with DRIVEBUS_ESI_BLESS=1)");
    if golden != xml {
        let line = golden
            .lines()
            .zip(xml.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(golden.lines().count().min(xml.lines().count()));
        panic!(
            "the iPOS ESI differs from tests/golden/ipos.xml at line {}:\n golden: {:?}\n now:    {:?}\n\
             review and regenerate with DRIVEBUS_ESI_BLESS=1 if the change is intended",
            line + 1,
            golden.lines().nth(line).unwrap_or("<end>"),
            xml.lines().nth(line).unwrap_or("<end>"),
        );
    }
}

#[test]
fn writing_is_deterministic() {
    let (a, _, _) = common::build(Profile::Ipos);
    let (b, _, _) = common::build(Profile::Ipos);
    assert_eq!(drivebus_esi::write(&a), drivebus_esi::write(&b));
}
