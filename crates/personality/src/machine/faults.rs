//! Faults of the machine applied at run time: a limit switch that trips,
//! a broken switch wire, an encoder or motor fault, each at a time after
//! the drive started and, optionally, for a while — and, on the same
//! schedule, the machine's input changes ([`super::InputChange`]).
//!
//! The schedule runs inside the drive's own poll ([`FaultSchedule::run`]),
//! so it works the same under `serve`, `slcan-pty`, `--sim`, the demo and
//! on the deterministic virtual bus of a test.

use super::io::{Input, InputChange};
use super::{MachineError, Polarity};
use drivebus_can::Instant;
use drivebus_cia402::drive::{Drive, Injection};
use drivebus_cia402::model::{ANALOG_INPUTS, DIGITAL_LINES, ModelInjection, SwitchInput};

/// One of the three switches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Switch {
    /// Negative limit switch (60FDh bit 0).
    NegativeLimit,
    /// Positive limit switch (60FDh bit 1).
    PositiveLimit,
    /// Home switch (60FDh bit 2).
    Home,
}

impl Switch {
    fn input(self) -> SwitchInput {
        match self {
            Switch::NegativeLimit => SwitchInput::NegativeLimit,
            Switch::PositiveLimit => SwitchInput::PositiveLimit,
            Switch::Home => SwitchInput::Home,
        }
    }
}

/// What goes wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    /// The switch reads actuated wherever the axis is (an obstacle, a
    /// carriage overrunning a cam).
    Trip(Switch),
    /// The switch's wire breaks: it reads actuated if normally closed,
    /// never again if normally open (the axis can then overrun it).
    WireBreak(Switch),
    /// The encoder stops counting (CiA 402 7305h).
    Encoder,
    /// Motor over-current (2310h).
    OverCurrent,
    /// Motor winding over-temperature (4310h).
    OverTemperature,
    /// DC link over-voltage (3210h).
    OverVoltage,
    /// DC link under-voltage (3220h).
    UnderVoltage,
}

/// A fault at a time after the drive started.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fault {
    /// Seconds after the drive started (booted).
    pub at: f64,
    /// What happens.
    pub kind: FaultKind,
    /// How long it lasts \[s\]; `None`: until the drive is rebuilt.
    pub duration: Option<f64>,
}

/// Checks a schedule entry's start and duration.
pub(super) fn check_time(at: f64, duration: Option<f64>) -> Result<(), MachineError> {
    let bad = |key: &str, reason: &str| MachineError { key: key.into(), reason: reason.into(), other: None };
    if !(at.is_finite() && (0.0..=1e9).contains(&at)) {
        return Err(bad("at", "must be a time in seconds, 0 or more"));
    }
    if let Some(d) = duration
        && !(d.is_finite() && d > 0.0 && d <= 1e9)
    {
        return Err(bad("duration", "must be a time in seconds above 0"));
    }
    Ok(())
}

impl Fault {
    pub(super) fn check(&self) -> Result<(), MachineError> {
        check_time(self.at, self.duration)
    }
}

/// What a schedule entry does.
#[derive(Debug, Clone, Copy, PartialEq)]
enum What {
    Fault(FaultKind),
    Input(Input),
}

/// One entry of the schedule: a fault or an input change.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    at: f64,
    duration: Option<f64>,
    what: What,
}

impl Entry {
    fn start_ns(&self) -> u64 {
        (self.at * 1e9) as u64
    }

    fn end_ns(&self) -> Option<u64> {
        self.duration.map(|d| ((self.at + d) * 1e9) as u64)
    }
}

/// A change made while the drive runs (the control interface, a test):
/// the schedule applies it at its next run exactly as an entry due now.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Change {
    /// A machine fault starts.
    Fault(FaultKind),
    /// An input changes.
    Input(Input),
    /// Every machine fault that is on ends, as at the end of a duration
    /// (a latched drive fault stays until the master's fault reset).
    ClearFaults,
}

