//! The Telnet command channel of the Kollmorgen drives: 2026h (4
//! characters per SDO, KC1 §7.2.2.6 / AKD §6.2.2.9, example 10) and 1026h
//! (one character per SDO, KC1 §7.2.1.18 / AKD §6.2.1.19). A command line
//! ends with CR LF; the answer is `>` + text + `\n\r\n` (example 10).
//!
//! Understood: every parameter the object tables name (KC1 §8.1.3 `[NAME]`,
//! AKD §7.1.4 "ASCII: NAME"), read (`NAME`) and written (`NAME value`,
//! the object's integer value: the float scaling of §8.1.1 is not applied)
//! through the same behaviour as an SDO write; `DRV.FAULTS`,
//! `DRV.WARNINGS`, `DRV.CLRFAULTS` (refused while FBUS.PARAM05 bit 0 says
//! faults reset by the controlword only, KC1 §5.4 / AKD §3.4), and the
//! motion tasks (KC1 §5.1.2 / AKD §4.1): `MT.SET` stores MT.P (607Ah),
//! MT.V (6081h), MT.ACC (6083h), MT.DEC (6084h) and MT.CNTL (bit 0:
//! relative) as task MT.NUM, `MT.MOVE n` starts task n in profile position
//! mode. Other commands answer `Error: unknown command`.

use super::Kollmorgen;
use super::status::Warning;
use crate::build::{Context, Verdict};
use alloc::collections::VecDeque;
use alloc::string::String;
use alloc::vec::Vec;
use drivebus_cia402::drive::op;
use drivebus_cia402::state_machine::State;
use drivebus_od::{DataType, ObjectDictionary, SdoAbort, Value};

extern crate alloc;

/// Motion tasks the drive stores (MT.NUM 0..=127).
pub const TASKS: usize = 128;

/// One line-oriented channel: the command being received, the reply
/// being read.
#[derive(Debug, Clone, Default)]
pub struct Line {
    input: String,
    output: VecDeque<u8>,
}

impl Line {
    /// Characters received; the complete command when CR LF arrived.
    pub fn receive(&mut self, data: &[u8]) -> Option<String> {
        // A runaway line without CR LF is dropped rather than grown.
        if self.input.len() > 256 {
            self.input.clear();
        }
        self.input.extend(data.iter().map(|&b| char::from(b)));
        let end = self.input.find("\r\n")?;
        let cmd: String = self.input.drain(..end + 2).collect();
        Some(String::from(cmd.trim()))
    }

    /// The reply of the last command, to be read.
    pub fn answer(&mut self, text: &str) {
        self.output.clear();
        self.output.push_back(b'>');
        self.output.extend(text.bytes());
        self.output.extend(b"\n\r\n");
    }

    /// The next `n` characters of the reply; NUL once it is exhausted.
    pub fn read<const N: usize>(&mut self) -> [u8; N] {
        let mut b = [0u8; N];
        for c in &mut b {
            *c = self.output.pop_front().unwrap_or(0);
        }
        b
    }
}

/// A stored motion task.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Task {
    /// MT.P \[position units\].
    pub position: i32,
    /// MT.V \[velocity units\].
    pub velocity: u32,
    /// MT.ACC.
    pub acceleration: u32,
    /// MT.DEC.
    pub deceleration: u32,
    /// MT.CNTL (bit 0: relative).
    pub control: u32,
}

/// The parameter names of the object table: `(name, index, sub)`, from
/// the EDS names (`… [NAME, NAME2]` or `… (ASCII: NAME)`).
pub fn parameter_names(eds: &drivebus_eds::Eds) -> Vec<(String, u16, u8)> {
    let mut v: Vec<(String, u16, u8)> = Vec::new();
    for (&index, o) in eds.objects.range(0x2000..) {
        let subs = o.var.iter().map(|var| (0u8, var)).chain(o.subs.iter().map(|(&s, var)| (s, var)));
        for (sub, var) in subs {
            let name = var.name.as_str();
            let inner = match (name.rfind('['), name.find("ASCII: ")) {
                (_, Some(a)) => name[a + 7..].split(')').next(),
                (Some(b), None) => name[b + 1..].split(']').next(),
                _ => None,
            };
            for n in inner.into_iter().flat_map(|t| t.split(',')) {
                let n = n.split_whitespace().next().unwrap_or("");
                let ok = n.contains('.') && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '.');
                if ok && !v.iter().any(|(m, _, _)| m.eq_ignore_ascii_case(n)) {
                    v.push((String::from(n), index, sub));
                }
            }
        }
    }
    v
}

