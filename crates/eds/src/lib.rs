//! EDS and DCF files (CiA 306): read, write, check, convert to and from a
//! running object dictionary, and the DCF of a configured device ([`dcf`]).
//!
//! ```
//! let text = "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x20192\n";
//! let parsed = drivebus_eds::parse(text).unwrap();
//! let od = drivebus_eds::to_od(&parsed.eds, 5).unwrap();
//! assert_eq!(od.get_u32(0x1000, 0), Some(0x20192));
//! ```

mod check;
mod convert;
mod dcf;
mod ini;
mod model;
mod read;
mod value;
mod write;

pub use check::{Finding, Severity, check};
pub use convert::{from_od, to_od, to_od_static};
pub use dcf::{dcf, dcf_from_od};
pub use model::{Commissioning, DeviceInfo, Diagnostic, Eds, EdsError, EdsObject, EdsVar};
pub use read::{ParsedEds, parse};
pub use value::{eval, format as format_value, is_node_relative};
pub use write::write;
