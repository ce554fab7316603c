//! The Kollmorgen status objects and warnings: 1002h manufacturer status
//! register and its bytes 2002h, the fault and warning numbers 2000h/2001h
//! (KC1 §7.2.1.3, §7.2.2.1–3; AKD §6.2.1.3, §6.2.2.1–3), the AKD's run time
//! and fault history 2011h–2013h (§6.2.2.4–6), and the warnings (n-codes)
//! with their EMCY and statusword bit 7 (KC1 §6.4.4, §7.1; AKD §5.4.4,
//! §6.1, FBUS.PARAM05 bit 11 §3.4).

use crate::EmcyEntry;
use crate::build::{Context, EmcyFrame};
use drivebus_can::Instant;
use drivebus_cia402::drive::units::round;
use drivebus_cia402::drive::{DriveView, op};
use drivebus_cia402::state_machine::State;
use drivebus_node::Request;
use drivebus_od::{EntryRef, ObjectDictionary};

/// A warning the emulated drive can raise (n-code, EMCY code of §7.1 /
/// AKD §6.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Warning {
    /// n439: following error above PL.ERRWTHRESH (3483h), EMCY FF12h.
    FollowingError,
    /// n107: beyond the positive software limit (607Dh:2), EMCY 8582h.
    PositiveSoftLimit,
    /// n108: beyond the negative software limit (607Dh:1), EMCY 8583h.
    NegativeSoftLimit,
    /// n125: the PLL lost the SYNC (FBUS.PARAM02 = 1), EMCY 8781h.
    SyncLost,
    /// n301: motor temperature above MOTOR.TEMPWARN (3453h), EMCY 7186h.
    MotorTemperature,
    /// n167: a pp target beyond a software limit was clamped to it, EMCY
    /// 86A9h.
    SoftLimitTraversed,
    /// n304: the motor foldback below IL.FOLDWTHRESH (or its I²t above
    /// IL.MI2TWTRESH), EMCY 8381h.
    MotorFoldback,
}

impl Warning {
    /// The drive's warning number (2000h, DRV.WARNINGS).
    pub fn number(self) -> u32 {
        match self {
            Warning::FollowingError => 439,
            Warning::PositiveSoftLimit => 107,
            Warning::NegativeSoftLimit => 108,
            Warning::SyncLost => 125,
            Warning::MotorTemperature => 301,
            Warning::SoftLimitTraversed => 167,
            Warning::MotorFoldback => 304,
        }
    }

    /// The EMCY code the tables give the warning.
    pub fn code(self) -> u16 {
        match self {
            Warning::FollowingError => 0xFF12,
            Warning::PositiveSoftLimit => 0x8582,
            Warning::NegativeSoftLimit => 0x8583,
            Warning::SyncLost => 0x8781,
            Warning::MotorTemperature => 0x7186,
            Warning::SoftLimitTraversed => 0x86A9,
            Warning::MotorFoldback => 0x8381,
        }
    }
}

/// Up to this many warnings are active at once (there are seven kinds).
const MAX_WARNINGS: usize = 7;
/// AKD 2012h/2013h: the last 20 faults.
const HISTORY: usize = 20;

/// Handles of the status objects, resolved once per dictionary layout.
#[derive(Debug, Clone, Default)]
struct Refs {
    objects: usize,
    statusword: Option<EntryRef>,
    status: Option<EntryRef>,
    bytes: [Option<EntryRef>; 4],
    warnings: [Option<EntryRef>; 3],
    faults: [Option<EntryRef>; 10],
    runtime: Option<EntryRef>,
    history: [Option<EntryRef>; HISTORY],
    stamps: [Option<EntryRef>; HISTORY],
    param05: Option<EntryRef>,
    err_warn: Option<EntryRef>,
    profile_velocity: Option<EntryRef>,
    torque: Option<EntryRef>,
    current: Option<EntryRef>,
    icont: Option<EntryRef>,
}

impl Refs {
    fn resolve(od: &ObjectDictionary) -> Refs {
        let f = |i: u16, s: u8| od.find(i, s).ok();
        Refs {
            objects: od.objects().len(),
            statusword: f(0x6041, 0),
            status: f(0x1002, 0),
            bytes: core::array::from_fn(|k| f(0x2002, k as u8 + 1)),
            warnings: core::array::from_fn(|k| f(0x2000, k as u8 + 1)),
            faults: core::array::from_fn(|k| f(0x2001, k as u8 + 1)),
            runtime: f(0x2011, 0),
            history: core::array::from_fn(|k| f(0x2012, k as u8 + 1)),
            stamps: core::array::from_fn(|k| f(0x2013, k as u8 + 1)),
            param05: f(0x36E9, 0),
            err_warn: f(0x3483, 0),
            profile_velocity: f(0x6081, 0),
            torque: f(0x6077, 0),
            current: f(0x2077, 0),
            icont: f(0x358E, 0),
        }
    }
}

