//! The iPOS on EtherCAT (*iPOS CoE Programming* §1.5, §2.3, §3.1, §3.2):
//! what its CoE dictionary lacks of the CAN twin's, its default PDO
//! assignment, its cycle limits and its ESM error reporting.
//!
//! * Appendix A (the CoE object list) has none of the CAN communication
//!   objects the CAN twin answers with (1005h, 1006h, 1014h, 1400h–1403h,
//!   1800h–1803h; §2.3.7/§2.3.8 mention 1802h/1803h only as CANopen
//!   legacy): they are not there on EtherCAT.
//! * Default assignment §2.3: 1C12h = 1600h (6040h + 607Ah), 1C13h = 1A00h
//!   (6041h + 6064h + 6077h) and 1A01h (60F4h + 60FDh), as the EDS says.
//! * §3.2: the drive synchronises its 1 ms slow loop to SYNC0, whose
//!   period must be the loop or a multiple of it: 1C32h:05 = 1 ms, a SYNC0
//!   cycle that is not a multiple is refused (AL 0035h). The fast-loop
//!   synchronisation 2082h = 1 (0.1 ms) is not emulated.
//! * §1.6.3.1: at most 64 bits per PDO.
//! * Table 3.1.3 / 2000h: an EtherCAT communication error (process-data
//!   watchdog, lost SYNC0) sets 2000h bit 0 and sends EMCY 8100h, cleared
//!   by a fault reset or the ESM error acknowledge (§3.1); a refused ESM
//!   transition sends EMCY A0xxh (xx = the AL status code's low byte).

use crate::ecat::EcatFacts;

/// CAN communication objects the CoE object list (Appendix A) lacks.
fn can_only(index: u16) -> bool {
    matches!(index, 0x1005..=0x1007 | 0x1012..=0x1017 | 0x1200..=0x12FF | 0x1400..=0x15FF | 0x1800..=0x19FF)
}

/// The iPOS's EtherCAT facts.
pub static FACTS: EcatFacts = EcatFacts {
    can_only,
    rx_assigned: &[0x1600],
    tx_assigned: &[0x1A00, 0x1A01],
    min_cycle_ns: 1_000_000,
    cycle_step_ns: 1_000_000,
    max_pdo_bits: super::MAX_PDO_BITS,
    esm_emcy: true,
};
