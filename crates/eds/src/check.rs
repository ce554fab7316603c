//! A CiA 306 / CiA 301 consistency checker for EDS and DCF files.

use crate::model::{Eds, EdsVar};
use crate::value::eval;
use drivebus_od::{DataType, ObjectCode, compare_le};
use std::cmp::Ordering;
use std::fmt;

/// How bad a finding is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// Suspicious but legal.
    Warning,
    /// Violates CiA 306 / 301: a tool or device will misbehave.
    Error,
}

/// One problem in a file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Finding {
    /// Error or warning.
    pub severity: Severity,
    /// Object index, if the finding is about one.
    pub index: Option<u16>,
    /// Sub-index, if the finding is about one.
    pub sub: Option<u8>,
    /// Line in the file (0 if unknown).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sev = match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        write!(f, "{sev}")?;
        if self.line > 0 {
            write!(f, " (line {})", self.line)?;
        }
        match (self.index, self.sub) {
            (Some(i), Some(s)) => write!(f, " {i:04X}sub{s:X}")?,
            (Some(i), None) => write!(f, " {i:04X}")?,
            _ => {}
        }
        write!(f, ": {}", self.message)
    }
}

/// Data types CiA 301 fixes for communication objects: (index, sub, type);
/// `sub = None` means every sub-index above 0.
const STANDARD_TYPES: &[(u16, Option<u8>, DataType)] = {
    use DataType::*;
    &[
        (0x1000, Some(0), Unsigned32),
        (0x1001, Some(0), Unsigned8),
        (0x1002, Some(0), Unsigned32),
        (0x1003, None, Unsigned32),
        (0x1005, Some(0), Unsigned32),
        (0x1006, Some(0), Unsigned32),
        (0x1007, Some(0), Unsigned32),
        (0x1008, Some(0), VisibleString),
        (0x1009, Some(0), VisibleString),
        (0x100A, Some(0), VisibleString),
        (0x100C, Some(0), Unsigned16),
        (0x100D, Some(0), Unsigned8),
        (0x1010, None, Unsigned32),
        (0x1011, None, Unsigned32),
        (0x1012, Some(0), Unsigned32),
        (0x1014, Some(0), Unsigned32),
        (0x1015, Some(0), Unsigned16),
        (0x1016, None, Unsigned32),
        (0x1017, Some(0), Unsigned16),
        (0x1018, None, Unsigned32),
        (0x1019, Some(0), Unsigned8),
        (0x1029, None, Unsigned8),
        (0x6040, Some(0), Unsigned16),
        (0x6041, Some(0), Unsigned16),
        (0x6060, Some(0), Integer8),
        (0x6061, Some(0), Integer8),
        (0x6064, Some(0), Integer32),
        (0x606C, Some(0), Integer32),
        (0x6071, Some(0), Integer16),
        (0x6077, Some(0), Integer16),
        (0x607A, Some(0), Integer32),
        (0x6098, Some(0), Integer8),
        (0x60FF, Some(0), Integer32),
        (0x6502, Some(0), Unsigned32),
    ]
};

fn expected_type(index: u16, sub: u8) -> Option<DataType> {
    use DataType::*;
    if let Some((_, _, t)) = STANDARD_TYPES.iter().find(|(i, s, _)| *i == index && s.is_none_or(|s| s == sub))
    {
        return if sub == 0 && STANDARD_TYPES.iter().any(|(i, s, _)| *i == index && s.is_none()) {
            Some(Unsigned8)
        } else {
            Some(*t)
        };
    }
    match (index, sub) {
        (0x1200..=0x12FF, 1 | 2) | (0x1400..=0x15FF, 1) | (0x1800..=0x19FF, 1) => Some(Unsigned32),
        (0x1200..=0x12FF, 3) | (0x1400..=0x15FF, 2) | (0x1800..=0x19FF, 2 | 4 | 6) => Some(Unsigned8),
        (0x1400..=0x15FF, 3 | 5) | (0x1800..=0x19FF, 3 | 5) => Some(Unsigned16),
        (0x1600..=0x17FF | 0x1A00..=0x1BFF, 0) => Some(Unsigned8),
        (0x1600..=0x17FF | 0x1A00..=0x1BFF, _) => Some(Unsigned32),
        (0x1200..=0x12FF | 0x1400..=0x15FF | 0x1800..=0x19FF, 0) => Some(Unsigned8),
        _ => None,
    }
}

struct Ctx<'a> {
    eds: &'a Eds,
    out: Vec<Finding>,
}

impl<'a> Ctx<'a> {
    fn push(
        &mut self,
        severity: Severity,
        index: Option<u16>,
        sub: Option<u8>,
        line: usize,
        message: String,
    ) {
        self.out.push(Finding { severity, index, sub, line, message });
    }

    fn var(&self, index: u16, sub: u8) -> Option<&'a EdsVar> {
        var_in(self.eds, index, sub)
    }
}

