//! The LSS address (CiA 305 §3.2: vendor-ID, product code, revision number,
//! serial number) is the identity object 1018h:01h–04h (CiA 301
//! §7.5.2.20): a master that read 1018h over SDO must reach the same slave
//! with every LSS service — inquire identity (5Ah–5Dh), switch state
//! selective (40h–43h), identify remote slave (46h–4Bh) and fastscan (51h).
//! Checked on every profile that answers LSS; the others stay silent on
//! 7E5h whatever 1018h holds.

mod replay_rig;

use drivebus_can::Frame;
use drivebus_lss::master;
use drivebus_lss::{Identity, LssAddressRange, LssField, LssMode};
use drivebus_personality::Profile;
use replay_rig::Rig;

const NODE: u8 = 6;

/// What the slave sent on 7E4h in answer to `frames`.
fn lss(r: &mut Rig, frames: &[Frame]) -> Vec<Frame> {
    r.take();
    for f in frames {
        r.bus.send_from(r.probe, *f);
        r.run_for(drivebus_can::Duration::from_micros(1));
    }
    r.take().into_iter().filter(|f| f.std_id() == Some(0x7E4)).collect()
}

/// 1018h:01h–04h as an SDO client reads them.
fn identity_by_sdo(r: &mut Rig) -> Identity {
    let mut a = Identity::default();
    for (sub, field) in (1u8..).zip(LssField::ALL) {
        field.set(&mut a, r.read_u32(NODE, 0x1018, sub));
    }
    a
}

/// Fastscan (CiA 305 §8.4.2.6) as a master runs it: bit by bit from the
/// top, a bit is 1 when no slave confirms it as 0.
fn fastscan(r: &mut Rig) -> Option<Identity> {
    if lss(r, &[master::fastscan_reset()]).len() != 1 {
        return None;
    }
    let mut found = Identity::default();
    for field in LssField::ALL {
        let sub = field.index();
        let mut id = 0u32;
        for bit in (0..32u8).rev() {
            if lss(r, &[master::fastscan(id, bit, sub, sub)]).is_empty() {
                id |= 1 << bit;
            }
        }
        let next = (sub + 1) % 4;
        if lss(r, &[master::fastscan(id, 0, sub, next)]).len() != 1 {
            return None;
        }
        field.set(&mut found, id);
    }
    Some(found)
}

#[test]
fn the_lss_address_is_the_identity_object() {
    for &p in Profile::all() {
        let (mut r, _) = Rig::new(p, NODE);
        let id = identity_by_sdo(&mut r);
        if !p.info().lss {
            let heard = lss(&mut r, &[master::switch_state_global(LssMode::Configuration)]);
            let heard2 = lss(&mut r, &[master::inquire_identity(LssField::Vendor)]);
            assert!(heard.is_empty() && heard2.is_empty(), "{p}: no LSS, yet {heard:?} {heard2:?}");
            continue;
        }
        // Inquire identity, each part in configuration state.
        lss(&mut r, &[master::switch_state_global(LssMode::Configuration)]);
        for field in LssField::ALL {
            let got = lss(&mut r, &[master::inquire_identity(field)]);
            let want = drivebus_lss::LssResponse::Identity { field, value: field.get(&id) }.to_frame();
            assert_eq!(got, vec![want], "{p}: inquire {field:?}");
        }
        lss(&mut r, &[master::switch_state_global(LssMode::Waiting)]);
        // Switch state selective with the address read by SDO.
        let got = lss(&mut r, &master::switch_state_selective(&id));
        assert_eq!(
            got,
            vec![drivebus_lss::LssResponse::SwitchStateSelective.to_frame()],
            "{p}: switch state selective"
        );
        lss(&mut r, &[master::switch_state_global(LssMode::Waiting)]);
        // Identify remote slave with the exact revision and serial.
        let range = LssAddressRange {
            vendor_id: id.vendor_id,
            product_code: id.product_code,
            revision_low: id.revision,
            revision_high: id.revision,
            serial_low: id.serial,
            serial_high: id.serial,
        };
        let got = lss(&mut r, &master::identify_remote_slave(&range));
        assert_eq!(got.len(), 1, "{p}: identify remote slave");
        // Fastscan finds unconfigured slaves only: node-ID FFh, then reset
        // communication (CiA 305 §8.3.3.1).
        let sel = lss(&mut r, &master::switch_state_selective(&id));
        assert_eq!(sel.len(), 1, "{p}");
        assert_eq!(lss(&mut r, &[master::configure_node_id(0xFF)]).len(), 1, "{p}");
        lss(&mut r, &[master::switch_state_global(LssMode::Waiting)]);
        r.send(&format!("000#82 {NODE:02X}"));
        r.run_ms(1);
        assert_eq!(fastscan(&mut r), Some(id), "{p}: fastscan");
    }
}
