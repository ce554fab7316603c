//! SDO abort codes (CiA 301 §7.2.4.3.17).

use core::fmt;

/// An SDO abort code. Also the error type of every object dictionary access,
/// so a failed write already carries the exact code the server must send.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct SdoAbort(pub u32);

macro_rules! aborts {
    ($($name:ident = $code:expr, $text:expr;)*) => {
        impl SdoAbort {
            $(#[doc = $text] pub const $name: SdoAbort = SdoAbort($code);)*

            /// The CiA 301 meaning of the code, or `None` for a code it does not define.
            pub fn description(self) -> Option<&'static str> {
                match self.0 {
                    $($code => Some($text),)*
                    _ => None,
                }
            }
        }
    };
}

aborts! {
    TOGGLE_NOT_ALTERNATED = 0x0503_0000, "Toggle bit not alternated";
    TIMEOUT = 0x0504_0000, "SDO protocol timed out";
    INVALID_COMMAND = 0x0504_0001, "Client/server command specifier not valid or unknown";
    INVALID_BLOCK_SIZE = 0x0504_0002, "Invalid block size (block mode only)";
    INVALID_SEQUENCE = 0x0504_0003, "Invalid sequence number (block mode only)";
    CRC_ERROR = 0x0504_0004, "CRC error (block mode only)";
    OUT_OF_MEMORY = 0x0504_0005, "Out of memory";
    UNSUPPORTED_ACCESS = 0x0601_0000, "Unsupported access to an object";
    READ_WRITE_ONLY = 0x0601_0001, "Attempt to read a write only object";
    WRITE_READ_ONLY = 0x0601_0002, "Attempt to write a read only object";
    NO_OBJECT = 0x0602_0000, "Object does not exist in the object dictionary";
    NOT_MAPPABLE = 0x0604_0041, "Object cannot be mapped to the PDO";
    PDO_TOO_LONG = 0x0604_0042, "The number and length of the objects to be mapped would exceed PDO length";
    PARAM_INCOMPATIBLE = 0x0604_0043, "General parameter incompatibility reason";
    INTERNAL_INCOMPATIBLE = 0x0604_0047, "General internal incompatibility in the device";
    HARDWARE_ERROR = 0x0606_0000, "Access failed due to an hardware error";
    TYPE_MISMATCH = 0x0607_0010, "Data type does not match, length of service parameter does not match";
    DATA_TOO_LONG = 0x0607_0012, "Data type does not match, length of service parameter too high";
    DATA_TOO_SHORT = 0x0607_0013, "Data type does not match, length of service parameter too low";
    NO_SUB_INDEX = 0x0609_0011, "Sub-index does not exist";
    INVALID_VALUE = 0x0609_0030, "Invalid value for parameter (download only)";
    VALUE_TOO_HIGH = 0x0609_0031, "Value of parameter written too high (download only)";
    VALUE_TOO_LOW = 0x0609_0032, "Value of parameter written too low (download only)";
    MAX_LESS_THAN_MIN = 0x0609_0036, "Maximum value is less than minimum value";
    RESOURCE_NOT_AVAILABLE = 0x060A_0023, "Resource not available: SDO connection";
    GENERAL_ERROR = 0x0800_0000, "General error";
    CANNOT_STORE = 0x0800_0020, "Data cannot be transferred or stored to the application";
    LOCAL_CONTROL = 0x0800_0021, "Data cannot be transferred or stored to the application because of local control";
    DEVICE_STATE = 0x0800_0022, "Data cannot be transferred or stored to the application because of the present device state";
    NO_OD = 0x0800_0023, "Object dictionary dynamic generation fails or no object dictionary is present";
    NO_DATA = 0x0800_0024, "No data available";
}

impl fmt::Debug for SdoAbort {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SdoAbort({:04X} {:04X})", self.0 >> 16, self.0 & 0xFFFF)
    }
}

impl fmt::Display for SdoAbort {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04X} {:04X}", self.0 >> 16, self.0 & 0xFFFF)?;
        match self.description() {
            Some(t) => write!(f, " ({t})"),
            None => f.write_str(" (unknown abort code)"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for SdoAbort {}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn display_has_code_and_text() {
        assert_eq!(
            SdoAbort::NO_OBJECT.to_string(),
            "0602 0000 (Object does not exist in the object dictionary)"
        );
        assert_eq!(SdoAbort(0x1234_5678).to_string(), "1234 5678 (unknown abort code)");
    }
}