/// A value as Telnet prints it.
fn show(od: &ObjectDictionary, index: u16, sub: u8) -> Option<String> {
    Some(match od.get_value(index, sub)? {
        Value::Str(s) => s,
        Value::Bool(b) => alloc::format!("{}", u8::from(b)),
        _ => {
            alloc::format!("{}", od.get_i64(index, sub).or_else(|| od.get_u64(index, sub).map(|u| u as i64))?)
        }
    })
}

impl Kollmorgen {
    /// The parameter `name` of the object table.
    fn parameter(&self, name: &str) -> Option<(u16, u8)> {
        self.names.iter().find(|(n, _, _)| n.eq_ignore_ascii_case(name)).map(|&(_, i, s)| (i, s))
    }

    /// Runs one Telnet command; the text of its answer.
    pub(crate) fn command(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, line: &str) -> String {
        let mut words = line.split_whitespace();
        let Some(cmd) = words.next() else { return String::new() };
        let arg = words.next();
        let upper = cmd.to_ascii_uppercase();
        match (upper.as_str(), arg) {
            ("DRV.FAULTS", None) => self.faults_text(cx),
            ("DRV.WARNINGS", None) => {
                let w: Vec<String> = self.status.warnings().map(|w| self.warning_text(w)).collect();
                if w.is_empty() { String::from("No warnings active") } else { w.join("\n") }
            }
            ("DRV.CLRFAULTS", None) => {
                if od.get_u32(0x36E9, 0).unwrap_or(0) & 1 != 0 {
                    return String::from("Error: faults are reset by the controlword only (FBUS.PARAM05)");
                }
                let cw = od.get_u32(0x6040, 0).unwrap_or(0) as u16;
                let _ = cx.drive.on_write(od, 0x6040, 0, &(cw & !0x80).to_le_bytes());
                let _ = cx.drive.on_write(od, 0x6040, 0, &(cw | 0x80).to_le_bytes());
                let _ = cx.drive.on_write(od, 0x6040, 0, &(cw & !0x80).to_le_bytes());
                String::new()
            }
            ("MT.SET", None) => {
                let n = self.task_number(od);
                let task = current_task(od, self.parameter("MT.CNTL"));
                match self.tasks.get_mut(n) {
                    Some(t) => {
                        *t = task;
                        String::new()
                    }
                    None => String::from("Error: MT.NUM out of range"),
                }
            }
            ("MT.MOVE", Some(n)) => match n.parse::<usize>().ok().and_then(|n| self.tasks.get(n).copied()) {
                Some(t) => self.start_task(cx, od, t),
                None => String::from("Error: invalid motion task"),
            },
            ("MT.NUM", Some(n)) if self.parameter("MT.NUM").is_none() => match n.parse() {
                Ok(n) => {
                    self.task_num = n;
                    String::new()
                }
                Err(_) => String::from("Error: invalid value"),
            },
            _ => match self.parameter(cmd) {
                Some((i, s)) => match arg {
                    None => show(od, i, s).unwrap_or_default(),
                    Some(v) => match self.telnet_write(cx, od, i, s, v) {
                        Ok(()) => String::new(),
                        Err(a) => alloc::format!("Error: refused ({:08X})", a.0),
                    },
                },
                None => String::from("Error: unknown command"),
            },
        }
    }

    fn faults_text(&self, cx: &Context<'_>) -> String {
        let code = cx.drive.state_machine().fault_code();
        let fault = matches!(cx.drive.state_machine().state(), State::Fault | State::FaultReactionActive);
        if !fault || code == 0 {
            return String::from("No faults active");
        }
        let code = super::kollmorgen_code(code);
        let text = self.profile.info().emcy.iter().find(|e| e.code == code).map_or("", |e| e.text);
        alloc::format!("F{}: {text}", self.status.fault_number(code))
    }

    fn warning_text(&self, w: Warning) -> String {
        let text = self.profile.info().emcy.iter().find(|e| e.code == w.code()).map_or("", |e| e.text);
        alloc::format!("n{}: {text}", w.number())
    }

