//! Per-device PDO capabilities.

use drivebus_can::MAX_DATA_LEN;

/// Most PDOs of one direction CiA 301 allows (1400h..15FFh, 1800h..19FFh).
pub const MAX_PDOS: u16 = 512;

/// Most mapping entries CiA 301 allows in one mapping record (sub 1..=40h).
pub const MAX_MAPPED_ENTRIES: u8 = 64;

/// Dummy types usable by default: INTEGER8..UNSIGNED32 (0002h..0007h),
/// one bit per data type index.
pub const DEFAULT_DUMMY_TYPES: u32 = 0b1111_1100;

/// How finely objects may be placed in a PDO (CiA 301 7.4.7.1, "granularity").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Granularity {
    /// Any bit length and offset: a BOOLEAN takes one bit.
    #[default]
    Bit,
    /// Whole bytes only (e.g. Kollmorgen KC1/AKD: "mappings are taken only
    /// byte-wise"): a BOOLEAN takes 8 bits, lengths must be multiples of 8.
    Byte,
}

/// What the device supports; fixed when the service is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PdoConfig {
    /// Node-ID used for the pre-defined connection set COB-IDs (1..=127).
    pub node_id: u8,
    /// Number of RPDOs (0..=512): objects 1400h+n / 1600h+n.
    pub rpdo_count: u16,
    /// Number of TPDOs (0..=512): objects 1800h+n / 1A00h+n.
    pub tpdo_count: u16,
    /// Mapping granularity.
    pub granularity: Granularity,
    /// Mapping entries per PDO (sub 1..=max_entries exist), at most 64.
    pub max_entries: u8,
    /// Largest PDO payload in bytes, at most [`MAX_DATA_LEN`].
    pub max_len: usize,
    /// Data type indices usable as dummy mapping entries: bit `t` set means
    /// type index `t` (e.g. 5 = UNSIGNED8) may be mapped as a dummy.
    pub dummy_types: u32,
    /// Remote frames may trigger TPDOs (types 252/253, and RTR on others).
    pub rtr_supported: bool,
    /// Without RTR support, accept TPDO COB-IDs with bit 30 clear (and
    /// still never answer remote frames) instead of refusing them. Real
    /// drives do this: KC1/AKD masters enable TPDOs as `0000_0183h`
    /// (seed000 example 6, seed001 §7.2.1.5).
    pub ignore_rtr_bit: bool,
}

impl PdoConfig {
    /// The CiA 301 generic device: 4 RPDOs, 4 TPDOs, bit granularity,
    /// 64 entries, full-length PDOs, dummies 0002h..0007h, RTR supported.
    pub const fn new(node_id: u8) -> PdoConfig {
        PdoConfig {
            node_id,
            rpdo_count: 4,
            tpdo_count: 4,
            granularity: Granularity::Bit,
            max_entries: MAX_MAPPED_ENTRIES,
            max_len: MAX_DATA_LEN,
            dummy_types: DEFAULT_DUMMY_TYPES,
            rtr_supported: true,
            ignore_rtr_bit: false,
        }
    }

    /// A Kollmorgen KC1/AKD-like drive: byte granularity, 8 entries per PDO.
    pub const fn kollmorgen(node_id: u8) -> PdoConfig {
        let mut c = PdoConfig::new(node_id);
        c.granularity = Granularity::Byte;
        c.max_entries = 8;
        c.rtr_supported = false;
        c.ignore_rtr_bit = true;
        c
    }

    /// Clamp every field into its legal range (what the service really uses).
    pub fn normalized(mut self) -> PdoConfig {
        self.rpdo_count = self.rpdo_count.min(MAX_PDOS);
        self.tpdo_count = self.tpdo_count.min(MAX_PDOS);
        self.max_entries = self.max_entries.min(MAX_MAPPED_ENTRIES);
        self.max_len = self.max_len.min(MAX_DATA_LEN);
        self
    }

    /// Largest PDO payload in bits.
    #[inline]
    pub fn max_bits(&self) -> u32 {
        8 * self.max_len.min(MAX_DATA_LEN) as u32
    }

    /// True if data type index `t` may be mapped as a dummy entry.
    #[inline]
    pub fn dummy_supported(&self, t: u16) -> bool {
        t < 32 && self.dummy_types & (1 << t) != 0
    }
}

impl Default for PdoConfig {
    fn default() -> Self {
        PdoConfig::new(1)
    }
}
