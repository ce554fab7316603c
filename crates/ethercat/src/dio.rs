//! A digital I/O slave to prove the ESC against real masters before CoE
//! exists: like a Beckhoff EL2008 + EL1008 pair in one device — 8, 16 or 32
//! outputs and as many inputs, no mailbox, process data described by the
//! SII TxPDO/RxPDO categories (one BOOL entry per channel, objects
//! 0x7000:n outputs and 0x6000:n inputs, PDOs 0x1600 and 0x1A00).
//!
//! The inputs are wired to the outputs through an XOR mask (`inputs =
//! outputs ^ mask`), so a test can check each slave's data path and that
//! every slave sits at the right place in the process image. While the
//! outputs are not applied (before OP, or after the watchdog), they read
//! as zero, so the inputs show the mask.
//!
//! Sync managers (as the SII tells masters): SM0 outputs at 0x1000 (3-buffer,
//! master writes, watchdog trigger), SM1 inputs at 0x1100 (3-buffer, master
//! reads); with 8 channels each is one byte long, which the ESC handles
//! unbuffered. FMMU0 outputs, FMMU1 inputs. DC SYNC0 is supported.

use drivebus_can::Instant;
use drivebus_esc::sii::{SiiDcSync, SiiImage, SiiPdo, SiiPdoEntry, SiiSyncManager, fmmu_usage, sm_type};
use drivebus_esc::slave::{AlState, ProcessDataSizes, Slave, SlaveApp, SlaveConfig};
use drivebus_esc::{ClockConfig, Esc, EscConfig};

/// Vendor ID used by drivebus test devices. Not an ETG-assigned ID: these
/// devices are test infrastructure, not products.
pub const VENDOR_ID: u32 = 0x0000_0DB0;
/// Product code of the digital I/O slave.
pub const PRODUCT_CODE: u32 = 0x0000_D10D;
/// SII order string (ethercrab's device name) for 8 channels; 16 and 32
/// channel devices are "DB-DIO16" and "DB-DIO32".
pub const NAME: &str = "DB-DIO8";

/// Options of one digital I/O slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DioConfig {
    /// Channels per direction: 8, 16 or 32.
    pub channels: u8,
    /// Inputs = outputs XOR this (low bytes used).
    pub mask: u32,
    /// Serial number in the SII identity.
    pub serial: u32,
    /// Station alias in the SII configuration area.
    pub alias: u16,
    /// Local clock offset and drift of its ESC.
    pub clock: ClockConfig,
}

impl Default for DioConfig {
    fn default() -> Self {
        DioConfig { channels: 8, mask: 0, serial: 1, alias: 0, clock: ClockConfig::default() }
    }
}

impl DioConfig {
    fn bytes(&self) -> usize {
        match self.channels {
            0..=8 => 1,
            9..=16 => 2,
            _ => 4,
        }
    }
}

/// The SII image of a digital I/O slave.
pub fn sii(cfg: &DioConfig) -> SiiImage {
    let bytes = cfg.bytes();
    let channels = (bytes * 8) as u8;
    let name = match bytes {
        1 => "DB-DIO8",
        2 => "DB-DIO16",
        _ => "DB-DIO32",
    };
    let mut b = SiiImage::builder()
        .identity(VENDOR_ID, PRODUCT_CODE + bytes as u32, 0x0001_0000, cfg.serial)
        .station_alias(cfg.alias)
        .names("DigIO", name, "drivebus digital I/O test slave")
        .fmmus(&[fmmu_usage::OUTPUTS, fmmu_usage::INPUTS])
        .sync_manager(SiiSyncManager {
            start: 0x1000,
            length: bytes as u16,
            control: 0x64,
            enable: 0x01,
            sm_type: sm_type::OUTPUTS,
        })
        .sync_manager(SiiSyncManager {
            start: 0x1100,
            length: bytes as u16,
            control: 0x20,
            enable: 0x01,
            sm_type: sm_type::INPUTS,
        })
        .dc(SiiDcSync { assign_activate: 0x0300, ..SiiDcSync::default() });
    let out_name = b.add_string("Output");
    let in_name = b.add_string("Input");
    let entries = |index: u16, name: u8| {
        (1..=channels)
            .map(|sub| SiiPdoEntry {
                index,
                sub_index: sub,
                name_idx: name,
                data_type: 1,
                bit_len: 1,
                flags: 0,
            })
            .collect()
    };
    b.rx_pdo(SiiPdo {
        index: 0x1600,
        sync_manager: 0,
        entries: entries(0x7000, out_name),
        ..SiiPdo::default()
    })
    .tx_pdo(SiiPdo { index: 0x1A00, sync_manager: 1, entries: entries(0x6000, in_name), ..SiiPdo::default() })
    .build()
}

