//! The ESC register map (0x0000–0x0FFF) and which bits each side may write.
//!
//! Addresses and access rights follow the Beckhoff "EtherCAT Slave
//! Controller Hardware Data Sheet, Section II – Register Description"
//! (ET1100/IP core columns). A register this emulation does not implement is
//! *reserved*: it reads 0 and ignores writes, and the access still counts in
//! the working counter, as on ESCs that set "unused register access
//! allowed" (0x0008 bit 1 = 0).

/// ESC type (0x0000).
pub const TYPE: u16 = 0x0000;
/// ESC revision (0x0001).
pub const REVISION: u16 = 0x0001;
/// ESC build (0x0002, u16).
pub const BUILD: u16 = 0x0002;
/// Number of FMMUs supported (0x0004).
pub const FMMU_COUNT: u16 = 0x0004;
/// Number of sync managers supported (0x0005).
pub const SM_COUNT: u16 = 0x0005;
/// Process RAM size in KiB (0x0006).
pub const RAM_SIZE: u16 = 0x0006;
/// Port descriptor, two bits per port (0x0007).
pub const PORT_DESCRIPTOR: u16 = 0x0007;
/// ESC features supported (0x0008, u16).
pub const FEATURES: u16 = 0x0008;
/// Configured station address (0x0010, u16).
pub const STATION_ADDRESS: u16 = 0x0010;
/// Configured station alias (0x0012, u16; ECAT read-only, loaded from SII word 4).
pub const STATION_ALIAS: u16 = 0x0012;
/// ESC reset ECAT (0x0040): writing 'R', 'E', 'S' in three consecutive frames resets the ESC.
pub const ESC_RESET_ECAT: u16 = 0x0040;
/// DL control (0x0100, u32).
pub const DL_CONTROL: u16 = 0x0100;
/// DL status (0x0110, u16).
pub const DL_STATUS: u16 = 0x0110;
/// AL control (0x0120, u16).
pub const AL_CONTROL: u16 = 0x0120;
/// AL status (0x0130, u16).
pub const AL_STATUS: u16 = 0x0130;
/// AL status code (0x0134, u16).
pub const AL_STATUS_CODE: u16 = 0x0134;
/// PDI control (0x0140): PDI type; 0x0141 is the ESC configuration byte.
pub const PDI_CONTROL: u16 = 0x0140;
/// ESC configuration (0x0141): bit 0 device emulation.
pub const ESC_CONFIG: u16 = 0x0141;
/// PDI configuration (0x0150, u16).
pub const PDI_CONFIG: u16 = 0x0150;
/// Extended PDI configuration (0x0152, u16).
pub const PDI_CONFIG_EXT: u16 = 0x0152;
/// ECAT event mask (0x0200, u16).
pub const ECAT_EVENT_MASK: u16 = 0x0200;
/// AL event mask (0x0204, u32; PDI writes it).
pub const AL_EVENT_MASK: u16 = 0x0204;
/// ECAT event request (0x0210, u16).
pub const ECAT_EVENT_REQUEST: u16 = 0x0210;
/// AL event request (0x0220, u32).
pub const AL_EVENT_REQUEST: u16 = 0x0220;
/// RX error counters, ports 0–3 (0x0300–0x0307: invalid frame, RX error per port).
pub const RX_ERROR_COUNTER: u16 = 0x0300;
/// Forwarded RX error counters (0x0308–0x030B).
pub const FORWARDED_RX_ERROR_COUNTER: u16 = 0x0308;
/// ECAT processing unit error counter (0x030C).
pub const PROCESSING_UNIT_ERROR_COUNTER: u16 = 0x030C;
/// PDI error counter (0x030D).
pub const PDI_ERROR_COUNTER: u16 = 0x030D;
/// Lost link counters, ports 0–3 (0x0310–0x0313).
pub const LOST_LINK_COUNTER: u16 = 0x0310;
/// Watchdog divider (0x0400, u16): (value + 2) × 40 ns per watchdog increment.
pub const WATCHDOG_DIVIDER: u16 = 0x0400;
/// PDI watchdog time (0x0410, u16) in watchdog increments.
pub const PDI_WATCHDOG_TIME: u16 = 0x0410;
/// Process-data (SM) watchdog time (0x0420, u16) in watchdog increments.
pub const PD_WATCHDOG_TIME: u16 = 0x0420;
/// Watchdog status process data (0x0440): bit 0 = 1 active or disabled, 0 expired.
pub const PD_WATCHDOG_STATUS: u16 = 0x0440;
/// Watchdog counter process data (0x0442).
pub const PD_WATCHDOG_COUNTER: u16 = 0x0442;
/// Watchdog counter PDI (0x0443).
pub const PDI_WATCHDOG_COUNTER: u16 = 0x0443;
/// SII EEPROM configuration (0x0500): bit 0 offer to PDI, bit 1 force ECAT access.
pub const SII_CONFIG: u16 = 0x0500;
/// SII EEPROM PDI access state (0x0501): bit 0 PDI has access.
pub const SII_PDI_ACCESS: u16 = 0x0501;
/// SII EEPROM control/status (0x0502, u16).
pub const SII_CONTROL: u16 = 0x0502;
/// SII EEPROM word address (0x0504, u32).
pub const SII_ADDRESS: u16 = 0x0504;
/// SII EEPROM data (0x0508, 8 bytes).
pub const SII_DATA: u16 = 0x0508;
/// First FMMU register (0x0600); FMMU n is at 0x0600 + 16·n.
pub const FMMU_BASE: u16 = 0x0600;
/// First sync manager register (0x0800); SM n is at 0x0800 + 8·n.
pub const SM_BASE: u16 = 0x0800;
/// DC receive time port 0 (0x0900, u32); ports 1–3 follow at 0x0904, 0x0908, 0x090C.
pub const DC_RECEIVE_TIME_PORT0: u16 = 0x0900;
/// DC system time (0x0910, u64).
pub const DC_SYSTEM_TIME: u16 = 0x0910;
/// DC receive time of the ECAT processing unit (0x0918, u64).
pub const DC_RECEIVE_TIME_PU: u16 = 0x0918;
/// DC system time offset (0x0920, u64).
pub const DC_SYSTEM_TIME_OFFSET: u16 = 0x0920;
/// DC system time delay (0x0928, u32).
pub const DC_SYSTEM_TIME_DELAY: u16 = 0x0928;
/// DC system time difference (0x092C, u32 sign/magnitude).
pub const DC_SYSTEM_TIME_DIFF: u16 = 0x092C;
/// DC speed counter start (0x0930, u16).
pub const DC_SPEED_COUNTER_START: u16 = 0x0930;
/// DC speed counter difference (0x0932, i16).
pub const DC_SPEED_COUNTER_DIFF: u16 = 0x0932;
/// DC system time difference filter depth (0x0934).
pub const DC_TIME_FILTER_DEPTH: u16 = 0x0934;
/// DC speed counter filter depth (0x0935).
pub const DC_SPEED_FILTER_DEPTH: u16 = 0x0935;
/// DC cyclic unit control (0x0980).
pub const DC_CYCLIC_UNIT_CONTROL: u16 = 0x0980;
/// DC activation (0x0981).
pub const DC_ACTIVATION: u16 = 0x0981;
/// DC pulse length of SYNC signals (0x0982, u16, 10 ns units).
pub const DC_PULSE_LENGTH: u16 = 0x0982;
/// DC activation status (0x0984).
pub const DC_ACTIVATION_STATUS: u16 = 0x0984;
/// DC SYNC0 status (0x098E; reading clears it).
pub const DC_SYNC0_STATUS: u16 = 0x098E;
/// DC SYNC1 status (0x098F; reading clears it).
pub const DC_SYNC1_STATUS: u16 = 0x098F;
/// DC start time cyclic operation (0x0990, u64); reads the next SYNC0 time.
pub const DC_START_TIME: u16 = 0x0990;
/// DC next SYNC1 pulse (0x0998, u64).
pub const DC_NEXT_SYNC1: u16 = 0x0998;
/// DC SYNC0 cycle time (0x09A0, u32 ns).
pub const DC_SYNC0_CYCLE: u16 = 0x09A0;
/// DC SYNC1 cycle time (0x09A4, u32 ns).
pub const DC_SYNC1_CYCLE: u16 = 0x09A4;
/// Digital I/O output data (0x0F00, u32).
pub const DIGITAL_OUTPUT: u16 = 0x0F00;
/// User RAM (0x0F80–0x0FFF).
pub const USER_RAM: u16 = 0x0F80;
/// First address of process RAM.
pub const RAM_START: u16 = 0x1000;

