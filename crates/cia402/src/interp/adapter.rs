//! The ip and cyclic engines as the drive's `ModeHandler`s:
//! [`IpMode`] (7), [`CspMode`] (8), [`CsvMode`] (9), [`CstMode`] (10).

use super::cyclic::{Cyclic, CyclicConfig, CyclicKind};
use super::ip::{Ip, IpBufferError, IpConfig, Organisation, SubMode, WARNING};
use crate::drive::Units;
use crate::drive::mode::{ModeCommand, ModeHandler, ModeIo, ModeOutput, op};
use core::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use drivebus_od::{SdoAbort, le_i64};

extern crate alloc;

/// Cycle time when 60C2h is 0 or out of range \[s\].
const DEFAULT_PERIOD: f64 = 1e-3;
/// cst halt: torque ramp to zero \[per mille/s\] (6087h is not in `ModeParams`).
const CST_HALT_SLOPE: f64 = 10_000.0;

fn period(io: &ModeIo<'_>) -> f64 {
    io.params.interpolation_period_s().unwrap_or(DEFAULT_PERIOD)
}

/// Halt decelerates on the slow-down ramp 6084h (605Dh option 1).
fn halt_deceleration(io: &ModeIo<'_>) -> f64 {
    io.units.acc_to_pos(f64::from(io.params.profile_deceleration))
}

/// Interpolated position mode for the drive (see [`Ip`]).
///
/// Records: the drive forwards 60C1h:1–3 writes (SDO or RPDO) through
/// [`ModeHandler::write_object`] into the buffer (60C4h:1 records deep);
/// 60C4h:2–6 configure it (actual size, organisation, position, record
/// size, clear) and read back through [`ModeHandler::read_object`]. Linear
/// records are consumed one per SYNC. A host that does not forward writes
/// gets the CiA 402 buffer-size-1 behaviour instead: each SYNC with bit 4
/// set pushes the present 60C1h:1 (`ModeParams::interpolation_data`) before
/// consuming one record (auto-push, switched off by the first forwarded
/// 60C1h write).
///
/// Buffer underflow / overflow set statusword bit 7 and raise EMCY FF01h /
/// FF02h ([`ModeOutput::warning`], [`ModeOutput::emcy`]).
#[derive(Debug, Clone)]
pub struct IpMode {
    engine: Ip,
    auto_push: bool,
    /// No buffer at all: 60C1h is a plain set-point sampled at SYNC.
    latest_only: bool,
    /// Shared with the owner: the buffer fill after every step and write.
    monitor: Option<IpMonitor>,
    /// Buffer under/overflow raise statusword bit 7 and EMCY FF01h/FF02h.
    buffer_warnings: bool,
}

/// A read-only view of an [`IpMode`]'s buffer for whoever built the
/// handler (the handler itself is owned by the drive): records waiting,
/// actual size, the underflow condition. Updated after every control step,
/// SYNC and forwarded write. Cloning shares the view.
#[derive(Debug, Clone, Default)]
pub struct IpMonitor(alloc::sync::Arc<MonitorCell>);

#[derive(Debug, Default)]
struct MonitorCell {
    len: AtomicUsize,
    size: AtomicUsize,
    underflow: AtomicBool,
}

impl IpMonitor {
    /// A view not attached yet (everything 0 until the handler updates it).
    pub fn new() -> Self {
        Self::default()
    }

    /// Records waiting in the buffer.
    pub fn len(&self) -> usize {
        self.0.len.load(Ordering::Relaxed)
    }

    /// Whether no record is waiting.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The actual buffer size (60C4h:2).
    pub fn size(&self) -> usize {
        self.0.size.load(Ordering::Relaxed)
    }

    /// The buffer ran empty while ip was active and no record came since
    /// (the engine's underflow condition).
    pub fn underflow(&self) -> bool {
        self.0.underflow.load(Ordering::Relaxed)
    }

    fn update(&self, ip: &Ip) {
        self.0.len.store(ip.buffer().len(), Ordering::Relaxed);
        self.0.size.store(ip.buffer().size(), Ordering::Relaxed);
        self.0.underflow.store(ip.underflow(), Ordering::Relaxed);
    }
}

impl Default for IpMode {
    fn default() -> Self {
        Self::new(16)
    }
}

impl IpMode {
    /// ip with a buffer of `max_buffer` records (60C4h:1).
    pub fn new(max_buffer: usize) -> Self {
        IpMode {
            engine: Ip::new(max_buffer),
            auto_push: true,
            latest_only: false,
            monitor: None,
            buffer_warnings: true,
        }
    }