/// The status objects and the active warnings of a KC1/AKD.
#[derive(Debug, Clone)]
pub struct Status {
    refs: Refs,
    emcy: &'static [EmcyEntry],
    /// Active warnings, oldest first.
    warnings: [Option<Warning>; MAX_WARNINGS],
    /// The warnings whose EMCY was sent (bit `Warning as u8`).
    sent: u8,
    /// The fault code (603Fh) last seen, to note a new fault once.
    last_fault: u16,
    /// Fault numbers and their DRV.RUNTIME seconds, newest first.
    history: [(u32, u32); HISTORY],
    boot: Option<Instant>,
    homed: bool,
    /// The fault code last looked up and its number.
    number: (u16, u32),
}

/// A number read from a handle (0 if absent).
fn word(od: &ObjectDictionary, r: Option<EntryRef>) -> u64 {
    r.map_or(0, |r| od.word(r))
}

/// Stores `v` (little-endian, the entry's size) behind a handle.
#[inline(always)]
fn put(od: &mut ObjectDictionary, r: Option<EntryRef>, v: u32) {
    if let Some(r) = r
        && !od.set_low(r, u64::from(v), 4)
    {
        let n = od.bytes(r).len().min(4);
        od.set_raw(r, &v.to_le_bytes()[..n]);
    }
}

/// The number the table gives a code (`F439`, `n125 (warning)` → 439, 125).
pub fn table_number(table: &[EmcyEntry], code: u16) -> u32 {
    table
        .iter()
        .find(|e| e.code == code)
        .and_then(|e| {
            let d = e.detail.strip_prefix('F').or_else(|| e.detail.strip_prefix('n'))?;
            let end = d.find(|c: char| !c.is_ascii_digit()).unwrap_or(d.len());
            d[..end].parse().ok()
        })
        .unwrap_or(0)
}

/// The motor's rated current \[mA\] (at least 1), the unit of 6071h/6077h:
/// MOTOR.ICONT (`icont`, 358Eh, mA) when set, else the motor model's.
pub fn rated_ma(drive: &drivebus_cia402::drive::Drive, icont: u64) -> i64 {
    if icont > 0 {
        return icont.min(u64::from(u32::MAX)) as i64;
    }
    (round(drive.config().params.motor.rated_current * 1000.0) as i64).max(1)
}

/// The Kollmorgen EMCY frame of `code` (§6.4.4.2: class bits, category 01h).
pub fn frame(code: u16) -> EmcyFrame {
    EmcyFrame {
        code,
        register: Some(crate::shared::class_bit(code)),
        bytes: [super::EMCY_CATEGORY, 0, 0, 0, 0],
    }
}

impl Status {
    /// The status of a drive whose EMCY table is `emcy`.
    pub fn new(emcy: &'static [EmcyEntry]) -> Status {
        Status {
            refs: Refs::default(),
            emcy,
            warnings: [None; MAX_WARNINGS],
            sent: 0,
            last_fault: 0,
            history: [(0, 0); HISTORY],
            boot: None,
            homed: false,
            number: (0, 0),
        }
    }

    /// The axis was homed outside the homing mode (HOME.SET): 1002h bit 1.
    pub fn set_homed(&mut self) {
        self.homed = true;
    }

    /// Whether `w` is active.
    pub fn has(&self, w: Warning) -> bool {
        self.warnings.contains(&Some(w))
    }