fn var_in(eds: &Eds, index: u16, sub: u8) -> Option<&EdsVar> {
    {
        let o = eds.objects.get(&index)?;
        match &o.var {
            Some(v) if o.compact_sub_obj.is_none() => (sub == 0).then_some(v),
            _ => o.subs.get(&sub),
        }
    }
}

impl Ctx<'_> {
    fn check_var(&mut self, index: u16, sub: u8, v: &EdsVar) {
        let Some(dt) = DataType::from_index(v.data_type) else {
            if !(0x0001..=0x0FFF).contains(&v.data_type) {
                self.push(
                    Severity::Error,
                    Some(index),
                    Some(sub),
                    v.line,
                    format!("unknown DataType {:#06x}", v.data_type),
                );
            }
            return;
        };
        if let Some(want) = expected_type(index, sub)
            && want != dt
        {
            self.push(
                Severity::Error,
                Some(index),
                Some(sub),
                v.line,
                format!("CiA 301/402 defines this as {}, file says {}", want.name(), dt.name()),
            );
        }
        let mut val = |what: &str, t: &Option<String>| -> Option<Vec<u8>> {
            let t = t.as_deref()?.trim();
            if t.is_empty() {
                return None;
            }
            match eval(t, dt, 1) {
                Ok(b) => Some(b),
                Err(m) => {
                    self.out.push(Finding {
                        severity: Severity::Error,
                        index: Some(index),
                        sub: Some(sub),
                        line: v.line,
                        message: format!("{what} outside the range of {}: {m}", dt.name()),
                    });
                    None
                }
            }
        };
        let lo = val("LowLimit", &v.low_limit);
        let hi = val("HighLimit", &v.high_limit);
        let def = val("DefaultValue", &v.default);
        let pv = val("ParameterValue", &v.parameter_value);
        if let (Some(l), Some(h)) = (&lo, &hi)
            && compare_le(dt, l, h) == Some(Ordering::Greater)
        {
            self.push(Severity::Error, Some(index), Some(sub), v.line, "LowLimit is above HighLimit".into());
        }
        for (what, x) in [("DefaultValue", &def), ("ParameterValue", &pv)] {
            let Some(x) = x else { continue };
            let below = lo.as_ref().is_some_and(|l| compare_le(dt, x, l) == Some(Ordering::Less));
            let above = hi.as_ref().is_some_and(|h| compare_le(dt, x, h) == Some(Ordering::Greater));
            if below || above {
                self.push(
                    Severity::Error,
                    Some(index),
                    Some(sub),
                    v.line,
                    format!("{what} outside LowLimit..HighLimit"),
                );
            }
        }
    }

    fn check_mapping(&mut self, index: u16) {
        let rpdo = index < 0x1A00;
        let eds = self.eds;
        let Some(o) = eds.objects.get(&index) else { return };
        let n = o
            .subs
            .get(&0)
            .and_then(|s| s.default.as_deref())
            .and_then(|t| eval(t, DataType::Unsigned8, 1).ok())
            .map_or(0, |b| b[0]);
        let mut bits = 0u32;
        for sub in 1..=n {
            let Some(v) = o.subs.get(&sub) else {
                self.push(
                    Severity::Error,
                    Some(index),
                    Some(sub),
                    o.line,
                    format!("sub 0 says {n} entries but sub {sub} is missing"),
                );
                continue;
            };
            let Some(e) = v.default.as_deref().and_then(|t| eval(t, DataType::Unsigned32, 1).ok()) else {
                continue;
            };
            let e = u32::from_le_bytes([e[0], e[1], e[2], e[3]]);
            let (mi, ms, len) = ((e >> 16) as u16, (e >> 8) as u8, e & 0xFF);
            bits += len;
            if (1..=7).contains(&mi) {
                if !self.eds.dummy_supported(mi) {
                    self.push(
                        Severity::Error,
                        Some(index),
                        Some(sub),
                        v.line,
                        format!("maps dummy {mi:04X} not enabled in [DummyUsage]"),
                    );
                }
                continue;
            }
            let Some(target) = var_in(self.eds, mi, ms) else {
                self.push(
                    Severity::Error,
                    Some(index),
                    Some(sub),
                    v.line,
                    format!("maps {mi:04X}sub{ms:X}, which does not exist"),
                );
                continue;
            };
            let dir_ok = if rpdo { target.access.writable() } else { target.access.readable() };
            if !target.pdo_mapping || !dir_ok {
                self.push(
                    Severity::Error,
                    Some(index),
                    Some(sub),
                    v.line,
                    format!(
                        "maps {mi:04X}sub{ms:X}, which is not {}PDO-mappable",
                        if rpdo { "R" } else { "T" }
                    ),
                );
            }
            if let Some(size) = DataType::from_index(target.data_type).and_then(DataType::fixed_size) {
                let want = if target.data_type == DataType::Boolean as u16 {
                    len == 1 || len == 8
                } else {
                    len == 8 * size as u32
                };
                if !want {
                    self.push(
                        Severity::Error,
                        Some(index),
                        Some(sub),
                        v.line,
                        format!("maps {mi:04X}sub{ms:X} with {len} bits"),
                    );
                }
            }
        }
        if bits > 64 {
            self.push(
                Severity::Error,
                Some(index),
                None,
                o.line,
                format!("default mapping is {bits} bits, over 64"),
            );
        }
    }
}

