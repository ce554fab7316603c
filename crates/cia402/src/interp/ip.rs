//! Interpolated position mode (ip, 6060h = 7; CiA 402-2 "Interpolated
//! position mode", objects 60C0h–60C4h).
//!
//! - 60C0h sub-mode: 0 linear (CiA 402); −1 PT and −2 PVT are
//!   manufacturer-specific sub-modes offered for personalities that have
//!   them (negative values are manufacturer-specific in CiA 402).
//! - 60C1h data record: sub 1 position; sub 2 velocity (PVT); sub 3 segment
//!   time in ms (PT, PVT; 0 = the 60C2h period). Writing sub 1 commits the
//!   record with the staged subs 2/3 into the buffer.
//! - 60C2h period: linear records are consumed one per SYNC and interpolated
//!   over that period (see [`Interpolator`]); PT/PVT records are consumed
//!   when the previous segment's time has run out (time-driven; SYNC only
//!   paces the master).
//! - 60C4h buffer: max size, actual size, organisation (0 FIFO / 1 ring),
//!   position, record size, clear ([`IpBuffer`]).
//! - Controlword bit 4 enables ip (statusword bit 12 "ip mode active"),
//!   bit 8 halts (ramp to rest); bit 10 = target reached (the last record's
//!   position reached with nothing left to interpolate, or halted at rest).
//!
//! Buffer errors. CiA 402-2 defines no dedicated statusword bit or error
//! code for ip buffer underflow/overflow (to the best of the sources
//! available here: the standard's object descriptions, vendor manuals;
//! verify against a licensed copy). This implementation reports them as
//! *warnings*: statusword bit 7 (warning) while the condition lasts and an
//! EMCY with a device-specific code from the CiA 301 FF00h–FFFFh range:
//! [`IP_UNDERFLOW_CODE`] FF01h, [`IP_OVERFLOW_CODE`] FF02h. The drive stays
//! in Operation enabled; on underflow it holds the last position.

use alloc::vec::Vec;

use super::cyclic::{CW_HALT, HaltRamp, Interpolator};

/// EMCY / 603Fh-style code for an ip buffer underflow (device specific).
pub const IP_UNDERFLOW_CODE: u16 = 0xFF01;
/// EMCY code for an ip buffer overflow (device specific).
pub const IP_OVERFLOW_CODE: u16 = 0xFF02;
/// Statusword bit 12 in ip: ip mode active.
pub const IP_ACTIVE: u16 = 1 << 12;
/// Statusword bit 10: target reached.
pub const TARGET_REACHED: u16 = 1 << 10;
/// Statusword bit 7: warning.
pub const WARNING: u16 = 1 << 7;

/// 60C0h interpolation sub-mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SubMode {
    /// 0: linear interpolation, one record per SYNC.
    Linear,
    /// −1: position–time segments, linear within a segment.
    Pt,
    /// −2: position–velocity–time segments, cubic Hermite.
    Pvt,
}

impl SubMode {
    /// Decodes 60C0h; `None` for unsupported values (abort 0609 0030).
    pub fn from_code(code: i16) -> Option<Self> {
        match code {
            0 => Some(SubMode::Linear),
            -1 => Some(SubMode::Pt),
            -2 => Some(SubMode::Pvt),
            _ => None,
        }
    }

    /// The 60C0h value.
    pub fn code(self) -> i16 {
        match self {
            SubMode::Linear => 0,
            SubMode::Pt => -1,
            SubMode::Pvt => -2,
        }
    }

    /// 60C4h:5 size of a data record \[bytes\]: position INTEGER32, PT adds
    /// the UNSIGNED8 time, PVT a velocity INTEGER32 and the time.
    pub fn record_size(self) -> u8 {
        match self {
            SubMode::Linear => 4,
            SubMode::Pt => 5,
            SubMode::Pvt => 9,
        }
    }
}

