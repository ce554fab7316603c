//! [`DescribedApp`]: the application of a slave made from a description —
//! process data of the described default PDO assignment, CoE (SDO, SDO
//! Information, complete access) over the described dictionary when the
//! description announces CoE.

use drivebus_can::Instant;
use drivebus_coe::{MailboxServer, NoFiles, ObjectAccess, access_bits};
use drivebus_esc::slave::{AlState, MailboxOut, ProcessDataSizes, SlaveApp};
use drivebus_od::{EntryRef, ObjectDictionary, SdoAbort};
use drivebus_pdo::unpack_bits;
use std::collections::HashMap;

/// Where a described device's inputs come from. The run-time input
/// mechanism (issue 17 §3) plugs in here; until then [`Loopback`].
pub trait InputSource: Send {
    /// Fills `inputs` before the master reads them. `outputs` are the
    /// outputs last applied (zero outside OP and after a watchdog expiry);
    /// `update` counts the input updates from 1.
    fn inputs(&mut self, outputs: &[u8], inputs: &mut [u8], update: u64, now: Instant);
}

/// The stand-in input source: inputs loop the outputs back, byte `i` of
/// the inputs being byte `i mod n` of the `n` output bytes; a device
/// without outputs (an input terminal) shows the update counter in every
/// byte, so a master sees its inputs move.
#[derive(Debug, Clone, Copy, Default)]
pub struct Loopback;

impl InputSource for Loopback {
    fn inputs(&mut self, outputs: &[u8], inputs: &mut [u8], update: u64, _now: Instant) {
        for (i, b) in inputs.iter_mut().enumerate() {
            *b = if outputs.is_empty() { update as u8 } else { outputs[i % outputs.len()] };
        }
    }
}

/// An entry of the process image mirrored in the dictionary.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Mirror {
    pub entry: EntryRef,
    pub bit_off: usize,
    pub bits: usize,
}

/// CoE: the dictionary, its access words as described, the server.
pub(crate) struct Coe {
    pub od: ObjectDictionary,
    /// The described access word of every entry (SDO Information, and the
    /// state restrictions of writes).
    pub access: HashMap<(u16, u8), u16>,
    pub mbx: MailboxServer,
    pub outputs: Vec<Mirror>,
    pub inputs: Vec<Mirror>,
}

/// Counters of a described slave.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DescribedStats {
    /// Output updates applied.
    pub outputs_applied: u64,
    /// Input updates produced.
    pub inputs_produced: u64,
}

/// The application of a described slave.
pub struct DescribedApp {
    pub(crate) name: String,
    pub(crate) sizes: ProcessDataSizes,
    pub(crate) outputs: Vec<u8>,
    /// The outputs of the last update in OP, kept when they are switched off.
    pub(crate) applied: Vec<u8>,
    pub(crate) inputs: Vec<u8>,
    pub(crate) source: Box<dyn InputSource>,
    pub(crate) coe: Option<Coe>,
    pub(crate) esm: AlState,
    pub(crate) stats: DescribedStats,
}

impl std::fmt::Debug for DescribedApp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DescribedApp")
            .field("name", &self.name)
            .field("esm", &self.esm)
            .finish_non_exhaustive()
    }
}

impl DescribedApp {
    /// The device's name (the SII order string or the ESI type).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The outputs last applied (zero outside OP).
    pub fn outputs(&self) -> &[u8] {
        &self.outputs
    }

    /// The outputs of the last update applied in OP (kept after the
    /// outputs went to their safe state on leaving OP).
    pub fn last_applied(&self) -> &[u8] {
        &self.applied
    }

    /// The inputs last produced.
    pub fn inputs(&self) -> &[u8] {
        &self.inputs
    }

    /// The dictionary, for a device with CoE.
    pub fn dictionary(&self) -> Option<&ObjectDictionary> {
        self.coe.as_ref().map(|c| &c.od)
    }

    /// Runs `f` on the dictionary through the read and write path its CoE
    /// server takes (the described access words in the current ESM
    /// state), for a local tool; `None` for a device without CoE.
    pub fn with_objects<R>(&mut self, f: impl FnOnce(&mut dyn ObjectAccess) -> R) -> Option<R> {
        let c = self.coe.as_mut()?;
        Some(f(&mut Access { od: &mut c.od, words: &c.access, esm: self.esm }))
    }

    /// Counters.
    pub fn stats(&self) -> DescribedStats {
        self.stats
    }

    /// The ESM state the application runs in.
    pub fn esm(&self) -> AlState {
        self.esm
    }

    /// Replaces the input source.
    pub fn set_input_source(&mut self, source: Box<dyn InputSource>) {
        self.source = source;
    }

    fn mirror(od: &mut ObjectDictionary, list: &[Mirror], data: &[u8]) {
        for m in list {
            od.set_word(m.entry, unpack_bits(data, m.bit_off, m.bits));
        }
    }

    fn drain(&mut self, now: Instant, out: &mut MailboxOut<'_>) {
        let Some(c) = self.coe.as_mut() else { return };
        while out.pending().0 < 8
            && let Some(m) = c.mbx.next_response(now)
        {
            out.respond(m);
        }
    }
}

/// The dictionary behind the CoE server, with the ESM state for the
/// described read and write restrictions.
struct Access<'a> {
    od: &'a mut ObjectDictionary,
    words: &'a HashMap<(u16, u8), u16>,
    esm: AlState,
}

