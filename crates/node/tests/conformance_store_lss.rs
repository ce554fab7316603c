//! Conformance-style cases, categories store/restore (CiA 301 §7.5.2.13/14)
//! and LSS (CiA 305).

mod common;
use common::*;
use drivebus_can::Duration;
use drivebus_node::{FileStorage, Node, NodeConfig};

const SAVE: [u8; 4] = *b"save";
const LOAD: [u8; 4] = *b"load";

#[test]
fn store_01_wrong_signature_refused_and_capability_read() {
    let mut r = Rig::new(device());
    assert_eq!(r.sdo_read(5, 0x1010, 1), fr("585#4310100101000000"));
    Rig::assert_abort(r.sdo_write(5, 0x1010, 1, b"SAVE"), 5, 0x1010, 1, 0x0800_0020);
    Rig::assert_abort(r.sdo_write(5, 0x1011, 1, b"save"), 5, 0x1011, 1, 0x0800_0020);
    Rig::assert_abort(r.sdo_write(5, 0x1010, 5, &SAVE), 5, 0x1010, 5, 0x0609_0011);
}

#[test]
fn store_02_saved_parameters_survive_reset_and_load_brings_defaults_back() {
    let mut r = Rig::new(device());
    Rig::assert_written(r.sdo_write(5, 0x1017, 0, &500u16.to_le_bytes()), 5, 0x1017, 0);
    Rig::assert_written(r.sdo_write(5, 0x1010, 2, &SAVE), 5, 0x1010, 2);
    r.exchange("000#8105", &["705#00"]);
    assert_eq!(r.sdo_read(5, 0x1017, 0), fr("585#4B171000F4010000"));
    // Restore defaults: effective after the next reset.
    Rig::assert_written(r.sdo_write(5, 0x1011, 2, &LOAD), 5, 0x1011, 2);
    assert_eq!(r.sdo_read(5, 0x1017, 0), fr("585#4B171000F4010000"));
    r.exchange("000#8205", &["705#00"]);
    assert_eq!(r.sdo_read(5, 0x1017, 0), fr("585#4B17100000000000"));
}

#[test]
fn store_03_file_storage_survives_a_new_process() {
    let dir = tempfile::tempdir().unwrap();
    {
        let node = Node::with_storage(device(), Box::new(FileStorage::new(dir.path()).unwrap()));
        let mut r = Rig::with_node(node);
        Rig::assert_written(r.sdo_write(5, 0x1017, 0, &250u16.to_le_bytes()), 5, 0x1017, 0);
        Rig::assert_written(r.sdo_write(5, 0x1010, 1, &SAVE), 5, 0x1010, 1);
    }
    let node = Node::with_storage(device(), Box::new(FileStorage::new(dir.path()).unwrap()));
    let mut r = Rig::with_node(node);
    assert_eq!(r.sdo_read(5, 0x1017, 0), fr("585#4B171000FA000000"));
    r.run_for(Duration::from_millis(260));
    assert_eq!(r.take(), frs(&["705#7F"]));
}

#[test]
fn lss_01_unconfigured_node_gets_its_id_and_boots() {
    let mut cfg: NodeConfig = device();
    cfg.node_id = 0xFF;
    let mut r = Rig::new(cfg);
    // Silent: no boot-up, no SDO, no NMT.
    assert!(r.take().is_empty());
    r.exchange("000#0100", &[]);
    // Switch to configuration, set node-ID 0x21, back to waiting.
    r.exchange("7E5#0401000000000000", &[]);
    r.exchange("7E5#1121000000000000", &["7E4#1100000000000000"]);
    r.exchange("7E5#5E00000000000000", &["7E4#5E21000000000000"]);
    r.exchange("7E5#0400000000000000", &["721#00"]);
    assert_eq!(r.node().node_id(), 0x21);
    // Node-relative COB-IDs moved with it: EMCY 80h + 21h.
    r.exchange("621#4014100000000000", &["5A1#43141000A1000000"]);
}

#[test]
fn lss_02_inquire_identity_and_selective_switch() {
    let mut r = Rig::new(device());
    r.exchange("7E5#40BC0A0000000000", &[]);
    r.exchange("7E5#4134120000000000", &[]);
    r.exchange("7E5#4200000100000000", &[]);
    r.exchange("7E5#432A000000000000", &["7E4#4400000000000000"]);
    r.exchange("7E5#5A00000000000000", &["7E4#5ABC0A0000000000"]);
    r.exchange("7E5#5D00000000000000", &["7E4#5D2A000000000000"]);
}
