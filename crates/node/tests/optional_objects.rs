//! Optional CiA 301 objects a device may lack (`NodeConfig::emcy_inhibit`,
//! `sync_window`, `sync_counter`, `sdo_server_param`): absent from the
//! dictionary, the service keeps working with the object's power-on
//! meaning.

mod common;
use common::*;
use drivebus_can::Duration;

#[test]
fn without_1015h_1007h_1019h() {
    let mut cfg = device();
    cfg.emcy_inhibit = false;
    cfg.sync_window = false;
    cfg.sync_counter = false;
    let mut r = Rig::new(cfg);
    for index in [0x1015u16, 0x1007, 0x1019] {
        // CiA 301 §7.2.4.3.17: 0602 0000h "object does not exist".
        let resp = r.sdo_read(5, index, 0);
        Rig::assert_abort(resp, 5, index, 0, 0x0602_0000);
        assert!(r.node().od().object(index).is_none(), "{index:04X}h");
    }
    // EMCY: two errors back to back both go out at once (no inhibit time).
    r.raise_emcy(0x5000, [0; 5]);
    r.raise_emcy(0x6000, [0; 5]);
    r.run_for(Duration::from_micros(1));
    let emcy: Vec<_> = r.take().into_iter().filter(|f| f.std_id() == Some(0x85)).collect();
    assert_eq!(emcy.len(), 2, "{emcy:?}");
    // SYNC without a counter and without a window still reaches the node.
    r.send("080#");
    assert!(r.take().is_empty());
}

/// Without 1200h (optional for the default server, CiA 301 §7.5.2.33) the
/// default SDO server still answers on 600h/580h + node-ID, and after a
/// reset communication too.
#[test]
fn without_1200h_the_default_server_answers() {
    let mut cfg = device();
    cfg.sdo_server_param = false;
    let mut r = Rig::new(cfg);
    Rig::assert_abort(r.sdo_read(5, 0x1200, 1), 5, 0x1200, 1, 0x0602_0000);
    assert_eq!(r.sdo_read(5, 0x1000, 0), fr("585#43 00 10 00 92 01 02 00"));
    r.exchange("000#82 05", &["705#00"]);
    assert_eq!(r.sdo_read(5, 0x1000, 0), fr("585#43 00 10 00 92 01 02 00"));
}

#[test]
fn defaults_have_them() {
    let mut r = Rig::new(device());
    for (index, sub) in [(0x1015u16, 0u8), (0x1007, 0), (0x1019, 0), (0x1200, 1)] {
        let resp = r.sdo_read(5, index, sub);
        assert_eq!(resp.data()[0] & 0xF0, 0x40, "{index:04X}h: {resp:?}");
    }
}
