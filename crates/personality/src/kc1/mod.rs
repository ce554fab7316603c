//! Kollmorgen KC1 (seed000, *KC1 CAN-BUS Communication*, edition J 05/2013)
//! and the parts the AKD shares with it ([`Kollmorgen`]).
//!
//! What is emulated (sections of the KC1 manual; AKD sections in `akd/`):
//!
//! - no SDO block transfer (§6.4.5), no TIME (§6.4.3), NMT 80h not in the
//!   command list (§6.4.1): configuration ([`crate::build::node_config`]);
//! - byte-granular mapping, 8 entries, no RTR on TPDOs but COB-IDs with bit
//!   30 clear accepted (§7.3.1.2, example 6): `PdoConfig::kollmorgen`;
//! - 2100h dummy placeholder (§8.2.2.1): mappable, RPDO data ignored;
//! - remapping a valid PDO is accepted (examples 6, 7, 9, 11, 12 remap PDOs
//!   they never invalidate);
//! - expedited downloads whose size field disagrees with the object are
//!   taken at the object's size (example 13, frames 12, 13, 20–22);
//! - EMCY frames: error register without the generic bit (examples 11/12,
//!   §7.2.1.2 notwithstanding), byte 3 "category" 01h (§6.4.4.2);
//! - 6099h homing speeds above 65535 velocity units → `0609 0031`
//!   (example 9 frames 43–44; our reading, see docs/personalities.md).

mod ascii;
mod brake;
mod emcy;
mod facts;
mod io;
mod latch;
mod monitor;
mod objects;
mod params;
mod pls;
pub mod status;
mod timing;
mod tuning;

pub use facts::INFO;

/// The EDS file (`crates/personality/eds/kc1.eds`).
pub const EDS: &str = include_str!("../../eds/kc1.eds");

use crate::Profile;

extern crate alloc;
use crate::build::{Behaviour, Context, EmcyFrame, FilterOutcome, Verdict, set_default};
use drivebus_can::Frame;
use drivebus_cia402::drive::{DriveConfig, Injection, ZeroRamp, op};
use drivebus_cia402::interp::IpMode;
use drivebus_cia402::state_machine::State;
use drivebus_node::{Node, NodeConfig, NodeEvent, Request};
use drivebus_od::{EntryRef, ObjectDictionary, SdoAbort, Value, le_u64};
use drivebus_pdo::PdoConfig;

/// Largest 6099h homing speed the Kollmorgen drives take (example 9:
/// 72000 is refused with 0609 0031 although §7.10.2.3 prints 0..2³²−1).
pub const MAX_HOMING_SPEED: u64 = 0xFFFF;

/// Byte 3 of a Kollmorgen EMCY: the "category" (§6.4.4.2; examples 01h).
pub const EMCY_CATEGORY: u8 = 0x01;

/// The CiA 301 behaviour shared by the KC1 and the AKD.
#[derive(Debug, Clone)]
pub struct Kollmorgen {
    profile: Profile,
    /// The DC bus is charged before *Switch on* (statusword 0231h in *Ready
    /// to switch on*, KC1 example 12, AKD §13) instead of at it (0221h, KC1
    /// example 9, AKD §9). Both appear in the manuals; default `false`.
    pub dc_bus_before_switch_on: bool,
    /// A valid PDO's COB-ID invalidated for the duration of one mapping write.
    lifted: Option<(u16, u32)>,
    /// A SYNC was received (FBUS.PARAM04 supervision starts with the first).
    sync_seen: bool,
    /// A PVT point's position (60C1h:1), held until the point's last item
    /// (60C1h:3) completes the record (§7.9.2.2).
    pvt_position: Option<[u8; 4]>,
    /// 2026h ASCII channel (4 characters per SDO).
    telnet: ascii::Line,
    /// 1026h OS prompt (one character per SDO).
    prompt: ascii::Line,
    /// The parameter names of the object table, for Telnet.
    names: alloc::vec::Vec<(alloc::string::String, u16, u8)>,
    /// Motion tasks stored by MT.SET.
    tasks: alloc::vec::Vec<ascii::Task>,
    /// MT.NUM where the dictionary has no object for it.
    task_num: usize,
    /// 1002h, 2000h–2002h, 2011h–2013h and the warnings.
    status: status::Status,
    /// The fieldbus PLL (36E6h, 3496h).
    pll: timing::Pll,
    /// 60C2h written as a pair.
    period: timing::PeriodPair,
    /// The measurement mirrors and their limits.
    monitor: monitor::Monitor,
    /// The latch objects over the touch probe.
    latch: latch::Latch,
    /// The brake objects 345Ah, MOTOR.BRAKERLS.
    brake: brake::FieldbusBrake,
    /// DIN1–7 and their change flags in 60FDh.
    inputs: io::Inputs,
    /// The foldback readings and supervision.
    foldback: tuning::Foldback,
    /// The position limit switches.
    pls: pls::Pls,
    /// FB1.OFFSET in force in the drive's reference \[position units\].
    fb_offset: i64,
    /// 6041h and 6061h, resolved once (patched after every step).
    handles: Handles,
}

