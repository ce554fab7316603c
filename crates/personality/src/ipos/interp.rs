//! The iPOS interpolated position mode (§9): CiA 402 linear or the legacy
//! PT/PVT records packed in 60C1h:01/02, with 2072h–207Ah.

use super::*;

/// EMCY FF01h "generic interpolated position mode error (PVT / PT
/// error)": a 2072h status bit changed or a point was refused (§3.1.3,
/// §9.2.3, §9.2.8); 2072h in bytes 3–4.
pub const EMCY_IP_STATUS: u16 = 0xFF01;

/// Largest ip buffer length 2073h: "The maximum is 000Fh" (§9.4 step 13,
/// §9.5 step 13).
pub const IP_BUFFER_MAX: u16 = 15;

/// 2073h default buffer length (§9.2.4).
pub const IP_BUFFER_DEFAULT: u16 = 7;

/// 2072h bits (Table 9.2.1).
pub mod ip_status {
    /// Buffer empty.
    pub const EMPTY: u16 = 1 << 15;
    /// Buffer low (points ≤ the 2074h low limit).
    pub const LOW: u16 = 1 << 14;
    /// Buffer full.
    pub const FULL: u16 = 1 << 13;
    /// Integrity counter error.
    pub const INTEGRITY: u16 = 1 << 12;
    /// PVT: quick stop after the buffer ran empty with a last velocity ≠ 0.
    pub const PVT_QUICK_STOP: u16 = 1 << 11;
    /// The status bits whose change sends EMCY FF01h (bits 0–6 are the
    /// counter, 7–10 reserved).
    pub const CHANGE_MASK: u16 = 0xF800;
}

/// One legacy interpolation point decoded from 60C1h:01 (X1) and 60C1h:02
/// (X2) (§9.2.2.2, §9.2.2.3, Figures 9.2.2/9.2.3 as the examples pack them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LegacyPoint {
    /// Position \[increments\] (PT: 32 bits; PVT: 24 bits, signed).
    pub position: i32,
    /// PVT end velocity \[increments/sample\] in 16.8 fixed point (24 bits,
    /// signed); 0 for PT.
    pub velocity_16_8: i32,
    /// Segment time \[samples\] (PT: 16 bits; PVT: 9 bits).
    pub time: u16,
    /// Integrity counter (7 bits).
    pub counter: u8,
}

impl LegacyPoint {
    /// PT: X1 = position; X2 = time (bits 0–15), 0 (16–23), counter in
    /// byte 3 bits 1–7 (§9.2.2.2 remarks; E26: X2 = 020003E8h = IC 1,
    /// 1000 samples).
    pub fn pt(x1: u32, x2: u32) -> Self {
        LegacyPoint { position: x1 as i32, velocity_16_8: 0, time: x2 as u16, counter: (x2 >> 25) as u8 }
    }

    /// PVT: X1 = position bits 16–23 (byte 3) | velocity bits 0–7 (byte 2) |
    /// position bits 0–15; X2 = counter (byte 3 bits 1–7) | time bit 8
    /// (byte 3 bit 0) | time bits 0–7 (byte 2) | velocity bits 8–23
    /// (§9.2.2.3; E27 P3: X1 = 00A80BA6h, X2 = 07860006h = 2982 counts,
    /// 6.66 IU, 390 samples, IC 3).
    pub fn pvt(x1: u32, x2: u32) -> Self {
        let pos24 = ((x1 >> 24) << 16) | (x1 & 0xFFFF);
        let vel24 = ((x2 & 0xFFFF) << 8) | ((x1 >> 16) & 0xFF);
        let sext24 = |v: u32| ((v << 8) as i32) >> 8;
        LegacyPoint {
            position: sext24(pos24),
            velocity_16_8: sext24(vel24),
            time: ((x2 >> 16) & 0x1FF) as u16,
            counter: (x2 >> 25) as u8,
        }
    }
}

/// The legacy (PT/PVT) interpolation state of the iPOS (§9.2).
#[derive(Debug, Clone, Default)]
pub(super) struct Legacy {
    /// The next integrity counter expected (2074h bits 0–6 set it).
    pub(super) counter: u8,
    /// 2074h bit 14: integrity checking off.
    pub(super) unchecked: bool,
    /// 2074h bit 12: absolute motion starts from the position demand
    /// instead of 2079h.
    pub(super) from_demand: bool,
    /// Buffer low limit (2074h bits 8–11 with bit 7).
    pub(super) low: u16,
    /// Integrity counter error in force.
    pub(super) integrity_error: bool,
    /// The PVT quick stop after an empty buffer happened.
    pub(super) quick_stopped: bool,
    /// Where the drive's absolute positions stand relative to the
    /// master's (absolute) and the last target (relative): set at the
    /// first point after a buffer reset.
    pub(super) origin: Option<(f64, f64)>,
    /// End velocity of the last point loaded \[16.8 IU\].
    pub(super) last_velocity: i32,
    /// 2072h as last published (`None` before the first publication).
    pub(super) shown: Option<u16>,
}

/// 208Eh bit 8: 1 = CiA 402 linear interpolation, 0 = legacy PT/PVT
/// (§4.9.11, §9.2.1; default 0100h).
pub const AUX_LINEAR_IP: u16 = 1 << 8;

impl Ipos {
    /// 60C0h (iPOS codes) and 208Eh bit 8 → the drive's ip sub-mode:
    /// 208Eh bit 8 = 1 with 60C0h = 0 is the CiA 402 linear interpolation,
    /// bit 8 = 0 the legacy PT (0) and PVT (−1) (§9.2.1). PVT with bit 8 =
    /// 1 is not described; it is run as PVT.
    pub fn drive_sub_mode(ipos: i16, aux: u16) -> Option<i16> {
        match (ipos, aux & AUX_LINEAR_IP != 0) {
            (0, true) => Some(0),
            (0, false) => Some(-1),
            (-1, _) => Some(-2),
            _ => None,
        }
    }

