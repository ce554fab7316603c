//! Per-step physics and the drive's inner control loops.

use super::{Coeffs, Demand, DriveModel, DriveParams, LoadTorque, StepperParams};
use core::f64::consts::{FRAC_PI_2, PI};

/// `1 − e^(−dt/τ)` (1 for τ = 0: no lag).
fn lag(dt: f64, tau: f64) -> f64 {
    if tau > 0.0 { -libm::expm1(-dt / tau) } else { 1.0 }
}

pub(super) fn coeffs(p: &DriveParams, inertia: f64, dt: f64) -> Coeffs {
    let m = &p.motor;
    let b = &p.bus;
    Coeffs {
        dt,
        current: lag(dt, m.current_time_constant),
        viscous: libm::exp(-m.viscous_friction * dt / inertia),
        thermal: lag(dt, m.thermal_resistance * m.thermal_capacity),
        vel_filter: lag(dt, p.control.velocity_filter),
        // V² decays as e^(−2t/(R·C)) while the chopper conducts.
        brake: if b.capacitance > 0.0 {
            libm::exp(-2.0 * dt / (b.brake_resistance * b.capacitance))
        } else {
            0.0
        },
    }
}

impl DriveModel {
    fn load_torque(&self, theta: f64) -> f64 {
        let t = match self.p.axis.load {
            LoadTorque::None => 0.0,
            LoadTorque::Constant(t) => t,
            LoadTorque::Pendulum { peak, zero } => -peak * libm::sin(theta / self.p.axis.gear_ratio - zero),
            LoadTorque::Spring { stiffness, rest } => -stiffness * (theta - rest),
        };
        t + self.load_step
    }

    /// Current window `[lo, hi]` the power stage can drive at speed `w`:
    /// `|R·i + kₑ·ω| ≤ V_bus`, intersected with `±i_max`.
    fn current_window(&self, w: f64) -> (f64, f64) {
        let m = &self.p.motor;
        let v = self.bus_voltage.max(0.0).min(self.limits.voltage);
        let emf = m.ke * w;
        let imax = self.current_cap();
        let (ip, in_) = (imax.min(self.limits.current[0]), imax.min(self.limits.current[1]));
        let hi = ((v - emf) / m.resistance).clamp(-in_, ip);
        let lo = ((-v - emf) / m.resistance).clamp(-in_, ip);
        (lo, hi.max(lo))
    }

    /// Velocity PI with conditional-integration anti-windup: the integrator
    /// only moves when the output is not saturated or the error drives it
    /// back out of saturation.
    fn velocity_loop(&mut self, v_ref: f64, acc_ff: f64, i_ff: f64, lo: f64, hi: f64, dt: f64) -> f64 {
        let c = &self.p.control;
        let m = &self.p.motor;
        let (vlo, vhi) = self.velocity_window();
        let v_ref = v_ref.clamp(vlo, vhi);
        let e = v_ref - self.vel_meas;
        let ff = acc_ff * self.d.inertia / m.kt + i_ff;
        let u = c.velocity_kp * e + self.int_vel + ff;
        let y = u.clamp(lo, hi);
        let sat = y != u;
        if !sat || (u > hi && e < 0.0) || (u < lo && e > 0.0) {
            self.int_vel = (self.int_vel + c.velocity_ki * e * dt).clamp(-m.max_current, m.max_current);
        }
        self.vel_saturated = sat;
        y
    }

    /// Position P(I); its integrator freezes while either loop saturates.
    fn position_loop(&mut self, p_ref: f64, v_ff: f64, dt: f64) -> f64 {
        let c = &self.p.control;
        let vmax = self.p.motor.max_speed;
        let (vlo, vhi) = self.velocity_window();
        let e = p_ref - self.position_measured();
        let u = c.velocity_feedforward * v_ff + c.position_kp * e + self.int_pos;
        let y = u.clamp(vlo, vhi);
        if c.position_ki > 0.0 && y == u && !self.vel_saturated {
            self.int_pos = (self.int_pos + c.position_ki * e * dt).clamp(-vmax, vmax);
        }
        y
    }

