//! CiA 301 data types, access types and object codes.

use crate::SdoAbort;
use core::cmp::Ordering;

/// A CiA 301 static data type, by its object dictionary index (0001h..001Bh).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u16)]
#[allow(missing_docs)]
pub enum DataType {
    Boolean = 0x01,
    Integer8 = 0x02,
    Integer16 = 0x03,
    Integer32 = 0x04,
    Unsigned8 = 0x05,
    Unsigned16 = 0x06,
    Unsigned32 = 0x07,
    Real32 = 0x08,
    VisibleString = 0x09,
    OctetString = 0x0A,
    UnicodeString = 0x0B,
    TimeOfDay = 0x0C,
    TimeDifference = 0x0D,
    Domain = 0x0F,
    Integer24 = 0x10,
    Real64 = 0x11,
    Integer40 = 0x12,
    Integer48 = 0x13,
    Integer56 = 0x14,
    Integer64 = 0x15,
    Unsigned24 = 0x16,
    Unsigned40 = 0x18,
    Unsigned48 = 0x19,
    Unsigned56 = 0x1A,
    Unsigned64 = 0x1B,
}

/// Every data type, for tests and tools.
pub const ALL_DATA_TYPES: [DataType; 25] = {
    use DataType::*;
    [
        Boolean,
        Integer8,
        Integer16,
        Integer32,
        Unsigned8,
        Unsigned16,
        Unsigned32,
        Real32,
        VisibleString,
        OctetString,
        UnicodeString,
        TimeOfDay,
        TimeDifference,
        Domain,
        Integer24,
        Real64,
        Integer40,
        Integer48,
        Integer56,
        Integer64,
        Unsigned24,
        Unsigned40,
        Unsigned48,
        Unsigned56,
        Unsigned64,
    ]
};

/// How a numeric type is interpreted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NumKind {
    /// Two's complement integer.
    Signed,
    /// Unsigned integer (and BOOLEAN).
    Unsigned,
    /// IEEE 754 float.
    Float,
}

impl DataType {
    /// From the CiA 301 type index, if it names a static data type.
    pub fn from_index(code: u16) -> Option<DataType> {
        ALL_DATA_TYPES.iter().copied().find(|t| *t as u16 == code)
    }

    /// Size in bytes for fixed-size types; `None` for strings and DOMAIN.
    #[inline]
    pub const fn fixed_size(self) -> Option<usize> {
        use DataType::*;
        Some(match self {
            Boolean | Integer8 | Unsigned8 => 1,
            Integer16 | Unsigned16 => 2,
            Integer24 | Unsigned24 => 3,
            Integer32 | Unsigned32 | Real32 => 4,
            Integer40 | Unsigned40 => 5,
            Integer48 | Unsigned48 | TimeOfDay | TimeDifference => 6,
            Integer56 | Unsigned56 => 7,
            Integer64 | Unsigned64 | Real64 => 8,
            VisibleString | OctetString | UnicodeString | Domain => return None,
        })
    }

    /// Number kind for types that compare numerically (limits), else `None`.
    #[inline]
    pub const fn num_kind(self) -> Option<NumKind> {
        use DataType::*;
        match self {
            Integer8 | Integer16 | Integer24 | Integer32 | Integer40 | Integer48 | Integer56 | Integer64 => {
                Some(NumKind::Signed)
            }
            Boolean | Unsigned8 | Unsigned16 | Unsigned24 | Unsigned32 | Unsigned40 | Unsigned48
            | Unsigned56 | Unsigned64 => Some(NumKind::Unsigned),
            Real32 | Real64 => Some(NumKind::Float),
            _ => None,
        }
    }

    /// True for VISIBLE_STRING, OCTET_STRING, UNICODE_STRING and DOMAIN.
    #[inline]
    pub const fn is_variable(self) -> bool {
        self.fixed_size().is_none()
    }