/// One interpolation data record, in position units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IpRecord {
    /// Position \[units\] (60C1h:1).
    pub position: f64,
    /// Velocity at the end of the segment \[units/s\] (60C1h:2, PVT).
    pub velocity: f64,
    /// Segment time \[s\] (60C1h:3); 0 = the 60C2h period.
    pub time: f64,
}

/// A buffer problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IpBufferError {
    /// FIFO full: the record was dropped.
    Overflow,
    /// Buffer access disabled (60C4h:6 = 0): the record was dropped.
    Disabled,
    /// The position is not a finite number within ±[`MAX_VALUE`]: dropped.
    Invalid,
}

/// Largest |position|, |velocity| accepted in a record (the model's
/// set-point limit).
pub const MAX_VALUE: f64 = 1e15;

/// 60C4h buffer organisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Organisation {
    /// 0: first in, first out; a full buffer refuses records (overflow).
    Fifo,
    /// 1: ring; a full buffer overwrites its oldest record.
    Ring,
}

/// The interpolation data buffer (60C4h). Storage is allocated once at
/// construction (max size), never on the record path.
#[derive(Debug, Clone, PartialEq)]
pub struct IpBuffer {
    slots: Vec<IpRecord>,
    size: usize,
    organisation: Organisation,
    read: usize,
    write: usize,
    count: usize,
    enabled: bool,
}

impl IpBuffer {
    /// A buffer of `max` records (60C4h:1, at least 1), actual size = max,
    /// FIFO, access enabled.
    pub fn new(max: usize) -> Self {
        let max = max.clamp(1, 65_536);
        IpBuffer {
            slots: alloc::vec![IpRecord::default(); max],
            size: max,
            organisation: Organisation::Fifo,
            read: 0,
            write: 0,
            count: 0,
            enabled: true,
        }
    }

    /// 60C4h:1 maximum buffer size.
    pub fn max_size(&self) -> usize {
        self.slots.len()
    }

    /// 60C4h:2 actual buffer size.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Writes 60C4h:2; refused (`false`) above the maximum or 0. Clears the buffer.
    pub fn set_size(&mut self, size: usize) -> bool {
        if size == 0 || size > self.max_size() {
            return false;
        }
        self.size = size;
        self.reset();
        true
    }

    /// 60C4h:3 organisation.
    pub fn organisation(&self) -> Organisation {
        self.organisation
    }

    /// Writes 60C4h:3 (0 FIFO, 1 ring; else `false`). Clears the buffer.
    pub fn set_organisation(&mut self, code: u8) -> bool {
        self.organisation = match code {
            0 => Organisation::Fifo,
            1 => Organisation::Ring,
            _ => return false,
        };
        self.reset();
        true
    }

    /// 60C4h:4 buffer position: where the next record goes (0-based).
    pub fn position(&self) -> usize {
        self.write
    }

    /// Writes 60C4h:4 (ring only, below the actual size).
    pub fn set_position(&mut self, p: usize) -> bool {
        if self.organisation != Organisation::Ring || p >= self.size {
            return false;
        }
        self.write = p;
        if self.count == 0 {
            self.read = p;
        }
        true
    }

    /// Writes 60C4h:6: 0 clears the buffer and disables access, 1 enables
    /// access; other values are refused.
    pub fn set_clear(&mut self, v: u8) -> bool {
        match v {
            0 => {
                self.reset();
                self.enabled = false;
            }
            1 => self.enabled = true,
            _ => return false,
        }
        true
    }

    /// 60C4h:6 as read: 1 = access enabled.
    pub fn access_enabled(&self) -> bool {
        self.enabled
    }