    pub(super) fn servo_step(&mut self, dt: f64) {
        let m = self.p.motor;
        let w = self.omega;
        let (lo, hi) = self.current_window(w);
        let ff = self.current_feedforward();
        let i_ref = match self.cmd {
            Demand::Off => 0.0,
            Demand::ShortCircuit => (-m.ke * w / m.resistance).clamp(-m.max_current, m.max_current),
            Demand::Torque(t) => (t / m.kt + ff).clamp(lo, hi),
            Demand::Velocity { velocity, acceleration } => {
                self.velocity_loop(velocity, acceleration, ff, lo, hi, dt)
            }
            Demand::Position { position, velocity, acceleration } => {
                let v = self.position_loop(position, velocity, dt);
                self.velocity_loop(v, acceleration, ff, lo, hi, dt)
            }
        };
        self.current += (i_ref - self.current) * self.k.current;
        let t_motor = m.kt * self.current;
        self.torque = t_motor;
        self.mechanics(t_motor, dt, false);
        // Blocked rotor: at the current limit without moving for 50 ms.
        // At the limit in force (a lowered limit, the foldback) counts too.
        let (ip, in_) = self.current_limits();
        let limit = if self.current >= 0.0 { ip } else { in_ };
        let blocked =
            limit > 0.0 && self.current.abs() >= 0.95 * limit && self.omega.abs() < 0.01 * m.max_speed;
        self.stall_timer = if blocked { self.stall_timer + dt } else { 0.0 };
        let pushing = self.contact != 0 && t_motor * f64::from(self.contact) > m.coulomb_friction;
        self.set_stalled(pushing || self.stall_timer >= 0.05);
    }

    pub(super) fn stepper_step(&mut self, dt: f64, s: StepperParams) {
        let m = self.p.motor;
        let vmax = m.max_speed;
        let energised = match self.cmd {
            Demand::Off | Demand::ShortCircuit => false,
            Demand::Position { position, .. } => {
                self.step_target = position;
                true
            }
            Demand::Velocity { velocity, .. } => {
                self.step_target += velocity.clamp(-vmax, vmax) * dt;
                true
            }
            // Open-loop steppers have no torque mode: hold the demand.
            Demand::Torque(_) => true,
        };
        let n = self.d.teeth;
        let a = if energised {
            let we = n * self.omega * s.inductance;
            let z = libm::sqrt(m.resistance * m.resistance + we * we);
            (self.bus_voltage.max(0.0) / (m.max_current * z)).min(1.0)
        } else {
            0.0
        };
        let demand = self.demand_position();
        let err_e = if s.closed_loop {
            // Field-oriented: at most 90° electrical ahead of the measured rotor.
            (n * (demand - self.position_measured())).clamp(-FRAC_PI_2, FRAC_PI_2)
        } else {
            n * (demand - self.theta)
        };
        let t_motor = s.holding_torque * a * libm::sin(err_e);
        self.current = m.max_current * a;
        self.torque = t_motor;
        self.mechanics(t_motor, dt, true);
        if !energised {
            return;
        }
        if s.closed_loop {
            let limit = err_e.abs() >= FRAC_PI_2 * 0.999;
            self.stall_timer = if limit { self.stall_timer + dt } else { 0.0 };
            self.set_stalled(self.stall_timer >= 0.05);
        } else {
            // Past ±180° electrical the rotor falls into the next stable
            // equilibrium: 4 full steps lost per electrical period.
            let k = libm::round(n * (demand - self.theta) / (2.0 * PI));
            let k = k.clamp(-1e15, 1e15) as i64;
            if k != self.slip {
                self.slip = k;
                self.stalled = false;
                self.set_stalled(true);
            }
        }
    }

    fn set_stalled(&mut self, now: bool) {
        if now && !self.stalled {
            let e = self.event_at(super::EventKind::Stall, true, self.theta, 1.0);
            self.events.push(e);
        }
        self.stalled = now;
    }