/// Whether a scheduled entry sets the same input as `input`.
fn same_input(what: &What, input: &Input) -> bool {
    match (what, input) {
        (What::Input(Input::Digital { line: a, .. }), Input::Digital { line: b, .. }) => a == b,
        (What::Input(Input::Analog { channel: a, .. }), Input::Analog { channel: b, .. }) => a == b,
        (What::Input(a), b) => core::mem::discriminant(a) == core::mem::discriminant(b),
        (What::Fault(_), _) => false,
    }
}

/// The machine's own input values, which an input change with a duration
/// returns to.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InputBase {
    /// Digital input lines high (bit `n − 1`: line `n`).
    pub digital_inputs: u16,
    /// Analog inputs \[V\].
    pub analog_inputs: [f64; ANALOG_INPUTS],
    /// Master encoder speed \[counts/s\].
    pub master_velocity: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Pending,
    Active,
    Over,
}

/// The faults and input changes of one machine, applied to its drive as
/// time passes.
#[derive(Debug, Clone)]
pub struct FaultSchedule {
    /// In the order they start (a later change of an input wins).
    faults: Vec<(Entry, Phase)>,
    limits: Polarity,
    home: Polarity,
    base: InputBase,
    /// When the drive started; the schedule's time origin.
    t0: Option<Instant>,
    /// Entries ended by [`FaultSchedule::change`], to clear at the next run.
    ended: bool,
}

impl FaultSchedule {
    /// `faults` for a machine whose limit switches and home switch are
    /// wired with the given polarities.
    pub fn new(faults: Vec<Fault>, limits: Polarity, home: Polarity) -> Self {
        Self::with_inputs(faults, Vec::new(), InputBase::default(), limits, home)
    }

    /// `faults` and `inputs` on one schedule; an input change that ends
    /// returns its input to `base` (the machine's value).
    pub fn with_inputs(
        faults: Vec<Fault>,
        inputs: Vec<InputChange>,
        base: InputBase,
        limits: Polarity,
        home: Polarity,
    ) -> Self {
        let faults =
            faults.into_iter().map(|f| Entry { at: f.at, duration: f.duration, what: What::Fault(f.kind) });
        let inputs =
            inputs.into_iter().map(|c| Entry { at: c.at, duration: c.duration, what: What::Input(c.input) });
        let mut entries: Vec<(Entry, Phase)> = faults.chain(inputs).map(|e| (e, Phase::Pending)).collect();
        entries.sort_by(|a, b| a.0.at.total_cmp(&b.0.at));
        FaultSchedule { faults: entries, limits, home, base, t0: None, ended: false }
    }

    /// Whether there is nothing to apply.
    pub fn is_empty(&self) -> bool {
        self.faults.is_empty()
    }

    /// Sets the time origin (the drive's boot) unless already set.
    pub fn start(&mut self, now: Instant) {
        self.t0.get_or_insert(now);
    }

    /// Makes `change` at `now`, for `duration` seconds (`None`: until
    /// changed again): an entry due now, applied by the next
    /// [`run`](Self::run) (the caller polls the device after this). An
    /// input or duration out of range is refused, naming the key.
    pub fn change(
        &mut self,
        now: Instant,
        change: Change,
        duration: Option<f64>,
    ) -> Result<(), MachineError> {
        let t0 = *self.t0.get_or_insert(now);
        let at = now.as_nanos().saturating_sub(t0.as_nanos()) as f64 / 1e9;
        let what = match change {
            Change::ClearFaults => {
                for (e, p) in &mut self.faults {
                    if *p == Phase::Active && matches!(e.what, What::Fault(_)) {
                        *p = Phase::Over;
                        self.ended = true;
                    }
                }
                return Ok(());
            }
            Change::Fault(k) => {
                check_time(at, duration)?;
                What::Fault(k)
            }
            Change::Input(input) => {
                InputChange { at, input, duration }.check()?;
                if duration.is_none() {
                    // A lasting change supersedes the lasting ones of the
                    // same input (keeps a long-running list short).
                    for (e, p) in &mut self.faults {
                        if *p == Phase::Active && e.duration.is_none() && same_input(&e.what, &input) {
                            *p = Phase::Over;
                        }
                    }
                }
                What::Input(input)
            }
        };
        // Ended entries are history; the inputs they touched are back at
        // the machine's values or touched by an entry still on.
        self.faults.retain(|(_, p)| *p != Phase::Over);
        let i = self.faults.partition_point(|(e, _)| e.at <= at);
        self.faults.insert(i, (Entry { at, duration, what }, Phase::Pending));
        Ok(())
    }

