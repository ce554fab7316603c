//! The ip and cyclic engines as the drive's `ModeHandler`s:
//! [`IpMode`] (7), [`CspMode`] (8), [`CsvMode`] (9), [`CstMode`] (10).

use super::cyclic::{Cyclic, CyclicConfig, CyclicKind};
use super::ip::{Ip, IpConfig, SubMode};
use crate::drive::mode::{ModeCommand, ModeHandler, ModeIo, ModeOutput, op};

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
/// Records: the drive's OD binding should forward 60C1h writes to
/// [`IpMode::engine_mut`]`.write_data(sub, value)` and 60C4h writes to the
/// buffer. Without that (the default), each SYNC with bit 4 set pushes the
/// present 60C1h:1 (`ModeParams::interpolation_data`) before consuming one
/// record: the CiA 402 buffer-size-1 behaviour.
#[derive(Debug, Clone)]
pub struct IpMode {
    engine: Ip,
    auto_push: bool,
}

impl Default for IpMode {
    fn default() -> Self {
        Self::new(16)
    }
}

impl IpMode {
    /// ip with a buffer of `max_buffer` records (60C4h:1).
    pub fn new(max_buffer: usize) -> Self {
        IpMode { engine: Ip::new(max_buffer), auto_push: true }
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
    }

    fn step(&mut self, _mode: i8, io: &ModeIo<'_>, dt: f64) -> ModeOutput {
        let out = self.engine.step(io.controlword, &Self::config(io), dt);
        // Bit 7 (buffer warning) is outside ModeOutput::STATUS_MASK; the
        // drive reads it from `engine().underflow()/overflow()`.
        ModeOutput::new(
            ModeCommand::Position {
                position: out.position,
                velocity: out.velocity,
                acceleration: out.acceleration,
            },
            out.status & ModeOutput::STATUS_MASK,
        )
    }
}

/// The shared cyclic adapter.
#[derive(Debug, Clone, Copy)]
struct CyclicMode {
    engine: Cyclic,
}

impl CyclicMode {
    fn new(kind: CyclicKind) -> Self {
        let cfg = CyclicConfig {
            period: DEFAULT_PERIOD,
            following_window: None,
            following_timeout: 0.0,
            halt_deceleration: 0.0,
        };
        CyclicMode { engine: Cyclic::new(kind, 0.0, &cfg) }
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
        ModeOutput { command, status: out.status, position_reset: None, fault: out.fault }
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
        }
    };
}

cyclic_mode!(
    CspMode,
    CyclicKind::Position,
    op::CSP,
    "Cyclic synchronous position (8): 607Ah + 60B0h at SYNC, 60B1h velocity \
     feed-forward, following error 6065h/6066h → 8611h; 60F4h via \
     `engine().following_error()`."
);
cyclic_mode!(
    CsvMode,
    CyclicKind::Velocity,
    op::CSV,
    "Cyclic synchronous velocity (9): 60FFh + 60B1h at SYNC."
);
cyclic_mode!(
    CstMode,
    CyclicKind::Torque,
    op::CST,
    "Cyclic synchronous torque (10): 6071h + 60B2h at SYNC \\[per mille\\]."
);