    /// Reports the buffer fill to `monitor` (a personality that keeps its
    /// own buffer status object, e.g. a manufacturer status word).
    pub fn with_monitor(mut self, monitor: IpMonitor) -> Self {
        monitor.update(&self.engine);
        self.monitor = Some(monitor);
        self
    }

    /// No statusword bit 7 and no EMCY FF01h/FF02h on buffer under- or
    /// overflow (a personality that signals the buffer state its own way):
    /// an overflowing record is still dropped, an empty buffer still holds.
    pub fn without_buffer_warnings(mut self) -> Self {
        self.buffer_warnings = false;
        self
    }

    fn report(&self) {
        if let Some(m) = &self.monitor {
            m.update(&self.engine);
        }
    }

    /// ip without a set-point buffer (drives without 60C4h): 60C1h:1 is
    /// stored like any parameter and each SYNC with bit 4 set interpolates
    /// towards its present value, so a set-point written twice between two
    /// SYNCs counts once and no underflow exists.
    pub fn latest_only() -> Self {
        let mut engine = Ip::new(1);
        engine.buffer_mut().set_organisation(1);
        IpMode { engine, auto_push: true, latest_only: true, monitor: None, buffer_warnings: true }
    }

    /// The engine (buffer, warnings).
    pub fn engine(&self) -> &Ip {
        &self.engine
    }

    /// The engine, for 60C1h / 60C4h writes.
    pub fn engine_mut(&mut self) -> &mut Ip {
        &mut self.engine
    }

    /// Whether SYNC pushes 60C1h:1 from `ModeParams` (default `true`); turn
    /// off when the OD binding calls `write_data` on every 60C1h write.
    pub fn set_auto_push(&mut self, on: bool) {
        self.auto_push = on;
    }

    fn config(io: &ModeIo<'_>) -> IpConfig {
        IpConfig {
            sub_mode: SubMode::from_code(io.params.interpolation_sub_mode).unwrap_or(SubMode::Linear),
            period: period(io),
            halt_deceleration: halt_deceleration(io),
        }
    }
}

impl ModeHandler for IpMode {
    fn supported_modes(&self) -> u32 {
        op::supported_bit(op::IP)
    }

    fn enter(&mut self, _mode: i8, io: &ModeIo<'_>) {
        self.engine.enter(io.demand_position, io.controlword);
    }

    fn on_sync(&mut self, _mode: i8, io: &ModeIo<'_>) {
        if self.auto_push && io.cw_bit(4) {
            // An overflow is latched as a warning by the engine.
            let _ = self.engine.write_data(1, f64::from(io.params.interpolation_data));
        }
        self.engine.on_sync(io.controlword, &Self::config(io));
        self.report();
    }

    fn step(&mut self, _mode: i8, io: &ModeIo<'_>, dt: f64) -> ModeOutput {
        let out = self.engine.step(io.controlword, &Self::config(io), dt);
        self.report();
        let warnings = self.buffer_warnings;
        ModeOutput {
            command: ModeCommand::Position {
                position: out.position,
                velocity: out.velocity,
                acceleration: out.acceleration,
            },
            status: out.status & ModeOutput::STATUS_MASK,
            warning: warnings && out.status & WARNING != 0,
            emcy: out.emcy.filter(|_| warnings),
            ..ModeOutput::default()
        }
    }

    fn write_object(&mut self, index: u16, sub: u8, data: &[u8], units: &Units) -> Result<bool, SdoAbort> {
        let r = self.write_forwarded(index, sub, data, units);
        self.report();
        r
    }

    fn read_object(&self, index: u16, sub: u8) -> Option<i64> {
        let b = self.engine.buffer();
        match (index, sub) {
            (0x60C4, 1) => Some(b.max_size() as i64),
            (0x60C4, 2) => Some(b.size() as i64),
            (0x60C4, 3) => Some(match b.organisation() {
                Organisation::Fifo => 0,
                Organisation::Ring => 1,
            }),
            (0x60C4, 4) => Some(b.position() as i64),
            (0x60C4, 6) => Some(i64::from(b.access_enabled())),
            _ => None,
        }
    }
}