    /// Records waiting.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether no record is waiting.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    fn reset(&mut self) {
        self.read = 0;
        self.write = 0;
        self.count = 0;
    }

    /// Stores a record.
    pub fn push(&mut self, r: IpRecord) -> Result<(), IpBufferError> {
        if !self.enabled {
            return Err(IpBufferError::Disabled);
        }
        if self.count == self.size {
            match self.organisation {
                Organisation::Fifo => return Err(IpBufferError::Overflow),
                Organisation::Ring => {
                    // Overwrite the oldest.
                    self.read = (self.read + 1) % self.size;
                    self.count -= 1;
                }
            }
        }
        if let Some(slot) = self.slots.get_mut(self.write) {
            *slot = r;
        }
        self.write = (self.write + 1) % self.size;
        self.count += 1;
        Ok(())
    }

    /// Takes the oldest record.
    pub fn pop(&mut self) -> Option<IpRecord> {
        if self.count == 0 {
            return None;
        }
        let r = self.slots.get(self.read).copied();
        self.read = (self.read + 1) % self.size;
        self.count -= 1;
        r
    }
}

/// A PT/PVT segment in progress.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Segment {
    p0: f64,
    v0: f64,
    p1: f64,
    v1: f64,
    duration: f64,
    t: f64,
    hermite: bool,
}

impl Segment {
    /// (position, velocity, acceleration) at the segment's time.
    fn eval(&self) -> (f64, f64, f64) {
        let d = self.duration;
        let s = (self.t / d).clamp(0.0, 1.0);
        if !self.hermite {
            let v = (self.p1 - self.p0) / d;
            return (self.p0 + (self.p1 - self.p0) * s, v, 0.0);
        }
        // Cubic Hermite basis on s ∈ [0, 1], tangents scaled by d.
        let (m0, m1) = (self.v0 * d, self.v1 * d);
        let (s2, s3) = (s * s, s * s * s);
        let p = (2.0 * s3 - 3.0 * s2 + 1.0) * self.p0
            + (s3 - 2.0 * s2 + s) * m0
            + (-2.0 * s3 + 3.0 * s2) * self.p1
            + (s3 - s2) * m1;
        let dp = (6.0 * s2 - 6.0 * s) * self.p0
            + (3.0 * s2 - 4.0 * s + 1.0) * m0
            + (-6.0 * s2 + 6.0 * s) * self.p1
            + (3.0 * s2 - 2.0 * s) * m1;
        let ddp = (12.0 * s - 6.0) * self.p0
            + (6.0 * s - 4.0) * m0
            + (-12.0 * s + 6.0) * self.p1
            + (6.0 * s - 2.0) * m1;
        (p, dp / d, ddp / (d * d))
    }

    fn done(&self) -> bool {
        self.t >= self.duration * (1.0 - 1e-9)
    }
}

/// Output of one ip period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IpOutput {
    /// Position demand \[units\].
    pub position: f64,
    /// Velocity feed-forward \[units/s\].
    pub velocity: f64,
    /// Acceleration feed-forward \[units/s²\].
    pub acceleration: f64,
    /// Statusword bits 7 (warning: buffer under/overflow), 10 and 12.
    pub status: u16,
    /// A buffer under- or overflow began in this period: the EMCY code to send.
    pub emcy: Option<u16>,
}

/// Settings of an ip run, in position units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IpConfig {
    /// 60C0h sub-mode.
    pub sub_mode: SubMode,
    /// 60C2h interpolation period \[s\].
    pub period: f64,
    /// Halt deceleration \[units/s²\].
    pub halt_deceleration: f64,
}

/// The ip engine (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Ip {
    buffer: IpBuffer,
    linear: Interpolator,
    segment: Option<Segment>,
    staged: IpRecord,
    bit4: bool,
    halt: Option<HaltRamp>,
    last: (f64, f64, f64),
    underflow: bool,
    overflow: bool,
    pending_emcy: Option<u16>,
    sub_mode: SubMode,
}

