//! Write validation (SDO and RPDO) and the drive's copy of its parameters.

use super::config::{ZeroMeansOff, ZeroRamp};
use super::mode::op;
use super::{Drive, Units};
use drivebus_od::{ObjectDictionary, SdoAbort, WriteOutcome, le_i64, le_u64};

/// Inclusive range check with the CiA 301 abort for each side.
fn range(v: i64, lo: i64, hi: i64) -> Result<(), SdoAbort> {
    if v < lo {
        Err(SdoAbort::VALUE_TOO_LOW)
    } else if v > hi {
        Err(SdoAbort::VALUE_TOO_HIGH)
    } else {
        Ok(())
    }
}

/// Reads a 2-entry array or record (sub 1, sub 2) as u32s.
fn pair(od: &ObjectDictionary, index: u16) -> (u32, u32) {
    (od.get_u32(index, 1).unwrap_or(1), od.get_u32(index, 2).unwrap_or(1))
}

/// Where a parameter's object is: the drive's withdrawn objects
/// (`Drive::withdraw_object`; the device may have another object at that
/// index, e.g. a manufacturer-shaped one), else the dictionary.
fn source<'a>(od: &'a ObjectDictionary, withdrawn: &'a ObjectDictionary, index: u16) -> &'a ObjectDictionary {
    if withdrawn.object(index).is_some() { withdrawn } else { od }
}

