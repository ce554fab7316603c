//! iPOS electronic gearing (§11): the slave follows the master position
//! × the gear ratio on the drive's csp.

use super::*;

/// Electronic gearing slave state (§11).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Gear {
    /// Ratio in force: computed when 2013h:02 is written (§11.2.3).
    pub(super) ratio: f64,
    /// Controlword bit 4 as last seen in gearing (the 0 → 1 edge starts).
    bit4: bool,
    /// Following the master (after the 0 → 1 edge of bit 4).
    pub(super) engaged: bool,
    /// Master position the last increment was taken from.
    pub(super) master: i64,
    /// Slave position reference \[increments, fractional\].
    pub(super) reference: f64,
    /// In the gearing (−1) or camming (−2) mode at the last step.
    pub(super) active: bool,
    /// The manufacturer mode in force (−1 gearing, −2 camming).
    pub(super) mode: i8,
    /// When the master position was last taken \[ns\].
    pub(super) updated_ns: u64,
    /// Coupling with the acceleration limited (controlword bit 5 at the
    /// start, §11.1): the slave's reference speed \[increments/s\] ramps to
    /// the master's × ratio at 6083h; `None` once coupled or unlimited.
    coupling: Option<f64>,
}

impl Default for Gear {
    fn default() -> Self {
        Gear {
            ratio: 1.0,
            bit4: false,
            engaged: false,
            master: 0,
            reference: 0.0,
            active: false,
            mode: -1,
            updated_ns: 0,
            coupling: None,
        }
    }
}

/// 2012h "non-cyclic (full 32-bit range)" master resolution (§11.2.2).
pub const MASTER_FULL_RANGE: u32 = 0x8000_0001;

/// The master position increment between two readings of a master of
/// `resolution` increments per revolution (2012h): the shorter way round a
/// cyclic master, the 32-bit difference of a non-cyclic one (§11.1).
pub fn master_increment(from: i64, to: i64, resolution: u32) -> i64 {
    if resolution == MASTER_FULL_RANGE || resolution == 0 || resolution > i32::MAX as u32 {
        return i64::from((to as i32).wrapping_sub(from as i32));
    }
    let r = i64::from(resolution);
    let d = (to - from).rem_euclid(r);
    if d > r / 2 { d - r } else { d }
}

impl Ipos {
    /// Gearing (§11.1): at each master position update the slave
    /// reference moves by the master increment × the gear ratio; the drive
    /// (csp stand-in) takes it at the next SYNC.
    pub(super) fn gear_update(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, master: i64) {
        // 2017h shows the master position whatever the mode (§11.2.4).
        if let Ok(r) = od.find(0x2017, 0) {
            od.set_le(r, &(master as i32).to_le_bytes());
        }
        let res = od.get_u32(0x2012, 0).unwrap_or(MASTER_FULL_RANGE);
        let d = master_increment(self.gear.master, master, res);
        if let Ok(r) = od.find(0x2018, 0) {
            od.set_le(r, &(d.clamp(-32768, 32767) as i16).to_le_bytes());
        }
        self.gear.master = master;
        let now = cx.now.as_nanos();
        let dt = now.saturating_sub(self.gear.updated_ns) as f64 * 1e-9;
        self.gear.updated_ns = now;
        if self.gear.active && self.gear.engaged {
            if self.gear.mode == -2 {
                // §12.1: the cam table's output for the new master position.
                let Some(r) = self.cam_update(od, d, dt) else { return };
                self.gear.reference = r;
            } else {
                self.gear.reference += self.gear_increment(cx, od, d as f64 * self.gear.ratio, dt);
            }
            Self::gear_target(cx, od, self.gear.reference);
        }
    }

    /// The slave reference increment for a master increment × ratio of
    /// `want`: `want` once coupled; while coupling with the acceleration
    /// limited (§11.1: "smooth the slave coupling with the master, by
    /// limiting the maximum acceleration of the slave drive … Controlword.5
    /// = 1 and the maximum acceleration value in 6083h"), the reference
    /// speed ramps to the master's at 6083h and the slave is coupled when
    /// it gets there (the distance lost while ramping stays lost: the
    /// slave's move is relative, §11.1).
    fn gear_increment(&mut self, cx: &mut Context<'_>, od: &ObjectDictionary, want: f64, dt: f64) -> f64 {
        let Some(v) = self.gear.coupling else { return want };
        if dt <= 0.0 {
            return 0.0;
        }
        let u = cx.drive.units();
        let acc = u.pos_to_inc_f(u.acc_to_pos(f64::from(od.get_u32(0x6083, 0).unwrap_or(0)))).abs();
        let target = want / dt;
        let step = acc * dt;
        if (target - v).abs() <= step {
            self.gear.coupling = None;
            return want;
        }
        let v = v + (target - v).clamp(-step, step);
        self.gear.coupling = Some(v);
        v * dt
    }

    /// The slave reference \[increments\] as 607Ah of the csp stand-in, in
    /// position units (the factor group scales 607Ah, §5).
    pub(super) fn gear_target(cx: &mut Context<'_>, od: &mut ObjectDictionary, reference: f64) {
        let t = cx.drive.units().inc_to_pos_f(reference);
        let t = t.round().clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
        let _ = cx.drive.on_write(od, 0x607A, 0, &t.to_le_bytes());
    }

    /// Per step in mode −1 / −2: entry holds the position; the 0 → 1 edge
    /// of controlword bit 4 engages (§11.1.1, §12.1.1); statusword bit 10
    /// is 0 while not halted (Tables 11.1.2, 12.1.2).
    pub(super) fn gear_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, refs: Refs) {
        let view = cx.drive.view();
        let mode = i64_at(od, refs.mode_display).unwrap_or(0) as i8;
        let active = matches!(mode, -1 | -2) && view.state == State::OperationEnabled;
        let bit4 = view.controlword & 0x10 != 0;
        if active && !self.gear.active {
            // The stand-in holds where the axis is until engaged.
            self.gear.engaged = false;
            self.gear.bit4 = bit4;
            self.gear.reference = cx.drive.units().pos_to_inc_f(cx.drive.demand_position());
            Self::gear_target(cx, od, self.gear.reference);
        }
        self.gear.active = active;
        if !active {
            return;
        }
        self.gear.mode = mode;
        if bit4 && !self.gear.bit4 && !self.gear.engaged {
            // "The slave executes a relative move, which starts from its
            // actual position" (§11.1): from the reference it holds.
            self.gear.engaged = true;
            // §11.1.1: bit 5 limits the acceleration while coupling.
            self.gear.coupling = (mode == -1 && view.controlword & 0x20 != 0).then_some(0.0);
            // The master's speed is measured from here on.
            self.gear.updated_ns = cx.now.as_nanos();
            if mode == -2 {
                self.cam_engage(od, view.controlword);
            }
        }
        self.gear.bit4 = bit4;
        if view.controlword & 0x100 == 0
            && let Some(r) = refs.statusword
        {
            let sw = u32_at(od, Some(r)).unwrap_or(0) as u16 & !(1 << 10) & !(1 << 12);
            od.set_le(r, &sw.to_le_bytes());
        }
    }
}