    /// The CiA 306 / CiA 301 name, e.g. `UNSIGNED32`.
    pub const fn name(self) -> &'static str {
        use DataType::*;
        match self {
            Boolean => "BOOLEAN",
            Integer8 => "INTEGER8",
            Integer16 => "INTEGER16",
            Integer24 => "INTEGER24",
            Integer32 => "INTEGER32",
            Integer40 => "INTEGER40",
            Integer48 => "INTEGER48",
            Integer56 => "INTEGER56",
            Integer64 => "INTEGER64",
            Unsigned8 => "UNSIGNED8",
            Unsigned16 => "UNSIGNED16",
            Unsigned24 => "UNSIGNED24",
            Unsigned32 => "UNSIGNED32",
            Unsigned40 => "UNSIGNED40",
            Unsigned48 => "UNSIGNED48",
            Unsigned56 => "UNSIGNED56",
            Unsigned64 => "UNSIGNED64",
            Real32 => "REAL32",
            Real64 => "REAL64",
            VisibleString => "VISIBLE_STRING",
            OctetString => "OCTET_STRING",
            UnicodeString => "UNICODE_STRING",
            TimeOfDay => "TIME_OF_DAY",
            TimeDifference => "TIME_DIFFERENCE",
            Domain => "DOMAIN",
        }
    }

    /// Parse a type name as [`DataType::name`] writes it (case-insensitive;
    /// short forms `u8`, `i32`, `f32`, `str`, ... accepted).
    pub fn from_name(s: &str) -> Option<DataType> {
        use DataType::*;
        let up = s.trim();
        let short = match up.to_ascii_lowercase().as_str() {
            "bool" => Some(Boolean),
            "i8" => Some(Integer8),
            "i16" => Some(Integer16),
            "i24" => Some(Integer24),
            "i32" => Some(Integer32),
            "i40" => Some(Integer40),
            "i48" => Some(Integer48),
            "i56" => Some(Integer56),
            "i64" => Some(Integer64),
            "u8" => Some(Unsigned8),
            "u16" => Some(Unsigned16),
            "u24" => Some(Unsigned24),
            "u32" => Some(Unsigned32),
            "u40" => Some(Unsigned40),
            "u48" => Some(Unsigned48),
            "u56" => Some(Unsigned56),
            "u64" => Some(Unsigned64),
            "f32" => Some(Real32),
            "f64" => Some(Real64),
            "str" | "string" => Some(VisibleString),
            "bytes" | "octets" => Some(OctetString),
            "domain" => Some(Domain),
            _ => None,
        };
        short.or_else(|| ALL_DATA_TYPES.iter().copied().find(|t| t.name().eq_ignore_ascii_case(up)))
    }
}

/// Access type of a sub-object (CiA 306 `AccessType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// Read only; the device may change it.
    Ro,
    /// Write only.
    Wo,
    /// Read and write.
    Rw,
    /// Read and write, process input (TPDO side).
    Rwr,
    /// Read and write, process output (RPDO side).
    Rww,
    /// Read only and constant.
    Const,
}

impl Access {
    /// SDO upload allowed.
    #[inline]
    pub const fn readable(self) -> bool {
        !matches!(self, Access::Wo)
    }
    /// SDO download allowed.
    #[inline]
    pub const fn writable(self) -> bool {
        matches!(self, Access::Wo | Access::Rw | Access::Rwr | Access::Rww)
    }
    /// CiA 306 spelling.
    pub const fn name(self) -> &'static str {
        match self {
            Access::Ro => "ro",
            Access::Wo => "wo",
            Access::Rw => "rw",
            Access::Rwr => "rwr",
            Access::Rww => "rww",
            Access::Const => "const",
        }
    }
    /// Parse the CiA 306 spelling (case-insensitive).
    pub fn from_name(s: &str) -> Option<Access> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "ro" => Access::Ro,
            "wo" => Access::Wo,
            "rw" => Access::Rw,
            "rwr" => Access::Rwr,
            "rww" => Access::Rww,
            "const" => Access::Const,
            _ => return None,
        })
    }
}

/// Object code (CiA 306 `ObjectType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum ObjectCode {
    /// No data fields (0).
    Null = 0,
    /// Large variable amount of data (2).
    Domain = 2,
    /// Type definition (5).
    DefType = 5,
    /// Record type definition (6).
    DefStruct = 6,
    /// Single value (7).
    Var = 7,
    /// Multiple fields of the same type (8).
    Array = 8,
    /// Multiple fields of different types (9).
    Record = 9,
}

impl ObjectCode {
    /// From the CiA 306 numeric code.
    pub fn from_code(c: u8) -> Option<ObjectCode> {
        Some(match c {
            0 => ObjectCode::Null,
            2 => ObjectCode::Domain,
            5 => ObjectCode::DefType,
            6 => ObjectCode::DefStruct,
            7 => ObjectCode::Var,
            8 => ObjectCode::Array,
            9 => ObjectCode::Record,
            _ => return None,
        })
    }
}

/// Which 1010h/1011h group a sub-object is stored and restored with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PersistGroup {
    /// Never stored (live values, read-only data).
    Volatile,
    /// Communication parameters (1000h..1FFFh), 1010h/1011h sub 2.
    Communication,
    /// Application parameters (6000h..9FFFh), sub 3.
    Application,
    /// Manufacturer parameters (2000h..5FFFh), sub 4.
    Manufacturer,
}

