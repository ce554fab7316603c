//! The process image of a CoE drive: the PDOs 1C12h assigns to SM2 and
//! 1C13h to SM3, in assignment order, each packed least significant bit
//! first right after the previous one (ETG.1000.6 §5.6.7.4; the masters
//! size SM2/SM3 from the same sums). Each PDO is a
//! [`drivebus_pdo::MappedPdo`] — the CAN PDO service's resolved plan and
//! packer — placed at its bit offset in the image.

use drivebus_od::{ObjectDictionary, ObjectHooks, SdoAbort};
use drivebus_pdo::{MappedPdo, PdoConfig, PdoKind, pack_bits, unpack_bits};
use drivebus_personality::ecat::rules;

/// One direction of the process image.
#[derive(Debug, Clone, Default)]
pub struct Image {
    pdos: Vec<(u32, MappedPdo)>,
    bits: u32,
}

impl Image {
    /// Resolves the PDOs `assign` (1C12h or 1C13h) names. A PDO that no
    /// longer maps (an entry refused by the checks of a mapping write)
    /// refuses the whole image with that PDO's abort.
    pub fn resolve(od: &ObjectDictionary, cfg: &PdoConfig, assign: u16) -> Result<Image, (u16, SdoAbort)> {
        let kind = if assign == 0x1C12 { PdoKind::Rpdo } else { PdoKind::Tpdo };
        let mut pdos = Vec::new();
        let mut bits = 0u32;
        for index in rules::assigned(od, assign) {
            if od.object(index).is_none() || rules::kind_of(index) != kind {
                return Err((index, SdoAbort::INVALID_VALUE));
            }
            let entries = rules::entries(od, index);
            let p = MappedPdo::resolve(od, cfg, kind, &entries).map_err(|e| (index, e))?;
            let n = p.bits();
            pdos.push((bits, p));
            bits += n;
        }
        Ok(Image { pdos, bits })
    }

    /// Bits the assigned PDOs' current mappings take (what
    /// `process_data_sizes` reports; no resolution, so it never fails).
    pub fn bits_of(od: &ObjectDictionary, assign: u16) -> u32 {
        rules::assigned(od, assign)
            .into_iter()
            .map(|i| rules::entries(od, i).iter().map(|e| e & 0xFF).sum::<u32>())
            .sum()
    }

    /// Length in bits.
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// Writes the RxPDO data of `data` into the dictionary through the
    /// write path (as received PDOs). Returns entries refused.
    pub fn apply(&self, od: &mut ObjectDictionary, hooks: &mut dyn ObjectHooks, data: &[u8]) -> u32 {
        let mut refused = 0;
        for (off, p) in &self.pdos {
            let v = unpack_bits(data, *off as usize, p.bits() as usize);
            refused += p.apply(od, hooks, v);
        }
        refused
    }

    /// Samples the TxPDO data into `data` (live entries refreshed through
    /// the read path). Returns entries whose refresh was refused.
    pub fn sample(&self, od: &mut ObjectDictionary, hooks: &mut dyn ObjectHooks, data: &mut [u8]) -> u32 {
        let mut refused = 0;
        for (off, p) in &self.pdos {
            let (v, r) = p.sample(od, hooks);
            pack_bits(data, *off as usize, p.bits() as usize, v);
            refused += r;
        }
        refused
    }
}

/// The abort a refused image means for the AL status (ETG.1000.6 Table
/// 11): an RxPDO problem is an invalid output configuration (001Dh), a
/// TxPDO one an invalid input configuration (001Eh).
pub fn al_code(assign: u16) -> u16 {
    if assign == 0x1C12 { 0x001D } else { 0x001E }
}