impl Ip {
    /// An engine with a buffer of `max_buffer` records, at rest at 0.
    pub fn new(max_buffer: usize) -> Self {
        Ip {
            buffer: IpBuffer::new(max_buffer),
            linear: Interpolator::new(0.0, 1e-3),
            segment: None,
            staged: IpRecord::default(),
            bit4: false,
            halt: None,
            last: (0.0, 0.0, 0.0),
            underflow: false,
            overflow: false,
            pending_emcy: None,
            sub_mode: SubMode::Linear,
        }
    }

    /// The buffer (60C4h).
    pub fn buffer(&self) -> &IpBuffer {
        &self.buffer
    }

    /// The buffer, for 60C4h writes.
    pub fn buffer_mut(&mut self) -> &mut IpBuffer {
        &mut self.buffer
    }

    /// Underflow warning in force (buffer ran empty while active).
    pub fn underflow(&self) -> bool {
        self.underflow
    }

    /// Overflow warning in force (a record was refused).
    pub fn overflow(&self) -> bool {
        self.overflow
    }

    /// The mode became active: hold `demand` bumplessly; `controlword` is
    /// the present one (bit 4 already set is no rising edge).
    pub fn enter(&mut self, demand: f64, controlword: u16) {
        let d = if demand.is_finite() { demand } else { 0.0 };
        self.linear.reset(d);
        self.segment = None;
        self.halt = None;
        self.last = (d, 0.0, 0.0);
        self.bit4 = controlword & 0x10 != 0;
    }

    /// A 60C1h write: subs 2 and 3 are staged, sub 1 commits the record.
    /// `value` is in position units (sub 1), units/s (sub 2) or ms (sub 3).
    pub fn write_data(&mut self, sub: u8, value: f64) -> Result<(), IpBufferError> {
        let v = if value.is_finite() { value } else { 0.0 };
        match sub {
            2 => self.staged.velocity = v,
            3 => self.staged.time = v.max(0.0) * 1e-3,
            _ => {
                self.staged.position = v;
                return self.push(self.staged);
            }
        }
        Ok(())
    }

    /// Stores a whole record; an overflow raises the warning. A velocity or
    /// time that is not finite and in range counts as 0.
    pub fn push(&mut self, r: IpRecord) -> Result<(), IpBufferError> {
        let ok = |v: f64| v.is_finite() && v.abs() <= MAX_VALUE;
        if !ok(r.position) {
            return Err(IpBufferError::Invalid);
        }
        let r = IpRecord {
            position: r.position,
            velocity: if ok(r.velocity) { r.velocity } else { 0.0 },
            time: if ok(r.time) && r.time > 0.0 { r.time.min(10.0) } else { 0.0 },
        };
        let res = self.buffer.push(r);
        if res == Err(IpBufferError::Overflow) && !self.overflow {
            self.overflow = true;
            self.pending_emcy = Some(IP_OVERFLOW_CODE);
        } else if res.is_ok() {
            self.underflow = false;
        }
        res
    }

    /// Clears the buffer (60C4h:6 = 0 then 1) and the warnings.
    pub fn clear(&mut self) {
        self.buffer.set_clear(0);
        self.buffer.set_clear(1);
        self.underflow = false;
        self.overflow = false;
    }

    /// Drops the under/overflow warnings (60C4h:6 = 0 clears the buffer).
    pub fn clear_warnings(&mut self) {
        self.underflow = false;
        self.overflow = false;
        self.pending_emcy = None;
    }

    fn active(&self) -> bool {
        self.bit4 && self.halt.is_none()
    }

    fn starve(&mut self) {
        if !self.underflow {
            self.underflow = true;
            self.pending_emcy = Some(IP_UNDERFLOW_CODE);
        }
    }

    /// Controlword bit 4 edge: enabling ip starts interpolating from the
    /// present demand.
    fn update_bit4(&mut self, controlword: u16) {
        let bit4 = controlword & 0x10 != 0;
        if bit4 && !self.bit4 {
            self.linear.reset(self.last.0);
            self.segment = None;
        }
        self.bit4 = bit4;
    }

