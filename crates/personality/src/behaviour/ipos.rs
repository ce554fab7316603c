//! Technosoft iPOS behaviour (*iPOS CoE Programming* P091.064.UM.0524,
//! seed002): the CiA 402 over EtherCAT object dictionary, served as a
//! CANopen personality (SDOs on 600h/580h + node-ID, PDOs with CiA 301
//! COB-IDs: the EtherCAT mailbox and state machine have no CAN equivalent).
//!
//! What a master sees that differs from a plain CiA 301/402 device:
//!
//! * mode −1 electronic gearing (§11) follows the online master position
//!   201Eh × 2013h on the drive's csp; −2 electronic camming (§12) is
//!   accepted and shown in 6061h and holds the position (the cam table's
//!   memory format is not in the manual);
//! * ip (7): CiA 402 linear interpolation with 208Eh bit 8 = 1, the legacy
//!   PT / PVT sub-modes 60C0h = 0 / −1 with bit 8 = 0: packed 60C1h:01/02
//!   points, integrity counter, 2072h–207Ah, EMCY FF01h (§9); csp, csv, cst;
//! * 6071h/6074h/6077h/6078h are ‰ of 6075h, the motor rated *current*
//!   (§8.2.1): the drive's torque reference is kept at kₜ × 6075h;
//! * 606Ch is the speed per 1 ms slow-loop sample (§10);
//! * limit switches send EMCY 5443h / 5442h and 0000h on release (§4.3.1);
//! * a PDO mapping of more than 64 bits is not taken: "When the drive will
//!   be re-initialized with the new settings, it will send an emergency
//!   message that ignored the PDO mapping" (§1.6.3.1). On CAN the
//!   re-initialisation is the write of mapping sub 0 that activates it: the
//!   write is confirmed (the master's tool sees success, as in TwinCAT),
//!   EMCY 8220h "PDO length exceeded" is sent and the mapping keeps its
//!   previous count. 8210h "PDO not processed due to length error" is
//!   what a received RPDO shorter than its mapping raises (CiA 301; the
//!   node does it). The manual gives no finer rule for the two codes;
//! * the error register uses only bits 0 and 4 (§3.1.3 / 1001h);
//! * no 1010h/1011h: 2076h saves, 2080h resets (§4.9.6).

use crate::Profile;
use crate::build::{Action, Behaviour, Context, EmcyFrame, Verdict};
use drivebus_cia402::drive::{DriveConfig, FactorGroup};
use drivebus_cia402::homing::{HomingContext, HomingMethod, MethodStep};
use drivebus_cia402::interp::{IpMode, IpMonitor};
use drivebus_cia402::model::EventKind;
use drivebus_cia402::state_machine::State;
use drivebus_node::{NodeConfig, NodeEvent};
use drivebus_od::{ObjectDictionary, ObjectHooks, SdoAbort};

/// EMCY 8220h "PDO length exceeded" (Table 3.1.3).
pub const EMCY_PDO_LENGTH_EXCEEDED: u16 = 0x8220;
/// EMCY 8210h "PDO not processed due to length error" (Table 3.1.3).
pub const EMCY_PDO_LENGTH_ERROR: u16 = 0x8210;
/// Bits of data one PDO carries at most (§1.6.3.1).
pub const MAX_PDO_BITS: u32 = 64;

/// Encoder increments per motor revolution of the emulated axis: 608Fh:1
/// default 2000 (§5.2.3), the "2000 counts per revolution" of the motion
/// examples (§6.4, §7.3).
pub const COUNTS_PER_REV: u32 = 2000;

/// The slow loop (position/speed control) sample \[s\]: 1 ms (§1.3, §6.4
/// "1ms sample rate for position/speed control").
pub const SLOW_LOOP_S: f64 = 1e-3;

/// Time constant of the speed measurement filter \[s\]: one slow-loop
/// sample (§10: 606Ch is increments per 1 ms sample; the emulation's
/// encoder is differentiated every 0.125 ms control period). A first-order
/// lag, so one 606Ch reading is within about one increment per sample of
/// the speed; it filters the speed loop's feedback too.
pub const SPEED_FILTER_S: f64 = 1e-3;

/// Sum of the lengths (bits) of mapping entries 1..=n of a mapping object.
pub fn mapped_bits(od: &ObjectDictionary, map: u16, n: u8) -> u32 {
    (1..=n).map(|s| od.get_u32(map, s).unwrap_or(0) & 0xFF).sum()
}