/// Size of the register block.
pub const REGISTER_SPACE: usize = 0x1000;

/// AL event request bits (0x0220).
pub mod al_event {
    /// AL control register written by the master.
    pub const AL_CONTROL: u32 = 1 << 0;
    /// A sync manager activation register (0x0806 + 8·n) changed.
    pub const SM_CHANGED: u32 = 1 << 4;
    /// Process-data watchdog expired.
    pub const WATCHDOG: u32 = 1 << 6;
    /// First sync manager interrupt bit; SM n is bit 8 + n.
    pub const SM0: u32 = 1 << 8;
}

/// ECAT event request bits (0x0210).
pub mod ecat_event {
    /// DL status changed (cleared when ECAT reads 0x0110).
    pub const DL_STATUS: u16 = 1 << 2;
    /// AL status changed (cleared when ECAT reads 0x0130).
    pub const AL_STATUS: u16 = 1 << 3;
    /// First sync manager status mirror bit; SM n (n < 8) is bit 4 + n.
    pub const SM0: u16 = 1 << 4;
}

/// Marks `len` bytes from `addr` with `mask` in a 4 KiB table.
const fn set(table: &mut [u8; REGISTER_SPACE], addr: usize, len: usize, mask: u8) {
    let mut i = 0;
    while i < len {
        table[addr + i] = mask;
        i += 1;
    }
}