impl Drive {
    /// Validates and applies a write to one of the drive's hooked objects.
    pub(crate) fn write_hook(
        &mut self,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        // The personality may refuse by drive state (e.g. no 1010h store
        // while enabled); it sees every hooked write, 1000h–1FFFh included,
        // because the node asks the application first.
        if let Some(ext) = self.cfg.extension.get() {
            ext.check_write(&self.view(), index, sub, data)?;
        }
        // Mode objects a handler may own (ip buffer, homing method): the
        // owner validates and takes the value; the drive keeps its copy.
        if matches!(index, 0x60C0 | 0x60C1 | 0x60C4 | 0x6098) {
            let units = self.units;
            for h in self.handlers.iter_mut() {
                if h.write_object(index, sub, data, &units)? {
                    break;
                }
            }
        }
        // Type, length and OD limits were checked by the dictionary.
        let s = le_i64(data);
        let u = le_u64(data);
        let u32v = u as u32;
        let p = &mut self.params;
        let x = &mut self.extra;
        match (index, sub) {
            (0x6040, 0) => {
                self.controlword(od, u as u16);
                return Ok(WriteOutcome::Store);
            }
            (0x6060, 0) => {
                let m = s as i8;
                // CiA 402-2 6060h: 0 is "no mode change / no mode
                // assigned" (the power-on value of a drive without a
                // default mode): stored, the mode in force stays.
                if m == 0 {
                    return Ok(WriteOutcome::Store);
                }
                if op::supported_bit(m) & self.modes == 0 {
                    // CiA 402-2 §6.3.2: an unsupported mode is refused.
                    return Err(SdoAbort::INVALID_VALUE);
                }
                self.request_mode(od, m);
                return Ok(WriteOutcome::Store);
            }
            (0x6007 | 0x605A..=0x605E, 0) => {
                let v = s as i16;
                let o = self.sm.options_mut();
                let r = match index {
                    0x6007 => o.set_abort_connection(v),
                    0x605A => o.set_quick_stop(v),
                    0x605B => o.set_shutdown(v),
                    0x605C => o.set_disable_operation(v),
                    0x605D => o.set_halt(v),
                    _ => o.set_fault_reaction(v),
                };
                if r.is_err() {
                    // Reserved and manufacturer-specific codes are not
                    // supported: 0609 0031 above the range, 0609 0032 below.
                    let lo = match index {
                        0x6007 => i16::MIN,
                        0x605D => 1,
                        _ => 0,
                    };
                    return Err(if v < lo { SdoAbort::VALUE_TOO_LOW } else { SdoAbort::VALUE_TOO_HIGH });
                }
            }
            (0x6065, 0) => {
                p.following_error_window =
                    ZeroMeansOff::effective(self.cfg.zero_means_off.following_error_window, u32v)
            }
            (0x6066, 0) => p.following_error_timeout = u as u16,
            (0x6067, 0) => p.position_window = u32v,
            (0x6068, 0) => p.position_window_time = u as u16,
            (0x606D, 0) => x.velocity_window = u as u16,
            (0x606E, 0) => x.velocity_window_time = u as u16,
            (0x606F, 0) => x.velocity_threshold = u as u16,
            (0x6070, 0) => x.velocity_threshold_time = u as u16,
            (0x6071, 0) => p.target_torque = s as i16,
            (0x6072, 0) => p.max_torque = u as u16,
            (0x6073, 0) => x.max_current = u as u16,
            (0x6075, 0) => {
                range(u as i64, 1, i64::from(u32::MAX))?;
                x.rated_current = u32v;
            }
            (0x6076, 0) => {
                range(u as i64, 1, i64::from(u32::MAX))?;
                x.rated_torque = u32v;
            }
            (0x607A, 0) => p.target_position = s as i32,
            (0x607B | 0x607D, 1 | 2) => {
                let (mut lo, mut hi) = if index == 0x607B { p.position_range } else { p.software_limits };
                if sub == 1 {
                    lo = s as i32;
                } else {
                    hi = s as i32;
                }
                if lo > hi {
                    // CiA 402-2 §6.6: min must not exceed max.
                    return Err(SdoAbort::MAX_LESS_THAN_MIN);
                }
                if index == 0x607B {
                    p.position_range = (lo, hi);
                } else {
                    p.software_limits = (lo, hi);
                }
            }
            (0x607C, 0) => p.home_offset = s as i32,
            (0x607E, 0) => {
                // Only bit 7 (position) and bit 6 (velocity) are defined.
                if u & !0xC0 != 0 {
                    return Err(SdoAbort::INVALID_VALUE);
                }
                self.factor.polarity = u as u8;
                self.retune_units()?;
            }
            (0x607F, 0) => p.max_profile_velocity = u32v,
            (0x6080, 0) => {
                p.max_motor_speed = ZeroMeansOff::effective(self.cfg.zero_means_off.max_motor_speed, u32v)
            }
            (0x6081, 0) => x.profile_velocity = u32v,
            (0x6082, 0) => x.end_velocity = u32v,
            (0x6083 | 0x6084 | 0x6085 | 0x60C5 | 0x60C6 | 0x609A, 0) => {
                // A zero ramp would never reach its target; drives whose
                // range includes 0 take it and refuse motion instead.
                let zero = self.cfg.zero_ramp;
                let lo = if zero != ZeroRamp::Refused && matches!(index, 0x6083 | 0x6084 | 0x609A) {
                    0
                } else {
                    1
                };
                range(u as i64, lo, i64::from(u32::MAX))?;
                let v = zero.effective(index, u32v);
                match index {
                    0x6083 => p.profile_acceleration = v,
                    0x6084 => p.profile_deceleration = v,
                    0x6085 => p.quick_stop_deceleration = v,
                    0x60C5 => p.max_acceleration = v,
                    0x60C6 => p.max_deceleration = v,
                    _ => p.homing_acceleration = v,
                }
            }
            (0x6086, 0) => {
                // 0 linear ramp, 1 sin² ramp, 3 jerk-limited ramp (CiA
                // 402-2 §6.7.x), as far as this drive offers them.
                let types = self.cfg.motion_profile_types & super::profile_type::IMPLEMENTED;
                if !(0..32).contains(&s) || types & (1u32 << s) == 0 {
                    return Err(SdoAbort::INVALID_VALUE);
                }
                x.profile_type = s as i16;
            }
            (0x60A4, 1 | 2) => {
                // A jerk of 0 would never build up any acceleration.
                range(u as i64, 1, i64::from(u32::MAX))?;
                let other = od.get_u32(0x60A4, 3 - sub).unwrap_or(u32v);
                let (acceleration, deceleration) = if sub == 1 { (u32v, other) } else { (other, u32v) };
                self.jerk = super::ProfileJerk::Rate { acceleration, deceleration };
            }
            (0x60D0, 1 | 2) => {
                // Touch probe source (CiA 402-2 / ETG.6010 coding, e.g.
                // Beckhoff AX8000 60D0h:01): 1 / 2 touch probe input 1 / 2,
                // 5 hardware and 6 software zero impulse of the position
                // encoder (the same index here); 3 / 4 (touch probe inputs
                // 3 / 4) and manufacturer codes are not wired.
                if !matches!(s, 1 | 2 | 5 | 6) {
                    return Err(SdoAbort::INVALID_VALUE);
                }
                self.probe.source[usize::from(sub) - 1] = s as i16;
            }
            (0x6087, 0) => x.torque_slope = u32v,
            // 6088h: only 0 (linear torque ramp) is implemented.
            (0x6088, 0) if s != 0 => return Err(SdoAbort::INVALID_VALUE),
            (0x6091 | 0x6092 | 0x6096 | 0x6097, 1 | 2) if self.cfg.fixed_factor_group => {
                // Stored set-up parameters: the units in force stay.
                range(u as i64, 1, i64::from(u32::MAX))?;
            }
            (0x6091 | 0x6092 | 0x6096 | 0x6097, 1 | 2) => {
                range(u as i64, 1, i64::from(u32::MAX))?;
                let f = &mut self.factor;
                let slot = match index {
                    0x6091 => &mut f.gear,
                    0x6092 => &mut f.feed,
                    0x6096 => &mut f.velocity_factor,
                    _ => &mut f.acceleration_factor,
                };
                let old = *slot;
                if sub == 1 {
                    slot.0 = u32v;
                } else {
                    slot.1 = u32v;
                }
                if let Err(e) = self.retune_units() {
                    let f = &mut self.factor;
                    let slot = match index {
                        0x6091 => &mut f.gear,
                        0x6092 => &mut f.feed,
                        0x6096 => &mut f.velocity_factor,
                        _ => &mut f.acceleration_factor,
                    };
                    *slot = old;
                    return Err(e);
                }
            }
            (0x6098, 0) => p.homing_method = s as i8,
            (0x6099, 1) => p.homing_speed_switch = u32v,
            (0x6099, 2) => p.homing_speed_zero = u32v,
            (0x60B0, 0) => p.position_offset = s as i32,
            (0x60B1, 0) => p.velocity_offset = s as i32,
            (0x60B2, 0) => p.torque_offset = s as i16,
            (0x60B8, 0) => {
                self.extra.probe_function = u as u16;
                self.probe.configure(u as u16);
            }
            (0x60C0, 0) => p.interpolation_sub_mode = s as i16,
            (0x60C1, 1) => p.interpolation_data = s as i32,
            (0x60C2, 1) => p.interpolation_period_value = u as u8,
            (0x60C2, 2) => {
                // 10^index s: microseconds to seconds are meaningful.
                range(s, -6, 0)?;
                p.interpolation_period_index = s as i8;
            }
            (0x60FE, 1) if self.cfg.io.keep_unmasked_command => x.outputs = u32v & x.output_mask,
            (0x60FE, 1) => {
                // Only the outputs enabled in the bit mask (sub 2) follow.
                x.outputs = u32v & x.output_mask;
                let v = x.outputs;
                if let Ok(r) = od.find(0x60FE, 1) {
                    od.set_le(r, &v.to_le_bytes());
                }
                return Ok(WriteOutcome::Handled);
            }
            (0x60FE, 2) => {
                x.output_mask = u32v;
                if self.cfg.io.keep_unmasked_command {
                    // The stored command takes effect through the new mask.
                    x.outputs = od.get_u32(0x60FE, 1).unwrap_or(0) & u32v;
                }
            }
            (0x60FF, 0) => p.target_velocity = s as i32,
            (0x6042, 0) => x.vl_target = s as i16,
            (0x6046, 1 | 2) => {
                let (mut lo, mut hi) = (x.vl_min, x.vl_max);
                if sub == 1 {
                    lo = u32v;
                } else {
                    hi = u32v;
                }
                if lo > hi {
                    return Err(SdoAbort::MAX_LESS_THAN_MIN);
                }
                (x.vl_min, x.vl_max) = (lo, hi);
            }
            (0x6048 | 0x6049, 1 | 2) => {
                let r = if index == 0x6048 { &mut x.vl_acc } else { &mut x.vl_dec };
                if sub == 1 {
                    r.0 = u32v;
                } else {
                    range(u as i64, 1, 65535)?;
                    r.1 = u as u16;
                }
            }
            _ => {}
        }
        Ok(WriteOutcome::Store)
    }