/// The 1001h value the iPOS sends with a code: bit 0 always, bit 4 for
/// communication errors (§3.1.3: only bits 0 and 4 are used).
pub fn error_register(code: u16) -> u8 {
    match code {
        0x0000..=0x00FF => 0,
        0x1000 | 0x7500 | 0x8100..=0x82FF => 0x11,
        _ => 0x01,
    }
}

/// The iPOS homing methods on a mechanical limit (§6): −1 / −2 run into the
/// negative / positive limit, then reverse at 6099h:2 to the first index
/// pulse; −3 / −4 run into the limit, then travel |607Ch| back, and that
/// point reports 607Ch (so the limit is 0). The limit is detected when the
/// axis hits its end stop or stalls (the manual's current threshold
/// 207Bh/207Ch, or the control error of an open-loop stepper, is what such
/// a contact produces on the real drive).
#[derive(Debug, Clone, Copy)]
pub struct MechanicalLimitHoming {
    code: i8,
    /// Where the limit was met (position units), once met.
    limit: Option<f64>,
}

impl MechanicalLimitHoming {
    /// Method −1..−4; `None` otherwise.
    pub fn new(code: i8) -> Option<Self> {
        (-4..=-1).contains(&code).then_some(MechanicalLimitHoming { code, limit: None })
    }

    fn towards_positive(&self) -> bool {
        matches!(self.code, -2 | -4)
    }

    fn with_index(&self) -> bool {
        matches!(self.code, -1 | -2)
    }
}

impl HomingMethod for MechanicalLimitHoming {
    fn code(&self) -> i8 {
        self.code
    }

    fn begin(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        self.limit = None;
        let v = ctx.config.switch_speed;
        MethodStep::Move(if self.towards_positive() { v } else { -v })
    }

    fn update(&mut self, ctx: &HomingContext<'_>) -> MethodStep {
        let away = if self.towards_positive() { -1.0 } else { 1.0 };
        let slow = ctx.config.zero_speed * away;
        match self.limit {
            None => {
                if let Some(e) =
                    ctx.events.iter().find(|e| matches!(e.kind, EventKind::HardStop | EventKind::Stall))
                {
                    self.limit = Some(e.position);
                    return MethodStep::Move(slow);
                }
                let v = ctx.config.switch_speed;
                MethodStep::Move(if self.towards_positive() { v } else { -v })
            }
            Some(at) => {
                if self.with_index() {
                    if let Some(e) = ctx.events.iter().find(|e| e.kind == EventKind::Index) {
                        return MethodStep::Found(e.position);
                    }
                } else if (ctx.position - at).abs() >= ctx.config.home_offset.abs() {
                    return MethodStep::Found(ctx.position);
                }
                MethodStep::Move(slow)
            }
        }
    }
}

/// EMCY FF01h "generic interpolated position mode error (PVT / PT
/// error)": a 2072h status bit changed or a point was refused (§3.1.3,
/// §9.2.3, §9.2.8); 2072h in bytes 3–4.
pub const EMCY_IP_STATUS: u16 = 0xFF01;
/// EMCY 5443h "positive limit switch active" (§4.3.1, Table 3.1.3).
pub const EMCY_LSP: u16 = 0x5443;
/// EMCY 5442h "negative limit switch active" (§4.3.1, Table 3.1.3).
pub const EMCY_LSN: u16 = 0x5442;
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
struct Legacy {
    /// The next integrity counter expected (2074h bits 0–6 set it).
    counter: u8,
    /// 2074h bit 14: integrity checking off.
    unchecked: bool,
    /// 2074h bit 12: absolute motion starts from the position demand
    /// instead of 2079h.
    from_demand: bool,
    /// Buffer low limit (2074h bits 8–11 with bit 7).
    low: u16,
    /// Integrity counter error in force.
    integrity_error: bool,
    /// The PVT quick stop after an empty buffer happened.
    quick_stopped: bool,
    /// Where the drive's absolute positions stand relative to the
    /// master's (absolute) and the last target (relative): set at the
    /// first point after a buffer reset.
    origin: Option<(f64, f64)>,
    /// End velocity of the last point loaded \[16.8 IU\].
    last_velocity: i32,
    /// 2072h as last published (`None` before the first publication).
    shown: Option<u16>,
}