    /// The active warnings, oldest first.
    pub fn warnings(&self) -> impl Iterator<Item = Warning> + '_ {
        self.warnings.iter().flatten().copied()
    }

    /// The drive's fault number of a 603Fh code (0 if the table has none).
    pub fn fault_number(&self, code: u16) -> u32 {
        table_number(self.emcy, super::kollmorgen_code(code))
    }

    /// Raises or clears `w`: EMCY (unless FBUS.PARAM05 bit 11 turns
    /// warning EMCYs off, AKD §3.4) and the reset EMCY when it goes.
    pub fn set(&mut self, cx: &mut Context<'_>, od: &ObjectDictionary, w: Warning, on: bool) {
        if on == self.has(w) {
            return;
        }
        let bit = 1u8 << (w as u8);
        if on {
            if let Some(slot) = self.warnings.iter_mut().find(|s| s.is_none()) {
                *slot = Some(w);
            }
            if word(od, self.refs.param05) & (1 << 11) == 0 {
                cx.request(frame(w.code()).raise());
                self.sent |= bit;
            }
        } else {
            // Keep the order of the rest (2000h lists them oldest first).
            let mut rest = self.warnings.iter().flatten().copied().filter(|&x| x != w);
            self.warnings = core::array::from_fn(|_| rest.next());
            // The reset EMCY for a warning whose EMCY went out, whatever
            // bit 11 says now.
            if self.sent & bit != 0 {
                self.sent &= !bit;
                cx.request(Request::ClearEmcy(w.code()));
            }
        }
    }

    /// The run time started (boot-up).
    pub fn boot(&mut self, now: Instant) {
        self.boot = Some(now);
    }

    /// NMT reset node: warnings, homing and the fault latch start afresh
    /// (the history is the drive's, kept).
    pub fn reset(&mut self) {
        self.warnings = [None; MAX_WARNINGS];
        self.sent = 0;
        self.last_fault = 0;
        self.homed = false;
    }

    /// After every drive step: the warnings this module supervises, then
    /// the status objects from the drive's state.
    pub fn update(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        if self.refs.objects != od.objects().len() {
            self.refs = Refs::resolve(od);
        }
        // n439: |following error| above PL.ERRWTHRESH while position-controlled.
        let thresh = word(od, self.refs.err_warn) as u32 as i32;
        let view = cx.drive.view();
        let positioning = matches!(view.mode, op::PP | op::HM | op::IP | op::CSP);
        let fe = cx.drive.demand_position() - cx.drive.position() as f64;
        let over = thresh > 0
            && positioning
            && view.state == State::OperationEnabled
            && fe.abs() > f64::from(thresh);
        self.set(cx, od, Warning::FollowingError, over);
        self.publish(cx, od, view);
    }

    /// 1002h, 2002h, 2000h, 2001h, 2011h–2013h and statusword bit 7.
    /// `view`: the drive's, as [`Status::update`] took it (raising a
    /// warning does not change it).
    fn publish(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, view: DriveView) {
        let drive = &*cx.drive;
        let mut sw = word(od, self.refs.statusword) as u16;
        if self.warnings[0].is_some() && sw & 0x80 == 0 {
            sw |= 0x80;
            if let Some(r) = self.refs.statusword {
                od.set_le(r, &sw.to_le_bytes());
            }
        }
        let homing = view.mode == op::HM;
        if homing && sw & 0x1400 == 0x1400 {
            self.homed = true;
        }
        let state = view.state;
        let enabled = state == State::OperationEnabled;
        let moving = enabled && drive.demand_velocity() != 0.0;
        let fault = matches!(state, State::Fault | State::FaultReactionActive);
        // The model's power stage is on from Operation enabled (FBUS.PARAM05
        // bit 8 = 0, power on in Switched on, is not emulated).
        let power =
            matches!(state, State::OperationEnabled | State::QuickStopActive | State::FaultReactionActive);
        let pv_reached = view.mode == op::PV && enabled && sw & 0x400 != 0;
        let pp_at_speed = view.mode == op::PP
            && moving
            && drive.demand_velocity().abs() + 0.5 >= word(od, self.refs.profile_velocity) as f64;
        let di = view.digital_inputs | u32::from(drive.model().digital_inputs() & 0x7F) << 16;
        let bits = [
            (0, moving && matches!(view.mode, op::PP | op::HM | op::IP | op::CSP)),
            (1, self.homed),
            (2, di & 0x4 != 0),
            (3, enabled && sw & 0x400 != 0),
            (7, state == State::QuickStopActive),
            (8, sw & 0x80 != 0),
            (9, pv_reached || pp_at_speed),
            (11, homing && sw & 0x2000 != 0),
            (14, power),
            (15, fault),
            (16, homing && moving),
            (19, state == State::QuickStopActive),
            (23, homing && sw & 0x1000 != 0),
            (24, state == State::FaultReactionActive),
            (25, di & (1 << 16) != 0),
            (26, di & (1 << 17) != 0),
            (27, di & (1 << 18) != 0),
            (28, di & (1 << 19) != 0),
            // Bit 29, the hardware enable input, is not wired in the model;
            // AKD §13 prints 1002h = 0 for an axis at rest: clear.
            (31, matches!(state, State::QuickStopActive | State::FaultReactionActive)),
        ];
        let status = bits.iter().fold(0u32, |acc, &(b, on)| acc | u32::from(on) << b);
        put(od, self.refs.status, status);
        for (k, b) in status.to_le_bytes().into_iter().enumerate() {
            put(od, self.refs.bytes[k], u32::from(b));
        }
        for k in 0..3 {
            put(
                od,
                self.refs.warnings[k],
                self.warnings.get(k).copied().flatten().map_or(0, Warning::number),
            );
        }
        // The drive holds one fault at a time (603Fh).
        let code = drive.state_machine().fault_code();
        // The table is searched once per fault, not every step.
        if self.number.0 != code {
            self.number = (code, self.fault_number(code));
        }
        let number = if fault && code != 0 { self.number.1 } else { 0 };
        put(od, self.refs.faults[0], number);
        let secs = self.boot.map_or(0, |b| cx.now.saturating_duration_since(b).as_secs() as u32);
        put(od, self.refs.runtime, secs);
        // KC1 §7.7.2.2 / AKD §6.7.2.2: 6077h in mA.
        let torque = word(od, self.refs.torque) as u16 as i16;
        put(
            od,
            self.refs.current,
            (i64::from(torque) * rated_ma(drive, word(od, self.refs.icont)) / 1000) as i32 as u32,
        );
        if fault && code != 0 && code != self.last_fault {
            self.history.copy_within(..HISTORY - 1, 1);
            self.history[0] = (number, secs);
            for k in 0..HISTORY {
                put(od, self.refs.history[k], self.history[k].0);
                put(od, self.refs.stamps[k], self.history[k].1);
            }
        }
        self.last_fault = if fault { code } else { 0 };
    }
}