/// The statusword and mode display, resolved once per dictionary layout
/// (`objects` is the object count they were resolved at).
#[derive(Debug, Clone, Copy, Default)]
struct Handles {
    objects: usize,
    statusword: Option<EntryRef>,
    mode_display: Option<EntryRef>,
}

impl Handles {
    fn get(&mut self, od: &ObjectDictionary) -> Handles {
        if self.objects != od.objects().len() {
            *self = Handles {
                objects: od.objects().len(),
                statusword: od.find(0x6041, 0).ok(),
                mode_display: od.find(0x6061, 0).ok(),
            };
        }
        *self
    }
}

impl Kollmorgen {
    /// The shared behaviour for `profile` (KC1 or AKD).
    pub fn new(profile: Profile) -> Self {
        Kollmorgen {
            profile,
            dc_bus_before_switch_on: false,
            lifted: None,
            sync_seen: false,
            pvt_position: None,
            telnet: ascii::Line::default(),
            prompt: ascii::Line::default(),
            names: alloc::vec::Vec::new(),
            tasks: alloc::vec![ascii::Task::default(); ascii::TASKS],
            task_num: 0,
            status: status::Status::new(profile.info().emcy),
            pll: timing::Pll::default(),
            period: timing::PeriodPair::default(),
            monitor: monitor::Monitor::default(),
            latch: latch::Latch::default(),
            brake: brake::FieldbusBrake::default(),
            inputs: io::Inputs::default(),
            foldback: tuning::Foldback::default(),
            pls: pls::Pls::default(),
            fb_offset: 0,
            handles: Handles::default(),
        }
    }

    /// With the DC bus charged before *Switch on* (see the field).
    pub fn with_dc_bus_before_switch_on(mut self, on: bool) -> Self {
        self.dc_bus_before_switch_on = on;
        self
    }

    /// Objects whose writes the Kollmorgen behaviour watches.
    pub const HOOKED: &'static [u16] = &[
        0x2014, 0x2015, 0x2016, 0x2017, 0x2026, 0x2100, 0x6099, 0x608F, 0x1400, 0x1401, 0x1402, 0x1403,
        0x1800, 0x1801, 0x1802, 0x1803, 0x1600, 0x1601, 0x1602, 0x1603, 0x1A00, 0x1A01, 0x1A02, 0x1A03,
        0x60C4, 0x1026, 0x2071, 0x3431, 0x35C7, 0x352A, 0x35A3, 0x35C6, 0x3856, 0x204C, 0x36E9, 0x358E,
        0x20A4, 0x20A5, 0x3501, 0x3522, 0x3502, 0x35EB, 0x345A, 0x3450, 0x20B8, 0x3542, 0x3480, 0x3548,
        0x354D, 0x354B, 0x3407, 0x3593, 0x35AB, 0x525F, 0x3456, 0x5260, 0x3454, 0x356E, 0x356F, 0x3622,
        0x3623, 0x358F, 0x34A3, 0x366E, 0x366F, 0x3422, 0x3423, 0x3598, 0x3455, 0x3470, 0x3452, 0x35F0,
        0x3490,
    ];
}