/// Electronic gearing slave state (§11).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Gear {
    /// Ratio in force: computed when 2013h:02 is written (§11.2.3).
    ratio: f64,
    /// Controlword bit 4 as last seen in gearing (the 0 → 1 edge starts).
    bit4: bool,
    /// Following the master (after the 0 → 1 edge of bit 4).
    engaged: bool,
    /// Master position the last increment was taken from.
    master: i64,
    /// Slave position reference \[increments, fractional\].
    reference: f64,
    /// In the gearing mode at the last step.
    active: bool,
}

impl Default for Gear {
    fn default() -> Self {
        Gear { ratio: 1.0, bit4: false, engaged: false, master: 0, reference: 0.0, active: false }
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

/// The iPOS quirks around the CiA 402 drive.
#[derive(Debug, Clone, Default)]
pub struct Ipos {
    /// The ip buffer fill, shared with the drive's ip handler.
    ip: IpMonitor,
    legacy: Legacy,
    gear: Gear,
    /// The count of a master encoder wired to the second encoder input
    /// (simulated: set by [`Ipos::set_second_encoder`]), and the count last
    /// taken by gearing.
    second_encoder: Option<i64>,
    second_taken: Option<i64>,
    /// Limit switches as last seen (LSN, LSP).
    limits: (bool, bool),
    /// Power-on work of the first step done.
    started: bool,
}

impl Ipos {
    /// The iPOS.
    pub fn new() -> Self {
        Ipos { legacy: Legacy { counter: 1, ..Legacy::default() }, ..Ipos::default() }
    }

    /// The second encoder input (§11.1, §11.3: "the encoder from the master
    /// drive … connected … to the second encoder input"): the emulated
    /// drive has no such input, so its count is set here (a test, a
    /// simulated master). With 201Dh = 3 gearing follows it, taken at the
    /// next step.
    pub fn set_second_encoder(&mut self, count: i64) {
        self.second_encoder = Some(count);
    }

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

    fn legacy_mode(od: &ObjectDictionary) -> Option<bool> {
        let aux = od.get_u32(0x208E, 0).unwrap_or(u32::from(AUX_LINEAR_IP)) as u16;
        match Self::drive_sub_mode(od.get_i64(0x60C0, 0).unwrap_or(0) as i16, aux)? {
            -1 => Some(false),
            -2 => Some(true),
            _ => None,
        }
    }

    /// Tells the drive the sub-mode the dictionary's 60C0h/208Eh select.
    fn sync_sub_mode(
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        ipos: i16,
        aux: u16,
    ) -> Result<(), SdoAbort> {
        let code = Self::drive_sub_mode(ipos, aux).ok_or(SdoAbort::INVALID_VALUE)?;
        cx.drive.on_write(od, 0x60C0, 0, &code.to_le_bytes()).map(|_| ())
    }

    /// ip is active (mode 7, Operation enabled, controlword bit 4).
    fn ip_active(cx: &Context<'_>) -> bool {
        let v = cx.drive.view();
        v.mode == 7 && v.state == State::OperationEnabled && v.controlword & 0x10 != 0
    }

    /// Clears the drive's ip buffer and restarts the point reference.
    fn clear_buffer(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let _ = cx.drive.on_write(od, 0x60C4, 6, &[0]);
        let _ = cx.drive.on_write(od, 0x60C4, 6, &[1]);
        self.legacy.origin = None;
        self.legacy.quick_stopped = false;
    }

    /// 2072h from the buffer and the counter state; EMCY FF01h when a
    /// status bit changed (or `force`: a refused point).
    fn publish_ip_status(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, force: bool) {
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
        if let Ok(r) = od.find(0x2072, 0) {
            od.set_le(r, &v.to_le_bytes());
        }
        let changed = self.legacy.shown.is_some_and(|s| (s ^ v) & ip_status::CHANGE_MASK != 0);
        self.legacy.shown = Some(v);
        if changed || force {
            let [a, b] = v.to_le_bytes();
            let reg = od.get_u32(0x1001, 0).unwrap_or(0) as u8;
            cx.actions.push(Action::RawEmcy(EmcyFrame {
                code: EMCY_IP_STATUS,
                register: Some(reg),
                bytes: [a, b, 0, 0, 0],
            }));
        }
    }

    /// A legacy point completed by its X2 write (§9.2.8): integrity
    /// check, then the point goes into the drive's buffer in drive
    /// positions.
    fn load_point(
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

    /// Per step: limit switch EMCYs (§4.3.1), the PVT stop on an empty
    /// buffer and 2072h (§9.2.3).
    fn watch(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let view = cx.drive.view();
        let lsn = view.digital_inputs & 1 != 0;
        let lsp = view.digital_inputs & 2 != 0;
        // §4.3.1: 60B8h bit 6 = 1 disables the limit switch EMCYs.
        let silent = od.get_u32(0x60B8, 0).unwrap_or(0) & 0x40 != 0;
        for (now, was, code, bit) in [(lsp, self.limits.1, EMCY_LSP, 6u16), (lsn, self.limits.0, EMCY_LSN, 7)]
        {
            if now != was {
                let mer = od.get_u32(0x2000, 0).unwrap_or(0) as u16;
                let mer = if now { mer | 1 << bit } else { mer & !(1 << bit) };
                if let Ok(r) = od.find(0x2000, 0) {
                    od.set_le(r, &mer.to_le_bytes());
                }
                if now && !silent {
                    cx.actions.push(Action::Raise(EmcyFrame {
                        code,
                        register: Some(error_register(code)),
                        bytes: [0; 5],
                    }));
                } else if !now {
                    // §4.3.1: "the emergency error code 0x0000 will be sent".
                    cx.actions.push(Action::Clear(code));
                }
            }
        }
        self.limits = (lsn, lsp);
        // §9.2.3 bit 11: PVT with the buffer run empty after a point whose
        // velocity is not 0: quick stop.
        if Self::legacy_mode(od) == Some(true)
            && Self::ip_active(cx)
            && self.ip.underflow()
            && self.legacy.last_velocity != 0
            && !self.legacy.quick_stopped
        {
            self.legacy.quick_stopped = true;
            let cw = (view.controlword & !0x0004) | 0x0002;
            let _ = cx.drive.on_write(od, 0x6040, 0, &cw.to_le_bytes());
        }
        self.publish_ip_status(cx, od, false);
    }

    /// Gearing (§11.1): at each master position update the slave
    /// reference moves by the master increment × the gear ratio; the drive
    /// (csp stand-in) takes it at the next SYNC.
    fn gear_update(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, master: i64) {
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
        if self.gear.active && self.gear.engaged {
            self.gear.reference += d as f64 * self.gear.ratio;
            Self::gear_target(cx, od, self.gear.reference);
        }
    }

    fn gear_target(cx: &mut Context<'_>, od: &mut ObjectDictionary, reference: f64) {
        let t = reference.round().clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
        let _ = cx.drive.on_write(od, 0x607A, 0, &t.to_le_bytes());
    }

    /// Per step in mode −1: entry holds the position; the 0 → 1 edge of
    /// controlword bit 4 engages (§11.1.1); statusword bit 10 is 0 while
    /// not halted (Table 11.1.2).
    fn gear_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let view = cx.drive.view();
        let active = od.get_i64(0x6061, 0) == Some(-1) && view.state == State::OperationEnabled;
        let bit4 = view.controlword & 0x10 != 0;
        if active && !self.gear.active {
            // The stand-in holds where the axis is until engaged.
            self.gear.engaged = false;
            self.gear.bit4 = bit4;
            self.gear.reference = cx.drive.demand_position();
            Self::gear_target(cx, od, self.gear.reference);
        }
        self.gear.active = active;
        if !active {
            return;
        }
        if bit4 && !self.gear.bit4 && !self.gear.engaged {
            // "The slave executes a relative move, which starts from its
            // actual position" (§11.1): from the reference it holds.
            self.gear.engaged = true;
        }
        self.gear.bit4 = bit4;
        if view.controlword & 0x100 == 0
            && let Ok(r) = od.find(0x6041, 0)
        {
            let sw = od.get_u32(0x6041, 0).unwrap_or(0) as u16 & !(1 << 10) & !(1 << 12);
            od.set_le(r, &sw.to_le_bytes());
        }
    }

    /// kₜ × 6075h: the torque the drive's ‰ refer to (§8.2.1: 6071h, 6072h,
    /// 6074h, 6077h are ‰ of the motor rated current 6075h; the drive
    /// computes with at least 1 mA).
    fn sync_torque_reference(cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let ma = od.get_u32(0x6075, 0).unwrap_or(0).max(1);
        let kt = cx.drive.config().params.motor.kt;
        let mnm = (kt * f64::from(ma)).round().clamp(1.0, f64::from(u32::MAX)) as u32;
        crate::build::set_default(od, 0x6076, 0, &drivebus_od::Value::U32(mnm));
        let _ = cx.drive.on_write(od, 0x6076, 0, &mnm.to_le_bytes());
    }
}

/// 208Eh bit 8: 1 = CiA 402 linear interpolation, 0 = legacy PT/PVT
/// (§4.9.11, §9.2.1; default 0100h).
pub const AUX_LINEAR_IP: u16 = 1 << 8;

impl Behaviour for Ipos {
    fn profile(&self) -> Profile {
        Profile::Ipos
    }

    fn adjust_node_config(&self, cfg: &mut NodeConfig) {
        // §4.9.6 / inventory B.5: 1010h/1011h are not documented; 2076h saves.
        cfg.store_restore = false;
        cfg.heartbeat_consumers = 0;
        cfg.error_classes = 0;
        // CAN-only objects the manual does not have (no CoE meaning).
        cfg.sync_window = false;
        cfg.sync_counter = false;
        cfg.sdo_server_param = false;
    }

    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        cfg.params.encoder.counts_per_rev = COUNTS_PER_REV;
        // §10 / §1.3: the iPOS speed (606Ch) is increments per slow-loop
        // sample (1 ms): the encoder difference over one sample, not one
        // control period. A first-order lag of one sample on the measured
        // speed gives that resolution (one count per sample = 1 IU).
        cfg.params.control.velocity_filter = SPEED_FILTER_S;
        // Internal units (§1.3, §5): position = increments; velocity =
        // increments per slow-loop sample (1 ms) in 16.16 fixed point;
        // acceleration = increments per sample² in 16.16. Factors in
        // position units/s per velocity unit: 1000/65536, 10^6/65536.
        cfg.factor = FactorGroup {
            velocity_factor: (125, 8192),
            acceleration_factor: (15_625, 1024),
            ..FactorGroup::increments(COUNTS_PER_REV)
        };
        // §5.2.2: the conversion is the position factor 6093h (set by
        // EasyMotion Studio); 6091h/6092h/6096h/6097h are stored set-up
        // parameters, default 1/1 (§5.2.5, §5.2.8, §5.2.11).
        cfg.fixed_factor_group = true;
        cfg.initial_mode = 0;
        let p = &mut cfg.profile;
        // 133 IU = 133 increments per 1 ms sample = 4000 rpm at 2000
        // increments per revolution.
        p.max_profile_velocity = 133 << 16;
        p.profile_velocity = 33 << 16;
        p.profile_acceleration = 1 << 16;
        p.profile_deceleration = 1 << 16;
        p.quick_stop_deceleration = 4 << 16;
        p.following_error_window = COUNTS_PER_REV;
        p.position_window = 10;
        p.position_window_time = 0;
        p.velocity_window = 0xFFFF;
        p.velocity_threshold = 0xFFFF;
        // 6087h default 0 (§8.2.3). The manual does not say what 0 does:
        // the drive refuses torque motion (tq demand 0) until the master
        // sets a slope, as the §8.3 example does with 6075h and 6087h.
        p.torque_slope = 0;
        // 6080h default 0 = no speed limit (§15.2.3).
        cfg.zero_means_off.max_motor_speed = true;
        // 60A8h default 00B50100h (IU = increments), 60A9h/60AAh 0 (§5.2.1,
        // §5.2.6, §5.2.9: informative only).
        cfg.si_units = [0x00B5_0100, 0, 0, 0];
        // 60FEh:2 bit mask default 0 (§4.5.3); sub 1 keeps the command, the
        // outputs change when the mask is written.
        cfg.io.output_mask = 0;
        cfg.io.keep_unmasked_command = true;
        cfg.remote = true;
    }

    fn finish(&mut self, node: &mut drivebus_node::Node) {
        use crate::build::set_default;
        use drivebus_od::Value;
        let od = node.od_mut();
        // §8.2.2: 6075h motor rated current default 0 (set by the master,
        // as in the §8.3 example; the drive computes with at least 1 mA).
        set_default(od, 0x6075, 0, &Value::U32(0));
        // §4.6.1: 607Dh defaults 80000000h / 7FFFFFFFh = check disabled.
        set_default(od, 0x607D, 1, &Value::I32(i32::MIN));
        set_default(od, 0x607D, 2, &Value::I32(i32::MAX));
        // §15.2.3: 6080h default 0 (no limit, `zero_means_off`).
        set_default(od, 0x6080, 0, &Value::U32(0));
        // §6.3.5 / §6.3.6: homing speeds 1.0 IU (00010000h), homing
        // acceleration 0.1 IU (0000199Ah).
        set_default(od, 0x6099, 1, &Value::U32(0x0001_0000));
        set_default(od, 0x6099, 2, &Value::U32(0x0001_0000));
        set_default(od, 0x609A, 0, &Value::U32(0x0000_199A));
        // §5.2.5, §5.2.8, §5.2.11: feed constant, velocity and acceleration
        // factors 1/1 (stored; `fixed_factor_group` keeps internal units).
        for index in [0x6092, 0x6096, 0x6097] {
            for sub in [1, 2] {
                set_default(od, index, sub, &Value::U32(1));
            }
        }
    }

    fn homing_methods(&self) -> Vec<Box<dyn HomingMethod + Send>> {
        (-4..=-1)
            .filter_map(MechanicalLimitHoming::new)
            .map(|m| Box::new(m) as Box<dyn HomingMethod + Send>)
            .collect()
    }

    fn manufacturer_mode(&self, mode: i8) -> Option<i8> {
        match mode {
            // −1 gearing (§11): the drive runs csp with the reference the
            // behaviour computes from the master position 201Eh (online).
            -1 => Some(8),
            // −2 camming (§12): accepted and displayed; the drive holds
            // its position under profile position (cam tables are not
            // emulated: their memory format is not in the manual,
            // docs/personalities.md).
            -2 => Some(1),
            _ => None,
        }
    }

    fn ip_mode(&self) -> IpMode {
        // §9.2.4: up to 000Fh points; the buffer state is 2072h and EMCY
        // FF01h (§9.2.3), not the drive's generic buffer warnings.
        IpMode::new(usize::from(IP_BUFFER_MAX)).with_monitor(self.ip.clone()).without_buffer_warnings()
    }

    fn hooked_objects(&self) -> &'static [u16] {
        &[
            0x1600, 0x1601, 0x1602, 0x1603, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x6086, 0x6075, 0x6076, 0x60C0,
            0x60C1, 0x2073, 0x2074, 0x208E, 0x201E, 0x2013,
        ]
    }

    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        let le = |d: &[u8]| drivebus_od::le_u64(d);
        match (index, sub) {
            // 6076h is the drive's internal torque reference kₜ × 6075h
            // (the iPOS has no 6076h; §8.2.1).
            (0x6076, _) => return Err(SdoAbort::WRITE_READ_ONLY),
            (0x60C0, 0) => {
                let v = le(data) as i16;
                let aux = od.get_u32(0x208E, 0).unwrap_or(u32::from(AUX_LINEAR_IP)) as u16;
                let old = od.get_i64(0x60C0, 0).unwrap_or(0) as i16;
                Self::drive_sub_mode(v, aux).ok_or(SdoAbort::INVALID_VALUE)?;
                if v != old {
                    // §9.2.1: changed only while interpolation is inactive;
                    // each change resets the buffer.
                    if Self::ip_active(cx) {
                        return Err(SdoAbort::DEVICE_STATE);
                    }
                    Self::sync_sub_mode(cx, od, v, aux)?;
                    self.clear_buffer(cx, od);
                }
                return Ok(Verdict::Store);
            }
            (0x208E, 0) => {
                let aux = le(data) as u16;
                let old = od.get_u32(0x208E, 0).unwrap_or(0) as u16;
                if (aux ^ old) & AUX_LINEAR_IP != 0 {
                    if Self::ip_active(cx) {
                        return Err(SdoAbort::DEVICE_STATE);
                    }
                    Self::sync_sub_mode(cx, od, od.get_i64(0x60C0, 0).unwrap_or(0) as i16, aux)?;
                    self.clear_buffer(cx, od);
                }
                return Ok(Verdict::Pass);
            }
            (0x60C1, 1 | 2) => {
                let Some(pvt) = Self::legacy_mode(od) else { return Ok(Verdict::Pass) };
                // X1 is kept until its X2 completes the point (the
                // integrity counter is in X2).
                if sub == 2 {
                    self.load_point(cx, od, pvt, le(data) as u32)?;
                }
                return Ok(Verdict::Store);
            }
            (0x2073, 0) => {
                // §9.2.4: a new length resets the buffer; 0 is not allowed.
                let n = le(data);
                if n == 0 {
                    return Err(SdoAbort::VALUE_TOO_LOW);
                }
                if n > u64::from(IP_BUFFER_MAX) {
                    return Err(SdoAbort::VALUE_TOO_HIGH);
                }
                cx.drive.on_write(od, 0x60C4, 2, &n.to_le_bytes())?;
                self.clear_buffer(cx, od);
                self.publish_ip_status(cx, od, false);
                return Ok(Verdict::Store);
            }
            (0x2074, 0) => {
                // Table 9.2.2.
                let v = le(data) as u16;
                let l = &mut self.legacy;
                l.unchecked = v & 1 << 14 != 0;
                l.from_demand = v & 1 << 12 != 0;
                if v & 1 << 13 != 0 {
                    l.counter = (v & 0x7F) as u8;
                    l.integrity_error = false;
                }
                if v & 1 << 7 != 0 {
                    l.low = (v >> 8) & 0xF;
                }
                if v & 1 << 15 != 0 {
                    self.clear_buffer(cx, od);
                }
                self.publish_ip_status(cx, od, false);
                return Ok(Verdict::Store);
            }
            _ => {}
        }
        if index == 0x6086 && data.first() == Some(&3) {
            // §7.3.3/§7.3.4 (E21/E22): 6086h = 3 selects the jerk-limited
            // S-curve (jerk time 2023h). Accepted and stored; the drive
            // keeps its own ramp shape (S-curve not emulated).
            return Ok(Verdict::Store);
        }
        if matches!(index, 0x1600..=0x1603 | 0x1A00..=0x1A03) && sub == 0 {
            let n = data.first().copied().unwrap_or(0);
            if n > 0 && mapped_bits(od, index, n) > MAX_PDO_BITS {
                // §1.6.3.1: the drive sends an EMCY and ignores the mapping.
                let reg = error_register(EMCY_PDO_LENGTH_EXCEEDED);
                cx.actions.push(Action::RawEmcy(EmcyFrame {
                    code: EMCY_PDO_LENGTH_EXCEEDED,
                    register: Some(reg),
                    bytes: [0; 5],
                }));
                return Ok(Verdict::Handled);
            }
        }
        Ok(Verdict::Pass)
    }

    fn after_write(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, sub: u8) {
        match (index, sub) {
            (0x6075, 0) => Self::sync_torque_reference(cx, od),
            (0x2013, 2) => {
                // §11.2.3: the ratio is computed when sub 2 is written; a
                // denominator 0 leaves the ratio as it was.
                let num = od.get_i64(0x2013, 1).unwrap_or(1) as i16;
                let den = od.get_u32(0x2013, 2).unwrap_or(1) as u16;
                if den != 0 {
                    self.gear.ratio = f64::from(num) / f64::from(den);
                }
            }
            // §11.2.6: 201Dh = 1, the master position comes online.
            (0x201E, 0) if od.get_u32(0x201D, 0) == Some(1) => {
                let m = od.get_i64(0x201E, 0).unwrap_or(0);
                self.gear_update(cx, od, m);
            }
            _ => {}
        }
    }

    fn on_event(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, event: &NodeEvent) {
        match event {
            NodeEvent::ResetApplication => {
                self.legacy = Legacy { counter: 1, ..Legacy::default() };
                self.gear = Gear::default();
                // The node forgot its errors: an active switch is reported
                // again, as at power-on.
                self.limits = (false, false);
                self.started = false;
            }
            NodeEvent::NmtState { .. } => {
                // The drive re-reads 60C0h and 6076h from the dictionary
                // (stored parameters): give it the iPOS meaning again.
                let aux = od.get_u32(0x208E, 0).unwrap_or(u32::from(AUX_LINEAR_IP)) as u16;
                let _ = Self::sync_sub_mode(cx, od, od.get_i64(0x60C0, 0).unwrap_or(0) as i16, aux);
                Self::sync_torque_reference(cx, od);
                if self.gear.active {
                    Self::gear_target(cx, od, self.gear.reference);
                }
            }
            _ => {}
        }
    }

    fn after_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        if !self.started {
            self.started = true;
            // Power-on: 2073h default 7 points (§9.2.4), the torque
            // reference of the power-on 6075h.
            let _ = cx.drive.on_write(od, 0x60C4, 2, &u64::from(IP_BUFFER_DEFAULT).to_le_bytes());
            Self::sync_torque_reference(cx, od);
        }
        // §11.2.6: 201Dh = 3, the master is the digital input (here the
        // second encoder; pulse & direction is not emulated).
        if od.get_u32(0x201D, 0) == Some(3)
            && let Some(m) = self.second_encoder
            && self.second_taken != Some(m)
        {
            self.second_taken = Some(m);
            self.gear_update(cx, od, m);
        }
        self.gear_step(cx, od);
        self.watch(cx, od);
    }

    fn emcy(&self, code: u16) -> EmcyFrame {
        EmcyFrame { code, register: Some(error_register(code)), bytes: [0; 5] }
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod facts_tests {
    use super::*;
    use drivebus_cia402::homing::{HomingConfig, HomingEvent};

    #[test]
    fn mechanical_limit_minus_3_travels_the_offset() {
        // §6: −3 runs negative into the limit, reverses and travels 607Ch.
        let cfg = HomingConfig {
            method: -3,
            switch_speed: 100.0,
            zero_speed: 10.0,
            acceleration: 1000.0,
            home_offset: 50.0,
            units_per_rev: f64::from(COUNTS_PER_REV),
        };
        let ctx = |position: f64, events: &'static [HomingEvent]| HomingContext {
            config: &cfg,
            position,
            velocity: 0.0,
            switches: Default::default(),
            events,
            torque: 0.0,
        };
        let mut m = MechanicalLimitHoming::new(-3).unwrap();
        assert_eq!(m.begin(&ctx(0.0, &[])), MethodStep::Move(-100.0));
        assert_eq!(m.update(&ctx(-10.0, &[])), MethodStep::Move(-100.0));
        static STOP: [HomingEvent; 1] = [HomingEvent {
            kind: EventKind::HardStop,
            active: false,
            position: -200.0,
            positive_direction: false,
        }];
        assert_eq!(m.update(&ctx(-200.0, &STOP)), MethodStep::Move(10.0));
        assert_eq!(m.update(&ctx(-170.0, &[])), MethodStep::Move(10.0));
        assert_eq!(m.update(&ctx(-150.0, &[])), MethodStep::Found(-150.0));
        assert!(MechanicalLimitHoming::new(-5).is_none());
    }

    #[test]
    fn master_increment_wraps_a_cyclic_master() {
        assert_eq!(master_increment(1990, 10, 2000), 20);
        assert_eq!(master_increment(10, 1990, 2000), -20);
        assert_eq!(master_increment(0, 500, 2000), 500);
        assert_eq!(master_increment(i64::from(i32::MAX), i64::from(i32::MIN), MASTER_FULL_RANGE), 1);
        assert_eq!(master_increment(5, 3, 0), -2);
    }

    #[test]
    fn legacy_points_decode_as_the_examples_pack_them() {
        // E26 point 2: 30000 counts, 2000 samples, IC 2.
        assert_eq!(
            LegacyPoint::pt(0x0000_7530, 0x0400_07D0),
            LegacyPoint { position: 30_000, velocity_16_8: 0, time: 2000, counter: 2 }
        );
        // E27 point 9: −1686 counts, −13.33 IU (FFF2ABh), 360 samples, IC 9.
        assert_eq!(
            LegacyPoint::pvt(0xFFAB_F96A, 0x1368_FFF2),
            LegacyPoint { position: -1686, velocity_16_8: -0xD55, time: 360, counter: 9 }
        );
        // IC 127 and the 9-bit time's top bit.
        assert_eq!(LegacyPoint::pvt(0, 0xFFFF_0000).counter, 127);
        assert_eq!(LegacyPoint::pvt(0, 0xFFFF_0000).time, 511);
    }

    #[test]
    fn sub_modes() {
        assert_eq!(Ipos::drive_sub_mode(0, AUX_LINEAR_IP), Some(0));
        assert_eq!(Ipos::drive_sub_mode(0, 0), Some(-1));
        assert_eq!(Ipos::drive_sub_mode(-1, 0), Some(-2));
        assert_eq!(Ipos::drive_sub_mode(1, 0), None);
        assert_eq!(Ipos::drive_sub_mode(-2, 0), None);
    }

    #[test]
    fn registers_use_bits_0_and_4() {
        assert_eq!(error_register(0x8220), 0x11);
        assert_eq!(error_register(0x8210), 0x11);
        assert_eq!(error_register(0x2310), 0x01);
        assert_eq!(error_register(0x0000), 0x00);
        for e in crate::Profile::Ipos.info().emcy {
            assert_eq!(error_register(e.code) & !0x11, 0);
        }
    }
}