impl PersistGroup {
    /// The group CiA 301 assigns by index range.
    pub const fn for_index(index: u16) -> PersistGroup {
        match index {
            0x1000..=0x1FFF => PersistGroup::Communication,
            0x2000..=0x5FFF => PersistGroup::Manufacturer,
            0x6000..=0x9FFF => PersistGroup::Application,
            _ => PersistGroup::Volatile,
        }
    }
    /// The 1010h/1011h sub-index of this group (`None` for volatile).
    pub const fn sub_index(self) -> Option<u8> {
        match self {
            PersistGroup::Volatile => None,
            PersistGroup::Communication => Some(2),
            PersistGroup::Application => Some(3),
            PersistGroup::Manufacturer => Some(4),
        }
    }
}

/// Compare two little-endian encodings of the same numeric type.
/// Returns `None` for non-numeric types or wrong lengths.
pub fn compare_le(dt: DataType, a: &[u8], b: &[u8]) -> Option<Ordering> {
    let n = dt.fixed_size()?;
    if a.len() != n || b.len() != n {
        return None;
    }
    match dt.num_kind()? {
        NumKind::Unsigned => Some(le_u64(a).cmp(&le_u64(b))),
        NumKind::Signed => Some(le_i64(a).cmp(&le_i64(b))),
        NumKind::Float => {
            let (x, y) = if n == 4 {
                (f32::from_bits(le_u64(a) as u32) as f64, f32::from_bits(le_u64(b) as u32) as f64)
            } else {
                (f64::from_bits(le_u64(a)), f64::from_bits(le_u64(b)))
            };
            x.partial_cmp(&y)
        }
    }
}

/// Little-endian unsigned read of up to 8 bytes.
#[inline]
pub fn le_u64(b: &[u8]) -> u64 {
    let mut buf = [0u8; 8];
    let n = b.len().min(8);
    buf[..n].copy_from_slice(&b[..n]);
    u64::from_le_bytes(buf)
}

/// Little-endian signed read of 1..=8 bytes, sign-extended.
#[inline]
pub fn le_i64(b: &[u8]) -> i64 {
    let n = b.len().min(8);
    if n == 0 {
        return 0;
    }
    let shift = 64 - 8 * n as u32;
    ((le_u64(b) << shift) as i64) >> shift
}

/// Check that `len` bytes fit `dt` for a download (exact size for fixed types).
#[inline]
pub fn check_len(dt: DataType, len: usize) -> Result<(), SdoAbort> {
    match dt.fixed_size() {
        Some(n) if len > n => Err(SdoAbort::DATA_TOO_LONG),
        Some(n) if len < n => Err(SdoAbort::DATA_TOO_SHORT),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_names_round_trip() {
        for t in ALL_DATA_TYPES {
            assert_eq!(DataType::from_index(t as u16), Some(t));
            assert_eq!(DataType::from_name(t.name()), Some(t));
        }
        assert_eq!(DataType::Integer24.fixed_size(), Some(3));
        assert_eq!(DataType::TimeOfDay.fixed_size(), Some(6));
        assert_eq!(DataType::Domain.fixed_size(), None);
        assert_eq!(DataType::from_name("u16"), Some(DataType::Unsigned16));
    }

    #[test]
    fn signed_compare_sign_extends() {
        assert_eq!(le_i64(&[0xFF, 0xFF, 0xFF]), -1);
        assert_eq!(le_i64(&[0x00, 0x00, 0x80]), -(1 << 23));
        assert_eq!(compare_le(DataType::Integer24, &[0xFF, 0xFF, 0xFF], &[1, 0, 0]), Some(Ordering::Less));
        assert_eq!(compare_le(DataType::Unsigned16, &[0xFF, 0xFF], &[1, 0]), Some(Ordering::Greater));
        assert_eq!(compare_le(DataType::Unsigned16, &[0xFF], &[1, 0]), None);
    }

    #[test]
    fn access_rules() {
        assert!(!Access::Wo.readable());
        assert!(!Access::Const.writable());
        assert!(Access::Rww.writable() && Access::Rww.readable());
        assert_eq!(Access::from_name("RWR"), Some(Access::Rwr));
    }

    #[test]
    fn length_check_codes() {
        assert_eq!(check_len(DataType::Unsigned16, 4), Err(SdoAbort::DATA_TOO_LONG));
        assert_eq!(check_len(DataType::Unsigned32, 2), Err(SdoAbort::DATA_TOO_SHORT));
        assert_eq!(check_len(DataType::Domain, 10_000), Ok(()));
    }
}