    fn polarity(&self, s: Switch) -> Polarity {
        if s == Switch::Home { self.home } else { self.limits }
    }

    fn injection(&self, what: What) -> Injection {
        use ModelInjection as M;
        let kind = match what {
            What::Fault(k) => k,
            What::Input(i) => return Injection::Model(i.injection()),
        };
        Injection::Model(match kind {
            FaultKind::Trip(s) => M::ForceSwitch(s.input(), Some(true)),
            FaultKind::WireBreak(s) => {
                M::ForceSwitch(s.input(), Some(self.polarity(s) == Polarity::NormallyClosed))
            }
            FaultKind::Encoder => M::EncoderFailure,
            FaultKind::OverCurrent => M::OverCurrent,
            FaultKind::OverTemperature => M::OverTemperature,
            FaultKind::OverVoltage => M::BusOverVoltage,
            FaultKind::UnderVoltage => M::BusUnderVoltage,
        })
    }

    /// The inputs a change may have touched, back at the machine's values.
    fn restore_inputs(&self, inject: &mut impl FnMut(Injection)) {
        use ModelInjection as M;
        let touched = |f: fn(&Input) -> bool| {
            self.faults.iter().any(|(e, p)| *p != Phase::Pending && matches!(&e.what, What::Input(i) if f(i)))
        };
        let b = &self.base;
        if touched(|i| matches!(i, Input::Digital { .. })) {
            for line in 1..=DIGITAL_LINES as u8 {
                let level = b.digital_inputs & (1 << (line - 1)) != 0;
                inject(Injection::Model(M::DigitalInput { line, level }));
            }
        }
        if touched(|i| matches!(i, Input::Analog { .. })) {
            for (k, &volts) in b.analog_inputs.iter().enumerate() {
                inject(Injection::Model(M::AnalogInput { channel: k as u8 + 1, volts }));
            }
        }
        if touched(|i| matches!(i, Input::MasterVelocity(_))) {
            inject(Injection::Model(M::MasterVelocity(b.master_velocity)));
        }
    }

    /// Applies what is due at `now` to `drive` (it shows at the drive's
    /// next control period) and returns when the next change is due.
    pub fn run(&mut self, now: Instant, drive: &mut Drive) -> Option<Instant> {
        self.run_with(now, |i| drive.inject(i))
    }

    /// [`FaultSchedule::run`] for any device the injections reach (an I/O
    /// module takes the digital and analog inputs).
    pub fn run_with(&mut self, now: Instant, mut inject: impl FnMut(Injection)) -> Option<Instant> {
        let t0 = *self.t0.get_or_insert(now);
        let t = now.as_nanos().saturating_sub(t0.as_nanos());
        let mut ended = core::mem::take(&mut self.ended);
        for i in 0..self.faults.len() {
            let (f, phase) = self.faults[i];
            if phase == Phase::Pending && t >= f.start_ns() {
                self.faults[i].1 = Phase::Active;
                inject(self.injection(f.what));
            }
            if self.faults[i].1 == Phase::Active && f.end_ns().is_some_and(|e| t >= e) {
                self.faults[i].1 = Phase::Over;
                ended = true;
            }
        }
        if ended {
            // The model clears its forced conditions all at once and the
            // inputs go back to the machine's values; the faults and
            // changes still on are put back (a jump of the master encoder
            // is not repeated).
            inject(Injection::Model(ModelInjection::Clear));
            self.restore_inputs(&mut inject);
            for (f, _) in self.faults.iter().filter(|(_, p)| *p == Phase::Active) {
                if !matches!(f.what, What::Input(Input::MasterPosition(_))) {
                    inject(self.injection(f.what));
                }
            }
        }
        let next = self
            .faults
            .iter()
            .filter_map(|(f, p)| match p {
                Phase::Pending => Some(f.start_ns()),
                Phase::Active => f.end_ns(),
                Phase::Over => None,
            })
            .min()?;
        Some(Instant::from_nanos(t0.as_nanos().saturating_add(next)))
    }
}

