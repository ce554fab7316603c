//! Technosoft's revision naming (iPOS CoE manual §1.5.4.6): the ESI
//! `RevisionNo` (and the SII revision) is the drive's firmware ID read as
//! four ASCII characters, first character in the most significant byte.
//! "515F" = 0x35313546 = 892417350; "515J" = 0x3531354A = 892417354.
//!
//! The firmware is named with a leading `F` ("F515J", "FA00G"); the ID is
//! the four characters after it. The FoE firmware password of the FA0xx
//! line, 0x41303041 = "A00A" (§17.4.7), follows the same rule.

use std::fmt;

/// A firmware ID that is not four printable ASCII characters.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RevisionError {
    /// The text given.
    pub text: String,
}

impl fmt::Display for RevisionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "firmware ID {:?} is not four printable ASCII characters (e.g. \"515J\")", self.text)
    }
}

impl std::error::Error for RevisionError {}

/// The revision number of a firmware ID: `"515F"` → `0x35313546`. A
/// leading `F` of a five-character firmware name is dropped (`"F515J"` →
/// `"515J"`), as the manual names firmware "F515J" but revisions "515J".
pub fn firmware_revision(firmware: &str) -> Result<u32, RevisionError> {
    let err = || RevisionError { text: firmware.to_string() };
    let id = match firmware.as_bytes() {
        [b'F' | b'f', rest @ ..] if rest.len() == 4 => rest,
        b => b,
    };
    let bytes: [u8; 4] = id.try_into().map_err(|_| err())?;
    if !bytes.iter().all(|b| b.is_ascii_graphic()) {
        return Err(err());
    }
    Ok(u32::from_be_bytes(bytes))
}

/// The firmware ID a revision number spells, if its four bytes are
/// printable ASCII: `0x3531354A` → `"515J"`; `0x00010000` → `None`.
pub fn revision_firmware(revision: u32) -> Option<String> {
    let bytes = revision.to_be_bytes();
    bytes.iter().all(|b| b.is_ascii_graphic()).then(|| bytes.iter().map(|&b| b as char).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manual_examples_section_1_5_4_6() {
        assert_eq!(firmware_revision("515F"), Ok(0x3531_3546));
        assert_eq!(firmware_revision("515F").unwrap(), 892_417_350);
        assert_eq!(firmware_revision("515J"), Ok(0x3531_354A));
        assert_eq!(firmware_revision("515J").unwrap(), 892_417_354);
        // The manual prints 515I as 0x35313149 (that is "511I"); its
        // decimal 892417353 is right and is 0x35313549.
        assert_eq!(firmware_revision("515I").unwrap(), 892_417_353);
        assert_eq!(firmware_revision("515I").unwrap(), 0x3531_3549);
        assert_eq!(revision_firmware(0x3531_3149).as_deref(), Some("511I"));
        // FA0xx FoE password §17.4.7.
        assert_eq!(revision_firmware(0x4130_3041).as_deref(), Some("A00A"));
    }

    #[test]
    fn leading_f_of_the_firmware_name_is_dropped() {
        assert_eq!(firmware_revision("F515J"), firmware_revision("515J"));
        assert_eq!(firmware_revision("FA00G"), Ok(0x4130_3047));
        assert_eq!(firmware_revision("FA00G").unwrap(), 1_093_677_127);
    }

    #[test]
    fn round_trip_and_refusals() {
        for id in ["515F", "515J", "A00G", "0100", "zz~!"] {
            let r = firmware_revision(id).unwrap();
            assert_eq!(revision_firmware(r).as_deref(), Some(id));
        }
        assert_eq!(revision_firmware(0x3031_3030).as_deref(), Some("0100")); // iPOS 1018h:03 (§4.8.6)
        for bad in ["", "515", "515JK1", "51 F", "5é5"] {
            assert!(firmware_revision(bad).is_err(), "{bad:?}");
        }
        assert_eq!(revision_firmware(0x0001_0000), None);
        assert!(firmware_revision("51\u{7f}F").is_err());
    }
}