/// Bits the EtherCAT side may write, per register byte (ESC data sheet
/// Section II "ECAT" access column). Bytes with a write side effect but no
/// stored value (error counters, 0x0040, 0x0900, 0x0910) are 0 here and are
/// handled by the ESC itself.
pub(crate) static ECAT_WRITE: [u8; REGISTER_SPACE] = ecat_write_table();

const fn ecat_write_table() -> [u8; REGISTER_SPACE] {
    let mut t = [0u8; REGISTER_SPACE];
    set(&mut t, 0x0010, 2, 0xFF); // station address
    set(&mut t, 0x0100, 1, 0x03); // forwarding rule, temporary loop
    set(&mut t, 0x0101, 1, 0xFF); // loop control ports 0-3
    set(&mut t, 0x0102, 1, 0x4F); // RX FIFO size, EBUS low jitter, remote link down
    set(&mut t, 0x0103, 1, 0x01); // station alias enable
    set(&mut t, 0x0108, 2, 0xFF); // physical read/write offset
    set(&mut t, 0x0120, 2, 0xFF); // AL control (mailbox-like, see Esc)
    set(&mut t, 0x0138, 2, 0xFF); // RUN/ERR LED override
    set(&mut t, 0x0200, 2, 0xFF); // ECAT event mask
    set(&mut t, 0x0400, 2, 0xFF); // watchdog divider
    set(&mut t, 0x0410, 2, 0xFF); // PDI watchdog time
    set(&mut t, 0x0420, 2, 0xFF); // process data watchdog time
    set(&mut t, 0x0500, 1, 0x03); // SII: offer to PDI, force ECAT
    set(&mut t, 0x0504, 4, 0xFF); // SII address (guarded by busy)
    set(&mut t, 0x0508, 8, 0xFF); // SII data (guarded by busy)
    // FMMUs: logical start, length, start/stop bits, physical start/bit, type, activate.
    let mut f = 0;
    while f < 16 {
        let b = 0x0600 + f * 16;
        set(&mut t, b, 6, 0xFF);
        set(&mut t, b + 6, 2, 0x07);
        set(&mut t, b + 8, 2, 0xFF);
        set(&mut t, b + 10, 1, 0x07);
        set(&mut t, b + 11, 1, 0x03);
        set(&mut t, b + 12, 1, 0x01);
        f += 1;
    }
    // Sync managers: start, length, control (writable only while disabled),
    // status read-only, activate bits 0, 1, 6, 7, PDI control read-only.
    let mut s = 0;
    while s < 16 {
        let b = 0x0800 + s * 8;
        set(&mut t, b, 4, 0xFF);
        set(&mut t, b + 4, 1, 0x7F);
        set(&mut t, b + 6, 1, 0xC3);
        s += 1;
    }
    set(&mut t, 0x0920, 8, 0xFF); // system time offset
    set(&mut t, 0x0928, 4, 0xFF); // system time delay
    set(&mut t, 0x0930, 1, 0xFF); // speed counter start (15 bits)
    set(&mut t, 0x0931, 1, 0x7F);
    set(&mut t, 0x0934, 2, 0x0F); // filter depths
    set(&mut t, 0x0980, 1, 0x31); // cyclic unit control
    set(&mut t, 0x0981, 1, 0xFF); // activation
    set(&mut t, 0x0990, 8, 0xFF); // start time (only while inactive, see Dc)
    set(&mut t, 0x09A0, 8, 0xFF); // SYNC0/SYNC1 cycle time
    set(&mut t, 0x09A8, 2, 0x03); // latch control (storage only: no latch inputs)
    set(&mut t, 0x0F00, 4, 0xFF); // digital I/O output data
    set(&mut t, 0x0F10, 8, 0xFF); // general purpose outputs
    set(&mut t, 0x0F80, 0x80, 0xFF); // user RAM
    t
}