    /// Integrates `J·dω/dt = t_motor + T_load − b·ω − T_c·sgn ω` over `dt`.
    /// Linear part exact (constant torque over the step); stiction and the
    /// zero crossing are handled so the speed does not chatter around 0.
    /// `symplectic`: position from the new speed (stable for the stiff
    /// stepper spring), else trapezoidal.
    fn mechanics(&mut self, t_motor: f64, dt: f64, symplectic: bool) {
        let m = &self.p.motor;
        let j = self.d.inertia;
        let b = m.viscous_friction;
        let t_drive = t_motor + self.load_torque(self.theta);
        // An engaged brake adds to the friction: it holds up to its torque
        // and slips against the motion beyond.
        let brake = self.brake_torque();
        let (t_static, t_coulomb) = (m.static_friction + brake, m.coulomb_friction + brake);
        let w0 = self.omega;
        let integrate = |w: f64, t: f64| {
            if b > 0.0 {
                let w_inf = t / b;
                w_inf + (w - w_inf) * self.k.viscous
            } else {
                w + t / j * dt
            }
        };
        let w1 = if w0 == 0.0 {
            if t_drive.abs() <= t_static {
                0.0
            } else {
                let dir = t_drive.signum();
                let w = integrate(0.0, t_drive - t_coulomb * dir);
                if w * dir > 0.0 { w } else { 0.0 }
            }
        } else {
            let dir = w0.signum();
            let w = integrate(w0, t_drive - t_coulomb * dir);
            // Friction alone cannot reverse the motion: stop at zero, and
            // let the stiction test decide about the next step.
            if w * dir < 0.0 { 0.0 } else { w }
        };
        let mut w1 = w1;
        let mut th = if symplectic { self.theta + w1 * dt } else { self.theta + 0.5 * (w0 + w1) * dt };
        let prev_contact = self.contact;
        self.contact = 0;
        if let Some(s) = self.d.pos_stop.filter(|&s| th >= s) {
            let f = frac(self.theta, th, s);
            th = s;
            w1 = w1.min(0.0);
            self.contact = 1;
            if prev_contact != 1 {
                let e = self.event_at(super::EventKind::HardStop, true, s, f);
                self.events.push(e);
            }
        }
        if let Some(s) = self.d.neg_stop.filter(|&s| th <= s) {
            let f = frac(self.theta, th, s);
            th = s;
            w1 = w1.max(0.0);
            self.contact = -1;
            if prev_contact != -1 {
                let e = self.event_at(super::EventKind::HardStop, false, s, f);
                self.events.push(e);
            }
        }
        self.theta = th;
        self.omega = w1;
    }

    pub(super) fn thermal_step(&mut self) {
        let m = &self.p.motor;
        let power = m.resistance * self.current * self.current;
        let target = m.ambient_temperature + m.thermal_resistance * power;
        self.temperature += (target - self.temperature) * self.k.thermal;
    }

    pub(super) fn bus_step(&mut self, dt: f64) {
        let b = self.p.bus;
        self.regen_power = 0.0;
        if let Some(v) = self.force_bus {
            self.bus_voltage = v;
            return;
        }
        if b.capacitance <= 0.0 {
            self.bus_voltage = b.nominal_voltage;
            return;
        }
        let m = &self.p.motor;
        // Power drawn by the inverter (negative while braking = regeneration);
        // short-circuit braking and a free motor exchange nothing with the bus.
        let p_drawn = match self.cmd {
            Demand::Off | Demand::ShortCircuit => 0.0,
            _ if self.d.teeth > 0.0 => m.resistance * self.current * self.current,
            _ => (m.resistance * self.current + m.ke * self.omega) * self.current,
        };
        let c = b.capacitance;
        let mut v2 = self.bus_voltage * self.bus_voltage - 2.0 * p_drawn * dt / c;
        if let Some(on) = b.brake_on_voltage {
            let on2 = on * on;
            if v2 > on2 {
                let after = (v2 * self.k.brake).max(on2);
                // The energy the braking resistor took this step.
                self.regen_power = (v2 - after) * c / (2.0 * dt);
                v2 = after;
            }
        }
        let v = libm::sqrt(v2.max(0.0));
        // The rectifier holds the bus up at the nominal voltage.
        self.bus_voltage = v.max(b.nominal_voltage);
    }
}

/// Fraction of the step `[a, b]` at which `x` is reached.
pub(super) fn frac(a: f64, b: f64, x: f64) -> f64 {
    let d = b - a;
    if d == 0.0 { 0.0 } else { ((x - a) / d).clamp(0.0, 1.0) }
}