    /// Shows the handlers' present values of the objects they own (60C4h)
    /// in the dictionary (before an SDO upload, after install).
    pub(crate) fn read_handler_object(&mut self, od: &mut ObjectDictionary, index: u16, sub: u8) {
        if index != 0x60C4 {
            return;
        }
        let Some(v) = self.handlers.iter().find_map(|h| h.read_object(index, sub)) else { return };
        if let Ok(r) = od.find(index, sub) {
            let n = od.bytes(r).len().min(8);
            od.set_le(r, &v.to_le_bytes()[..n]);
        }
    }

    /// After install or a new handler: 60C4h from the ip handler, 60E3h
    /// from the hm handler's method registry.
    pub(crate) fn refresh_handler_objects(&mut self, od: &mut ObjectDictionary) {
        for sub in 1..=6 {
            self.read_handler_object(od, 0x60C4, sub);
            // The handler's state now is the power-on value (1011h restores it).
            if let Some(s) = od.get_mut(0x60C4, sub) {
                s.default = s.bytes().to_vec();
            }
        }
        // Replaced in place only: inserting a new object would move the
        // handles the node's PDO service holds (a handler added after
        // install without hm at install keeps no 60E3h).
        let present = od.object(0x60E3).is_some();
        if let Some(methods) = self.handlers.iter().find_map(|h| h.homing_methods())
            && present
        {
            od.insert(super::objects::supported_homing_methods(&methods));
            self.refs = super::objects::Refs::resolve(od);
        }
    }