impl IpMode {
    /// A forwarded write (60C0h, 60C1h:1–3, 60C4h:2–6).
    fn write_forwarded(&mut self, index: u16, sub: u8, data: &[u8], units: &Units) -> Result<bool, SdoAbort> {
        let v = le_i64(data);
        let buf = self.engine.buffer_mut();
        let ok = |b: bool| if b { Ok(true) } else { Err(SdoAbort::INVALID_VALUE) };
        match (index, sub) {
            // 60C0h: 0 linear, −1 PT, −2 PVT (manufacturer sub-modes).
            (0x60C0, 0) => ok(SubMode::from_code(v as i16).is_some()),
            // Stored by the drive, pushed at SYNC.
            (0x60C1, _) if self.latest_only => Ok(false),
            (0x60C1, 1..=3) => {
                self.auto_push = false;
                let value = match sub {
                    1 => v as f64,
                    2 => units.vel_to_pos(v as f64),
                    _ => v as f64,
                };
                match self.engine.write_data(sub, value) {
                    // Overflow is reported as warning bit 7 + EMCY FF02h
                    // (the record is dropped); SDO and RPDO alike.
                    Ok(()) | Err(IpBufferError::Overflow) => Ok(true),
                    // 60C4h:6 = 0: buffer access disabled.
                    Err(IpBufferError::Disabled) => Err(SdoAbort::DEVICE_STATE),
                    Err(IpBufferError::Invalid) => Err(SdoAbort::INVALID_VALUE),
                }
            }
            (0x60C4, 2) => {
                if v < 1 {
                    Err(SdoAbort::VALUE_TOO_LOW)
                } else if v as u64 > buf.max_size() as u64 {
                    Err(SdoAbort::VALUE_TOO_HIGH)
                } else {
                    ok(buf.set_size(v as usize))
                }
            }
            (0x60C4, 3) => ok(buf.set_organisation(v as u8)),
            (0x60C4, 4) => {
                if buf.organisation() == Organisation::Fifo {
                    // A FIFO has no writable position; the one it reads
                    // is taken back unchanged.
                    if v as u64 == buf.position() as u64 { Ok(true) } else { Err(SdoAbort::INVALID_VALUE) }
                } else if v as u64 >= buf.size() as u64 {
                    Err(SdoAbort::VALUE_TOO_HIGH)
                } else {
                    ok(buf.set_position(v as usize))
                }
            }
            // 60C4h:5: the record size of a supported sub-mode.
            (0x60C4, 5) => ok([4, 5, 9].contains(&v)),
            (0x60C4, 6) => {
                let r = ok(buf.set_clear(v as u8));
                if v == 0 {
                    self.engine.clear_warnings();
                }
                r
            }
            _ => Ok(false),
        }
    }
}

/// The shared cyclic adapter.
#[derive(Debug, Clone, Copy)]
struct CyclicMode {
    engine: Cyclic,
    /// 60B2h latched at SYNC: torque feed-forward in csp/csv \[per mille\].
    torque_ff: f64,
}

impl CyclicMode {
    fn new(kind: CyclicKind) -> Self {
        let cfg = CyclicConfig {
            period: DEFAULT_PERIOD,
            following_window: None,
            following_timeout: 0.0,
            halt_deceleration: 0.0,
        };
        CyclicMode { engine: Cyclic::new(kind, 0.0, &cfg), torque_ff: 0.0 }
    }

    fn config(&self, io: &ModeIo<'_>) -> CyclicConfig {
        let p = io.params;
        CyclicConfig {
            period: period(io),
            // 6065h = FFFF FFFFh switches the supervision off.
            following_window: (p.following_error_window != u32::MAX)
                .then(|| f64::from(p.following_error_window)),
            following_timeout: f64::from(p.following_error_timeout) * 1e-3,
            halt_deceleration: match self.engine.kind() {
                CyclicKind::Torque => CST_HALT_SLOPE,
                _ => halt_deceleration(io),
            },
        }
    }

    fn enter(&mut self, io: &ModeIo<'_>) {
        let start = match self.engine.kind() {
            CyclicKind::Position => io.demand_position,
            CyclicKind::Velocity => io.demand_velocity,
            CyclicKind::Torque => io.torque,
        };
        self.engine.enter(start);
        self.torque_ff = 0.0;
    }

    fn on_sync(&mut self, io: &ModeIo<'_>) {
        let p = io.params;
        let u = io.units;
        let (target, offset, ff) = match self.engine.kind() {
            CyclicKind::Position => (
                f64::from(p.target_position),
                f64::from(p.position_offset),
                u.vel_to_pos(f64::from(p.velocity_offset)),
            ),
            CyclicKind::Velocity => {
                (u.vel_to_pos(f64::from(p.target_velocity)), u.vel_to_pos(f64::from(p.velocity_offset)), 0.0)
            }
            CyclicKind::Torque => (f64::from(p.target_torque), f64::from(p.torque_offset), 0.0),
        };
        // csp/csv: 60B2h is torque feed-forward (CiA 402-4; cst adds it to
        // the target above).
        self.torque_ff = match self.engine.kind() {
            CyclicKind::Torque => 0.0,
            _ => f64::from(p.torque_offset),
        };
        let cfg = self.config(io);
        self.engine.sync(target, offset, ff, &cfg);
    }

