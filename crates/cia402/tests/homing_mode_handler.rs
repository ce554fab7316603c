//! `HomingMode` through the drive's `ModeHandler` interface, with a
//! stand-in for the drive's frame arithmetic (6063h = counts + offset,
//! position reset shifts the offset), default units (1 unit = 1 increment,
//! 2^20 per revolution).

use drivebus_cia402::drive::{ModeCommand, ModeHandler, ModeIo, ModeParams, Units, op};
use drivebus_cia402::homing::HomingMode;
use drivebus_cia402::model::{AxisParams, Demand, DriveModel, DriveParams};

use core::f64::consts::PI;

const DT: f64 = 1.0 / 8000.0;
const CPR: f64 = 1_048_576.0;

struct DriveStandIn {
    model: DriveModel,
    units: Units,
    params: ModeParams,
    inc_offset: i64,
    demand: f64,
    cw: u16,
}

impl DriveStandIn {
    fn new(start_deg: f64) -> Self {
        let mut p = DriveParams::servo_small();
        p.encoder.index_angle = 0.3;
        p.axis = AxisParams {
            negative_limit: Some(-1000.0),
            negative_stop: Some(-1200.0),
            initial_position: start_deg,
            ..AxisParams::rotary_degrees(1.6e-5)
        };
        let deg = CPR / 360.0; // increments per degree
        let params = ModeParams {
            homing_method: 1,
            homing_speed_switch: (1800.0 * deg) as u32,
            homing_speed_zero: (180.0 * deg) as u32,
            homing_acceleration: (36_000.0 * deg) as u32,
            home_offset: 1000,
            ..ModeParams::default()
        };
        let model = DriveModel::new(p).unwrap();
        let demand = model.position_counts() as f64;
        DriveStandIn { model, units: Units::default(), params, inc_offset: 0, demand, cw: 0x0F }
    }

    fn inc(&self) -> i64 {
        self.model.position_counts() + self.inc_offset
    }

    fn run(&mut self, h: &mut HomingMode, max_steps: usize) -> u16 {
        let mut status = 0;
        for n in 0..max_steps {
            let inc = self.inc();
            let io = ModeIo {
                controlword: self.cw,
                position: self.units.inc_to_pos(inc),
                position_inc: inc,
                inc_offset: self.inc_offset,
                velocity: self.units.rad_to_pos(self.model.velocity_measured()),
                torque: 0.0,
                demand_position: self.demand,
                demand_velocity: 0.0,
                events: self.model.events(),
                switches: self.model.switches(),
                master_position: 0,
                master_velocity: 0.0,
                params: &self.params,
                units: &self.units,
                dt: DT,
                time: n as f64 * DT,
            };
            let out = h.step(op::HM, &io, DT);
            if let Some(r) = out.position_reset {
                // The drive's shift (drive/control.rs): no motion.
                self.inc_offset += self.units.pos_to_inc(r) - inc;
            }
            status = out.status;
            let (position, velocity, acceleration) = match out.command {
                ModeCommand::Position { position, velocity, acceleration } => {
                    (position, velocity, acceleration)
                }
                other => panic!("unexpected {other:?}"),
            };
            self.demand = position;
            let u = &self.units;
            // Demand in the shifted frame → raw motor angle.
            let raw = u.pos_to_inc_f(position) - self.inc_offset as f64;
            assert!(self.model.set_demand(Demand::Position {
                position: u.inc_to_rad(raw),
                velocity: u.pos_to_rad(velocity),
                acceleration: u.pos_to_rad(acceleration),
            }));
            self.model.step(DT);
            if n > 10 && status & 0x0400 != 0 && self.cw & 0x10 != 0 {
                break;
            }
        }
        status
    }
}

fn deg_to_counts(d: f64) -> f64 {
    d / 360.0 * CPR
}

#[test]
fn method_1_then_34_through_the_mode_handler() {
    let mut h = HomingMode::default();
    assert_eq!(h.supported_modes(), op::supported_bit(op::HM));
    assert_eq!(h.supported_methods().len(), 32);
    assert!(h.is_supported(37) && !h.is_supported(36));
    let mut d = DriveStandIn::new(0.0);
    let io_enter = {
        let inc = d.inc();
        ModeIo {
            controlword: d.cw,
            position: inc,
            position_inc: inc,
            inc_offset: d.inc_offset,
            velocity: 0.0,
            torque: 0.0,
            demand_position: d.demand,
            demand_velocity: 0.0,
            events: d.model.events(),
            switches: d.model.switches(),
            master_position: 0,
            master_velocity: 0.0,
            params: &d.params,
            units: &d.units,
            dt: DT,
            time: 0.0,
        }
    };
    h.enter(op::HM, &io_enter);
    d.run(&mut h, 10);
    d.cw = 0x1F;
    assert_eq!(d.run(&mut h, 200_000), 0x1400);
    // Method 1: first index pulse right of the NLS edge at −1000°:
    // 0.3 rad + k·2π → 17.1887° − 720°.
    let index = 0.3 * 180.0 / PI - 720.0;
    let truth = d.model.position() * CPR / (2.0 * PI);
    let want = 1000.0 + truth - deg_to_counts(index);
    assert!((d.inc() as f64 - want).abs() <= 2.0, "{} vs {want}", d.inc());

    // Re-home with method 34 (next index pulse, positive) in the shifted
    // frame: the handler must place the raw events correctly.
    d.params.homing_method = 34;
    d.params.home_offset = -5000;
    d.cw = 0x0F;
    d.run(&mut h, 10);
    let start_deg = d.model.position() * 180.0 / PI;
    d.cw = 0x1F;
    assert_eq!(d.run(&mut h, 200_000), 0x1400);
    let next = 0.3 * 180.0 / PI + 360.0 * ((start_deg - 0.3 * 180.0 / PI) / 360.0).floor() + 360.0;
    let truth = d.model.position() * CPR / (2.0 * PI);
    let want = -5000.0 + truth - deg_to_counts(next);
    assert!((d.inc() as f64 - want).abs() <= 2.0, "{} vs {want}", d.inc());
}