    /// SYNC with the present controlword: the linear sub-mode consumes one
    /// record (or underflows and holds).
    pub fn on_sync(&mut self, controlword: u16, config: &IpConfig) {
        self.update_bit4(controlword);
        self.sub_mode = config.sub_mode;
        self.linear.set_period(config.period);
        if !self.active() || config.sub_mode != SubMode::Linear {
            return;
        }
        match self.buffer.pop() {
            Some(r) => {
                self.linear.sync(r.position);
                self.overflow = false;
            }
            None => {
                self.starve();
                // Hold where the interpolation stands.
                self.linear.hold();
            }
        }
    }

    fn next_segment(&mut self, config: &IpConfig) {
        let (p0, v0, _) = self.last;
        match self.buffer.pop() {
            Some(r) => {
                let duration = if r.time > 0.0 { r.time } else { config.period };
                let duration = if duration.is_finite() && duration > 0.0 { duration } else { 1e-3 };
                let hermite = config.sub_mode == SubMode::Pvt;
                self.segment = Some(Segment {
                    p0,
                    v0: if hermite { v0 } else { 0.0 },
                    p1: r.position,
                    v1: r.velocity,
                    duration,
                    t: 0.0,
                    hermite,
                });
                self.overflow = false;
            }
            None => {
                self.starve();
                self.segment = None;
            }
        }
    }

    /// One control period.
    pub fn step(&mut self, controlword: u16, config: &IpConfig, dt: f64) -> IpOutput {
        let bit4 = controlword & 0x10 != 0;
        let halt = controlword & CW_HALT != 0;
        let dt = if dt.is_finite() && dt > 0.0 { dt } else { 0.0 };
        self.update_bit4(controlword);
        if config.sub_mode != self.sub_mode {
            self.sub_mode = config.sub_mode;
            self.linear.reset(self.last.0);
            self.segment = None;
        }
        let mut idle = false;
        self.last = if halt {
            let (p, v, _) = self.last;
            let ramp = self.halt.get_or_insert(HaltRamp { position: p, velocity: v });
            let out = ramp.step(config.halt_deceleration, dt);
            idle = out.1 == 0.0;
            out
        } else if !bit4 {
            self.halt = None;
            idle = true;
            (self.last.0, 0.0, 0.0)
        } else {
            if self.halt.take().is_some() {
                self.linear.reset(self.last.0);
                self.segment = None;
            }
            match config.sub_mode {
                SubMode::Linear => {
                    let s = self.linear.step(dt);
                    idle = s.slope == 0.0 && self.buffer.is_empty();
                    (s.value, s.slope, s.curvature)
                }
                SubMode::Pt | SubMode::Pvt => {
                    if self.segment.is_none_or(|s| s.done()) {
                        let mut carry = 0.0;
                        if let Some(s) = self.segment {
                            // The next segment starts from this one's end state.
                            self.last = (s.p1, if s.hermite { s.v1 } else { 0.0 }, 0.0);
                            carry = s.t - s.duration;
                        }
                        self.next_segment(config);
                        if let Some(s) = self.segment.as_mut() {
                            s.t = carry.max(0.0);
                        }
                    }
                    match self.segment.as_mut() {
                        Some(s) => {
                            // Demand for the period's start (see `Interpolator::step`).
                            let out = s.eval();
                            s.t += dt;
                            out
                        }
                        None => {
                            idle = true;
                            (self.last.0, 0.0, 0.0)
                        }
                    }
                }
            }
        };
        let mut status = 0;
        if bit4 {
            status |= IP_ACTIVE;
        }
        if idle {
            status |= TARGET_REACHED;
        }
        if self.underflow || self.overflow {
            status |= WARNING;
        }
        IpOutput {
            position: self.last.0,
            velocity: self.last.1,
            acceleration: self.last.2,
            status,
            emcy: self.pending_emcy.take(),
        }
    }
}