    fn step(&mut self, io: &ModeIo<'_>, dt: f64) -> ModeOutput {
        let cfg = self.config(io);
        let out = self.engine.step(io.controlword, io.position as f64, &cfg, dt);
        let command = match self.engine.kind() {
            CyclicKind::Position => ModeCommand::Position {
                position: out.demand,
                velocity: out.feed_forward,
                acceleration: out.feed_forward2,
            },
            CyclicKind::Velocity => {
                ModeCommand::Velocity { velocity: out.demand, acceleration: out.feed_forward }
            }
            CyclicKind::Torque => ModeCommand::Torque(out.demand),
        };
        // Halted: no feed-forward, the ramp alone brings the axis to rest.
        let halted = io.cw_bit(8);
        ModeOutput {
            command,
            status: out.status,
            fault: out.fault,
            torque_offset: if halted { 0.0 } else { self.torque_ff },
            ..ModeOutput::default()
        }
    }
}

macro_rules! cyclic_mode {
    ($name:ident, $kind:expr, $op:expr, $doc:literal) => {
        #[doc = $doc]
        #[derive(Debug, Clone, Copy)]
        pub struct $name(CyclicMode);

        impl Default for $name {
            fn default() -> Self {
                $name(CyclicMode::new($kind))
            }
        }

        impl $name {
            /// A mode handler at rest.
            pub fn new() -> Self {
                Self::default()
            }

            /// The engine (demand, following error 60F4h).
            pub fn engine(&self) -> &Cyclic {
                &self.0.engine
            }
        }

        impl ModeHandler for $name {
            fn supported_modes(&self) -> u32 {
                op::supported_bit($op)
            }

            fn enter(&mut self, _mode: i8, io: &ModeIo<'_>) {
                self.0.enter(io);
            }

            fn step(&mut self, _mode: i8, io: &ModeIo<'_>, dt: f64) -> ModeOutput {
                self.0.step(io, dt)
            }

            fn on_sync(&mut self, _mode: i8, io: &ModeIo<'_>) {
                self.0.on_sync(io);
            }

            fn owns_following_error(&self, _mode: i8) -> bool {
                // csp reports bit 13 and 8611h itself (paired samples,
                // 60F4h); the drive does not supervise it a second time.
                self.0.engine.kind() == CyclicKind::Position
            }
        }
    };
}

cyclic_mode!(
    CspMode,
    CyclicKind::Position,
    op::CSP,
    "Cyclic synchronous position (8): 607Ah + 60B0h at SYNC, 60B1h velocity \
     and 60B2h torque feed-forward, following error 6065h/6066h → 8611h \
     (supervised here, not by the drive); 60F4h via \
     `engine().following_error()`."
);
cyclic_mode!(
    CsvMode,
    CyclicKind::Velocity,
    op::CSV,
    "Cyclic synchronous velocity (9): 60FFh + 60B1h at SYNC, 60B2h torque \
     feed-forward."
);
cyclic_mode!(
    CstMode,
    CyclicKind::Torque,
    op::CST,
    "Cyclic synchronous torque (10): 6071h + 60B2h at SYNC \\[per mille\\]."
);

#[cfg(test)]
mod monitor_tests {
    use super::*;

    #[test]
    fn monitor_follows_writes_and_warnings_can_be_off() {
        let m = IpMonitor::new();
        let mut ip = IpMode::new(4).with_monitor(m.clone()).without_buffer_warnings();
        assert_eq!((m.len(), m.size(), m.underflow()), (0, 4, false));
        let u = Units::default();
        assert_eq!(ip.write_object(0x60C4, 2, &[2], &u), Ok(true));
        assert_eq!((m.len(), m.size()), (0, 2));
        for p in [10i32, 20, 30] {
            // The third overflows the 2-record buffer and is dropped.
            assert_eq!(ip.write_object(0x60C1, 1, &p.to_le_bytes(), &u), Ok(true));
        }
        assert_eq!(m.len(), 2);
        assert!(!m.is_empty());
        assert!(ip.engine().overflow());
        // Clearing the buffer (60C4h:6 = 0) empties the view too.
        assert_eq!(ip.write_object(0x60C4, 6, &[0], &u), Ok(true));
        assert!(m.is_empty());
        assert!(!ip.buffer_warnings);
        assert!(IpMode::new(4).buffer_warnings);
    }
}
