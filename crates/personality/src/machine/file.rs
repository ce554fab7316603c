//! The machine file: TOML, one `[[node]]` table per node whose machine
//! differs from its profile's default (`docs/machine.md` lists every key).
//!
//! ```toml
//! [[node]]
//! id = 5
//! limits = { negative = -1260.0, positive = 1260.0 }
//!
//! [[node.faults]]
//! at = 2.0
//! kind = "trip"
//! switch = "positive_limit"
//! ```
//!
//! A node's table changes only the keys it names; the rest stays as in
//! [`Machine::default_for`] its profile. Every error names the line and
//! column (1-based) it was found at: TOML syntax, an unknown key, a wrong
//! type, a value out of range or in the wrong order.

use super::io::{Brake, Input, InputChange};
use super::{
    Fault, FaultKind, HardStops, HomeSwitch, LimitSwitches, Machine, MachineError, Polarity, Switch,
};
use crate::Profile;
use drivebus_cia402::model::{ANALOG_INPUTS, DIGITAL_LINES};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use toml::Spanned;

/// A machine file that could not be read or does not fit the drives.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MachineFileError {
    /// Line of the offending text, from 1 (0: not tied to a place).
    pub line: usize,
    /// Column, from 1 (characters).
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

impl core::fmt::Display for MachineFileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.line == 0 {
            write!(f, "{}", self.message)
        } else {
            write!(f, "line {}, column {}: {}", self.line, self.column, self.message)
        }
    }
}

impl std::error::Error for MachineFileError {}