/// Bits the PDI (slave firmware) may write, per register byte.
pub(crate) static PDI_WRITE: [u8; REGISTER_SPACE] = pdi_write_table();

const fn pdi_write_table() -> [u8; REGISTER_SPACE] {
    let mut t = [0u8; REGISTER_SPACE];
    set(&mut t, 0x0012, 2, 0xFF); // station alias
    set(&mut t, 0x0130, 1, 0x3F); // AL status: state, error, device identification
    set(&mut t, 0x0131, 1, 0xFF);
    set(&mut t, 0x0134, 2, 0xFF); // AL status code
    set(&mut t, 0x0204, 4, 0xFF); // AL event mask
    set(&mut t, 0x0501, 1, 0x01); // SII: PDI takes access
    let mut s = 0;
    while s < 16 {
        set(&mut t, 0x0807 + s * 8, 1, 0x03); // SM PDI control: deactivate, repeat ack
        s += 1;
    }
    set(&mut t, 0x0F18, 8, 0xFF); // general purpose inputs
    set(&mut t, 0x0F80, 0x80, 0xFF); // user RAM
    t
}

/// True if `addr` is a byte of sync manager `n`'s register block.
#[inline]
pub(crate) fn sm_index(addr: usize) -> Option<usize> {
    (0x0800..0x0880).contains(&addr).then(|| (addr - 0x0800) / 8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks_match_the_register_description() {
        // Read-only identification and status registers.
        for a in [0x0000, 0x0005, 0x0008, 0x0012, 0x0110, 0x0130, 0x0134, 0x0140, 0x0440] {
            assert_eq!(ECAT_WRITE[a], 0, "{a:#06x} must be read-only for ECAT");
        }
        // SM status byte and PDI control are read-only for ECAT; activate is not.
        assert_eq!(ECAT_WRITE[0x0805], 0);
        assert_eq!(ECAT_WRITE[0x0807], 0);
        assert_eq!(ECAT_WRITE[0x0806], 0xC3);
        assert_eq!(PDI_WRITE[0x0807], 0x03);
        // FMMU reserved bytes.
        assert_eq!(ECAT_WRITE[0x060D], 0);
        assert_eq!(ECAT_WRITE[0x060C], 0x01);
        // The PDI owns AL status and the alias; the master does not.
        assert_eq!(PDI_WRITE[0x0130], 0x3F);
        assert_eq!(PDI_WRITE[0x0012], 0xFF);
        assert_eq!(PDI_WRITE[0x0120], 0);
        assert_eq!(sm_index(0x087F), Some(15));
        assert_eq!(sm_index(0x0880), None);
    }
}