    fn task_number(&self, od: &ObjectDictionary) -> usize {
        match self.parameter("MT.NUM") {
            Some((i, s)) => od.get_i64(i, s).and_then(|n| usize::try_from(n).ok()).unwrap_or(usize::MAX),
            None => self.task_num,
        }
    }

    /// MT.MOVE: the task's set-point in pp, a new set-point (controlword
    /// bit 4 edge, bit 6 for a relative task) without changing the
    /// master's controlword.
    fn start_task(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, t: Task) -> String {
        let view = cx.drive.view();
        if view.state != State::OperationEnabled || view.mode != op::PP {
            return String::from("Error: motion task needs profile position mode, operation enabled");
        }
        let writes: [(u16, [u8; 4]); 4] = [
            (0x607A, t.position.to_le_bytes()),
            (0x6081, t.velocity.to_le_bytes()),
            (0x6083, t.acceleration.to_le_bytes()),
            (0x6084, t.deceleration.to_le_bytes()),
        ];
        for (i, v) in writes {
            if let Err(a) = self.local_write(cx, od, i, 0, &v) {
                return alloc::format!("Error: refused ({:08X})", a.0);
            }
        }
        let cw = view.controlword;
        let start = (cw & !0x70) | 0x10 | (u16::from(t.control & 1 != 0) << 6);
        for c in [cw & !0x10, start, cw & !0x10] {
            let _ = cx.drive.on_write(od, 0x6040, 0, &c.to_le_bytes());
        }
        String::new()
    }

    /// `NAME value`: parsed for the object's type and written like an SDO
    /// download (limits, the behaviour, the drive), without the access
    /// check of a bus write (Telnet reaches every parameter).
    fn telnet_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        text: &str,
    ) -> Result<(), SdoAbort> {
        let dt = od.get(index, sub).map(|e| e.data_type).ok_or(SdoAbort::NO_OBJECT)?;
        if dt.num_kind().is_none() && dt != DataType::VisibleString {
            return Err(SdoAbort::TYPE_MISMATCH);
        }
        let v = Value::parse(dt, text).map_err(|_| SdoAbort::INVALID_VALUE)?;
        let data = v.encode(dt)?;
        self.local_write(cx, od, index, sub, &data)
    }

    /// A write from inside the drive (Telnet, a motion task): the
    /// behaviour decides, then the drive's entry; stored; the behaviour's
    /// follow-up. Communication objects are not reached this way.
    pub(crate) fn local_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        if index < 0x2000 {
            return Err(SdoAbort::UNSUPPORTED_ACCESS);
        }
        let r = od.find(index, sub)?;
        od.entry(r).validate(data)?;
        let owner = od.entry(r).owner;
        let drive_owned = owner.is_app() && owner != crate::build::BEHAVIOUR;
        let store = match verdict(self, cx, od, index, sub, data)? {
            Verdict::Handled => false,
            Verdict::Store => true,
            Verdict::Pass if drive_owned => {
                cx.drive.on_write(od, index, sub, data)? == drivebus_od::WriteOutcome::Store
            }
            Verdict::Pass => true,
        };
        if store {
            od.set_raw(r, data);
        }
        crate::build::Behaviour::after_write(self, cx, od, index, sub);
        Ok(())
    }
}

/// The behaviour's verdict on a local write (its `on_write`), except for
/// the Telnet channel itself.
fn verdict(
    k: &mut Kollmorgen,
    cx: &mut Context<'_>,
    od: &mut ObjectDictionary,
    index: u16,
    sub: u8,
    data: &[u8],
) -> Result<Verdict, SdoAbort> {
    if index == 0x2026 {
        return Err(SdoAbort::UNSUPPORTED_ACCESS);
    }
    crate::build::Behaviour::on_write(k, cx, od, index, sub, data)
}

/// The task MT.SET stores: the pp objects and MT.CNTL as they are now.
pub(crate) fn current_task(od: &ObjectDictionary, cntl: Option<(u16, u8)>) -> Task {
    let g = |i: u16| od.get_i64(i, 0).unwrap_or(0);
    Task {
        position: g(0x607A) as i32,
        velocity: g(0x6081) as u32,
        acceleration: g(0x6083) as u32,
        deceleration: g(0x6084) as u32,
        control: cntl.and_then(|(i, s)| od.get_i64(i, s)).unwrap_or(0) as u32,
    }
}