/// `[FileInfo]` (CiA 306 §4.2): the keys that identify the file are
/// errors when missing (an empty section passed before), the dates and
/// authors warnings. A file without the section at all gets the reader's
/// one warning "[FileInfo] missing": Lely's dcfgen writes its master.dcf
/// so, and its own dcfchk takes it.
fn file_info(c: &mut Ctx<'_>) {
    if c.eds.file_info.is_empty() {
        return;
    }
    let has =
        |k: &str| c.eds.file_info.iter().any(|(key, v)| key.eq_ignore_ascii_case(k) && !v.trim().is_empty());
    let missing = |keys: &[&'static str]| keys.iter().copied().filter(|k| !has(k)).collect::<Vec<_>>();
    let errors = missing(&["FileName", "FileVersion", "FileRevision", "EDSVersion"]);
    let warnings = missing(&[
        "Description",
        "CreationTime",
        "CreationDate",
        "CreatedBy",
        "ModificationTime",
        "ModificationDate",
        "ModifiedBy",
    ]);
    if !errors.is_empty() {
        let msg = format!("[FileInfo] lacks {} (CiA 306 §4.2)", errors.join(", "));
        c.push(Severity::Error, None, None, 0, msg);
    }
    if !warnings.is_empty() {
        let msg = format!("[FileInfo] lacks {} (CiA 306 §4.2)", warnings.join(", "));
        c.push(Severity::Warning, None, None, 0, msg);
    }
}

/// Check a file for CiA 306 violations and inconsistencies, like Lely's
/// dcfchk: missing mandatory objects, wrong types for standard objects,
/// limits outside the type's range, defaults outside limits, default PDO
/// mappings of non-mappable objects.
pub fn check(eds: &Eds) -> Vec<Finding> {
    let mut c = Ctx { eds, out: Vec::new() };
    file_info(&mut c);
    for idx in [0x1000u16, 0x1001, 0x1018] {
        if !eds.objects.contains_key(&idx) {
            c.push(Severity::Error, Some(idx), None, 0, "mandatory object missing (CiA 301 §7.4)".into());
        }
    }
    if eds.objects.contains_key(&0x1018) && c.var(0x1018, 1).is_none() {
        c.push(Severity::Error, Some(0x1018), Some(1), 0, "identity object without vendor-ID".into());
    }
    if !eds.objects.contains_key(&0x1017) && !eds.objects.contains_key(&0x100C) {
        c.push(
            Severity::Warning,
            None,
            None,
            0,
            "neither heartbeat (1017h) nor node guarding (100Ch) is described".into(),
        );
    }
    let listed: std::collections::BTreeSet<u16> =
        eds.mandatory.iter().chain(&eds.optional).chain(&eds.manufacturer).copied().collect();
    for (idx, o) in &eds.objects {
        if !listed.is_empty()
            && !listed.contains(idx)
            && !matches!(o.object_type, ObjectCode::DefType | ObjectCode::DefStruct)
        {
            c.push(
                Severity::Warning,
                Some(*idx),
                None,
                o.line,
                "object not listed in any *Objects section".into(),
            );
        }
        match &o.var {
            Some(v) if o.compact_sub_obj.is_none() => c.check_var(*idx, 0, v),
            _ => {
                for (sub, v) in &o.subs {
                    c.check_var(*idx, *sub, v);
                }
            }
        }
        if matches!(idx, 0x1600..=0x17FF | 0x1A00..=0x1BFF) {
            c.check_mapping(*idx);
        }
    }
    let rx = eds.objects.keys().filter(|i| (0x1400..=0x15FF).contains(*i)).count();
    let tx = eds.objects.keys().filter(|i| (0x1800..=0x19FF).contains(*i)).count();
    if rx != eds.device_info.nr_of_rx_pdo as usize {
        c.push(
            Severity::Warning,
            None,
            None,
            0,
            format!("NrOfRXPDO={} but {rx} RPDO communication objects", eds.device_info.nr_of_rx_pdo),
        );
    }
    if tx != eds.device_info.nr_of_tx_pdo as usize {
        c.push(
            Severity::Warning,
            None,
            None,
            0,
            format!("NrOfTXPDO={} but {tx} TPDO communication objects", eds.device_info.nr_of_tx_pdo),
        );
    }
    c.out.sort_by(|a, b| b.severity.cmp(&a.severity).then(a.index.cmp(&b.index)).then(a.sub.cmp(&b.sub)));
    c.out
}