/// The application: outputs wired to inputs through the mask.
#[derive(Debug, Clone, Default)]
pub struct DioApp {
    bytes: usize,
    mask: u32,
    outputs: u32,
    outputs_applied: u64,
    watchdog_trips: u32,
}

impl DioApp {
    /// Current output state.
    pub fn outputs(&self) -> u32 {
        self.outputs
    }

    /// How many output updates were applied.
    pub fn outputs_applied(&self) -> u64 {
        self.outputs_applied
    }

    /// Watchdog expiries seen.
    pub fn watchdog_trips(&self) -> u32 {
        self.watchdog_trips
    }
}

impl SlaveApp for DioApp {
    fn process_data_sizes(&self) -> ProcessDataSizes {
        let bits = (self.bytes * 8) as u32;
        ProcessDataSizes { output_bits: bits, input_bits: bits }
    }

    fn state_changed(&mut self, _from: AlState, to: AlState, _now: Instant) {
        if to != AlState::Op {
            self.outputs = 0; // outputs off outside OP
        }
    }

    fn outputs(&mut self, data: &[u8], _now: Instant) {
        let mut b = [0u8; 4];
        b[..data.len().min(4)].copy_from_slice(&data[..data.len().min(4)]);
        self.outputs = u32::from_le_bytes(b);
        self.outputs_applied += 1;
    }

    fn inputs(&mut self, data: &mut [u8], _now: Instant) {
        let v = (self.outputs ^ self.mask).to_le_bytes();
        let n = data.len().min(4);
        data[..n].copy_from_slice(&v[..n]);
    }

    fn watchdog_expired(&mut self, _now: Instant) {
        self.outputs = 0;
        self.watchdog_trips += 1;
    }
}

/// A digital I/O slave: ESC with the DIO SII and the application.
pub fn slave(cfg: &DioConfig) -> Slave<DioApp> {
    let esc = Esc::new(EscConfig { clock: cfg.clock, ..EscConfig::with_sii(sii(cfg)) });
    let app = DioApp { bytes: cfg.bytes(), mask: cfg.mask, ..DioApp::default() };
    Slave::new(esc, app, SlaveConfig::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sii_describes_pdos_and_sync_managers() {
        let c = sii(&DioConfig { channels: 16, serial: 7, ..DioConfig::default() }).parse().unwrap();
        assert_eq!(c.identity.vendor_id, VENDOR_ID);
        assert_eq!(c.identity.serial, 7);
        assert_eq!(c.strings[usize::from(c.general.unwrap().order_idx) - 1], "DB-DIO16");
        assert_eq!(c.rx_pdos[0].bit_len(), 16);
        assert_eq!(c.tx_pdos[0].bit_len(), 16);
        assert_eq!(c.sync_managers[0].sm_type, sm_type::OUTPUTS);
        assert_eq!(c.mailbox.rx_size, 0, "no mailbox");
    }

    #[test]
    fn inputs_follow_outputs_through_the_mask() {
        let mut a = DioApp { bytes: 1, mask: 0x0F, ..DioApp::default() };
        let mut i = [0u8; 1];
        a.inputs(&mut i, Instant::ZERO);
        assert_eq!(i, [0x0F]);
        SlaveApp::outputs(&mut a, &[0xA0], Instant::ZERO);
        a.inputs(&mut i, Instant::ZERO);
        assert_eq!(i, [0xAF]);
    }
}