/// 1-based line and column of byte offset `at` in `text`.
fn line_col(text: &str, at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let before = text.get(..at).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

fn pol(p: Option<PolarityName>) -> Option<Polarity> {
    p.map(|p| match p {
        PolarityName::No => Polarity::NormallyOpen,
        PolarityName::Nc => Polarity::NormallyClosed,
    })
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum PolarityName {
    No,
    Nc,
}

type S<T> = Option<Spanned<T>>;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Doc {
    #[serde(default)]
    node: Vec<Spanned<NodePatch>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct NodePatch {
    id: Spanned<u8>,
    feed: S<f64>,
    gear_ratio: S<f64>,
    start: S<f64>,
    limits: Option<LimitsPatch>,
    home_switch: Option<HomePatch>,
    hard_stops: Option<StopsPatch>,
    index: Option<IndexPatch>,
    load: Option<LoadPatch>,
    io: Option<IoPatch>,
    master_encoder: Option<MasterPatch>,
    brake: Option<BrakePatch>,
    temperature: Option<TemperaturePatch>,
    #[serde(default)]
    faults: Vec<Spanned<FaultSpec>>,
    #[serde(default)]
    inputs: Vec<Spanned<InputSpec>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct IoPatch {
    digital_inputs: Option<Vec<Spanned<u8>>>,
    analog_inputs: Option<Spanned<Vec<f64>>>,
    wiring: Option<BTreeMap<String, Spanned<u8>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MasterPatch {
    position: S<f64>,
    velocity: S<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BrakePatch {
    enabled: S<bool>,
    release_delay: S<f64>,
    apply_delay: S<f64>,
    holding_torque: S<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TemperaturePatch {
    ambient: S<f64>,
    motor: S<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
enum InputName {
    Digital,
    Analog,
    MasterVelocity,
    MasterPosition,
    MotorTemperature,
    Brake,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct InputSpec {
    at: Spanned<f64>,
    input: Spanned<InputName>,
    line: S<u8>,
    value: Spanned<f64>,
    duration: S<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitsPatch {
    enabled: S<bool>,
    negative: S<f64>,
    positive: S<f64>,
    polarity: Option<PolarityName>,
    hysteresis: S<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HomePatch {
    enabled: S<bool>,
    from: S<f64>,
    to: S<f64>,
    polarity: Option<PolarityName>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StopsPatch {
    enabled: S<bool>,
    negative: S<f64>,
    positive: S<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct IndexPatch {
    offset: S<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LoadPatch {
    inertia: S<f64>,
    viscous_friction: S<f64>,
    coulomb_friction: S<f64>,
    torque: S<f64>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
enum KindName {
    Trip,
    WireBreak,
    Encoder,
    OverCurrent,
    OverTemperature,
    OverVoltage,
    UnderVoltage,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
enum SwitchName {
    NegativeLimit,
    PositiveLimit,
    HomeSwitch,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FaultSpec {
    at: Spanned<f64>,
    kind: Spanned<KindName>,
    switch: Option<Spanned<SwitchName>>,
    duration: S<f64>,
}

/// The fault `kind` and `switch` name; `Err`: the wrong key and why.
fn fault_of(kind: KindName, switch: Option<SwitchName>) -> Result<FaultKind, (&'static str, String)> {
    let switch = switch.map(|s| match s {
        SwitchName::NegativeLimit => Switch::NegativeLimit,
        SwitchName::PositiveLimit => Switch::PositiveLimit,
        SwitchName::HomeSwitch => Switch::Home,
    });
    Ok(match (kind, switch) {
        (KindName::Trip, Some(s)) => FaultKind::Trip(s),
        (KindName::WireBreak, Some(s)) => FaultKind::WireBreak(s),
        (KindName::Encoder, None) => FaultKind::Encoder,
        (KindName::OverCurrent, None) => FaultKind::OverCurrent,
        (KindName::OverTemperature, None) => FaultKind::OverTemperature,
        (KindName::OverVoltage, None) => FaultKind::OverVoltage,
        (KindName::UnderVoltage, None) => FaultKind::UnderVoltage,
        (KindName::Trip | KindName::WireBreak, None) => {
            return Err(("kind", "needs `switch` (negative_limit, positive_limit or home_switch)".into()));
        }
        _ => return Err(("switch", "only `trip` and `wire_break` take a switch".into())),
    })
}

/// The input `name` with `line` and `value`; `Err`: the wrong key and why.
fn input_of(name: InputName, line: Option<u8>, v: f64) -> Result<Input, (&'static str, String)> {
    let takes_line = matches!(name, InputName::Digital | InputName::Analog);
    let line = match (line, takes_line) {
        (Some(l), true) => l,
        (None, true) => return Err(("input", "needs `line`".into())),
        (Some(_), false) => return Err(("line", "only `digital` and `analog` take a line".into())),
        (None, false) => 0,
    };
    let level = || {
        if v == 0.0 || v == 1.0 {
            Ok(v == 1.0)
        } else {
            Err(("value", format!("{v} is not a level (0 or 1)")))
        }
    };
    Ok(match name {
        InputName::Digital => Input::Digital { line, level: level()? },
        InputName::Analog => Input::Analog { channel: line, volts: v },
        InputName::MasterVelocity => Input::MasterVelocity(v),
        InputName::MasterPosition => Input::MasterPosition(v),
        InputName::MotorTemperature => Input::MotorTemperature(v),
        InputName::Brake => Input::Brake(level()?),
    })
}

/// A name of the machine file's lists (`kind`, `switch`, `input`).
fn name<'de, T: Deserialize<'de>>(key: &str, text: &'de str) -> Result<T, MachineError> {
    use serde::de::IntoDeserializer;
    T::deserialize(IntoDeserializer::<serde::de::value::Error>::into_deserializer(text))
        .map_err(|e| super::err(key, e.to_string()))
}

impl super::Change {
    /// The fault named as in a `[[node.faults]]` entry (`kind`, and
    /// `switch` for `trip` and `wire_break`), or `kind = "clear"` for
    /// [`Change::ClearFaults`](super::Change::ClearFaults).
    pub fn fault(kind: &str, switch: Option<&str>) -> Result<Self, MachineError> {
        if kind == "clear" && switch.is_none() {
            return Ok(super::Change::ClearFaults);
        }
        let switch = switch.map(|s| name("switch", s)).transpose()?;
        fault_of(name("kind", kind)?, switch).map(super::Change::Fault).map_err(|(k, why)| super::err(k, why))
    }

    /// The input change named as in a `[[node.inputs]]` entry (`input`,
    /// `line` for `digital` and `analog`, `value`).
    pub fn input(input: &str, line: Option<u8>, value: f64) -> Result<Self, MachineError> {
        input_of(name("input", input)?, line, value)
            .map(super::Change::Input)
            .map_err(|(k, why)| super::err(k, why))
    }
}

impl FaultKind {
    /// The `kind` and `switch` a `[[node.faults]]` entry names this fault
    /// with (the reverse of [`Change::fault`](super::Change::fault)).
    pub fn names(self) -> (&'static str, Option<&'static str>) {
        let switch = |s: Switch| match s {
            Switch::NegativeLimit => "negative_limit",
            Switch::PositiveLimit => "positive_limit",
            Switch::Home => "home_switch",
        };
        match self {
            FaultKind::Trip(s) => ("trip", Some(switch(s))),
            FaultKind::WireBreak(s) => ("wire_break", Some(switch(s))),
            FaultKind::Encoder => ("encoder", None),
            FaultKind::OverCurrent => ("over_current", None),
            FaultKind::OverTemperature => ("over_temperature", None),
            FaultKind::OverVoltage => ("over_voltage", None),
            FaultKind::UnderVoltage => ("under_voltage", None),
        }
    }
}

impl Input {
    /// The `input`, `line` and `value` a `[[node.inputs]]` entry gives
    /// this change with (the reverse of [`Change::input`](super::Change::input)).
    pub fn names(self) -> (&'static str, Option<u8>, f64) {
        let level = |b: bool| if b { 1.0 } else { 0.0 };
        match self {
            Input::Digital { line, level: l } => ("digital", Some(line), level(l)),
            Input::Analog { channel, volts } => ("analog", Some(channel), volts),
            Input::MasterVelocity(v) => ("master_velocity", None, v),
            Input::MasterPosition(v) => ("master_position", None, v),
            Input::MotorTemperature(v) => ("motor_temperature", None, v),
            Input::Brake(b) => ("brake", None, level(b)),
        }
    }
}

/// Where each key of a node's table is, to place an error on it.
#[derive(Debug, Default)]
struct Spans(BTreeMap<String, Range<usize>>);

impl Spans {
    fn take<T: Copy>(&mut self, key: &str, v: &S<T>) -> Option<T> {
        v.as_ref().map(|s| {
            self.0.insert(key.to_owned(), s.span());
            *s.get_ref()
        })
    }
}

/// A position a table must name because the default machine has none.
fn missing(key: &str) -> MachineError {
    MachineError { key: key.into(), reason: "missing (no default to keep)".into(), other: None }
}

/// A parsed machine file: the `[[node]]` tables by node-ID, still to be
/// laid over each node's default machine ([`MachineFile::machine_for`]).
#[derive(Debug)]
pub struct MachineFile {
    text: String,
    nodes: BTreeMap<u8, Spanned<NodePatch>>,
}

impl MachineFile {
    /// Parses `text` (TOML). Syntax, unknown keys, wrong types, a node-ID
    /// outside 1..=127 or given twice are errors with their place.
    pub fn parse(text: &str) -> Result<MachineFile, MachineFileError> {
        let doc: Doc = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((0, 0), |s| line_col(text, s.start));
            MachineFileError { line, column, message: e.message().trim_end().to_owned() }
        })?;
        let mut nodes = BTreeMap::new();
        for n in doc.node {
            let id = *n.get_ref().id.get_ref();
            let at = |message: String| {
                let (line, column) = line_col(text, n.get_ref().id.span().start);
                MachineFileError { line, column, message }
            };
            if !(1..=127).contains(&id) {
                return Err(at(format!("node id {id} is not in 1..127")));
            }
            if nodes.contains_key(&id) {
                return Err(at(format!("node {id} is given twice")));
            }
            nodes.insert(id, n);
        }
        Ok(MachineFile { text: text.to_owned(), nodes })
    }

    /// Reads and parses a file; an I/O error has no line.
    pub fn read(path: &std::path::Path) -> Result<MachineFile, MachineFileError> {
        let text = std::fs::read_to_string(path).map_err(|e| MachineFileError {
            line: 0,
            column: 0,
            message: format!("cannot read: {e}"),
        })?;
        Self::parse(&text)
    }

    /// The node-IDs the file has a table for.
    pub fn nodes(&self) -> impl Iterator<Item = u8> + '_ {
        self.nodes.keys().copied()
    }

    /// Refuses a table for a node that is not among `present` (a typo
    /// would otherwise leave the intended node on its default machine).
    pub fn check_nodes(&self, present: &[u8]) -> Result<(), MachineFileError> {
        for (id, n) in &self.nodes {
            if !present.contains(id) {
                let (line, column) = line_col(&self.text, n.get_ref().id.span().start);
                return Err(MachineFileError {
                    line,
                    column,
                    message: format!("node {id} has a machine but no drive"),
                });
            }
        }
        Ok(())
    }

    /// The machine of node `node` running `profile`: its default machine
    /// with the file's keys laid over it, checked.
    pub fn machine_for(&self, profile: Profile, node: u8) -> Result<Machine, MachineFileError> {
        let mut m = Machine::default_for(profile);
        let Some(n) = self.nodes.get(&node) else {
            return Ok(m);
        };
        let mut sp = Spans::default();
        let p = n.get_ref();
        let place = |sp: &Spans, e: MachineError| {
            // The key's own place, else its partner's; else the node's id.
            let at =
                sp.0.get(&e.key)
                    .or_else(|| e.other.as_ref().and_then(|o| sp.0.get(o)))
                    .map_or(p.id.span().start, |r| r.start);
            let (line, column) = line_col(&self.text, at);
            MachineFileError { line, column, message: format!("node {node}: {e}") }
        };
        if let Some(v) = sp.take("feed", &p.feed) {
            m.feed = v;
        }
        if let Some(v) = sp.take("gear_ratio", &p.gear_ratio) {
            m.gear_ratio = v;
        }
        if let Some(v) = sp.take("start", &p.start) {
            m.start = v;
        }
        if let Some(l) = &p.limits {
            let enabled = sp.take("limits.enabled", &l.enabled);
            let (neg, posv) =
                (sp.take("limits.negative", &l.negative), sp.take("limits.positive", &l.positive));
            let hyst = sp.take("limits.hysteresis", &l.hysteresis);
            if enabled == Some(false) {
                m.limits = None;
            } else {
                let base = m.limits;
                let need = |v: Option<f64>, b: Option<f64>, key: &str| {
                    v.or(b).ok_or_else(|| place(&sp, missing(key)))
                };
                m.limits = Some(LimitSwitches {
                    negative: need(neg, base.map(|b| b.negative), "limits.negative")?,
                    positive: need(posv, base.map(|b| b.positive), "limits.positive")?,
                    polarity: pol(l.polarity).or(base.map(|b| b.polarity)).unwrap_or_default(),
                    hysteresis: hyst.or(base.map(|b| b.hysteresis)).unwrap_or(0.0),
                });
            }
        }
        if let Some(h) = &p.home_switch {
            let enabled = sp.take("home_switch.enabled", &h.enabled);
            let (from, to) = (sp.take("home_switch.from", &h.from), sp.take("home_switch.to", &h.to));
            if enabled == Some(false) {
                m.home_switch = None;
            } else {
                let base = m.home_switch;
                let need = |v: Option<f64>, b: Option<f64>, key: &str| {
                    v.or(b).ok_or_else(|| place(&sp, missing(key)))
                };
                m.home_switch = Some(HomeSwitch {
                    from: need(from, base.map(|b| b.from), "home_switch.from")?,
                    to: need(to, base.map(|b| b.to), "home_switch.to")?,
                    polarity: pol(h.polarity).or(base.map(|b| b.polarity)).unwrap_or(Polarity::NormallyOpen),
                });
            }
        }
        if let Some(s) = &p.hard_stops {
            let enabled = sp.take("hard_stops.enabled", &s.enabled);
            let (neg, posv) =
                (sp.take("hard_stops.negative", &s.negative), sp.take("hard_stops.positive", &s.positive));
            if enabled == Some(false) {
                m.hard_stops = None;
            } else {
                let base = m.hard_stops;
                let need = |v: Option<f64>, b: Option<f64>, key: &str| {
                    v.or(b).ok_or_else(|| place(&sp, missing(key)))
                };
                m.hard_stops = Some(HardStops {
                    negative: need(neg, base.map(|b| b.negative), "hard_stops.negative")?,
                    positive: need(posv, base.map(|b| b.positive), "hard_stops.positive")?,
                });
            }
        }
        if let Some(i) = &p.index
            && let Some(v) = sp.take("index.offset", &i.offset)
        {
            m.index_offset = v;
        }
        if let Some(l) = &p.load {
            if let Some(v) = sp.take("load.inertia", &l.inertia) {
                m.load.inertia = v;
            }
            if let Some(v) = sp.take("load.viscous_friction", &l.viscous_friction) {
                m.load.viscous_friction = v;
            }
            if let Some(v) = sp.take("load.coulomb_friction", &l.coulomb_friction) {
                m.load.coulomb_friction = v;
            }
            if let Some(v) = sp.take("load.torque", &l.torque) {
                m.load.torque = v;
            }
        }
        for (i, f) in p.faults.iter().enumerate() {
            let f_span = f.span();
            let f = f.get_ref();
            let key = |k: &str| format!("faults[{i}].{k}");
            sp.0.insert(key("at"), f.at.span());
            sp.0.insert(key("kind"), f.kind.span());
            if let Some(d) = &f.duration {
                sp.0.insert(key("duration"), d.span());
            }
            let switch = f.switch.as_ref().map(|s| {
                sp.0.insert(key("switch"), s.span());
                *s.get_ref()
            });
            let kind = match fault_of(*f.kind.get_ref(), switch) {
                Ok(k) => k,
                Err((k, why)) => {
                    let k = key(k);
                    let at = sp.0.get(&k).map_or(f_span.start, |r| r.start);
                    let (line, column) = line_col(&self.text, at);
                    return Err(MachineFileError {
                        line,
                        column,
                        message: format!("node {node}: {k}: {why}"),
                    });
                }
            };
            m.faults.push(Fault {
                at: *f.at.get_ref(),
                kind,
                duration: f.duration.as_ref().map(|d| *d.get_ref()),
            });
        }
        self.signals(node, p, &mut m, &mut sp).map_err(|e| match e {
            Placed::At(e) => e,
            Placed::Key(e) => place(&sp, e),
        })?;
        m.check().map_err(|e| place(&sp, e))?;
        Ok(m)
    }

    /// The machine of node `node` hosting a device from its EDS or DCF (a
    /// CiA 401 I/O module): `io` (inputs at power-on, outputs wired back)
    /// and the digital and analog changes of `[[node.inputs]]`. A key of a
    /// drive's machine (an axis, switches, faults …) is an error at its
    /// place: the device has none of it.
    pub fn io_machine_for(&self, node: u8) -> Result<Machine, MachineFileError> {
        if let Some(n) = self.nodes.get(&node) {
            let p = n.get_ref();
            let spans = [
                ("feed", p.feed.as_ref().map(|s| s.span())),
                ("gear_ratio", p.gear_ratio.as_ref().map(|s| s.span())),
                ("start", p.start.as_ref().map(|s| s.span())),
                ("faults", p.faults.first().map(|s| s.span())),
            ];
            let tables = [
                ("limits", p.limits.is_some()),
                ("home_switch", p.home_switch.is_some()),
                ("hard_stops", p.hard_stops.is_some()),
                ("index", p.index.is_some()),
                ("load", p.load.is_some()),
                ("master_encoder", p.master_encoder.is_some()),
                ("brake", p.brake.is_some()),
                ("temperature", p.temperature.is_some()),
            ];
            let why = "a device from an EDS/DCF has only `io` and digital and analog `inputs`";
            if let Some((key, span)) = spans.iter().find_map(|(k, s)| s.clone().map(|s| (k, s))) {
                return Err(self.error_at(node, span.start, format!("{key}: {why}")));
            }
            if let Some((key, _)) = tables.iter().find(|(_, on)| *on) {
                return Err(self.error_at(node, p.id.span().start, format!("{key}: {why}")));
            }
            for c in &p.inputs {
                let name = *c.get_ref().input.get_ref();
                if !matches!(name, InputName::Digital | InputName::Analog) {
                    let at = c.get_ref().input.span().start;
                    return Err(self.error_at(node, at, format!("inputs: {why}")));
                }
            }
        }
        self.machine_for(Profile::Generic, node)
    }

    fn error_at(&self, node: u8, at: usize, message: String) -> MachineFileError {
        let (line, column) = line_col(&self.text, at);
        MachineFileError { line, column, message: format!("node {node}: {message}") }
    }

    /// The signals' keys: `io`, `master_encoder`, `brake`, `temperature`
    /// and the `[[node.inputs]]` schedule.
    fn signals(&self, node: u8, p: &NodePatch, m: &mut Machine, sp: &mut Spans) -> Result<(), Placed> {
        let at = |span: Range<usize>, msg: String| Placed::At(self.error_at(node, span.start, msg));
        if let Some(io) = &p.io {
            if let Some(lines) = &io.digital_inputs {
                m.io.digital_inputs = 0;
                for l in lines {
                    let n = *l.get_ref();
                    if !(1..=DIGITAL_LINES as u8).contains(&n) {
                        return Err(at(l.span(), format!("io.digital_inputs: {n} is not a line in 1..=16")));
                    }
                    m.io.digital_inputs |= 1 << (n - 1);
                }
            }
            if let Some(a) = &io.analog_inputs {
                sp.0.insert("io.analog_inputs".into(), a.span());
                if a.get_ref().len() > ANALOG_INPUTS {
                    return Err(at(a.span(), "io.analog_inputs: at most 4 channels".into()));
                }
                m.io.analog_inputs = [0.0; ANALOG_INPUTS];
                m.io.analog_inputs[..a.get_ref().len()].copy_from_slice(a.get_ref());
            }
            for (out, to) in io.wiring.iter().flatten() {
                let bad = |what: &str| at(to.span(), format!("io.wiring: {what} is not a line in 1..=16"));
                let k = out.parse::<u8>().ok().filter(|k| (1..=DIGITAL_LINES as u8).contains(k));
                let Some(k) = k else { return Err(bad(&format!("output {out}"))) };
                let n = *to.get_ref();
                if !(1..=DIGITAL_LINES as u8).contains(&n) {
                    return Err(bad(&format!("input {n}")));
                }
                m.io.wiring[usize::from(k - 1)] = n;
            }
        }
        if let Some(e) = &p.master_encoder {
            if let Some(v) = sp.take("master_encoder.position", &e.position) {
                m.master_encoder.position = v;
            }
            if let Some(v) = sp.take("master_encoder.velocity", &e.velocity) {
                m.master_encoder.velocity = v;
            }
        }
        if let Some(b) = &p.brake {
            let enabled = sp.take("brake.enabled", &b.enabled);
            let release = sp.take("brake.release_delay", &b.release_delay);
            let apply = sp.take("brake.apply_delay", &b.apply_delay);
            let torque = sp.take("brake.holding_torque", &b.holding_torque);
            if enabled == Some(false) {
                m.brake = None;
            } else {
                let base = m.brake;
                // Placed at the brake's key the table has.
                let given = if release.is_some() { "brake.release_delay" } else { "brake.apply_delay" };
                let need = |v: Option<f64>, b: Option<f64>, key: &str| {
                    v.or(b).ok_or_else(|| {
                        Placed::Key(MachineError {
                            other: Some(given.into()),
                            ..super::err(key, "missing (no default to keep)")
                        })
                    })
                };
                m.brake = Some(Brake {
                    release_delay: need(release, base.map(|b| b.release_delay), "brake.release_delay")?,
                    apply_delay: need(apply, base.map(|b| b.apply_delay), "brake.apply_delay")?,
                    holding_torque: torque.or(base.and_then(|b| b.holding_torque)),
                });
            }
        }
        if let Some(t) = &p.temperature {
            if let Some(v) = sp.take("temperature.ambient", &t.ambient) {
                m.temperature.ambient = Some(v);
            }
            if let Some(v) = sp.take("temperature.motor", &t.motor) {
                m.temperature.motor = Some(v);
            }
        }
        for (i, c) in p.inputs.iter().enumerate() {
            let c = c.get_ref();
            let key = |k: &str| format!("inputs[{i}].{k}");
            sp.0.insert(key("at"), c.at.span());
            sp.0.insert(key("input"), c.input.span());
            sp.0.insert(key("value"), c.value.span());
            if let Some(d) = &c.duration {
                sp.0.insert(key("duration"), d.span());
            }
            if let Some(l) = &c.line {
                sp.0.insert(key("line"), l.span());
            }
            let line = c.line.as_ref().map(|l| *l.get_ref());
            let input = input_of(*c.input.get_ref(), line, *c.value.get_ref()).map_err(|(k, why)| {
                let span = match k {
                    "line" => c.line.as_ref().map_or(c.input.span(), |l| l.span()),
                    "value" => c.value.span(),
                    _ => c.input.span(),
                };
                at(span, format!("{}: {why}", key(k)))
            })?;
            m.inputs.push(InputChange {
                at: *c.at.get_ref(),
                input,
                duration: c.duration.as_ref().map(|d| *d.get_ref()),
            });
        }
        Ok(())
    }
}

/// An error of the signals' keys: placed already, or at its key.
enum Placed {
    At(MachineFileError),
    Key(MachineError),
}
