//! The installed CiA 402 objects: data types, access and PDO mapping as
//! CiA 402-2 §6 describes them.

use drivebus_cia402::drive::{Drive, DriveConfig};
use drivebus_node::{Node, NodeConfig};
use drivebus_od::{Access, DataType as T};

#[test]
fn object_descriptions() {
    use Access::{Ro, Rw, Rww};
    let mut node = Node::new(NodeConfig::new(1));
    Drive::install(&mut node, DriveConfig::default()).unwrap();
    // (index, sub, type, access, PDO-mappable)
    let table: &[(u16, u8, T, Access, bool)] = &[
        (0x6007, 0, T::Integer16, Rw, false),
        (0x603F, 0, T::Unsigned16, Ro, true),
        (0x6040, 0, T::Unsigned16, Rww, true),
        (0x6041, 0, T::Unsigned16, Ro, true),
        (0x605A, 0, T::Integer16, Rw, false),
        (0x605E, 0, T::Integer16, Rw, false),
        (0x6060, 0, T::Integer8, Rww, true),
        (0x6061, 0, T::Integer8, Ro, true),
        (0x6062, 0, T::Integer32, Ro, true),
        (0x6063, 0, T::Integer32, Ro, true),
        (0x6064, 0, T::Integer32, Ro, true),
        (0x6065, 0, T::Unsigned32, Rw, true),
        (0x6066, 0, T::Unsigned16, Rw, true),
        (0x6067, 0, T::Unsigned32, Rw, true),
        (0x6068, 0, T::Unsigned16, Rw, true),
        (0x606B, 0, T::Integer32, Ro, true),
        (0x606C, 0, T::Integer32, Ro, true),
        (0x606D, 0, T::Unsigned16, Rw, true),
        (0x6071, 0, T::Integer16, Rww, true),
        (0x6072, 0, T::Unsigned16, Rw, true),
        (0x6074, 0, T::Integer16, Ro, true),
        (0x6075, 0, T::Unsigned32, Rw, false),
        (0x6076, 0, T::Unsigned32, Rw, false),
        (0x6077, 0, T::Integer16, Ro, true),
        (0x6078, 0, T::Integer16, Ro, true),
        (0x6079, 0, T::Unsigned32, Ro, true),
        (0x607A, 0, T::Integer32, Rww, true),
        (0x607B, 2, T::Integer32, Rw, false),
        (0x607D, 1, T::Integer32, Rw, false),
        (0x607E, 0, T::Unsigned8, Rw, false),
        (0x6081, 0, T::Unsigned32, Rw, true),
        (0x6085, 0, T::Unsigned32, Rw, true),
        (0x6086, 0, T::Integer16, Rw, true),
        (0x6087, 0, T::Unsigned32, Rw, true),
        (0x608F, 1, T::Unsigned32, Ro, false),
        (0x6091, 2, T::Unsigned32, Rw, false),
        (0x6092, 1, T::Unsigned32, Rw, false),
        (0x6098, 0, T::Integer8, Rw, true),
        (0x6099, 2, T::Unsigned32, Rw, true),
        (0x60B8, 0, T::Unsigned16, Rww, true),
        (0x60B9, 0, T::Unsigned16, Ro, true),
        (0x60BA, 0, T::Integer32, Ro, true),
        (0x60C2, 2, T::Integer8, Rw, true),
        (0x60C5, 0, T::Unsigned32, Rw, true),
        (0x60F4, 0, T::Integer32, Ro, true),
        (0x60FD, 0, T::Unsigned32, Ro, true),
        (0x60FE, 1, T::Unsigned32, Rww, true),
        (0x60FF, 0, T::Integer32, Rww, true),
        (0x6502, 0, T::Unsigned32, Ro, false),
        (0x6042, 0, T::Integer16, Rww, true),
        (0x6044, 0, T::Integer16, Ro, true),
        (0x6048, 2, T::Unsigned16, Rw, false),
    ];
    for &(i, s, t, a, m) in table {
        let e = node.od().get(i, s).unwrap_or_else(|| panic!("{i:04X}:{s} missing"));
        assert_eq!((e.data_type, e.access, e.pdo_mappable), (t, a, m), "{i:04X}:{s}");
    }
    // hm is not supported without a handler: no 60E3h.
    assert!(node.od().get(0x60E3, 0).is_none());
    // 608Fh:1 is the encoder: 2^20 increments per revolution.
    assert_eq!(node.od().get_u32(0x608F, 1), Some(1 << 20));
}

/// A device without some CiA 402 objects (a manufacturer whose manual does
/// not list them): withdrawn, they are gone from the dictionary, the drive
/// keeps working with the parameter's value, takes what the application
/// writes into it, and goes back to the power-on value at reset
/// application — through a reload from the dictionary too.
#[test]
fn withdrawn_objects_keep_their_parameters() {
    use drivebus_node::{Application, NmtState, NodeEvent};
    use drivebus_od::ObjectHooks;
    let mut node = Node::new(NodeConfig::new(1));
    let mut drive = Drive::install(&mut node, DriveConfig::default()).unwrap();
    let max = drive.mode_params().max_profile_velocity;
    assert!(max > 1000);
    for index in [0x607F, 0x6062, 0x6075] {
        assert!(drive.withdraw_object(node.od_mut(), index));
        assert!(node.od().object(index).is_none() && drive.is_withdrawn(index));
    }
    assert!(!drive.withdraw_object(node.od_mut(), 0x607F), "already out");
    let od = node.od_mut();
    let reload = |d: &mut Drive, od: &mut drivebus_od::ObjectDictionary| {
        d.on_event(
            od,
            NodeEvent::NmtState { from: NmtState::Stopped, to: NmtState::PreOperational },
            drivebus_can::Instant::ZERO,
        )
    };
    reload(&mut drive, od);
    assert_eq!(drive.mode_params().max_profile_velocity, max, "power-on value kept");
    // The application sets it (a personality's own object maps onto it).
    drive.on_write(od, 0x607F, 0, &1000u32.to_le_bytes()).unwrap();
    reload(&mut drive, od);
    assert_eq!(drive.mode_params().max_profile_velocity, 1000, "the written value survives a reload");
    drive.on_event(od, NodeEvent::ResetApplication, drivebus_can::Instant::ZERO);
    reload(&mut drive, od);
    assert_eq!(drive.mode_params().max_profile_velocity, max, "reset application: power-on value");
    // Live values of withdrawn objects are not published; the others are.
    drive.poll(od, drivebus_can::Instant::from_millis(1));
    assert!(od.get(0x6062, 0).is_none());
    assert!(od.get_u32(0x6041, 0).is_some_and(|sw| sw != 0));
}