/// A change of the machine in force: a fault, or an input held at a value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InForce {
    /// The fault ([`Change::Fault`]) or input change ([`Change::Input`]).
    pub change: Change,
    /// How long it has been in force \[s\].
    pub active: f64,
    /// Seconds left (`None`: until changed again or cleared).
    pub remaining: Option<f64>,
}

impl FaultSchedule {
    /// The faults and input changes in force at `now`, in the order they
    /// began (a later change of the same input wins): begun, not ended,
    /// not superseded or cleared. A jump of the master encoder is an
    /// event, not a state, and is not listed.
    pub fn in_force(&self, now: Instant) -> Vec<InForce> {
        let Some(t0) = self.t0 else { return Vec::new() };
        let t = now.as_nanos().saturating_sub(t0.as_nanos());
        self.faults
            .iter()
            .filter(|(e, p)| {
                *p != Phase::Over
                    && e.start_ns() <= t
                    && e.end_ns().is_none_or(|end| t < end)
                    && !matches!(e.what, What::Input(Input::MasterPosition(_)))
            })
            .map(|(e, _)| InForce {
                change: match e.what {
                    What::Fault(k) => Change::Fault(k),
                    What::Input(i) => Change::Input(i),
                },
                active: (t as f64 / 1e9 - e.at).max(0.0),
                remaining: e.duration.map(|d| (e.at + d - t as f64 / 1e9).max(0.0)),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_as_the_same_change() {
        let switches = [Switch::NegativeLimit, Switch::PositiveLimit, Switch::Home];
        let mut kinds = vec![
            FaultKind::Encoder,
            FaultKind::OverCurrent,
            FaultKind::OverTemperature,
            FaultKind::OverVoltage,
            FaultKind::UnderVoltage,
        ];
        kinds.extend(switches.iter().flat_map(|&s| [FaultKind::Trip(s), FaultKind::WireBreak(s)]));
        for k in kinds {
            let (kind, switch) = k.names();
            assert_eq!(Change::fault(kind, switch).unwrap(), Change::Fault(k), "{kind} {switch:?}");
        }
        for i in [
            Input::Digital { line: 16, level: true },
            Input::Digital { line: 1, level: false },
            Input::Analog { channel: 4, volts: -2.5 },
            Input::MasterVelocity(1000.0),
            Input::MasterPosition(-5.0),
            Input::MotorTemperature(80.0),
            Input::Brake(true),
            Input::Brake(false),
        ] {
            let (name, line, value) = i.names();
            assert_eq!(Change::input(name, line, value).unwrap(), Change::Input(i), "{name}");
        }
    }

    #[test]
    fn in_force_lists_what_began_and_has_not_ended() {
        let t = |s: f64| Instant::from_nanos((s * 1e9) as u64);
        let mut s = FaultSchedule::new(
            vec![Fault { at: 1.0, kind: FaultKind::Encoder, duration: Some(2.0) }],
            Polarity::default(),
            Polarity::NormallyOpen,
        );
        s.start(t(0.0));
        // The device polls the schedule after every change (`run`).
        let at = |s: &mut FaultSchedule, secs: f64, c: Change| {
            s.change(t(secs), c, None).unwrap();
            s.run_with(t(secs), |_| ());
        };
        assert!(s.in_force(t(0.5)).is_empty(), "the machine file's fault has not begun");
        let enc = s.in_force(t(1.5));
        assert_eq!(enc.len(), 1);
        assert_eq!(enc[0].change, Change::Fault(FaultKind::Encoder));
        assert!((enc[0].active - 0.5).abs() < 1e-9, "{enc:?}");
        assert!((enc[0].remaining.unwrap() - 1.5).abs() < 1e-9, "{enc:?}");
        let d3 = Change::Input(Input::Digital { line: 3, level: true });
        at(&mut s, 2.0, d3);
        at(&mut s, 2.0, Change::Input(Input::MasterPosition(100.0)));
        let now: Vec<Change> = s.in_force(t(2.5)).iter().map(|f| f.change).collect();
        assert_eq!(now, [Change::Fault(FaultKind::Encoder), d3]);
        assert_eq!(s.in_force(t(2.5))[1].remaining, None);
        // The fault's duration ends it; a lasting change of line 3 replaces the first.
        let d3_low = Change::Input(Input::Digital { line: 3, level: false });
        at(&mut s, 3.5, d3_low);
        let now: Vec<Change> = s.in_force(t(3.5)).iter().map(|f| f.change).collect();
        assert_eq!(now, [d3_low]);
        // Clear ends faults, not inputs.
        at(&mut s, 4.0, Change::Fault(FaultKind::OverTemperature));
        assert_eq!(s.in_force(t(4.2)).len(), 2);
        at(&mut s, 4.5, Change::ClearFaults);
        let now: Vec<Change> = s.in_force(t(4.5)).iter().map(|f| f.change).collect();
        assert_eq!(now, [d3_low]);
    }

    #[test]
    fn changes_are_named_as_in_the_machine_file() {
        assert_eq!(Change::fault("encoder", None).unwrap(), Change::Fault(FaultKind::Encoder));
        assert_eq!(
            Change::fault("trip", Some("positive_limit")).unwrap(),
            Change::Fault(FaultKind::Trip(Switch::PositiveLimit))
        );
        assert_eq!(Change::fault("clear", None).unwrap(), Change::ClearFaults);
        assert_eq!(Change::fault("trip", None).unwrap_err().key, "kind");
        assert_eq!(Change::fault("encoder", Some("home_switch")).unwrap_err().key, "switch");
        assert!(Change::fault("encodr", None).unwrap_err().reason.contains("unknown variant"));
        assert_eq!(
            Change::input("digital", Some(3), 1.0).unwrap(),
            Change::Input(Input::Digital { line: 3, level: true })
        );
        assert_eq!(Change::input("digital", Some(3), 0.5).unwrap_err().key, "value");
        assert_eq!(Change::input("analog", None, 1.0).unwrap_err().key, "input");
        assert_eq!(Change::input("brake", Some(1), 1.0).unwrap_err().key, "line");
    }

    /// The injections `run` makes at `now`.
    fn run(s: &mut FaultSchedule, ms: u64) -> Vec<Injection> {
        let mut got = Vec::new();
        s.run_with(Instant::from_millis(ms), |i| got.push(i));
        got
    }

    #[test]
    fn run_time_changes_go_through_the_schedule() {
        use ModelInjection as M;
        let mut s = FaultSchedule::new(Vec::new(), Polarity::NormallyClosed, Polarity::NormallyOpen);
        s.start(Instant::ZERO);
        s.change(Instant::from_millis(10), Change::Fault(FaultKind::Encoder), None).unwrap();
        assert_eq!(run(&mut s, 10), [Injection::Model(M::EncoderFailure)]);
        // A lasting input supersedes the earlier lasting one of its line.
        let dig = |level| Change::Input(Input::Digital { line: 2, level });
        s.change(Instant::from_millis(20), dig(true), None).unwrap();
        assert_eq!(run(&mut s, 20), [Injection::Model(M::DigitalInput { line: 2, level: true })]);
        s.change(Instant::from_millis(25), dig(false), None).unwrap();
        assert_eq!(run(&mut s, 25), [Injection::Model(M::DigitalInput { line: 2, level: false })]);
        assert_eq!(s.faults.len(), 2, "the superseded change is gone");
        // Clear: the model's conditions go, the inputs come back, the
        // input change still on is put back, the fault is not.
        s.change(Instant::from_millis(30), Change::ClearFaults, None).unwrap();
        let got = run(&mut s, 30);
        assert_eq!(got[0], Injection::Model(M::Clear));
        assert!(!got.contains(&Injection::Model(M::EncoderFailure)));
        assert_eq!(got.last(), Some(&Injection::Model(M::DigitalInput { line: 2, level: false })));
        assert!(run(&mut s, 40).is_empty());
        assert!(s.change(Instant::from_millis(50), dig(true), Some(0.0)).is_err());
    }
}