impl Behaviour for Kollmorgen {
    fn profile(&self) -> Profile {
        self.profile
    }

    fn adjust_node_config(&self, cfg: &mut NodeConfig) {
        let k = PdoConfig::kollmorgen(cfg.node_id);
        cfg.pdo.rtr_supported = k.rtr_supported;
        cfg.pdo.ignore_rtr_bit = k.ignore_rtr_bit;
        cfg.software_version = None;
        // 1007h, 1019h and 1200h are in neither manual's object list (KC1
        // §8.1.2, AKD §7.1.3): no window, SYNC without counter, the default
        // SDO server on its pre-defined identifiers.
        cfg.sync_window = false;
        cfg.sync_counter = false;
        cfg.sdo_server_param = false;
        // KC1 §6.4.4.2 / AKD §5.4.4.2: F129 (guarding/heartbeat loss,
        // §7.1) goes out like every drive fault: class bits, category.
        cfg.comm_error_emcy = Some((crate::shared::class_bit(0x8130), [EMCY_CATEGORY, 0, 0, 0, 0]));
    }

    fn hooked_objects(&self) -> &'static [u16] {
        Self::HOOKED
    }

    fn ip_mode(&self) -> IpMode {
        // KC1 §7.9.2.4 / AKD §6.9.2.4: maximum buffer size 10 (60C4h:1),
        // actual buffer size 9 (60C4h:2, 0..9).
        let mut m = IpMode::new(10);
        m.engine_mut().buffer_mut().set_size(9);
        m
    }

    fn adjust_drive_config(&self, cfg: &mut DriveConfig) {
        kollmorgen_units(cfg);
        // KC1 §7.2.3.9 / AKD §6.2.3.9: 60FEh:1 bit 0 "set brake", bits
        // 16/17 DOUT1/2 (as far as 60FEh:2 enables them).
        cfg.io.output_lines = true;
        cfg.io.set_brake_bit = true;
        // SYNC loss is supervised only when FBUS.PARAM04 (36E8h) = 1.
        cfg.sync_loss_fault = false;
        kollmorgen_power_on(cfg);
    }

    fn on_event(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, event: &NodeEvent) {
        // FBUS.PARAM04 (KC1 §4.4 / AKD §3.4): with 36E8h = 1, SYNC loss after
        // the first SYNC is fault F125 (EMCY 8780h, §7.1); 0 (the CANopen
        // default) leaves it unsupervised.
        if matches!(event, NodeEvent::SyncTimeout) && self.sync_seen && od.get_u32(0x36E8, 0) == Some(1) {
            cx.drive.inject(Injection::Fault(0x8780));
        }
        if matches!(event, NodeEvent::ResetCommunication | NodeEvent::ResetApplication) {
            self.sync_seen = false;
            self.pll.stop();
        }
        if matches!(event, NodeEvent::ResetApplication) {
            self.status.reset();
            self.period.reset();
            self.brake = brake::FieldbusBrake::default();
            self.pls = pls::Pls::default();
        }
        // §7.2.2.15: "when fieldbus communication is lost, the drive will
        // regain control of the brake".
        let left_operational =
            matches!(event, NodeEvent::NmtState { from: drivebus_node::NmtState::Operational, .. });
        if left_operational
            || matches!(event, NodeEvent::HeartbeatTimeout { .. } | NodeEvent::LifeGuardingLost)
        {
            self.brake.lost();
        }
        // The drive reloaded its parameters: set those that follow a
        // manufacturer parameter again.
        if let NodeEvent::NmtState { to: drivebus_node::NmtState::PreOperational, from } = event
            && *from != drivebus_node::NmtState::Operational
        {
            self.forward_all(cx, od);
        }
    }

    fn on_boot(&mut self, cx: &mut Context<'_>, _od: &mut ObjectDictionary) {
        self.status.boot(cx.now);
    }

    fn finish(&mut self, node: &mut Node) {
        self.names = ascii::parameter_names(&self.profile.eds().eds);
        for index in 0x2014..=0x2017u16 {
            let mask = tpdo_mask(node.od(), index);
            node.set_tpdo_change_mask(index - 0x2014, mask);
        }
        let od = node.od_mut();
        // KC1 §7.7.2.4 / AKD §6.7.2.4: 6073h default 0, no limit besides
        // 6072h (`zero_means_off.max_current`); a value written limits the
        // torque-creating current as the manual words it.
        set_default(od, 0x6073, 0, &Value::U16(0));
        // KC1 §7.9.2.4 / AKD §6.9.2.4: 60C4h:5 default 1 (records), 60C4h:6
        // default 0. Both are write-only commands: the buffer itself starts
        // with access enabled (example 12 sends records without a 60C4h:6
        // write).
        set_default(od, 0x60C4, 5, &Value::U8(1));
        set_default(od, 0x60C4, 6, &Value::U8(0));
        // §7.10.2.3: 6099h:1 "equivalent 60 rpm", :2 1/8 of it.
        set_default(od, 0x6099, 1, &Value::U32(UNITS_PER_REV));
        set_default(od, 0x6099, 2, &Value::U32(UNITS_PER_REV / 8));
        // §8.1.4: 608Fh:1/2 are RW on the Kollmorgen drives.
        for sub in [1, 2] {
            if let Some(e) = od.get_mut(0x608F, sub) {
                e.access = drivebus_od::Access::Rw;
                // Owned by this behaviour: its writes come here.
                e.owner = crate::build::BEHAVIOUR;
                e.live = true;
            }
        }
    }

    fn filter_rx(&mut self, od: &ObjectDictionary, node_id: u8, frame: &Frame) -> FilterOutcome {
        if let (Some(id), Some(cob)) = (frame.std_id(), od.get_u32(0x1005, 0))
            && u32::from(id) == cob & 0x7FF
        {
            self.sync_seen = true;
            self.pll.sync_pending = true;
        }
        if let Some(f) = crate::shared::resize_expedited(od, node_id, frame) {
            return FilterOutcome::Replace(f);
        }
        if let Some(f) = crate::shared::pad_short_rpdo(od, frame) {
            return FilterOutcome::Replace(f);
        }
        FilterOutcome::Pass
    }

    fn on_write(
        &mut self,
        cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Verdict, SdoAbort> {
        if let Some(verdict) = self.object_write(cx, od, index, sub, data)? {
            return Ok(verdict);
        }
        match index {
            // §8.2.2.1: the placeholder takes the RPDO bytes and ignores them.
            0x2100 => Ok(Verdict::Handled),
            // §7.9.2.2: 60C1h:2 is the time to the next point (ms,
            // UNSIGNED32), :3 the target velocity; the drive's ip engine
            // takes the velocity at :2 and the time at :3. In PVT (60C0h =
            // −2) a record is complete with its last item: "after the last
            // item … is written … the pointer of the buffer is automatically
            // incremented", so the position waits for :3.
            0x60C1 if (1..=3).contains(&sub) => {
                let pvt = od.get_i64(0x60C0, 0) == Some(-2);
                match sub {
                    1 if pvt => {
                        let mut b = [0u8; 4];
                        b[..data.len().min(4)].copy_from_slice(&data[..data.len().min(4)]);
                        self.pvt_position = Some(b);
                    }
                    1 => return Ok(Verdict::Pass),
                    _ => {
                        cx.drive.on_write(od, 0x60C1, 5 - sub, data)?;
                        if sub == 3
                            && let Some(p) = self.pvt_position.take()
                        {
                            cx.drive.on_write(od, 0x60C1, 1, &p)?;
                        }
                    }
                }
                Ok(Verdict::Store)
            }
            // §7.9.2.4: the size of a data record counts records; only 1 is
            // possible for linear interpolation (the drive's ip engine counts
            // bytes and is not asked).
            0x60C4 if sub == 5 => {
                if le_u64(data) == 1 {
                    Ok(Verdict::Store)
                } else {
                    Err(SdoAbort::INVALID_VALUE)
                }
            }
            0x6099 if (1..=2).contains(&sub) && le_u64(data) > MAX_HOMING_SPEED => {
                Err(SdoAbort::VALUE_TOO_HIGH)
            }
            // §8.1.4 tsv: 608Fh:1/2 RW; encoder increments only powers of 2.
            // Stored; the simulated encoder keeps its resolution.
            0x608F if sub == 1 => {
                if !(le_u64(data) as u32).is_power_of_two() {
                    return Err(SdoAbort::INVALID_VALUE);
                }
                Ok(Verdict::Handled)
            }
            0x608F if sub == 2 => Ok(Verdict::Handled),
            0x1600..=0x1603 | 0x1A00..=0x1A03 | 0x1400..=0x1403 | 0x1800..=0x1803 => {
                // Remapping a valid PDO, or moving a valid PDO to another
                // valid COB-ID, is accepted (examples 6, 9, 11, 12): lift
                // the CiA 301 §7.5.2.35/36 restriction for this write only.
                let comm = index & !0x0200;
                let new_valid = sub == 1 && data.len() == 4 && le_u64(data) & 0x8000_0000 == 0;
                if index & 0x0200 == 0 && !new_valid {
                    return Ok(Verdict::Pass);
                }
                if let Some(cob) = od.get_u32(comm, 1)
                    && cob & 0x8000_0000 == 0
                    && let Ok(r) = od.find(comm, 1)
                {
                    od.set_raw(r, &(cob | 0x8000_0000).to_le_bytes());
                    if index & 0x0200 != 0 {
                        self.lifted = Some((comm, cob));
                    }
                    // Put back if the service refused the write.
                    cx.request(Request::Restore {
                        index: comm,
                        sub: 1,
                        value: cob,
                        only_if: Some(cob | 0x8000_0000),
                    });
                }
                Ok(Verdict::Pass)
            }
            _ => Ok(Verdict::Pass),
        }
    }

    fn on_read(
        &mut self,
        _cx: &mut Context<'_>,
        od: &mut ObjectDictionary,
        index: u16,
        sub: u8,
    ) -> Result<(), SdoAbort> {
        if (index, sub) == (0x2026, 2) {
            // The next 4 characters of the reply; NUL once it is exhausted
            // (the manual does not say).
            let chunk = self.telnet.read::<4>();
            let r = od.find(index, sub)?;
            od.set_raw(r, &chunk);
        }
        if index == 0x35C7
            && let (Some(w), Ok(r)) = (od.get_u32(0x6065, 0), od.find(index, sub))
        {
            od.set_raw(r, &w.to_le_bytes());
        }
        if (index, sub) == (0x1026, 2) {
            let c = self.prompt.read::<1>();
            let r = od.find(index, sub)?;
            od.set_raw(r, &c);
        }
        Ok(())
    }

    fn after_write(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary, index: u16, _sub: u8) {
        if let 0x2014..=0x2017 = index {
            cx.request(Request::TpdoChangeMask { tpdo: index - 0x2014, mask: tpdo_mask(od, index) });
        }
        // Valid again before the PDO service re-reads the PDO.
        if let Some((comm, cob)) = self.lifted.take()
            && let Ok(r) = od.find(comm, 1)
        {
            od.set_raw(r, &cob.to_le_bytes());
        }
    }

    fn after_step(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let h = self.handles.get(od);
        kollmorgen_statusword_at(od, h.statusword, self.dc_bus_before_switch_on);
        self.supervise(cx, od);
        let mode = h.mode_display.map(|r| od.word(r) as u8 as i8);
        if let Some(r) = h.statusword {
            let sw = od.word(r) as u16;
            // ip: bit 10 is not shown (example 12 frames 53/55: 0237h, 1237h;
            // CiA 402 would show 0637h while ip is not active).
            // hm: not started and in progress both read 0237h (example 8
            // frames 23/27, example 9); CiA 402 shows "not started" as
            // 0637h. Bit 10 comes with bit 12 (homing attained, 1637h) only.
            let clear = match mode {
                Some(7) => sw & 0x0400 != 0,
                Some(6) => sw & 0x3400 == 0x0400,
                _ => false,
            };
            if clear {
                od.set_le(r, &(sw & !0x0400).to_le_bytes());
            }
        }
    }

    fn emcy(&self, code: u16) -> EmcyFrame {
        let code = kollmorgen_code(code);
        EmcyFrame { code, register: Some(crate::shared::class_bit(code)), bytes: [EMCY_CATEGORY, 0, 0, 0, 0] }
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn core::any::Any> {
        Some(self)
    }
}

impl Kollmorgen {
    /// After every step: software limits, PLL, then the status objects
    /// (which set statusword bit 7 for the warnings).
    fn supervise(&mut self, cx: &mut Context<'_>, od: &mut ObjectDictionary) {
        let view = cx.drive.view();
        // KC1 §7.11.2.2 / AKD §6.11.2.2: limits relative to the machine
        // home; 0/0 = off; not while homing.
        let (lo, hi) = cx.drive.mode_params().software_limits;
        let active = (lo != 0 || hi != 0) && view.mode != op::HM;
        let pos = cx.drive.position();
        let (above, below) = (active && pos > i64::from(hi), active && pos < i64::from(lo));
        if self.profile == Profile::Kc1 {
            // KC1 §7.1: F107/F108 (8580h/8581h) when the set-point takes
            // the axis past a limit outwards (not the settling of a move
            // that stops at it); back inwards it may move.
            let v = cx.drive.demand_velocity();
            let d = cx.drive.demand_position();
            let (above, below) = (active && d > f64::from(hi), active && d < f64::from(lo));
            if view.state == State::OperationEnabled && ((above && v > 0.0) || (below && v < 0.0)) {
                cx.drive.inject(Injection::Fault(if above { 0x8580 } else { 0x8581 }));
            }
        } else {
            // AKD §6.1 lists only the warnings n107/n108 (8582h/8583h).
            self.status.set(cx, od, status::Warning::PositiveSoftLimit, above);
            self.status.set(cx, od, status::Warning::NegativeSoftLimit, below);
        }
        // n167: the drive clamped a pp target to a limit (statusword bit
        // 11 without a limit switch).
        let clamped = active
            && view.mode == op::PP
            && view.state == State::OperationEnabled
            && view.statusword & 0x800 != 0
            && view.digital_inputs & 0x3 == 0;
        self.status.set(cx, od, status::Warning::SoftLimitTraversed, clamped);
        let period = cx.drive.mode_params().interpolation_period_s().map(|s| (s * 1e9).round() as u64);
        self.pll.run(od, cx.now, period, matches!(view.mode, op::IP | op::CSP));
        self.status.set(cx, od, status::Warning::SyncLost, self.pll.lost);
        self.inputs.update(cx, od);
        self.foldback.update(cx, od, &mut self.status);
        self.status.update(cx, od);
        self.monitor.update(cx, od, &mut self.status);
        self.latch.update(od);
        self.brake.update(cx, od);
        self.pls.update(cx, od);
    }
}

/// Statusword bit 4 "voltage enabled" is only shown from *Switched on*
/// on: *Ready to switch on* reads 0221h (KC1 example 9 frame 47, AKD §9),
/// not CiA 402's 0231h.
/// *Switch on disabled* reads 0240h (bit 5 "quick stop" clear; CiA 402
/// leaves it open): KC1 examples 3, 8, 9, AKD §3, §8.
pub fn kollmorgen_statusword(od: &mut ObjectDictionary, dc_bus_before_switch_on: bool) {
    kollmorgen_statusword_at(od, od.find(0x6041, 0).ok(), dc_bus_before_switch_on);
}

/// [`kollmorgen_statusword`] through a resolved handle of 6041h.
fn kollmorgen_statusword_at(od: &mut ObjectDictionary, r: Option<EntryRef>, dc_bus_before_switch_on: bool) {
    if let Some(r) = r {
        let b = od.bytes(r);
        let sw = u16::from_le_bytes([b[0], b.get(1).copied().unwrap_or(0)]);
        let mut new = sw;
        if sw & 0x6F == 0x21 && !dc_bus_before_switch_on {
            new &= !0x10;
        }
        if sw & 0x4F == 0x40 {
            new &= !0x20;
        }
        if new != sw {
            od.set_le(r, &new.to_le_bytes());
        }
    }
}

/// The Kollmorgen EMCY code for a fault the CiA 402 drive reports with its
/// generic CiA 402 code, where the tables (KC1 §7.1, AKD §6.1) list the
/// condition under another code: output over-current 2310h → FF07h (F525),
/// SYNC loss 8700h → 8780h (F125). Codes the tables list are kept.
pub fn kollmorgen_code(code: u16) -> u16 {
    match code {
        0x2310 => 0xFF07,
        0x8700 => 0x8780,
        c => c,
    }
}

/// The KC1: the shared Kollmorgen behaviour, nothing else.
pub fn kc1() -> Kollmorgen {
    Kollmorgen::new(Profile::Kc1)
}

/// Position units per motor revolution of the Kollmorgen personalities:
/// KC1 example 9 (§8.2.1.8) reads "36000 µm" for one revolution and "72000
/// units/s = 2 s⁻¹"; velocity units are position units/s, acceleration
/// units position units/s².
pub const UNITS_PER_REV: u32 = 36_000;

/// The Kollmorgen scaling on a drive configuration: [`UNITS_PER_REV`] and the
/// profile defaults rescaled from the stack's 360000 units/rev.
pub fn kollmorgen_units(cfg: &mut DriveConfig) {
    cfg.factor.feed = (UNITS_PER_REV, 1);
    let k = 360_000 / UNITS_PER_REV;
    let p = &mut cfg.profile;
    for v in [
        &mut p.max_profile_velocity,
        &mut p.profile_velocity,
        &mut p.profile_acceleration,
        &mut p.profile_deceleration,
        &mut p.quick_stop_deceleration,
        &mut p.following_error_window,
        &mut p.position_window,
    ] {
        *v = (*v / k).max(1);
    }
}

/// The power-on values the manuals' object tables give (KC1 §8.1.4 /
/// AKD §7.1.5) where they differ from the generic servo's.
fn kollmorgen_power_on(cfg: &mut DriveConfig) {
    // 6065h default 0 = following error monitoring off (KC1 §7.8.2.3,
    // AKD §6.8.2.3).
    cfg.zero_means_off.following_error_window = true;
    cfg.profile.following_error_window = 0;
    // 6073h default 0 (§7.7.2.4 / §6.7.2.4) with the drive moving in tq.
    cfg.zero_means_off.max_current = true;
    // 60FEh:2 bit mask default 0 (KC1 §7.2.3.9, AKD §6.2.3.9): no output
    // follows sub 1 until the master sets the mask.
    cfg.io.output_mask = 0;
    // 6083h/6084h/609Ah range 0..2^32-1, default 0 (KC1 §7.11.2.4/5,
    // §7.10.2.4; AKD §6.11.2.4/5, §6.10.2.4). 0 selects the drive's own
    // ramp: 6083h/6084h are DRV.ACC/DRV.DEC in pv, and examples 4 and 6 jog
    // in pv, example 9 homes, all at the default 0.
    let p = &mut cfg.profile;
    cfg.zero_ramp = ZeroRamp::DriveRamp {
        acceleration: p.profile_acceleration,
        deceleration: p.profile_deceleration,
        homing: p.profile_acceleration,
    };
    p.profile_acceleration = 0;
    p.profile_deceleration = 0;
    // 6081h default 10 (KC1 §7.11.2.3, AKD §6.11.2.3).
    p.profile_velocity = 10;
}

/// KC1 §7.2.2.4 / AKD B.4: 2014h..2017h sub 1 masks TPDO bytes 0..3, sub 2
/// bytes 4..7; a set bit is monitored for change of state. All ones is the
/// CiA 301 default (every change counts).
fn tpdo_mask(od: &ObjectDictionary, index: u16) -> Option<[u8; 8]> {
    let lo = od.get_u32(index, 1).unwrap_or(u32::MAX);
    let hi = od.get_u32(index, 2).unwrap_or(u32::MAX);
    if lo == u32::MAX && hi == u32::MAX {
        return None;
    }
    let mut m = [0u8; 8];
    m[..4].copy_from_slice(&lo.to_le_bytes());
    m[4..].copy_from_slice(&hi.to_le_bytes());
    Some(m)
}