impl Access<'_> {
    /// The access bits that count in the current state: (read, write).
    fn state_bits(&self) -> (u16, u16) {
        match self.esm {
            AlState::SafeOp => (access_bits::READ_SAFEOP, access_bits::WRITE_SAFEOP),
            AlState::Op => (access_bits::READ_OP, access_bits::WRITE_OP),
            _ => (access_bits::READ_PREOP, access_bits::WRITE_PREOP),
        }
    }
}

impl ObjectAccess for Access<'_> {
    fn dictionary(&self) -> &ObjectDictionary {
        self.od
    }

    fn read(&mut self, index: u16, sub: u8) -> Result<&[u8], SdoAbort> {
        let w = self.object_access(index, sub);
        let (r, _) = self.state_bits();
        if self.od.get(index, sub).is_some() && w & access_bits::READ != 0 && w & r == 0 {
            return Err(SdoAbort::DEVICE_STATE);
        }
        self.od.read(&mut drivebus_od::NoHooks, index, sub)
    }

    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        let w = self.object_access(index, sub);
        let (_, wr) = self.state_bits();
        if self.od.get(index, sub).is_some() && w & access_bits::WRITE != 0 && w & wr == 0 {
            return Err(SdoAbort::DEVICE_STATE);
        }
        self.od.write(&mut drivebus_od::NoHooks, index, sub, data)
    }

    fn object_access(&self, index: u16, sub: u8) -> u16 {
        match self.words.get(&(index, sub)) {
            Some(w) => *w,
            None => self.od.get(index, sub).map_or(0, drivebus_coe::default_object_access),
        }
    }
}

impl SlaveApp for DescribedApp {
    fn process_data_sizes(&self) -> ProcessDataSizes {
        self.sizes
    }

    fn state_changed(&mut self, from: AlState, to: AlState, _now: Instant) {
        self.esm = to;
        if to != AlState::Op {
            self.outputs.fill(0);
        }
        if let Some(c) = self.coe.as_mut() {
            if from == AlState::Init || to == AlState::Init {
                c.mbx.reset(&mut NoFiles);
            }
            Self::mirror(&mut c.od, &c.outputs, &self.outputs);
        }
    }

    fn mailbox(&mut self, request: &[u8], now: Instant, out: &mut MailboxOut<'_>) {
        let esm = self.esm;
        if let Some(c) = self.coe.as_mut() {
            let mut a = Access { od: &mut c.od, words: &c.access, esm };
            c.mbx.handle_request(request, now, esm, &mut a, &mut NoFiles);
        }
        self.drain(now, out);
    }

    fn outputs(&mut self, data: &[u8], _now: Instant) {
        let n = data.len().min(self.outputs.len());
        self.outputs[..n].copy_from_slice(&data[..n]);
        self.applied.clone_from(&self.outputs);
        self.stats.outputs_applied += 1;
        if let Some(c) = self.coe.as_mut() {
            Self::mirror(&mut c.od, &c.outputs, &self.outputs);
        }
    }

    fn inputs(&mut self, data: &mut [u8], now: Instant) {
        self.stats.inputs_produced += 1;
        self.source.inputs(&self.outputs, data, self.stats.inputs_produced, now);
        let n = data.len().min(self.inputs.len());
        self.inputs[..n].copy_from_slice(&data[..n]);
        if let Some(c) = self.coe.as_mut() {
            Self::mirror(&mut c.od, &c.inputs, &self.inputs);
        }
    }

    fn watchdog_expired(&mut self, _now: Instant) {
        self.outputs.fill(0);
        if let Some(c) = self.coe.as_mut() {
            Self::mirror(&mut c.od, &c.outputs, &self.outputs);
        }
    }

    fn poll(&mut self, now: Instant, out: &mut MailboxOut<'_>) -> Option<Instant> {
        let next = self.coe.as_mut().and_then(|c| c.mbx.poll(now, &mut NoFiles));
        self.drain(now, out);
        next
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_repeats_outputs_or_counts() {
        let mut i = [0u8; 5];
        Loopback.inputs(&[1, 2], &mut i, 1, Instant::ZERO);
        assert_eq!(i, [1, 2, 1, 2, 1]);
        Loopback.inputs(&[], &mut i, 7, Instant::ZERO);
        assert_eq!(i, [7; 5]);
    }

    #[test]
    fn mirror_writes_bits_into_entries() {
        use drivebus_od::{Access as A, DataType, Object, Value};
        let mut od = ObjectDictionary::new();
        od.insert(Object::var(0x7000, "b", DataType::Boolean, A::Rww, Value::Bool(false)));
        od.insert(Object::var(0x7001, "w", DataType::Unsigned16, A::Rww, Value::U16(0)));
        let m = [
            Mirror { entry: od.find(0x7000, 0).unwrap(), bit_off: 1, bits: 1 },
            Mirror { entry: od.find(0x7001, 0).unwrap(), bit_off: 8, bits: 16 },
        ];
        DescribedApp::mirror(&mut od, &m, &[0b10, 0x34, 0x12]);
        assert_eq!(od.get_u64(0x7000, 0), Some(1));
        assert_eq!(od.get_u64(0x7001, 0), Some(0x1234));
    }
}