    /// Re-derives the unit conversions after a factor group write; refuses
    /// (0609 0030) a combination that overflows the exact arithmetic.
    fn retune_units(&mut self) -> Result<(), SdoAbort> {
        let u = Units::new(&self.factor).ok_or(SdoAbort::INVALID_VALUE)?;
        // Keep the position where it is: the demand is in user units.
        let inc = self.units.pos_to_inc_f(self.dem.pos);
        // The reference shift's fraction, over the new denominator.
        let frac = self.units.frac_to_inc_f(self.inc_frac) * u.position_ratio().den as f64;
        self.inc_frac = (libm::floor(frac) as i128).clamp(0, u.position_ratio().den as i128 - 1);
        self.units = u;
        self.dem.pos = self.units.inc_to_pos_f(inc);
        self.dem.vel = 0.0;
        self.pp.reset(self.dem.pos);
        Ok(())
    }

    /// Reads every parameter from the dictionary (after install, and after
    /// the node restored or loaded values behind the hooks).
    pub(crate) fn reload(&mut self, od: &mut ObjectDictionary) {
        let w = &self.withdrawn;
        let i = |idx: u16, sub: u8| source(od, w, idx).get_i64(idx, sub).unwrap_or(0);
        let u = |idx: u16, sub: u8| source(od, w, idx).get_u64(idx, sub).unwrap_or(0);
        let p = &mut self.params;
        p.target_position = i(0x607A, 0) as i32;
        p.target_velocity = i(0x60FF, 0) as i32;
        p.target_torque = i(0x6071, 0) as i16;
        p.position_offset = i(0x60B0, 0) as i32;
        p.velocity_offset = i(0x60B1, 0) as i32;
        p.torque_offset = i(0x60B2, 0) as i16;
        p.homing_method = i(0x6098, 0) as i8;
        p.homing_speed_switch = u(0x6099, 1) as u32;
        p.homing_speed_zero = u(0x6099, 2) as u32;
        let ramp = self.cfg.zero_ramp;
        p.homing_acceleration = ramp.effective(0x609A, u(0x609A, 0) as u32);
        p.home_offset = i(0x607C, 0) as i32;
        p.homing_return_to_home = self.cfg.homing_return_to_home;
        p.interpolation_sub_mode = i(0x60C0, 0) as i16;
        p.interpolation_data = i(0x60C1, 1) as i32;
        p.interpolation_period_value = u(0x60C2, 1) as u8;
        p.interpolation_period_index = i(0x60C2, 2) as i8;
        let zero = self.cfg.zero_means_off;
        p.following_error_window = ZeroMeansOff::effective(zero.following_error_window, u(0x6065, 0) as u32);
        p.following_error_timeout = u(0x6066, 0) as u16;
        p.position_window = u(0x6067, 0) as u32;
        p.position_window_time = u(0x6068, 0) as u16;
        p.max_profile_velocity = u(0x607F, 0) as u32;
        p.max_motor_speed = ZeroMeansOff::effective(zero.max_motor_speed, u(0x6080, 0) as u32);
        p.profile_acceleration = ramp.effective(0x6083, u(0x6083, 0) as u32);
        p.profile_deceleration = ramp.effective(0x6084, u(0x6084, 0) as u32);
        p.quick_stop_deceleration = u(0x6085, 0) as u32;
        p.max_acceleration = u(0x60C5, 0) as u32;
        p.max_deceleration = u(0x60C6, 0) as u32;
        p.software_limits = (i(0x607D, 1) as i32, i(0x607D, 2) as i32);
        p.position_range = (i(0x607B, 1) as i32, i(0x607B, 2) as i32);
        p.max_torque = u(0x6072, 0) as u16;
        let x = &mut self.extra;
        x.profile_velocity = u(0x6081, 0) as u32;
        x.end_velocity = u(0x6082, 0) as u32;
        x.profile_type = i(0x6086, 0) as i16;
        x.torque_slope = u(0x6087, 0) as u32;
        x.velocity_window = u(0x606D, 0) as u16;
        x.velocity_window_time = u(0x606E, 0) as u16;
        x.velocity_threshold = u(0x606F, 0) as u16;
        x.velocity_threshold_time = u(0x6070, 0) as u16;
        x.max_current = u(0x6073, 0) as u16;
        x.rated_current = (u(0x6075, 0) as u32).max(1);
        x.rated_torque = (u(0x6076, 0) as u32).max(1);
        x.probe_function = u(0x60B8, 0) as u16;
        if self.cfg.io.probe_source_object {
            for k in 0..2 {
                let v = i(0x60D0, k as u8 + 1) as i16;
                self.probe.source[k] = if matches!(v, 1 | 2 | 5 | 6) { v } else { 0 };
            }
        }
        // 60A4h (stored or restored values) sets the jerk rates; a jerk
        // time (configured or set by the personality) stays in force until
        // 60A4h itself is written.
        let jerk = source(od, w, 0x60A4);
        if self.cfg.profile_jerk_object
            && matches!(self.jerk, super::ProfileJerk::Rate { .. })
            && let (Some(a), Some(d)) = (jerk.get_u32(0x60A4, 1), jerk.get_u32(0x60A4, 2))
        {
            self.jerk = super::ProfileJerk::Rate { acceleration: a, deceleration: d };
        }
        x.output_mask = u(0x60FE, 2) as u32;
        x.outputs = u(0x60FE, 1) as u32 & x.output_mask;
        x.vl_target = i(0x6042, 0) as i16;
        x.vl_min = u(0x6046, 1) as u32;
        x.vl_max = u(0x6046, 2) as u32;
        x.vl_acc = (u(0x6048, 1) as u32, (u(0x6048, 2) as u16).max(1));
        x.vl_dec = (u(0x6049, 1) as u32, (u(0x6049, 2) as u16).max(1));
        self.probe.configure(x.probe_function);
        let f = &mut self.factor;
        if !self.cfg.fixed_factor_group {
            f.gear = pair(source(od, w, 0x6091), 0x6091);
            f.feed = pair(source(od, w, 0x6092), 0x6092);
            f.velocity_factor = pair(source(od, w, 0x6096), 0x6096);
            f.acceleration_factor = pair(source(od, w, 0x6097), 0x6097);
        }
        f.polarity = u(0x607E, 0) as u8;
        if let Some(units) = Units::new(&self.factor) {
            self.units = units;
        }
        let o = self.sm.options_mut();
        let opt = |idx: u16| i(idx, 0) as i16;
        // Stored values passed the hooks once; a failure keeps the old code.
        let _ = o.set_quick_stop(opt(0x605A));
        let _ = o.set_shutdown(opt(0x605B));
        let _ = o.set_disable_operation(opt(0x605C));
        let _ = o.set_halt(opt(0x605D));
        let _ = o.set_fault_reaction(opt(0x605E));
        let _ = o.set_abort_connection(opt(0x6007));
        let m = i(0x6060, 0) as i8;
        if op::supported_bit(m) & self.modes != 0 {
            self.request_mode(od, m);
        }
        self.refs = super::objects::Refs::resolve(od);
    }
}
