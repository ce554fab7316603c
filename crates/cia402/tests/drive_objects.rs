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