    pub(super) fn legacy_mode(od: &ObjectDictionary) -> Option<bool> {
        Self::legacy_of(od.get_u32(0x208E, 0), od.get_i64(0x60C0, 0))
    }

    /// [`Ipos::legacy_mode`] from the values of 208Eh and 60C0h.
    pub(super) fn legacy_of(aux: Option<u32>, sub_mode: Option<i64>) -> Option<bool> {
        let aux = aux.unwrap_or(u32::from(AUX_LINEAR_IP)) as u16;
        match Self::drive_sub_mode(sub_mode.unwrap_or(0) as i16, aux)? {
            -1 => Some(false),
            -2 => Some(true),
            _ => None,
        }
    }

    /// Tells the drive the sub-mode the dictionary's 60C0h/208Eh select.
    pub(super) fn sync_sub_mode(
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        ipos: i16,
        aux: u16,
    ) -> Result<(), SdoAbort> {
        let code = Self::drive_sub_mode(ipos, aux).ok_or(SdoAbort::INVALID_VALUE)?;
        cx.drive.on_write(od, 0x60C0, 0, &code.to_le_bytes()).map(|_| ())
    }

    /// ip is active (mode 7, Operation enabled, controlword bit 4).
    pub(super) fn ip_active(cx: &Context<'_>) -> bool {
        let v = cx.drive.view();
        v.mode == 7 && v.state == State::OperationEnabled && v.controlword & 0x10 != 0
    }

    /// Clears the drive's ip buffer and restarts the point reference.
    pub(super) fn clear_buffer(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let _ = cx.drive.on_write(od, 0x60C4, 6, &[0]);
        let _ = cx.drive.on_write(od, 0x60C4, 6, &[1]);
        self.legacy.origin = None;
        self.legacy.quick_stopped = false;
    }

    /// 2072h from the buffer and the counter state; EMCY FF01h when a
    /// status bit changed (or `force`: a refused point).
    pub(super) fn publish_ip_status(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, force: bool) {
        let l = &self.legacy;
        let n = self.ip.len() as u16;
        let mut v = u16::from(l.counter & 0x7F);
        if n == 0 {
            v |= ip_status::EMPTY;
        }
        if n <= l.low {
            v |= ip_status::LOW;
        }
        if n >= self.ip.size() as u16 {
            v |= ip_status::FULL;
        }
        if l.integrity_error {
            v |= ip_status::INTEGRITY;
        }
        if l.quick_stopped {
            v |= ip_status::PVT_QUICK_STOP;
        }
        if let Some(r) = self.refs.fresh(od).ip_status {
            od.set_le(r, &v.to_le_bytes());
        }
        let changed = self.legacy.shown.is_some_and(|s| (s ^ v) & ip_status::CHANGE_MASK != 0);
        self.legacy.shown = Some(v);
        if changed || force {
            let [a, b] = v.to_le_bytes();
            let reg = od.get_u32(0x1001, 0).unwrap_or(0) as u8;
            cx.request(EmcyFrame { code: EMCY_IP_STATUS, register: Some(reg), bytes: [a, b, 0, 0, 0] }.raw());
        }
    }

    /// A legacy point completed by its X2 write (§9.2.8): integrity
    /// check, then the point goes into the drive's buffer in drive
    /// positions.
    pub(super) fn load_point(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        pvt: bool,
        x2: u32,
    ) -> Result<(), SdoAbort> {
        let x1 = od.get_u32(0x60C1, 1).unwrap_or(0);
        let mut p = if pvt { LegacyPoint::pvt(x1, x2) } else { LegacyPoint::pt(x1, x2) };
        let l = &mut self.legacy;
        if !l.unchecked && p.counter != l.counter {
            // The same number again: ignored with an EMCY; lower or more
            // than one ahead: ignored, integrity counter error (§9.2.8).
            if p.counter != l.counter.wrapping_sub(1) & 0x7F {
                l.integrity_error = true;
            }
            self.publish_ip_status(cx, od, true);
            return Ok(());
        }
        l.integrity_error = false;
        l.counter = (p.counter + 1) & 0x7F;
        // 207Ah: a fixed segment time replaces the point's (§9.2.7).
        let fixed = od.get_u32(0x207A, 0).unwrap_or(0) as u16;
        if fixed != 0 {
            p.time = fixed;
        }
        let relative = cx.drive.view().controlword & 0x40 != 0;
        let demand = cx.drive.demand_position();
        let (offset, last) = *l.origin.get_or_insert_with(|| {
            let initial = if l.from_demand { demand } else { od.get_i64(0x2079, 0).unwrap_or(0) as f64 };
            (demand - initial, demand)
        });
        let target = if relative { last + f64::from(p.position) } else { f64::from(p.position) + offset };
        l.origin = Some((offset, target));
        l.last_velocity = p.velocity_16_8;
        // The drive's record: time [ms] = samples × 1 ms, velocity in
        // 16.16 IU, then the position commits it.
        let time_ms = (f64::from(p.time) * SLOW_LOOP_S * 1000.0) as i64;
        cx.drive.on_write(od, 0x60C1, 3, &time_ms.to_le_bytes())?;
        cx.drive.on_write(od, 0x60C1, 2, &(i64::from(p.velocity_16_8) << 8).to_le_bytes())?;
        cx.drive.on_write(od, 0x60C1, 1, &(target.round() as i64).to_le_bytes())?;
        self.publish_ip_status(cx, od, false);
        Ok(())
    }
}
